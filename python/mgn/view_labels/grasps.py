"""Scene grasp labels (docs/models.md §9; the ``*_grasps`` groups of ``{v}_scene.hdf5``,
docs/format.md).

Typed façade over the C++ ``SceneGraspModel`` (cpp/include/mgn/scene/scene_grasps.hpp, which
documents the model). Built once per scene, reused for every view:

1. Placement: every object-level parallel-jaw grasp becomes a hand (flange) pose and a grasp frame
   at the first contact p1 (x = closing, z = approach); every suction grasp a contact frame
   (z = approach into the surface, origin at the contact) and a tool pose (same axes, origin
   :data:`SUCTION_TOOL_OFFSET` = 13.21 cm behind the contact, MetaGraspNet's convention). World
   frame.
2. Collision, once per scene: the hand (fingers at the pre-grasp opening ``min(w + margin,
   max_opening)``) and the suction tool (cup body of ``cup.outer_radius`` from ``clearance`` to
   ``cup.body_height`` behind the contact, then a shaft of :data:`DEFAULT_SHAFT_RADIUS` x
   :data:`DEFAULT_SHAFT_LENGTH` by default) against every other object and the tote, at the
   grasp and moved back along the approach by each offset (default 0 and 100 mm). The grasped
   object is skipped for the hand at offset 0 only (the object-level sampler checked it there);
   the suction tool is checked against it too. Colliding grasps are kept apart, not dropped.
3. Wrench scores recomputed with the scene's gravity (0, 0, -1) in the world, i.e. R_WO^T g in
   the object frame; analytical and simulation scores are carried over (the suction simulation
   score, docs/models.md §3a, is NaN only for object labels made without it).
4. Per view (:meth:`SceneGraspModel.view_grasps`): a grasp is kept when its object is seen and its
   contact is visible: in front of the camera (z > ``near_plane``), inside the image, and a ray
   from the camera centre meets nothing closer than ``distance - visibility_tolerance``
   (default 2 mm). A parallel-jaw grasp is kept when p1 or p2 = p1 + w v is visible.

Everything here is in metres; the dataset writer converts to centimetres.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.errors import InvalidArgumentError
from mgn.geometry.mesh import Mesh, mass_properties
from mgn.hardware import ParallelJawGripper, SuctionCup
from mgn.objects import tote_mesh
from mgn.pj.labels import PjLabels
from mgn.pj.sampler import core_gripper
from mgn.scene.cameras import CameraView
from mgn.scene.lens import Lens, lens_for
from mgn.scene.scene import Scene
from mgn.suction.labels import CUP_BODY_CLEARANCE, SuctionLabels
from mgn.suction.seal import core_cup

#: Codes of ``colliding_grasps/*/collision_part``: the gripper part that collides first along
#: the approach.
COLLISION_PARTS: dict[int, str] = {1: "palm", 2: "finger", 3: "cup", 4: "shaft"}
#: Codes of ``colliding_grasps/*/collision_obstacle``: floor = the tote where the part reaches
#: below its inner floor surface, wall = the rest of the tote.
COLLISION_OBSTACLES: dict[int, str] = {
    1: "floor",
    2: "wall",
    3: "other object",
    4: "grasped object",
}

__all__ = [
    "COLLISION_OBSTACLES",
    "COLLISION_PARTS",
    "DEFAULT_APPROACH_STEP",
    "DEFAULT_SHAFT_LENGTH",
    "DEFAULT_SHAFT_RADIUS",
    "SUCTION_TOOL_OFFSET",
    "GraspCollisions",
    "GraspGroups",
    "PjGraspSet",
    "PlacedGrasps",
    "SceneGraspModel",
    "SceneGrasps",
    "SuctionGraspSet",
    "ToolCollisions",
]

#: MetaGraspNet's suction tool pose: the contact frame moved back along the approach by 2 cm
#: (cup) + 11.21 cm (tool) = 0.1321 m (the one constant, defined in the C++ core).
SUCTION_TOOL_OFFSET: float = float(_core.scene.SUCTION_TOOL_OFFSET)
#: The C++ defaults (mgn/scene/scene_grasps.hpp): the one place they are written.
_CORE_OPTIONS = _core.scene.SceneGraspOptions()
#: Largest spacing of the tool poses checked along the approach between two offsets, m.
DEFAULT_APPROACH_STEP: float = _CORE_OPTIONS.approach_step
#: Radius of the suction tool shaft behind the cup body, m (a vacuum tube / tool body).
DEFAULT_SHAFT_RADIUS: float = _CORE_OPTIONS.tool.shaft_radius
#: Length of the suction tool shaft behind the cup body, m.
DEFAULT_SHAFT_LENGTH: float = _CORE_OPTIONS.tool.shaft_length
#: A contact is visible when the first hit from the camera is at most this much closer, m.
DEFAULT_VISIBILITY_TOLERANCE: float = _CORE_OPTIONS.visibility_tolerance
#: Contacts closer to the camera plane than this are not visible, m.
DEFAULT_NEAR_PLANE: float = _CORE_OPTIONS.near_plane


@dataclass(frozen=True)
class PjGraspSet:
    """Parallel-jaw grasps of one view and one group (camera frame, metres).

    Attributes:
        franka_poses: (M, 4, 4) hand (flange) poses X_CH.
        contact_poses: (M, 4, 4) grasp frames at the first contact X_CG (x closing, z approach).
        contact_width: (M,) float32 contact width w, m.
        score_analytical, score_simulation, score_wrench: (M,) float32 in [0, 1] (NaN: not
            available).
        object_id: (M,) int32 instance id - 1.
        index: (M,) int64 row in :attr:`SceneGraspModel.pj` (for inspection).
    """

    franka_poses: npt.NDArray[np.float64]
    contact_poses: npt.NDArray[np.float64]
    contact_width: npt.NDArray[np.float32]
    score_analytical: npt.NDArray[np.float32]
    score_simulation: npt.NDArray[np.float32]
    score_wrench: npt.NDArray[np.float32]
    object_id: npt.NDArray[np.int32]
    index: npt.NDArray[np.int64]
    #: (M,) uint8 why each grasp collides (:data:`COLLISION_PARTS`, 0 in the non-colliding group)
    collision_part: npt.NDArray[np.uint8] = field(default_factory=lambda: np.zeros(0, np.uint8))
    #: (M,) uint8 what it hits (:data:`COLLISION_OBSTACLES`)
    collision_obstacle: npt.NDArray[np.uint8] = field(default_factory=lambda: np.zeros(0, np.uint8))

    def __len__(self) -> int:
        return len(self.object_id)


@dataclass(frozen=True)
class SuctionGraspSet:
    """Suction grasps of one view and one group (camera frame, metres).

    Attributes:
        suction_poses: (K, 4, 4) tool poses X_CT: z = approach, origin
            :data:`SUCTION_TOOL_OFFSET` behind the contact (MetaGraspNet: 2 + 11.21 cm).
        contact_poses: (K, 4, 4) contact frames X_CS: z = approach into the surface, origin at
            the contact.
        score_analytical: (K,) float32 seal score; score_simulation: (K,) seal x hold score
            (NaN for object labels without one);
        score_wrench: (K,) float32.
        object_id: (K,) int32 instance id - 1.
        index: (K,) int64 row in :attr:`SceneGraspModel.suction`.
    """

    suction_poses: npt.NDArray[np.float64]
    contact_poses: npt.NDArray[np.float64]
    score_analytical: npt.NDArray[np.float32]
    score_simulation: npt.NDArray[np.float32]
    score_wrench: npt.NDArray[np.float32]
    object_id: npt.NDArray[np.int32]
    index: npt.NDArray[np.int64]
    #: (M,) uint8 why each grasp collides (:data:`COLLISION_PARTS`, 0 in the non-colliding group)
    collision_part: npt.NDArray[np.uint8] = field(default_factory=lambda: np.zeros(0, np.uint8))
    #: (M,) uint8 what it hits (:data:`COLLISION_OBSTACLES`)
    collision_obstacle: npt.NDArray[np.uint8] = field(default_factory=lambda: np.zeros(0, np.uint8))

    def __len__(self) -> int:
        return len(self.object_id)


@dataclass(frozen=True)
class GraspGroups:
    """One docs/format.md group (``non_colliding_grasps`` or ``colliding_grasps``)."""

    paralleljaw: PjGraspSet
    suctioncup: SuctionGraspSet


@dataclass(frozen=True)
class SceneGrasps:
    """The grasp labels of one view, split like docs/format.md's ``{v}_scene.hdf5`` groups."""

    non_colliding: GraspGroups
    colliding: GraspGroups

    def renumbered(self, new_index: npt.ArrayLike) -> SceneGrasps:
        """The same grasps with ``object_id`` mapped through ``new_index`` (old object index ->
        new one; e.g. the view's numbering of the objects it sees,
        :func:`mgn.view_labels.objects.seen_objects`). Every grasp's object must map to
        an index >= 0."""
        m = np.asarray(new_index, np.int64)
        groups = []
        for g in (self.non_colliding, self.colliding):
            ids = [m[s.object_id] for s in (g.paralleljaw, g.suctioncup)]
            if any(np.any(i < 0) for i in ids):
                raise InvalidArgumentError(
                    "SceneGrasps.renumbered: a grasp of an object left out of the numbering"
                )
            groups.append(
                GraspGroups(
                    paralleljaw=dataclasses.replace(
                        g.paralleljaw, object_id=ids[0].astype(np.int32)
                    ),
                    suctioncup=dataclasses.replace(g.suctioncup, object_id=ids[1].astype(np.int32)),
                )
            )
        return SceneGrasps(non_colliding=groups[0], colliding=groups[1])

    def datasets(self) -> dict[str, np.ndarray]:
        """``{hdf5 path: array}`` in metres, e.g.
        ``non_colliding_grasps/paralleljaw/franka_poses_relative_to_camera`` (the writer converts
        lengths to cm and casts to float32). The ``index`` arrays are not included."""
        out: dict[str, np.ndarray] = {}
        for group, g in (
            ("non_colliding_grasps", self.non_colliding),
            ("colliding_grasps", self.colliding),
        ):
            pj, su = g.paralleljaw, g.suctioncup
            base = f"{group}/paralleljaw/"
            out[base + "franka_poses_relative_to_camera"] = pj.franka_poses
            out[base + "contact_poses_relative_to_camera"] = pj.contact_poses
            out[base + "contact_width"] = pj.contact_width
            for name in ("score_analytical", "score_simulation", "score_wrench", "object_id"):
                out[base + name] = getattr(pj, name)
            if group == "colliding_grasps":
                out[base + "collision_part"] = pj.collision_part
                out[base + "collision_obstacle"] = pj.collision_obstacle
            base = f"{group}/suctioncup/"
            out[base + "suction_poses_relative_to_camera"] = su.suction_poses
            out[base + "contact_poses_relative_to_camera"] = su.contact_poses
            for name in ("score_analytical", "score_simulation", "score_wrench", "object_id"):
                out[base + name] = getattr(su, name)
            if group == "colliding_grasps":
                out[base + "collision_part"] = su.collision_part
                out[base + "collision_obstacle"] = su.collision_obstacle
        return out


