"""A dropped scene: which objects lie where in the tote, serialisable to JSON.

A :class:`Scene` holds everything needed to re-render or re-label a scene without simulating
again: the object instances (name, where the object comes from, settled pose ``X_WO``, tote
contacts), the tote, the seed and the drop options. Frames: the world W is the tote frame
(origin at the centre of the inner floor top, z up; see :mod:`mgn.objects.tote`); ``X_WO`` maps
object-frame coordinates to world coordinates (4x4 float64, metres).

JSON layout (``schema_version`` 1; the file is written and read by :mod:`mgn.io.scene_json`)::

    {"schema_version": 1, "seed": 0,
     "tote": {ToteSpec fields}, "drop_options": {DropOptions fields},
     "instances": [{"instance_id": 1, "name": "mug", "category_id": 12, "source": "builtin",
                    "X_WO": [[...4 rows...]], "contacts": ["floor", "-x"], "settled": true}],
     "removed": [{"name": "pear", "source": "builtin", "reason": "left_tote"}],
     "stats": {"steps": 412, "simulated_time": 1.716, "settled": true, "max_penetration": 1e-4}}

``source`` is ``"builtin"`` for the built-in library, ``random-shapes:...`` for a pool of
random shapes (:func:`mgn.objects.random_shapes.random_shape_source`), else the path of the
user-objects YAML file the object was read from (see :func:`mgn.objects.load_objects_yaml`).
"""

from __future__ import annotations

import dataclasses
import functools
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.base.core_result import to_core
from mgn.errors import InvalidArgumentError
from mgn.geometry.mesh import Mesh
from mgn.objects import ObjectSpec, ToteSpec, get_object, load_objects_yaml
from mgn.objects.random_shapes import RANDOM_SOURCE_PREFIX, random_shapes_from_source

__all__ = [
    "BUILTIN",
    "CONTACT_NAMES",
    "DropOptions",
    "RemovedInstance",
    "Scene",
    "SceneInstance",
    "resolve_object",
]

SCHEMA_VERSION = 1
#: ``source`` of the built-in objects.
BUILTIN = "builtin"
#: Tote surfaces an object can touch, in the order of the C++ ToteContact bits.
CONTACT_NAMES: tuple[str, ...] = ("-x", "+x", "-y", "+y", "floor")
_WALLS = frozenset(CONTACT_NAMES[:4])


#: The C++ defaults (mgn/scene/drop.hpp): the one place DropOptions' defaults are written.
_CORE = _core.scene.DropOptions()


