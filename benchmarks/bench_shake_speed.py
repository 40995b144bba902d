"""Faster shake trials against today's default outcomes: the time step and held-load windows.

For each object, grasps and their full 10x10 grid with the default ``ShakeOptions`` come from
``--grid-cache`` (``full_<name>.npz`` with ``rows`` and ``success``, as bench_staircase writes
it; its rows are used as they are, so a cache made by an older labeller still serves), or are
computed from ``bench_staircase.real_grasps`` and stored there. Each variant's full grid is then
simulated (1 thread, stored as ``<variant>_<name>.npz`` so a rerun only adds grasps) and compared
with the default: trials per CPU-s and steps per trial, identical trial outcomes, identical
full-grid scores, and the staircase search's scores (replayed on the variant's grid with the
default checks: every cell is a deterministic trial, so the search's result is a function of the
grid) against the default full-grid scores. ``--confirm`` grasps per object are also scored for
real with ``staircase=True`` and the variant, one grasp at a time (CPU-s per grasp; their scores
must equal the replay).

Variants: ``default`` (today's options on the first ``--rate-grasps`` grasps: its trial
rate, and a check that the cache still holds today's outcomes; ``--rate-grasps 0`` skips it),
``dt150``, ``dt100`` and ``dt75`` (time step 1/150, 1/100 and 1/75 s, every step count scaled to
keep each phase's duration), ``dt100k`` (also the force controller's gain per step scaled),
``dt400`` (a finer step), ``hold`` (``hold_tolerance`` = 3 mm: the translational cycles after
the first and the last quarter of the rotational shake are skipped when the object stayed within
3 mm of its pose in the hand through a window whose loads they repeat; the default since
session 13), ``full`` (``hold_tolerance`` = 0: the full schedule, the default before),
``hold5`` and ``hold10`` (5 mm, 1 cm), ``smooth`` and
``smooth_dt100`` (``smooth_shake``), ``dt100i15``, ``dt100i20``, ``dt100i40`` and ``dt75i30``
(a coarse step with 15, 20, 40 or 30 solver iterations), ``dt100f5`` (1/100 s with
``iterations_per_hull_contact`` = 5), and on top of it ``dt100f5m1`` (margin 1 mm),
``dt100f5m1v32`` (also 32 hull vertices) and ``dt100f2i5m1v32`` (5 solver iterations and 2.5 per
hull contact, so a single hull held by both fingers still gets 5); session 13: ``noskip``
(``skip_separated_pairs`` off: the same trials, Bullet's narrow phase on every pair) and ``v32``
(32 hull vertices at the default step); session 15: ``twosided`` (``one_sided_rows`` off:
Bullet's own solver iterations, the same trials). The last column compares the
staircase search replayed on the variant's grid with that grid's own score: the agreement the
search can reach under that physics (a different default physics is acceptable if its own grids are
monotone enough); ``--curve`` adds it for several check budgets and search variants.

    python -m benchmarks.bench_shake_speed --grid-cache /tmp/shake \
        [--objects can_soda:100,box_cereal:170] [--variants hold,dt150,dt100] [--confirm 20]
    python -m benchmarks.bench_shake_speed --grid-cache /tmp/shake --objects box_cereal,mug \
        --noise 1e-6,1e-4 [--noise-grasps 20]   # the physics' own noise band

Numbers and findings: benchmarks/RESULTS.md, "Shake test: faster trials".
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from .bench_staircase import VARIANTS as SEARCHES
from .bench_staircase import real_grasps, replay


def _dt(hz: int, gain: bool = False) -> dict:
    f = 200 / hz  # default steps per step of this variant
    kw = {
        "dt": 1.0 / hz,
        "close_steps": round(400 / f),
        "shake_steps": round(400 / f),
        "rotate_steps": round(300 / f),
        "settle_steps": max(1, round(10 / f)),
        "lost_contact_steps": max(1, round(10 / f)),
    }
    if gain:
        kw["controller_stiffness"] = 1e5 / f
    return kw


VARIANTS = {
    "default": {},
    "hold": {"hold_tolerance": 3e-3},  # the default since session 13
    # Session 13: the full schedule (the default before) and wider held-load windows.
    "full": {"hold_tolerance": 0.0},
    "hold5": {"hold_tolerance": 5e-3},
    "hold10": {"hold_tolerance": 1e-2},
    "dt150": _dt(150),
    "dt100": _dt(100),
    "dt100k": _dt(100, gain=True),
    "dt400": _dt(400),
    "dt75": _dt(75),
    "smooth": {"smooth_shake": True},
    "smooth_dt100": {"smooth_shake": True, **_dt(100)},
    # Session 11: the coarse step's isolated failures of light objects (the solver does not
    # converge on the stiff pads in 10 iterations) go away with more iterations.
    "dt100i15": {**_dt(100), "solver_iterations": 15},
    "dt100i20": {**_dt(100), "solver_iterations": 20},
    "dt75i30": {**_dt(75), "solver_iterations": 30},
    "dt100i40": {**_dt(100), "solver_iterations": 40},
    "dt100f5": {**_dt(100), "iterations_per_hull_contact": 5.0},
    # Session 12: session 8's cheaper model knobs on top of f5, judged by their own grids.
    "dt100f5m1": {**_dt(100), "iterations_per_hull_contact": 5.0, "margin": 1e-3},
    "dt100f5m1v32": {
        **_dt(100),
        "iterations_per_hull_contact": 5.0,
        "margin": 1e-3,
        "max_hull_vertices": 32,
    },
    # Session 13 (collision side): Bullet's narrow phase on every pair, as before
    # skip_separated_pairs (its trials are the same; the rate shows the saving), and hulls of at
    # most 32 vertices at the default step.
    "noskip": {"skip_separated_pairs": False},
    "v32": {"max_hull_vertices": 32},
    # Session 14: closing ends after 5 (3) steps at the grip force instead of 10.
    "settle5": {"settle_steps": 5},
    "settle3": {"settle_steps": 3},
    # Session 15: Bullet's own solver iterations (both halves of every contact row), as before
    # one_sided_rows (the same trials bit for bit; the rate shows the saving).
    "twosided": {"one_sided_rows": False},
    "dt100f2i5m1v32": {
        **_dt(100),
        "iterations_per_hull_contact": 2.5,
        "solver_iterations": 5,
        "margin": 1e-3,
        "max_hull_vertices": 32,
    },
}


def _object(name: str):
    from mgn.geometry import mass_properties
    from mgn.geometry.convex import cached_convex_decomposition
    from mgn.objects import get_object

    spec = get_object(name)
    mesh = spec.to_mesh()
    return cached_convex_decomposition(mesh), mass_properties(mesh, spec.density)


def default_grids(name: str, n: int, cache: Path):
    """(rows, (G, 10, 10) default outcomes) from the cache, else computed and stored."""
    from .bench_staircase import full_grids

    path = cache / f"full_{name}.npz"
    if path.is_file():
        d = np.load(path)
        k = min(n, len(d["rows"]))
        parts, props = _object(name)
        return parts, props, d["rows"][:k], d["success"][:k]
    parts, props, rows = real_grasps(name, n)
    grids, _, _ = full_grids(name, parts, props, rows, 1, cache)
    return parts, props, rows, grids


def variant_grids(name, parts, props, rows, variant: str, cache: Path, chunk: int = 10):
    """(success (G, 10, 10), steps (G, 10, 10), CPU s) of a variant, grown in the cache."""
    from mgn.pj.physics import ShakeOptions, shake_scores

    path = cache / f"{variant}_{name}.npz"
    succ, steps, cpu = [], [], 0.0
    if path.is_file():
        d = np.load(path)
        succ, steps, cpu = [d["success"]], [d["steps"]], float(d["cpu"])
    start = sum(len(s) for s in succ)
    for s in range(start, len(rows), chunk):
        opts = ShakeOptions(num_threads=1, first_grasp_index=s, **VARIANTS[variant])
        c0 = time.process_time()
        r = shake_scores(parts, props.mass, props.center_of_mass, props.inertia,
                         rows[s : s + chunk], None, opts)  # fmt: skip
        cpu += time.process_time() - c0
        succ.append(r.trial_success)
        steps.append(r.trial_steps)
        tmp = path.with_suffix(".tmp.npz")
        np.savez(tmp, success=np.concatenate(succ), steps=np.concatenate(steps), cpu=cpu)
        os.replace(tmp, path)
    return np.concatenate(succ)[: len(rows)], np.concatenate(steps)[: len(rows)], cpu


def staircase_cost(parts, props, rows, variant: str | None) -> tuple[np.ndarray, float, int]:
    """Real staircase scores of rows, one grasp per call on 1 thread: (scores, CPU s, trials)."""
    from mgn.pj.physics import ShakeOptions, shake_scores

    kw = {} if variant is None else VARIANTS[variant]
    scores, cpu, trials = [], 0.0, 0
    for g in range(len(rows)):
        opts = ShakeOptions(num_threads=1, staircase=True, first_grasp_index=g, **kw)
        c0 = time.process_time()
        r = shake_scores(parts, props.mass, props.center_of_mass, props.inertia,
                         rows[g : g + 1], None, opts)  # fmt: skip
        cpu += time.process_time() - c0
        scores.append(r.score[0])
        trials += r.num_trials
    return np.asarray(scores), cpu, trials


def _moved_grids(parts, props, rows: np.ndarray, eps: float) -> np.ndarray:
    """(G, 10, 10) default outcomes with every grasp point moved by eps (m) along its approach."""
    from mgn.pj.physics import ShakeOptions, shake_scores

    moved = rows.copy()
    moved[:, 6:9] += eps * moved[:, 0:3]
    r = shake_scores(parts, props.mass, props.center_of_mass, props.inertia, moved, None,
                     ShakeOptions(num_threads=0))  # fmt: skip
    return np.asarray(r.trial_success, bool)


def noise_band(objects: str, eps_list: str, grasps: int, cache: Path) -> int:
    """The physics' own noise: default options with every grasp point moved by eps (m) along
    its approach axis (physically nothing), full grids of the first `grasps` grasps against the
    same grasps unmoved (both simulated here with today's defaults; the cache gives the grasps).
    A change of the trial that moves outcomes no more than this does is within what the
    simulation cannot tell apart."""
    print(
        "| object | shift | grasps | cells agree | identical scores | mean \\|d\\| | max \\|d\\| "
        "| mean shift |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for item in objects.split(","):
        name = item.partition(":")[0]
        parts, props, rows, _ = default_grids(name, grasps, cache)
        base = _moved_grids(parts, props, rows, 0.0)
        for eps in (float(e) for e in eps_list.split(",")):
            got = _moved_grids(parts, props, rows, eps)
            a, b = base.mean(axis=(1, 2)), got.mean(axis=(1, 2))
            print(
                f"| {name} | {eps:g} m | {len(rows)} | {np.mean(got == base):.2%} | "
                f"{np.mean(a == b):.0%} | {np.abs(a - b).mean():.4f} | {np.abs(a - b).max():.2f} "
                f"| {np.mean(b - a):+.4f} |",
                flush=True,
            )
    return 0


def main(argv: list[str] | None = None) -> int:
    from mgn.pj.physics import ShakeOptions

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", default="can_soda:100,box_cereal:170")
    ap.add_argument("--variants", default="hold,dt150,dt100")
    ap.add_argument("--grid-cache", type=Path, required=True)
    ap.add_argument("--confirm", type=int, default=20, help="grasps per object run for real")
    ap.add_argument(
        "--rate-grasps",
        type=int,
        default=30,
        help="grasps per object rerun with the default options (trials per CPU-s; the cache "
        "must reproduce)",
    )
    ap.add_argument(
        "--curve",
        default="",
        help="check budgets (e.g. 0,6,20,40): per variant, identical scores and trials per grasp "
        "of bench_staircase's searches replayed on the variant's own grids",
    )
    ap.add_argument(
        "--noise",
        default="",
        help="shifts in m (e.g. 1e-6,1e-4): print the physics' own noise band on the first "
        "--noise-grasps grasps of each object instead of the variants",
    )
    ap.add_argument("--noise-grasps", type=int, default=20)
    args = ap.parse_args(argv)
    args.grid_cache.mkdir(parents=True, exist_ok=True)
    if args.noise:
        return noise_band(args.objects, args.noise, args.noise_grasps, args.grid_cache)
    checks = ShakeOptions().staircase_checks
    print(f"load average at start: {os.getloadavg()[0]:.1f}")
    print(
        "| object | variant | grasps | trials per CPU-s (grid) | steps/trial | identical "
        "outcomes | identical grid scores | identical staircase scores | staircase: trials/grasp,"
        " CPU-s/grasp | staircase = own full grid |"
    )
    print("|---|---|---:|---:|---:|---:|---:|---:|---|---:|")
    curves = []
    for item in args.objects.split(","):
        name, _, n = item.partition(":")
        parts, props, rows, base = default_grids(name, int(n or 100), args.grid_cache)
        truth = base.sum(axis=(1, 2))
        stair = np.array([replay(g, checks)[0] for g in base])
        k = min(args.confirm, len(rows))
        dcpu, dtrials = 0.0, 0
        if args.rate_grasps > 0:
            _, dcpu, dtrials = staircase_cost(parts, props, rows[:k], None)
        print(
            f"| {name} | default: cache vs its staircase | {len(rows)} | - | - | 100 % | 100 % | "
            f"{np.mean(stair == truth):.1%} | - | {np.mean(stair == truth):.1%} |",
            flush=True,
        )
        for v in ["default"] * (args.rate_grasps > 0) + args.variants.split(","):
            sub = slice(0, args.rate_grasps if v == "default" else len(rows))
            succ, steps, vcpu = variant_grids(name, parts, props, rows[sub], v, args.grid_cache)
            if v == "default" and not np.array_equal(succ, base[sub]):
                print(
                    f"  {name}: the default options no longer reproduce the cached grids (made "
                    "with other defaults? hold_tolerance is 3 mm since session 13: use a fresh "
                    "--grid-cache)"
                )
                return 1
            vbase, vtruth = base[sub], truth[sub]
            vs = np.array([replay(g, checks)[0] for g in succ])
            if v == "default":
                cost = f"{dtrials / max(k, 1):.1f}, {dcpu / max(k, 1):.3f}"
            else:
                real, cpu, trials = staircase_cost(parts, props, rows[:k], v)
                if not np.array_equal(np.round(real * 100), vs[:k]):
                    print(f"  {name} {v}: real staircase scores differ from the replay")
                    return 1
                cost = f"{trials / max(k, 1):.1f}, {cpu / max(k, 1):.3f}"
            print(
                f"| {name} | {v} | {len(succ)} | {succ.size / vcpu:.0f} | {steps.mean():.0f} | "
                f"{np.mean(succ == vbase):.2%} | {np.mean(succ.sum(axis=(1, 2)) == vtruth):.1%} "
                f"| {np.mean(vs == vtruth):.1%} | {cost} | "
                f"{np.mean(vs == succ.sum(axis=(1, 2))):.1%} |",
                flush=True,
            )
            curves.append((name, v, succ))
    for name, v, succ in curves if args.curve else []:
        own = succ.sum(axis=(1, 2))
        for label, search in list(SEARCHES.items())[2:]:
            cells = []
            for c in map(int, args.curve.split(",")):
                res = [search(g, c) for g in succ]
                same = np.mean([r[0] for r in res] == own)
                cells.append(f"{c}: {same:.1%} / {np.mean([r[1] for r in res]):.1f}")
            print(f"  {name} {v}, {label} (checks: identical / trials): " + "; ".join(cells))
    print(f"load average at end: {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
