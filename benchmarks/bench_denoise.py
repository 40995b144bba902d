"""The denoiser's share of a 1200 x 1200 path-traced view: Open Image Denoise alone, its variants.

``python -m benchmarks.bench_denoise [--work DIR] [--seeds 0,1,2,3] [--repeats 3] [--out F.json]``

Uses the work folder of ``python -m benchmarks.bench_path --study full-res-crop`` (its scene, the
pickled 1200 x 1200 camera and mgn's 1024-spp reference of the 320 x 320 window): traces the view
at 1 spp (as the study's denoised 1-spp row, 2 threads) once per seed, then times only the
denoiser call on those buffers: CPU seconds (``time.process_time``: OIDN's threads run in this
process) and wall seconds, the first call of the process (device and filter set-up, scratch
allocation) apart from the later ones, and scores each variant with the study's FLIP on the window
(mean over the seeds and seed 0 alone, which is the study's row).

Variants: ``mgn.render.photo.denoise`` as the renderer calls it (albedo + normal guides, quality
``fast``), then pyoidn devices and filters driven directly: one OIDN thread, ``setAffinity``,
float16 buffers, a larger ``maxMemoryMB`` (OIDN tiles an image that does not fit its memory
limit), albedo-only and colour-only guides, qualities ``balanced`` and ``high``; and the cost of
the input clean-up in ``denoise`` (NaN/inf removal, guide clipping: NumPy, one thread).

Not part of ``python -m benchmarks`` (it needs the study's work folder); the numbers are written
by hand into benchmarks/RESULTS.md ("Denoiser cost").
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from . import path_scene as ps
from .bench_path import _engine_mgn, exposure_of, flip_error, tonemap

CROP = (400, 130, 320)  # the study's window: x0, y0, size (px)
Buffers = tuple[np.ndarray, np.ndarray, np.ndarray]


def _clean(rad: np.ndarray, alb: np.ndarray, nrm: np.ndarray, dtype: Any = np.float32) -> Buffers:
    c = np.ascontiguousarray(np.nan_to_num(rad, nan=0.0, posinf=0.0), dtype)
    a = np.ascontiguousarray(np.clip(alb, 0.0, 1.0), dtype)
    n = np.ascontiguousarray(np.clip(nrm, -1.0, 1.0), dtype)
    return c, a, n


def _direct(
    threads: int = 0,
    affinity: bool | None = None,
    half: bool = False,
    guides: str = "an",
    quality: str = "fast",
    max_memory_mb: int | None = None,
) -> Callable[[Buffers], np.ndarray]:
    """A denoiser on its own pyoidn device and RT filter, set up at its first call."""
    import pyoidn

    state: dict[str, Any] = {}
    fmt = pyoidn.OIDN_FORMAT_HALF3 if half else pyoidn.OIDN_FORMAT_FLOAT3
    q = {"fast": pyoidn.OIDN_QUALITY_FAST, "balanced": pyoidn.OIDN_QUALITY_BALANCED,
         "high": pyoidn.OIDN_QUALITY_HIGH}[quality]  # fmt: skip

    def run(bufs: Buffers) -> np.ndarray:
        if not state:
            dev = pyoidn.Device()
            if threads:
                dev.set_int("numThreads", threads)
            if affinity is not None:
                dev.set_bool("setAffinity", affinity)
            dev.commit()
            state["dev"], state["flt"] = dev, pyoidn.Filter(dev, "RT")
        dev, flt = state["dev"], state["flt"]
        c, a, n = _clean(*bufs, np.float16 if half else np.float32)
        out = np.empty_like(c)
        flt.set_image("color", c, fmt)
        if "a" in guides:
            flt.set_image("albedo", a, fmt)
        if "n" in guides:
            flt.set_image("normal", n, fmt)
        flt.set_image("output", out, fmt)
        flt.set_bool("hdr", True)
        flt.set_quality(q)
        if max_memory_mb is not None:
            flt.set_int("maxMemoryMB", max_memory_mb)
        flt.commit()
        flt.execute()
        err = dev.get_error()
        if err is not None:
            raise RuntimeError(f"OIDN: {err}")
        return np.maximum(out.astype(np.float32), 0.0)

    return run


def _photo() -> Callable[[Buffers], np.ndarray]:
    from mgn.render.photo import denoise

    return lambda b: denoise(b[0], b[1], b[2], "fast", num_threads=2)


VARIANTS: list[tuple[str, Callable[[], Callable[[Buffers], np.ndarray]]]] = [
    ("photo.denoise (albedo + normal, fast): mgn today", _photo),
    ("pyoidn direct, same settings", lambda: _direct()),
    ("1 OIDN thread", lambda: _direct(threads=1)),
    ("setAffinity on", lambda: _direct(affinity=True)),
    ("float16 buffers", lambda: _direct(half=True)),
    ("maxMemoryMB 8000", lambda: _direct(max_memory_mb=8000)),
    ("albedo guide only", lambda: _direct(guides="a")),
    ("no guides (colour only)", lambda: _direct(guides="")),
    ("quality balanced", lambda: _direct(quality="balanced")),
    ("quality high", lambda: _direct(quality="high")),
]


def _clock() -> tuple[float, float]:
    return time.perf_counter(), time.process_time()


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks.bench_denoise")
    p.add_argument("--work", default=str(Path(tempfile.gettempdir()) / "mgn_path_crop"))
    p.add_argument("--seeds", default="0,1,2,3")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--only", default="", help="comma-separated variant numbers (0 = mgn today)")
    p.add_argument("--out", default="")
    a = p.parse_args(argv)
    work = Path(a.work)
    desc: ps.SceneDesc = pickle.loads((work / "desc_full.pkl").read_bytes())
    ref = np.load(work / "mgn_ref.npz")["ref"]
    e = exposure_of(ref)
    ref_t = tonemap(ref, e)
    x0, y0, s = CROP
    tmp = tempfile.TemporaryDirectory()
    trace = _engine_mgn(desc, work / "scene.json", Path(tmp.name))["trace"]
    bufs = []
    for seed in (int(v) for v in a.seeds.split(",")):
        out = trace(1, seed)
        bufs.append((out.radiance, out.albedo, out.normal))
    rows: list[dict[str, Any]] = []
    clean = []
    for _ in range(a.repeats + 1):
        w0, c0 = _clock()
        _clean(*bufs[0])
        w1, c1 = _clock()
        clean.append((w1 - w0, c1 - c0))
    only = {int(v) for v in a.only.split(",") if v}
    for i, (name, make) in enumerate(VARIANTS):
        if only and i not in only:
            continue
        fn = make()
        w0, c0 = _clock()
        img = fn(bufs[0])
        w1, c1 = _clock()
        first = (w1 - w0, c1 - c0)
        steady, loads = [], []
        for _ in range(a.repeats):
            loads.append(os.getloadavg()[0])
            w0, c0 = _clock()
            again = fn(bufs[0])
            w1, c1 = _clock()
            steady.append((w1 - w0, c1 - c0))
        after_trace = []  # as in a render: each call right after tracing the view
        for _ in range(a.repeats if i == 0 else 0):
            out = trace(1, 0)
            w0, c0 = _clock()
            fn((out.radiance, out.albedo, out.normal))
            w1, c1 = _clock()
            after_trace.append((w1 - w0, c1 - c0))
        flips = []
        for k, b in enumerate(bufs):
            img_k = img if k == 0 else fn(b)
            flips.append(flip_error(ref_t, tonemap(img_k[y0 : y0 + s, x0 : x0 + s], e)))
        row = {
            "variant": name,
            "first_wall": first[0],
            "first_cpu": first[1],
            "wall": float(np.median([w for w, _ in steady])),
            "cpu": float(np.median([c for _, c in steady])),
            "load1": float(np.mean(loads)),
            "flip_seed0": flips[0],
            "flip_mean": float(np.mean(flips)),
            "repeatable": bool(np.array_equal(img, again)),
        }
        if after_trace:
            row["after_trace_wall"] = float(np.median([w for w, _ in after_trace]))
            row["after_trace_cpu"] = float(np.median([c for _, c in after_trace]))
            print(f"  right after tracing: {row['after_trace_cpu']:.2f} CPU-s / "
                  f"{row['after_trace_wall']:.2f} s", file=sys.stderr)  # fmt: skip
        rows.append(row)
        print(
            f"{name}: first {first[1]:.2f} CPU-s / {first[0]:.2f} s; then {row['cpu']:.2f} CPU-s"
            f" / {row['wall']:.2f} s (load {row['load1']:.1f}); FLIP {flips[0]:.4f} (seed 0), "
            f"{row['flip_mean']:.4f} (mean of {len(flips)})",
            file=sys.stderr,
            flush=True,
        )
    result = {
        "rows": rows,
        "input_cleanup": {
            "wall": float(np.median([w for w, _ in clean[1:]])),
            "cpu": float(np.median([c for _, c in clean[1:]])),
        },
        "seeds": a.seeds,
    }
    tmp.cleanup()
    print(json.dumps(result, indent=1))
    if a.out:
        Path(a.out).write_text(json.dumps(result, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
