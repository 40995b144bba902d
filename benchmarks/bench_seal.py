"""Suction seal: mgn.suction.SealModel against a NumPy + trimesh/embreex implementation of the
same spring-mass model (benchmarks/seal_peer.py) on the same candidates.

Per built-in object: candidates from `mgn.sample_surface(mesh, N, method="even")`, the
MetaGraspNet cup (128 mass points, 1000-ray hole check) and the robust score (10 perturbed
trials). mgn is timed with 1 thread and with every usable core; the peer on a strided subset of
the same candidates (it is slow), with the same random streams, so it runs the very same trials.

Rays per evaluation. mgn casts, per trial, 129 projection rays (ring + centre), then 128
obstruction rays and then the 1000 hole rays, in packets of 16, and stops the obstruction and the
hole check at the first packet that decides them; plus one on-surface ray per candidate. From the
failure reason of every trial (which mgn returns) the count is exact for "miss" (129), "hill"
(257), "force" and sealed trials (1257); for "obstruction" and "hole" trials it lies between
bounds and is estimated from the peer, which runs the same trials, gets the same outcomes and
counts the packets mgn traces (exact on the peer's subset, a per-reason mean elsewhere).

The coherent-ray limit: mgn.RayScene(mesh).intersect (and .occluded) of a camera's rays with
coherent=True on the same mesh, timed in the same loop; the seal's rays/s are given as a share.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from typing import Any

import numpy as np

from .common import (
    PEER_NOT_INSTALLED,
    Row,
    Timing,
    fmt_rate,
    measure_alternating,
    percent,
    thread_counts,
)

OBJECTS = ("mug", "bottle_water", "box_cereal", "pear")
SEED = 7  # trial perturbations
SAMPLE_SEED = 1  # candidate sampling
AGREEMENT_MIN = 0.95  # nominal seal/no-seal and reason equal on at least this share
TARGET_EVALS_PER_S = 2000.0  # target at 2 threads
PEER_NAME = "seal_peer.PeerSealModel.evaluate (NumPy + trimesh RayMeshIntersector/embreex)"


def load_peer() -> tuple[Any | None, str]:
    try:
        from trimesh.ray.ray_pyembree import RayMeshIntersector  # noqa: F401

        from . import seal_peer
    except ImportError as exc:
        return None, f"{PEER_NOT_INSTALLED} (trimesh/embreex: {exc})"
    return seal_peer, ""


def top_down_camera(mgn: Any, bounds: np.ndarray, side: int) -> tuple[np.ndarray, np.ndarray]:
    """A 60° pinhole camera above the object looking straight down (world -z), framing its
    larger horizontal side: `side`² rays from one centre, pixel order (coherent)."""
    lo, hi = np.asarray(bounds, np.float64)
    centre = (lo + hi) / 2
    half = 0.5 * float(np.max((hi - lo)[:2]))
    tan_half = np.tan(np.radians(30.0))
    f = 0.5 * side / tan_half
    K = np.array([[f, 0.0, side / 2], [0.0, f, side / 2], [0.0, 0.0, 1.0]])
    X_WC = np.eye(4)
    X_WC[:3, :3] = np.diag([1.0, -1.0, -1.0])  # OpenCV camera looking along world -z
    X_WC[:3, 3] = [centre[0], centre[1], hi[2] + 1.05 * half / tan_half]
    return mgn.camera_rays(K, side, side, X_WC)


def mgn_ray_counts(
    trial_reason: np.ndarray, cup: Any, peer_means: dict[int, float]
) -> tuple[float, float, float, bool]:
    """Rays mgn casts for trials with these failure codes: (estimate, lower, upper, exact?).
    Includes the on-surface ray of every candidate."""
    N, H = int(cup.num_points), int(cup.hole_rays)
    ring, up = N + 1, N
    full = ring + up + H
    first_packet = min(16, N)
    bounds = {
        0: (full, full),  # sealed
        1: (ring, ring),  # miss
        2: (ring + first_packet, ring + up),  # obstruction: up rays stop at a hit packet
        3: (ring + up, ring + up),  # hill
        4: (ring + up, full),  # hole: centre missed (no disc rays) .. all disc rays
        5: (full, full),  # force
    }
    counts = Counter(int(x) for x in np.asarray(trial_reason).ravel())
    n_cand = np.asarray(trial_reason).shape[0]
    est = lo = hi = float(n_cand)
    exact = True
    for code, k in counts.items():
        a, b = bounds[code]
        lo += k * a
        hi += k * b
        if a == b:
            est += k * a
        else:
            exact = False
            est += k * peer_means.get(code, b)
    return est, lo, hi, exact


def detect_ring_unit(
    model: Any, peer: Any, points: np.ndarray, normals: np.ndarray, samples: int = 5
) -> float | None:
    """The length unit (m) in which mgn's ring-spring stiffness takes its rest lengths: mgn's
    ring forces (SealModel.trial) over the peer's pure-SI ones on the same projected rings,
    least squares over the first `samples` candidates that reach the force stage."""
    num = den = 0.0
    found = 0
    saved = peer.ring_length_unit
    peer.ring_length_unit = 1.0
    try:
        for c, nrm in zip(points.astype(np.float64), normals.astype(np.float64), strict=True):
            n = nrm / np.linalg.norm(nrm)
            f_mgn = np.asarray(model.trial(c, n).ring_force, np.float64)
            if f_mgn.size == 0 or not np.any(f_mgn):
                continue
            x = peer.projected_ring(c, n)
            if x is None:
                continue
            f_si = peer.ring_forces(x)
            num += float(np.sum(f_mgn * f_si))
            den += float(np.sum(f_si * f_si))
            found += 1
            if found >= samples:
                break
    finally:
        peer.ring_length_unit = saved
    if den == 0.0:
        return None
    ratio = num / den
    for unit in (0.01, 1.0):  # MetaGraspNet's cm convention, pure SI
        if abs(ratio / unit - 1.0) < 0.01:
            return unit
    return ratio


def reason_counts(mgn_reason: np.ndarray, peer_reason: np.ndarray, names) -> str:
    pairs = Counter(
        (names[int(a)], names[int(b)])
        for a, b in zip(mgn_reason, peer_reason, strict=True)
        if a != b
    )
    return ", ".join(f"mgn {a} / peer {b} ×{k}" for (a, b), k in pairs.most_common()) or "none"


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any | None,
    mgn_status: str,
    log: Callable[[str], None],
) -> list[Row]:
    n_cand = 400 if quick else 2000  # candidates per mgn call
    n_peer = 12 if quick else 40  # of them, robust evaluations timed on the peer
    n_nominal = 200 if quick else 1000  # of them, nominal trials for the agreement check
    side = 400 if quick else 1000  # camera rays side² for the coherent limit
    peer_mod, peer_status = load_peer()
    rows: list[Row] = []
    if mgn is None:
        # The objects and the candidates come from mgn: nothing can be measured without it.
        for name in OBJECTS:
            rows.append(
                Row(
                    group="suction seal",
                    case=f"{name}: robust score",
                    n=n_cand,
                    unit="evals/s",
                    peer_name=PEER_NAME,
                    mgn_status=mgn_status,
                    peer_status="needs mgn for the objects and candidates",
                )
            )
        return rows

    for name in OBJECTS:
        rows += _object_rows(
            mgn,
            name,
            n_cand=n_cand,
            n_peer=n_peer,
            n_nominal=n_nominal,
            side=side,
            repeats=repeats,
            peer_mod=peer_mod,
            peer_status=peer_status,
            mgn_status=mgn_status,
            log=log,
        )
    return rows


def _object_rows(
    mgn: Any,
    name: str,
    *,
    n_cand: int,
    n_peer: int,
    n_nominal: int,
    side: int,
    repeats: int,
    peer_mod: Any | None,
    peer_status: str,
    mgn_status: str,
    log: Callable[[str], None],
) -> list[Row]:
    """The three rows of one object: evaluations/s, rays/s, the coherent-ray limit."""
    from mgn.objects import get_object
    from mgn.suction import FAILURE_REASONS, SealModel

    threads = thread_counts()
    tmax = threads[-1]
    rows: list[Row] = []
    mesh = get_object(name).to_mesh()
    samples = mgn.sample_surface(mesh, n_cand, method="even", seed=SAMPLE_SEED)
    points = np.ascontiguousarray(samples.points, np.float32)
    normals = np.ascontiguousarray(samples.normals, np.float32)
    model = SealModel(mesh)
    cup = model.cup
    scene = mgn.RayScene(mesh)
    cam_o, cam_d = top_down_camera(mgn, mesh.bounds, side)
    case = (
        f"{name} ({mesh.num_faces:,} tri), robust score, {cup.num_points} points, "
        f"{cup.hole_rays} hole rays, 10 trials"
    )
    log(f"  suction seal: {case}, {n_cand} candidates")

    peer = None
    if peer_mod is not None:
        peer = peer_mod.PeerSealModel(
            np.asarray(mesh.vertices),
            np.asarray(mesh.faces),
            radius=cup.radius,
            num_points=cup.num_points,
            youngs_modulus=cup.youngs_modulus,
            pressure_difference=cup.pressure_difference,
            compensable_height=cup.compensable_height,
            approach_height=cup.approach_height,
            c1=cup.c1,
            c2=cup.c2,
            hole_rays=cup.hole_rays,
        )
    ring_unit_note = ""
    if peer is not None:
        unit = detect_ring_unit(model, peer, points, normals)
        if unit is not None:
            peer.ring_length_unit = unit
        ring_unit_note = (
            "mgn's ring-spring stiffness takes the rest length in "
            + {
                0.01: "cm (c2 as MetaGraspNet fitted it; MODELS.md §1 states pure SI)",
                1.0: "m (pure SI, as MODELS.md §1)",
                None: "an unknown unit (no ring force seen; the peer assumes cm)",
            }.get(unit, f"units of {unit:.4g} m (neither cm nor m: check Cup::ring_stiffness)")
            + "; the peer uses the same"
        )
    peer_idx = np.linspace(0, n_cand - 1, n_peer).round().astype(int)
    nominal_idx = np.linspace(0, n_cand - 1, n_nominal).round().astype(int)

    cases: dict[str, Callable[[], object]] = {}
    for t in threads:
        cases[f"mgn/{t}"] = lambda t=t: model.evaluate(points, normals, seed=SEED, num_threads=t)
    if peer is not None:
        cases["peer"] = lambda: peer.evaluate(
            points[peer_idx], normals[peer_idx], seed=SEED, indices=peer_idx
        )
    for t in threads:
        cases[f"cam.intersect/{t}"] = lambda t=t: scene.intersect(
            cam_o, cam_d, coherent=True, num_threads=t
        )
    cases[f"cam.occluded/{tmax}"] = lambda: scene.occluded(
        cam_o, cam_d, coherent=True, num_threads=tmax
    )

    # Warm-up; these results are the ones compared. The peer's ray counters cover exactly
    # the warm-up call.
    results = {}
    for key, fn in cases.items():
        if key == "peer":
            peer.rays_cast = peer.mgn_rays = 0
            peer.trial_mgn_rays.clear()
        results[key] = fn()
    peer_rays_per_call = peer.rays_cast if peer is not None else 0
    peer_mgn_rays_subset = peer.mgn_rays if peer is not None else 0
    peer_trials = list(peer.trial_mgn_rays) if peer is not None else []
    timings = measure_alternating(cases, repeats)

    # Nominal agreement (one trial at the nominal point and normal), untimed.
    m_nom = model.evaluate(points, normals, perturb=False, num_threads=tmax)
    agreement, agreement_ok = "—", None
    nominal_detail = ""
    if peer is not None:
        peer.trial_mgn_rays.clear()
        p_nom = peer.evaluate(points[nominal_idx], normals[nominal_idx], perturb=False)
        peer_trials += peer.trial_mgn_rays
        m_r = np.asarray(m_nom.reason)[nominal_idx]
        p_r = p_nom["reason"]
        same_outcome = (m_r == 0) == (p_r == 0)
        same_reason = m_r == p_r
        ok_share = float(np.mean(same_outcome & same_reason))
        agreement_ok = ok_share >= AGREEMENT_MIN
        m_rob = results[f"mgn/{tmax}"]
        p_rob = results["peer"]
        trial_same = float(
            np.mean(np.asarray(m_rob.trial_reason)[peer_idx] == p_rob["trial_reason"])
        )
        score_same = float(np.mean(np.asarray(m_rob.score)[peer_idx] == p_rob["score"]))
        agreement = (
            f"nominal seal/no-seal and reason {percent(ok_share)} of {len(nominal_idx)}; "
            f"robust: trial reasons {percent(trial_same)}, scores {percent(score_same)} "
            f"of {len(peer_idx)}"
        )
        nominal_detail = (
            f"nominal disagreements: {reason_counts(m_r, p_r, FAILURE_REASONS)}; "
            f"nominal outcomes (mgn): "
            + ", ".join(
                f"{FAILURE_REASONS[c]} {k}" for c, k in sorted(Counter(int(x) for x in m_r).items())
            )
        )

    # Rays mgn casts per call, from the failure reason of every trial.
    per_reason: dict[int, list[int]] = {}
    for code, rays in peer_trials:
        per_reason.setdefault(code, []).append(rays)
    peer_means = {c: float(np.mean(v)) for c, v in per_reason.items()}
    m_rob = results[f"mgn/{tmax}"]
    trial_reason = np.asarray(m_rob.trial_reason)
    est, lo, hi, exact = mgn_ray_counts(trial_reason, cup, peer_means)
    if peer is not None:
        # On the peer's subset the count is exact (same trials, packets counted).
        sub_est, _, _, _ = mgn_ray_counts(trial_reason[peer_idx], cup, peer_means)
        est += peer_mgn_rays_subset - sub_est
        est = min(max(est, lo), hi)

    eval_row = Row(
        group="suction seal",
        case=case,
        n=n_cand,
        unit="evals/s",
        peer_name=PEER_NAME,
        mgn_status=mgn_status,
        peer_status=peer_status,
        agreement=agreement,
        agreement_ok=agreement_ok,
    )
    eval_row.mgn = {t: timings[f"mgn/{t}"] for t in threads}
    same_threads = all(
        np.array_equal(results["mgn/1"].trial_reason, results[f"mgn/{t}"].trial_reason)
        for t in threads
    )
    mgn_rate = eval_row.mgn[tmax].rate(n_cand)
    eval_row.notes.append(
        f"mean robust score {float(np.mean(m_rob.score)):.3f}; trial outcomes "
        + ", ".join(
            f"{FAILURE_REASONS[c]} {k}"
            for c, k in sorted(Counter(int(x) for x in trial_reason.ravel()).items())
        )
    )
    eval_row.notes.append(
        f"mgn at {tmax} threads: {fmt_rate(mgn_rate)} evals/s, target "
        f"{fmt_rate(TARGET_EVALS_PER_S)}/s {'met' if mgn_rate >= TARGET_EVALS_PER_S else 'NOT met'}"
        f"; mgn results with 1 and {tmax} threads {'identical' if same_threads else 'DIFFER'}"
    )
    if peer is not None:
        pt = timings["peer"]
        scale = n_cand / len(peer_idx)
        eval_row.peer = Timing([w * scale for w in pt.wall], [c * scale for c in pt.cpu])
        eval_row.notes.append(
            f"peer timed on {len(peer_idx)} of the {n_cand} candidates (evenly strided, "
            f"same random streams): {fmt_rate(pt.rate(len(peer_idx)))} evals/s, its times "
            f"scaled by {scale:.3g} to the {n_cand} candidates for the table; "
            f"{pt.cores_used:.2f} cores used; it cast {peer_rays_per_call:,} rays per call "
            f"({fmt_rate(peer_rays_per_call / pt.median)} rays/s), mgn casts "
            f"{peer_mgn_rays_subset:,} for the same trials"
        )
        eval_row.notes.append(nominal_detail)
        eval_row.notes.append(ring_unit_note)
    rows.append(eval_row)

    # Rays/s of the seal evaluations, and their share of the coherent limit.
    cam_n = len(cam_o)
    lim_i = timings[f"cam.intersect/{tmax}"].rate(cam_n)
    lim_o = timings[f"cam.occluded/{tmax}"].rate(cam_n)
    seal_rays_s = est / timings[f"mgn/{tmax}"].median
    ray_row = Row(
        group="suction seal",
        case=f"{name}: rays traced by mgn in those evaluations" + ("" if exact else " (estimated)"),
        n=int(round(est)),
        unit="rays/s",
        peer_name="—",
        mgn_status=mgn_status,
        limit_work=("embree_coherent", 1.0),
        agreement=(
            f"{tmax} threads: {percent(seal_rays_s / lim_i)} of the coherent intersect "
            f"limit, {percent(seal_rays_s / lim_o)} of the coherent occluded limit"
        ),
    )
    ray_row.mgn = eval_row.mgn
    ray_row.notes.append(
        f"{est / n_cand:,.0f} rays per evaluation "
        + (
            "(exact)"
            if exact
            else f"(estimated; bounds {lo / n_cand:,.0f}–{hi / n_cand:,.0f}, i.e. "
            f"{fmt_rate(lo / timings[f'mgn/{tmax}'].median)}–"
            f"{fmt_rate(hi / timings[f'mgn/{tmax}'].median)} rays/s at {tmax} threads; "
            "obstruction and hole trials stop early at an unknown packet, estimated from "
            "the peer's exact count on the same trials)"
        )
        + "; 129 of them are first-hit rays, the rest any-hit (occlusion) rays"
    )
    rows.append(ray_row)

    hit_rate = float(np.mean(np.asarray(results[f"cam.intersect/{tmax}"].hit)))
    cam_row = Row(
        group="suction seal",
        case=f"{name}: coherent-ray limit, {side}×{side} camera rays, "
        "RayScene.intersect(coherent=True)",
        n=cam_n,
        unit="rays/s",
        peer_name="—",
        mgn_status=mgn_status,
    )
    cam_row.mgn = {t: timings[f"cam.intersect/{t}"] for t in threads}
    cam_row.notes.append(
        f"hit rate {percent(hit_rate)}; RayScene.occluded(coherent=True) at {tmax} threads: "
        f"{fmt_rate(lim_o)} rays/s"
    )
    rows.append(cam_row)
    log(
        f"    mgn {fmt_rate(eval_row.mgn[1].rate(n_cand))} evals/s (1T), "
        f"{fmt_rate(mgn_rate)} ({tmax}T); {fmt_rate(seal_rays_s)} rays/s = "
        f"{percent(seal_rays_s / lim_i)} of {fmt_rate(lim_i)} coherent; "
        + (
            f"peer {fmt_rate(timings['peer'].rate(len(peer_idx)))} evals/s; {agreement}"
            if peer is not None
            else f"peer: {peer_status}"
        )
    )
    return rows
