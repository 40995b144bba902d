"""The path tracer's materials of a photographed scene: the :class:`mgn.render.path.PbrMaterial`
of a mesh material (:func:`pbr_material`), the tote's and floor's materials and the procedural
NumPy textures that the domain randomisation lays on them (:func:`procedural_texture`: value
noise, checker, stripes), mapped by a box projection (:func:`box_uv_mesh`).

Colours: ``base_color`` linear RGB in [0, 1]; textures (H, W, 3) uint8 sRGB; lengths in metres.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.errors import InvalidArgumentError
from mgn.geometry import Material, Mesh
from mgn.render.path import PbrMaterial

__all__ = [
    "FLOOR_COLOR",
    "FLOOR_ROUGHNESS",
    "OBJECT_TEXTURE_TILE",
    "TEXTURES",
    "TEXTURE_TILE",
    "TOTE_ROUGHNESS",
    "box_uv_mesh",
    "linear_to_srgb8",
    "pbr_default",
    "pbr_material",
    "procedural_pattern",
    "procedural_texture",
    "srgb_to_linear",
    "two_colour_texture",
]

#: Kinds of :func:`procedural_texture`.
TEXTURES = ("plain", "noise", "checker", "stripes")

#: The tote's plastic (polypropylene): a rough dielectric.
TOTE_ROUGHNESS = 0.55
#: The floor (sealed concrete / lino): a rough dielectric.
FLOOR_COLOR = (0.32, 0.31, 0.29)
FLOOR_ROUGHNESS = 0.75
#: Side of one repetition of a procedural texture on the tote and floor, m.
TEXTURE_TILE = 0.25
#: Side of one repetition of a procedural texture on an object without its own uvs, m.
OBJECT_TEXTURE_TILE = 0.06


def pbr_material(m: Material, texture: npt.NDArray[np.uint8] | None = None) -> Any:
    """The path tracer's :class:`mgn.render.path.PbrMaterial` of a mesh material: its own PBR
    parameters when it has them (``has_pbr``: built-in objects, glTF/GLB files, user objects),
    else :meth:`PbrMaterial.from_material` (derived from the Phong description)."""

    if not m.has_pbr:
        return PbrMaterial.from_material(m)
    base = np.clip(np.asarray(m.base_color, np.float64)[:3], 0.0, 1.0)
    tex = texture if texture is not None else _core.render.material_texture_rgb(m)
    transmission = float(m.transmission)
    return PbrMaterial(
        base_color=(float(base[0]), float(base[1]), float(base[2])),
        metallic=float(m.metallic),
        roughness=float(m.roughness),
        ior=max(1.0, float(m.ior)),
        transmission=transmission,
        base_color_texture=tex,
    )


def srgb_to_linear(c: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb8(c: npt.NDArray[np.float64]) -> npt.NDArray[np.uint8]:
    c = np.clip(c, 0.0, 1.0)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    return np.round(s * 255.0).astype(np.uint8)


def procedural_pattern(
    kind: str, rng: np.random.Generator, size: int = 128
) -> npt.NDArray[np.float64] | None:
    """A tileable (H, W) pattern in [0, 1]: ``noise`` (smooth value noise, two octaves, about
    0.1-0.9), ``checker`` and ``stripes`` (0 / 1; random period, and direction for stripes);
    ``plain``: None."""
    if kind == "plain":
        return None
    if kind not in TEXTURES:
        raise InvalidArgumentError(f"texture kind must be one of {TEXTURES}, got {kind!r}")
    y, x = np.mgrid[0:size, 0:size] / size
    if kind == "noise":
        v = np.zeros((size, size))
        for cells, weight in ((4, 0.65), (16, 0.35)):
            g = rng.random((cells, cells))
            # Bilinear (smoothstep) interpolation of a periodic lattice: tileable.
            fx, fy = x * cells, y * cells
            i0, j0 = np.floor(fx).astype(int) % cells, np.floor(fy).astype(int) % cells
            i1, j1 = (i0 + 1) % cells, (j0 + 1) % cells
            tx, ty = fx - np.floor(fx), fy - np.floor(fy)
            tx, ty = tx * tx * (3 - 2 * tx), ty * ty * (3 - 2 * ty)
            top = g[j0, i0] * (1 - tx) + g[j0, i1] * tx
            bot = g[j1, i0] * (1 - tx) + g[j1, i1] * tx
            v += weight * (top * (1 - ty) + bot * ty)
        return v
    pattern: npt.NDArray[np.float64]
    if kind == "checker":
        n = int(rng.integers(2, 5))
        pattern = ((np.floor(x * 2 * n) + np.floor(y * 2 * n)) % 2).astype(np.float64)
    else:  # stripes
        n = int(rng.integers(2, 7))
        pattern = (np.floor((x if rng.random() < 0.5 else y) * 2 * n) % 2).astype(np.float64)
    return pattern


def procedural_texture(
    kind: str, rng: np.random.Generator, size: int = 128, contrast: float = 0.3
) -> npt.NDArray[np.uint8] | None:
    """A tileable grey (H, W, 3) uint8 sRGB texture around white that multiplies a base colour:
    ``noise`` (smooth value noise, two octaves), ``checker``, ``stripes`` (random period and
    direction), ``plain`` (None); :func:`procedural_pattern`. ``contrast`` is the darkening of
    the darkest texels (linear)."""
    v = procedural_pattern(kind, rng, size)
    if v is None:
        return None
    grey = linear_to_srgb8(1.0 - contrast * v)
    return np.repeat(grey[:, :, None], 3, axis=2)


def two_colour_texture(
    pattern: npt.NDArray[np.float64], first: npt.ArrayLike, second: npt.ArrayLike
) -> npt.NDArray[np.uint8]:
    """(H, W, 3) uint8 sRGB texture blending two linear RGB colours by ``pattern`` (H, W) in
    [0, 1]: ``first`` where it is 0, ``second`` where it is 1 (linear blend)."""
    v = np.clip(np.asarray(pattern, np.float64), 0.0, 1.0)[:, :, None]
    a = np.asarray(first, np.float64).reshape(1, 1, 3)
    b = np.asarray(second, np.float64).reshape(1, 1, 3)
    return linear_to_srgb8(a * (1.0 - v) + b * v)


def box_uv_mesh(mesh: Mesh, tile: float, name: str, *, keep_face_materials: bool = False) -> Mesh:
    """``mesh`` with every face given its own vertices and uvs from a box projection (the two
    axes of the mesh frame across the face's dominant normal axis, divided by ``tile`` m): same
    triangles, texturable; the faces keep their material slots with ``keep_face_materials``
    (else all use slot 0). The tracer's shading normals weld vertices by position, so shading
    is unchanged."""
    V = np.asarray(mesh.vertices, np.float64)
    F = np.asarray(mesh.faces, np.int64)
    P = V[F]  # (F, 3, 3)
    n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    axis = np.argmax(np.abs(n), axis=1)
    uv_axes = np.array([[1, 2], [0, 2], [0, 1]])[axis]  # (F, 2)
    uv = np.take_along_axis(P, uv_axes[:, None, :].repeat(3, axis=1), axis=2) / tile
    return Mesh(
        P.reshape(-1, 3).astype(np.float32),
        np.arange(3 * len(F), dtype=np.int32).reshape(-1, 3),
        uv.reshape(-1, 2).astype(np.float32),
        list(mesh.materials),
        list(mesh.face_materials) if keep_face_materials else [],
        name,
    )


def pbr_default() -> Any:
    """The path tracer's default material (a mesh without materials)."""

    return PbrMaterial()
