"""Builders of closed, outward-wound triangle meshes for the procedural object library.

Every builder returns a :class:`Mesh`: vertex positions in metres (float64, shape (V, 3)),
triangles as vertex indices (int32, shape (F, 3)) wound counter-clockwise seen from outside, so
that face normals point out of the solid and the signed volume is positive, and optionally
per-vertex texture coordinates (float32, shape (V, 2)).

Texture-coordinate convention (OBJ / OpenGL): ``u`` grows to the right of the image, ``v`` grows
upwards, ``v = 0`` is the *last* (bottom) image row and ``v = 1`` the first (top) row.

A mesh with texture coordinates may hold several vertices at exactly the same position (UV
seams, the copies of a pole). Positions that belong together are always bit-identical, so the
mesh is watertight once vertices are welded by position (:func:`weld`).

The frame of a builder's output is the one stated in its docstring; the library
(:mod:`mgn.objects.library`) re-centres every finished object on its bounding-box centre.

Booleans (:func:`union`, :func:`difference`) go through ``manifold3d``, whose results are
manifold, free of self-intersections and deterministic. Everything else is plain numpy.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import manifold3d
import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError

__all__ = [
    "BOX_FACES",
    "Mesh",
    "box_atlas_cell",
    "difference",
    "ensure_min_faces",
    "extrude",
    "grid_box",
    "loft",
    "parallel_transport_frames",
    "revolve",
    "rings_to_mesh",
    "rotation_matrix",
    "rounded_box",
    "signed_volume",
    "star_blob",
    "subdivide",
    "superellipsoid",
    "sweep_circle",
    "sweep_hollow",
    "union",
    "weld",
]


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh.

    Attributes:
        vertices: (V, 3) float64 positions in metres.
        faces: (F, 3) int32 vertex indices, counter-clockwise seen from outside.
        uvs: (V, 2) float32 texture coordinates in [0, 1] (OBJ convention, see module doc), or
            ``None``.
    """

    vertices: np.ndarray
    faces: np.ndarray
    uvs: np.ndarray | None = None

    def __post_init__(self) -> None:
        v = np.ascontiguousarray(self.vertices, dtype=np.float64).reshape(-1, 3)
        f = np.ascontiguousarray(self.faces, dtype=np.int32).reshape(-1, 3)
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "faces", f)
        if self.uvs is not None:
            uv = np.ascontiguousarray(self.uvs, dtype=np.float32).reshape(-1, 2)
            if len(uv) != len(v):
                raise InvalidArgumentError(
                    f"uvs has {len(uv)} rows but the mesh has {len(v)} vertices"
                )
            object.__setattr__(self, "uvs", uv)

    @property
    def signed_volume(self) -> float:
        """Signed enclosed volume in m^3 (positive for an outward-wound closed mesh)."""
        return signed_volume(self.vertices, self.faces)

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) array: axis-aligned minimum and maximum corner, metres."""
        return np.stack([self.vertices.min(axis=0), self.vertices.max(axis=0)])

    def translated(self, offset: Sequence[float]) -> Mesh:
        """This mesh moved by ``offset`` (metres)."""
        return Mesh(self.vertices + np.asarray(offset, dtype=np.float64), self.faces, self.uvs)

    def transformed(self, rotation: np.ndarray, offset: Sequence[float] = (0.0, 0.0, 0.0)) -> Mesh:
        """This mesh mapped by ``x -> rotation @ x + offset``.

        ``rotation`` is any invertible 3x3 matrix; a mirroring one (negative determinant) also
        reverses the triangles so that they stay outward-wound.
        """
        r = np.asarray(rotation, dtype=np.float64).reshape(3, 3)
        v = self.vertices @ r.T + np.asarray(offset, dtype=np.float64)
        f = self.faces if np.linalg.det(r) > 0 else self.faces[:, ::-1]
        return Mesh(v, f, self.uvs)

    def flipped(self) -> Mesh:
        """The same surface with every triangle's winding reversed."""
        return Mesh(self.vertices, self.faces[:, ::-1], self.uvs)

    def oriented_outward(self) -> Mesh:
        """This mesh, reversed if needed so that its signed volume is positive.

        Only meaningful for a closed, consistently wound mesh.
        """
        return self.flipped() if self.signed_volume < 0 else self


