"""Cost and image error of a path-traced 1200 x 1200 view at the pipeline's defaults.

``python -m benchmarks.bench_path_cost --work DIR --parts refs|views|report [--tag T] [--set K=V]``

The benchmark scene of bench_path (:mod:`benchmarks.path_scene`: 20 objects dropped in the tote,
two area lights, a uniform environment, view 0) traced at 1200 x 1200 with 1 sample per pixel
and denoised as ``render.denoise`` does by default (OIDN ``fast``, smoothed guides, half
resolution), with 2 threads. Scored on five 320 x 320 windows (WINDOWS) against high-spp
references of those windows alone (:func:`path_scene.crop`: the same rays through a smaller
camera), each with the exposure that puts the reference's 99.5th luminance percentile at 1
(bench_path's tone map and FLIP). Both the references and the tested views are traced without
clamping (``clamp_indirect = 0``), as bench_path's mgn engine traces them.

``refs`` renders the references (REF_SPP samples per pixel) with the mgn that is imported;
``views`` traces the full view with three seeds under ``--tag`` (``--set`` changes a
PathTraceOptions field, e.g. ``--set max_bounces=4``) and records per seed: trace CPU-s and wall
s, the rays traced, denoise CPU-s, FLIP of each window and the 1-minute load;
``report`` prints one table row per tag. Work files stay in ``--work``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from . import path_scene as ps
from .bench_path import exposure_of, flip_error, tonemap

WIDTH = 1200
SIZE = 320
#: The scored windows: name -> (x0, y0) of a SIZE x SIZE window of the 1200 x 1200 view.
WINDOWS = {
    "glass": (400, 130),
    "cup_box": (100, 750),
    "can": (750, 700),
    "tote_corner": (860, 860),
    "jar": (40, 640),
}
REF_SPP = 128
SEEDS = (1, 2, 3)
THREADS = 2


def _load1() -> float:
    return float(os.getloadavg()[0])


def _scene(work: Path) -> tuple[Any, ps.SceneDesc]:
    from mgn.render import path as mpath

    scene_json = work / "scene.json"
    if not scene_json.exists():
        ps.drop(scene_json)
    inp = ps.mgn_inputs(scene_json)
    lights, env = ps.mgn_lighting()
    scene = mpath.PathScene(
        inp["meshes"], inp["poses"], inp["instance_ids"], inp["materials"], lights, env
    )
    return scene, ps.describe(scene_json, WIDTH)


def _view(desc: ps.SceneDesc) -> Any:
    cams = ps.cameras()
    c = desc.camera
    return cams.CameraView(cams.Intrinsics(c.width, c.height, c.fx, c.fy, c.cx, c.cy), c.X_WC)


def _options(spp: int, seed: int, changes: dict[str, Any]) -> Any:
    from mgn.render import path as mpath

    opts = mpath.PathTraceOptions(spp=spp, seed=seed, num_threads=THREADS)
    opts = dataclasses.replace(opts, labels=False, clamp_indirect=0.0)
    return dataclasses.replace(opts, **changes)


def refs(work: Path) -> None:
    scene, desc = _scene(work)
    for name, (x0, y0) in WINDOWS.items():
        path = work / f"ref_{name}.npy"
        if path.exists():
            continue
        view = _view(ps.crop(desc, x0, y0, SIZE, SIZE))
        t0, c0 = time.perf_counter(), time.process_time()
        out = scene.render(view, _options(REF_SPP, 0, {}))
        np.save(path, np.asarray(out.radiance, np.float32))
        print(
            f"ref {name}: {REF_SPP} spp {time.perf_counter() - t0:.0f} s wall, "
            f"{time.process_time() - c0:.0f} CPU-s, load {_load1():.1f}",
            flush=True,
        )


def views(work: Path, tag: str, changes: dict[str, Any]) -> None:
    from mgn.render.photo import RenderSettings, denoise

    d = RenderSettings()
    scene, desc = _scene(work)
    view = _view(desc)
    rows = []
    for seed in SEEDS:
        load = _load1()
        t0, c0 = time.perf_counter(), time.process_time()
        out = scene.render(view, _options(1, seed, changes))
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        c1 = time.process_time()
        img = np.asarray(
            denoise(
                out.radiance, out.albedo, out.normal, d.denoise_quality,
                num_threads=THREADS, guides=d.denoise_guides, resolution=d.denoise_resolution,
            ),
            np.float32,
        )  # fmt: skip
        cpu_dn = time.process_time() - c1
        flips = {}
        for name, (x0, y0) in WINDOWS.items():
            ref = np.load(work / f"ref_{name}.npy")
            e = exposure_of(ref)
            win = img[y0 : y0 + SIZE, x0 : x0 + SIZE]
            flips[name] = flip_error(tonemap(ref, e), tonemap(win, e))
        row = {
            "seed": seed, "trace_cpu": cpu, "trace_wall": wall, "rays": int(out.rays),
            "denoise_cpu": cpu_dn, "flip": flips, "load1": load,
        }  # fmt: skip
        rows.append(row)
        print(json.dumps(row), flush=True)
        if seed == SEEDS[0]:
            from .bench_path import save_png

            save_png(
                (np.clip(tonemap(img, exposure_of(img)), 0, 1) * 255).astype(np.uint8),
                work / f"view_{tag}.png",
            )
    (work / f"views_{tag}.json").write_text(
        json.dumps({"tag": tag, "changes": changes, "rows": rows}, indent=1) + "\n"
    )


def report(work: Path) -> None:
    names = list(WINDOWS)
    print(
        "| tag | trace CPU-s | rays/px | denoise CPU-s | " + " | ".join(names) + " | mean | load |"
    )
    print("|---|---:|---:|---:|" + "---:|" * (len(names) + 2))
    for f in sorted(work.glob("views_*.json"), key=lambda p: p.stat().st_mtime):
        r = json.loads(f.read_text())
        rows = r["rows"]
        fl = {n: float(np.mean([x["flip"][n] for x in rows])) for n in names}
        print(
            f"| {r['tag']} | {np.median([x['trace_cpu'] for x in rows]):.2f} | "
            f"{np.mean([x['rays'] for x in rows]) / WIDTH**2:.2f} | "
            f"{np.median([x['denoise_cpu'] for x in rows]):.2f} | "
            + " | ".join(f"{fl[n]:.4f}" for n in names)
            + f" | {np.mean(list(fl.values())):.4f} | "
            f"{np.mean([x['load1'] for x in rows]):.1f} |"
        )


def _value(v: str) -> Any:
    for cast in (int, float):
        try:
            return cast(v)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(v.lower(), v)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--work", type=Path, required=True)
    p.add_argument("--parts", default="refs,views,report")
    p.add_argument("--tag", default="default")
    p.add_argument("--set", action="append", default=[], help="PathTraceOptions field=value")
    a = p.parse_args(argv)
    a.work.mkdir(parents=True, exist_ok=True)
    changes = {k: _value(v) for k, v in (s.split("=", 1) for s in a.set)}
    parts = a.parts.split(",")
    if "refs" in parts:
        refs(a.work)
    if "views" in parts:
        views(a.work, a.tag, changes)
    if "report" in parts:
        report(a.work)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
