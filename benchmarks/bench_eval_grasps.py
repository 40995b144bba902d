"""Grasp evaluation: the collision query of arbitrary grasps and the matching (no peer).

The 20-object scene of bench_scene_grasps (built-in objects in two layers, stand-in label
candidates with the geometry of real labels). Measured:

- SceneGraspModel.collides on every placed label pose (what ``mgn eval grasps`` runs on each
  matched prediction), parallel-jaw (with the target checked at the grasp) and suction, 1 and all
  threads; agreement: the query reproduces the labels' ``colliding`` flags.
- The matching of ``mgn eval grasps`` (mgn.eval.grasps._match): 500 predictions of one view
  against every placed label of the scene (the worst case: a view that sees every object).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .bench_scene_grasps import _labels, _scene
from .common import Row, measure_alternating, thread_counts

GRASPS_PER_OBJECT = 500
NUM_PREDICTIONS = 500


def run(
    *, quick: bool, repeats: int, mgn: Any, mgn_status: str, log: Callable[[str], None]
) -> list[Row]:
    per_object = GRASPS_PER_OBJECT // 4 if quick else GRASPS_PER_OBJECT
    rows = [
        Row(
            "grasp eval",
            "collides: parallel-jaw label poses, 0 and 100 mm",
            0,
            "grasps/s",
            "—",
            peer_status="no peer",
        ),
        Row(
            "grasp eval",
            "collides: suction label poses, 0 and 100 mm",
            0,
            "grasps/s",
            "—",
            peer_status="no peer",
        ),
        Row(
            "grasp eval",
            f"matching: {NUM_PREDICTIONS} parallel-jaw predictions vs all labels",
            NUM_PREDICTIONS,
            "predictions/s",
            "—",
            peer_status="no peer",
        ),
    ]
    if mgn is None:
        for r in rows:
            r.mgn_status = mgn_status
        return rows
    from mgn.eval.grasps import DEFAULT_MATCH_ANGLE, DEFAULT_MATCH_DISTANCE, _match
    from mgn.view_labels.grasps import SceneGraspModel

    scene = _scene(mgn)
    pj, su = _labels(mgn, scene, per_object)
    models = {t: SceneGraspModel(scene, pj, su, num_threads=t) for t in thread_counts()}
    for row, kind in zip(rows[:2], ("pj", "suction"), strict=True):
        placed = models[1].pj if kind == "pj" else models[1].suction
        row.n = len(placed)
        args = (kind, placed.contact_poses, placed.width, placed.object_id)
        cases = {}
        results = {}
        for t, m in models.items():
            results[t] = m.collides(*args)  # warm-up
            cases[t] = lambda m=m, args=args: m.collides(*args)
        row.mgn = measure_alternating(cases, repeats)
        agree = all(np.array_equal(r.colliding, placed.colliding) for r in results.values())
        row.agreement = "= label flags, every thread count" if agree else "differs from labels"
        row.agreement_ok = agree
        row.notes.append(f"{int(placed.colliding.sum()):,} of {len(placed):,} colliding")
        log(f"grasp eval: collides {kind} on {len(placed):,} poses")
    p = models[1].pj
    rng = np.random.default_rng(0)
    pick = rng.choice(len(p), NUM_PREDICTIONS, replace=False)
    X = p.contact_poses[pick].copy()
    X[:, :3, 3] += rng.normal(0.0, 0.003, (NUM_PREDICTIONS, 3))
    w = p.width[pick].astype(np.float64)
    Lw = p.width.astype(np.float64)

    def match() -> np.ndarray:
        return _match(
            "paralleljaw", X, w, p.contact_poses, Lw, DEFAULT_MATCH_DISTANCE, DEFAULT_MATCH_ANGLE
        )

    found = match()
    timing = measure_alternating({1: match}, repeats)
    rows[2].mgn = timing
    rows[2].notes.append(
        f"{len(p):,} labels; {int((found >= 0).sum())} of {NUM_PREDICTIONS} matched (3 mm noise)"
    )
    return rows
