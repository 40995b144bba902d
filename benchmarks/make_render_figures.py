"""Regenerates the pictures of docs/rendering.md: one scene rendered by mgn's raster engine, by
mgn's path tracer at the demo's settings (1 spp + OIDN `fast`, as scripts/demo.yaml) and at a
high sample count (256 spp, not denoised), and by Blender Cycles; the same for a glass scene,
plus a close-up of its glass objects.

    python -m benchmarks.make_render_figures [--width 480] [--cycles-spp 256] [--out docs/images]

Same scene, lights and camera as the path benchmark (benchmarks/path_scene.py); the path-traced
and Cycles images go through the same film (``mgn.render.path.develop``: exposure, filmic curve,
sRGB), so they differ only by the renderer. Each engine runs in its own process (bench_path's
child), as in the benchmark. PNGs are colour-quantised to stay small (< 400 KB).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import pickle
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from . import path_scene as ps
from .bench_path import raster_ids, raster_render, run_child

ROOT = Path(__file__).resolve().parent.parent
GLASS_NAMES = ("wine_glass", "bottle_clear", "can_soda", "box_tea", "tennis_ball", "pear", "mug")


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def save_png(rgb: np.ndarray, path: Path, max_kib: int = 400) -> None:
    """Writes an sRGB uint8 image as PNG; quantised to a palette if the plain PNG is too big."""
    from PIL import Image

    img = Image.fromarray(np.asarray(rgb, np.uint8))
    img.save(path, optimize=True)
    if path.stat().st_size > max_kib * 1024:
        img.quantize(
            colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.FLOYDSTEINBERG
        ).save(path, optimize=True)
    log(f"  wrote {path} ({path.stat().st_size // 1024} KiB)")


def raster_rgb(desc: ps.SceneDesc, scene_json: Path) -> np.ndarray:
    return np.asarray(raster_render(desc, scene_json).rgb, np.uint8)


def glass_camera(scene_json: Path, width: int) -> ps.Camera:
    """An oblique camera above the tote aimed between the glass objects."""

    from mgn.io.scene_json import read_scene_json

    scene = read_scene_json(scene_json)
    glass = [
        np.asarray(i.X_WO, np.float64)[:3, 3]
        for i in scene.instances
        if i.name in ("wine_glass", "bottle_clear")
    ]
    target = np.mean(glass, axis=0) if glass else np.zeros(3)
    eye = target + np.array([0.0, -0.14, 0.42])
    z = target - eye
    z /= np.linalg.norm(z)
    x = np.cross(z, np.array([0.0, 0.0, 1.0]))
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    X = np.eye(4)
    X[:3, 0], X[:3, 1], X[:3, 2], X[:3, 3] = x, y, z, eye
    f = 1.5 * width
    return ps.Camera(width, width, f, f, width / 2, width / 2, X)


def render_set(
    name: str,
    desc: ps.SceneDesc,
    scene_json: Path,
    tmp: Path,
    mgn_spp: int,
    high_spp: int,
    cycles_spp: int,
    exposure: float,
    out: Path,
    closeup: tuple[str, ...] = (),
) -> dict[str, float]:
    from mgn.render import path as mpath

    desc_path = tmp / f"{name}.pkl"
    desc_path.write_bytes(pickle.dumps(desc))
    times: dict[str, float] = {}
    save_png(raster_rgb(desc, scene_json), out / f"{name}_raster.png")
    film = mpath.FilmOptions(exposure=exposure)
    res, status = run_child(
        "mgn", desc_path, scene_json, (mgn_spp, high_spp), 0, 1, tmp / f"{name}_mgn.npz", log
    )
    if res is None:
        raise RuntimeError(f"mgn path failed: {status}")
    with np.load(tmp / f"{name}_mgn.npz") as z:
        demo, high, ids = z[f"{mgn_spp}d"], z[f"{high_spp}"], z["ids"]
    save_png(mpath.develop(demo, film), out / f"{name}_path.png")
    save_png(mpath.develop(high, film), out / f"{name}_path_high.png")
    for c in res["configs"]:
        if c["spp"] == mgn_spp and c["denoise"]:
            times["mgn"] = c["wall"][0]
        if c["spp"] == high_spp and not c["denoise"]:
            times["mgn_high"] = c["wall"][0]
    res, status = run_child(
        "cycles", desc_path, scene_json, (), cycles_spp, 1, tmp / f"{name}_cycles.npz", log
    )
    if res is None:
        raise RuntimeError(f"Cycles failed: {status}")
    with np.load(tmp / f"{name}_cycles.npz") as z:
        cycles = z["ref"]
    save_png(mpath.develop(cycles, film), out / f"{name}_cycles.png")
    times["cycles"] = res["ref"]["wall"]
    log(
        f"  {name}: mgn {mgn_spp} spp + OIDN {times['mgn']:.1f} s, {high_spp} spp "
        f"{times['mgn_high']:.1f} s, Cycles {cycles_spp} spp {times['cycles']:.1f} s"
    )
    if closeup:
        # The glass objects' bounding box (+ a margin), each image enlarged 2x, side by side.
        sel = [it.instance_id for it in desc.items if it.name in closeup]
        ys, xs = np.nonzero(np.isin(ids, sel))
        if len(ys):
            m = 6
            y0, y1 = max(0, ys.min() - m), min(ids.shape[0], ys.max() + 1 + m)
            x0, x1 = max(0, xs.min() - m), min(ids.shape[1], xs.max() + 1 + m)
            tiles = [mpath.develop(np.ascontiguousarray(i[y0:y1, x0:x1]), film) for i in
                     (demo, high, cycles)]  # fmt: skip
            gap = np.full((y1 - y0, 4, 3), 255, np.uint8)
            strip = np.concatenate([tiles[0], gap, tiles[1], gap, tiles[2]], 1)
            save_png(np.repeat(np.repeat(strip, 2, 0), 2, 1), out / f"{name}_closeup.png")
    return times


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m benchmarks.make_render_figures", description=__doc__
    )
    p.add_argument("--width", type=int, default=480)
    p.add_argument("--mgn-spp", type=int, default=1, help="denoised (the demo's setting)")
    p.add_argument("--high-spp", type=int, default=256, help="mgn without denoising")
    p.add_argument("--cycles-spp", type=int, default=256)
    p.add_argument("--exposure", type=float, default=0.5, help="EV for both path-traced images")
    p.add_argument("--out", type=Path, default=ROOT / "docs" / "images")
    a = p.parse_args(argv)
    a.out.mkdir(parents=True, exist_ok=True)
    info = {
        "width": a.width,
        "mgn_spp": a.mgn_spp,
        "high_spp": a.high_spp,
        "cycles_spp": a.cycles_spp,
    }
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        scene_json = tmp / "scene.json"
        t0 = time.perf_counter()
        ps.drop(scene_json)
        log(f"scene dropped in {time.perf_counter() - t0:.0f} s")
        desc = ps.describe(scene_json, a.width)
        assert np.mean(raster_ids(desc, scene_json) > 0) > 0.1, "the camera sees no objects"
        info["bin"] = render_set(
            "render_bin", desc, scene_json, tmp, a.mgn_spp, a.high_spp, a.cycles_spp,
            a.exposure, a.out,
        )  # fmt: skip
        glass_json = tmp / "glass.json"
        ps.drop(glass_json, GLASS_NAMES, seed=3)
        glass = ps.describe(glass_json, a.width)
        glass = dataclasses.replace(glass, camera=glass_camera(glass_json, a.width))
        info["glass"] = render_set(
            "render_glass", glass, glass_json, tmp, a.mgn_spp, a.high_spp, a.cycles_spp,
            a.exposure, a.out, closeup=("wine_glass", "bottle_clear"),
        )  # fmt: skip
    (a.out / "render_figures.json").write_text(json.dumps(info, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