@dataclass(frozen=True)
class PlacedGrasps:
    """All grasps of one kind placed in the world (objects concatenated in scene order).

    Attributes:
        tool_poses: (M, 4, 4) hand (flange) poses X_WH, or suction tool poses X_WT.
        contact_poses: (M, 4, 4) grasp frames at p1, or suction contact frames.
        contacts: (M, 3) p1, or the suction contact; second_contacts: (M, 3) p1 + w v (suction:
            = contacts).
        width: (M,) contact width (suction: 0).
        score_analytical, score_simulation, score_wrench: (M,) float32 (NaN: not available).
        object_id: (M,) int32 instance id - 1.
        colliding: (M,) bool, the tool collides at some offset.
        hit: (M, K) int32 first obstacle hit on the approach path ending at offset k (k = 0: at
            the first offset): -1 none, 0 the tote, else the instance id of the object hit
            (objects are tried in scene order, then the tote); -2 not checked (the offsets
            after the first colliding one of a model made with ``first_collision_only``).
        collision_part, collision_obstacle: (M,) uint8, why the grasp collides at the first
            colliding pose along the approach (:data:`COLLISION_PARTS`,
            :data:`COLLISION_OBSTACLES`; 0 = does not collide).
    """

    tool_poses: npt.NDArray[np.float64]
    contact_poses: npt.NDArray[np.float64]
    contacts: npt.NDArray[np.float64]
    second_contacts: npt.NDArray[np.float64]
    width: npt.NDArray[np.float32]
    score_analytical: npt.NDArray[np.float32]
    score_simulation: npt.NDArray[np.float32]
    score_wrench: npt.NDArray[np.float32]
    object_id: npt.NDArray[np.int32]
    colliding: npt.NDArray[np.bool_]
    hit: npt.NDArray[np.int32]
    collision_part: npt.NDArray[np.uint8]
    collision_obstacle: npt.NDArray[np.uint8]

    def __len__(self) -> int:
        return len(self.object_id)


