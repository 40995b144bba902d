"""Closed-loop picking (``mgn.eval.run_picking``): seconds per pick on a dropped pile.

A pile of built-in objects is dropped once; the label policy then clears it with the suction
cup at a low top-view resolution. Each attempt rebuilds the scene grasp model (placement and
collision checks of every label), renders the top view, labels it (masks, layout) and, after a
successful pick, lets the pile settle again in Bullet. There is no peer: no maintained library
runs this loop (MetaGraspNet's own loop needs Isaac Gym and a GPU), so the row reports mgn
alone. Object labels are computed once (cached) before the timing, as in a dataset run.

Run alone: `python -m benchmarks.bench_pick [--quick]`.
"""

from __future__ import annotations

import json
import os
import sys
import time
from collections.abc import Callable
from typing import Any

from .common import Row, bench_tempdir, measure_alternating, thread_counts

SEED = 2
RESOLUTION = 160


def _config(quick: bool) -> Any:
    from mgn.pipeline.config import load_config

    points = 200 if quick else 1000
    return load_config(
        {
            "object_labels": {"suction_points": points, "pj_points": 40},
            "labels": {"pj_physics": False},
        }
    )


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any | None,
    mgn_status: str,
    log: Callable[[str], None],
) -> list[Row]:
    num_objects = 5 if quick else 10
    row = Row(
        group="closed-loop picking",
        case=f"label policy clears {num_objects} dropped objects (suction, {RESOLUTION} px top "
        "view, re-settle after each pick)",
        n=1,
        unit="runs/s",
        peer_name="none (no library peer)",
        mgn_status=mgn_status,
        peer_status="no peer: MetaGraspNet's loop needs Isaac Gym (GPU)",
    )
    if mgn is None:
        return [row]
    from mgn.eval.pick import run_picking
    from mgn.scene import compose_objects, drop_scene

    os.environ.setdefault("MGN_CACHE_DIR", str(bench_tempdir("mgn-bench-pick-")))
    config = _config(quick)
    scene = drop_scene(compose_objects(count=num_objects, seed=SEED), seed=SEED)
    threads = thread_counts()[-1]
    kw = {"config": config, "resolution": RESOLUTION, "num_threads": threads}
    t0 = time.perf_counter()
    first = run_picking(scene, **kw)  # warm-up: object labels, decompositions
    log(f"bench_pick: first run (with object labels) {time.perf_counter() - t0:.2f} s")
    timings = measure_alternating({"mgn": lambda: run_picking(scene, **kw)}, repeats)
    row.mgn[threads] = timings["mgn"]
    attempts = max(1, len(first.attempts))
    row.notes.append(
        f"{len(scene)} objects in the tote, {len(first.attempts)} attempts, "
        f"R_grasp {first.R_grasp:.2f}, R_object {first.R_object:.2f}, "
        f"R_mixture {first.R_mixture:.2f} (stopped: {first.stop_reason}); median "
        f"{timings['mgn'].median:.2f} s per run = {timings['mgn'].median / attempts:.2f} s per "
        "attempt"
    )
    row.agreement = "not compared"
    return [row]


if __name__ == "__main__":
    from .common import import_mgn

    mgn_mod, status = import_mgn()
    rows = run(
        quick="--quick" in sys.argv,
        repeats=1 if "--quick" in sys.argv else 3,
        mgn=mgn_mod,
        mgn_status=status,
        log=lambda m: print(m, file=sys.stderr),
    )
    for r in rows:
        print(json.dumps(r.to_json(), indent=1))