def rotation_matrix(axis: npt.ArrayLike, angle: float) -> np.ndarray:
    """3x3 rotation by ``angle`` radians about ``axis`` (right-hand rule)."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    out: np.ndarray = np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)
    return out


def signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Signed volume (m^3) enclosed by a closed triangle mesh (divergence theorem)."""
    v = np.asarray(vertices, dtype=np.float64)
    t = v[np.asarray(faces)]
    return float(np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum() / 6.0)


def weld(mesh: Mesh) -> Mesh:
    """Merge vertices whose positions are bit-identical; texture coordinates are dropped.

    Vertices keep the order of their first occurrence, so the result is deterministic.
    """
    _, first, inverse = np.unique(mesh.vertices, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    new_index = rank[inverse.reshape(-1)]
    vertices = mesh.vertices[first[order]]
    return Mesh(vertices, new_index[mesh.faces])


def subdivide(mesh: Mesh) -> Mesh:
    """Split every triangle into four at its edge midpoints (the surface is unchanged).

    Works on meshes with texture seams: midpoints of edges whose end positions coincide are
    computed from identical numbers, so they coincide as well.
    """
    f = mesh.faces.astype(np.int64)
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    key = np.sort(edges, axis=1)
    uniq, inverse = np.unique(key, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    nv = len(mesh.vertices)
    mid_v = 0.5 * (mesh.vertices[uniq[:, 0]] + mesh.vertices[uniq[:, 1]])
    vertices = np.concatenate([mesh.vertices, mid_v])
    uvs = None
    if mesh.uvs is not None:
        mid_uv = 0.5 * (mesh.uvs[uniq[:, 0]] + mesh.uvs[uniq[:, 1]])
        uvs = np.concatenate([mesh.uvs, mid_uv])
    nf = len(f)
    m01, m12, m20 = (nv + inverse[i * nf : (i + 1) * nf] for i in range(3))
    a, b, c = f[:, 0], f[:, 1], f[:, 2]
    faces = np.concatenate(
        [
            np.stack([a, m01, m20], axis=1),
            np.stack([m01, b, m12], axis=1),
            np.stack([m20, m12, c], axis=1),
            np.stack([m01, m12, m20], axis=1),
        ]
    )
    return Mesh(vertices, faces, uvs)


def ensure_min_faces(mesh: Mesh, min_faces: int) -> Mesh:
    """Subdivide (see :func:`subdivide`) until the mesh has at least ``min_faces`` triangles."""
    while len(mesh.faces) < min_faces:
        mesh = subdivide(mesh)
    return mesh


# ----------------------------------------------------------------------------------------------
# Ring-based surfaces: revolve, loft, sweeps
# ----------------------------------------------------------------------------------------------


def _band(a: np.ndarray, b: np.ndarray, wrap: bool) -> np.ndarray:
    """Triangles joining two index rings of equal length (quad a[j], a[j+1], b[j+1], b[j])."""
    if wrap:
        a0, a1, b0, b1 = a, np.roll(a, -1), b, np.roll(b, -1)
    else:
        a0, a1, b0, b1 = a[:-1], a[1:], b[:-1], b[1:]
    return np.concatenate([np.stack([a0, a1, b1], axis=1), np.stack([a0, b1, b0], axis=1)])


def rings_to_mesh(
    rings: np.ndarray,
    *,
    closed: bool = False,
    start_cap: np.ndarray | None = None,
    end_cap: np.ndarray | None = None,
) -> Mesh:
    """Stitch a sequence of closed vertex rings into a surface.

    Args:
        rings: (K, n, 3) positions, metres; ring k is joined to ring k+1 by a band of quads.
        closed: also join the last ring back to the first (a torus-like surface, no caps).
        start_cap: a point (3,) closing ring 0 with a fan (a pole), or ``None`` for no cap.
        end_cap: a point (3,) closing ring K-1 with a fan, or ``None``.

    Returns:
        The mesh, oriented so that its signed volume is positive (the caller provides rings that
        make a closed surface; the orientation of the rings themselves does not matter).
    """
    rings = np.asarray(rings, dtype=np.float64)
    k, n, _ = rings.shape
    idx = np.arange(k * n).reshape(k, n)
    parts = [rings.reshape(-1, 3)]
    tris = [_band(idx[i], idx[i + 1], True) for i in range(k - 1)]
    if closed:
        tris.append(_band(idx[k - 1], idx[0], True))
    nxt = k * n
    if start_cap is not None:
        ring = idx[0]
        tris.append(np.stack([np.full(n, nxt), np.roll(ring, -1), ring], axis=1))
        parts.append(np.asarray(start_cap, dtype=np.float64).reshape(1, 3))
        nxt += 1
    if end_cap is not None:
        ring = idx[k - 1]
        tris.append(np.stack([np.full(n, nxt), ring, np.roll(ring, -1)], axis=1))
        parts.append(np.asarray(end_cap, dtype=np.float64).reshape(1, 3))
    return Mesh(np.concatenate(parts), np.concatenate(tris)).oriented_outward()


def revolve(
    profile: npt.ArrayLike,
    segments: int = 64,
    *,
    closed: bool = False,
    with_uv: bool = False,
) -> Mesh:
    """Surface of revolution about the z axis.

    Args:
        profile: (N, 2) points (r, z) in metres in the half plane r >= 0. Open profile
            (``closed=False``): the first and last points lie on the axis (r == 0) and become the
            poles, all other points have r > 0. Closed profile: a simple loop with every r > 0
            (e.g. a ring or a pipe). The profile, closed by the axis, must be a simple polygon.
        segments: number of angular steps around the axis.
        closed: see ``profile``.
        with_uv: add cylindrical texture coordinates: u = angle / 2 pi (starting at +x,
            counter-clockwise seen from +z), v = arc length along the profile / total length
            (v = 0 at the first profile point). The seam at u = 0/1 and the poles are duplicated.

    Returns:
        The mesh in the profile's frame (axis = z).
    """
    p = np.asarray(profile, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 3:
        raise InvalidArgumentError("profile must be an (N >= 3, 2) array of (r, z)")
    if closed:
        if np.any(p[:, 0] <= 0):
            raise InvalidArgumentError("a closed profile must have r > 0 everywhere")
        ring_pts, pole0, pole1 = p, None, None
    else:
        if p[0, 0] != 0.0 or p[-1, 0] != 0.0 or np.any(p[1:-1, 0] <= 0):
            raise InvalidArgumentError(
                "an open profile starts and ends on the axis (r == 0), r > 0 between"
            )
        ring_pts, pole0, pole1 = p[1:-1], p[0], p[-1]
    theta = np.arange(segments) * (2.0 * np.pi / segments)
    c, s = np.cos(theta), np.sin(theta)
    rings = np.stack(
        [
            ring_pts[:, :1] * c[None, :],
            ring_pts[:, :1] * s[None, :],
            np.repeat(ring_pts[:, 1:], segments, 1),
        ],
        axis=2,
    )
    if not with_uv:
        return rings_to_mesh(
            rings,
            closed=closed,
            start_cap=None if pole0 is None else np.array([0.0, 0.0, pole0[1]]),
            end_cap=None if pole1 is None else np.array([0.0, 0.0, pole1[1]]),
        )
    # Textured variant: one extra seam column (a bit-identical copy of column 0) and, for open
    # profiles, one pole vertex per angular step.
    loop = np.concatenate([p, p[:1]]) if closed else p
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(loop, axis=0), axis=1))])
    v_all = arc / arc[-1]
    v_rings = v_all[: len(p)] if closed else v_all[1:-1]
    k = len(ring_pts)
    rings_uv = np.concatenate([rings, rings[:, :1]], axis=1)  # (k, segments + 1, 3)
    n = segments + 1
    idx = np.arange(k * n).reshape(k, n)
    verts = [rings_uv.reshape(-1, 3)]
    u = np.arange(n) / segments
    uvs = [np.stack([np.tile(u, k), np.repeat(v_rings, n)], axis=1)]
    tris = [_band(idx[i], idx[i + 1], False) for i in range(k - 1)]
    if closed:
        last = k * n
        verts.append(rings_uv[0])
        uvs.append(np.stack([u, np.ones(n)], axis=1))
        tris.append(_band(idx[k - 1], np.arange(last, last + n), False))
    else:
        assert pole0 is not None
        assert pole1 is not None
        uc = (np.arange(segments) + 0.5) / segments
        base = k * n
        poles0 = np.arange(base, base + segments)
        verts.append(np.tile([0.0, 0.0, pole0[1]], (segments, 1)))
        uvs.append(np.stack([uc, np.zeros(segments)], axis=1))
        tris.append(np.stack([poles0, idx[0][1:], idx[0][:-1]], axis=1))
        poles1 = np.arange(base + segments, base + 2 * segments)
        verts.append(np.tile([0.0, 0.0, pole1[1]], (segments, 1)))
        uvs.append(np.stack([uc, np.ones(segments)], axis=1))
        tris.append(np.stack([poles1, idx[k - 1][:-1], idx[k - 1][1:]], axis=1))
    mesh = Mesh(np.concatenate(verts), np.concatenate(tris), np.clip(np.concatenate(uvs), 0.0, 1.0))
    return mesh.oriented_outward()


