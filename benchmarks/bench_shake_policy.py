"""ShakeScorer's object-level staircase policy replayed on stored full grids (no physics).

The policy (``mgn.pj.ShakeScorer.calibration_grasps``, ``mgn.pj.calibrate_staircase``): the
first K grasps of an object are simulated on the full 10x10 grid and keep its scores; the
staircase search is replayed on their grids, and if it differs from the full grid on any of them
the object's other grasps are scored on the full grid too, else with the staircase search. Every
cell of a grid is a deterministic trial (its own random stream, whichever search simulates it),
so the scores and trial counts of the policy are a function of the stored full grids: this
replays it on the grid caches of ``bench_staircase`` / ``bench_shake_speed`` and reports, per
physics, object and K, the identical scores against the full grid, the trials per grasp, the CPU
seconds per grasp (trials per grasp / the grid's trials per CPU-s, from the cache's ``cpu`` where
it has one) and the projected seconds for 2,000 grasps on 2 busy cores. Besides the first K
grasps, every cyclic window of K consecutive grasps is tried as the calibration set: the share
of windows that switch the object to the full grid, and the mean agreement over the windows
(how much the verdict depends on which grasps come first).

Cache files (``--grid-cache``): ``<prefix>_<object>.npz`` with ``success`` (G, 10, 10) and,
optionally, ``cpu`` (CPU s of those grids on 1 thread); the prefix of today's physics is
``full`` (its rate comes from ``default_<object>.npz``, bench_shake_speed's rerun of the first
grasps), f5's ``dt100f5``.

    python -m benchmarks.bench_shake_policy --grid-cache DIR \\
        [--physics today=full,f5=dt100f5] [--objects can_soda:100,...] [--k 0,8,16]
    python -m benchmarks.bench_shake_policy --real box_cereal:2000 --real-variant dt100f5

``--real name:N`` instead scores N grasps of the object (an evenly strided subset of mgn's
labeller's grasps) for real through ``ShakeScorer`` (the policy with its default calibration,
the staircase's default checks, ``--threads`` threads, ``--real-variant`` a bench_shake_speed
variant or ``default``) and reports wall and CPU seconds, the verdict and the score statistics.

Numbers and findings: benchmarks/RESULTS.md, "Shake test, session 12".
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

OBJECTS = "can_soda,box_cereal,mug,can_food,bottle_water,marker_pen,hex_nut"


def _rate(cache: Path, prefix: str, name: str) -> float | None:
    """Trials per CPU-s of the physics' full grids of this object (None: not measured)."""
    for p in ([cache / f"default_{name}.npz"] if prefix == "full" else []) + [
        cache / f"{prefix}_{name}.npz"
    ]:
        if p.is_file():
            d = np.load(p)
            if "cpu" in d.files and float(d["cpu"]) > 0:
                return d["success"].size / float(d["cpu"])
    return None


def policy(grids: np.ndarray, k: int, checks: int, start: int = 0, rows: int = -1):
    """(scores, trials, full-grid verdict) of the policy with calibration grasps start..start+k-1
    (cyclic), the others in their order; the search verifies the boundary in `rows` rows (-1:
    all)."""
    from mgn.pj.physics import calibrate_staircase, replay_staircase

    G, S = grids.shape[0], grids.shape[1]
    full = grids.sum(axis=(1, 2)) / float(S * S)
    stair, stair_trials = replay_staircase(grids, checks, rows)
    if k == 0:
        return stair, stair_trials, False
    cal = (start + np.arange(min(k, G))) % G
    verdict = calibrate_staircase(grids[cal], checks, 0, rows)
    scores = stair.copy() if verdict.staircase else full.copy()
    trials = stair_trials.copy() if verdict.staircase else np.full(G, S * S)
    scores[cal], trials[cal] = full[cal], S * S
    return scores, trials, not verdict.staircase


