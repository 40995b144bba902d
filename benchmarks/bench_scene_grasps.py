"""Scene grasp labels: the per-scene collision pass and the per-view selection (no peer).

A 20-object scene (built-in objects placed in two layers in the tote, hand-made poses) with about
2,000 parallel-jaw and 2,000 suction candidates per object. The candidates are stand-ins with the
geometry of real labels (contacts evenly spread on the surface; suction approach = -normal;
parallel-jaw closing = -normal at p1, approach perpendicular to it, width clipped to the gripper)
so that the collision work is representative without running the object-level labelers.

Measured: the SceneGraspModel construction (placement, wrench, collisions at 0 and 100 mm: once
per scene for its 37 views) with 1 and all threads, and view_grasps over the 37 MetaGraspNet views
with every object seen (the worst case). Target: per-view selection <= 60 ms.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .common import Row, measure_alternating, thread_counts

NUM_OBJECTS = 20
GRASPS_PER_OBJECT = 2000
TARGET_VIEW_MS = 60.0


def _scene(mgn: Any):
    from mgn.objects import ToteSpec, builtin_objects
    from mgn.scene import Scene, SceneInstance

    specs = sorted(builtin_objects(), key=lambda s: s.name)
    tote = ToteSpec()
    instances = []
    rng = np.random.default_rng(0)
    for i in range(NUM_OBJECTS):
        spec = specs[i % len(specs)]
        layer, k = divmod(i, 10)
        x = -0.15 + 0.075 * (k % 5)
        y = -0.07 + 0.14 * (k // 5)
        v = np.asarray(spec.vertices)
        z = -v[:, 2].min() + layer * 0.08 + 1e-4
        theta = rng.uniform(0, 2 * np.pi)
        c, s = np.cos(theta), np.sin(theta)
        X = np.eye(4)
        X[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
        X[:3, 3] = (x, y, z)
        instances.append(SceneInstance(i + 1, spec.name, spec.category_id, "builtin", X))
    return Scene(instances=tuple(instances), tote=tote, seed=0)


def _labels(mgn: Any, scene: Any, n: int):
    from mgn.geometry.mesh import sample_surface
    from mgn.pj.labels import PjLabels
    from mgn.suction.labels import SuctionLabels

    rng = np.random.default_rng(1)
    pj, su = [], []
    for i in range(len(scene.instances)):
        mesh = scene.mesh(i)
        s = sample_surface(mesh, n, method="even", seed=i)
        p, nrm = np.asarray(s.points, np.float64), np.asarray(s.normals, np.float64)
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        v = -nrm
        t = rng.normal(size=(len(p), 3))
        a = t - (t * v).sum(1, keepdims=True) * v
        a /= np.linalg.norm(a, axis=1, keepdims=True)
        extent = float(np.ptp(np.asarray(mesh.vertices), axis=0).min())
        w = np.full(len(p), min(extent, 0.07), np.float32)
        m = len(p)
        pj.append(
            PjLabels(
                approach=a.astype(np.float32),
                closing=v.astype(np.float32),
                p1=p.astype(np.float32),
                width=w,
                quality_score=np.ones(m, np.float32),
                score_wrench=np.ones(m, np.float32),
                quality_score_simulation=np.full(m, np.nan, np.float32),
                point_index=np.arange(m),
                point_score=np.ones(m, np.float32),
                num_points=m,
                num_colliding=0,
            )
        )
        su.append(
            SuctionLabels(
                points=p.astype(np.float32),
                approach=v.astype(np.float32),
                score=np.ones(m, np.float32),
                wrench=np.ones(m, np.float32),
                reason=np.zeros(m, np.uint8),
                num_candidates=m,
                num_colliding=0,
            )
        )
    return pj, su


def run(
    *, quick: bool, repeats: int, mgn: Any, mgn_status: str, log: Callable[[str], None]
) -> list[Row]:
    per_object = GRASPS_PER_OBJECT // 4 if quick else GRASPS_PER_OBJECT
    rows = [
        Row(
            "scene grasps",
            f"collision pass, {NUM_OBJECTS} objects, 0 and 100 mm",
            0,
            "grasps/s",
            "—",
            peer_status="no peer",
        ),
        Row(
            "scene grasps",
            "per-view selection (37 views, every object seen)",
            37,
            "views/s",
            "—",
            peer_status="no peer",
        ),
    ]
    if mgn is None:
        for r in rows:
            r.mgn_status = mgn_status
        return rows
    from mgn.scene.cameras import mgn_views
    from mgn.view_labels.grasps import SceneGraspModel

    scene = _scene(mgn)
    pj, su = _labels(mgn, scene, per_object)
    total = sum(len(p) for p in pj) + sum(len(s.points) for s in su)
    rows[0].n = total
    log(f"scene grasps: {len(scene.instances)} objects, {total:,} candidate grasps")
    models: dict[int, Any] = {}
    cases = {}
    for t in thread_counts():
        models[t] = SceneGraspModel(scene, pj, su, num_threads=t)  # warm-up
        cases[t] = lambda t=t: SceneGraspModel(scene, pj, su, num_threads=t)
    timings = measure_alternating(cases, max(1, min(repeats, 3)))
    rows[0].mgn = timings
    m = models[max(models)]
    for kind in ("pj", "suction"):
        c = m.collisions(kind)
        rows[0].notes.append(
            f"{kind}: {c.colliding:,} of {c.total:,} colliding "
            f"({', '.join(f'{o * 1000:.0f} mm: {n:,}' for o, n in c.at_offset.items())})"
        )
    agree = all(
        np.array_equal(models[t].pj.hit, m.pj.hit)
        and np.array_equal(models[t].suction.hit, m.suction.hit)
        for t in models
    )
    rows[0].agreement = "identical for every thread count" if agree else "thread counts differ"
    rows[0].agreement_ok = agree
    views = mgn_views(0)
    seen = np.ones(len(scene.instances), bool)
    view_cases = {}
    for t, model in models.items():
        model.view_grasps(views[0], seen)  # warm-up
        view_cases[t] = lambda model=model: [model.view_grasps(v, seen) for v in views]
    view_timings = measure_alternating(view_cases, repeats)
    rows[1].mgn = view_timings
    kept = [m.view_grasps(v, seen) for v in views]
    counts = [len(k.non_colliding.paralleljaw) + len(k.colliding.paralleljaw) for k in kept]
    ms = {t: 1000 * tm.median / len(views) for t, tm in view_timings.items()}
    rows[1].notes.append(
        "per view: "
        + ", ".join(f"{v:.1f} ms ({t} thread{'s' if t > 1 else ''})" for t, v in ms.items())
        + f"; target <= {TARGET_VIEW_MS:.0f} ms; parallel-jaw kept per view: "
        f"{min(counts):,}-{max(counts):,}"
    )
    rows[0].notes.append(
        "per scene: "
        + ", ".join(
            f"{tm.median:.2f} s ({t} thread{'s' if t > 1 else ''})" for t, tm in timings.items()
        )
    )
    return rows
