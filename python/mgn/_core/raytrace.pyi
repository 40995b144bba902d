"""
mgn/raytrace: Embree ray casting.
"""

from __future__ import annotations

import collections.abc
import typing

import numpy
import numpy.typing

import mgn._core.geometry

__all__: list[str] = ["RayAllHits", "RayHits", "RayScene", "camera_rays"]

class RayHits:
    """
    RayScene.intersect() result (mgn/raytrace/ray_scene.hpp), world frame; misses have distance inf and ids -1.
    """
    @property
    def barycentric(self) -> numpy.ndarray:
        """
        (N,2) float32 (u, v): p = (1-u-v) v0 + u v1 + v v2
        """
    @property
    def distance(self) -> numpy.ndarray:
        """
        (N,) float32 m
        """
    @property
    def face_ids(self) -> numpy.ndarray:
        """
        (N,) int32 face index within its mesh
        """
    @property
    def instance_ids(self) -> numpy.ndarray:
        """
        (N,) int32
        """
    @property
    def normals(self) -> numpy.ndarray:
        """
        (N,3) float32 unit geometric normal, outward for CCW faces
        """
    @property
    def points(self) -> numpy.ndarray:
        """
        (N,3) float32
        """

class RayAllHits:
    """
    RayScene.intersect_all() result: the hits of ray i are entries offsets[i] .. offsets[i+1]-1, sorted by distance.
    """
    @property
    def distance(self) -> numpy.ndarray:
        """
        (H,) float32 m
        """
    @property
    def face_ids(self) -> numpy.ndarray:
        """
        (H,) int32
        """
    @property
    def instance_ids(self) -> numpy.ndarray:
        """
        (H,) int32
        """
    @property
    def normals(self) -> numpy.ndarray:
        """
        (H,3) float32
        """
    @property
    def offsets(self) -> numpy.ndarray:
        """
        (N+1,) int64
        """
    @property
    def points(self) -> numpy.ndarray:
        """
        (H,3) float32
        """
    @property
    def ray_ids(self) -> numpy.ndarray:
        """
        (H,) int32 ray of each hit
        """

class RayScene:
    """
    Immutable Embree scene of meshes placed in the world frame.
    """
    def __init__(
        self,
        meshes: collections.abc.Sequence[mgn._core.geometry.Mesh],
        poses: typing.Any | None = None,
        instance_ids: typing.Any = None,
    ) -> None: ...
    def intersect(
        self,
        origins: typing.Any,
        directions: typing.Any,
        tnear: typing.SupportsFloat | typing.SupportsIndex = 0.0,
        tfar: typing.SupportsFloat | typing.SupportsIndex = ...,
        coherent: bool = False,
        num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
    ) -> RayHits: ...
    def intersect_all(
        self,
        origins: typing.Any,
        directions: typing.Any,
        max_hits_per_ray: typing.SupportsInt | typing.SupportsIndex = 64,
        tnear: typing.SupportsFloat | typing.SupportsIndex = 0.0,
        tfar: typing.SupportsFloat | typing.SupportsIndex = ...,
        num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
    ) -> RayAllHits: ...
    def intersect_ids(
        self,
        origins: typing.Any,
        directions: typing.Any,
        tnear: typing.SupportsFloat | typing.SupportsIndex = 0.0,
        tfar: typing.SupportsFloat | typing.SupportsIndex = ...,
        coherent: bool = False,
        num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
    ) -> tuple[numpy.ndarray, numpy.ndarray]: ...
    def occluded(
        self,
        origins: typing.Any,
        directions: typing.Any,
        tnear: typing.SupportsFloat | typing.SupportsIndex = 0.0,
        tfar: typing.SupportsFloat | typing.SupportsIndex = ...,
        coherent: bool = False,
        num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
    ) -> numpy.ndarray: ...
    @property
    def bounds(self) -> numpy.ndarray: ...
    @property
    def num_geometries(self) -> int: ...
    @property
    def num_triangles(self) -> int: ...

def camera_rays(
    K: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 3]"],
    width: typing.SupportsInt | typing.SupportsIndex,
    height: typing.SupportsInt | typing.SupportsIndex,
    X_WC: typing.Any,
) -> tuple[numpy.ndarray, numpy.ndarray]: ...
