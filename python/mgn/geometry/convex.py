"""Convex hulls and approximate convex decomposition (HACD, in the C++ core), with a disk cache.

Parts are closed convex :data:`mgn.Mesh` objects in the input mesh's frame whose union
approximates the mesh; a (nearly) convex mesh gives its single hull. The physics (scene drop,
grasp shake test) uses them as Bullet compound shapes.

Cache: ``$MGN_CACHE_DIR/convex/<sha256>.npz`` (default ``~/.cache/mgn/convex``); the key hashes
the vertices, faces and options, so a changed mesh or option never reads a stale entry.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import io
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.base.atomic import atomic_write_bytes
from mgn.base.core_result import to_core
from mgn.errors import InvalidArgumentError
from mgn.geometry.mesh import Mesh

__all__ = [
    "DROP_DECOMPOSITION",
    "ConvexDecompositionOptions",
    "cache_dir",
    "cached_convex_decomposition",
    "convex_decomposition",
    "convex_hull",
    "drop_contained_parts",
    "hull_distance",
]

#: Bump when the decomposition algorithm changes, so old cache entries are not reused.
_CACHE_VERSION = "hacd-4"


#: The C++ defaults (mgn/geometry/convex_decomposition.hpp), the one place they are written.
_CORE = _core.geometry.ConvexDecompositionOptions()


@dataclass(frozen=True)
class ConvexDecompositionOptions:
    """Options of :func:`convex_decomposition` (C++: mgn/geometry/convex_decomposition.hpp).

    Attributes:
        convex_volume_tolerance: the mesh counts as convex if its hull's volume is at most this
            fraction above the mesh volume (then one part).
        max_concavity: largest concavity allowed in a part, fraction of the bounding-box diagonal.
        min_parts: HACD stops merging at this many parts.
        max_parts: at most this many parts (the concavity bound is relaxed until it holds).
        compactness_weight: weight of the compactness term of HACD's merge cost.
        volume_weight: weight of the volume term of HACD's merge cost.
        extra_concavity_points: HACD samples extra points to measure concavity (better parts,
            slower).
        max_hacd_faces, grid_resolution: larger meshes are simplified for HACD by clustering
            their vertices on a grid of ``grid_resolution`` cells along the bounding-box diagonal
            (part hulls still contain every original vertex).
        merge_volume_tolerance: after HACD, parts are merged greedily (the pair whose merged hull
            adds the least volume first) while the volume added in total stays within this
            fraction of the volume of the mesh's convex hull; fewer parts make the drop much
            cheaper. 0: no merging.
        merge_max_parts: then merge further (cheapest first) until at most this many parts are
            left. 0: no cap.
    """

    convex_volume_tolerance: float = _CORE.convex_volume_tolerance
    max_concavity: float = _CORE.max_concavity
    min_parts: int = _CORE.min_parts
    max_parts: int = _CORE.max_parts
    compactness_weight: float = _CORE.compactness_weight
    volume_weight: float = _CORE.volume_weight
    extra_concavity_points: bool = _CORE.extra_concavity_points
    max_hacd_faces: int = _CORE.max_hacd_faces
    grid_resolution: int = _CORE.grid_resolution
    merge_volume_tolerance: float = _CORE.merge_volume_tolerance
    merge_max_parts: int = _CORE.merge_max_parts

    def to_core(self) -> _core.geometry.ConvexDecompositionOptions:
        """The C++ options (the core checks the ranges when it decomposes)."""
        return to_core(self, _core.geometry.ConvexDecompositionOptions())


#: The decomposition the scene drop uses by default: HACD parts merged while they add at most 10 %
#: of the object's hull volume (mug 27 -> 9 parts, wine glass 32 -> 11, cable coil 30 -> 16). It
#: makes the 20-object drop ~4x cheaper per step (compound-compound pairs dominate); see
#: third_party_notes/bullet.md for the measurements.
DROP_DECOMPOSITION = ConvexDecompositionOptions(merge_volume_tolerance=0.10)


def convex_hull(mesh: Mesh) -> Mesh:
    """Closed, outward-wound convex hull of ``mesh`` (same frame). Raises InvalidArgumentError
    for an empty mesh or coplanar vertices."""
    return _core.geometry.convex_hull(mesh)


def convex_decomposition(
    mesh: Mesh, options: ConvexDecompositionOptions | None = None
) -> list[Mesh]:
    """Convex parts (closed meshes, frame of ``mesh``) whose union approximates ``mesh``.

    Every vertex of ``mesh`` lies in at least one part. Deterministic. Not cached: see
    :func:`cached_convex_decomposition`.
    """
    o = options or ConvexDecompositionOptions()
    return list(_core.geometry.convex_decomposition(mesh, o.to_core()))


def hull_distance(points: npt.ArrayLike, hull: Mesh) -> npt.NDArray[np.float64]:
    """Euclidean distance (m) from each of the (N, 3) ``points`` to the solid convex ``hull``.

    ``hull`` is a closed convex mesh with outward-wound faces (a part of
    :func:`convex_decomposition`, the output of :func:`convex_hull`); a point inside it or on
    its surface is at distance 0. Outside, the distance is the smallest distance to one of its
    triangles (exact for a convex solid). Raises InvalidArgumentError for points that are not
    (N, 3) or a hull without a face of positive area.
    """
    p = np.asarray(points, np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise InvalidArgumentError(f"points: expected shape (N, 3), got {p.shape}")
    v = np.asarray(hull.vertices, np.float64)
    f = np.asarray(hull.faces, np.int64)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    n = np.cross(b - a, c - a)
    area2 = np.linalg.norm(n, axis=1)
    keep = area2 > 1e-12 * max(float(np.max(area2, initial=0.0)), 1e-300)
    if not np.any(keep):
        raise InvalidArgumentError(f"hull {hull.name!r}: expected a face of positive area")
    a, b, c, n = a[keep], b[keep], c[keep], n[keep] / area2[keep, None]
    # Signed distances to the face planes (P, F): all <= 0 means inside the solid.
    plane = p @ n.T - np.einsum("fk,fk->f", n, a)[None, :]
    out = np.zeros(len(p))
    outside = np.max(plane, axis=1, initial=-np.inf) > 0.0
    if not np.any(outside):
        return out
    q = p[outside][:, None, :]  # (Q, 1, 3)

    def segment(s0: npt.NDArray[np.float64], s1: npt.NDArray[np.float64]) -> Any:
        d = s1 - s0
        t = np.einsum("qfk,fk->qf", q - s0, d) / np.maximum(np.einsum("fk,fk->f", d, d), 1e-300)
        t = np.clip(t, 0.0, 1.0)
        return np.linalg.norm(q - (s0 + t[..., None] * d), axis=2)

    best = np.minimum(np.minimum(segment(a, b), segment(b, c)), segment(c, a))
    # The projection onto a face's plane, where it falls inside the triangle.
    h = plane[outside]
    proj = q - h[..., None] * n
    inside = np.ones(h.shape, bool)
    for s0, s1 in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("qfk,fk->qf", np.cross(s1 - s0, proj - s0), n) >= 0.0
    best = np.where(inside, np.minimum(best, np.abs(h)), best)
    out[outside] = np.min(best, axis=1)
    return out


def _volume(part: Mesh) -> float:
    v = np.asarray(part.vertices, np.float64)
    f = np.asarray(part.faces, np.int64)
    return float(np.einsum("fk,fk->", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]]))) / 6.0


def drop_contained_parts(parts: Sequence[Mesh], tolerance: float) -> list[Mesh]:
    """The convex ``parts`` without those that lie inside another within ``tolerance`` (m).

    Parts are visited from the largest volume down (ties: list order); one is dropped when
    every vertex of it is within ``tolerance`` of a part already kept (:func:`hull_distance`),
    which then contains it up to ``tolerance`` (the kept part grown by ``tolerance`` is convex
    and holds its vertices). Kept parts are never dropped later, so the union of the result is
    within ``tolerance`` (Hausdorff distance) of the union of ``parts``, and inside it. Of two
    identical parts the first is kept. The kept parts keep their order. ``tolerance`` >= 0;
    raises InvalidArgumentError otherwise.
    """
    if isinstance(tolerance, bool) or not (
        isinstance(tolerance, (int, float)) and math.isfinite(tolerance) and tolerance >= 0
    ):
        raise InvalidArgumentError(
            f"tolerance: expected a distance >= 0 in metres, got {tolerance!r}"
        )
    parts = list(parts)
    order = sorted(range(len(parts)), key=lambda k: -_volume(parts[k]))
    kept: list[int] = []
    for k in order:
        pts = np.asarray(parts[k].vertices, np.float64)
        if not any(np.all(hull_distance(pts, parts[j]) <= tolerance) for j in kept):
            kept.append(k)
    return [parts[k] for k in sorted(kept)]


def cache_dir() -> Path:
    """Folder of the decomposition cache: ``$MGN_CACHE_DIR/convex`` or ``~/.cache/mgn/convex``."""
    root = os.environ.get("MGN_CACHE_DIR")
    base = Path(root) if root else Path.home() / ".cache" / "mgn"
    return base / "convex"


def _key(mesh: Mesh, o: ConvexDecompositionOptions) -> str:
    h = hashlib.sha256()
    h.update(_CACHE_VERSION.encode())
    h.update(np.ascontiguousarray(mesh.vertices, np.float32).tobytes())
    h.update(np.ascontiguousarray(mesh.faces, np.int32).tobytes())
    h.update(repr(dataclasses.astuple(o)).encode())
    return h.hexdigest()


def _pack(parts: list[Mesh]) -> bytes:
    buf = io.BytesIO()
    np.savez_compressed(
        buf,
        vertices=np.concatenate([p.vertices for p in parts]).astype(np.float32),
        faces=np.concatenate([p.faces for p in parts]).astype(np.int32),
        vertex_counts=np.array([p.num_vertices for p in parts], np.int64),
        face_counts=np.array([p.num_faces for p in parts], np.int64),
    )
    return buf.getvalue()


def _unpack(path: Path, name: str) -> list[Mesh] | None:
    try:
        with np.load(path) as z:
            v, f = z["vertices"], z["faces"]
            vc, fc = z["vertex_counts"], z["face_counts"]
    except (OSError, KeyError, ValueError):
        return None  # unreadable or partial entry: recompute
    parts = []
    vo = np.concatenate([[0], np.cumsum(vc)])
    fo = np.concatenate([[0], np.cumsum(fc)])
    for k in range(len(vc)):
        parts.append(Mesh(v[vo[k] : vo[k + 1]], f[fo[k] : fo[k + 1]], None, [], [], f"{name}_{k}"))
    return parts


def cached_convex_decomposition(
    mesh: Mesh, options: ConvexDecompositionOptions | None = None, *, use_cache: bool = True
) -> list[Mesh]:
    """:func:`convex_decomposition` with a disk cache (see the module doc); written atomically.

    An unwritable cache folder is not an error: the parts are still returned.
    """
    o = options or ConvexDecompositionOptions()
    if not use_cache:
        return convex_decomposition(mesh, o)
    path = cache_dir() / f"{_key(mesh, o)}.npz"
    name = mesh.name or "part"
    if path.is_file():
        parts = _unpack(path, name)
        if parts is not None:
            return parts
    parts = convex_decomposition(mesh, o)
    # A read-only home or a full disk: the cache is an optimisation only.
    with contextlib.suppress(OSError):
        atomic_write_bytes(path, _pack(parts))
    return parts
