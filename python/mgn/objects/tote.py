"""The tote (bin) that objects are dropped into.

Tote frame: origin at the centre of the inner floor surface (the top face of the floor), x along
the inner length, y along the inner width, z up. Objects resting in the tote have z >= 0. The
inner walls are the planes x = +-inner_length / 2 and y = +-inner_width / 2, the rim is at
z = inner_height, the outer bottom at z = -floor_thickness. All lengths in metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from mgn.errors import InvalidArgumentError, InvalidTypeError
from mgn.geometry import mesh as geo

__all__ = ["ToteSpec", "make_tote", "default_tote", "tote_mesh", "tote_volume"]


@dataclass(frozen=True)
class ToteSpec:
    """Dimensions and colour of an open-topped rectangular tote (a KLT-style bin).

    Attributes:
        inner_length: inner size along x, metres.
        inner_width: inner size along y, metres.
        inner_height: floor top to rim, metres.
        wall_thickness: side-wall thickness, metres.
        floor_thickness: floor thickness, metres.
        color: linear RGBA in [0, 1].
    """

    inner_length: float = 0.400
    inner_width: float = 0.300
    inner_height: float = 0.150
    wall_thickness: float = 0.008
    floor_thickness: float = 0.010
    color: tuple[float, float, float, float] = (0.2, 0.35, 0.6, 1.0)

    def __post_init__(self) -> None:
        for f in fields(self):
            if f.name == "color":
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
        """Outer (length, width, height) in metres."""
        return (
            self.inner_length + 2.0 * self.wall_thickness,
            self.inner_width + 2.0 * self.wall_thickness,
            self.inner_height + self.floor_thickness,
        )


def default_tote() -> ToteSpec:
    """The default tote: 400 x 300 x 150 mm inside, 8 mm walls, 10 mm floor, blue."""
    return ToteSpec()


def tote_volume(spec: ToteSpec) -> float:
    """Material volume of the tote in m^3: outer box minus the cavity."""
    lx, ly, lz = spec.outer_size
    return lx * ly * lz - spec.inner_length * spec.inner_width * spec.inner_height


def make_tote(spec: ToteSpec | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Closed, outward-wound triangle mesh of the tote in the tote frame.

    One polyhedron of 16 vertices and 28 triangles: outer bottom, outer sides, top rim, inner
    walls and inner floor.

    Args:
        spec: dimensions (default :func:`default_tote`).

    Returns:
        (vertices (16, 3) float64 metres, faces (28, 3) int32 counter-clockwise seen from
        outside the material).
    """
    s = default_tote() if spec is None else spec
    if not isinstance(s, ToteSpec):
        raise InvalidTypeError(f"make_tote expects a ToteSpec, got {type(s).__name__}")
    hx, hy = 0.5 * s.inner_length, 0.5 * s.inner_width
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
