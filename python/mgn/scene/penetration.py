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

import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError
from mgn.geometry import Mesh
from mgn.geometry.collision import CollisionModel, distance
from mgn.geometry.raytrace import RayScene
from mgn.objects import ToteSpec

__all__ = [
    "EDGE_SPACING",
    "edge_points",
    "float_gaps",
    "point_triangle_distance",
    "render_penetration",
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
    return best.min(axis=1)


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
        return scene.intersect_all(p, d, num_threads=1).counts() % 2 == 1

    first, second = parity(points, _PARITY[0]), parity(points, _PARITY[1])
    inside = first & second
    split = np.flatnonzero(first != second)  # the third ray decides
    inside[split] = parity(points[split], _PARITY[2])
    return inside


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
    hx, hy, H = 0.5 * tote.inner_length, 0.5 * tote.inner_width, tote.inner_height
    worst = 0.0
    local = [np.asarray(m.vertices, np.float64) for m in meshes]
    poses = [np.asarray(X, np.float64) for X in X_WO]
    world = [v @ X[:3, :3].T + X[:3, 3] for v, X in zip(local, poses, strict=True)]
    samples: dict[int, np.ndarray] = {}  # copies of one object share their mesh
    for m in meshes:
        if id(m) not in samples:
            samples[id(m)] = edge_points(m)
    surface = [samples[id(m)] @ X[:3, :3].T + X[:3, 3] for m, X in zip(meshes, poses, strict=True)]
    for w in world:
        worst = max(worst, float(-w[:, 2].min()))
        low = w[w[:, 2] <= H]
        if len(low) and tote.walls:  # a table top has no walls to penetrate
            worst = max(worst, float((np.abs(low[:, 0]) - hx).max()))
            worst = max(worst, float((np.abs(low[:, 1]) - hy).max()))
    lo = [w.min(axis=0) for w in world]
    hi = [w.max(axis=0) for w in world]
    parts: dict[int, list[tuple[Mesh, RayScene]]] = {}
    split: dict[int, list[tuple[Mesh, RayScene]]] = {}
    for a in range(len(meshes)):
        for b in range(len(meshes)):
            if a == b or np.any(lo[a] > hi[b]) or np.any(lo[b] > hi[a]):
                continue
            # Surface points of a inside b's world bounding box, in b's frame, inside b's local
            # bounding box, then inside b's mesh.
            pa = surface[a]
            pa = pa[np.all((pa >= lo[b]) & (pa <= hi[b]), axis=1)]
            Xb = poses[b]
            pa = (pa - Xb[:3, 3]) @ Xb[:3, :3]
            blo, bhi = local[b].min(axis=0), local[b].max(axis=0)
            pa = pa[np.all((pa >= blo) & (pa <= bhi), axis=1)]
            if len(pa) == 0:
                continue
            if b not in parts:
                key = id(meshes[b])  # copies of one object share their mesh: split it once
                if key not in split:
                    split[key] = [(m, RayScene(m)) for m in _connected_parts(meshes[b])]
                parts[b] = split[key]
            # A mesh of several closed parts that overlap one another (one object modelled as
            # a union of solids) is tested part by part: the parity of the whole would count a
            # point inside two parts as outside, and coincident faces of two parts as one
            # crossing. A point inside a part sinks into b at least as deep as into that part.
            for part, scene in parts[b]:
                p = pa[_inside(scene, pa)]
                if len(p):
                    worst = _deepest(p, part, worst)
    return max(worst, 0.0)


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
    hx, hy, H = 0.5 * tote.inner_length, 0.5 * tote.inner_width, tote.inner_height
    poses = [np.asarray(X, np.float64) for X in X_WO]
    world = [
        np.asarray(m.vertices, np.float64) @ X[:3, :3].T + X[:3, 3]
        for m, X in zip(meshes, poses, strict=True)
    ]
    gaps = np.zeros(len(meshes))
    for a, w in enumerate(world):
        gap = float(w[:, 2].min())  # a mesh's nearest point to a plane is a vertex
        low = w[w[:, 2] <= H]
        if len(low) and tote.walls:
            gap = min(
                gap, float((hx - np.abs(low[:, 0])).min()), float((hy - np.abs(low[:, 1])).min())
            )
        gaps[a] = gap
    lo = [w.min(axis=0) for w in world]
    hi = [w.max(axis=0) for w in world]
    models: dict[int, CollisionModel] = {}  # copies of one object share their mesh
    for a in range(len(meshes)):
        # Other meshes nearest first by their bounding boxes; a box farther than the gap found
        # so far cannot hold a nearer mesh.
        box_gap = [
            float(np.linalg.norm(np.maximum(np.maximum(lo[b] - hi[a], lo[a] - hi[b]), 0.0)))
            for b in range(len(meshes))
        ]
        for b in sorted(range(len(meshes)), key=lambda b: (box_gap[b], b)):
            if b == a:
                continue
            if box_gap[b] >= gaps[a]:
                break
            for m in (meshes[a], meshes[b]):
                if id(m) not in models:
                    models[id(m)] = CollisionModel(m)
            d = distance(models[id(meshes[a])], poses[a], models[id(meshes[b])], poses[b],
                         num_threads=1)  # fmt: skip
            gaps[a] = min(gaps[a], float(d.distance[0]))
    return np.maximum(gaps, 0.0)


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


def _deepest(p: np.ndarray, part: Mesh, worst: float) -> float:
    """max(``worst``, the largest distance of the points ``p`` (inside ``part``) to the
    surface of ``part``)."""
    # A point's distance to the surface is at most its distance to the nearest vertex
    # (`bound`): points are measured in order of decreasing bound, and once the bound
    # is no more than the deepest penetration found, no later point can exceed it. The
    # result is the brute-force maximum, found with fewer point-triangle distances.
    # (Vertices of the faces only; the bound is widened by far more than the rounding
    # of either distance.)
    faces = np.asarray(part.faces)
    vertices = np.asarray(part.vertices, np.float64)
    corners = vertices[np.unique(faces)]
    bound = np.concatenate(
        [
            np.sqrt(((p[k : k + 64, None, :] - corners[None]) ** 2).sum(-1).min(1))
            for k in range(0, len(p), 64)
        ]
    )
    bound = bound * (1.0 + 1e-9) + 1e-12
    order = np.argsort(-bound, kind="stable")
    p, bound = p[order], bound[order]
    tri = vertices[faces]
    for k in range(0, len(p), 64):
        if bound[k] <= worst:
            break
        worst = max(worst, float(point_triangle_distance(p[k : k + 64], tri).max()))
    return worst
