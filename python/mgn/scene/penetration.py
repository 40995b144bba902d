"""Penetration of the render meshes of a settled pile (what a user sees, not the physics hulls).

The drop simulates reduced convex hulls; what is rendered and labelled are the objects' meshes.
:func:`render_penetration` measures how deep those meshes sink into the tote (floor and inner
walls, planes of the tote frame) and into each other: the largest distance of a mesh vertex
below the floor / beyond a wall (exact: a mesh's deepest point against a plane is a vertex), or
of a point of one object's surface inside another object's closed mesh from that mesh's
surface, both ways round. The surface points tested are every vertex and points along every
edge at most :data:`EDGE_SPACING` apart, so an edge that crosses the other mesh between its
vertices (two boxes meeting edge to edge, no vertex inside the other) counts with its depth:
the depth along an edge changes by at most the distance moved, so the deepest point of an edge
is found to within half the spacing. A face that another mesh's vertex or edge pokes into is
seen from that vertex or edge (the other direction).
An object whose mesh is several closed parts that overlap one another (a union of solids) is
tested part by part: its parts never count as penetrating each other, and a vertex of another
object inside one of its parts counts with its depth below that part's surface.

:func:`float_gaps` measures the opposite error, objects resting above what holds them: the
clearance of each object's mesh to the nearest other body (the tote's floor and inner walls, or
another object's mesh; exact, FCL mesh-mesh distance), 0 where it touches or overlaps one.

Units m, tote frame W (see :mod:`mgn.scene.drop`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError
from mgn.geometry import Mesh, make_box
from mgn.geometry.collision import CollisionModel, distance
from mgn.geometry.raytrace import RayScene
from mgn.objects import ToteSpec

__all__ = [
    "EDGE_SPACING",
    "MeshCache",
    "Overlap",
    "OverlapSweep",
    "clearance",
    "deepest_overlap",
    "edge_points",
    "float_gaps",
    "mesh_overlaps",
    "meshes_overlap",
    "point_triangle_distance",
    "render_penetration",
    "tote_depth",
]

#: Largest distance (m) between the points tested along a mesh edge (see the module doc):
#: edge depths are found to within half of it, 0.1 mm.
EDGE_SPACING = 2e-4

# Three fixed ray directions off every axis and diagonal, for the ray-parity inside test: a point
# is inside when at least two of the three rays cross the surface an odd number of times (one
# ray grazing an edge or vertex, where single-precision parity may miscount, is outvoted).
_PARITY = tuple(
    np.array(d) / np.linalg.norm(d)
    for d in ((0.5773, 0.6213, 0.5297), (-0.6917, 0.3164, 0.6491), (0.2261, -0.8423, 0.4893))
)


_GRID = 16  # cells per axis of a point grid (:class:`_PointGrid`)


class _PointGrid:
    """Points binned into a uniform grid of :data:`_GRID` ^ 3 cells over their bounding box:
    the point indices sorted by cell (x-major, then y, then z) with each cell's first index."""

    def __init__(self, points: npt.NDArray[np.float64]) -> None:
        self.lo = points.min(axis=0) if len(points) else np.zeros(3)
        hi = points.max(axis=0) if len(points) else np.zeros(3)
        self.size = np.maximum(hi - self.lo, 1e-12) / _GRID
        cell = self._cell(points)
        linear = (cell[:, 0] * _GRID + cell[:, 1]) * _GRID + cell[:, 2]
        self.order: npt.NDArray[np.intp] = np.argsort(linear, kind="stable")
        self.start: npt.NDArray[np.intp] = np.searchsorted(
            linear[self.order], np.arange(_GRID**3 + 1)
        )

    def _cell(self, p: npt.NDArray[np.float64]) -> npt.NDArray[np.int64]:
        return np.clip(np.floor((p - self.lo) / self.size), 0, _GRID - 1).astype(np.int64)

    def candidates(
        self, lo: npt.NDArray[np.float64], hi: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.intp]:
        """Indices of the points in the cells that the box ``lo``, ``hi`` touches (a superset
        of the points inside the box), unordered."""
        if np.any(hi < lo):
            return np.zeros(0, np.intp)
        c0, c1 = self._cell(lo[None])[0], self._cell(hi[None])[0]
        x, y = np.meshgrid(np.arange(c0[0], c1[0] + 1), np.arange(c0[1], c1[1] + 1), indexing="ij")
        first = ((x * _GRID + y) * _GRID + c0[2]).ravel()  # each (x, y) column's z run of cells
        return self._points_of_runs(first, c1[2] - c0[2] + 1)

    def candidates_rotated(
        self,
        lo: npt.NDArray[np.float64],
        hi: npt.NDArray[np.float64],
        R: npt.NDArray[np.float64],
        rlo: npt.NDArray[np.float64],
        rhi: npt.NDArray[np.float64],
    ) -> npt.NDArray[np.intp]:
        """:meth:`candidates` of the box ``lo``, ``hi``, less the cells whose image under the
        rotation ``R`` (a point p goes to R p) lies outside the box ``rlo``, ``rhi``: a
        superset of the points p inside ``lo``, ``hi`` with R p inside ``rlo``, ``rhi``."""
        if np.any(hi < lo) or np.any(rhi < rlo):
            return np.zeros(0, np.intp)
        c0, c1 = self._cell(lo[None])[0], self._cell(hi[None])[0]
        axes = [np.arange(c0[k], c1[k] + 1) for k in range(3)]
        cells = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        centre = (self.lo + (cells + 0.5) * self.size) @ R.T
        # Half extent of a cell's image, widened for rounding (and for the points that the
        # clip of _cell puts into a border cell from its outer face).
        half = np.abs(R) @ (0.5 * self.size * (1.0 + 1e-6) + _BOX_SLACK)
        near = np.all((centre + half >= rlo) & (centre - half <= rhi), axis=1)
        first = (cells[near] @ np.array([_GRID * _GRID, _GRID, 1])).astype(np.intp)
        return self._points_of_runs(first, 1)

    def _points_of_runs(self, first: npt.NDArray[np.intp], length: int) -> npt.NDArray[np.intp]:
        """Indices of the points in the runs of ``length`` consecutive cells (linear index)
        starting at each of ``first``, run after run."""
        begin, end = self.start[first], self.start[first + length]
        count = end - begin
        offset = np.repeat(begin - (np.cumsum(count) - count), count)
        points: npt.NDArray[np.intp] = self.order[np.arange(int(count.sum())) + offset]
        return points


