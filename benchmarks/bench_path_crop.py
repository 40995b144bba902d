"""Path tracing at the issue's size: error of full-resolution (1200 x 1200) views, scored on a crop.

``python -m benchmarks.bench_path --study full-res-crop [--work DIR] [--crop X0,Y0,SIZE] ...``

The 240 x 240 study of bench_path is a different quantity from the target ("a denoised 1200 x
1200 view"): the denoiser sees 25x fewer pixels per object. Here every compared image is rendered
and denoised at 1200 x 1200 (the denoiser sees the whole view) and only then cropped to a window;
each engine's reference is rendered for that window alone (a camera with the same focal lengths,
the principal point moved by the window's corner and the window's size:
:func:`path_scene.crop`), so a high-spp reference costs the window's pixels only. The window
(default 320 x 320 px at (400, 130)) holds the clear bottle (glass, close up), the black
remote, parts of the water and detergent bottles and the tote wall.

Each engine's reference is also checked for alignment: its instance ids of the window equal mgn's
raster instance ids of the full view cut to the window. Error = FLIP and PSNR against the
reference of the same engine, tone-mapped as in bench_path; time = CPU seconds of the full view
(wall seconds and the 1-minute load are reported beside them).

Work files (the scene, every engine's images and timings) stay in --work so the parts can run
separately (``--parts refs``, ``--parts renders``, ``--parts report``) and a changed mgn can be
re-rendered under another ``--tag`` and compared against the same references.
"""

from __future__ import annotations

import argparse
import json
import pickle
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from . import path_scene as ps
from .bench_path import (
    HERE,
    exposure_of,
    flip_at,
    flip_error,
    load1,
    psnr,
    raster_ids,
    report_main,
    run_child,
    tonemap,
)

FULL_WIDTH = 1200
CROP = (400, 130, 320)  # x0, y0, size (px) of the scored window of the 1200 x 1200 view
REF_SPP = 1024
SPPS = {"mgn": (1, 2, 4), "cycles": (1, 2, 4, 8, 16)}
#: mgn's adaptive sampling rows: extra samples per pixel on average (`render.adaptive_samples`)
#: after a first pass at ADAPTIVE_SPPS samples per pixel.
ADAPTIVE = (0.25, 0.5, 1.0)
ADAPTIVE_SPPS = (1,)


def _log(msg: str) -> None:
    print(msg, flush=True)


def _window(img: np.ndarray, crop: tuple[int, int, int]) -> np.ndarray:
    x0, y0, s = crop
    return img[y0 : y0 + s, x0 : x0 + s]


def _run(
    engine: str,
    desc_path: Path,
    scene_json: Path,
    spps: tuple[int, ...],
    ref_spp: int,
    stem: Path,
    log: Callable[[str], None],
    denoised_only: bool = False,
    adaptive: float = 0.0,
) -> None:
    res, status = run_child(
        engine,
        desc_path,
        scene_json,
        spps,
        ref_spp,
        1,
        stem.with_suffix(".npz"),
        log,
        denoised_only=denoised_only,
        adaptive=adaptive,
    )
    if res is None:
        raise RuntimeError(f"{engine}: {status}")
    stem.with_suffix(".json").write_text(json.dumps(res, default=float) + "\n")


def _load(stem: Path) -> tuple[dict[str, Any], dict[str, np.ndarray]] | None:
    if not stem.with_suffix(".json").exists():
        return None
    with np.load(stem.with_suffix(".npz")) as z:
        frames = {k: z[k] for k in z.files}
    return json.loads(stem.with_suffix(".json").read_text()), frames


def evaluate(work: Path, crop: tuple[int, int, int], tags: list[str]) -> dict[str, Any]:
    """Rows (engine run, spp, denoise): full-view CPU and wall seconds, load, FLIP and PSNR of the
    window against the engine's own window reference; alignment and faithfulness notes."""
    scene_json = work / "scene.json"
    desc = ps.describe(scene_json, FULL_WIDTH)
    raster = _window(raster_ids(desc, scene_json), crop)
    ev: dict[str, Any] = {"rows": [], "refs": {}, "alignment": {}, "crop": list(crop)}
    refs: dict[str, np.ndarray] = {}
    for engine in ("mgn", "cycles"):
        got = _load(work / f"{engine}_ref")
        if got is None:
            continue
        res, frames = got
        refs[engine] = frames["ref"]
        ev["refs"][engine] = {**res["ref"], "version": res.get("version", "")}
        ev["alignment"][f"{engine} window reference"] = float(np.mean(frames["ids"] == raster))
    for run_name in tags:
        engine = "cycles" if run_name.startswith("cycles") else "mgn"
        got = _load(work / f"{run_name}_full")
        if got is None or engine not in refs:
            continue
        res, frames = got
        ev["alignment"][f"{run_name} full view"] = float(
            np.mean(_window(frames["ids"], crop) == raster)
        )
        e = exposure_of(refs[engine])
        ref_t = tonemap(refs[engine], e)
        for cfg in res["configs"]:
            key = f"{cfg['spp']}{'d' if cfg['denoise'] else ''}"
            test = tonemap(_window(frames[key], crop), e)
            ev["rows"].append(
                {
                    "run": run_name,
                    "engine": engine,
                    "spp": cfg["spp"],
                    "denoise": cfg["denoise"],
                    "seconds": float(np.median(cfg["wall"])),
                    "cpu_seconds": float(np.median(cfg["cpu"])),
                    "load1": float(np.mean(cfg["load1"])),
                    "flip": flip_error(ref_t, test),
                    "psnr": psnr(ref_t, test),
                    "peak_mib": res["peak_kib"] / 1024,
                }
            )
    if "mgn" in refs and "cycles" in refs:
        e = exposure_of(refs["mgn"])
        ev["cross_flip"] = flip_error(tonemap(refs["mgn"], e), tonemap(refs["cycles"], e))
        ev["cross_ratio"] = float(refs["cycles"].mean() / max(refs["mgn"].mean(), 1e-9))
    return ev