def loft(rings: np.ndarray, *, caps: bool = True) -> Mesh:
    """Closed surface through a sequence of closed rings, each capped by a fan at its centroid.

    Args:
        rings: (K, n, 3) positions in metres. Consecutive rings must not cross each other and
            the first and last rings must be planar and star-shaped about their centroids.
        caps: close both ends (otherwise the result is open).
    """
    rings = np.asarray(rings, dtype=np.float64)
    return rings_to_mesh(
        rings,
        start_cap=rings[0].mean(axis=0) if caps else None,
        end_cap=rings[-1].mean(axis=0) if caps else None,
    )


def parallel_transport_frames(path: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rotation-minimising frames along a polyline.

    Args:
        path: (K, 3) points in metres, K >= 2, no two consecutive points equal.

    Returns:
        (tangents, normals, binormals), each (K, 3) unit vectors; the tangent at an interior
        point is the bisector of its two segments.
    """
    path = np.asarray(path, dtype=np.float64)
    seg = np.diff(path, axis=0)
    seg /= np.linalg.norm(seg, axis=1, keepdims=True)
    tan = np.empty_like(path)
    tan[0], tan[-1] = seg[0], seg[-1]
    tan[1:-1] = seg[:-1] + seg[1:]
    tan /= np.linalg.norm(tan, axis=1, keepdims=True)
    helper = np.eye(3)[int(np.argmin(np.abs(tan[0])))]
    nrm = np.empty_like(path)
    n0 = helper - tan[0] * np.dot(helper, tan[0])
    nrm[0] = n0 / np.linalg.norm(n0)
    for i in range(1, len(path)):
        axis = np.cross(tan[i - 1], tan[i])
        sin_a = np.linalg.norm(axis)
        cos_a = float(np.clip(np.dot(tan[i - 1], tan[i]), -1.0, 1.0))
        n = nrm[i - 1]
        if sin_a > 1e-12:
            n = rotation_matrix(axis, np.arctan2(sin_a, cos_a)) @ n
        n = n - tan[i] * np.dot(n, tan[i])
        nrm[i] = n / np.linalg.norm(n)
    return tan, nrm, np.cross(tan, nrm)


def _tube_rings(path: np.ndarray, radius: np.ndarray, segments: int) -> np.ndarray:
    _, nrm, bin_ = parallel_transport_frames(path)
    phi = np.arange(segments) * (2.0 * np.pi / segments)
    c, s = np.cos(phi), np.sin(phi)
    offs = c[None, :, None] * nrm[:, None, :] + s[None, :, None] * bin_[:, None, :]
    out: np.ndarray = path[:, None, :] + radius[:, None, None] * offs
    return out


def sweep_circle(path: npt.ArrayLike, radius: float | Sequence[float], segments: int = 16) -> Mesh:
    """Solid circular tube along a polyline, both ends closed by flat caps.

    Args:
        path: (K, 3) centre-line points, metres. Its radius of curvature must exceed the tube
            radius and distinct parts of the path must stay more than two radii apart.
        radius: tube radius in metres, a scalar or one value per path point.
        segments: points around each cross-section.
    """
    p = np.asarray(path, dtype=np.float64)
    r = np.broadcast_to(np.asarray(radius, dtype=np.float64), (len(p),))
    rings = _tube_rings(p, r, segments)
    return rings_to_mesh(rings, start_cap=p[0], end_cap=p[-1])


def sweep_hollow(
    path: npt.ArrayLike, outer_radius: float, inner_radius: float, segments: int = 32
) -> Mesh:
    """Hollow circular tube (a pipe) along a polyline, closed by flat annular end faces.

    Args:
        path: (K, 3) centre-line points, metres (see :func:`sweep_circle`).
        outer_radius: metres.
        inner_radius: metres, 0 < inner_radius < outer_radius.
        segments: points around each cross-section.
    """
    if not 0.0 < inner_radius < outer_radius:
        raise InvalidArgumentError("need 0 < inner_radius < outer_radius")
    p = np.asarray(path, dtype=np.float64)
    k = len(p)
    outer = _tube_rings(p, np.full(k, outer_radius), segments)
    inner = _tube_rings(p, np.full(k, inner_radius), segments)
    return rings_to_mesh(np.concatenate([outer, inner[::-1]]), closed=True)


# ----------------------------------------------------------------------------------------------
# Extrusion
# ----------------------------------------------------------------------------------------------


def _loop_area(loop: np.ndarray) -> float:
    x, y = loop[:, 0], loop[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def extrude(
    outer: npt.ArrayLike,
    holes: Sequence[npt.ArrayLike] = (),
    height: float = 0.01,
    *,
    layers: int = 1,
) -> Mesh:
    """Prism from a planar polygon with optional holes, extruded along +z from z = 0 to ``height``.

    Args:
        outer: (N, 2) outer boundary (x, y) in metres, either orientation, not repeated at the end.
        holes: hole boundaries, each (M, 2), strictly inside ``outer`` and disjoint.
        height: extrusion length, metres (> 0).
        layers: number of slices of the side walls along z (more triangles, same shape).
    """
    if height <= 0:
        raise InvalidArgumentError("height must be > 0")
    loops = [np.asarray(outer, dtype=np.float64)]
    if _loop_area(loops[0]) < 0:
        loops[0] = loops[0][::-1]
    for h in holes:
        h = np.asarray(h, dtype=np.float64)
        loops.append(h[::-1] if _loop_area(h) > 0 else h)  # holes clockwise
    pts = np.concatenate(loops)
    tri = np.asarray(manifold3d.triangulate([lp.copy() for lp in loops]), dtype=np.int64)
    n = len(pts)
    zs = np.linspace(0.0, height, layers + 1)
    verts = np.concatenate([np.column_stack([pts, np.full(n, z)]) for z in zs])
    faces = [tri[:, ::-1], tri + layers * n]  # bottom faces down, top faces up
    start = 0
    for lp in loops:
        m = len(lp)
        ring = np.arange(start, start + m)
        for layer in range(layers):
            a = ring + layer * n
            b = np.roll(ring, -1) + layer * n
            # loop runs with the material on its left, so (b - a) x z points outward
            faces.append(np.stack([a, b, b + n], axis=1))
            faces.append(np.stack([a, b + n, a + n], axis=1))
        start += m
    return Mesh(verts, np.concatenate(faces)).oriented_outward()


# ----------------------------------------------------------------------------------------------
# Lattice boxes: plain (texturable), rounded, star-shaped blobs
# ----------------------------------------------------------------------------------------------

#: The six faces of a lattice box in atlas order: (name, normal axis, sign, u axis, u sign,
#: v axis, v sign), with (u direction) x (v direction) = outward normal. Side faces have v = +z.
BOX_FACES: tuple[tuple[str, int, int, int, int, int, int], ...] = (
    ("+x", 0, +1, 1, +1, 2, +1),
    ("-x", 0, -1, 1, -1, 2, +1),
    ("+y", 1, +1, 0, -1, 2, +1),
    ("-y", 1, -1, 0, +1, 2, +1),
    ("+z", 2, +1, 0, +1, 1, +1),
    ("-z", 2, -1, 0, +1, 1, -1),
)


def box_atlas_cell(face_index: int) -> tuple[float, float, float, float]:
    """UV rectangle (u0, v0, u1, v1) of a box face in the 3 x 2 texture atlas.

    Face k (order of :data:`BOX_FACES`) occupies column k % 3 and image row k // 3 (row 0 at the
    top of the image, i.e. v in [0.5, 1]).
    """
    col, row = face_index % 3, face_index // 3
    return col / 3.0, 1.0 - (row + 1) / 2.0, (col + 1) / 3.0, 1.0 - row / 2.0


def _lattice_faces(coords: Sequence[np.ndarray]) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per box face: lattice indices (nu+1, nv+1, 3), normalised (s, t) in [0,1], triangles."""
    out = []
    for _, ax, sgn, uax, usgn, vax, vsgn in BOX_FACES:
        nu, nv = len(coords[uax]) - 1, len(coords[vax]) - 1
        iu = np.arange(nu + 1) if usgn > 0 else np.arange(nu, -1, -1)
        iv = np.arange(nv + 1) if vsgn > 0 else np.arange(nv, -1, -1)
        lat = np.zeros((nu + 1, nv + 1, 3), dtype=np.int64)
        lat[..., ax] = len(coords[ax]) - 1 if sgn > 0 else 0
        lat[..., uax] = iu[:, None]
        lat[..., vax] = iv[None, :]
        cu = coords[uax][iu]
        cv = coords[vax][iv]
        s = (cu - cu[0]) / (cu[-1] - cu[0])
        t = (cv - cv[0]) / (cv[-1] - cv[0])
        st = np.stack(np.broadcast_arrays(s[:, None], t[None, :]), axis=-1)
        grid = np.arange((nu + 1) * (nv + 1)).reshape(nu + 1, nv + 1)
        a, b = grid[:-1, :-1].ravel(), grid[1:, :-1].ravel()
        c, d = grid[1:, 1:].ravel(), grid[:-1, 1:].ravel()
        tris = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
        out.append((lat.reshape(-1, 3), st.reshape(-1, 2), tris))
    return out