class MeshCache:
    """What the overlap tests derive from a mesh, computed once and reused across calls: its
    surface points (:func:`edge_points`) per spacing, its closed parts with their ray scenes,
    its bounding box (mesh frame, m) and FCL collision models. Keyed by the mesh object; the
    cache holds a reference to every mesh it has seen, so a key stays valid while the cache
    lives. Use one cache for a set of meshes that do not change (their poses may)."""

    def __init__(self) -> None:
        self._meshes: dict[int, Mesh] = {}
        self._points: dict[tuple[int, float], npt.NDArray[np.float64]] = {}
        self._grids: dict[tuple[int, float], _PointGrid] = {}
        self._parts: dict[int, list[tuple[Mesh, RayScene]]] = {}
        self._bounds: dict[int, tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]] = {}
        #: FCL collision models by ``id`` of a mesh or part held here (the probe under -1).
        self.models: dict[int, CollisionModel] = {}
        #: World bounding boxes by (``id`` of a mesh held here, pose bytes) (:func:`clearance`).
        self.boxes: dict[tuple[int, bytes], tuple[np.ndarray, np.ndarray]] = {}

    def _hold(self, mesh: Mesh) -> int:
        self._meshes.setdefault(id(mesh), mesh)
        return id(mesh)

    def points(self, mesh: Mesh, spacing: float) -> npt.NDArray[np.float64]:
        """:func:`edge_points` of ``mesh`` at ``spacing`` (m), mesh frame."""
        key = (self._hold(mesh), float(spacing))
        if key not in self._points:
            self._points[key] = edge_points(mesh, spacing)
        return self._points[key]

    def points_in_box(
        self, mesh: Mesh, spacing: float, lo: npt.ArrayLike, hi: npt.ArrayLike
    ) -> npt.NDArray[np.float64]:
        """The points of :meth:`points` inside the axis-aligned box ``lo`` <= p <= ``hi`` (mesh
        frame, m), in the order of :meth:`points`. The points are binned once into a
        :data:`_GRID` ^ 3 grid over their bounding box; a query tests only the points of the
        cells the box touches."""
        return self.points(mesh, spacing)[self.indices_in_box(mesh, spacing, lo, hi)]

    def _grid(self, mesh: Mesh, spacing: float) -> _PointGrid:
        key = (self._hold(mesh), float(spacing))
        if key not in self._grids:
            self._grids[key] = _PointGrid(self.points(mesh, spacing))
        return self._grids[key]

    def cells_in_box(
        self, mesh: Mesh, spacing: float, lo: npt.ArrayLike, hi: npt.ArrayLike
    ) -> npt.NDArray[np.intp]:
        """Indices into :meth:`points` of the points in the grid cells that the box ``lo``,
        ``hi`` (mesh frame, m) touches: a superset of the points inside it, unordered."""
        lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
        return self._grid(mesh, spacing).candidates(lo, hi)

    def indices_in_box(
        self, mesh: Mesh, spacing: float, lo: npt.ArrayLike, hi: npt.ArrayLike
    ) -> npt.NDArray[np.intp]:
        """Ascending indices into :meth:`points` of the points inside the axis-aligned box
        ``lo`` <= p <= ``hi`` (mesh frame, m): :meth:`points_in_box` is ``points[indices]``.
        Costs the cells the box touches and their points, not the whole point set."""
        points = self.points(mesh, spacing)
        lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
        found = np.sort(self.cells_in_box(mesh, spacing, lo, hi), kind="stable")
        near = points[found]
        return found[_in_box(near, lo, hi)]

    def parts(self, mesh: Mesh) -> list[tuple[Mesh, RayScene]]:
        """The connected parts of ``mesh`` (:func:`_connected_parts`), each with its ray scene."""
        key = self._hold(mesh)
        if key not in self._parts:
            parts = [(m, RayScene(m)) for m in _connected_parts(mesh)]
            for m, _ in parts:
                self._hold(m)
            self._parts[key] = parts
        return self._parts[key]

    def bounds(self, mesh: Mesh) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """(lo, hi): the corners (3,) of ``mesh``'s bounding box in its frame (m)."""
        key = self._hold(mesh)
        if key not in self._bounds:
            v = np.asarray(mesh.vertices, np.float64)
            self._bounds[key] = (v.min(axis=0), v.max(axis=0))
        return self._bounds[key]

    def model(self, mesh: Mesh) -> CollisionModel:
        """The FCL collision model of ``mesh``."""
        key = self._hold(mesh)
        if key not in self.models:
            self.models[key] = CollisionModel(mesh)
        return self.models[key]


