"""How well the shake test's staircase search keeps 2 threads busy on real grasps.

With the staircase search a grasp costs from ~17 trials (a grid that holds everywhere) to the
full S x S (a fallback), so how grasps are shared between threads matters. For real grasps of
built-in objects (``bench_staircase.real_grasps``) this measures each grasp's CPU seconds alone
(1 thread, ``first_grasp_index`` keeps its random streams), then derives the busy fraction of 2
threads, sum of costs / (2 x finishing time), for two ways to share them:

- contiguous halves (shake_test before 25 Nov: thread 0 the first half of a call's grasps,
  thread 1 the second);
- one grasp at a time from a shared counter (now): each thread takes the next grasp when it is
  done with one (shake_test also shares the remaining cells of a grasp that falls back between
  the threads; the model leaves that out, so its busy fraction is a lower bound),

for one call over all grasps and for the calls of ``ShakeScorer``'s progress bar (before: pieces
of 2 grasps per thread; now 16). The costs are measured, only the schedule is computed, so the
fractions do not depend on the machine's load. Then the whole list is run for real with 1 and 2
threads (wall and CPU seconds, load average; wall times are only meaningful on an idle machine).

    python -m benchmarks.bench_shake_threads [--objects box_cereal:40,can_soda:40,mug:40]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from .bench_staircase import real_grasps
from .common import load_average


def halves(costs: np.ndarray) -> float:
    """Finishing time of 2 threads given contiguous halves (parallel_for's equal ranges)."""
    h = len(costs) // 2
    return max(float(costs[:h].sum()), float(costs[h:].sum()))


def greedy(costs: np.ndarray, threads: int = 2) -> float:
    """Finishing time of threads that take the next grasp in index order when free."""
    busy = [0.0] * threads
    for c in costs:
        k = int(np.argmin(busy))
        busy[k] += float(c)
    return max(busy)


def busy_fraction(costs: np.ndarray, piece: int, schedule) -> float:
    total = finish = 0.0
    for s in range(0, len(costs), piece):
        c = costs[s : s + piece]
        total += float(c.sum())
        finish += schedule(c) if len(c) > 1 else float(c.sum())
    return total / (2 * finish)


def main() -> None:
    from mgn.pj.physics import ShakeOptions, shake_scores

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", default="box_cereal:40,can_soda:40,mug:40")
    args = ap.parse_args()
    print(f"load average at start: {load_average()}")
    print(
        "| object | grasps | trials/grasp (min-max) | CPU s/grasp | 2-thread busy: halves, "
        "one call | counter, one call | halves, pieces of 4 | counter, pieces of 32 |"
    )
    print("|---|---:|---|---:|---:|---:|---:|---:|")
    runs = []
    for item in args.objects.split(","):
        name, n = item.split(":")
        parts, props, rows = real_grasps(name, int(n))
        args_ = (parts, props.mass, props.center_of_mass, props.inertia)
        costs, trials = [], []
        for g in range(len(rows)):
            c0 = time.process_time()
            r = shake_scores(
                *args_,
                rows[g : g + 1],
                None,
                ShakeOptions(num_threads=1, staircase=True, first_grasp_index=g),
            )
            costs.append(time.process_time() - c0)
            trials.append(r.num_trials)
        cost = np.asarray(costs)
        print(
            f"| {name} | {len(rows)} | {np.mean(trials):.1f} ({min(trials)}-{max(trials)}) | "
            f"{cost.mean():.3f} | {busy_fraction(cost, len(cost), halves):.1%} | "
            f"{busy_fraction(cost, len(cost), greedy):.1%} | "
            f"{busy_fraction(cost, 4, halves):.1%} | "
            f"{busy_fraction(cost, 32, greedy):.1%} |",
            flush=True,
        )
        runs.append((name, args_, rows, int(np.sum(trials))))
    print("\n| object | threads | wall s | CPU s | trials/s (wall) | trials per CPU-s | load |")
    print("|---|---:|---:|---:|---:|---:|---|")
    for name, args_, rows, trials in runs:
        for threads in (1, 2):
            t0, c0 = time.perf_counter(), time.process_time()
            shake_scores(*args_, rows, None, ShakeOptions(num_threads=threads, staircase=True))
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            print(
                f"| {name} | {threads} | {wall:.1f} | {cpu:.1f} | {trials / wall:.0f} | "
                f"{trials / cpu:.0f} | {load_average()} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
