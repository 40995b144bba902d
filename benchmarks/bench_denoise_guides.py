"""Open Image Denoise's guide images on five windows of the 1200 x 1200 path-traced view.

``python -m benchmarks.bench_denoise_guides --work GLASS_DIR --window NAME=X,Y,DIR ...
[--seeds 0,1,2] [--repeats 5] [--out-dir DIR]``

The view of ``python -m benchmarks.bench_path --study full-res-crop`` (``GLASS_DIR`` is its work
folder: scene, pickled camera and the 1024-spp reference of the window (400, 130, 320)) is traced
at 1 spp (2 threads) once per seed; every variant below denoises the same buffers (quality
``fast``) and is scored with the study's FLIP on each window against that window's own reference
(``--window NAME=X,Y,DIR``: a work folder of ``bench_path --study full-res-crop --crop X,Y,320``
holding ``mgn_ref.npz``; the glass window is always included). OIDN CPU seconds
(``time.process_time``: OIDN's threads run in this process) and wall seconds per variant are the
median of ``--repeats`` calls on seed 0's buffers, the variants interleaved so that a changing
load hits them alike (the machine is shared).

Variants: albedo + normal guides as traced (``photo.denoise``'s ``raw``, the default before this
study), albedo only, both with OIDN's ``cleanAux`` (the guides declared noise-free), no guides,
the guides prefiltered by OIDN's own filter (the documented way to use ``cleanAux`` with noisy
guides), and the guides blurred by a 3 x 3 Gaussian (OpenCV; sigma 0.35-0.8 px) with and without
``cleanAux``: ``photo.denoise``'s ``smoothed`` (its NumPy blur, sigma 0.5, ``cleanAux``).
Also measured: how noisy the tracer's 1-spp guides are (two seeds compared) and the Python time
around the denoiser in ``photo.denoise`` (input clean-up, output clamp).

Not part of ``python -m benchmarks`` (it needs the study's work folders); the numbers are
written by hand into benchmarks/RESULTS.md ("Denoiser guides on five windows").
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

import numpy as np

from . import path_scene as ps
from .bench_path import _engine_mgn, exposure_of, flip_error, tonemap

GLASS = (400, 130)
SIZE = 320
Buffers = tuple[np.ndarray, np.ndarray, np.ndarray]


class _Oidn:
    """One pyoidn CPU device (2 threads) and RT filter per variant, set up at the first call."""

    def __init__(
        self, guides: str, clean_aux: bool, prefilter: bool = False, blur: float = 0.0
    ) -> None:
        import pyoidn

        self.oidn, self.guides, self.clean_aux, self.prefilter = (
            pyoidn,
            guides,
            clean_aux,
            prefilter,
        )
        self.blur = blur
        self.dev = pyoidn.Device()
        self.dev.set_int("numThreads", 2)
        self.dev.commit()
        self.flt = pyoidn.Filter(self.dev, "RT")
        self.aux = {k: pyoidn.Filter(self.dev, "RT") for k in ("albedo", "normal")}

    def _pre(self, name: str, img: np.ndarray) -> np.ndarray:
        """OIDN's prefilter of a guide: the RT filter with the guide bound as albedo / normal
        and as output (in place)."""
        f, fmt = self.aux[name], self.oidn.OIDN_FORMAT_FLOAT3
        out = img.copy()
        f.set_image(name, img, fmt)
        f.set_image("output", out, fmt)
        f.set_quality(self.oidn.OIDN_QUALITY_FAST)
        f.commit()
        f.execute()
        return out

    def __call__(self, b: Buffers) -> np.ndarray:
        fmt = self.oidn.OIDN_FORMAT_FLOAT3
        c = np.ascontiguousarray(np.nan_to_num(b[0], nan=0.0, posinf=0.0), np.float32)
        a = np.ascontiguousarray(np.clip(b[1], 0.0, 1.0), np.float32)
        n = np.ascontiguousarray(np.clip(b[2], -1.0, 1.0), np.float32)
        if self.blur > 0.0:  # a cheap prefilter: 3 x 3 Gaussian of the guides (OpenCV)
            import cv2

            a = cv2.GaussianBlur(a, (3, 3), self.blur)
            n = cv2.GaussianBlur(n, (3, 3), self.blur)
        if self.prefilter:
            a = self._pre("albedo", a)
            n = self._pre("normal", n) if "n" in self.guides else n
        out = np.empty_like(c)
        self.flt.set_image("color", c, fmt)
        if "a" in self.guides:
            self.flt.set_image("albedo", a, fmt)
        if "n" in self.guides:
            self.flt.set_image("normal", n, fmt)
        self.flt.set_image("output", out, fmt)
        self.flt.set_bool("hdr", True)
        self.flt.set_bool("cleanAux", self.clean_aux)
        self.flt.set_quality(self.oidn.OIDN_QUALITY_FAST)
        self.flt.commit()
        self.flt.execute()
        err = self.dev.get_error()
        if err is not None:
            raise RuntimeError(f"OIDN: {err}")
        return np.maximum(out, 0.0)


def _photo(guides: str) -> Callable[[], Callable[[Buffers], np.ndarray]]:
    def make() -> Callable[[Buffers], np.ndarray]:
        from mgn.render.photo import denoise

        return lambda b: denoise(b[0], b[1], b[2], "fast", num_threads=2, guides=guides)

    return make


VARIANTS: list[tuple[str, Callable[[], Callable[[Buffers], np.ndarray]]]] = [
    ("albedo + normal (photo.denoise guides raw)", _photo("raw")),
    ("albedo + normal", lambda: _Oidn("an", False)),
    ("albedo only", lambda: _Oidn("a", False)),
    ("albedo + normal, cleanAux", lambda: _Oidn("an", True)),
    ("albedo only, cleanAux", lambda: _Oidn("a", True)),
    ("no guides", lambda: _Oidn("", False)),
    ("albedo + normal prefiltered, cleanAux", lambda: _Oidn("an", True, prefilter=True)),
    ("albedo prefiltered, cleanAux", lambda: _Oidn("a", True, prefilter=True)),
    ("albedo + normal blurred 3x3 sigma 0.5, cleanAux", lambda: _Oidn("an", True, blur=0.5)),
    ("albedo + normal blurred 3x3 sigma 0.8, cleanAux", lambda: _Oidn("an", True, blur=0.8)),
    ("albedo + normal blurred 3x3 sigma 0.8", lambda: _Oidn("an", False, blur=0.8)),
    ("photo.denoise guides smoothed (sigma 0.5, NumPy)", _photo("smoothed")),
    ("albedo + normal blurred 3x3 sigma 0.35, cleanAux", lambda: _Oidn("an", True, blur=0.35)),
    ("albedo + normal blurred 3x3 sigma 0.65, cleanAux", lambda: _Oidn("an", True, blur=0.65)),
    ("albedo only blurred 3x3 sigma 0.5", lambda: _Oidn("a", True, blur=0.5)),
]


def _clock() -> tuple[float, float]:
    return time.perf_counter(), time.process_time()


def guide_noise(b0: Buffers, b1: Buffers) -> dict[str, float]:
    """How much the 1-spp guides change between two seeds (0 for noise-free guides)."""
    r: dict[str, float] = {}
    for k, name in ((1, "albedo"), (2, "normal")):
        d = np.abs(b0[k] - b1[k]).max(axis=2)
        r[f"{name}_mean_abs"] = float(d.mean())
        r[f"{name}_frac_gt_0.05"] = float(np.mean(d > 0.05))
    return r


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks.bench_denoise_guides")
    p.add_argument("--work", required=True, help="the full-res-crop study's work folder")
    p.add_argument("--window", action="append", default=[], help="NAME=X,Y,DIR (repeatable)")
    p.add_argument("--seeds", default="0,1,2")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--only", default="", help="comma-separated variant numbers")
    p.add_argument("--out-dir", default=str(Path(tempfile.gettempdir()) / "mgn_guides"))
    a = p.parse_args(argv)
    work, out_dir = Path(a.work), Path(a.out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    windows: list[tuple[str, int, int, Path]] = [("glass", *GLASS, work)]
    for w in a.window:
        name, rest = w.split("=", 1)
        x, y, d = rest.split(",", 2)
        windows.append((name, int(x), int(y), Path(d)))
    refs = {}
    for name, x, y, d in windows:
        ref = np.load(d / "mgn_ref.npz")["ref"]
        e = exposure_of(ref)
        refs[name] = (x, y, e, tonemap(ref, e))
    desc: ps.SceneDesc = pickle.loads((work / "desc_full.pkl").read_bytes())
    tmp = tempfile.TemporaryDirectory()
    trace = _engine_mgn(desc, work / "scene.json", Path(tmp.name))["trace"]
    seeds = [int(v) for v in a.seeds.split(",")]
    bufs: list[Buffers] = []
    for seed in seeds:
        t = trace(1, seed)
        bufs.append((np.asarray(t.radiance), np.asarray(t.albedo), np.asarray(t.normal)))
    noise = guide_noise(bufs[0], bufs[1]) if len(bufs) > 1 else {}
    print(f"guide noise between seeds {seeds[:2]}: {noise}", file=sys.stderr, flush=True)
    # The renderer's Python around OIDN: photo.denoise's input clean-up and output clamp.
    c0 = _clock()
    cl = np.ascontiguousarray(np.nan_to_num(bufs[0][0], nan=0.0, posinf=0.0), np.float32)
    np.ascontiguousarray(np.clip(bufs[0][1], 0.0, 1.0), np.float32)
    np.ascontiguousarray(np.clip(bufs[0][2], -1.0, 1.0), np.float32)
    c1 = _clock()
    np.maximum(cl, 0.0, out=cl)
    c2 = _clock()
    python_side = {"input_wall": c1[0] - c0[0], "input_cpu": c1[1] - c0[1],
                   "output_wall": c2[0] - c1[0], "output_cpu": c2[1] - c1[1]}  # fmt: skip
    only = {int(v) for v in a.only.split(",") if v}
    chosen = [(i, n, mk()) for i, (n, mk) in enumerate(VARIANTS) if not only or i in only]
    first: dict[int, tuple[float, float]] = {}
    for i, _, fn in chosen:  # first calls: device set-up and scratch
        w0 = _clock()
        fn(bufs[0])
        w1 = _clock()
        first[i] = (w1[0] - w0[0], w1[1] - w0[1])
    times: dict[int, list[tuple[float, float]]] = {i: [] for i, _, _ in chosen}
    loads = []
    for _ in range(a.repeats):
        for i, _, fn in chosen:
            loads.append(os.getloadavg()[0])
            w0 = _clock()
            fn(bufs[0])
            w1 = _clock()
            times[i].append((w1[0] - w0[0], w1[1] - w0[1]))
    (out_dir / "times.json").write_text(json.dumps({"times": times, "first": first}) + "\n")
    rows = []
    for i, name, fn in chosen:
        flips: dict[str, list[float]] = {w: [] for w in refs}
        for k, b in enumerate(bufs):
            img = fn(b)
            for w, (x, y, e, ref_t) in refs.items():
                test = tonemap(img[y : y + SIZE, x : x + SIZE], e)
                flips[w].append(flip_error(ref_t, test))
                if k == 0:
                    np.save(out_dir / f"{w}_v{i}_s0.npy", test.astype(np.float32))
        row = {
            "variant": name,
            "index": i,
            "cpu": float(np.median([c for _, c in times[i]])),
            "wall": float(np.median([w for w, _ in times[i]])),
            "first_cpu": first[i][1],
            "first_wall": first[i][0],
            "flip": flips,
            "flip_mean": {w: float(np.mean(v)) for w, v in flips.items()},
        }
        rows.append(row)
        cells = " ".join(f"{w} {row['flip_mean'][w]:.4f}" for w in refs)
        print(f"[{i}] {name}: {row['cpu']:.2f} CPU-s / {row['wall']:.2f} s; {cells}",
              file=sys.stderr, flush=True)  # fmt: skip
    for w, (_, _, _, ref_t) in refs.items():
        np.save(out_dir / f"{w}_ref.npy", ref_t.astype(np.float32))
    result = {"rows": rows, "guide_noise": noise, "python_side": python_side,
              "load1_mean": float(np.mean(loads)) if loads else None, "seeds": seeds,
              "windows": {w: [x, y] for w, (x, y, _, _) in refs.items()}}  # fmt: skip
    tmp.cleanup()
    (out_dir / "guides.json").write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