def point_triangle_distance(
    points: npt.ArrayLike, triangles: npt.ArrayLike
) -> npt.NDArray[np.float64]:
    """(N,) distance (m) of each point to the nearest of (F, 3, 3) triangles (brute force)."""
    p = np.asarray(points, np.float64)[:, None, :]
    t = np.asarray(triangles, np.float64)[None]
    a, b, c = t[..., 0, :], t[..., 1, :], t[..., 2, :]
    ab, ac, ap = b - a, c - a, p - a
    # Closest point on a triangle by its Voronoi regions, evaluated for every pair at once:
    # the projection onto the plane if it falls inside, else the nearest point of the 3 edges.
    n = np.cross(ab, ac)
    nn = np.maximum(np.einsum("...k,...k", n, n), 1e-300)
    d_plane = np.einsum("...k,...k", ap, n) / nn
    q = p - d_plane[..., None] * n
    # Barycentric inside test of the projection.
    v0, v1, v2 = ab, ac, q - a
    d00 = np.einsum("...k,...k", v0, v0)
    d01 = np.einsum("...k,...k", v0, v1)
    d11 = np.einsum("...k,...k", v1, v1)
    d20 = np.einsum("...k,...k", v2, v0)
    d21 = np.einsum("...k,...k", v2, v1)
    den = np.maximum(d00 * d11 - d01 * d01, 1e-300)
    v = (d11 * d20 - d01 * d21) / den
    w = (d00 * d21 - d01 * d20) / den
    inside = (v >= 0) & (w >= 0) & (v + w <= 1)
    best = np.where(inside, np.linalg.norm(p - q, axis=-1), np.inf)
    for s, e in ((a, b), (b, c), (c, a)):
        se = e - s
        u = np.clip(
            np.einsum("...k,...k", p - s, se) / np.maximum(np.einsum("...k,...k", se, se), 1e-300),
            0.0,
            1.0,
        )
        best = np.minimum(best, np.linalg.norm(p - (s + u[..., None] * se), axis=-1))
    nearest: npt.NDArray[np.float64] = best.min(axis=1)
    return nearest


def edge_points(mesh: Mesh, spacing: float = EDGE_SPACING) -> npt.NDArray[np.float64]:
    """(N, 3) points of ``mesh`` (its frame, m): every vertex used by a face, and points along
    every edge, evenly spaced at most ``spacing`` (m, > 0) apart, end points excluded."""
    if not spacing > 0:
        raise InvalidArgumentError(f"edge_points: spacing must be > 0 m, got {spacing!r}")
    v = np.asarray(mesh.vertices, np.float64)
    f = np.asarray(mesh.faces, np.int64)
    if len(f) == 0:
        return np.zeros((0, 3))
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    e = np.unique(e, axis=0)
    a, b = v[e[:, 0]], v[e[:, 1]]
    pieces = np.ceil(np.linalg.norm(b - a, axis=1) / spacing).astype(np.int64)
    inner = np.maximum(pieces - 1, 0)  # points strictly between the end points
    edge = np.repeat(np.arange(len(e)), inner)
    start = np.cumsum(inner) - inner
    k = np.arange(int(inner.sum())) - np.repeat(start, inner) + 1
    t = (k / pieces[edge])[:, None]
    return np.concatenate([v[np.unique(f)], a[edge] + t * (b[edge] - a[edge])])


def _inside(scene: RayScene, points: np.ndarray) -> np.ndarray:
    if len(points) == 0:
        return np.zeros(0, bool)

    def parity(p: np.ndarray, direction: np.ndarray) -> np.ndarray:
        d = np.broadcast_to(direction, p.shape)
        odd: np.ndarray = scene.intersect_all(p, d, num_threads=1).counts() % 2 == 1
        return odd

    first, second = parity(points, _PARITY[0]), parity(points, _PARITY[1])
    inside: np.ndarray = first & second
    split = np.flatnonzero(first != second)  # the third ray decides
    inside[split] = parity(points[split], _PARITY[2])
    return inside


@dataclass(frozen=True)
class Overlap:
    """The deepest point of object ``a``'s surface inside object ``b`` (tote frame, m).

    Attributes:
        a, b: indices of the two objects in the lists measured.
        depth: the point's distance to ``b``'s surface (m, > 0).
        point: (3,) the point (a vertex or edge point of ``a``'s mesh).
        exit: (3,) the nearest point of ``b``'s surface (of the closed part of ``b`` that holds
            the point): moving ``a`` by ``exit - point`` takes this point out of ``b``.
    """

    a: int
    b: int
    depth: float
    point: npt.NDArray[np.float64]
    exit: npt.NDArray[np.float64]


def render_penetration(
    meshes: Sequence[Mesh], X_WO: Sequence[npt.ArrayLike], tote: ToteSpec
) -> float:
    """Deepest penetration (m, >= 0) of closed meshes at poses ``X_WO`` (tote frame): of a vertex
    below the floor (z < 0) or beyond an inner wall below the rim (a tote with walls), and of a
    point of one mesh's surface inside another mesh (its distance to that mesh's surface): every
    vertex and points along every edge (:func:`edge_points`), so edges crossing between vertices
    count to within :data:`EDGE_SPACING` / 2. Only different meshes (objects) count against each
    other: the parts of one mesh never penetrate each other."""
    if len(meshes) != len(X_WO):
        raise InvalidArgumentError(
            f"render_penetration: {len(meshes)} meshes but {len(X_WO)} poses; expected one each"
        )
    worst = 0.0
    for m, X in zip(meshes, X_WO, strict=True):
        worst = max(worst, tote_depth(m, np.asarray(X, np.float64), tote))
    found = _overlaps(meshes, X_WO, worst, running=True)
    return max([worst, 0.0] + [o.depth for o in found])


def tote_depth(mesh: Mesh, X: npt.NDArray[np.float64], tote: ToteSpec) -> float:
    """How deep (m, >= 0) ``mesh`` at pose ``X`` (tote frame) sinks into the floor (z < 0) or an
    inner wall below the rim (a tote with walls; a table top has none): exact, a mesh's deepest
    point against a plane is a vertex."""
    w = np.asarray(mesh.vertices, np.float64) @ X[:3, :3].T + X[:3, 3]
    depth = float(-w[:, 2].min())
    low = w[w[:, 2] <= tote.inner_height]
    if len(low) and tote.walls:
        depth = max(depth, float((np.abs(low[:, 0]) - 0.5 * tote.inner_length).max()))
        depth = max(depth, float((np.abs(low[:, 1]) - 0.5 * tote.inner_width).max()))
    return max(depth, 0.0)


