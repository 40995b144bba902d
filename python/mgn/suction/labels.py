"""Object-level suction labels (``grasps/suctioncup/*`` of ``textured.obj.hdf5``, docs/format.md).

Pipeline per object: sample candidate points evenly on the surface (MetaGraspNet: 5000), score
each with a seal model (robust 10-trial score), drop candidates whose cup body would collide with
the object (FCL), compute the suction wrench score with gravity along -z of the object frame, and
the physics score: the seal score times the share of the shake test's (friction, density) grid in
which the sealed cup holds the object (:mod:`mgn.suction.hold`, docs/models.md §3a).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
from tqdm import tqdm

from mgn import _core
from mgn.errors import InvalidArgumentError
from mgn.geometry.collision import CollisionModel, collide
from mgn.geometry.mesh import Mesh, SurfaceSamples, make_cylinder, sample_surface
from mgn.hardware import SuctionCup
from mgn.suction.hold import ShakeLoads, frames_z_to, suction_hold_scores
from mgn.suction.seal import SealModel, SealModelName, suction_wrench_scores

#: Gap between the contact and the bottom of the cup body in the collision check, m: the lip
#: itself touches the surface, so the body cylinder starts this far above the contact.
CUP_BODY_CLEARANCE = 0.003


@dataclass(frozen=True)
class SuctionLabels:
    """Suction labels of one object (object frame, metres).

    Attributes:
        points: (K, 3) contact points.
        approach: (K, 3) unit approach directions, into the surface (= -normal).
        score: (K,) robust seal score in [0, 1].
        wrench: (K,) suction wrench score in [0, 1] (gravity along -z of the object frame).
        reason: (K,) failure code of the seal (see mgn.suction.FAILURE_REASONS).
        num_candidates: points sampled before the collision filter.
        num_colliding: candidates dropped because the cup body hits the object.
        metadata: cup, model, seed and counts, as written to the file.
        simulation: (K,) physics score in [0, 1]: ``score`` times the hold score of
            :func:`mgn.suction.hold.suction_hold_scores` (0 where the cup never seals); None:
            not computed (NaN in the scene files).
    """

    points: npt.NDArray[np.float32]
    approach: npt.NDArray[np.float32]
    score: npt.NDArray[np.float32]
    wrench: npt.NDArray[np.float32]
    reason: npt.NDArray[np.uint8]
    num_candidates: int
    num_colliding: int
    metadata: dict[str, Any] = field(default_factory=dict)
    simulation: npt.NDArray[np.float32] | None = None


def cup_body_poses(points: np.ndarray, normals: np.ndarray, cup: SuctionCup) -> np.ndarray:
    """(N, 4, 4) poses of the cup-body cylinder (z axis along the normal) above each contact."""
    n = normals.astype(np.float64)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    length = cup.body_height - CUP_BODY_CLEARANCE
    X = np.tile(np.eye(4), (len(points), 1, 1))
    X[:, :3, :3] = frames_z_to(n)
    X[:, :3, 3] = points + n * (CUP_BODY_CLEARANCE + length / 2)
    return X


def label_object(
    mesh: Mesh,
    *,
    mass: float,
    com: npt.ArrayLike,
    inertia: npt.ArrayLike | None = None,
    cup: SuctionCup | None = None,
    model: SealModelName = "spring",
    num_points: int = 5000,
    seed: int = 0,
    num_threads: int = 0,
    progress: bool = False,
    chunk: int | None = None,
    samples: SurfaceSamples | None = None,
    grid: int = 10,
) -> SuctionLabels:
    """Suction labels of one object: see the module docstring. Deterministic for ``seed``.

    Args:
        mesh: the object, metres, object frame.
        mass: kg; com: centre of mass (m, object frame) — for the wrench and hold scores.
        inertia: (3, 3) inertia about the centre of mass, kg m^2, for the hold score's
            rotational terms (None: left out).
        cup: the suction cup (default: MetaGraspNet's).
        model: seal model name.
        num_points: candidates sampled evenly on the surface.
        progress: show a tqdm progress bar.
        chunk: points per native call (labels do not depend on it); None: 250 with a
            progress bar, else all at once (every call waits for its slowest thread).
        samples: the candidates, if already drawn: they must be
            ``sample_surface(mesh, num_points, method="even", seed=seed)`` (e.g. shared with
            :func:`mgn.pj.label_object`); None draws them here.
        grid: S of the hold score's S x S (friction, density factor) grid (MetaGraspNet's
            shake grid: 10).
    """

    cup = cup if cup is not None else SuctionCup()
    if samples is None:
        samples = sample_surface(mesh, num_points, method="even", seed=seed)
    elif len(samples.points) != num_points:
        raise InvalidArgumentError(
            f"suction label_object: samples holds {len(samples.points)} points, expected "
            f"num_points = {num_points}"
        )
    points, normals = samples.points, samples.normals
    body = CollisionModel(make_cylinder(cup.outer_radius, cup.body_height - CUP_BODY_CLEARANCE, 32))
    obj = CollisionModel(mesh)
    poses = cup_body_poses(points, normals, cup)
    hits = collide(body, poses, obj, np.eye(4), num_threads=num_threads)
    keep = ~np.asarray(hits, bool).reshape(-1)
    kept_idx = np.flatnonzero(keep)
    seal = SealModel(mesh, cup, model)
    if chunk is None:
        chunk = 250 if progress else max(1, len(kept_idx))
    if chunk < 1:
        raise InvalidArgumentError(f"label_object: chunk must be >= 1, got {chunk!r}")
    score = np.zeros(len(kept_idx), np.float32)
    reason = np.zeros(len(kept_idx), np.uint8)
    bar = tqdm(
        total=len(kept_idx),
        desc=f"suction {mesh.name or 'object'}",
        unit="pt",
        disable=not progress,
    )
    for start in range(0, len(kept_idx), chunk):
        idx = kept_idx[start : start + chunk]
        # Candidate k of the kept list uses the random stream (seed, k) whatever the chunking.
        res = seal.evaluate(
            points[idx], normals[idx], seed=seed, first_index=start, num_threads=num_threads
        )
        score[start : start + len(idx)] = res.score
        reason[start : start + len(idx)] = res.reason
        bar.update(len(idx))
    bar.close()
    approach = -normals[kept_idx]
    wrench = suction_wrench_scores(
        points[kept_idx], approach, mass=mass, com=com, cup_radius=cup.radius, k=cup.bending_k
    )
    loads = ShakeLoads.from_shake(grid)
    hold = suction_hold_scores(
        points[kept_idx], approach, mass=mass, com=com, inertia=inertia, cup=cup, loads=loads
    )
    simulation = (score * hold.score).astype(np.float32)
    metadata = {
        "suction_model": model,
        "suction_cup": cup.to_dict(),
        "suction_seed": int(seed),
        "suction_num_candidates": int(num_points),
        "suction_num_colliding": int((~keep).sum()),
        "suction_wrench": (
            f"gravity -z of the object frame; tau_max = {cup.bending_k:g} * r * pi * sqrt(2)"
        ),
        "suction_physics": {
            "score": "seal score x share of the (friction, density) grid held",
            "grid": int(grid),
            "friction": [round(v, 6) for v in loads.friction],
            "density_factor": [round(v, 6) for v in loads.density],
            "acceleration_m_s2": round(loads.translation_acceleration, 6),
            "rotation_rad": round(loads.rotation_angle, 6),
            "rotation_rad_s": round(loads.rotation_frequency, 6),
            "rotational_inertia": inertia is not None,
        },
        "mgn_version": _core.__version__,
    }
    return SuctionLabels(
        points[kept_idx],
        approach.astype(np.float32),
        score,
        wrench,
        reason,
        int(num_points),
        int((~keep).sum()),
        metadata,
        simulation,
    )