@dataclass(frozen=True)
class GraspCollisions:
    """Collision counts of one grasp kind.

    Attributes:
        total: grasps; colliding: grasps colliding at some offset.
        at_offset: {offset m: grasps colliding there} (a model made with
            ``first_collision_only`` counts a grasp at its first colliding offset only).
        by_obstacle: {obstacle: grasps whose first hit (any offset, nearest offset first) is it};
            keys ``"tote"`` and instance ids (int).
    """

    total: int
    colliding: int
    at_offset: dict[float, int]
    by_obstacle: dict[str | int, int]


@dataclass(frozen=True)
class ToolCollisions:
    """Result of :meth:`SceneGraspModel.collides` (one row per queried pose).

    Attributes:
        colliding: (M,) bool, the tool collides at some offset.
        hit: (M, K) int32 first obstacle hit at offset k: -1 none, 0 the tote, else the instance
            id of the object hit (as :attr:`PlacedGrasps.hit`).
    """

    colliding: npt.NDArray[np.bool_]
    hit: npt.NDArray[np.int32]

    def __len__(self) -> int:
        return len(self.colliding)


def _pose_array(poses: np.ndarray) -> np.ndarray:
    return np.asarray(poses, np.float64).reshape(-1, 4, 4)


def _wrench_option(labels: Sequence[PjLabels | None], key: str, default: float) -> float:
    values = {
        float(lab.metadata["pj_wrench"][key])
        for lab in labels
        if lab is not None
        and isinstance(lab.metadata.get("pj_wrench"), dict)
        and key in lab.metadata["pj_wrench"]
    }
    if len(values) > 1:
        raise InvalidArgumentError(
            f"SceneGraspModel: the parallel-jaw labels use different wrench {key} values "
            f"{sorted(values)}; pass {key}= explicitly"
        )
    return values.pop() if values else default