def mesh_overlaps(
    meshes: Sequence[Mesh],
    X_WO: Sequence[npt.ArrayLike],
    above: float = 0.0,
    spacing: float = EDGE_SPACING,
    exact: bool = True,
    cache: MeshCache | None = None,
    involving: int | None = None,
) -> list[Overlap]:
    """For each ordered pair of closed meshes (objects) at poses ``X_WO`` (tote frame) whose
    surfaces sink deeper than ``above`` (m, >= 0) into each other, the deepest point of ``a``'s
    surface inside ``b`` (:class:`Overlap`; tested as :func:`render_penetration` does: every
    vertex and points along every edge at most ``spacing`` (m, > 0) apart, so a depth is found
    to within ``spacing`` / 2; parts of one mesh never count). Pairs in order of (a, b); the
    tote is not measured. ``exact=False``: each inside point's depth is its FCL distance to
    the other mesh (a 0.01 mm probe; faster, short of the exact depth by at most 0.01 mm).
    ``cache``: per-mesh data reused across calls on the same meshes (:class:`MeshCache`).
    ``involving``: only the pairs that include the mesh at this index (None: every pair)."""
    _check_overlap_args("mesh_overlaps", meshes, X_WO, above, involving)
    return _overlaps(
        meshes,
        X_WO,
        float(above),
        running=False,
        spacing=spacing,
        exact=exact,
        cache=cache,
        involving=involving,
    )


def deepest_overlap(
    meshes: Sequence[Mesh],
    X_WO: Sequence[npt.ArrayLike],
    spacing: float = EDGE_SPACING,
    exact: bool = True,
    cache: MeshCache | None = None,
    involving: int | None = None,
) -> float:
    """The largest depth (m, >= 0; 0 without overlaps) of the :func:`mesh_overlaps` of
    ``meshes`` at ``X_WO`` with ``above`` 0 (same ``spacing``, ``exact``, ``cache`` and
    ``involving``), without searching each overlap's exit."""
    _check_overlap_args("deepest_overlap", meshes, X_WO, 0.0, involving)
    found = _overlaps(
        meshes,
        X_WO,
        0.0,
        running=False,
        spacing=spacing,
        exact=exact,
        cache=cache,
        involving=involving,
        exits=False,
    )
    return max([0.0] + [o.depth for o in found])


def _check_overlap_args(
    name: str,
    meshes: Sequence[Mesh],
    X_WO: Sequence[npt.ArrayLike],
    above: float,
    involving: int | None,
) -> None:
    if len(meshes) != len(X_WO):
        raise InvalidArgumentError(
            f"{name}: {len(meshes)} meshes but {len(X_WO)} poses; expected one each"
        )
    if not above >= 0:
        raise InvalidArgumentError(f"{name}: above must be >= 0 m, got {above!r}")
    if involving is not None and not 0 <= involving < len(meshes):
        raise InvalidArgumentError(
            f"{name}: involving must index one of the {len(meshes)} meshes, got {involving!r}"
        )


def _overlaps(
    meshes: Sequence[Mesh],
    X_WO: Sequence[npt.ArrayLike],
    above: float,
    running: bool,
    spacing: float = EDGE_SPACING,
    exact: bool = True,
    cache: MeshCache | None = None,
    involving: int | None = None,
    exits: bool = True,
) -> list[Overlap]:
    """The deepest point of each ordered pair deeper than ``above``; ``running``: only pairs
    deeper than every pair before them (enough for the maximum, and faster); ``involving``:
    only the pairs that include this index; ``exits=False``: each Overlap's ``exit`` is its
    ``point`` (not searched; for callers that want depths only)."""
    cache = MeshCache() if cache is None else cache  # copies of one object share their mesh
    local = [np.asarray(m.vertices, np.float64) for m in meshes]
    poses = [np.asarray(X, np.float64) for X in X_WO]
    world = [v @ X[:3, :3].T + X[:3, 3] for v, X in zip(local, poses, strict=True)]
    lo = [w.min(axis=0) for w in world]
    hi = [w.max(axis=0) for w in world]
    found: list[Overlap] = []
    for a in range(len(meshes)):
        for b in range(len(meshes)):
            if a == b or (involving is not None and involving not in (a, b)):
                continue
            if np.any(lo[a] > hi[b]) or np.any(lo[b] > hi[a]):
                continue
            # Surface points of a inside b's world bounding box, in b's frame, inside b's local
            # bounding box, then inside b's mesh.
            Xb = poses[b]
            pa = _points_inside_box(
                cache, meshes[a], poses[a], meshes[b], Xb, lo[b], hi[b], spacing
            )
            if len(pa) == 0:
                continue
            # A mesh of several closed parts that overlap one another (one object modelled as
            # a union of solids) is tested part by part: the parity of the whole would count a
            # point inside two parts as outside, and coincident faces of two parts as one
            # crossing. A point inside a part sinks into b at least as deep as into that part.
            worst = max([above] + [o.depth for o in found]) if running else above
            best: tuple[float, np.ndarray, Mesh] | None = None
            for part, scene in cache.parts(meshes[b]):
                p = pa[_inside(scene, pa)]
                if len(p):
                    if exact:
                        depth, at = _deepest(p, part, worst, cache.models)
                    else:
                        depth, at = _deepest_fcl(p, part, worst, cache.models)
                    if at is not None:
                        worst, best = depth, (depth, at, part)
            if best is not None:
                depth, at, part = best
                R, t = Xb[:3, :3], Xb[:3, 3]
                if exits:
                    tri = np.asarray(part.vertices, np.float64)[np.asarray(part.faces)]
                    q = _closest_point(at, tri)
                    found.append(Overlap(a, b, depth, R @ at + t, R @ q + t))
                else:
                    found.append(Overlap(a, b, depth, R @ at + t, R @ at + t))
    return found


