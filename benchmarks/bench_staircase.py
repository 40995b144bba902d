"""Staircase search of the shake test against MetaGraspNet's full 10x10 grid on real grasps.

For several built-in objects, parallel-jaw grasps come from mgn's own labeller (antipodal
sampling, collision-free); each grasp is scored twice with the same trials: over the full
friction x density grid, and with ``ShakeOptions(staircase=True)`` (walk the monotone success
boundary, check cells next to it, fall back to the full grid where a check fails). Reported:
identical scores, mean absolute score difference, trials per grasp, fallback share, time.

    python -m benchmarks.bench_staircase [--grasps-per-object 170] [--objects a,b,c]

Measured 2026-11-24 on the shared 2-core machine (load average ~20, so times are long; the
ratios hold), 10x10 grid, default options, 170 labelled grasps per object:
  box_tea   165/170 identical scores, mean |diff| 0.0006, 15.0 trials/grasp, 2 fallbacks
  can_soda  150/170 identical scores, mean |diff| 0.0065, 22.3 trials/grasp, 16 fallbacks
  together  315/340 identical (92.6 %; target 99 % not reached: single trials near the boundary
            are not monotone in friction/density), 5.4x fewer trials (full grid 100/grasp);
            staircase time 96.9 + 229.3 s against 807.6 + 1229.6 s for the full grid.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def real_grasps(name: str, n: int, seed: int = 0):
    from mgn.geometry import mass_properties
    from mgn.geometry.convex import cached_convex_decomposition
    from mgn.objects import get_object
    from mgn.pj.labels import label_object

    spec = get_object(name)
    mesh = spec.to_mesh()
    props = mass_properties(mesh, spec.density)
    labels = label_object(
        mesh, mass=props.mass, com=props.center_of_mass, num_points=1500, seed=seed
    )
    k = len(labels)
    idx = np.unique(np.linspace(0, k - 1, min(n, k)).round().astype(np.int64))
    rows = np.concatenate(
        [
            np.asarray(labels.approach, np.float64)[idx],
            np.asarray(labels.closing, np.float64)[idx],
            np.asarray(labels.p1, np.float64)[idx],
            np.asarray(labels.width, np.float64)[idx, None],
        ],
        axis=1,
    )
    return cached_convex_decomposition(mesh), props, rows


def main(argv: list[str] | None = None) -> int:
    from mgn.pj.physics import ShakeOptions, shake_scores

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grasps-per-object", type=int, default=170)
    ap.add_argument("--objects", default="box_cereal,can_soda,mug")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args(argv)
    total = same = 0
    diffs: list[float] = []
    trials_stair = trials_full = 0
    t_full = t_stair = 0.0
    fallbacks = 0
    for name in args.objects.split(","):
        parts, props, rows = real_grasps(name, args.grasps_per_object)
        base = dict(num_threads=args.threads)

        def run(staircase: bool, parts=parts, props=props, rows=rows, base=base):
            t0 = time.perf_counter()
            r = shake_scores(
                parts,
                props.mass,
                props.center_of_mass,
                props.inertia,
                rows,
                None,
                ShakeOptions(staircase=staircase, **base),
            )
            return r, time.perf_counter() - t0

        full, tf = run(False)
        stair, ts = run(True)
        n_same = int(np.sum(full.score == stair.score))
        print(
            f"{name}: {len(rows)} grasps, identical scores {n_same}/{len(rows)}, "
            f"mean |diff| {np.mean(np.abs(full.score - stair.score)):.4f}, "
            f"trials/grasp {stair.num_trials / len(rows):.1f} "
            f"(full {full.num_trials / len(rows):.0f}), "
            f"fallback {int(stair.fallback.sum())}, time full {tf:.1f} s staircase {ts:.1f} s, "
            f"mean score {full.score.mean():.3f}",
            flush=True,
        )
        total += len(rows)
        same += n_same
        diffs += list(np.abs(full.score - stair.score))
        trials_stair += stair.num_trials
        trials_full += full.num_trials
        t_full += tf
        t_stair += ts
        fallbacks += int(stair.fallback.sum())
    print(
        f"ALL: {total} grasps, identical scores {same}/{total} ({100.0 * same / total:.2f} %), "
        f"mean |diff| {np.mean(diffs):.4f}, max |diff| {np.max(diffs):.2f}, "
        f"trials/grasp {trials_stair / total:.1f} vs {trials_full / total:.0f}, "
        f"fallback {fallbacks}, time {t_stair:.1f} s vs {t_full:.1f} s "
        f"({trials_full / t_full:.0f} full-grid trials/s)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
