"""Typed façade over the C++ parallel-jaw code (docs/models.md §5): gripper, sampler, wrench.

Frames and units: object frame O, metres. A grasp is MetaGraspNet's [a, v, p1, w]: approach a
(unit, into the object), closing direction v (unit, from p1 towards the second contact, a ⟂ v),
first contact p1 and width w = |p2 - p1|. The hand (flange) pose is X_OH = (R, p1 + (w/2) v -
flange_to_contact a) with R = [v | a x v | a].
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.base.core_result import from_core
from mgn.geometry.mesh import Mesh, load_mesh
from mgn.hardware import ParallelJawGripper

_MESH_FIELDS = ("palm_mesh", "finger_left_mesh", "finger_right_mesh")
#: The C++ defaults (mgn/grasp/antipodal.hpp, mgn/grasp/pj_wrench.hpp): the one place they are
#: written; the keyword defaults below read them.
_ANTIPODAL = _core.grasp.AntipodalOptions()
_PJ_WRENCH = _core.grasp.PjWrenchOptions()


def core_gripper(gripper: ParallelJawGripper) -> _core.grasp.ParallelJawGripper:
    """The C++ gripper for a :class:`~mgn.hardware.ParallelJawGripper` (same field names, SI);
    mesh files of a user gripper are loaded (scaled by ``mesh_scale``)."""
    g = _core.grasp.ParallelJawGripper()
    for f in dataclasses.fields(gripper):
        value = getattr(gripper, f.name)
        if f.name == "mesh_scale":
            continue
        if f.name in _MESH_FIELDS:
            if value is not None:
                setattr(g, f.name, load_mesh(value, scale=gripper.mesh_scale))
            continue
        setattr(g, f.name, np.asarray(value, np.float64) if isinstance(value, tuple) else value)
    g.validate()
    return g


def gripper_meshes(gripper: ParallelJawGripper, opening: float) -> tuple[Mesh, Mesh, Mesh]:
    """(palm, finger_left, finger_right) closed meshes in the hand frame at ``opening`` (m)."""
    return _core.grasp.gripper_meshes(core_gripper(gripper), float(opening))


def hand_poses(
    p1: npt.ArrayLike,
    closing: npt.ArrayLike,
    approach: npt.ArrayLike,
    width: npt.ArrayLike,
    gripper: ParallelJawGripper | None = None,
) -> npt.NDArray[np.float64]:
    """(N, 4, 4) hand (flange) poses X_OH of N grasps given as (N, 3), (N, 3), (N, 3), (N,)."""
    g = core_gripper(gripper if gripper is not None else ParallelJawGripper())
    return _core.grasp.hand_poses(
        np.asarray(p1, np.float64).reshape(-1, 3),
        np.asarray(closing, np.float64).reshape(-1, 3),
        np.asarray(approach, np.float64).reshape(-1, 3),
        np.asarray(width, np.float64).reshape(-1),
        g,
    )


@dataclass(frozen=True)
class AntipodalResult:
    """Grasps sampled at N contact points (object frame, metres).

    Attributes:
        point_score: (N,) analytic score of each point: accepted probes / probes.
        num_kept: (N,) grasps kept per point.
        p1, closing, approach: (M, 3) first contact, unit closing direction, unit approach.
        width: (M,) contact width, m.
        point_index: (M,) row of the source point; probe: (M,) probe that produced the grasp.
        score: (M,) analytic score of the source point.
        num_accepted_probes: accepted probes over all points.
        num_colliding: approaches rejected by the collision check.
    """

    point_score: npt.NDArray[np.float32]
    num_kept: npt.NDArray[np.int32]
    p1: npt.NDArray[np.float64]
    closing: npt.NDArray[np.float64]
    approach: npt.NDArray[np.float64]
    width: npt.NDArray[np.float64]
    point_index: npt.NDArray[np.int64]
    probe: npt.NDArray[np.int32]
    score: npt.NDArray[np.float32]
    num_accepted_probes: int
    num_colliding: int


class AntipodalSampler:
    """Antipodal robust sampler of one object for one gripper (docs/models.md §5); build once.

    Args:
        mesh: the object, metres, object frame; must be watertight (a closed volume).
        gripper: the gripper (default: MetaGraspNet's Franka-like hand).

    Raises:
        InvalidArgumentError: the mesh has no closed volume or the gripper is invalid.
    """

    def __init__(self, mesh: Mesh, gripper: ParallelJawGripper | None = None) -> None:
        self.gripper = gripper if gripper is not None else ParallelJawGripper()
        self._core = _core.grasp.AntipodalSampler(mesh, core_gripper(self.gripper))

    def sample(
        self,
        points: npt.ArrayLike,
        normals: npt.ArrayLike,
        *,
        probes: int = _ANTIPODAL.probes,
        tilt: float = _ANTIPODAL.tilt,
        offset: float = _ANTIPODAL.offset,
        start_offset: float = _ANTIPODAL.start_offset,
        friction_coef: float = _ANTIPODAL.friction_coef,
        approaches_tried: int = _ANTIPODAL.approaches_tried,
        approaches_kept: int = _ANTIPODAL.approaches_kept,
        check_collision: bool = _ANTIPODAL.check_collision,
        seed: int = _ANTIPODAL.seed,
        first_index: int = _ANTIPODAL.first_index,
        num_threads: int = _ANTIPODAL.num_threads,
    ) -> AntipodalResult:
        """Sample grasps at N contact points ((N, 3) on the surface, outward normals (N, 3)).

        Each point gets ``probes`` probes: the inward normal tilted by Euler angles in
        (-tilt, tilt) rad, the start moved by up to ``offset`` m per axis and placed
        ``start_offset`` m outside; the ray's first two hits are accepted as a grasp if closer
        than the maximum opening and inside the friction cone (half-angle atan(friction_coef)).
        Up to ``approaches_tried`` random approach directions are tried per accepted probe, the
        first ``approaches_kept`` collision-free ones are kept. Point i draws from the random
        stream (``seed``, ``first_index`` + i): any thread count or batching gives the same result.
        """
        o = _core.grasp.AntipodalOptions()
        o.probes = int(probes)
        o.tilt = float(tilt)
        o.offset = float(offset)
        o.start_offset = float(start_offset)
        o.friction_coef = float(friction_coef)
        o.approaches_tried = int(approaches_tried)
        o.approaches_kept = int(approaches_kept)
        o.check_collision = bool(check_collision)
        o.seed = int(seed)
        o.first_index = int(first_index)
        o.num_threads = int(num_threads)
        return from_core(AntipodalResult, self._core.sample(points, normals, o))

    def collides(self, X_OH: npt.ArrayLike, opening: float) -> bool:
        """Whether the gripper at hand pose ``X_OH`` (4, 4), opened at ``opening`` m, intersects
        the object (surface contact, or a part entirely inside it)."""
        return bool(self._core.collides(np.asarray(X_OH, np.float64), float(opening)))


def pj_wrench_scores(
    p1: npt.ArrayLike,
    closing: npt.ArrayLike,
    width: npt.ArrayLike,
    *,
    mass: float,
    com: npt.ArrayLike,
    gravity_direction: npt.ArrayLike = (0.0, 0.0, -1.0),
    friction: float = _PJ_WRENCH.friction,
    grip_force: float = _PJ_WRENCH.grip_force,
    contact_radius: float = _PJ_WRENCH.contact_radius,
    gravity: float = _PJ_WRENCH.gravity,
) -> npt.NDArray[np.float32]:
    """Soft-finger wrench score in [0, 1] of each grasp (see ``mgn/grasp/pj_wrench.hpp``).

    Each finger presses with ``grip_force`` N on a soft contact of radius ``contact_radius`` m
    with friction ``friction``; elliptic limit surface (f_t/(mu f))^2 + (tau/(gamma f))^2 <= 1,
    gamma = (2/3) mu r; the gravity load (``mass`` kg at ``com``) is shared by the two fingers;
    score = min(1, 1/u) with u the utilisation. All vectors in one frame.
    """
    return _core.grasp.pj_wrench_scores(
        np.asarray(p1, np.float64).reshape(-1, 3),
        np.asarray(closing, np.float64).reshape(-1, 3),
        np.asarray(width, np.float64).reshape(-1),
        float(mass),
        np.asarray(com, np.float64),
        np.asarray(gravity_direction, np.float64),
        _wrench_options(friction, grip_force, contact_radius, gravity),
    )


def _wrench_options(
    friction: float = _PJ_WRENCH.friction,
    grip_force: float = _PJ_WRENCH.grip_force,
    contact_radius: float = _PJ_WRENCH.contact_radius,
    gravity: float = _PJ_WRENCH.gravity,
) -> _core.grasp.PjWrenchOptions:
    """The C++ constants of the parallel-jaw wrench score (mu, N, m, m/s^2), range-checked."""
    o = _core.grasp.PjWrenchOptions()
    o.friction = float(friction)
    o.grip_force = float(grip_force)
    o.contact_radius = float(contact_radius)
    o.gravity = float(gravity)
    o.validate()
    return o