def _points_inside_box(
    cache: MeshCache,
    mesh_a: Mesh,
    Xa: npt.NDArray[np.float64],
    mesh_b: Mesh,
    Xb: npt.NDArray[np.float64],
    lo_b: npt.NDArray[np.float64],
    hi_b: npt.NDArray[np.float64],
    spacing: float,
) -> npt.NDArray[np.float64]:
    """The surface points of ``mesh_a`` (at ``Xa``) inside the world bounding box ``lo_b``,
    ``hi_b`` of ``mesh_b`` (at ``Xb``), in ``mesh_b``'s frame, inside its local bounding box; in
    the order of :meth:`MeshCache.points`.

    Defined by these steps: the points of ``a`` in the box around b's world box in a's frame,
    carried into the world, those inside b's world box carried into b's frame, those inside b's
    local box. Computed from the grid cells of ``a`` whose image in b's frame reaches b's local
    box (:meth:`_PointGrid.candidates_rotated`), with the same products on rows of the same
    points (a product's row does not depend on the other rows, except that a one-row product
    rounds differently: a step that meets one row, where the definition may meet several, is
    taken as defined)."""
    corners = _box_corners(lo_b, hi_b)
    in_a = (corners - Xa[:3, 3]) @ Xa[:3, :3]  # b's world box in a's frame
    a_lo, a_hi = in_a.min(axis=0) - _BOX_SLACK, in_a.max(axis=0) + _BOX_SLACK
    blo, bhi = cache.bounds(mesh_b)

    def steps(pa: npt.NDArray[np.float64]) -> tuple[int, npt.NDArray[np.float64]]:
        pa = pa @ Xa[:3, :3].T + Xa[:3, 3]
        pa = pa[_in_box(pa, lo_b, hi_b)]
        rows = len(pa)
        pa = (pa - Xb[:3, 3]) @ Xb[:3, :3]
        return rows, pa[_in_box(pa, blo, bhi)]

    # Rotation and translation from a's frame to b's (image p -> R p + t); cells whose image
    # misses b's local box (widened) hold no point that reaches the end.
    R = Xb[:3, :3].T @ Xa[:3, :3]
    t = Xb[:3, :3].T @ (Xa[:3, 3] - Xb[:3, 3])
    cand = np.sort(
        cache._grid(mesh_a, spacing).candidates_rotated(
            a_lo, a_hi, R, blo - t - _BOX_SLACK, bhi - t + _BOX_SLACK
        ),
        kind="stable",
    )
    points = cache.points(mesh_a, spacing)
    near = points[cand]
    near = near[_in_box(near, a_lo, a_hi)]
    if len(near) == 0:
        return near
    rows, pa = steps(near)
    if len(near) == 1 or rows == 1:  # the definition may meet more rows there
        rows, pa = steps(cache.points_in_box(mesh_a, spacing, a_lo, a_hi))
    return pa


def meshes_overlap(
    mesh_a: Mesh,
    X_a: npt.ArrayLike,
    mesh_b: Mesh,
    X_b: npt.ArrayLike,
    spacing: float = EDGE_SPACING,
    cache: MeshCache | None = None,
) -> bool:
    """Whether a point of either closed mesh's surface (every vertex and points along every
    edge at most ``spacing`` (m) apart) lies inside the other at poses ``X_a``, ``X_b`` (the
    inside test of :func:`render_penetration`, part by part). ``cache``: per-mesh data reused
    across calls (:class:`MeshCache`)."""
    cache = MeshCache() if cache is None else cache
    Xa, Xb = np.asarray(X_a, np.float64), np.asarray(X_b, np.float64)
    for (m, X), (n, Y) in (((mesh_a, Xa), (mesh_b, Xb)), ((mesh_b, Xb), (mesh_a, Xa))):
        # m's surface points in n's frame (one transform), inside n's bounding box, then inside
        # a part of n.
        R = Y[:3, :3].T @ X[:3, :3]
        t = Y[:3, :3].T @ (X[:3, 3] - Y[:3, 3])
        parts = cache.parts(n)
        lo, hi = cache.bounds(n)
        # First the points inside the box around n's bounding box in m's own frame (no
        # transform of every point), then in n's frame.
        in_m = (_box_corners(lo, hi) - t) @ R  # n's box corners in m's frame
        p = cache.points_in_box(m, spacing, in_m.min(axis=0), in_m.max(axis=0)) @ R.T + t
        p = p[_in_box(p, lo, hi)]
        if len(p) and any(_inside(scene, p).any() for _, scene in parts):
            return True
    return False


def _in_box(
    p: npt.NDArray[np.float64], lo: npt.NDArray[np.float64], hi: npt.NDArray[np.float64]
) -> npt.NDArray[np.bool_]:
    """(N,) whether each row of ``p`` (N, 3) lies in the box ``lo`` <= p <= ``hi``: ``np.all((p
    >= lo) & (p <= hi), axis=1)``, one column at a time (faster)."""
    inside: npt.NDArray[np.bool_] = p[:, 0] >= lo[0]
    inside &= p[:, 0] <= hi[0]
    for k in (1, 2):
        inside &= p[:, k] >= lo[k]
        inside &= p[:, k] <= hi[k]
    return inside


# m: a box carried into another frame is widened by this before it selects points there, so that
# rounding cannot drop a point that the exact test in the first frame keeps.
_BOX_SLACK = 1e-9