def _object_labels(
    pj: PjLabels | None, suction: SuctionLabels | None
) -> _core.scene.ObjectGraspLabels:
    """The C++ input of one object: its object-level labels (object frame, m; None: none)."""

    def rows(a: npt.ArrayLike | None, dtype: type) -> np.ndarray | None:
        return None if a is None else np.asarray(a, dtype).reshape(-1, 3)

    def column(a: npt.ArrayLike | None) -> np.ndarray | None:
        return None if a is None else np.asarray(a, np.float32).reshape(-1)

    return _core.scene.ObjectGraspLabels(
        pj_p1=rows(None if pj is None else pj.p1, np.float64),
        pj_closing=rows(None if pj is None else pj.closing, np.float64),
        pj_approach=rows(None if pj is None else pj.approach, np.float64),
        pj_width=column(None if pj is None else pj.width),
        pj_score_analytical=column(None if pj is None else pj.quality_score),
        pj_score_simulation=column(None if pj is None else pj.quality_score_simulation),
        suction_points=rows(None if suction is None else suction.points, np.float32),
        suction_approach=rows(None if suction is None else suction.approach, np.float32),
        suction_score_analytical=column(None if suction is None else suction.score),
        suction_score_simulation=column(None if suction is None else suction.simulation),
    )


def _in_lens_image(
    lens: Lens, view: CameraView, points_W: npt.NDArray[np.float64]
) -> npt.NDArray[np.bool_]:
    """(N,) bool: world points (N, 3), m, projecting inside the distorted image of ``view``."""
    X_CW = np.linalg.inv(view.X_WC)
    p = np.asarray(points_W, np.float64).reshape(-1, 3)
    return lens.in_image(p @ X_CW[:3, :3].T + X_CW[:3, 3])


