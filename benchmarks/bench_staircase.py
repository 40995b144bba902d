"""Staircase search of the shake test against MetaGraspNet's full 10x10 grid on real grasps.

For several built-in objects, parallel-jaw grasps come from mgn's own labeller (antipodal
sampling, collision-free, an evenly strided subset). Each grasp is simulated once over the full
friction x density grid (every trial; optionally kept in ``--grid-cache`` so a rerun only adds
grasps). Every cell's trial is deterministic (its own random stream, the same in every search),
so a search's result is a function of the full grid: three searches are replayed on the stored
grids for several check budgets -- the previous search (session 6, re-implemented here), the
gallop+bisect walk without the boundary band, and mgn's ``staircase_grid`` (through
``mgn._core``) -- and the default budget is also run for real with
``ShakeOptions(staircase=True)`` on the first ``--confirm`` grasps of each object, which must give
the replayed scores. Reported: identical scores, misses, mean and max absolute score difference,
mean and max trials per grasp, fallbacks; where the walk's inference is wrong; wall and CPU time.

    python -m benchmarks.bench_staircase [--objects name:grasps,...] [--grid-cache DIR
        [--cached-only]] [--checks 0,5,6,10] [--confirm 10]

Measured 2026-11-25 (shared 2-core machine, load 17-25): 550 grasps of 5 objects (can_soda 100,
mug 80, box_cereal 170 -- the first grasps of 170 strided ones -- can_food 100, bottle_water 100);
table and findings in benchmarks/README.md. At the default (6 checks): 96.9 % identical scores,
23.9 trials per grasp (max 100 on a fallback, 42 fallbacks), score differences <= 0.15 (mean
0.0007); the previous search needs 10 checks for 25.0 trials and gets 95.3 %; 99 % needs about
60 checks (~74 trials) with either.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

DEFAULT_CHECKS = (0, 5, 6, 10, 15, 20, 30, 40, 60)
OBJECTS = "can_soda:170,mug:170,box_cereal:170,can_food:100,bottle_water:100"
GOLDEN = 0.6180339887498949


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


def full_grids(name, parts, props, rows, threads, cache: Path | None, cached_only: bool = False,
               chunk: int = 10):  # fmt: skip
    """(G, S, S) full-grid outcomes of every grasp (default options), grown in the cache."""
    from mgn.pj.physics import ShakeOptions, shake_scores

    path = None if cache is None else cache / f"full_{name}.npz"
    done = np.zeros((0, 10, 10), bool)
    if path is not None and path.is_file():
        d = np.load(path)
        k = min(len(d["success"]), len(rows))
        if np.array_equal(d["rows"][:k], rows[:k]):
            done = d["success"][:k]
    wall = cpu = 0.0
    for start in range(len(done), len(done) if cached_only else len(rows), chunk):
        t0, c0 = time.perf_counter(), time.process_time()
        r = shake_scores(parts, props.mass, props.center_of_mass, props.inertia,
                         rows[start : start + chunk], None,
                         ShakeOptions(num_threads=threads, first_grasp_index=start))  # fmt: skip
        wall += time.perf_counter() - t0
        cpu += time.process_time() - c0
        done = np.concatenate([done, r.trial_success])
        if path is not None:
            np.savez(path, rows=rows[: len(done)], success=done)
    return done, wall, cpu


def _search_previous(grid: np.ndarray, checks: int) -> tuple[int, int, bool]:
    """Session 6's search, replayed: walk each row right from the previous row's boundary while
    trials succeed, then `checks` checks: cells at distance 1, then 2 from each row's boundary,
    then golden-ratio order; full grid on a contradiction."""
    S = grid.shape[0]
    sim = np.zeros_like(grid)
    inf = np.zeros_like(grid)

    def run(i: int, j: int) -> bool:
        sim[i, j] = True
        return bool(grid[i, j])

    b, j = [], 0
    for i in range(S):
        while j < S and run(i, j):
            j += 1
        b.append(j)
        inf[i, :j] = True
    near = [(i, c) for d in (1, 2) for i in range(S) for c in (b[i] - d, b[i] + d) if 0 <= c < S]
    near = list(dict.fromkeys(c for c in near if not sim[c]))
    rest = [(i, jj) for i in range(S) for jj in range(S) if not sim[i, jj] and (i, jj) not in near]
    return _verify(grid, sim, inf, near + _golden(rest), checks)


def _search_bisect(
    grid: np.ndarray, checks: int, band: bool, extra: tuple = ()
) -> tuple[int, int, bool]:
    """The walk of staircase_grid (hardest cell of row 0 first, then per row gallop and bisect
    from the previous row's boundary), with or without the band of cells next to the boundary
    before `checks` golden-ratio checks; the inferred cells of `extra` are verified after the
    band."""
    S = grid.shape[0]
    sim = np.zeros_like(grid)
    inf = np.zeros_like(grid)

    def run(i: int, j: int) -> bool:
        sim[i, j] = True
        return bool(grid[i, j])

    b, lo = [], 0
    for i in range(S):
        hi = S
        if i == 0:
            lo, hi = (S, S) if run(0, S - 1) else (0, S - 1)
        step = 1
        while lo < hi:
            j = min(lo + step - 1, hi - 1)
            if not run(i, j):
                hi = j
                break
            lo, step = j + 1, 2 * step
        while lo < hi:
            m = (lo + hi) // 2
            lo, hi = (m + 1, hi) if run(i, m) else (lo, m)
        b.append(lo)
        inf[i, :lo] = True
    near = []
    for i in range(S if band else 0):  # nearest unsimulated cell on each side of the boundary
        for c, step in ((b[i] - 1, -1), (b[i], 1)):
            c += step if 0 <= c < S and sim[i, c] else 0
            if 0 <= c < S and not sim[i, c]:
                near.append((i, c))
    near += [c for c in extra if not sim[c] and c not in near]
    rest = [(i, jj) for i in range(S) for jj in range(S) if not sim[i, jj] and (i, jj) not in near]
    return _verify(grid, sim, inf, near, checks, _golden(rest))


def _golden(cells: list) -> list:
    key = [((k + 1) * GOLDEN) % 1.0 for k in range(len(cells))]
    return [cells[k] for k in sorted(range(len(cells)), key=lambda k: (key[k], k))]


def _verify(grid, sim, inf, first, checks, spread=()):
    """Simulate `first` (all of it when `spread` is given, else its first `checks`) and the
    first `checks` of `spread`; on a contradiction every cell: (successes, trials, fallback)."""
    cells = list(first) + list(spread)[:checks] if spread != () else list(first)[:checks]
    for c in cells:
        sim[c] = True
        if grid[c] != inf[c]:
            return int(grid.sum()), grid.size, True
    return int(inf.sum()), int(sim.sum()), False


def replay(grid: np.ndarray, checks: int) -> tuple[int, int, bool]:
    """(successes, trials, fallback) of mgn's staircase search (_core.staircase_grid)."""
    from mgn import _core

    r = _core.staircase_grid(grid.shape[0], lambda i, j: bool(grid[i, j]), checks)
    return int(r.success.sum()), int(r.trials), bool(r.fallback)


VARIANTS = {
    "previous (walk right, checks at distance 1-2)": _search_previous,
    "gallop+bisect, no band": lambda g, c: _search_bisect(g, c, band=False),
    "gallop+bisect, band (staircase_grid)": replay,
    # Session 11: at a coarse step the isolated failures sit in the lightest column (light
    # objects squeezed between the pads: the solver does not converge), so verify it too.
    "gallop+bisect, band + lightest column": lambda g, c: _search_bisect(
        g, c, band=True, extra=tuple((i, 0) for i in range(g.shape[0]))
    ),
}


def where(grids: np.ndarray) -> str:
    """Where staircase_grid without spread checks (walk and boundary band only) infers cells
    wrongly: per grid the number of wrong cells, and of grids with exactly one wrong cell how
    many are next to a row boundary."""
    wrong, single_near = [], 0
    for g in grids:
        r = _core_grid(g, 0)
        w = r.success != g
        wrong.append(int(w.sum()))
        if w.sum() == 1:
            i, j = np.argwhere(w)[0]
            b = int(r.success[i].sum())
            single_near += j in (b - 1, b)
    wrong_a = np.array(wrong)
    return (
        f"grids with wrong cells after walk and band {int((wrong_a > 0).sum())}: one cell "
        f"{int((wrong_a == 1).sum())} ({single_near} next to the boundary), 2-3 cells "
        f"{int(((wrong_a >= 2) & (wrong_a <= 3)).sum())}, >= 4 cells {int((wrong_a >= 4).sum())}"
    )


def _core_grid(g: np.ndarray, checks: int):
    from mgn import _core

    return _core.staircase_grid(g.shape[0], lambda i, j: bool(g[i, j]), checks)


def _line(label: str, truth: np.ndarray, res: list) -> str:
    s = np.array([r[0] for r in res])
    tr = np.array([r[1] for r in res])
    fb = np.array([r[2] for r in res])
    d = np.abs(s - truth) / 100.0
    return (
        f"{label}  {len(d):6d}  {np.mean(d == 0) * 100:7.1f} %  {int((d > 0).sum()):4d}  "
        f"{d.mean():.4f}  {d.max():.2f}  {tr.mean():6.1f}  {tr.max():4d}  {int(fb.sum()):4d}"
    )


def main(argv: list[str] | None = None) -> int:
    from mgn.pj.physics import ShakeOptions, shake_scores

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", default=OBJECTS, help="name:grasps,... (evenly strided)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--grid-cache", type=Path, default=None, help="folder of full-grid results")
    ap.add_argument("--checks", default=",".join(map(str, DEFAULT_CHECKS)))
    ap.add_argument("--confirm", type=int, default=10, help="grasps per object run for real")
    ap.add_argument("--cached-only", action="store_true", help="only the grasps in --grid-cache")
    args = ap.parse_args(argv)
    budgets = [int(c) for c in args.checks.split(",")]
    default = ShakeOptions().staircase_checks
    if args.grid_cache is not None:
        args.grid_cache.mkdir(parents=True, exist_ok=True)
    all_grids, names = [], []
    for item in args.objects.split(","):
        name, _, n = item.partition(":")
        parts, props, rows = real_grasps(name, int(n or 100))
        grids, wall, cpu = full_grids(
            name, parts, props, rows, args.threads, args.grid_cache, args.cached_only
        )
        if len(grids) == 0:
            continue
        rows = rows[: len(grids)]
        all_grids.append(grids)
        names += [name] * len(grids)
        print(
            f"{name}: {len(grids)} grasps; full grid computed now {wall:.0f} s wall "
            f"{cpu:.0f} s CPU (load {os.getloadavg()[0]:.1f}); mean score "
            f"{grids.mean():.3f}; {where(grids)}"
        )
        truth = grids.sum(axis=(1, 2))
        print(_line(f"  checks {default:3d} (default)", truth, [replay(g, default) for g in grids]))
        k = min(args.confirm, len(rows))
        if k:
            t0, c0 = time.perf_counter(), time.process_time()
            real = shake_scores(
                parts,
                props.mass,
                props.center_of_mass,
                props.inertia,
                rows[:k],
                None,
                ShakeOptions(staircase=True, num_threads=args.threads),
            )
            w, c = time.perf_counter() - t0, time.process_time() - c0
            rep = np.array([replay(g, default)[0] for g in grids[:k]]) / 100.0
            ok = np.array_equal(real.score, rep)
            print(
                f"  real staircase run on {k} grasps: scores {'EQUAL' if ok else 'DIFFER FROM'}"
                f" the replay; {real.num_trials / k:.1f} trials/grasp, {w:.1f} s wall {c:.1f} s"
                f" CPU (load {os.getloadavg()[0]:.1f})"
            )
            if not ok:
                return 1
    grids = np.concatenate(all_grids)
    truth = grids.sum(axis=(1, 2))
    print(f"\nALL {len(grids)} grasps of {len(set(names))} objects; {where(grids)}")
    print(
        "variant / checks                                  grasps  identical  miss  "
        "mean|d|  max|d|  trials  max  fallbacks"
    )
    for label, search in VARIANTS.items():
        for c in budgets:
            print(_line(f"{label:44s} {c:3d}", truth, [search(g, c) for g in grids]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