class OverlapSweep:
    """:func:`meshes_overlap` of ``mesh_a`` moved along a line, for many distances: ``overlap(t,
    spacing)`` is ``meshes_overlap(mesh_a, X_a moved by t * direction, mesh_b, X_b, spacing,
    cache)``, bit for bit, for any ``t`` (m).

    A translation leaves the rotation between the two frames unchanged, so each mesh's surface
    points that can reach the other's bounding box over a stretch of ``t``
    (:data:`_SWEEP_STRETCH` beyond the first ``t`` asked for; a new stretch is taken when a
    ``t`` falls outside) are rotated into the other's frame once: the rows of the same product
    :func:`meshes_overlap` forms, which do not depend on which other rows it holds. Each ``t``
    then adds its translation, keeps the points inside both boxes that :func:`meshes_overlap`
    tests (the other's box in its frame, and the box around it in the points' own frame) and
    runs the same inside test on them, the points found inside at the last overlap first. A
    selection of one point is formed as :func:`meshes_overlap` forms it (a one-row product
    rounds differently)."""

    def __init__(
        self,
        mesh_a: Mesh,
        X_a: npt.ArrayLike,
        mesh_b: Mesh,
        X_b: npt.ArrayLike,
        direction: npt.ArrayLike,
        cache: MeshCache | None = None,
    ) -> None:
        self.mesh_a, self.mesh_b = mesh_a, mesh_b
        self.X_a = np.asarray(X_a, np.float64)
        self.X_b = np.asarray(X_b, np.float64)
        self.direction = np.asarray(direction, np.float64)
        self.cache = MeshCache() if cache is None else cache
        # Per (spacing, side; side 0: a's points against b): the stretch (t0, t1) covered, the
        # rotation, the points in their own frame and rotated into the other's.
        self._blocks: dict[tuple[float, int], _SweepBlock] = {}

    def moved(self, t: float) -> npt.NDArray[np.float64]:
        """``X_a`` moved by ``t`` (m) along the direction (as the caller of
        :func:`meshes_overlap` forms it)."""
        moved: npt.NDArray[np.float64] = self.X_a.copy()
        moved[:3, 3] += t * self.direction
        return moved

    def overlap(self, t: float, spacing: float = EDGE_SPACING) -> bool:
        """:func:`meshes_overlap` with ``mesh_a`` at :meth:`moved` (``t``)."""
        Xa = self.moved(t)
        sides = ((self.mesh_a, Xa, self.mesh_b, self.X_b), (self.mesh_b, self.X_b, self.mesh_a, Xa))
        for side, (m, X, n, Y) in enumerate(sides):
            R = Y[:3, :3].T @ X[:3, :3]
            tv = Y[:3, :3].T @ (X[:3, 3] - Y[:3, 3])
            lo, hi = self.cache.bounds(n)
            in_m = (_box_corners(lo, hi) - tv) @ R
            m_lo, m_hi = in_m.min(axis=0), in_m.max(axis=0)
            block = self._block(float(spacing), side, t, R)
            rows: npt.NDArray[np.intp] | None = None  # p's rows of the block
            if block is None:  # the rotation differs (cannot happen for a translation)
                p = self.cache.points_in_box(m, spacing, m_lo, m_hi) @ R.T + tv
            else:
                q = block.rotated + tv
                keep = _in_box(q, lo, hi)
                keep &= _in_box(block.points, m_lo, m_hi)
                rows = np.flatnonzero(keep)
                p = q[rows]
                if len(p) <= 1:
                    # meshes_overlap's selection in m's frame may be this one point alone: a
                    # one-row product, formed (and rounded) as there.
                    sel = self.cache.points_in_box(m, spacing, m_lo, m_hi)
                    if len(sel) == 1:
                        p, rows = sel @ R.T + tv, None
            inside = _in_box(p, lo, hi)
            p = p[inside]
            if len(p) == 0:
                continue
            # The inside test of meshes_overlap; the points found inside at this block's last
            # overlap go first (the answer is whether any point is inside: an early yes).
            groups = [np.ones(len(p), bool)]
            if block is not None and rows is not None:
                rows = rows[inside]
                groups = [block.hit[rows], ~block.hit[rows]]
            for group in groups:
                if not group.any():
                    continue
                for _, scene in self.cache.parts(n):
                    found = _inside(scene, p[group])
                    if found.any():
                        if block is not None and rows is not None:
                            block.hit[:] = False
                            block.hit[rows[group][found]] = True
                        return True
        return False

    def _block(self, spacing: float, side: int, t: float, R: np.ndarray) -> _SweepBlock | None:
        block = self._blocks.get((spacing, side))
        if block is None or not block.t0 <= t <= block.t1:
            t0 = t - _SWEEP_STRETCH if block is None else min(t, block.t0)
            t1 = t + _SWEEP_STRETCH if block is None else max(t, block.t1) + _SWEEP_STRETCH
            block = self._build(spacing, side, t0, t1, R)
            self._blocks[(spacing, side)] = block
        return block if np.array_equal(block.R, R) else None

    def _build(self, spacing: float, side: int, t0: float, t1: float, R: np.ndarray) -> _SweepBlock:
        """The points of one side that lie, at some t in [t0, t1], in the box around the other's
        bounding box (own frame) and in that bounding box (the other's frame): both boxes move
        linearly with t, so the boxes at the ends bound them (widened by :data:`_BOX_SLACK`)."""
        m, n = (self.mesh_a, self.mesh_b) if side == 0 else (self.mesh_b, self.mesh_a)
        lo, hi = self.cache.bounds(n)
        corners, shifts = [], []
        for t in (t0, t1):
            Xa = self.moved(t)
            X, Y = (Xa, self.X_b) if side == 0 else (self.X_b, Xa)
            tv = Y[:3, :3].T @ (X[:3, 3] - Y[:3, 3])
            corners.append((_box_corners(lo, hi) - tv) @ R)
            shifts.append(tv)
        box = np.concatenate(corners)
        reach_lo = lo - np.maximum(shifts[0], shifts[1]) - _BOX_SLACK
        reach_hi = hi - np.minimum(shifts[0], shifts[1]) + _BOX_SLACK
        idx = self.cache._grid(m, spacing).candidates_rotated(
            box.min(axis=0) - _BOX_SLACK, box.max(axis=0) + _BOX_SLACK, R, reach_lo, reach_hi
        )
        points = self.cache.points(m, spacing)[idx]
        rotated = points @ R.T
        keep = _in_box(rotated, reach_lo, reach_hi)
        return _SweepBlock(
            t0, t1, R.copy(), points[keep], rotated[keep], np.zeros(int(keep.sum()), bool)
        )


