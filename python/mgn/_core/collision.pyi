"""
mgn/collision: FCL collision and distance.
"""

from __future__ import annotations

import typing

import numpy

import mgn._core.geometry

__all__: list[str] = ["CollisionModel", "DistanceResult", "collide", "distance"]

class DistanceResult:
    """
    distance() result (mgn/collision/collision_model.hpp), one row per pose pair.
    """
    @property
    def collide(self) -> numpy.ndarray:
        """
        (N,) bool
        """
    @property
    def distance(self) -> numpy.ndarray:
        """
        (N,) float64 m, 0 for intersecting pairs
        """
    @property
    def points_a(self) -> numpy.ndarray:
        """
        (N,3) float64 closest point on A, world frame
        """
    @property
    def points_b(self) -> numpy.ndarray:
        """
        (N,3) float64 closest point on B, world frame
        """

class CollisionModel:
    """
    Immutable FCL BVH (OBBRSS) of a mesh.
    """
    def __init__(self, mesh: mgn._core.geometry.Mesh) -> None: ...
    @property
    def num_triangles(self) -> int: ...
    @property
    def num_vertices(self) -> int: ...

def collide(
    a: CollisionModel,
    X_WA: typing.Any,
    b: CollisionModel,
    X_WB: typing.Any,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> numpy.ndarray: ...
def distance(
    a: CollisionModel,
    X_WA: typing.Any,
    b: CollisionModel,
    X_WB: typing.Any,
    rel_err: typing.SupportsFloat | typing.SupportsIndex = 0.0,
    abs_err: typing.SupportsFloat | typing.SupportsIndex = 0.0,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> DistanceResult: ...
