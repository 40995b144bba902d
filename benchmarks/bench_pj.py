"""Parallel-jaw labels: mgn's antipodal sampler against a numpy + trimesh probe test.

Two rows on one built-in object (the mug: thin walls, a handle, many colliding approaches):

1. The antipodal probe test alone (MODELS.md §5: 5 perturbed probes per contact point, first two
   hits of an all-hit ray cast, width below the opening, both normals in the friction cone).
   The peer draws its perturbations with numpy and casts with trimesh's ``intersects_location``
   (embreex when installed), then does the per-ray bookkeeping in numpy. The two sides draw
   different random numbers, so agreement compares the mean analytic score over all points.
2. The full analytic labels of ``mgn.pj.label_object`` (even sampling, probes, up to 50 approaches
   per accepted probe with the gripper-vs-object collision check, wrench score). There is no
   drop-in peer for the collision-checked sampler; the row reports mgn alone, in points/s, and
   notes the grasps/s and whether 1 and N threads give identical labels. Target: 5000 points in
   <= 5 s on 2 cores.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from .common import PEER_NOT_INSTALLED, Row, measure_alternating, thread_counts

OBJECT = "mug"
TILT = math.pi / 16
OFFSET = 0.005
START = 0.010
MU = math.tan(math.pi / 8)
MAX_OPENING = 0.08


def _euler_xyz(a: np.ndarray) -> np.ndarray:
    """(n,3,3) rotations Rz(a2) Ry(a1) Rx(a0)."""
    cx, cy, cz = np.cos(a).T
    sx, sy, sz = np.sin(a).T
    one, zero = np.ones_like(cx), np.zeros_like(cx)
    Rx = np.stack([one, zero, zero, zero, cx, -sx, zero, sx, cx], -1).reshape(-1, 3, 3)
    Ry = np.stack([cy, zero, sy, zero, one, zero, -sy, zero, cy], -1).reshape(-1, 3, 3)
    Rz = np.stack([cz, -sz, zero, sz, cz, zero, zero, zero, one], -1).reshape(-1, 3, 3)
    return Rz @ Ry @ Rx


def peer_probe_scores(tm: Any, points: np.ndarray, normals: np.ndarray, seed: int) -> np.ndarray:
    """Analytic score per point with numpy + trimesh (the same probe test as mgn)."""
    rng = np.random.default_rng(seed)
    n_pts, probes = len(points), 5
    p = np.repeat(points, probes, axis=0)
    n = np.repeat(normals, probes, axis=0)
    R = _euler_xyz(rng.uniform(-TILT, TILT, (len(p), 3)))
    d = np.einsum("nij,nj->ni", R, -n)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    origins = p + rng.uniform(-OFFSET, OFFSET, p.shape) - START * d
    loc, ray, tri = tm.ray.intersects_location(origins, d, multiple_hits=True)
    t = np.einsum("ij,ij->i", loc - origins[ray], d[ray])
    order = np.lexsort((t, ray))
    loc, ray, tri = loc[order], ray[order], tri[order]
    first = np.ones(len(ray), bool)
    first[1:] = ray[1:] != ray[:-1]
    idx1 = np.flatnonzero(first)
    has2 = np.zeros(len(idx1), bool)
    has2[:-1] = ray[idx1[:-1] + 1] == ray[idx1[:-1]] if len(idx1) > 1 else has2[:-1]
    if len(idx1) and idx1[-1] + 1 < len(ray):
        has2[-1] = ray[idx1[-1] + 1] == ray[idx1[-1]]
    i1 = idx1[has2]
    i2 = i1 + 1
    q1, q2 = loc[i1], loc[i2]
    w = np.linalg.norm(q2 - q1, axis=1)
    ok = (w > 1e-9) & (w < MAX_OPENING)
    v = (q2 - q1) / np.maximum(w, 1e-12)[:, None]
    fn = tm.face_normals
    cos_cone = math.cos(math.atan(MU))
    ok &= (-np.einsum("ij,ij->i", fn[tri[i1]], v) >= cos_cone) & (
        np.einsum("ij,ij->i", fn[tri[i2]], v) >= cos_cone
    )
    accepted = np.zeros(len(p), bool)
    accepted[ray[i1][ok]] = True
    return accepted.reshape(n_pts, probes).mean(axis=1)


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any | None,
    mgn_status: str,
    log: Callable[[str], None],
) -> list[Row]:
    import trimesh

    from mgn.objects import builtin_objects

    threads = thread_counts()
    num_points = 1000 if quick else 5000
    spec = next(s for s in builtin_objects() if s.name == OBJECT)
    verts, faces = np.asarray(spec.vertices, np.float64), np.asarray(spec.faces)
    tm = trimesh.Trimesh(np.asarray(verts, np.float32).astype(np.float64), faces, process=False)
    probe_row = Row(
        group="parallel-jaw",
        case=f"{OBJECT} ({len(faces):,} tri), antipodal probe test, {num_points} points x 5 probes",
        n=num_points,
        unit="points/s",
        peer_name="numpy + trimesh intersects_location(multiple_hits=True)",
        mgn_status=mgn_status,
    )
    label_row = Row(
        group="parallel-jaw",
        case=f"{OBJECT}, analytic labels with collision check (label_object), {num_points} points",
        n=num_points,
        unit="points/s",
        peer_name="—",
        mgn_status=mgn_status,
        peer_status="no drop-in peer for the collision-checked sampler",
    )
    cases: dict[str, Callable[[], object]] = {}
    if mgn is not None:
        from mgn.geometry.mesh import mass_properties
        from mgn.pj import AntipodalSampler, label_object

        mesh = spec.to_mesh()
        props = mass_properties(mesh, spec.density)
        samples = mgn.sample_surface(mesh, num_points, method="even", seed=0)
        pts = np.asarray(samples.points, np.float64)
        nrm = np.asarray(samples.normals, np.float64)
        sampler = AntipodalSampler(mesh)
        for t in threads:
            cases[f"mgn.probe/{t}"] = lambda t=t: sampler.sample(
                pts, nrm, approaches_tried=0, num_threads=t
            )
            cases[f"mgn.label/{t}"] = lambda t=t: label_object(
                mesh,
                mass=props.mass,
                com=props.center_of_mass,
                num_points=num_points,
                num_threads=t,
            )
    else:
        samples = None
    try:
        tm.ray.intersects_location  # noqa: B018  (ray backend present)
        peer_ok = samples is not None
    except AttributeError:
        peer_ok = False
        probe_row.peer_status = PEER_NOT_INSTALLED
    if peer_ok:
        cases["peer.probe"] = lambda: peer_probe_scores(tm, pts, nrm, seed=0)
    elif not probe_row.peer_status:
        probe_row.peer_status = "needs mgn's sample points"

    log(f"  parallel-jaw: {OBJECT}, {num_points} points")
    results = {name: fn() for name, fn in cases.items()}  # warm-up; compared below
    timings = measure_alternating(cases, repeats) if cases else {}
    if mgn is not None:
        probe_row.mgn = {t: timings[f"mgn.probe/{t}"] for t in threads}
        label_row.mgn = {t: timings[f"mgn.label/{t}"] for t in threads}
        labels = results[f"mgn.label/{threads[-1]}"]
        best = timings[f"mgn.label/{threads[-1]}"].median
        label_row.notes.append(
            f"{len(labels):,} grasps, {len(labels) / best:,.0f} grasps/s with {threads[-1]} "
            f"threads; {labels.num_colliding:,} colliding approaches rejected"
        )
        label_row.notes.append(f"target 5 s: measured {best:.2f} s")
        if len(threads) > 1:
            one = results["mgn.label/1"]
            same = np.array_equal(one.approach, labels.approach) and np.array_equal(
                one.p1, labels.p1
            )
            label_row.notes.append(
                f"labels with 1 and {threads[-1]} threads " + ("identical" if same else "DIFFER")
            )
    if mgn is not None and peer_ok:
        probe_row.peer = timings["peer.probe"]
        m_score = np.asarray(results[f"mgn.probe/{threads[-1]}"].point_score, np.float64)
        p_score = np.asarray(results["peer.probe"], np.float64)
        diff = abs(m_score.mean() - p_score.mean())
        probe_row.agreement = f"mean score {m_score.mean():.3f} vs {p_score.mean():.3f}"
        probe_row.agreement_ok = bool(diff < 0.03)
        probe_row.notes.append(
            "different random perturbations on each side: agreement is statistical "
            "(mean analytic score within 0.03)"
        )
    return [probe_row, label_row]
