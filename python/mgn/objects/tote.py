"""The tote (bin) that objects are dropped into.

Tote frame: origin at the centre of the inner floor surface (the top face of the floor), x along
the inner length, y along the inner width, z up. Objects resting in the tote have z >= 0. The
inner walls are the planes x = +-inner_length / 2 and y = +-inner_width / 2, the rim is at
z = inner_height, the outer bottom at z = -floor_thickness. All lengths in metres.

Your own bin: ``mesh`` (a mesh file, read with ``mesh_scale``) replaces the parametric box for
rendering, the labels and ``drop.tote_collision: mesh`` (use it for any bin that is not a
rectangular box). It must be in the tote frame (origin at the centre of the inner floor, z up).
``inner_length`` x ``inner_width`` x ``inner_height`` are then the bounding box of its cavity:
an object that ends outside that box has left the tote, and ``tote_collision: boxes`` puts its
walls there. In a config (a round bin of 180 mm inner radius, drawn in millimetres)::

    tote: {mesh: bins/round_bin.stl, mesh_scale: 0.001, inner_length: 0.36, inner_width: 0.36,
           inner_height: 0.15}
    drop: {tote_collision: mesh}
"""

from __future__ import annotations

import functools
import math
import os
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from mgn.errors import InvalidArgumentError, InvalidTypeError
from mgn.geometry import load_mesh
from mgn.geometry import mesh as geo

__all__ = ["ToteSpec", "default_tote", "make_tote", "tote_mesh", "tote_volume"]


@dataclass(frozen=True)
class ToteSpec:
    """Dimensions and colour of an open-topped rectangular tote (a KLT-style bin).

    Attributes:
        inner_length: inner size along x, metres.
        inner_width: inner size along y, metres.
        inner_height: floor top to rim, metres.
        wall_thickness: side-wall thickness, metres.
        floor_thickness: floor thickness, metres.
        color: linear RGBA in [0, 1], the tote's colour in the images when ``camera.randomize``
            is off. With ``camera.randomize`` (the default of a dataset config) every view
            draws the tote's colour at random instead (the raster engine always, the path engine
            while ``render.randomize.materials`` is on), and this colour is not used.
        mesh: a user bin mesh file in the tote frame, or None (the parametric box).
        mesh_scale: multiplies the mesh coordinates (0.001 for a file in millimetres).
        walls: False for a table top (a shelf board, a conveyor): no walls, the "tote" is a
            slab of inner_length x inner_width x floor_thickness with its top at z = 0;
            inner_height then only bounds the drop. Objects that fall off an edge leave the
            scene, and every bin relation is ``no_rel``. wall_thickness is unused.
    """

    inner_length: float = 0.400
    inner_width: float = 0.300
    inner_height: float = 0.150
    wall_thickness: float = 0.008
    floor_thickness: float = 0.010
    color: tuple[float, float, float, float] = (0.2, 0.35, 0.6, 1.0)
    mesh: str | None = None
    mesh_scale: float = 1.0
    walls: bool = True

    def __post_init__(self) -> None:
        if self.mesh is not None and (
            not isinstance(self.mesh, (str, os.PathLike)) or not os.fspath(self.mesh)
        ):
            raise InvalidArgumentError(
                f"ToteSpec.mesh must be a mesh file path or None, got {self.mesh!r}"
            )
        if self.mesh is not None:
            object.__setattr__(self, "mesh", os.fspath(self.mesh))
        if not isinstance(self.walls, (bool, np.bool_)):
            raise InvalidArgumentError(f"ToteSpec.walls must be true or false, got {self.walls!r}")
        object.__setattr__(self, "walls", bool(self.walls))
        if not self.walls and self.mesh is not None:
            raise InvalidArgumentError(
                f"ToteSpec: walls: false (a table top) and mesh '{self.mesh}' exclude each other; "
                "expected a bin mesh or a table top"
            )
        for f in fields(self):
            if f.name in ("color", "mesh", "walls"):
                continue
            value = getattr(self, f.name)
            if isinstance(value, bool) or not isinstance(
                value, (int, float, np.floating, np.integer)
            ):
                raise InvalidArgumentError(f"ToteSpec.{f.name} must be a number, got {value!r}")
            if not math.isfinite(float(value)) or float(value) <= 0.0:
                raise InvalidArgumentError(
                    f"ToteSpec.{f.name} must be finite and > 0, got {value!r}"
                )
            object.__setattr__(self, f.name, float(value))
        color = tuple(self.color)
        if len(color) != 4 or not all(
            isinstance(c, (int, float)) and 0.0 <= float(c) <= 1.0 for c in color
        ):
            raise InvalidArgumentError(
                f"ToteSpec.color must be 4 values in [0, 1], got {self.color!r}"
            )
        object.__setattr__(self, "color", tuple(float(c) for c in color))

    @property
    def outer_size(self) -> tuple[float, float, float]:
        """Outer (length, width, height) in metres (a table top: the slab)."""
        if not self.walls:
            return (self.inner_length, self.inner_width, self.floor_thickness)
        return (
            self.inner_length + 2.0 * self.wall_thickness,
            self.inner_width + 2.0 * self.wall_thickness,
            self.inner_height + self.floor_thickness,
        )


def default_tote() -> ToteSpec:
    """The default tote: 400 x 300 x 150 mm inside, 8 mm walls, 10 mm floor, blue."""
    return ToteSpec()


