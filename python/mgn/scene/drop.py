"""Drop objects into the tote with Bullet (C++ core) and return the settled :class:`Scene`."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.errors import InvalidArgumentError
from mgn.geometry.convex import (
    DROP_DECOMPOSITION,
    ConvexDecompositionOptions,
    cached_convex_decomposition,
)
from mgn.geometry.mesh import Mesh, mass_properties
from mgn.objects import ObjectSpec, ToteSpec, builtin_objects, tote_mesh
from mgn.objects.random_shapes import RANDOM_SOURCE_PREFIX
from mgn.scene.penetration import (
    EDGE_SPACING,
    MeshCache,
    Overlap,
    OverlapSweep,
    clearance,
    deepest_overlap,
    float_gaps,
    mesh_overlaps,
    render_penetration,
    tote_depth,
)
from mgn.scene.scene import (
    BUILTIN,
    CONTACT_NAMES,
    DropOptions,
    RemovedInstance,
    Scene,
    SceneInstance,
)

__all__ = [
    "RESTITUTION",
    "SEPARATION_ROUNDS",
    "SEPARATION_SPACING",
    "SEPARATION_THRESHOLD",
    "drop_scene",
    "drop_scene_refilled",
    "separate_overlaps",
    "settle",
    "settle_tracked",
]

#: Restitution of the objects (the library carries friction but not restitution).
RESTITUTION = 0.1
_STATUS = {0: "kept", 1: "left_tote", 2: "not_settled"}

#: The final separation pass acts on resting objects whose render meshes sink deeper than this
#: into each other (m), as found with surface points :data:`SEPARATION_SPACING` apart: see
#: :func:`drop_scene`.
SEPARATION_THRESHOLD = 3e-4
#: Largest distance (m) between the points tested along a mesh edge by the separation pass (the
#: depths it sees are short of the exact ones by at most half of it).
SEPARATION_SPACING = 1e-3
#: Rounds of the final separation pass at most (measure, pull the pairs apart, lower).
SEPARATION_ROUNDS = 8
# How far beyond the least separating distance a pair is pulled apart (m), and the farthest
# one object is moved to separate a pair (m): sideways, and straight up (an object hooked
# through another, two cable coils, is lifted onto the strand it hooked); objects then
# floating more than _LOWER_ABOVE (m) are lowered until within _LOWER_TO (m) of what is below
# them, _LOWER_MOVES moves each at most.
_SEPARATION_MARGIN = 1e-4
_SEPARATION_REACH = 5e-3
_LIFT_REACH = 1.5e-2
_LOWER_ABOVE = 1e-4
_LOWER_TO = 2e-5
_LOWER_MOVES = 60


@dataclasses.dataclass
class _Pile:
    """The simulated pile, one row per object (the C++ result, merged over the settles of the
    separation pass)."""

    X_WO: np.ndarray  # (N, 4, 4) m
    status: np.ndarray  # (N,) 0 kept, 1 left the tote, 2 not settled
    settled: np.ndarray  # (N,) bool
    contacts: np.ndarray  # (N,) uint32 tote contact bits
    steps: int
    simulated_time: float
    all_settled: bool
    max_penetration_hulls: float
    separation_rounds: int = 0
    separation_max_move: float = 0.0

    @classmethod
    def of(cls, out: _core.scene.DropResult) -> _Pile:
        return cls(
            np.array(out.X_WO, np.float64),
            np.array(out.status, np.int64),
            np.array(out.object_settled, bool),
            np.array(out.contacts, np.uint32),
            int(out.steps),
            float(out.simulated_time),
            bool(out.settled),
            float(out.max_penetration),
        )


def _source_of(spec: ObjectSpec, sources: dict[str, str]) -> str:
    if spec.name in sources:
        return sources[spec.name]
    for b in builtin_objects():
        if b.name == spec.name:
            if b == spec:
                return BUILTIN
            break
    raise InvalidArgumentError(
        f"drop_scene: object '{spec.name}' is not a built-in object; pass "
        f"sources={{'{spec.name}': 'path/to/objects.yaml'}} so the scene can find it again"
    )


def _simulate(
    objects: Sequence[ObjectSpec],
    seed: int,
    tote: ToteSpec,
    options: DropOptions,
    sources: Mapping[str, str | os.PathLike[str]] | None,
    decomposition: ConvexDecompositionOptions | None,
    use_cache: bool,
    X_WO_start: np.ndarray | None = None,
) -> tuple[_core.scene.DropResult, dict[str, str], dict[str, Mesh]]:
    """Validates, prepares the per-object physics and runs the C++ drop. Returns the C++ result
    (X_WO, X_WO_release, status, object_settled, contacts, steps, ...), each name's source and
    mesh."""
    if len(objects) == 0:
        raise InvalidArgumentError("drop_scene: expected at least one object, got none")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidArgumentError(f"drop_scene: seed must be an integer >= 0, got {seed!r}")
    src = {
        k: os.fspath(v)
        if os.fspath(v).startswith(RANDOM_SOURCE_PREFIX)
        else os.fspath(Path(v).resolve())
        for k, v in (sources or {}).items()
    }
    per_name: dict[str, tuple[Any, ...]] = {}
    for spec in objects:
        if not isinstance(spec, ObjectSpec):
            raise InvalidArgumentError(
                f"drop_scene: objects must be ObjectSpec, got {type(spec).__name__}"
            )
        if spec.name in per_name:
            continue
        mesh = spec.to_mesh()
        props = mass_properties(mesh, spec.density)
        parts = cached_convex_decomposition(
            mesh, decomposition or DROP_DECOMPOSITION, use_cache=use_cache
        )
        per_name[spec.name] = (parts, props, _source_of(spec, src), mesh)

    all_parts = [per_name[s.name][0] for s in objects]
    all_props = [per_name[s.name][1] for s in objects]
    out = _core.scene.drop_objects(
        all_parts,
        [p.mass for p in all_props],
        np.array([np.asarray(p.center_of_mass) for p in all_props], np.float64),
        np.array([np.asarray(p.inertia).reshape(9) for p in all_props], np.float64),
        [float(s.friction) for s in objects],
        [RESTITUTION] * len(objects),
        [s.name for s in objects],
        tote_mesh(tote),
        [
            tote.inner_length,
            tote.inner_width,
            tote.inner_height,
            tote.wall_thickness,
            tote.floor_thickness,
            1.0 if tote.walls else 0.0,
        ],
        options.to_core(int(seed)),
        None if X_WO_start is None else np.asarray(X_WO_start, np.float64).reshape(-1, 16),
    )
    return out, {k: v[2] for k, v in per_name.items()}, {k: v[3] for k, v in per_name.items()}


def _stats(
    pile: _Pile,
    instances: Sequence[SceneInstance],
    meshes: dict[str, Mesh],
    tote: ToteSpec,
    num_dropped: int,
) -> dict[str, Any]:
    """Scene stats; ``max_penetration`` and ``max_float_gap`` are measured on the render meshes
    of the kept objects (:func:`mgn.scene.penetration.render_penetration`,
    :func:`mgn.scene.penetration.float_gaps`), ``max_penetration_hulls`` is Bullet's on the
    simulated hulls (of the last settle)."""
    kept = [meshes[i.name] for i in instances]
    poses = [i.X_WO for i in instances]
    gaps = float_gaps(kept, poses, tote)
    return {
        "steps": pile.steps,
        "simulated_time": pile.simulated_time,
        "settled": pile.all_settled,
        "max_penetration": render_penetration(kept, poses, tote),
        "max_penetration_hulls": pile.max_penetration_hulls,
        "max_float_gap": float(gaps.max()) if len(gaps) else 0.0,
        "separation_rounds": pile.separation_rounds,
        "separation_max_move": pile.separation_max_move,
        "num_dropped": num_dropped,
    }


def _out_of_tote(mesh: Mesh, X: np.ndarray, tote: ToteSpec) -> None:
    """Moves ``X`` (in place) by the least that takes ``mesh`` out of the floor and the inner
    walls below the rim (exact: planes)."""
    w = np.asarray(mesh.vertices, np.float64) @ X[:3, :3].T + X[:3, 3]
    X[2, 3] += max(0.0, float(-w[:, 2].min()))
    low = w[w[:, 2] <= tote.inner_height]
    if len(low) and tote.walls:
        for axis, half in ((0, 0.5 * tote.inner_length), (1, 0.5 * tote.inner_width)):
            X[axis, 3] -= max(0.0, float(low[:, axis].max()) - half)
            X[axis, 3] += max(0.0, -half - float(low[:, axis].min()))


def _pull_apart(
    meshes: Sequence[Mesh],
    poses: np.ndarray,
    overlap: Overlap,
    tote: ToteSpec,
    cache: MeshCache,
) -> int | None:
    """Moves one object of an overlapping pair (``poses`` in place) the least distance along a
    direction that separates their render meshes (:func:`meshes_overlap` at
    :data:`EDGE_SPACING`, then :data:`_SEPARATION_MARGIN` more). Directions in order: the way
    out of the deepest point (``exit - point``) for the object it lifts, the opposite way for
    the other, straight up for the higher object (lowest vertex), straight up for the lower
    one. "Sunk": how deep the moved object then lies in the tote or any third object. The
    first move no longer than :data:`_SEPARATION_REACH` that sinks it no deeper than
    :data:`SEPARATION_THRESHOLD` wins; else the short move that sinks it least, if less than
    this pair's depth (progress, the next round goes on); else the first clean move (a lift up
    to :data:`_LIFT_REACH`); else the least sinking move. ``cache``: the pass's per-mesh data.
    No move farther than :data:`_SEPARATION_REACH` (straight up: :data:`_LIFT_REACH`) is made.
    Returns the index of the object moved (None: none)."""
    way = overlap.exit - overlap.point
    way = way / max(float(np.linalg.norm(way)), 1e-12)
    a, b = (overlap.a, overlap.b) if way[2] >= 0 else (overlap.b, overlap.a)
    way = way if way[2] >= 0 else -way
    lowest = [
        float((np.asarray(meshes[k].vertices, np.float64) @ poses[k, :3, :3].T)[:, 2].min())
        + poses[k, 2, 3]
        for k in (overlap.a, overlap.b)
    ]
    high, low = (overlap.a, overlap.b) if lowest[0] >= lowest[1] else (overlap.b, overlap.a)
    up = np.array([0.0, 0.0, 1.0])
    options = ((a, b, way), (b, a, -way), (high, low, up), (low, high, up))
    moves: list[tuple[float, float, int, np.ndarray]] = []  # (sunk, distance, mover, X)
    for mover, other, direction in options:
        reach = _LIFT_REACH if direction is up else _SEPARATION_REACH
        X = _separating_move(
            meshes[mover],
            poses[mover],
            meshes[other],
            poses[other],
            direction,
            overlap.depth,
            reach,
            cache,
        )
        if X is None:
            continue
        sunk = _sunk(meshes, poses, mover, X, other, tote, cache)
        distance = float(np.linalg.norm(X[:3, 3] - poses[mover, :3, 3]))
        moves.append((sunk, distance, mover, X))
        if sunk <= SEPARATION_THRESHOLD and distance <= _SEPARATION_REACH:
            break
    if not moves:
        return None
    # Clean and short; else short and making progress (sinks the mover less deep than this
    # pair overlapped); else clean (a long lift); else the least sinking (the first of equals).
    short = [m for m in moves if m[1] <= _SEPARATION_REACH]
    clean = [m for m in moves if m[0] <= SEPARATION_THRESHOLD]
    progress = [m for m in short if m[0] < overlap.depth]
    pick = (
        [m for m in short if m[0] <= SEPARATION_THRESHOLD]
        or sorted(progress, key=lambda m: m[0])[:1]
        or clean
        or sorted(moves, key=lambda m: m[0])[:1]
    )
    best = (pick[0][0], pick[0][2], pick[0][3])
    poses[best[1]] = best[2]
    return best[1]


def _sunk(
    meshes: Sequence[Mesh],
    poses: np.ndarray,
    k: int,
    X: np.ndarray,
    skip: int,
    tote: ToteSpec,
    cache: MeshCache,
) -> float:
    """How deep (m) object ``k`` at ``X`` sinks into the tote or any object but ``skip`` (the
    pass's measure: surface points :data:`SEPARATION_SPACING` apart, FCL depths)."""
    sunk = tote_depth(meshes[k], X, tote)
    others = [j for j in range(len(meshes)) if j not in (k, skip)]
    deepest = deepest_overlap(
        [meshes[k]] + [meshes[j] for j in others],
        [X] + [poses[j] for j in others],
        spacing=SEPARATION_SPACING,
        exact=False,
        cache=cache,
        involving=0,
    )
    return max(sunk, deepest)


def _separating_move(
    mesh: Mesh,
    X: np.ndarray,
    other: Mesh,
    Y: np.ndarray,
    direction: np.ndarray,
    guess: float,
    reach: float,
    cache: MeshCache,
) -> np.ndarray | None:
    """``X`` moved along the unit ``direction`` by the least distance after which ``mesh`` no
    longer overlaps ``other`` at ``Y`` (:func:`meshes_overlap`, evaluated by one
    :class:`OverlapSweep`; doubling from ``guess`` (m), then halvings), plus
    :data:`_SEPARATION_MARGIN`; None if that is farther than ``reach`` (m)."""

    sweep = OverlapSweep(mesh, X, other, Y, direction, cache)

    def clear(t: float, spacing: float) -> bool:
        return not sweep.overlap(t, spacing)

    # Bisection with surface points SEPARATION_SPACING apart, then with EDGE_SPACING on the
    # last stretch (a coarse point set misses at most half its spacing).
    lo, hi = 0.0, max(guess, 1e-4)
    while not clear(hi, SEPARATION_SPACING):
        if hi >= reach:
            return None
        lo, hi = hi, min(2 * hi, reach)
    for _ in range(5):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if clear(mid, SEPARATION_SPACING) else (mid, hi)
    lo, hi = hi, hi + 0.5 * SEPARATION_SPACING
    while not clear(hi, EDGE_SPACING):
        if hi >= reach + SEPARATION_SPACING:
            return None
        lo, hi = hi, hi + 0.5 * SEPARATION_SPACING
    for _ in range(2):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if clear(mid, EDGE_SPACING) else (mid, hi)
    moved = X.copy()
    moved[:3, 3] += (hi + _SEPARATION_MARGIN) * direction
    return np.asarray(moved)


def _lower(meshes: Sequence[Mesh], poses: np.ndarray, tote: ToteSpec, cache: MeshCache) -> None:
    """Lowers (``poses`` in place) every object whose render mesh floats more than
    :data:`_LOWER_ABOVE` above what is nearest, lowest first, each by its clearance (which
    cannot make it overlap anything) until it is within :data:`_LOWER_TO` of a body; twice
    over, for objects that rested on a lowered one."""
    models = cache.models
    for m in meshes:  # world boxes are kept by id(mesh): the cache holds the meshes
        cache.bounds(m)
    boxes = cache.boxes
    for _ in range(2):
        gaps = [clearance(meshes, list(poses), tote, k, models, boxes) for k in range(len(meshes))]
        low = [
            float((np.asarray(m.vertices, np.float64) @ X[:3, :3].T + X[:3, 3])[:, 2].min())
            for m, X in zip(meshes, poses, strict=True)
        ]
        todo = sorted(
            (k for k in range(len(meshes)) if gaps[k] > _LOWER_ABOVE), key=lambda k: (low[k], k)
        )
        if not todo:
            return
        for k in todo:
            for _ in range(_LOWER_MOVES):
                gap = clearance(meshes, list(poses), tote, k, models, boxes)
                if gap <= _LOWER_TO:
                    break
                poses[k, 2, 3] -= gap


def separate_overlaps(
    meshes: Sequence[Mesh], X_WO: Sequence[npt.ArrayLike], tote: ToteSpec
) -> tuple[npt.NDArray[np.float64], int]:
    """The drop's final separation pass on closed meshes at poses ``X_WO`` (tote frame, m).

    While a mesh sinks deeper than :data:`SEPARATION_THRESHOLD` into the tote's floor or an
    inner wall, or two meshes into each other (found with surface points
    :data:`SEPARATION_SPACING` apart), at most :data:`SEPARATION_ROUNDS` rounds: each mesh
    sunk into the tote is moved out of it by the least (exact, planes); each overlapping pair,
    deepest first, is pulled apart by moving one of them the least distance that separates
    their surfaces (tested every 0.2 mm along every edge) plus 0.1 mm, along the way out of the
    pair's deepest point (moving the object it lifts; at most 5 mm), else the opposite way (the
    other object; 5 mm), else straight up (the higher, then the lower one; 15 mm): the first
    move that sinks the moved object no deeper than the threshold into the tote or a third
    object, else the one that sinks it least (:func:`_pull_apart`); then every object floating
    more than 0.1 mm above the nearest body is lowered (lowest first) until it touches one
    (within 0.02 mm). Poses without such overlaps are returned unchanged. Objects are moved,
    never turned.

    Returns:
        (N, 4, 4) poses, and the number of rounds that moved objects.
    """
    if len(meshes) != len(X_WO):
        raise InvalidArgumentError(
            f"separate_overlaps: {len(meshes)} meshes but {len(X_WO)} poses; expected one each"
        )
    poses = np.array([np.asarray(X, np.float64) for X in X_WO]).reshape(len(meshes), 4, 4)
    rounds = 0
    cache = MeshCache()  # the meshes do not change during the pass; their poses do
    for _ in range(SEPARATION_ROUNDS):
        sunk = [
            k
            for k in range(len(meshes))
            if tote_depth(meshes[k], poses[k], tote) > SEPARATION_THRESHOLD
        ]
        for k in sunk:
            _out_of_tote(meshes[k], poses[k], tote)
        found = mesh_overlaps(
            meshes, list(poses), SEPARATION_THRESHOLD, SEPARATION_SPACING, exact=False, cache=cache
        )
        if not found and not sunk:
            break
        pairs: dict[tuple[int, int], Overlap] = {}
        for o in sorted(found, key=lambda o: (-o.depth, o.a, o.b)):
            pairs.setdefault((min(o.a, o.b), max(o.a, o.b)), o)
        for o in pairs.values():
            _pull_apart(meshes, poses, o, tote, cache)
        _lower(meshes, poses, tote, cache)
        rounds += 1
    return poses, rounds


def _separate(
    pile: _Pile, objects: Sequence[ObjectSpec], meshes: dict[str, Mesh], tote: ToteSpec
) -> _Pile:
    """:func:`separate_overlaps` of the kept objects of ``pile``."""
    kept = np.flatnonzero(pile.status == 0)
    poses, rounds = separate_overlaps(
        [meshes[objects[int(k)].name] for k in kept], list(pile.X_WO[kept]), tote
    )
    if len(kept):
        moved = np.linalg.norm(poses[:, :3, 3] - pile.X_WO[kept][:, :3, 3], axis=1)
        pile.separation_max_move = float(moved.max())
    pile.X_WO[kept] = poses
    pile.separation_rounds = rounds
    return pile


def _settled_pile(
    objects: Sequence[ObjectSpec],
    seed: int,
    tote: ToteSpec,
    options: DropOptions,
    sources: Mapping[str, str | os.PathLike[str]] | None,
    decomposition: ConvexDecompositionOptions | None,
    use_cache: bool,
    X_WO_start: np.ndarray | None = None,
) -> tuple[_Pile, dict[str, str], dict[str, Mesh]]:
    """:func:`_simulate`, then the final separation pass (:func:`_separate`)."""
    out, sources_of, meshes = _simulate(
        objects, seed, tote, options, sources, decomposition, use_cache, X_WO_start
    )
    return _separate(_Pile.of(out), objects, meshes, tote), sources_of, meshes


def drop_scene(
    objects: Sequence[ObjectSpec],
    *,
    seed: int = 0,
    tote: ToteSpec | None = None,
    options: DropOptions | None = None,
    sources: dict[str, str | os.PathLike[str]] | None = None,
    decomposition: ConvexDecompositionOptions | None = None,
    use_cache: bool = True,
) -> Scene:
    """Drop ``objects`` into the tote, simulate until they settle, return the :class:`Scene`.

    Objects are released together at random orientations in the release window (seeded per
    object), collide through their cached convex decompositions, and settle; those that left
    the tote are listed in ``Scene.removed``. Mass, centre of mass and inertia come from each
    mesh and its density; friction from the spec. A final pass on the render meshes
    (:func:`separate_overlaps`) moves objects that the simulation left sunk more than
    :data:`SEPARATION_THRESHOLD` into each other or into the tote apart, and lowers what then
    floats onto what holds it.

    Args:
        objects: what to drop (see :func:`mgn.scene.compose_objects`); copies may repeat.
        seed: the same seed gives the same scene.
        tote: the tote (default :func:`mgn.objects.default_tote`).
        options: simulation options (MetaGraspNet defaults).
        sources: for user objects, name -> the YAML file they were loaded from.
        decomposition: convex decomposition options (default
            :data:`mgn.geometry.convex.DROP_DECOMPOSITION`: HACD parts merged for speed).
        use_cache: read/write the decomposition cache (:func:`mgn.geometry.convex.cache_dir`).

    Raises:
        InvalidArgumentError: no objects, an object larger than the tote, bad options, an
            unknown object source.
    """
    tote = tote or ToteSpec()
    options = options or DropOptions()
    pile, sources_of, meshes = _settled_pile(
        objects, seed, tote, options, sources, decomposition, use_cache
    )
    instances: list[SceneInstance] = []
    removed: list[RemovedInstance] = []
    for k, spec in enumerate(objects):
        source = sources_of[spec.name]
        status = _STATUS[int(pile.status[k])]
        if status != "kept":
            removed.append(RemovedInstance(spec.name, source, status))
            continue
        bits = int(pile.contacts[k])
        instances.append(
            SceneInstance(
                instance_id=len(instances) + 1,
                name=spec.name,
                category_id=spec.category_id,
                source=source,
                X_WO=pile.X_WO[k],
                contacts=tuple(c for b, c in enumerate(CONTACT_NAMES) if bits & (1 << b)),
                settled=bool(pile.settled[k]),
            )
        )
    stats = _stats(pile, instances, meshes, tote, len(objects))
    return Scene(tuple(instances), tote, int(seed), options, tuple(removed), stats)


def settle_tracked(
    scene: Scene,
    *,
    remove: Sequence[int] = (),
    options: DropOptions | None = None,
    decomposition: ConvexDecompositionOptions | None = None,
    use_cache: bool = True,
) -> tuple[Scene, tuple[int, ...]]:
    """:func:`settle`, also returning for each instance of the new scene the instance id it had
    in ``scene`` (instances are renumbered 1..M in their old order)."""
    n = len(scene.instances)
    ids = []
    for r in remove:
        if isinstance(r, bool) or not isinstance(r, (int, np.integer)) or not 1 <= r <= n:
            raise InvalidArgumentError(
                f"settle: remove must hold instance ids of the scene (1..{n}), got {r!r}"
            )
        ids.append(int(r))
    keep = [inst for inst in scene.instances if inst.instance_id not in set(ids)]
    options = options or scene.drop_options
    if not keep:
        empty = dataclasses.replace(scene, instances=(), stats={"num_dropped": 0})
        return empty, ()
    specs = [scene.object_spec(inst.instance_id - 1) for inst in keep]
    sources = {inst.name: inst.source for inst in keep if inst.source != BUILTIN}
    start = np.stack([inst.X_WO for inst in keep])
    pile, sources_of, meshes = _settled_pile(
        specs, scene.seed, scene.tote, options, sources, decomposition, use_cache, start
    )
    instances: list[SceneInstance] = []
    removed = list(scene.removed)
    old_ids: list[int] = []
    for k, (inst, spec) in enumerate(zip(keep, specs, strict=True)):
        status = _STATUS[int(pile.status[k])]
        if status != "kept":
            removed.append(RemovedInstance(spec.name, sources_of[spec.name], status))
            continue
        bits = int(pile.contacts[k])
        instances.append(
            dataclasses.replace(
                inst,
                instance_id=len(instances) + 1,
                X_WO=pile.X_WO[k],
                contacts=tuple(c for b, c in enumerate(CONTACT_NAMES) if bits & (1 << b)),
                settled=bool(pile.settled[k]),
            )
        )
        old_ids.append(inst.instance_id)
    stats = _stats(pile, instances, meshes, scene.tote, len(keep))
    new = Scene(tuple(instances), scene.tote, scene.seed, scene.drop_options, tuple(removed), stats)
    return new, tuple(old_ids)


def settle(
    scene: Scene,
    *,
    remove: Sequence[int] = (),
    options: DropOptions | None = None,
    decomposition: ConvexDecompositionOptions | None = None,
    use_cache: bool = True,
) -> Scene:
    """Take the instances ``remove`` (instance ids) out of ``scene`` and let the others settle
    again from their current poses, starting at rest (C++ ``settle_objects``: the drop's
    simulation, rest test and removal of objects that left the tote, without the random
    release). Returns a new :class:`Scene`: the remaining instances renumbered 1..M in their old
    order, with their settled poses, tote contacts (hence bin relations) and ``settled`` flags;
    objects that left the tote while settling are appended to ``removed``; ``stats`` describe
    this simulation. An already resting pile stays put (sub-millimetre creep). The final
    separation pass of :func:`drop_scene` runs here too.

    Args:
        scene: the current scene.
        remove: instance ids (1..N) to take out first (e.g. the object just picked).
        options: simulation options (default: the scene's drop options; the release window
            and seed are not used).
        decomposition, use_cache: as in :func:`drop_scene`.

    Raises:
        InvalidArgumentError: an id in ``remove`` that is not an instance id of the scene, bad
            options.
    """
    return settle_tracked(
        scene, remove=remove, options=options, decomposition=decomposition, use_cache=use_cache
    )[0]


def drop_scene_refilled(
    objects: Sequence[ObjectSpec],
    *,
    seed: int = 0,
    attempts: int = 5,
    **kwargs: Any,
) -> Scene:
    """:func:`drop_scene` again until every object stays in the tote (``objects.refill``).

    Attempt 0 uses ``seed``; attempt k > 0 the seed derived from (seed, k) (deterministic). Stops
    at the first scene without removed objects, else after ``attempts`` drops and keeps the
    scene with the most objects in the tote (the earliest on a tie). ``stats["drop_attempts"]``
    records the drops made. Other arguments as :func:`drop_scene`.
    """
    if isinstance(attempts, bool) or not isinstance(attempts, int) or attempts < 1:
        raise InvalidArgumentError(
            f"objects.refill_attempts must be an integer >= 1, got {attempts!r}"
        )
    best: Scene | None = None
    for k in range(attempts):
        s = seed if k == 0 else int(np.random.SeedSequence([seed, k]).generate_state(1)[0])
        scene = drop_scene(objects, seed=s, **kwargs)
        if best is None or len(scene.instances) > len(best.instances):
            best = scene
        if not scene.removed:
            break
    assert best is not None
    best.stats["drop_attempts"] = k + 1
    return best