def _checked_type(name: str, kind: type, value: Any) -> Any:
    """DropOptions.<name> as a ``kind`` (bool, int or float); ranges are the C++ core's."""
    if kind is bool:
        if not isinstance(value, (bool, np.bool_)):
            raise InvalidArgumentError(f"DropOptions.{name} must be true or false, got {value!r}")
        return bool(value)
    if isinstance(value, (bool, np.bool_)):
        raise InvalidArgumentError(f"DropOptions.{name} must be a number, got {value!r}")
    if kind is int:
        if not isinstance(value, (int, np.integer)):
            raise InvalidArgumentError(f"DropOptions.{name} must be an integer, got {value!r}")
        return int(value)
    if not isinstance(value, (int, float, np.integer, np.floating)):
        raise InvalidArgumentError(f"DropOptions.{name} must be a number, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class DropOptions:
    """Simulation options of the drop (SI units; see cpp/include/mgn/scene/drop.hpp).

    Attributes:
        window_min, window_max: release window in the tote frame, m (MetaGraspNet: x +-60 mm,
            y +-30 mm, z 0.3-0.8 m above the floor).
        dt: fixed time step, s. solver_iterations: Bullet solver iterations.
        max_time: simulated seconds at most (MetaGraspNet: 7 s).
        linear_rest, angular_rest, rest_time: an object is at rest below these speeds (m/s,
            rad/s) held for rest_time seconds.
        gravity: m/s^2. rolling_friction, angular_damping: of the objects.
        tote_friction, tote_restitution: of the tote.
        collision_margin: Bullet margin, m. contact_distance: touching distance for the tote
            contacts, m.
        remove_unsettled: drop objects still moving at max_time.
        tote_collision: ``"boxes"`` (five static boxes fitted to the cavity, robust) or
            ``"mesh"`` (the tote's triangle mesh).
        max_hull_vertices: each convex part's Bullet hull keeps at most this many vertices (0:
            all, else >= 8); the reduced hull contains the part (cut from its face planes).
        hull_tolerance: stop reducing a hull once it protrudes at most this far beyond the
            part, m (>= 0).
        polyhedral_contacts: whole contact patches from Bullet's polyhedral clipping (piles
            settle sooner) instead of one GJK point per step.
        resettle_time: after objects on or over the rim are removed, the rest may take this many
            more simulated seconds (beyond max_time) to settle again (>= 0).
        two_friction_directions: friction along two tangent directions per contact (default;
            with one, resting objects creep along the other tangent and large piles settle
            ~2x later or not at all; with two, a symmetric resting contact may drift to one
            side).
        guard_height: while the objects fall and pile up, the walls reach this far above the
            rim (m, >= 0; collision only), so objects bouncing off the pile stay in; then they
            are lowered to the rim and the pile settles again (resettle_time). 0: none.
    """

    window_min: tuple[float, float, float] = _CORE.window_min
    window_max: tuple[float, float, float] = _CORE.window_max
    dt: float = _CORE.dt
    solver_iterations: int = _CORE.solver_iterations
    max_time: float = _CORE.max_time
    linear_rest: float = _CORE.linear_rest
    angular_rest: float = _CORE.angular_rest
    rest_time: float = _CORE.rest_time
    gravity: float = _CORE.gravity
    rolling_friction: float = _CORE.rolling_friction
    angular_damping: float = _CORE.angular_damping
    tote_friction: float = _CORE.tote_friction
    tote_restitution: float = _CORE.tote_restitution
    collision_margin: float = _CORE.collision_margin
    contact_distance: float = _CORE.contact_distance
    remove_unsettled: bool = _CORE.remove_unsettled
    tote_collision: str = _CORE.tote_collision
    max_hull_vertices: int = _CORE.max_hull_vertices
    hull_tolerance: float = _CORE.hull_tolerance
    polyhedral_contacts: bool = _CORE.polyhedral_contacts
    resettle_time: float = _CORE.resettle_time
    two_friction_directions: bool = _CORE.two_friction_directions
    guard_height: float = _CORE.guard_height

    def __post_init__(self) -> None:
        """Python types here (the fields are plain numbers afterwards); ranges in C++
        (``mgn::validate(const DropOptions&)``), which names the field."""
        for name in ("window_min", "window_max"):
            raw = getattr(self, name)
            try:
                value = tuple(float(v) for v in raw)
            except (TypeError, ValueError) as e:
                raise InvalidArgumentError(
                    f"DropOptions.{name} must be 3 numbers, got {raw!r}"
                ) from e
            if len(value) != 3:
                raise InvalidArgumentError(f"DropOptions.{name} must be 3 numbers, got {raw}")
            object.__setattr__(self, name, value)
        if not isinstance(self.tote_collision, str):
            raise InvalidArgumentError(
                f"DropOptions.tote_collision must be 'boxes' or 'mesh', got {self.tote_collision!r}"
            )
        kinds = {"bool": bool, "int": int, "float": float}
        for f in dataclasses.fields(self):
            kind = kinds.get(str(f.type))
            if kind is not None:
                object.__setattr__(self, f.name, _checked_type(f.name, kind, getattr(self, f.name)))
        self.to_core().validate()

    def to_core(self, seed: int = 0) -> _core.scene.DropOptions:
        """The C++ options (``seed`` is :func:`mgn.scene.drop_scene`'s own argument)."""
        o = to_core(self, _core.scene.DropOptions())
        o.seed = int(seed)
        return o

    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["window_min"] = list(self.window_min)
        d["window_max"] = list(self.window_max)
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> DropOptions:
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(d) - known)
        if unknown:
            raise InvalidArgumentError(f"DropOptions: unknown key(s) {unknown}")
        return cls(**d)


