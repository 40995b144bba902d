"""Depth sensor model: CPU per 1200 x 1200 view of ``mgn.render.apply_depth_sensor``.

Standalone (not part of ``python -m benchmarks``): ``python -m benchmarks.bench_sensor``.

The input is a synthetic bin view: a floor tilted from 0.85 m to 1.15 m with 20 boxes 5-12 cm
above it (depth edges, projector shadows), every pixel seen, so ~1.4 M pixels get noise, as in
the pipeline's views. Each preset (structured light: the pipeline's default; ToF: flying pixels
too) is timed with its noise and with the noise switched off (sigma_a = sigma_b = 0), whose
difference is the cost of the noise itself. CPU time is ``time.process_time`` (all threads of
the process); wall time is reported alongside because the machine may be shared.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from mgn.render import apply_depth_sensor, sensor_params
from mgn.scene.cameras import Intrinsics

SIZE = 1200


def bin_view(size: int = SIZE, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(depth m, instance ids) of the synthetic bin view."""
    rng = np.random.default_rng(seed)
    v, u = np.mgrid[0:size, 0:size]
    depth = (0.85 + 0.3 * (v / size)).astype(np.float32)
    ids = np.zeros((size, size), np.int32)
    for k in range(20):
        w, h = rng.integers(size // 12, size // 5, 2)
        u0, v0 = rng.integers(0, size - w), rng.integers(0, size - h)
        depth[v0 : v0 + h, u0 : u0 + w] -= rng.uniform(0.05, 0.12)
        ids[v0 : v0 + h, u0 : u0 + w] = k + 1
    return depth, ids


def time_view(
    depth: np.ndarray, ids: np.ndarray, params: object, repeats: int
) -> tuple[float, float]:
    """(CPU s, wall s) per call, best of `repeats`."""
    K = Intrinsics(SIZE, SIZE, 1000.0, 1000.0, SIZE / 2, SIZE / 2)
    apply_depth_sensor(depth, ids, K, params, seed=1)  # warm-up
    cpu, wall = [], []
    for r in range(repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        apply_depth_sensor(depth, ids, K, params, seed=r)
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
    return min(cpu), min(wall)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    depth, ids = bin_view()
    print(f"load {os.getloadavg()[0]:.2f}, {SIZE}x{SIZE}, best of {args.repeats}")
    for preset in ("structured-light", "tof"):
        noisy = sensor_params(preset)
        quiet = sensor_params(preset, sigma_a=0.0, sigma_b=0.0)
        c1, w1 = time_view(depth, ids, noisy, args.repeats)
        c0, w0 = time_view(depth, ids, quiet, args.repeats)
        print(
            f"{preset:17s} CPU {1e3 * c1:6.1f} ms/view (wall {1e3 * w1:6.1f}); "
            f"without noise CPU {1e3 * c0:6.1f} ms (wall {1e3 * w0:6.1f}); "
            f"noise {1e3 * (c1 - c0):6.1f} CPU-ms/view"
        )


if __name__ == "__main__":
    main()