def tote_volume(spec: ToteSpec) -> float:
    """Material volume of the tote in m^3: outer box minus the cavity (a table top: the slab)."""
    lx, ly, lz = spec.outer_size
    if not spec.walls:
        return lx * ly * lz
    return lx * ly * lz - spec.inner_length * spec.inner_width * spec.inner_height


def make_tote(spec: ToteSpec | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Closed, outward-wound triangle mesh of the tote in the tote frame.

    One polyhedron of 16 vertices and 28 triangles: outer bottom, outer sides, top rim, inner
    walls and inner floor; for a table top (``walls=False``) the slab, 8 vertices and 12
    triangles.

    Args:
        spec: dimensions (default :func:`default_tote`), or a user bin (``spec.mesh``).

    Returns:
        (vertices (16, 3) float64 metres, faces (28, 3) int32 counter-clockwise seen from
        outside the material).
    """
    s = default_tote() if spec is None else spec
    if not isinstance(s, ToteSpec):
        raise InvalidTypeError(f"make_tote expects a ToteSpec, got {type(s).__name__}")
    if s.mesh is not None:
        return _user_tote(s)
    hx, hy = 0.5 * s.inner_length, 0.5 * s.inner_width
    if not s.walls:  # a table top: the slab, top face at z = 0
        v = np.array(
            [[x, y, z] for z in (-s.floor_thickness, 0.0) for y in (-hy, hy) for x in (-hx, hx)],
            np.float64,
        )
        # Vertex k: x = k & 1, y = k & 2, z = k & 4 (bits set: +).
        quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
        tri = [(a, b, c) for a, b, c, d in quads] + [(a, c, d) for a, b, c, d in quads]
        return v, np.asarray(tri, np.int32)
    ox, oy = hx + s.wall_thickness, hy + s.wall_thickness
    top, bottom = s.inner_height, -s.floor_thickness
    corners = np.array(
        [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]
    )  # counter-clockwise from +z

    def ring(x: float, y: float, z: float) -> np.ndarray:
        return np.column_stack([corners[:, 0] * x, corners[:, 1] * y, np.full(4, z)])

    vertices = np.concatenate(
        [
            ring(ox, oy, bottom),  # 0..3 outer bottom
            ring(ox, oy, top),  # 4..7 outer top
            ring(hx, hy, top),  # 8..11 inner top (rim edge)
            ring(hx, hy, 0.0),  # 12..15 inner floor
        ]
    )
    faces: list[tuple[int, int, int]] = [(0, 2, 1), (0, 3, 2)]  # outer bottom, normal -z
    for i in range(4):
        j = (i + 1) % 4
        faces += [(i, j, 4 + j), (i, 4 + j, 4 + i)]  # outer side, outward
        faces += [(4 + i, 4 + j, 8 + j), (4 + i, 8 + j, 8 + i)]  # rim, +z
        faces += [(8 + i, 8 + j, 12 + j), (8 + i, 12 + j, 12 + i)]  # inner wall, facing the cavity
    faces += [(12, 13, 14), (12, 14, 15)]  # inner floor, +z
    return vertices, np.asarray(faces, dtype=np.int32)


def tote_mesh(spec: ToteSpec | None = None) -> geo.Mesh:
    """The tote (:func:`make_tote`, default :class:`ToteSpec`) as a closed :class:`mgn.Mesh` in
    the tote frame, with its colour as material. The one tote mesh of mgn: physics, rendering and
    labels use it."""
    s = ToteSpec() if spec is None else spec
    vertices, faces = make_tote(s)
    mat = geo.Material()
    mat.name = "tote"
    mat.base_color = np.asarray(s.color, np.float32)
    mat.specular = np.full(3, 0.1, np.float32)
    return geo.Mesh(
        np.asarray(vertices, np.float32), np.asarray(faces, np.int32), None, [mat], [], "tote"
    )


def _user_tote(s: ToteSpec) -> tuple[np.ndarray, np.ndarray]:
    assert s.mesh is not None  # make_tote calls this for a user bin only
    path = os.path.abspath(s.mesh)
    try:
        stamp = Path(path).stat().st_mtime_ns
    except OSError:
        stamp = -1  # load_mesh names the missing file
    v, f = _load_user_tote(path, s.mesh_scale, stamp)
    lo, hi = v.min(axis=0), v.max(axis=0)
    tol = 0.005
    need_lo = np.array([-s.inner_length / 2, -s.inner_width / 2, 0.0])
    need_hi = np.array([s.inner_length / 2, s.inner_width / 2, s.inner_height])
    if np.any(lo > need_lo + tol) or np.any(hi < need_hi - tol) or lo[2] > -1e-4:
        raise InvalidArgumentError(
            f"tote.mesh '{s.mesh}' (scale {s.mesh_scale:g}) spans {lo.round(3).tolist()} .. "
            f"{hi.round(3).tolist()} m; expected a bin in the tote frame (origin at the centre of "
            "the inner floor, z up, material below z = 0) around the inner box of inner_length x "
            f"inner_width x inner_height = {s.inner_length:g} x {s.inner_width:g} x "
            f"{s.inner_height:g} m"
        )
    return v.copy(), f.copy()


@functools.lru_cache(maxsize=8)
def _load_user_tote(path: str, scale: float, stamp: int) -> tuple[np.ndarray, np.ndarray]:  # noqa: ARG001
    # ``stamp`` (the file's modification time) is part of the cache key only.

    mesh = load_mesh(path, scale=scale)
    if mesh.validate().signed_volume < 0:
        mesh = mesh.flipped()
    return np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int32)
