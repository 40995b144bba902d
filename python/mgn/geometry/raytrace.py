"""Ray casting against meshes placed in a world frame (Embree, typed façade).

Rays are (N, 3) origins and directions in the world frame W. Directions need not be unit
length; distances are in units of the direction's length (metres for unit directions).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.base.core_result import from_core
from mgn.geometry.mesh import Mesh


@dataclass(frozen=True)
class RayHits:
    """First hit of every ray. Misses have distance +inf, ids -1 and zero point/normal.

    Attributes:
        distance: (N,) float32.
        points: (N, 3) float32 hit points, world frame.
        normals: (N, 3) float32 unit geometric normals (outward for outward-wound meshes).
        instance_ids: (N,) int32 instance id of the mesh hit, -1 on a miss.
        face_ids: (N,) int32 face index within that mesh, -1 on a miss.
        barycentric: (N, 2) float32 (u, v): p = (1-u-v) v0 + u v1 + v v2.
    """

    distance: npt.NDArray[np.float32]
    points: npt.NDArray[np.float32]
    normals: npt.NDArray[np.float32]
    instance_ids: npt.NDArray[np.int32]
    face_ids: npt.NDArray[np.int32]
    barycentric: npt.NDArray[np.float32]

    @property
    def hit(self) -> npt.NDArray[np.bool_]:
        """(N,) bool, True where the ray hit something."""
        return self.instance_ids >= 0


@dataclass(frozen=True)
class RayAllHits:
    """Every hit along every ray, nearest first, in CSR layout.

    The hits of ray ``i`` are entries ``offsets[i]:offsets[i + 1]`` of the other arrays. A ray
    through a shared edge or vertex is reported once.
    """

    offsets: npt.NDArray[np.int64]
    distance: npt.NDArray[np.float32]
    points: npt.NDArray[np.float32]
    normals: npt.NDArray[np.float32]
    instance_ids: npt.NDArray[np.int32]
    face_ids: npt.NDArray[np.int32]
    ray_ids: npt.NDArray[np.int32]

    def counts(self) -> npt.NDArray[np.int64]:
        """(N,) number of hits of each ray."""
        return np.diff(self.offsets)


class RayScene:
    """An immutable ray-casting scene of meshes, each placed at a world pose with an instance id.

    Built once (the geometry is copied), then any number of threads may cast rays. Long calls
    release the GIL. ``num_threads=0`` uses every hardware thread; results do not depend on it.

    Args:
        meshes: one mesh or a sequence of meshes.
        poses: None (identity) or (K, 4, 4) float64 poses ``X_WO`` of the K meshes.
        instance_ids: None (0..K-1) or K ids >= 0 reported for hits on each mesh.
    """

    def __init__(
        self,
        meshes: Mesh | Sequence[Mesh],
        poses: npt.ArrayLike | None = None,
        instance_ids: Sequence[int] | None = None,
    ) -> None:
        mesh_list = [meshes] if isinstance(meshes, Mesh) else list(meshes)
        if poses is not None:
            poses = np.asarray(poses, dtype=np.float64)
            if poses.ndim == 2:
                poses = poses[None]
        self._meshes = mesh_list  # keeps the Python objects alive for repr/introspection
        self._scene = _core.raytrace.RayScene(
            mesh_list, poses, None if instance_ids is None else [int(i) for i in instance_ids]
        )

    @property
    def num_geometries(self) -> int:
        return int(self._scene.num_geometries)

    @property
    def num_triangles(self) -> int:
        return int(self._scene.num_triangles)

    @property
    def bounds(self) -> npt.NDArray[np.float64]:
        """(2, 3) world-frame bounds: row 0 min, row 1 max (m)."""
        return self._scene.bounds

    def intersect(
        self,
        origins: npt.ArrayLike,
        directions: npt.ArrayLike,
        *,
        tnear: float = 0.0,
        tfar: float = float("inf"),
        coherent: bool = False,
        num_threads: int = 0,
    ) -> RayHits:
        """First hit of each ray within [tnear, tfar].

        ``coherent=True`` casts packets of 16 rays; use it for camera or parallel rays (same
        results, faster).
        """
        out = self._scene.intersect(origins, directions, tnear, tfar, coherent, num_threads)
        return from_core(RayHits, out)

    def intersect_ids(
        self,
        origins: npt.ArrayLike,
        directions: npt.ArrayLike,
        *,
        tnear: float = 0.0,
        tfar: float = float("inf"),
        coherent: bool = False,
        num_threads: int = 0,
    ) -> tuple[npt.NDArray[np.int32], npt.NDArray[np.int32]]:
        """``(instance_ids, face_ids)`` of the first hit of each ray, both (N,) int32 and -1 on a
        miss: identical to :meth:`intersect`'s, faster when nothing else is needed (distances,
        points, normals and barycentrics are not computed)."""
        return self._scene.intersect_ids(origins, directions, tnear, tfar, coherent, num_threads)

    def occluded(
        self,
        origins: npt.ArrayLike,
        directions: npt.ArrayLike,
        *,
        tnear: float = 0.0,
        tfar: float = float("inf"),
        coherent: bool = False,
        num_threads: int = 0,
    ) -> npt.NDArray[np.bool_]:
        """(N,) bool: does each ray hit anything within [tnear, tfar]? Cheaper than intersect."""
        return self._scene.occluded(origins, directions, tnear, tfar, coherent, num_threads)

    def intersect_all(
        self,
        origins: npt.ArrayLike,
        directions: npt.ArrayLike,
        *,
        max_hits_per_ray: int = 64,
        tnear: float = 0.0,
        tfar: float = float("inf"),
        num_threads: int = 0,
    ) -> RayAllHits:
        """Every hit along each ray (at most ``max_hits_per_ray`` nearest), sorted by distance."""
        out = self._scene.intersect_all(
            origins, directions, max_hits_per_ray, tnear, tfar, num_threads
        )
        return from_core(RayAllHits, out)

    def __repr__(self) -> str:
        return f"RayScene(geometries={self.num_geometries}, triangles={self.num_triangles})"


def camera_rays(
    K: npt.ArrayLike, width: int, height: int, X_WC: npt.ArrayLike
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
    """Rays of a pinhole camera through pixel centres, row-major (pixel (u, v) -> v*width+u).

    Camera frame is OpenCV (x right, y down, z forward). ``K`` is the 3x3 intrinsic matrix in
    pixels, ``X_WC`` the (4, 4) camera pose in the world. Returns (origins, unit directions), both
    (width*height, 3) float32 in the world frame.
    """
    return _core.raytrace.camera_rays(
        np.asarray(K, dtype=np.float64), int(width), int(height), np.asarray(X_WC, np.float64)
    )
