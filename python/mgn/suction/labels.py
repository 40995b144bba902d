"""Object-level suction labels (``grasps/suctioncup/*`` of ``textured.obj.hdf5``, docs/format.md).

Pipeline per object: sample candidate points evenly on the surface (MetaGraspNet: 5000), score
each with a seal model (robust 10-trial score), drop candidates whose cup body would collide with
the object (FCL), and compute the suction wrench score with gravity along -z of the object frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from tqdm import tqdm

from mgn import _core
from mgn.errors import InvalidArgumentError
from mgn.geometry.collision import CollisionModel, collide
from mgn.geometry.mesh import Mesh, SurfaceSamples, make_cylinder, sample_surface
from mgn.hardware import SuctionCup
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
    """

    points: npt.NDArray[np.float32]
    approach: npt.NDArray[np.float32]
    score: npt.NDArray[np.float32]
    wrench: npt.NDArray[np.float32]
    reason: npt.NDArray[np.uint8]
    num_candidates: int
    num_colliding: int
    metadata: dict = field(default_factory=dict)


def _frames_z_to(n: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotations whose z column is the unit vector n (branch-free basis)."""
    sign = np.where(n[:, 2] >= 0, 1.0, -1.0)
    a = -1.0 / (sign + n[:, 2])
    b = n[:, 0] * n[:, 1] * a
    u = np.stack([1 + sign * n[:, 0] ** 2 * a, sign * b, -sign * n[:, 0]], axis=1)
    v = np.stack([b, sign + n[:, 1] ** 2 * a, -n[:, 1]], axis=1)
    return np.stack([u, v, n], axis=2)


def cup_body_poses(points: np.ndarray, normals: np.ndarray, cup: SuctionCup) -> np.ndarray:
    """(N, 4, 4) poses of the cup-body cylinder (z axis along the normal) above each contact."""
    n = normals.astype(np.float64)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    length = cup.body_height - CUP_BODY_CLEARANCE
    X = np.tile(np.eye(4), (len(points), 1, 1))
    X[:, :3, :3] = _frames_z_to(n)
    X[:, :3, 3] = points + n * (CUP_BODY_CLEARANCE + length / 2)
    return X


def label_object(
    mesh: Mesh,
    *,
    mass: float,
    com: npt.ArrayLike,
    cup: SuctionCup | None = None,
    model: SealModelName = "spring",
    num_points: int = 5000,
    seed: int = 0,
    num_threads: int = 0,
    progress: bool = False,
    chunk: int | None = None,
    samples: SurfaceSamples | None = None,
) -> SuctionLabels:
    """Suction labels of one object: see the module docstring. Deterministic for ``seed``.

    Args:
        mesh: the object, metres, object frame.
        mass: kg; com: centre of mass (m, object frame) — for the wrench score.
        cup: the suction cup (default: MetaGraspNet's).
        model: seal model name.
        num_points: candidates sampled evenly on the surface.
        progress: show a tqdm progress bar.
        chunk: points per native call (labels do not depend on it); None: 250 with a
            progress bar, else all at once (every call waits for its slowest thread).
        samples: the candidates, if already drawn: they must be
            ``sample_surface(mesh, num_points, method="even", seed=seed)`` (e.g. shared with
            :func:`mgn.pj.label_object`); None draws them here.
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
        points[kept_idx], approach, mass=mass, com=com, cup_radius=cup.radius
    )
    metadata = {
        "suction_model": model,
        "suction_cup": cup.to_dict(),
        "suction_seed": int(seed),
        "suction_num_candidates": int(num_points),
        "suction_num_colliding": int((~keep).sum()),
        "suction_wrench": "gravity -z of the object frame; tau_max = 15.6 * r * pi * sqrt(2)",
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
    )
