"""Depth sensor model: views per second of ``mgn.render.apply_depth_sensor`` at 1200 x 1200.

The input is a synthetic bin view: a floor tilted from 0.85 m to 1.15 m with 20 boxes 5-12 cm
above it (depth edges, projector shadows), every pixel seen, so ~1.4 M pixels get noise, as in the
pipeline's views. Each preset (structured light: the pipeline's default; time of flight: flying
pixels too) is timed with 1 and N threads; the notes give the cost of the noise itself (the same
call with sigma_a = sigma_b = 0 subtracted) and whether 1 and N threads give the same bytes.
There is no peer: no library models these sensors.

    python -m benchmarks --only sensor [--quick]      (quick: 600 x 600)
    python -m benchmarks.bench_sensor
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .common import Row, measure_alternating, thread_counts

SIZE = 1200


def bin_view(size: int = SIZE, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(depth m, instance ids) of the synthetic bin view."""
    rng = np.random.default_rng(seed)
    v, _ = np.mgrid[0:size, 0:size]
    depth = (0.85 + 0.3 * (v / size)).astype(np.float32)
    ids = np.zeros((size, size), np.int32)
    for k in range(20):
        w, h = rng.integers(size // 12, size // 5, 2)
        u0, v0 = rng.integers(0, size - w), rng.integers(0, size - h)
        depth[v0 : v0 + h, u0 : u0 + w] -= rng.uniform(0.05, 0.12)
        ids[v0 : v0 + h, u0 : u0 + w] = k + 1
    return depth, ids


def _call(depth: np.ndarray, ids: np.ndarray, params: Any, threads: int) -> Callable[[], Any]:
    """One sensor call on the view (seed 1) with ``threads`` threads."""
    from mgn.render import apply_depth_sensor
    from mgn.scene.cameras import Intrinsics

    h, w = depth.shape
    f = 1000.0 * w / SIZE
    K = Intrinsics(w, h, f, f, w / 2, h / 2)
    return lambda: apply_depth_sensor(depth, ids, K, params, seed=1, num_threads=threads)


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any | None,
    mgn_status: str,
    log: Callable[[str], None],
) -> list[Row]:
    size = 600 if quick else SIZE
    depth, ids = bin_view(size)
    threads = thread_counts()
    rows = []
    for preset in ("structured-light", "tof"):
        row = Row(
            group="depth sensor",
            case=f"{preset}, {size}x{size} bin view, noise + depth grid",
            n=1,
            unit="views/s",
            peer_name="—",
            mgn_status=mgn_status,
            peer_status="no peer (no library models these sensors)",
        )
        rows.append(row)
        if mgn is None:
            continue
        from mgn.render import sensor_params

        noisy = sensor_params(preset)
        quiet = sensor_params(preset, sigma_a=0.0, sigma_b=0.0)
        cases = {f"mgn/{t}": _call(depth, ids, noisy, t) for t in threads}
        cases["quiet/1"] = _call(depth, ids, quiet, 1)
        results = {k: fn() for k, fn in cases.items()}  # warm-up; compared below
        timings = measure_alternating(cases, repeats)
        row.mgn = {t: timings[f"mgn/{t}"] for t in threads}
        a, b = results[f"mgn/{threads[0]}"], results[f"mgn/{threads[-1]}"]
        same = np.array_equal(np.asarray(a.depth), np.asarray(b.depth), equal_nan=True)
        row.agreement = f"1 and {threads[-1]} threads: " + ("same bytes" if same else "DIFFER")
        row.agreement_ok = same
        noise_ms = 1e3 * (timings["mgn/1"].median - timings["quiet/1"].median)
        row.notes.append(
            f"1 thread: {1e3 * timings['mgn/1'].median:.1f} ms per view, of which the noise "
            f"{noise_ms:.1f} ms (the same call without noise: "
            f"{1e3 * timings['quiet/1'].median:.1f} ms)"
        )
        log(f"  sensor: {preset} {1e3 * timings['mgn/1'].median:.1f} ms per view (1 thread)")
    return rows


if __name__ == "__main__":
    import sys

    from .common import import_mgn, markdown_table

    mgn_mod, status = import_mgn()
    out = run(quick=False, repeats=7, mgn=mgn_mod, mgn_status=status, log=print)
    print(markdown_table(out, thread_counts()))
    for r in out:
        print("\n".join(r.notes))
    sys.exit(0 if all(r.agreement_ok is not False for r in out) else 1)
