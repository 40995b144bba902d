"""Mesh-mesh collision and distance (FCL, typed façade).

Models are built once per mesh (in its own frame) and placed by world poses at query time.
Pose arguments are (4, 4) or (N, 4, 4) float64; when one side has N poses and the other one
pose, the single pose is broadcast. A single pair returns scalars, a batch returns arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.base.core_result import from_core

#: Immutable FCL bounding-volume hierarchy (OBBRSS) of a mesh; share it freely across threads.
CollisionModel = _core.collision.CollisionModel


def _is_single(X_WA: np.ndarray, X_WB: np.ndarray) -> bool:
    return X_WA.ndim == 2 and X_WB.ndim == 2


def collide(
    a: CollisionModel,
    X_WA: npt.ArrayLike,
    b: CollisionModel,
    X_WB: npt.ArrayLike,
    *,
    num_threads: int = 0,
) -> bool | npt.NDArray[np.bool_]:
    """Do the surfaces of A (at ``X_WA``) and B (at ``X_WB``) intersect?

    Returns a bool for one pair of (4, 4) poses, else an (N,) bool array. A mesh entirely inside
    another without touching its surface does not count as a collision.
    """
    xa = np.asarray(X_WA, dtype=np.float64)
    xb = np.asarray(X_WB, dtype=np.float64)
    out = _core.collision.collide(a, xa, b, xb, num_threads)
    return bool(out[0]) if _is_single(xa, xb) else out


@dataclass(frozen=True)
class DistanceResult:
    """Separation of pairs of meshes.

    Attributes:
        distance: (N,) float64 metres, 0 for intersecting pairs.
        points_a: (N, 3) closest point on A, world frame (a contact point when colliding).
        points_b: (N, 3) closest point on B, world frame.
        collide: (N,) bool, True where the pair intersects.
    """

    distance: npt.NDArray[np.float64]
    points_a: npt.NDArray[np.float64]
    points_b: npt.NDArray[np.float64]
    collide: npt.NDArray[np.bool_]


def distance(
    a: CollisionModel,
    X_WA: npt.ArrayLike,
    b: CollisionModel,
    X_WB: npt.ArrayLike,
    *,
    rel_err: float = 0.0,
    abs_err: float = 0.0,
    num_threads: int = 0,
) -> DistanceResult:
    """Minimum distance between A and B with the closest points (always batched arrays)."""
    xa = np.asarray(X_WA, dtype=np.float64)
    xb = np.asarray(X_WB, dtype=np.float64)
    return from_core(
        DistanceResult, _core.collision.distance(a, xa, b, xb, rel_err, abs_err, num_threads)
    )