@dataclass(frozen=True)
class SceneInstance:
    """One object lying in the tote.

    Attributes:
        instance_id: 1..N, contiguous in the scene (the id used in masks and labels).
        name: object name (built-in library name or user-object name).
        category_id: the object's category id.
        source: ``"builtin"`` or the path of the user-objects YAML file.
        X_WO: (4, 4) float64 settled pose of the object frame in the tote frame.
        contacts: tote surfaces touched after settling, a subset of :data:`CONTACT_NAMES`.
        settled: at rest when the simulation stopped.
    """

    instance_id: int
    name: str
    category_id: int
    source: str
    X_WO: npt.NDArray[np.float64] = field(compare=False)
    contacts: tuple[str, ...] = ()
    settled: bool = True

    def __post_init__(self) -> None:
        X = np.array(self.X_WO, dtype=np.float64)
        if X.shape != (4, 4) or not np.all(np.isfinite(X)):
            raise InvalidArgumentError(
                f"SceneInstance {self.instance_id} ('{self.name}'): X_WO must be a finite 4x4 "
                f"matrix, got shape {X.shape}"
            )
        X.setflags(write=False)
        object.__setattr__(self, "X_WO", X)
        bad = set(self.contacts) - set(CONTACT_NAMES)
        if bad:
            raise InvalidArgumentError(
                f"SceneInstance {self.instance_id}: unknown contacts {sorted(bad)}; "
                f"valid: {list(CONTACT_NAMES)}"
            )
        object.__setattr__(self, "contacts", tuple(c for c in CONTACT_NAMES if c in self.contacts))

    @property
    def bin_relation(self) -> str:
        """``"no_rel"``, ``"edge"`` (touches one tote wall) or ``"corner"`` (two or more)."""
        walls = len(_WALLS.intersection(self.contacts))
        return "no_rel" if walls == 0 else ("edge" if walls == 1 else "corner")


@dataclass(frozen=True)
class RemovedInstance:
    """An object that was dropped but is not in the scene (``reason``: left_tote, not_settled)."""

    name: str
    source: str
    reason: str


@functools.lru_cache(maxsize=32)
def _user_catalogue(path: str) -> dict[str, ObjectSpec]:
    # The loader's warnings about the objects (size, missing files) were given where the
    # catalogue was read (mgn generate, mgn config check); a scene does not repeat them.
    return {s.name: s for s in load_objects_yaml(path, notes=[])}


def resolve_object(name: str, source: str) -> ObjectSpec:
    """The :class:`ObjectSpec` named ``name`` from ``source`` (``"builtin"``, a YAML path, or
    a pool of random shapes: :func:`mgn.objects.random_shapes.random_shape_source`)."""
    if source == BUILTIN:
        return get_object(name)
    if source.startswith(RANDOM_SOURCE_PREFIX):
        pool = {s.name: s for s in random_shapes_from_source(source)}
        if name not in pool:
            raise InvalidArgumentError(f"object '{name}' not found in '{source}'")
        return pool[name]
    catalogue = _user_catalogue(os.fspath(Path(source).resolve()))
    if name not in catalogue:
        raise InvalidArgumentError(
            f"object '{name}' not found in '{source}'; it holds {sorted(catalogue)}"
        )
    return catalogue[name]


