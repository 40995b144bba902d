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
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mgn import _core
from mgn.base.atomic import atomic_write_bytes
from mgn.base.core_result import to_core
from mgn.geometry.mesh import Mesh

__all__ = [
    "DROP_DECOMPOSITION",
    "ConvexDecompositionOptions",
    "cache_dir",
    "cached_convex_decomposition",
    "convex_decomposition",
    "convex_hull",
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
