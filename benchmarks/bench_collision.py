"""Mesh-mesh collision and distance: mgn batch calls against python-fcl in a Python loop.

The peer is python-fcl as a user would drive it: two `fcl.CollisionObject`s over `fcl.BVHModel`s
(OBBRSS), a loop that sets both transforms and calls `fcl.collide` / `fcl.distance` once per pose
pair. mgn gets the same poses as (N,4,4) arrays in one call. Both wrap the same library (FCL 0.7),
so this measures what the batch interface saves, plus threads.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import trimesh

from .bench_raycast import as_float32_mesh, random_rotation
from .common import (
    PEER_NOT_INSTALLED,
    Row,
    fraction,
    measure_alternating,
    percent,
    thread_counts,
)

DIST_TOL = 1e-4  # metres
AGREEMENT_MIN = 0.999
# Radius of the ball the second object's centre is drawn from: about half of the pose pairs
# collide for these two shapes (49.7 % measured with FCL on 2,000 pairs).
TRANSLATION_RADIUS = 0.10


def make_meshes() -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """A torus (5,120 triangles, has a hole) and an elongated ellipsoid (5,120 triangles), with
    float32-exact vertices."""
    torus = trimesh.creation.torus(0.05, 0.015, major_sections=64, minor_sections=40)
    ellipsoid = trimesh.creation.icosphere(subdivisions=4, radius=1.0)
    ellipsoid.apply_scale([0.06, 0.02, 0.02])
    return as_float32_mesh(torus), as_float32_mesh(ellipsoid)


def make_poses(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """X_WA: random rotation at the origin; X_WB: random rotation, centre uniform in a ball."""
    X_WA = np.tile(np.eye(4), (n, 1, 1))
    X_WB = np.tile(np.eye(4), (n, 1, 1))
    X_WA[:, :3, :3] = random_rotation(rng, n)
    X_WB[:, :3, :3] = random_rotation(rng, n)
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    X_WB[:, :3, 3] = u * (TRANSLATION_RADIUS * np.cbrt(rng.uniform(size=n)))[:, None]
    return np.ascontiguousarray(X_WA), np.ascontiguousarray(X_WB)


def load_peer() -> tuple[Any | None, str]:
    try:
        import fcl
    except ImportError as exc:
        return None, f"{PEER_NOT_INSTALLED} (python-fcl: {exc})"
    return fcl, ""


def fcl_object(fcl: Any, mesh: trimesh.Trimesh) -> Any:
    model = fcl.BVHModel()
    model.beginModel(len(mesh.vertices), len(mesh.faces))
    model.addSubModel(np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int32))
    model.endModel()
    return fcl.CollisionObject(model, fcl.Transform())


def fcl_collide_loop(fcl: Any, oa: Any, ob: Any, X_WA: np.ndarray, X_WB: np.ndarray):
    request = fcl.CollisionRequest()
    out = np.empty(len(X_WA), bool)
    for i in range(len(X_WA)):
        oa.setTransform(fcl.Transform(X_WA[i, :3, :3], X_WA[i, :3, 3]))
        ob.setTransform(fcl.Transform(X_WB[i, :3, :3], X_WB[i, :3, 3]))
        out[i] = fcl.collide(oa, ob, request, fcl.CollisionResult()) > 0
    return out


def fcl_distance_loop(fcl: Any, oa: Any, ob: Any, X_WA: np.ndarray, X_WB: np.ndarray):
    request = fcl.DistanceRequest(enable_nearest_points=True)
    out = np.empty(len(X_WA))
    for i in range(len(X_WA)):
        oa.setTransform(fcl.Transform(X_WA[i, :3, :3], X_WA[i, :3, 3]))
        ob.setTransform(fcl.Transform(X_WB[i, :3, :3], X_WB[i, :3, 3]))
        out[i] = fcl.distance(oa, ob, request, fcl.DistanceResult())
    return out  # FCL reports 0 or -1 for an intersecting pair


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any | None,
    mgn_status: str,
    log: Callable[[str], None],
) -> list[Row]:
    rng = np.random.default_rng(20240612)
    n = 2_000 if quick else 10_000
    threads = thread_counts()
    torus, ellipsoid = make_meshes()
    X_WA, X_WB = make_poses(rng, n)
    fcl, peer_status = load_peer()
    case = (
        f"torus ({len(torus.faces):,} tri) vs ellipsoid ({len(ellipsoid.faces):,} tri), "
        f"{n:,} random poses"
    )

    cases: dict[str, Callable[[], object]] = {}
    if mgn is not None:
        cm_a = mgn.CollisionModel(
            mgn.Mesh(np.asarray(torus.vertices, np.float32), np.asarray(torus.faces, np.int32))
        )
        cm_b = mgn.CollisionModel(
            mgn.Mesh(
                np.asarray(ellipsoid.vertices, np.float32), np.asarray(ellipsoid.faces, np.int32)
            )
        )
        for t in threads:
            cases[f"mgn.collide/{t}"] = lambda t=t: mgn.collide(
                cm_a, X_WA, cm_b, X_WB, num_threads=t
            )
            cases[f"mgn.distance/{t}"] = lambda t=t: mgn.distance(
                cm_a, X_WA, cm_b, X_WB, num_threads=t
            )
    if fcl is not None:
        oa, ob = fcl_object(fcl, torus), fcl_object(fcl, ellipsoid)
        cases["peer.collide"] = lambda: fcl_collide_loop(fcl, oa, ob, X_WA, X_WB)
        cases["peer.distance"] = lambda: fcl_distance_loop(fcl, oa, ob, X_WA, X_WB)

    log(f"  collision: {case}")
    results = {name: fn() for name, fn in cases.items()}  # warm-up; compared below
    timings = measure_alternating(cases, repeats) if cases else {}

    rows = []
    for query, key, peer_call in (
        ("collide (boolean)", "collide", "fcl.collide"),
        ("distance with nearest points", "distance", "fcl.distance"),
    ):
        row = Row(
            group="collision",
            case=f"{case}, {query}",
            n=n,
            unit="checks/s",
            peer_name=f"{peer_call} in a Python loop",
            mgn_status=mgn_status,
            peer_status=peer_status,
        )
        if mgn is not None:
            row.mgn = {t: timings[f"mgn.{key}/{t}"] for t in threads}
        if fcl is not None:
            row.peer = timings[f"peer.{key}"]
        rows.append(row)

    collide_row, distance_row = rows
    if mgn is not None:
        m_hit = np.asarray(results[f"mgn.collide/{threads[-1]}"], bool)
        m_dist = np.asarray(results[f"mgn.distance/{threads[-1]}"].distance, np.float64)
        if len(threads) > 1:
            same_hit = np.array_equal(m_hit, np.asarray(results["mgn.collide/1"], bool))
            d1 = results["mgn.distance/1"]
            same_dist = np.array_equal(m_dist, np.asarray(d1.distance)) and np.array_equal(
                results[f"mgn.distance/{threads[-1]}"].points_a, d1.points_a
            )
            for row, same in ((collide_row, same_hit), (distance_row, same_dist)):
                row.notes.append(
                    f"mgn results with 1 and {threads[-1]} threads "
                    + ("identical" if same else "DIFFER")
                )
        collide_row.notes.append(f"mgn: {percent(fraction(m_hit))} of pairs collide")
    if fcl is not None:
        p_hit = np.asarray(results["peer.collide"], bool)
        p_dist = np.asarray(results["peer.distance"], np.float64)
        collide_row.notes.append(f"FCL: {percent(fraction(p_hit))} of pairs collide")
    if mgn is not None and fcl is not None:
        hit_ok = fraction(m_hit == p_hit)
        collide_row.agreement = f"collides {percent(hit_ok)}"
        collide_row.agreement_ok = hit_ok >= AGREEMENT_MIN
        apart = ~m_hit & ~p_hit
        dist_ok = fraction(np.abs(m_dist[apart] - p_dist[apart]) <= DIST_TOL)
        # A colliding pair must read 0 in mgn; FCL gives 0 or -1 for it.
        zero_ok = fraction(m_dist[m_hit] == 0.0)
        distance_row.agreement = (
            f"distance ±{DIST_TOL:g} m {percent(dist_ok)} of {int(apart.sum()):,} separated "
            f"pairs; mgn 0 on colliding pairs {percent(zero_ok)}"
        )
        distance_row.agreement_ok = dist_ok >= AGREEMENT_MIN and zero_ok >= AGREEMENT_MIN
    return rows