@dataclass
class _SweepBlock:
    t0: float
    t1: float
    R: npt.NDArray[np.float64]
    points: npt.NDArray[np.float64]  # (K, 3) own frame
    rotated: npt.NDArray[np.float64]  # (K, 3) points @ R.T: the other's frame, less translation
    hit: npt.NDArray[np.bool_]  # (K,) found inside the other at the last overlap


# m: the stretch of distances along an OverlapSweep that one block of points covers beyond the
# first distance asked for (a longer one is built when a distance falls outside).
_SWEEP_STRETCH = 2e-3


def _box_corners(lo: npt.ArrayLike, hi: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """(8, 3) corners of the axis-aligned box ``lo``, ``hi``."""
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    return np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )


def float_gaps(
    meshes: Sequence[Mesh], X_WO: Sequence[npt.ArrayLike], tote: ToteSpec
) -> npt.NDArray[np.float64]:
    """(N,) clearance (m, >= 0) of each closed mesh at its pose ``X_WO`` (tote frame) to the
    nearest other body: the floor (z = 0), an inner wall below the rim (a tote with walls), or
    another mesh (FCL distance between the meshes); 0 where it touches or overlaps one. An
    object at rest touches something, so a positive value is the height it floats at. A lower
    bound on floating: an object that touches one body and floats above another it leans on
    counts 0."""
    if len(meshes) != len(X_WO):
        raise InvalidArgumentError(
            f"float_gaps: {len(meshes)} meshes but {len(X_WO)} poses; expected one each"
        )
    models: dict[int, CollisionModel] = {}  # copies of one object share their mesh
    boxes: dict[tuple[int, bytes], tuple[np.ndarray, np.ndarray]] = {}
    return np.array([clearance(meshes, X_WO, tote, a, models, boxes) for a in range(len(meshes))])


def clearance(
    meshes: Sequence[Mesh],
    X_WO: Sequence[npt.ArrayLike],
    tote: ToteSpec,
    index: int,
    models: dict[int, CollisionModel] | None = None,
    boxes: dict[tuple[int, bytes], tuple[np.ndarray, np.ndarray]] | None = None,
) -> float:
    """:func:`float_gaps` of the one mesh ``meshes[index]`` (m, >= 0). ``models``: collision
    models by ``id(mesh)``, filled and reused across calls. ``boxes``: world bounding boxes by
    ``(id(mesh), pose bytes)``, filled and reused across calls (the meshes must not change)."""
    hx, hy, H = 0.5 * tote.inner_length, 0.5 * tote.inner_width, tote.inner_height
    poses = [np.asarray(X, np.float64) for X in X_WO]
    a = index
    w = np.asarray(meshes[a].vertices, np.float64) @ poses[a][:3, :3].T + poses[a][:3, 3]
    gap = float(w[:, 2].min())  # a mesh's nearest point to a plane is a vertex
    low = w[w[:, 2] <= H]
    if len(low) and tote.walls:
        gap = min(gap, float((hx - np.abs(low[:, 0])).min()), float((hy - np.abs(low[:, 1])).min()))
    boxes = {} if boxes is None else boxes
    world_boxes = [_world_box(m, X, boxes) for m, X in zip(meshes, poses, strict=True)]
    lo = [b[0] for b in world_boxes]
    hi = [b[1] for b in world_boxes]
    models = {} if models is None else models
    # Other meshes nearest first by their bounding boxes; a box farther than the gap found so
    # far cannot hold a nearer mesh.
    box_gap = [
        float(np.linalg.norm(np.maximum(np.maximum(lo[b] - hi[a], lo[a] - hi[b]), 0.0)))
        for b in range(len(meshes))
    ]
    for b in sorted(range(len(meshes)), key=lambda b: (box_gap[b], b)):
        if b == a:
            continue
        if box_gap[b] >= gap:
            break
        for m in (meshes[a], meshes[b]):
            if id(m) not in models:
                models[id(m)] = CollisionModel(m)
        d = distance(
            models[id(meshes[a])], poses[a], models[id(meshes[b])], poses[b], num_threads=1
        )
        gap = min(gap, float(d.distance[0]))
    return max(gap, 0.0)


def _world_box(
    mesh: Mesh, X: np.ndarray, boxes: dict[tuple[int, bytes], tuple[np.ndarray, np.ndarray]]
) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) of ``mesh``'s vertices at pose ``X`` (world), kept in ``boxes``."""
    key = (id(mesh), np.ascontiguousarray(X, np.float64).tobytes())
    if key not in boxes:
        w = np.asarray(mesh.vertices, np.float64) @ X[:3, :3].T + X[:3, 3]
        boxes[key] = (w.min(axis=0), w.max(axis=0))
    return boxes[key]