@dataclass(frozen=True)
class Scene:
    """Objects settled in a tote (see the module doc for the JSON layout).

    Attributes:
        instances: the objects in the tote, instance ids 1..N in order.
        tote: the tote's dimensions.
        seed: the seed the scene was dropped with.
        drop_options: the simulation options used.
        removed: objects that were dropped but left the tote (or did not settle).
        stats: steps, simulated_time (s), settled (bool), max_penetration (m, of the render
            meshes: deepest point of one object's surface inside another object or the tote),
            max_penetration_hulls (m, of the simulated hulls), max_float_gap (m, of the render
            meshes: the largest clearance of an object to its nearest body, tote or object),
            separation_rounds (rounds of the drop's final separation pass that moved objects,
            :func:`mgn.scene.drop.separate_overlaps`), separation_max_move (m, the farthest it
            moved an object), num_dropped.
    """

    instances: tuple[SceneInstance, ...]
    tote: ToteSpec
    seed: int
    drop_options: DropOptions = DropOptions()
    removed: tuple[RemovedInstance, ...] = ()
    stats: dict[str, Any] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "instances", tuple(self.instances))
        object.__setattr__(self, "removed", tuple(self.removed))
        ids = [i.instance_id for i in self.instances]
        if ids != list(range(1, len(ids) + 1)):
            raise InvalidArgumentError(f"Scene: instance ids must be 1..N in order, got {ids}")

    def __len__(self) -> int:
        return len(self.instances)

    @property
    def poses(self) -> npt.NDArray[np.float64]:
        """(N, 4, 4) X_WO of every instance."""
        if not self.instances:
            return np.zeros((0, 4, 4))
        return np.stack([i.X_WO for i in self.instances])

    def object_spec(self, index: int) -> ObjectSpec:
        """The :class:`ObjectSpec` of instance ``index`` (0-based position in ``instances``)."""
        inst = self.instances[index]
        return resolve_object(inst.name, inst.source)

    def mesh(self, index: int) -> Mesh:
        """The :data:`mgn.Mesh` of instance ``index`` in its object frame (with its material)."""

        return self.object_spec(index).to_mesh()

    def render_items(self) -> list[tuple[Mesh, npt.NDArray[np.float64], int]]:
        """(mesh, X_WO, instance id) per instance, as :func:`mgn.render_views` takes them;
        copies of an object share one Mesh (so a renderer uploads it once)."""
        meshes: dict[tuple[str, str], Mesh] = {}
        items = []
        for i, inst in enumerate(self.instances):
            key = (inst.name, inst.source)
            if key not in meshes:
                meshes[key] = self.mesh(i)
            items.append((meshes[key], inst.X_WO, inst.instance_id))
        return items

    def world_mesh(self, index: int) -> Mesh:
        """The mesh of instance ``index`` placed at its pose (tote frame)."""
        return self.mesh(index).transformed(self.instances[index].X_WO)

    # ------------------------------------------------------------------ JSON

    def to_dict(self) -> dict[str, Any]:
        tote = dataclasses.asdict(self.tote)
        tote["color"] = list(self.tote.color)
        if tote["walls"]:
            del tote["walls"]  # a tote (the default); "walls": false marks a table top
        return {
            "schema_version": SCHEMA_VERSION,
            "seed": int(self.seed),
            "tote": tote,
            "drop_options": self.drop_options.to_dict(),
            "instances": [
                {
                    "instance_id": i.instance_id,
                    "name": i.name,
                    "category_id": i.category_id,
                    "source": i.source,
                    "X_WO": i.X_WO.tolist(),
                    "contacts": list(i.contacts),
                    "settled": i.settled,
                }
                for i in self.instances
            ],
            "removed": [dataclasses.asdict(r) for r in self.removed],
            "stats": dict(self.stats),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Scene:
        if not isinstance(d, dict):
            raise InvalidArgumentError(f"Scene: expected a JSON object, got {type(d).__name__}")
        version = d.get("schema_version")
        if version != SCHEMA_VERSION:
            raise InvalidArgumentError(
                f"Scene: unsupported schema_version {version!r}, expected {SCHEMA_VERSION}"
            )
        try:
            tote = dict(d["tote"])
            tote["color"] = tuple(tote.get("color", ToteSpec().color))
            return cls(
                instances=tuple(
                    SceneInstance(
                        instance_id=int(i["instance_id"]),
                        name=str(i["name"]),
                        category_id=int(i["category_id"]),
                        source=str(i["source"]),
                        X_WO=np.asarray(i["X_WO"], dtype=np.float64),
                        contacts=tuple(i.get("contacts", ())),
                        settled=bool(i.get("settled", True)),
                    )
                    for i in d["instances"]
                ),
                tote=ToteSpec(**tote),
                seed=int(d["seed"]),
                drop_options=DropOptions.from_dict(d.get("drop_options", {})),
                removed=tuple(RemovedInstance(**r) for r in d.get("removed", ())),
                stats=dict(d.get("stats", {})),
            )
        except (KeyError, TypeError) as e:
            raise InvalidArgumentError(
                f"Scene: malformed scene data ({type(e).__name__}: {e})"
            ) from e