class SceneGraspModel:
    """Scene grasp labels of one scene (see the module docstring).

    Args:
        scene: a :class:`~mgn.scene.Scene`, or ``None`` with ``meshes``/``poses``/... given
            (see :meth:`from_meshes`).
        pj_labels: one entry per instance in scene order: its :class:`~mgn.pj.PjLabels` (object
            frame) or None (no parallel-jaw labels for that object).
        suction_labels: likewise with :class:`~mgn.suction.SuctionLabels` or None.
        gripper, cup: the end effectors the labels were made for (defaults: MetaGraspNet's).
        offsets: distances back along the approach where the tool is checked, m.
        approach_step: largest spacing of the poses checked on the path between consecutive
            offsets, m (the whole approach is checked; docs/models.md §9).
        shaft_radius, shaft_length: the suction tool shaft behind the cup body, m.
        gravity_world: direction of gravity in the world (tote frame).
        friction, grip_force, contact_radius: parallel-jaw wrench constants; default: those in
            the labels' metadata (else 0.5, 70 N, 5 mm).
        visibility_tolerance, near_plane: of the per-view visibility test, m.
        num_threads: C++ threads (0 = all); results do not depend on it.
        first_collision_only: stop checking a grasp at its first colliding pose along the
            approach: ``colliding``, ``collision_part`` and ``collision_obstacle`` are unchanged,
            but ``hit`` of the offsets after the first colliding one is -2 (not checked). The
            dataset files do not store ``hit``; in a cluttered scene this saves about half of the
            collision tests. :meth:`collides` always checks every offset.

    Raises:
        InvalidArgumentError: label lists of the wrong length, a scene without objects, NaN or
            non-rigid poses, non-finite grasps, bad options.
    """

    def __init__(
        self,
        scene: Scene | None,
        pj_labels: Sequence[PjLabels | None],
        suction_labels: Sequence[SuctionLabels | None],
        gripper: ParallelJawGripper | None = None,
        cup: SuctionCup | None = None,
        *,
        offsets: Sequence[float] = tuple(_CORE_OPTIONS.offsets),
        approach_step: float = DEFAULT_APPROACH_STEP,
        shaft_radius: float = DEFAULT_SHAFT_RADIUS,
        shaft_length: float = DEFAULT_SHAFT_LENGTH,
        gravity_world: Sequence[float] = _CORE_OPTIONS.gravity_world,
        friction: float | None = None,
        grip_force: float | None = None,
        contact_radius: float | None = None,
        visibility_tolerance: float = DEFAULT_VISIBILITY_TOLERANCE,
        near_plane: float = DEFAULT_NEAR_PLANE,
        num_threads: int = 0,
        first_collision_only: bool = False,
        _objects: tuple[Any, ...] | None = None,
    ) -> None:
        if _objects is None:
            if scene is None:
                raise InvalidArgumentError("SceneGraspModel: give a scene (or use from_meshes)")
            n = len(scene.instances)
            meshes = [scene.mesh(i) for i in range(n)]
            masses, coms = [], []
            for i, mesh in enumerate(meshes):
                props = mass_properties(mesh, scene.object_spec(i).density)
                masses.append(float(props.mass))
                coms.append(np.asarray(props.center_of_mass, np.float64))
            poses = scene.poses
            tote, X_WT = tote_mesh(scene.tote), np.eye(4)
        else:
            meshes, poses, masses, coms, tote, X_WT = _objects
            n = len(meshes)
        for name, labels in (("pj_labels", pj_labels), ("suction_labels", suction_labels)):
            if len(labels) != n:
                raise InvalidArgumentError(
                    f"SceneGraspModel: {name} has {len(labels)} entries; expected one per "
                    f"scene instance ({n}), None for objects without labels"
                )
        if n == 0:
            raise InvalidArgumentError(
                "SceneGraspModel: the scene has no objects; expected at least one"
            )
        self.gripper = gripper if gripper is not None else ParallelJawGripper()
        self.cup = cup if cup is not None else SuctionCup()
        wrench = _core.grasp.PjWrenchOptions()
        for name, key, given in (
            ("friction", "friction", friction),
            ("grip_force", "grip_force_N", grip_force),
            ("contact_radius", "contact_radius_m", contact_radius),
        ):
            default = float(getattr(wrench, name))
            value = _wrench_option(pj_labels, key, default) if given is None else given
            setattr(wrench, name, float(value))
        try:
            offs = [float(o) for o in offsets]
            gx, gy, gz = (float(g) for g in gravity_world)
        except (TypeError, ValueError) as e:
            raise InvalidArgumentError(
                f"SceneGraspModel: offsets must be distances in m and gravity_world 3 numbers, "
                f"got {offsets!r} and {gravity_world!r}"
            ) from e
        opts = _core.scene.SceneGraspOptions()
        opts.offsets = offs
        opts.approach_step = float(approach_step)
        opts.tool.clearance = CUP_BODY_CLEARANCE
        opts.tool.shaft_radius = float(shaft_radius)
        opts.tool.shaft_length = float(shaft_length)
        opts.gravity_world = (gx, gy, gz)
        opts.pj_wrench = wrench
        opts.visibility_tolerance = float(visibility_tolerance)
        opts.near_plane = float(near_plane)
        opts.num_threads = int(num_threads)
        opts.first_collision_only = bool(first_collision_only)
        opts.validate()
        self._core = _core.scene.SceneGraspModel(
            list(meshes),
            np.asarray(poses, np.float64).reshape(-1, 4, 4),
            [float(m) for m in masses],
            np.asarray(coms, np.float64).reshape(-1, 3),
            [_object_labels(p, s) for p, s in zip(pj_labels, suction_labels, strict=True)],
            tote,
            np.asarray(X_WT, np.float64),
            core_gripper(self.gripper),
            core_cup(self.cup),
            opts,
        )
        self.offsets: tuple[float, ...] = tuple(offs)
        self.pj: PlacedGrasps = self._placed(self._core.pj())
        self.suction: PlacedGrasps = self._placed(self._core.suction())

    @classmethod
    def from_meshes(
        cls,
        meshes: Sequence[Mesh],
        poses: npt.ArrayLike,
        masses: Sequence[float],
        coms: npt.ArrayLike,
        pj_labels: Sequence[PjLabels | None],
        suction_labels: Sequence[SuctionLabels | None],
        tote: Mesh,
        X_WT: npt.ArrayLike | None = None,
        gripper: ParallelJawGripper | None = None,
        cup: SuctionCup | None = None,
        **options: Any,
    ) -> SceneGraspModel:
        """The model for objects given directly: meshes (object frame), (N, 4, 4) poses X_WO,
        masses (kg), (N, 3) centres of mass (object frame), a closed tote mesh at ``X_WT``
        (default identity). Keyword options as in the constructor."""
        X = np.eye(4) if X_WT is None else X_WT
        objects = (list(meshes), poses, list(masses), coms, tote, X)
        return cls(None, pj_labels, suction_labels, gripper, cup, _objects=objects, **options)

    @staticmethod
    def _placed(d: _core.scene.PlacedGraspArrays) -> PlacedGrasps:
        return PlacedGrasps(
            tool_poses=_pose_array(d.tool_poses),
            contact_poses=_pose_array(d.contact_poses),
            contacts=np.asarray(d.contacts, np.float64).reshape(-1, 3),
            second_contacts=np.asarray(d.second_contacts, np.float64).reshape(-1, 3),
            width=d.width,
            score_analytical=d.score_analytical,
            score_simulation=d.score_simulation,
            score_wrench=d.score_wrench,
            object_id=d.object_index,
            colliding=d.colliding,
            hit=d.hit,
            collision_part=np.asarray(d.collision_part, np.uint8),
            collision_obstacle=np.asarray(d.collision_obstacle, np.uint8),
        )

    @property
    def num_objects(self) -> int:
        return int(self._core.num_objects)

    def collisions(self, kind: str = "pj") -> GraspCollisions:
        """Collision counts of ``kind`` (``"pj"`` or ``"suction"``); per-grasp details are in
        ``model.pj.hit`` / ``model.suction.hit``."""
        if kind not in ("pj", "suction"):
            raise InvalidArgumentError(f"collisions: kind must be 'pj' or 'suction', got {kind!r}")
        p = self.pj if kind == "pj" else self.suction
        hit = p.hit.reshape(len(p), len(self.offsets))
        first = np.full(len(p), -1, np.int32)
        for k in range(hit.shape[1] - 1, -1, -1):
            first = np.where(hit[:, k] >= 0, hit[:, k], first)
        ids, counts = np.unique(first[first >= 0], return_counts=True)
        return GraspCollisions(
            total=len(p),
            colliding=int(p.colliding.sum()),
            at_offset={o: int((hit[:, k] >= 0).sum()) for k, o in enumerate(self.offsets)},
            by_obstacle={
                ("tote" if i == 0 else int(i)): int(c) for i, c in zip(ids, counts, strict=True)
            },
        )

    def collides(
        self,
        kind: str,
        contact_poses: npt.ArrayLike,
        width: npt.ArrayLike | None = None,
        target_object: npt.ArrayLike | None = None,
        *,
        check_target_at_grasp: bool = False,
    ) -> ToolCollisions:
        """Collision of arbitrary grasps with exactly the test that made the labels'
        ``colliding`` flags (same tool geometry, offsets and obstacles).

        Args:
            kind: ``"pj"`` or ``"suction"``.
            contact_poses: (M, 4, 4) world poses in the frame of :attr:`PlacedGrasps.contact_poses`:
                parallel-jaw: the grasp frame at the first contact p1 (x = closing, z =
                approach); suction: the contact frame (z = approach into the surface).
            width: (M,) parallel-jaw contact widths, m (fingers checked at the collision opening
                ``min(w + margin, max_opening)``); ignored for suction.
            target_object: (M,) 0-based index of the grasped object, -1 for none (default: all
                -1). Parallel-jaw: skipped at offset 0 exactly, as for the labels, unless
                ``check_target_at_grasp`` (then the hand must not touch it there either).
                Suction: the target is always checked (as for the labels).

        For the label grasps, ``collides(kind, p.contact_poses, p.width, p.object_id)`` equals
        ``p.colliding`` / ``p.hit`` (``p = model.pj`` or ``model.suction``).

        Raises:
            InvalidArgumentError: a bad kind, shapes that do not agree, a non-finite or non-rigid
                pose, a width outside [0, max_opening], a target outside [-1, N).
        """
        if kind not in ("pj", "suction"):
            raise InvalidArgumentError(f"collides: kind must be 'pj' or 'suction', got {kind!r}")
        X = np.asarray(contact_poses, np.float64)
        if X.ndim != 3 or X.shape[1:] != (4, 4):
            raise InvalidArgumentError(
                f"collides: contact_poses must have shape (M, 4, 4), got {X.shape}"
            )
        m = X.shape[0]
        if width is None:
            if kind == "pj":
                raise InvalidArgumentError("collides: parallel-jaw grasps need width (M,) in m")
            w = np.zeros(m)
        else:
            w = np.asarray(width, np.float64).reshape(-1)
        t = (
            np.full(m, -1, np.int32)
            if target_object is None
            else np.asarray(target_object).astype(np.int32).reshape(-1)
        )
        if len(w) != m or len(t) != m:
            raise InvalidArgumentError(
                f"collides: {m} poses but {len(w)} widths and {len(t)} target objects; "
                "expected one of each per pose"
            )
        r = self._core.collides(kind, X, w.tolist(), t.tolist(), bool(check_target_at_grasp))
        return ToolCollisions(
            colliding=np.asarray(r.colliding, bool),
            hit=np.asarray(r.hit, np.int32).reshape(m, len(self.offsets)),
        )

    def visible(self, view: CameraView, points: npt.ArrayLike) -> npt.NDArray[np.bool_]:
        """(N,) bool: whether each world point (N, 3) is visible from ``view`` (a
        :class:`~mgn.scene.cameras.CameraView`)."""
        pts = np.asarray(points, np.float64).reshape(-1, 3)
        lens = lens_for(view.K)
        if lens is None:
            return self._core.visible(view.K.to_core(), view.X_WC, pts)
        # Through a lens: visible from the covering pinhole and inside the distorted image.
        seen = self._core.visible(lens.render_K.to_core(), view.X_WC, pts)
        return np.asarray(seen, bool) & _in_lens_image(lens, view, pts)

    def view_grasps(self, view: CameraView, seen: npt.ArrayLike) -> SceneGrasps:
        """The grasp labels of one view (camera frame, metres). With lens distortion, "inside
        the image" is decided through the lens (:meth:`mgn.scene.lens.Lens.in_image`).

        Args:
            view: a :class:`~mgn.scene.cameras.CameraView` (``.K`` intrinsics, ``.X_WC``).
            seen: (N,) bool, True where instance i+1 has visible pixels in the view.
        """
        s = np.asarray(seen)
        if s.shape != (self.num_objects,):
            raise InvalidArgumentError(
                f"view_grasps: seen must have shape ({self.num_objects},) (one entry per scene "
                f"instance), got {s.shape}"
            )
        lens = lens_for(view.K)
        K = view.K if lens is None else lens.render_K
        r = self._core.view_grasps(K.to_core(), view.X_WC, s.astype(bool))
        pj_idx, su_idx = r.pj_index, r.suction_index
        pj_tool, pj_contact = _pose_array(r.pj_tool), _pose_array(r.pj_contact)
        su_tool, su_contact = _pose_array(r.suction_tool), _pose_array(r.suction_contact)
        if lens is not None:
            # The covering pinhole sees more than the lens: keep a grasp only when a contact
            # that is visible also projects inside the distorted image.
            pin = CameraView(lens.render_K, view.X_WC)
            p1, p2 = self.pj.contacts[pj_idx], self.pj.second_contacts[pj_idx]
            ok = (_in_lens_image(lens, view, p1) & self.visible(pin, p1)) | (
                _in_lens_image(lens, view, p2) & self.visible(pin, p2)
            )
            pj_idx, pj_tool, pj_contact = pj_idx[ok], pj_tool[ok], pj_contact[ok]
            ok = _in_lens_image(lens, view, self.suction.contacts[su_idx])
            su_idx, su_tool, su_contact = su_idx[ok], su_tool[ok], su_contact[ok]
        groups = []
        for want in (False, True):
            m = self.pj.colliding[pj_idx] == want
            i = pj_idx[m]
            pj = PjGraspSet(
                franka_poses=pj_tool[m],
                contact_poses=pj_contact[m],
                contact_width=self.pj.width[i],
                score_analytical=self.pj.score_analytical[i],
                score_simulation=self.pj.score_simulation[i],
                score_wrench=self.pj.score_wrench[i],
                object_id=self.pj.object_id[i],
                index=i.astype(np.int64),
                collision_part=self.pj.collision_part[i],
                collision_obstacle=self.pj.collision_obstacle[i],
            )
            m = self.suction.colliding[su_idx] == want
            i = su_idx[m]
            su = SuctionGraspSet(
                suction_poses=su_tool[m],
                contact_poses=su_contact[m],
                score_analytical=self.suction.score_analytical[i],
                score_simulation=self.suction.score_simulation[i],
                score_wrench=self.suction.score_wrench[i],
                object_id=self.suction.object_id[i],
                index=i.astype(np.int64),
                collision_part=self.suction.collision_part[i],
                collision_obstacle=self.suction.collision_obstacle[i],
            )
            groups.append(GraspGroups(paralleljaw=pj, suctioncup=su))
        return SceneGrasps(non_colliding=groups[0], colliding=groups[1])