def _connected_parts(mesh: Mesh) -> list[Mesh]:
    """The pieces of ``mesh`` connected through shared (welded) vertices; ``[mesh]`` when it is
    one piece."""
    v = np.asarray(mesh.vertices)
    f = np.asarray(mesh.faces, np.int64)
    if len(f) == 0:
        return [mesh]
    _, weld = np.unique(v + np.float32(0.0), axis=0, return_inverse=True)
    wf = weld.reshape(-1)[f]
    # Connected components by min-label propagation along the face edges with pointer jumping.
    label = np.arange(int(wf.max()) + 1)
    u = np.concatenate([wf[:, 0], wf[:, 1], wf[:, 2]])
    w = np.concatenate([wf[:, 1], wf[:, 2], wf[:, 0]])
    while True:
        low = np.minimum(label[u], label[w])
        new = label.copy()
        np.minimum.at(new, u, low)
        np.minimum.at(new, w, low)
        new = new[new]
        if np.array_equal(new, label):
            break
        label = new
    face_label = label[wf[:, 0]]
    pieces = np.unique(face_label)
    if len(pieces) == 1:
        return [mesh]
    return [Mesh(v, f[face_label == k].astype(np.int32)) for k in pieces]


def _deepest(
    p: np.ndarray, part: Mesh, worst: float, models: dict[int, CollisionModel]
) -> tuple[float, np.ndarray | None]:
    """The largest distance of the points ``p`` (inside ``part``) to the surface of ``part``
    and the point at that distance, when it exceeds ``worst``; else ``(worst, None)``."""
    # Every point's depth is first bracketed by FCL (a BVH search): the distance d of a probe
    # cube of edge _PROBE centred at the point to the part's triangles is at most the point's
    # distance, and short of it by at most the cube's half diagonal. Only points whose upper
    # end d + half diagonal reaches the largest lower end (and ``worst``) can be the deepest;
    # their exact distances (brute force over the triangles) decide. The result is the
    # brute-force maximum.
    if len(p) == 0:
        return worst, None
    lower = np.maximum(_probe_distances(p, part, models), 0.0)
    reach = 0.5 * np.sqrt(3.0) * _PROBE * (1.0 + 1e-6) + 1e-12  # half diagonal, widened
    candidates = np.flatnonzero(lower + reach > max(worst, float(lower.max())))
    if len(candidates) == 0:
        return worst, None
    faces = np.asarray(part.faces)
    tri = np.asarray(part.vertices, np.float64)[faces]
    chunk = max(1, 200_000 // max(1, len(faces)))  # points per brute-force block
    exact = np.concatenate(
        [
            point_triangle_distance(p[candidates[k : k + chunk]], tri)
            for k in range(0, len(candidates), chunk)
        ]
    )
    best = float(exact.max())
    if not best > worst:
        return worst, None
    # Of the points at the deepest distance, the one farthest from the part's vertices (then
    # the first in input order): a deterministic choice among equally deep points.
    tied = p[candidates[exact == best]]
    corners = np.asarray(part.vertices, np.float64)[np.unique(faces)]
    bound = np.sqrt(((tied[:, None, :] - corners[None]) ** 2).sum(-1).min(1))
    return best, tied[int(np.argsort(-bound, kind="stable")[0])]


_PROBE = 1e-5  # m, edge of the probe cube whose FCL distance to a mesh gives a point's depth


def _probe_distances(
    p: np.ndarray, part: Mesh, models: dict[int, CollisionModel]
) -> npt.NDArray[np.float64]:
    """(N,) FCL distance (m) of a probe cube (edge :data:`_PROBE`) centred at each point ``p``
    to ``part``'s triangles; ``models`` caches the collision models (the probe under -1)."""
    if id(part) not in models:
        models[id(part)] = CollisionModel(part)
    if -1 not in models:
        models[-1] = CollisionModel(make_box([_PROBE, _PROBE, _PROBE]))
    X = np.repeat(np.eye(4)[None], len(p), axis=0)
    X[:, :3, 3] = p
    found = distance(models[-1], X, models[id(part)], np.eye(4), num_threads=1).distance
    return np.asarray(found, np.float64)


def _deepest_fcl(
    p: np.ndarray, part: Mesh, worst: float, models: dict[int, CollisionModel]
) -> tuple[float, np.ndarray | None]:
    """:func:`_deepest` with each point's depth from FCL: the distance of a tiny probe cube at
    the point to ``part``'s triangles (a BVH search instead of every triangle)."""
    d = _probe_distances(p, part, models)
    i = int(np.argmax(d))
    if d[i] + 0.5 * _PROBE <= worst:
        return worst, None
    return float(d[i]) + 0.5 * _PROBE, p[i]


def _closest_point(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(3,) the nearest point to ``p`` (3,) on the (F, 3, 3) triangles (brute force)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    ab, ac = b - a, c - a
    n = np.cross(ab, ac)
    nn = np.maximum(np.einsum("fk,fk->f", n, n), 1e-300)
    q = p - (np.einsum("fk,fk->f", p - a, n) / nn)[:, None] * n
    v2 = q - a
    d00, d01, d11 = (np.einsum("fk,fk->f", x, y) for x, y in ((ab, ab), (ab, ac), (ac, ac)))
    d20, d21 = np.einsum("fk,fk->f", v2, ab), np.einsum("fk,fk->f", v2, ac)
    den = np.maximum(d00 * d11 - d01 * d01, 1e-300)
    v = (d11 * d20 - d01 * d21) / den
    w = (d00 * d21 - d01 * d20) / den
    candidates = [np.where(((v >= 0) & (w >= 0) & (v + w <= 1))[:, None], q, np.inf)]
    for s, e in ((a, b), (b, c), (c, a)):
        se = e - s
        u = np.einsum("fk,fk->f", p - s, se) / np.maximum(np.einsum("fk,fk->f", se, se), 1e-300)
        candidates.append(s + np.clip(u, 0.0, 1.0)[:, None] * se)
    points = np.concatenate(candidates)
    dist = np.linalg.norm(points - p, axis=1)
    return np.asarray(points[int(np.argmin(np.where(np.isfinite(dist), dist, np.inf)))])