def real(item: str, variant: str, threads: int, checks: int | None) -> int:
    """Score N grasps of an object through ShakeScorer for real; print the cost."""
    import os
    import time

    from mgn.geometry import mass_properties
    from mgn.objects import get_object
    from mgn.pj.labels import label_object
    from mgn.pj.physics import ShakeOptions, ShakeScorer, default_staircase_checks

    from .bench_shake_speed import VARIANTS

    name, _, n = item.partition(":")
    spec = get_object(name)
    mesh = spec.to_mesh()
    props = mass_properties(mesh, spec.density)
    labels = label_object(
        mesh, mass=props.mass, com=props.center_of_mass, num_points=5000, num_threads=threads
    )
    kw = {} if variant == "default" else VARIANTS[variant]
    scorer = ShakeScorer(spec.density, max_grasps=int(n), progress=False)
    if checks is None:  # the default of the scorer's calibration
        checks = default_staircase_checks(scorer.calibration_grasps)
    opts = ShakeOptions(
        staircase=True,
        num_threads=threads,
        staircase_checks=checks,
        staircase_verify_share=scorer.options.staircase_verify_share,
        **kw,
    )
    scorer.options = opts
    load0 = os.getloadavg()[0]
    t0, c0 = time.perf_counter(), time.process_time()
    sim = scorer(mesh, labels)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    got = np.isfinite(sim)
    print(
        f"{name} ({variant}, {threads} thread(s)): {int(got.sum())} of {len(sim)} grasps scored in "
        f"{wall:.1f} s wall, {cpu:.1f} CPU-s ({cpu / got.sum():.3f} CPU-s per grasp; 2,000 grasps "
        f"on 2 busy cores ~{cpu / got.sum() * 1000:.0f} s); {scorer.__name__}, {checks} checks; "
        f"mean score "
        f"{np.nanmean(sim):.3f}; load {load0:.1f} -> {os.getloadavg()[0]:.1f}"
    )
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid-cache", type=Path)
    ap.add_argument(
        "--verified-rows",
        default="-1,5",
        help="rows whose boundary the search verifies, comma-separated (-1: all; 5: the "
        "default with calibration on a 10x10 grid)",
    )
    ap.add_argument("--real", default="", help="name:N: score N grasps for real instead")
    ap.add_argument("--real-variant", default="default")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--physics", default="today=full,f5=dt100f5")
    ap.add_argument("--objects", default=OBJECTS, help="names, optionally name:max_grasps")
    ap.add_argument("--k", default="0,8,16", help="calibration grasps (0 = plain staircase)")
    ap.add_argument(
        "--checks",
        default=None,
        help="staircase checks, comma-separated (default 0,6: the defaults with and without "
        "calibration); --real takes the first (default: the scorer's own)",
    )
    args = ap.parse_args(argv)
    if args.real:
        first = None if args.checks is None else int(args.checks.split(",")[0])
        return real(args.real, args.real_variant, args.threads, first)
    if args.grid_cache is None:
        ap.error("--grid-cache is required (or --real)")
    ks = [int(k) for k in args.k.split(",")]
    checks_list = [int(c) for c in (args.checks or "0,6").split(",")]
    rows_list = [int(r) for r in args.verified_rows.split(",")]
    print(
        "| physics | object | checks | verified rows | K | grasps | identical scores (first K) "
        "| full grid? | trials/grasp"
        " | trials/grasp at 2,000 | trials per CPU-s | CPU-s/grasp at 2,000 | s per 2,000 grasps"
        " on 2 cores | windows -> full grid | identical scores (mean over windows) | identical at"
        " 2,000 (projected) |"
    )
    print("|---|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    pooled: dict[tuple[str, int, int, int], list[float]] = {}
    pooled_w: dict[tuple[str, int, int, int], list[float]] = {}
    pooled_p: dict[tuple[str, int, int, int], list[float]] = {}
    for item in args.physics.split(","):
        label, _, prefix = item.partition("=")
        for obj in args.objects.split(","):
            name, _, cap = obj.partition(":")
            path = args.grid_cache / f"{prefix}_{name}.npz"
            if not path.is_file():
                print(f"| {label} | {name} | - | no grids ({path.name}) |")
                continue
            grids = np.load(path)["success"].astype(bool)
            if cap:
                grids = grids[: int(cap)]
            G, S = grids.shape[0], grids.shape[1]
            truth = grids.sum(axis=(1, 2)) / float(S * S)
            rate = _rate(args.grid_cache, prefix, name)
            for checks, rows in [(c, r) for c in checks_list for r in rows_list]:
                for k in ks:
                    scores, trials, to_full = policy(grids, k, checks, 0, rows)
                    same = scores == truth
                    # At 2,000 grasps: K calibration grids, the others as the verdict says (their
                    # mean over this object's grids).
                    rest = S * S if to_full else float(policy(grids, 0, checks, 0, rows)[1].mean())
                    t2000 = (min(k, 2000) * S * S + (2000 - min(k, 2000)) * rest) / 2000
                    windows = [policy(grids, k, checks, s, rows) for s in range(G)] if k else []
                    w_full = np.mean([w[2] for w in windows]) if windows else 0.0
                    w_same = (
                        np.mean([np.mean(w[0] == truth) for w in windows])
                        if windows
                        else float(np.mean(same))
                    )
                    # At 2,000 grasps the K calibration grasps hardly count: the object is scored on
                    # the full grid (exact) with the windows' probability, else by the search.
                    a0 = float(np.mean(policy(grids, 0, checks, 0, rows)[0] == truth))
                    p2000 = w_full + (1 - w_full) * a0
                    cpu = f"{t2000 / rate:.3f}" if rate else "-"
                    proj = f"{t2000 / rate * 1000:.0f}" if rate else "-"
                    head = (
                        f"| {label} | {name} | {checks} | {rows} | {k} | {G} | "
                        f"{np.mean(same):.1%} | {'yes' if to_full else 'no'} | "
                        f"{trials.mean():.1f} | {t2000:.1f} | "
                    )
                    cost = f"{rate:.0f} | {cpu} | {proj}" if rate else "- | - | -"
                    print(f"{head}{cost} | {w_full:.0%} | {w_same:.1%} | {p2000:.1%} |", flush=True)
                    pooled.setdefault((label, checks, rows, k), []).extend(same.tolist())
                    pooled_w.setdefault((label, checks, rows, k), []).extend([w_same] * G)
                    pooled_p.setdefault((label, checks, rows, k), []).append(p2000)
    for (label, checks, rows, k), same in pooled.items():
        print(
            f"pooled {label}, {checks} checks, {rows} verified rows, K = {k}: "
            f"{np.mean(same):.2%} identical scores over {len(same)} grasps (first K as "
            f"calibration); {np.mean(pooled_w[label, checks, rows, k]):.2%} on average over the "
            f"cyclic windows; {np.mean(pooled_p[label, checks, rows, k]):.2%} projected at 2,000 "
            f"grasps of each of the {len(pooled_p[label, checks, rows, k])} objects"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