def _lattice_mesh(
    coords: Sequence[np.ndarray],
    position: Callable[[np.ndarray], np.ndarray],
    *,
    with_uv: bool = False,
    uv_inset: float = 0.004,
) -> Mesh:
    """Surface of a lattice box mapped by ``position`` (lattice coordinates (M,3) -> xyz (M,3))."""
    faces_data = _lattice_faces(coords)
    if with_uv:
        verts, uvs, tris, base = [], [], [], 0
        for k, (lat, st, tr) in enumerate(faces_data):
            xyz = np.stack([coords[i][lat[:, i]] for i in range(3)], axis=1)
            verts.append(position(xyz))
            u0, v0, u1, v1 = box_atlas_cell(k)
            s = uv_inset + st * (1.0 - 2.0 * uv_inset)
            uvs.append(np.stack([u0 + s[:, 0] * (u1 - u0), v0 + s[:, 1] * (v1 - v0)], axis=1))
            tris.append(tr + base)
            base += len(lat)
        return Mesh(np.concatenate(verts), np.concatenate(tris), np.concatenate(uvs))
    dims = np.array([len(c) for c in coords], dtype=np.int64)
    keys, tris, base = [], [], 0
    for lat, _, tr in faces_data:
        keys.append((lat[:, 0] * dims[1] + lat[:, 1]) * dims[2] + lat[:, 2])
        tris.append(tr + base)
        base += len(lat)
    key = np.concatenate(keys)
    uniq, inverse = np.unique(key, return_inverse=True)
    lat = np.stack(
        [uniq // (dims[1] * dims[2]), (uniq // dims[2]) % dims[1], uniq % dims[2]], axis=1
    )
    xyz = np.stack([coords[i][lat[:, i]] for i in range(3)], axis=1)
    return Mesh(position(xyz), inverse.reshape(-1)[np.concatenate(tris)])


def grid_box(
    size: Sequence[float],
    max_edge: float = 0.012,
    *,
    min_divisions: int = 4,
    with_uv: bool = False,
) -> Mesh:
    """Axis-aligned cuboid centred on the origin, each face a regular grid of quads.

    Args:
        size: (sx, sy, sz) edge lengths, metres.
        max_edge: longest grid step, metres.
        min_divisions: fewest grid steps along any edge.
        with_uv: per-face texture coordinates in the 3 x 2 atlas of :func:`box_atlas_cell`;
            vertices on box edges are then duplicated per face (bit-identical positions).
    """
    half = 0.5 * np.asarray(size, dtype=np.float64)
    coords = [
        np.linspace(-h, h, max(min_divisions, int(np.ceil(2 * h / max_edge))) + 1) for h in half
    ]
    for c, h in zip(coords, half, strict=True):
        c[0], c[-1] = -h, h
    return _lattice_mesh(coords, lambda x: x, with_uv=with_uv)


def _rounded_axis(half: float, radius: float, flat_steps: int, round_steps: int) -> np.ndarray:
    inner = half - radius
    flat = np.linspace(-inner, inner, flat_steps + 1)
    ang = np.arange(1, round_steps + 1) * (0.25 * np.pi / round_steps)
    band = inner + radius * np.tan(ang)
    return np.concatenate([-band[::-1], flat, band])


def rounded_box(
    size: Sequence[float],
    radius: float,
    *,
    max_edge: float = 0.01,
    round_steps: int = 4,
) -> Mesh:
    """Cuboid centred on the origin with all edges and corners rounded by ``radius`` (metres).

    The surface is the set of points at distance ``radius`` from the inner box of half-size
    ``size / 2 - radius``; it is built on a lattice of the outer box and projected, so it is
    watertight and free of self-intersections by construction.

    Args:
        size: (sx, sy, sz) outer edge lengths, metres.
        radius: rounding radius, 0 < radius < min(size) / 2.
        max_edge: longest step on the flat parts, metres.
        round_steps: steps over each 45 degrees of a rounded edge.
    """
    half = 0.5 * np.asarray(size, dtype=np.float64)
    if not 0.0 < radius < half.min():
        raise InvalidArgumentError("rounded_box needs 0 < radius < min(size) / 2")
    inner = half - radius
    coords = [
        _rounded_axis(h, radius, max(1, int(np.ceil(2 * (h - radius) / max_edge))), round_steps)
        for h in half
    ]

    def position(x: np.ndarray) -> np.ndarray:
        core = np.clip(x, -inner, inner)
        d = x - core
        out: np.ndarray = core + radius * d / np.linalg.norm(d, axis=1, keepdims=True)
        return out

    return _lattice_mesh(coords, position)


def _cube_sphere_dirs(steps: int) -> Mesh:
    """Unit sphere from an equal-angle cube lattice (closed, outward-wound)."""
    c = np.tan(np.linspace(-0.25 * np.pi, 0.25 * np.pi, steps + 1))
    c[0], c[-1] = -1.0, 1.0
    return _lattice_mesh([c, c, c], lambda x: x / np.linalg.norm(x, axis=1, keepdims=True))


def star_blob(radius_of: Callable[[np.ndarray], np.ndarray], steps: int = 16) -> Mesh:
    """Star-shaped closed surface about the origin: the point of direction d lies at radius_of(d).

    Args:
        radius_of: maps (M, 3) unit directions to (M,) positive radii in metres.
        steps: lattice steps along each cube edge (6 * steps^2 * 2 triangles).
    """
    sphere = _cube_sphere_dirs(steps)
    r = np.asarray(radius_of(sphere.vertices), dtype=np.float64)
    if np.any(~np.isfinite(r)) or np.any(r <= 0):
        raise InvalidArgumentError("radius_of must return finite positive radii")
    return Mesh(sphere.vertices * r[:, None], sphere.faces).oriented_outward()


def superellipsoid(
    radii: Sequence[float],
    e1: float = 1.0,
    e2: float = 1.0,
    *,
    steps: int = 16,
    noise: Callable[[np.ndarray], np.ndarray] | None = None,
) -> Mesh:
    """Superellipsoid centred on the origin, optionally with a smooth radial perturbation.

    The surface is ((|x/a|^(2/e2) + |y/b|^(2/e2))^(e2/e1) + |z/c|^(2/e1)) = 1.

    Args:
        radii: semi-axes (a, b, c) in metres.
        e1: north-south squareness (1 round, < 1 boxier along z).
        e2: east-west squareness (1 round, < 1 boxier in xy).
        steps: lattice steps per cube edge.
        noise: maps (M, 3) unit directions to (M,) relative radius factors (> 0), e.g. 1 + bumps.
    """
    a, b, c = (float(x) for x in radii)

    def radius_of(d: np.ndarray) -> np.ndarray:
        x = np.abs(d[:, 0]) / a
        y = np.abs(d[:, 1]) / b
        z = np.abs(d[:, 2]) / c
        xy = (x ** (2.0 / e2) + y ** (2.0 / e2)) ** (e2 / e1)
        f = xy + z ** (2.0 / e1)
        r = f ** (-e1 / 2.0)
        out: np.ndarray = r if noise is None else r * noise(d)
        return out

    return star_blob(radius_of, steps)


# ----------------------------------------------------------------------------------------------
# Booleans through manifold3d
# ----------------------------------------------------------------------------------------------


def _to_manifold(mesh: Mesh) -> manifold3d.Manifold:
    m = weld(mesh) if mesh.uvs is not None else mesh
    man = manifold3d.Manifold(
        manifold3d.Mesh64(
            vert_properties=np.ascontiguousarray(m.vertices, dtype=np.float64),
            tri_verts=np.ascontiguousarray(m.faces, dtype=np.uint64),
        )
    )
    if man.status() != manifold3d.Error.NoError or man.is_empty():
        raise InvalidArgumentError(f"mesh is not a closed oriented 2-manifold ({man.status()})")
    return man


def _from_manifold(man: manifold3d.Manifold) -> Mesh:
    if man.status() != manifold3d.Error.NoError:
        raise InvalidArgumentError(f"boolean failed: {man.status()}")
    out = man.to_mesh64()
    v = np.asarray(out.vert_properties, dtype=np.float64)[:, :3]
    f = np.asarray(out.tri_verts, dtype=np.int64)
    return Mesh(v, f)


def union(*meshes: Mesh) -> Mesh:
    """Boolean union of closed meshes (texture coordinates are dropped)."""
    return _from_manifold(
        manifold3d.Manifold.batch_boolean([_to_manifold(m) for m in meshes], manifold3d.OpType.Add)
    )


def difference(base: Mesh, *cutters: Mesh) -> Mesh:
    """Boolean difference ``base - cutters`` of closed meshes (texture coordinates are dropped)."""
    mans = [_to_manifold(base)] + [_to_manifold(m) for m in cutters]
    return _from_manifold(manifold3d.Manifold.batch_boolean(mans, manifold3d.OpType.Subtract))