def _label(r: dict[str, Any]) -> str:
    name = "Cycles" if r["engine"] == "cycles" else "mgn path"
    tag = r["run"][len(r["engine"]) :].lstrip("_")
    return name + (f" [{tag}]" if tag else "") + (" + OIDN" if r["denoise"] else "")


def markdown(ev: dict[str, Any]) -> str:
    x0, y0, s = ev["crop"]
    lines = [
        "## Path tracing at 1200×1200, scored on a window "
        "(`python -m benchmarks.bench_path --study full-res-crop`)",
        "",
        f"Every image is rendered (and denoised) at 1200×1200, view 0, max 6 bounces, 2 threads; "
        f"the error is measured on the {s}×{s} px window at ({x0}, {y0}) (the clear glass "
        "bottle close up, the black remote, parts of the water and detergent bottles, the tote "
        "wall) against each engine's "
        "own reference of that window, rendered through a camera cut to the window (same rays). "
        "Time: CPU seconds of the whole 1200×1200 view (wall seconds and the 1-minute load "
        "beside: the machine was shared, so wall time is pessimistic).",
        "",
        "| run | spp | s/view | CPU-s/view | load (1 min) | FLIP | PSNR dB | peak RSS MiB |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in sorted(ev["rows"], key=lambda r: (_label(r), r["spp"])):
        lines.append(
            f"| {_label(r)} | {r['spp']} | {r['seconds']:.2f} | {r['cpu_seconds']:.2f} | "
            f"{r['load1']:.1f} | {r['flip']:.4f} | {r['psnr']:.1f} | {r['peak_mib']:.0f} |"
        )
    lines.append("")
    for engine, r in ev["refs"].items():
        lines.append(
            f"- {engine} reference: {r['spp']} spp on the {s}×{s} window took {r['wall']:.0f} s "
            f"wall (load {r['load1']:.1f}); version {r['version'] or 'this checkout'}"
        )
    for what, a in ev["alignment"].items():
        lines.append(
            f"- alignment: {what}: instance ids equal mgn's raster ids of the window on "
            f"{100 * a:.3f} % of pixels"
        )
    if "cross_flip" in ev:
        lines.append(
            f"- export faithfulness: Cycles' window reference vs mgn's, FLIP "
            f"{ev['cross_flip']:.4f}, mean radiance ratio {ev['cross_ratio']:.3f}"
        )
    peers = sorted(
        (r for r in ev["rows"] if r["engine"] == "cycles" and r["denoise"]),
        key=lambda r: r["cpu_seconds"],
    )
    mine = [r for r in ev["rows"] if r["engine"] == "mgn" and r["denoise"]]
    if peers and mine:
        lines += [
            "",
            "Target check: each denoised mgn point against what Cycles + OIDN reaches at the "
            "same size with the same and with 10× the CPU time (log-log interpolation between "
            "its measured sample counts; ≤ x: beyond its slowest point, an upper bound; n/a: "
            "its 1 spp is already slower).",
            "",
            "| mgn run | spp | CPU-s/view | wall s (load) | FLIP | Cycles + OIDN 1× | "
            "Cycles + OIDN 10× | target met |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for m in sorted(mine, key=lambda r: (r["run"], r["spp"])):
            cells = []
            for k in (1, 10):
                val, how = flip_at(peers, k * m["cpu_seconds"])
                cells.append(
                    (val, "n/a (slower)" if np.isnan(val) else
                     f"≤ {val:.4f}" if how.startswith("beyond") else f"{val:.4f}")
                )  # fmt: skip
            met = "—" if np.isnan(cells[1][0]) else ("yes" if m["flip"] <= cells[1][0] else "no")
            lines.append(
                f"| {_label(m)} | {m['spp']} | {m['cpu_seconds']:.2f} | {m['seconds']:.2f} "
                f"({m['load1']:.1f}) | {m['flip']:.4f} | {cells[0][1]} | {cells[1][1]} | {met} |"
            )
    return "\n".join(lines) + "\n"


def picture(work: Path, ev: dict[str, Any], tags: list[str], path: Path) -> None:
    """The window: each engine's reference, and each run's denoised 1 spp, tone-mapped alike."""
    import PIL.Image

    crop = tuple(ev["crop"])
    tiles = []
    for engine in ("mgn", "cycles"):
        got = _load(work / f"{engine}_ref")
        if got is None:
            continue
        e = exposure_of(got[1]["ref"])
        tiles.append(tonemap(got[1]["ref"], e))
        for run_name in tags:
            if run_name.startswith(engine) and (full := _load(work / f"{run_name}_full")):
                if "1d" in full[1]:
                    tiles.append(tonemap(_window(full[1]["1d"], crop), e))
    if tiles:
        img = np.concatenate(tiles, axis=1)
        PIL.Image.fromarray(np.clip(img * 255 + 0.5, 0, 255).astype(np.uint8)).save(path)


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks.bench_path --study")
    p.add_argument("study", choices=["full-res-crop"])
    p.add_argument("--work", default=str(Path(tempfile.gettempdir()) / "mgn_path_crop"))
    p.add_argument("--crop", default=",".join(map(str, CROP)), help="X0,Y0,SIZE in px")
    p.add_argument("--ref-spp", type=int, default=REF_SPP)
    p.add_argument("--parts", default="refs,renders,report")
    p.add_argument("--engines", default="mgn,cycles")
    p.add_argument("--tag", default="", help="name of this mgn build's runs (compare variants)")
    p.add_argument(
        "--spps",
        default="",
        help="override the sample counts (comma-separated; 0: adaptive rows only)",
    )
    p.add_argument("--adaptive", default=",".join(map(str, ADAPTIVE)),
                   help="mgn: adaptive_samples values of extra rows (empty: none)")  # fmt: skip
    p.add_argument("--report-tags", default="", help="runs in the report (default: all found)")
    p.add_argument("--out-dir", default=str(HERE))
    a = p.parse_args(argv)
    work = Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    x0, y0, size = (int(v) for v in a.crop.split(","))
    crop = (x0, y0, size)
    parts = set(a.parts.split(","))
    engines = [e for e in a.engines.split(",") if e]
    scene_json = work / "scene.json"
    if not scene_json.exists():
        ps.drop(scene_json)
    desc = ps.describe(scene_json, FULL_WIDTH)
    full_path, crop_path = work / "desc_full.pkl", work / "desc_crop.pkl"
    full_path.write_bytes(pickle.dumps(desc))
    crop_path.write_bytes(pickle.dumps(ps.crop(desc, x0, y0, size, size)))
    for engine in engines:
        if "refs" in parts and not (work / f"{engine}_ref.json").exists():
            _log(f"{engine}: {a.ref_spp}-spp reference of the window (load {load1():.1f})")
            _run(engine, crop_path, scene_json, (), a.ref_spp, work / f"{engine}_ref", _log)
        if "renders" in parts:
            spps = tuple(int(s) for s in a.spps.split(",") if s) or SPPS[engine]
            name = engine + (f"_{a.tag}" if a.tag else "")
            if spps != (0,):  # --spps 0: the adaptive rows only
                _log(f"{name}: full views at {spps} spp (load {load1():.1f})")
                _run(engine, full_path, scene_json, spps, 0, work / f"{name}_full", _log,
                     denoised_only=engine == "cycles")  # fmt: skip
            for b in (float(x) for x in a.adaptive.split(",") if x and engine == "mgn"):
                run_name = f"{name}_adaptive{b:g}".replace(".", "p")  # 0.25 -> adaptive0p25
                _log(f"{run_name}: full views at {ADAPTIVE_SPPS} spp + {b:g} adaptive samples "
                     f"(load {load1():.1f})")  # fmt: skip
                _run(engine, full_path, scene_json, ADAPTIVE_SPPS, 0, work / f"{run_name}_full",
                     _log, adaptive=b)  # fmt: skip
    if "report" in parts:
        tags = [t for t in a.report_tags.split(",") if t] or sorted(
            f.name[: -len("_full.json")] for f in work.glob("*_full.json")
        )
        ev = evaluate(work, crop, tags)
        out = Path(a.out_dir)
        out.mkdir(parents=True, exist_ok=True)
        (out / "path_crop_results.json").write_text(json.dumps(ev, indent=1, default=float) + "\n")
        (out / "path_crop_results.md").write_text(markdown(ev))
        picture(work, ev, tags, work / "window.png")
        if (out / "path_results.json").exists():  # path_results.md and RESULTS.md include it
            report_main(out / "path_results.json")
        _log(markdown(ev))
    return 0
