"""The built-in catalogue of procedural objects (warehouse and household items).

Frames and units: every :class:`ObjectSpec` holds a closed triangle mesh in metres, in the
object frame, whose origin is the centre of the mesh's axis-aligned bounding box, z up (the
"natural" standing pose of the object). Densities are in kg/m^3 and are *effective* densities:
mass = density x enclosed mesh volume (so a closed cereal box is light, a full can is close to
water).

The catalogue is built procedurally (numpy + manifold3d) on first use and cached; the build is
deterministic (fixed parameters, fixed random seeds), so every call in every process returns the
same bytes. Category ids are 1..N in catalogue order and never change meaning: new objects are
only ever appended.

Tags (a subset of :data:`ALLOWED_TAGS`) describe the object for dataset splits:

- ``box`` a printed carton; ``cylindrical`` a body of revolution with a round side;
- ``nonconvex`` clearly non-convex (volume < 70 % of its convex hull: cups, pipes, brackets...);
- ``transparent`` material opacity < 0.5; ``black`` base colour below 0.05 in every channel;
- ``deformable`` soft in reality (the mesh is one static shape); ``textured`` has a texture;
- ``novel`` held out of training sets by default (the unseen split of ``mgn generate --split``):
  the paper's novel set of non-convex, black, shape-varying and transparent objects;
- ``small`` largest extent <= 70 mm; ``large`` largest extent >= 180 mm; ``thin`` smallest
  extent <= 25 mm. The three size tags are derived from the mesh, never declared by hand.
"""

from __future__ import annotations

import dataclasses
import functools
import io
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from PIL import Image

from mgn.errors import InvalidArgumentError, InvalidTypeError
from mgn.geometry import mesh as geo

from . import textures as tx
from .shapes import (
    Mesh,
    difference,
    ensure_min_faces,
    extrude,
    grid_box,
    loft,
    revolve,
    rotation_matrix,
    rounded_box,
    superellipsoid,
    sweep_circle,
    sweep_hollow,
    union,
)

__all__ = [
    "NUM_COM_KEYPOINTS",
    "com_keypoints",
    "ALLOWED_TAGS",
    "MaterialSpec",
    "Keypoint",
    "ObjectSpec",
    "builtin_objects",
    "get_object",
    "object_names",
]

#: Tags an object may carry (see the module documentation for their meaning).
ALLOWED_TAGS: frozenset[str] = frozenset(
    {
        "box",
        "cylindrical",
        "nonconvex",
        "transparent",
        "black",
        "deformable",
        "novel",
        "textured",
        "small",
        "large",
        "thin",
    }
)

SMALL_MAX_EXTENT = 0.070  # m, "small": largest bounding-box extent at most this
LARGE_MIN_EXTENT = 0.180  # m, "large": largest bounding-box extent at least this
THIN_MAX_EXTENT = 0.025  # m, "thin": smallest bounding-box extent at most this


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, copy=True)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class MaterialSpec:
    """Appearance of an object (one material per object).

    Attributes:
        name: short identifier, e.g. ``"cardboard_print"``.
        base_color: linear RGBA in [0, 1]. With a texture it tints the texture (white = as is).
        specular: linear RGB specular colour in [0, 1].
        shininess: Phong exponent (> 0).
        opacity: 1 opaque, lower is more transparent (e.g. 0.15 for clear glass).
        texture: (H, W, 3) uint8 sRGB image (row 0 = top of the image) or ``None``. Read-only;
            excluded from equality and hashing.
        metallic, roughness, ior, transmission: the physically based description used by the
            path tracer (glTF 2.0 metallic-roughness, mgn.render.path): metallic in [0, 1],
            perceptual roughness in [0, 1] (GGX alpha = roughness^2), index of refraction
            >= 1, transmission in [0, 1] (1 = clear glass or plastic). The Phong fields above
            drive the raster preview.
    """

    name: str
    base_color: tuple[float, float, float, float]
    specular: tuple[float, float, float] = (0.2, 0.2, 0.2)
    shininess: float = 20.0
    opacity: float = 1.0
    texture: np.ndarray | None = field(default=None, compare=False, hash=False, repr=False)
    metallic: float = 0.0
    roughness: float = 0.5
    ior: float = 1.5
    transmission: float = 0.0

    def __post_init__(self) -> None:
        if len(self.base_color) != 4 or not all(0.0 <= float(c) <= 1.0 for c in self.base_color):
            raise InvalidArgumentError(
                f"MaterialSpec.base_color must be 4 values in [0, 1], got {self.base_color!r}"
            )
        if len(self.specular) != 3 or not all(0.0 <= float(c) <= 1.0 for c in self.specular):
            raise InvalidArgumentError(
                f"MaterialSpec.specular must be 3 values in [0, 1], got {self.specular!r}"
            )
        if not (np.isfinite(self.shininess) and self.shininess > 0):
            raise InvalidArgumentError(
                f"MaterialSpec.shininess must be > 0, got {self.shininess!r}"
            )
        if not 0.0 < self.opacity <= 1.0:
            raise InvalidArgumentError(
                f"MaterialSpec.opacity must be in (0, 1], got {self.opacity!r}"
            )
        for key in ("metallic", "roughness", "transmission"):
            v = getattr(self, key)
            if isinstance(v, bool) or not (np.isfinite(v) and 0.0 <= v <= 1.0):
                raise InvalidArgumentError(f"MaterialSpec.{key} must be in [0, 1], got {v!r}")
            object.__setattr__(self, key, float(v))
        if isinstance(self.ior, bool) or not (np.isfinite(self.ior) and 1.0 <= self.ior <= 4.0):
            raise InvalidArgumentError(f"MaterialSpec.ior must be in [1, 4], got {self.ior!r}")
        object.__setattr__(self, "ior", float(self.ior))
        object.__setattr__(self, "base_color", tuple(float(c) for c in self.base_color))
        object.__setattr__(self, "specular", tuple(float(c) for c in self.specular))
        if self.texture is not None:
            t = np.asarray(self.texture)
            if (
                t.dtype != np.uint8
                or t.ndim != 3
                or t.shape[2] != 3
                or t.shape[0] < 1
                or t.shape[1] < 1
            ):
                raise InvalidArgumentError(
                    "MaterialSpec.texture must be an (H, W, 3) uint8 array, "
                    f"got {t.dtype} {t.shape}"
                )
            object.__setattr__(self, "texture", _readonly(t))


@dataclass(frozen=True)
class Keypoint:
    """A semantic keypoint of an object.

    Attributes:
        id: 1-based index within the object.
        name: e.g. ``"top_centre"``, ``"handle"``, ``"cap"``.
        position: (x, y, z) in the object frame, metres (on or near the surface).
    """

    id: int
    name: str
    position: tuple[float, float, float]


@dataclass(frozen=True, eq=False)
class ObjectSpec:
    """One object class of the catalogue: geometry, appearance, physics and semantics.

    Attributes:
        category_id: 1..N, unique and stable.
        name: unique snake_case name, e.g. ``"box_cereal"``.
        description: one sentence for people.
        vertices: (V, 3) float64, metres, object frame (origin at the bounding-box centre, z up).
        faces: (F, 3) int32, counter-clockwise seen from outside (outward normals). Welded by
            position the mesh is closed, manifold and has positive volume.
        uvs: (V, 2) float32 texture coordinates in [0, 1] (v up, OBJ convention) when the
            material has a texture, else ``None``. Vertices on UV seams are duplicated with
            bit-identical positions.
        material: appearance.
        density: effective density, kg/m^3 (mass = density x mesh volume).
        friction: Coulomb friction coefficient.
        keypoints: 2..8 semantic keypoints (ids 1..K in order).
        tags: subset of :data:`ALLOWED_TAGS`.

    Arrays are read-only. Two specs are equal when every field (arrays compared exactly) is.
    """

    category_id: int
    name: str
    description: str
    vertices: np.ndarray
    faces: np.ndarray
    uvs: np.ndarray | None
    material: MaterialSpec
    density: float
    friction: float
    keypoints: tuple[Keypoint, ...]
    tags: frozenset[str]

    def __post_init__(self) -> None:
        v = np.asarray(self.vertices, dtype=np.float64)
        f = np.asarray(self.faces)
        if v.ndim != 2 or v.shape[1] != 3 or len(v) < 4 or not np.all(np.isfinite(v)):
            raise InvalidArgumentError(
                f"{self.name}: vertices must be a finite (V >= 4, 3) array, got {v.shape}"
            )
        if f.ndim != 2 or f.shape[1] != 3 or len(f) < 4 or not np.issubdtype(f.dtype, np.integer):
            raise InvalidArgumentError(
                f"{self.name}: faces must be an integer (F >= 4, 3) array, got {f.dtype} {f.shape}"
            )
        if f.min() < 0 or f.max() >= len(v):
            raise InvalidArgumentError(f"{self.name}: faces index outside 0..{len(v) - 1}")
        object.__setattr__(self, "vertices", _readonly(v))
        object.__setattr__(self, "faces", _readonly(f.astype(np.int32)))
        has_tex = self.material.texture is not None
        if (self.uvs is not None) != has_tex:
            raise InvalidArgumentError(
                f"{self.name}: uvs must be given exactly when the material has a texture"
            )
        if self.uvs is not None:
            uv = np.asarray(self.uvs, dtype=np.float32)
            if uv.shape != (len(v), 2) or not np.all((uv >= 0) & (uv <= 1)):
                raise InvalidArgumentError(
                    f"{self.name}: uvs must be a (V, 2) array in [0, 1], got {uv.shape}"
                )
            object.__setattr__(self, "uvs", _readonly(uv))
        if not (np.isfinite(self.density) and self.density > 0):
            raise InvalidArgumentError(
                f"{self.name}: density must be > 0 kg/m^3, got {self.density!r}"
            )
        if not (np.isfinite(self.friction) and 0 < self.friction <= 2):
            raise InvalidArgumentError(
                f"{self.name}: friction must be in (0, 2], got {self.friction!r}"
            )
        if not 2 <= len(self.keypoints) <= 8:
            raise InvalidArgumentError(
                f"{self.name}: needs 2..8 keypoints, got {len(self.keypoints)}"
            )
        if [k.id for k in self.keypoints] != list(range(1, len(self.keypoints) + 1)):
            raise InvalidArgumentError(f"{self.name}: keypoint ids must be 1..K in order")
        bad = set(self.tags) - ALLOWED_TAGS
        if bad:
            raise InvalidArgumentError(
                f"{self.name}: unknown tags {sorted(bad)}; allowed: {sorted(ALLOWED_TAGS)}"
            )
        object.__setattr__(self, "tags", frozenset(self.tags))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ObjectSpec):
            return NotImplemented
        same_uv = (self.uvs is None and other.uvs is None) or (
            self.uvs is not None and other.uvs is not None and np.array_equal(self.uvs, other.uvs)
        )
        return (
            (
                self.category_id,
                self.name,
                self.description,
                self.material,
                self.density,
                self.friction,
            )
            == (
                other.category_id,
                other.name,
                other.description,
                other.material,
                other.density,
                other.friction,
            )
            and self.keypoints == other.keypoints
            and self.tags == other.tags
            and np.array_equal(self.vertices, other.vertices)
            and np.array_equal(self.faces, other.faces)
            and same_uv
        )

    def __hash__(self) -> int:
        return hash((self.category_id, self.name, len(self.vertices), len(self.faces)))

    @property
    def extents(self) -> np.ndarray:
        """(3,) bounding-box edge lengths in metres."""
        return self.vertices.max(axis=0) - self.vertices.min(axis=0)

    @property
    def volume(self) -> float:
        """Enclosed volume in m^3."""
        t = self.vertices[self.faces]
        return float(np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum() / 6.0)

    @property
    def mass(self) -> float:
        """density x volume, kg."""
        return self.density * self.volume

    def to_mesh(self) -> geo.Mesh:
        """The :class:`mgn.Mesh` of this object (metres, object frame), with its material (its
        texture, if any, embedded as PNG bytes in ``Material.texture_data``)."""
        mat = geo.Material()
        mat.name = self.material.name
        mat.base_color = np.asarray(self.material.base_color, np.float32)
        mat.specular = np.asarray(self.material.specular, np.float32)
        mat.shininess = float(self.material.shininess)
        mat.opacity = float(self.material.opacity)
        mat.has_pbr = True
        mat.metallic = float(self.material.metallic)
        mat.roughness = float(self.material.roughness)
        mat.ior = float(self.material.ior)
        mat.transmission = float(self.material.transmission)
        uvs = None if self.uvs is None else np.asarray(self.uvs, np.float32)
        if self.material.texture is not None and uvs is not None:
            # The texture travels with the mesh as embedded PNG bytes (the renderer decodes them).
            buf = io.BytesIO()
            Image.fromarray(np.asarray(self.material.texture, np.uint8)).save(buf, format="PNG")
            mat.texture_data = buf.getvalue()
        return geo.Mesh(
            np.asarray(self.vertices, np.float32),
            np.asarray(self.faces, np.int32),
            uvs,
            [mat],
            [],
            self.name,
        )


#: Number of centre-of-mass keypoints per object (MetaGraspNet).
NUM_COM_KEYPOINTS = 1000


def com_keypoints(mesh: geo.Mesh, density: float, *, seed: int) -> npt.NDArray[np.float64]:
    """(1000, 4) [score, x, y, z] in metres: surface points scored by closeness to the CoM.

    score = (d_max - d) / (d_max - d_min), d = distance to the mass-weighted centre of mass.
    Points are spread evenly (blue noise) with a fixed ``seed``.
    """
    com = geo.mass_properties(mesh, density).center_of_mass
    pts = geo.sample_surface(mesh, NUM_COM_KEYPOINTS, method="even", seed=seed).points.astype(
        np.float64
    )
    d = np.linalg.norm(pts - com, axis=1)
    span = max(float(d.max() - d.min()), 1e-12)
    score = (d.max() - d) / span
    return np.column_stack([score, pts])


# ----------------------------------------------------------------------------------------------
# Building blocks
# ----------------------------------------------------------------------------------------------

MM = 1e-3  # metres per millimetre
SEG = 64  # angular steps of bodies of revolution


@dataclass(frozen=True)
class _Built:
    """A builder's output: mesh and named keypoints in the builder's own frame (metres)."""

    mesh: Mesh
    keypoints: tuple[tuple[str, tuple[float, float, float]], ...]
    texture: np.ndarray | None = None


def _mm(points: Sequence[Sequence[float]]) -> np.ndarray:
    return np.asarray(points, dtype=np.float64) * MM


def _kp(**named: Sequence[float]) -> tuple[tuple[str, tuple[float, float, float]], ...]:
    """Keypoints given in millimetres, in keyword order."""
    return tuple((n, tuple(float(c) * MM for c in p)) for n, p in named.items())  # type: ignore[misc]


def _lin(hex_srgb: str, alpha: float = 1.0) -> tuple[float, float, float, float]:
    """'#rrggbb' sRGB colour -> linear RGBA."""
    c = np.array([int(hex_srgb[i : i + 2], 16) for i in (1, 3, 5)], dtype=np.float64) / 255.0
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return (round(float(lin[0]), 4), round(float(lin[1]), 4), round(float(lin[2]), 4), alpha)


def _arc_fractions(profile: np.ndarray) -> np.ndarray:
    """Texture v of each profile point, as :func:`revolve` assigns it (open profile)."""
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(profile, axis=0), axis=1))])
    return arc / arc[-1]


def _cylinder(
    radius: float, z0: float, z1: float, segments: int = 32, axial_steps: int = 1
) -> Mesh:
    """Closed cylinder about the z axis from z0 to z1 (metres)."""
    zs = np.linspace(z0, z1, axial_steps + 1)
    prof = [(0.0, z0)] + [(radius, z) for z in zs] + [(0.0, z1)]
    return revolve(prof, segments)


def _polyline(*pieces: np.ndarray) -> np.ndarray:
    """Concatenate point arrays, dropping a piece's first point when it repeats the previous end."""
    out = [pieces[0]]
    for p in pieces[1:]:
        out.append(p[1:] if np.allclose(p[0], out[-1][-1]) else p)
    return np.concatenate(out)


def _arc(
    centre: Sequence[float], radii: Sequence[float], a0: float, a1: float, n: int
) -> np.ndarray:
    """Points (r, z) on an axis-aligned ellipse arc, angles in radians from a0 to a1 inclusive."""
    t = np.linspace(a0, a1, n)
    return np.stack([centre[0] + radii[0] * np.cos(t), centre[1] + radii[1] * np.sin(t)], axis=1)


def _box_keypoints(size: Sequence[float]) -> tuple[tuple[str, tuple[float, float, float]], ...]:
    """Face centres and one top corner of a centred box (metres).

    "front"/"back" are the two largest side faces (those printed with the title, see
    :func:`mgn.objects.textures.box_atlas`), "left"/"right" the two other side faces.
    """
    sx, sy, sz = (0.5 * s for s in size)
    x_is_front = size[1] >= size[0]
    x_names = ("front_centre", "back_centre") if x_is_front else ("right_centre", "left_centre")
    y_names = ("left_centre", "right_centre") if x_is_front else ("back_centre", "front_centre")
    return (
        ("top_centre", (0.0, 0.0, sz)),
        ("bottom_centre", (0.0, 0.0, -sz)),
        (x_names[0], (sx, 0.0, 0.0)),
        (x_names[1], (-sx, 0.0, 0.0)),
        (y_names[0], (0.0, sy, 0.0)),
        (y_names[1], (0.0, -sy, 0.0)),
        ("top_corner", (sx, sy, sz)),
    )


def _printed_box(size_mm: Sequence[float], palette: tx.Palette, title: str, seed: int) -> _Built:
    size = tuple(s * MM for s in size_mm)
    mesh = grid_box(size, max_edge=0.012, with_uv=True)
    tex = tx.box_atlas(size, palette, title, seed)
    return _Built(mesh, _box_keypoints(size), tex)


def _smooth_noise(
    seed: int, amplitude: float, terms: int = 7
) -> Callable[[np.ndarray], np.ndarray]:
    """Radial factor 1 + a smooth random field on the unit sphere (fixed seed), always > 0."""
    rng = np.random.default_rng(seed)
    dirs = rng.normal(size=(terms, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    freq = rng.uniform(2.0, 6.0, terms)
    phase = rng.uniform(0.0, 2.0 * np.pi, terms)
    weights = rng.uniform(0.5, 1.0, terms)
    weights *= amplitude / weights.sum()

    def factor(d: np.ndarray) -> np.ndarray:
        return 1.0 + np.sin(d @ dirs.T * freq + phase) @ weights

    return factor


# ----------------------------------------------------------------------------------------------
# Materials and the registry
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Entry:
    """Catalogue entry: everything about an object class except its geometry."""

    name: str
    description: str
    build: Callable[[], _Built]
    material: MaterialSpec
    density: float
    friction: float
    tags: frozenset[str]


#: Registered entries in category-id order (the order of the builder definitions below).
_CATALOGUE: list[_Entry] = []


def _register(
    name: str,
    description: str,
    *,
    material: MaterialSpec,
    density: float,
    friction: float,
    tags: tuple[str, ...] = (),
) -> Callable[[Callable[[], _Built]], Callable[[], _Built]]:
    """Decorator adding a builder to the catalogue; ids follow the definition order.

    Only ever append new builders at the end of this module: ids must keep their meaning.
    ``density`` in kg/m^3 (effective), ``friction`` the Coulomb coefficient.
    """

    def add(build: Callable[[], _Built]) -> Callable[[], _Built]:
        if any(e.name == name for e in _CATALOGUE):
            raise InvalidArgumentError(f"duplicate object name {name!r}")
        _CATALOGUE.append(
            _Entry(name, description, build, material, density, friction, frozenset(tags))
        )
        return build

    return add


def _mat(
    name: str,
    color: tuple[float, float, float, float],
    specular: float = 0.2,
    shininess: float = 20.0,
    opacity: float = 1.0,
    *,
    roughness: float,
    metallic: float = 0.0,
    transmission: float = 0.0,
    ior: float = 1.5,
) -> MaterialSpec:
    """Material with a grey specular colour of level ``specular`` (raster preview) and its
    physically based parameters (path tracer)."""
    return MaterialSpec(
        name, color, (specular, specular, specular), shininess, opacity, None,
        metallic=metallic, roughness=roughness, ior=ior, transmission=transmission,
    )  # fmt: skip


_WHITE = (1.0, 1.0, 1.0, 1.0)
_BLACK = (0.03, 0.03, 0.03, 1.0)
# Printed cardboard: a rough dielectric (uncoated board, matte print).
_PRINT = _mat("cardboard_print", _WHITE, 0.1, 10.0, roughness=0.75)
# Printed tinplate: lacquered print over steel, the metal showing through.
_TIN = _mat("printed_metal", _WHITE, 0.6, 60.0, roughness=0.28, metallic=0.45)
# Clear soda-lime glass / PET: a smooth dielectric that transmits (n = 1.5).
_GLASS = _mat("clear_glass", (0.85, 0.92, 0.9, 0.15), 0.9, 120.0, 0.15,
              roughness=0.02, transmission=1.0, ior=1.5)  # fmt: skip


# ----------------------------------------------------------------------------------------------
# Builders (dimensions in millimetres unless stated)
#
# Profiles of bodies of revolution are (r, z) point tables in millimetres; they are kept as
# compact tables (formatter off) so that they read like drawings.
# ----------------------------------------------------------------------------------------------


def _pal(*colors: tuple[int, int, int]) -> tx.Palette:
    return tx.Palette(*colors)


@_register(
    "box_cereal",
    "Printed cereal carton, 65 x 190 x 240 mm.",
    material=_PRINT, density=150.0, friction=0.5, tags=("box",),
)  # fmt: skip
def _box_cereal() -> _Built:
    pal = _pal((236, 180, 40), (200, 60, 40), (40, 30, 90), (250, 245, 230))
    return _printed_box((65, 190, 240), pal, "CRUNCH", 11)


@_register(
    "box_shoe",
    "Printed shoe-box-like carton, 240 x 150 x 90 mm.",
    material=_PRINT, density=120.0, friction=0.5, tags=("box",),
)  # fmt: skip
def _box_shoe() -> _Built:
    pal = _pal((190, 150, 110), (120, 85, 60), (20, 20, 20), (235, 225, 210))
    return _printed_box((240, 150, 90), pal, "STRIDE", 12)


@_register(
    "box_tea",
    "Small printed tea box, 125 x 75 x 65 mm.",
    material=_PRINT, density=250.0, friction=0.5, tags=("box",),
)  # fmt: skip
def _box_tea() -> _Built:
    pal = _pal((40, 110, 70), (200, 170, 80), (245, 240, 220), (120, 40, 40))
    return _printed_box((125, 75, 65), pal, "TEA", 13)


@_register(
    "box_cube",
    "Printed gift cube, 60 mm.",
    material=_PRINT, density=300.0, friction=0.5, tags=("box",),
)  # fmt: skip
def _box_cube() -> _Built:
    pal = _pal((90, 160, 220), (240, 240, 240), (200, 40, 60), (250, 210, 60))
    return _printed_box((60, 60, 60), pal, "GIFT", 14)


@_register(
    "box_medicine",
    "Flat printed medicine box, 100 x 45 x 20 mm.",
    material=_PRINT, density=200.0, friction=0.5, tags=("box",),
)  # fmt: skip
def _box_medicine() -> _Built:
    pal = _pal((245, 245, 245), (30, 120, 200), (20, 40, 90), (230, 60, 60))
    return _printed_box((100, 45, 20), pal, "MED 20", 15)


@_register(
    "can_soda",
    "Soda can with printed label, 66 mm diameter, 123 mm tall.",
    material=_TIN, density=880.0, friction=0.35, tags=("cylindrical",),
)  # fmt: skip
def _can_soda() -> _Built:
    # fmt: off
    prof = _mm([
        (0, 9), (12, 8.3), (20, 5.5), (24.5, 1.5), (25.5, 0), (27.5, 0), (31, 3), (33, 9),
        *[(33, z) for z in np.linspace(15, 102, 12)],
        (33, 108), (30.5, 115), (27, 119), (27.3, 121.8), (26.9, 122.6), (26.1, 122.6),
        (25.7, 121.8), (25.3, 118.8), (12, 118.8), (0, 118.8),
    ])
    # fmt: on
    mesh = revolve(prof, SEG, with_uv=True)
    v = _arc_fractions(prof)  # the label covers the straight side: profile points 7..20
    pal = _pal((200, 20, 30), (240, 240, 240), (250, 250, 250), (30, 30, 30))
    tex = tx.wrap_label(pal, "FIZZ", 21, (v[7], v[20]))
    kp = _kp(
        top_centre=(0, 0, 118.8), bottom_centre=(0, 0, 0), side_front=(33, 0, 60),
        side_back=(-33, 0, 60), rim=(0, 26.5, 122.6),
    )  # fmt: skip
    return _Built(mesh, kp, tex)


@_register(
    "can_food",
    "Ribbed food tin with paper label, 77 mm diameter, 110 mm tall.",
    material=_TIN, density=930.0, friction=0.35, tags=("cylindrical",),
)  # fmt: skip
def _can_food() -> _Built:
    zr = np.arange(20, 92.1, 1.0)
    ribs = np.stack([37.5 - 0.35 * (1.0 - np.cos(2 * np.pi * (zr - 20) / 8.0)), zr], axis=1)
    # fmt: off
    prof = _mm([
        (0, 2), (34, 2), (36, 0.8), (37.5, 0), (38.6, 1.2), (38.6, 3.2), (37.5, 4.5), (37.5, 12),
        *ribs,
        (37.5, 100), (37.5, 105.5), (38.6, 106.8), (38.6, 108.8), (37.5, 110), (36, 109.2),
        (34, 108), (0, 108),
    ])
    # fmt: on
    mesh = revolve(prof, SEG, with_uv=True)
    v = _arc_fractions(prof)  # the label covers the side between the two beads
    pal = _pal((245, 235, 200), (40, 120, 60), (150, 30, 20), (230, 120, 30))
    tex = tx.wrap_label(pal, "BEANS", 22, (v[6], v[-8]))
    kp = _kp(
        top_centre=(0, 0, 108), bottom_centre=(0, 0, 2), side_front=(37.5, 0, 56),
        side_back=(-37.5, 0, 56), rim=(0, 38.6, 108.8),
    )  # fmt: skip
    return _Built(mesh, kp, tex)


@_register(
    "spray_can",
    "Aerosol spray can with cap, 53 mm diameter, 192 mm tall.",
    material=_TIN, density=750.0, friction=0.35, tags=("cylindrical",),
)  # fmt: skip
def _spray_can() -> _Built:
    # fmt: off
    prof = _mm([
        (0, 6), (15, 4.8), (22, 2), (24.5, 0), (26.5, 1.5),
        *[(26.5, z) for z in np.linspace(10, 140, 14)],
        (26.5, 148), (26, 150.5), (24.5, 152), (25.2, 153), (25.2, 170), (25.2, 185), (24, 189),
        (20, 191), (10, 191.5), (0, 191.5),
    ])
    # fmt: on
    mesh = revolve(prof, SEG, with_uv=True)
    v = _arc_fractions(prof)
    pal = _pal((30, 60, 160), (250, 200, 30), (250, 250, 250), (230, 60, 40))
    tex = tx.wrap_label(pal, "SPRAY", 23, (v[4], v[20]), metal=(235, 235, 235))
    kp = _kp(
        cap_top=(0, 0, 191.5), bottom_centre=(0, 0, 6), side_front=(26.5, 0, 75),
        side_back=(-26.5, 0, 75), shoulder=(0, 25.2, 160),
    )  # fmt: skip
    return _Built(mesh, kp, tex)


@_register(
    "bottle_water",
    "Opaque plastic water bottle with neck and screw cap, 208 mm tall.",
    material=_mat("blue_plastic", _lin("#5fa8d3"), 0.4, 40.0, roughness=0.3),
    density=850.0, friction=0.4, tags=("cylindrical",),
)  # fmt: skip
def _bottle_water() -> _Built:
    zb = np.arange(8, 140.1, 5.0)
    groove = (zb >= 40) & (zb <= 120) & ((zb // 10) % 2 == 1)
    body = np.stack([32.8 - 0.9 * groove, zb], axis=1)
    shoulder = _arc((13, 140), (19.8, 38), 0, np.pi / 2, 12)[1:]
    # fmt: off
    prof = _mm([
        (0, 2.5), (15, 1.8), (26, 0.6), (30.5, 0), (32.3, 1.5), (32.8, 4),
        *body, *shoulder,
        (13, 184), (17, 185), (17, 187), (15.5, 188), (15.5, 198), (15.5, 206), (14.5, 208),
        (7, 208), (0, 208),
    ])
    # fmt: on
    mesh = revolve(prof, SEG)
    kp = _kp(
        cap_top=(0, 0, 208), bottom_centre=(0, 0, 2.5), side_front=(32.8, 0, 90),
        side_back=(-32.8, 0, 90), neck=(0, 13, 181),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "bottle_detergent",
    "Detergent bottle, rounded-rectangle section 95 x 60 mm, with cap.",
    material=_mat("orange_plastic", _lin("#f08a24"), 0.3, 30.0, roughness=0.4),
    density=700.0, friction=0.45,
)  # fmt: skip
def _bottle_detergent() -> _Built:
    body = rounded_box((0.095, 0.06, 0.17), 0.014, max_edge=0.012).translated((0.0, 0.0, 0.085))
    neck = _cylinder(15 * MM, 160 * MM, 186 * MM, 40)
    cap = revolve(_mm([(0, 180), (19, 180), (19, 200), (17.5, 202), (0, 202)]), 40)
    mesh = union(body, neck, cap)
    kp = _kp(
        cap_top=(0, 0, 202), bottom_centre=(0, 0, 0), front_centre=(0, -30, 85),
        back_centre=(0, 30, 85), side=(47.5, 0, 85), shoulder=(30, 0, 170),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "jar",
    "Jam jar with a metal lid, 82 mm diameter, 115 mm tall.",
    material=_mat("red_jam_glass", _lin("#8c1c24"), 0.6, 80.0, roughness=0.06),
    density=1300.0, friction=0.4, tags=("cylindrical",),
)  # fmt: skip
def _jar() -> _Built:
    # fmt: off
    prof = _mm([
        (0, 1.5), (30, 0.5), (36, 1.5), (39, 4), (40, 10),
        *[(40, z) for z in np.linspace(18, 74, 8)],
        (40, 80), (38.5, 86), (36, 90), (34, 93), (34, 96), (41, 96), (41, 106), (41, 113),
        (39.5, 115), (20, 115), (0, 115),
    ])
    # fmt: on
    mesh = revolve(prof, SEG)
    kp = _kp(
        lid_top=(0, 0, 115), bottom_centre=(0, 0, 1.5), side_front=(40, 0, 45),
        side_back=(-40, 0, 45), lid_edge=(0, 41, 105),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "mug",
    "Ceramic mug with a handle, 82 mm diameter, 96 mm tall.",
    material=_mat("white_ceramic", _lin("#ece8df"), 0.5, 60.0, roughness=0.12),
    density=2300.0, friction=0.6, tags=("nonconvex",),
)  # fmt: skip
def _mug(path_steps: int = 36, handle_segments: int = 16) -> _Built:
    # The defaults of path_steps / handle_segments were chosen so that the union leaves no
    # sliver triangles (every altitude > 10 micrometres).
    # fmt: off
    prof = _mm([
        (0, 0), (36, 0), (39.5, 1.2), (41, 4),
        *[(41, z) for z in np.linspace(12, 86, 8)],
        (41, 94), (40, 95.5), (38.5, 95.5), (37.5, 94.5), (37, 93),
        *[(37, z) for z in np.linspace(84, 18, 7)],
        (37, 11), (35.5, 8), (32, 7), (16, 7), (0, 7),
    ])
    # fmt: on
    cup = revolve(prof, SEG)
    # C-shaped handle in the x-z plane; both ends stop inside the 4 mm wall (x = 39 mm)
    t = np.linspace(0.0, np.pi, path_steps)
    path = np.stack([39 + 22 * np.sin(t), np.zeros_like(t), 50.5 + 24.5 * np.cos(t)], axis=1)
    handle = sweep_circle(path * MM, 6 * MM, handle_segments)
    mesh = union(cup, handle)
    kp = _kp(
        rim=(-39, 0, 95.5), handle=(61, 0, 50.5), bottom_centre=(0, 0, 0),
        inside_bottom=(0, 0, 7), side=(0, -41, 50),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "bowl",
    "Thick-walled ceramic bowl, 156 mm diameter.",
    material=_mat("green_ceramic", _lin("#6b9e78"), 0.5, 60.0, roughness=0.12),
    density=2300.0, friction=0.6, tags=("nonconvex",),
)  # fmt: skip
def _bowl() -> _Built:
    a0 = -np.arccos(42 / 78)
    outer = _arc((0, 58), (78, 54), a0, 0, 16)
    inner = _arc((0, 58), (73, 50), 0, -np.pi / 2, 18)[:-1]
    # fmt: off
    prof = _mm([
        (0, 0), (20, 0), (40, 0), (42, 2), *outer,
        (77.4, 59.6), (75.5, 60.2), (73.6, 59.6), *inner, (0, 8),
    ])
    # fmt: on
    mesh = revolve(prof, SEG)
    kp = _kp(
        rim_front=(75.5, 0, 60.2), rim_back=(-75.5, 0, 60.2), inside_bottom=(0, 0, 8),
        bottom_centre=(0, 0, 0), outer_side=(0, -70, 35),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "cup_black",
    "Black plastic cup, tapered, 86 mm rim diameter.",
    material=_mat("black_plastic", _BLACK, 0.3, 30.0, roughness=0.35),
    density=1100.0, friction=0.5, tags=("nonconvex", "black", "novel"),
)  # fmt: skip
def _cup_black() -> _Built:
    s = np.linspace(0, 1, 10)
    outer = np.stack([30.5 + 11.5 * s, 1.5 + 86.5 * s], axis=1)
    inner = np.stack([39.6 - 12.1 * s, 88 - 84.5 * s], axis=1)
    # fmt: off
    prof = _mm([
        (0, 0), (15, 0), (29, 0), *outer,
        (42.8, 89.3), (42.5, 90.5), (41, 90.8), (39.8, 89.5), *inner, (14, 3.5), (0, 3.5),
    ])
    # fmt: on
    mesh = revolve(prof, SEG)
    kp = _kp(
        rim_front=(41.5, 0, 90.8), rim_back=(-41.5, 0, 90.8), inside_bottom=(0, 0, 3.5),
        bottom_centre=(0, 0, 0), side=(0, -36, 45),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "pipe_straight",
    "Straight PVC pipe, 40 mm outer / 32 mm inner diameter, 200 mm long.",
    material=_mat("grey_pvc", _lin("#9a9ea3"), 0.3, 30.0, roughness=0.55),
    density=1400.0, friction=0.5, tags=("nonconvex", "cylindrical"),
)  # fmt: skip
def _pipe_straight() -> _Built:
    zs = np.linspace(0, 200, 21)
    prof = _mm([(20, z) for z in zs] + [(16, z) for z in zs[::-1]])
    mesh = revolve(prof, 48, closed=True)
    kp = _kp(
        end_a=(0, 0, 0), end_b=(0, 0, 200), rim_a=(18, 0, 0), rim_b=(-18, 0, 200),
        middle=(0, 20, 100),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "pipe_elbow",
    "90-degree PVC elbow, 40 mm outer diameter, 50 mm bend radius.",
    material=_mat("white_pvc", _lin("#e6e6e1"), 0.3, 30.0, roughness=0.55),
    density=1400.0, friction=0.5, tags=("nonconvex",),
)  # fmt: skip
def _pipe_elbow() -> _Built:
    stub_a = np.stack([np.linspace(-30, 0, 6), np.zeros(6), np.zeros(6)], axis=1)
    a = np.linspace(0, np.pi / 2, 25)
    arc = np.stack([50 * np.sin(a), np.zeros_like(a), 50 - 50 * np.cos(a)], axis=1)
    stub_b = np.stack([np.full(6, 50.0), np.zeros(6), np.linspace(50, 80, 6)], axis=1)
    path = _polyline(stub_a, arc, stub_b) * MM
    mesh = sweep_hollow(path, 20 * MM, 16 * MM, 32)
    c45 = np.cos(np.pi / 4)
    bend = (50 * c45 + 20 * c45, 0, 50 - 50 * c45 - 20 * c45)
    kp = _kp(
        end_a=(-30, 0, 0), end_b=(50, 0, 80), bend_outer=bend, rim_a=(-30, 0, 18),
        rim_b=(68, 0, 80),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "l_bracket",
    "Steel L-bracket, 80 x 60 x 40 mm, 4 mm plate, two holes.",
    material=_mat("zinc_steel", _lin("#b8bcc2"), 0.8, 80.0, roughness=0.4, metallic=1.0),
    density=7850.0, friction=0.4, tags=("nonconvex",),
)  # fmt: skip
def _l_bracket() -> _Built:
    fillet = _arc((8, 8), (4, 4), -np.pi / 2, -np.pi, 7)
    outline = _mm([(0, 0), (40, 0), (80, 0), (80, 4), *fillet, (4, 34), (4, 60), (0, 60), (0, 30)])
    plate = extrude(outline, height=40 * MM, layers=4)
    # the outline is drawn in the part's x-z plane: rotating +90 degrees about x sends the
    # drawing's y to z and the extrusion axis to -y; then centre the 40 mm width on y = 0
    plate = plate.transformed(rotation_matrix((1, 0, 0), np.pi / 2), (0.0, 20 * MM, 0.0))
    hole_a = _cylinder(3.5 * MM, -5 * MM, 10 * MM, 32).translated((50 * MM, 0.0, 0.0))
    hole_b = _cylinder(3.5 * MM, -5 * MM, 10 * MM, 32).transformed(
        rotation_matrix((0, 1, 0), np.pi / 2), (0.0, 0.0, 38 * MM)
    )
    mesh = ensure_min_faces(difference(plate, hole_a, hole_b), 300)
    kp = _kp(
        corner=(0, 0, 0), flange_tip=(80, 0, 2), upright_top=(2, 0, 60), hole_flange=(50, 0, 4),
        hole_upright=(4, 0, 38),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "hex_nut",
    "M16 steel hex nut, 24 mm across flats, 13 mm thick.",
    material=_mat("steel", _lin("#a7abb0"), 0.8, 80.0, roughness=0.18, metallic=1.0),
    density=7850.0, friction=0.4, tags=("nonconvex",),
)  # fmt: skip
def _hex_nut() -> _Built:
    ang = np.arange(6) * (np.pi / 3)
    hexagon = np.stack([np.cos(ang), np.sin(ang)], axis=1) * (24.0 / np.sqrt(3.0))
    phi = np.arange(48) * (2 * np.pi / 48)
    hole = np.stack([np.cos(phi), np.sin(phi)], axis=1) * 8.0
    mesh = extrude(hexagon * MM, [hole * MM], height=13 * MM, layers=3)
    c30, s30 = np.cos(np.pi / 6), np.sin(np.pi / 6)
    kp = _kp(
        bore_top=(0, 0, 13), bore_bottom=(0, 0, 0), top_face=(0, 10.5, 13),
        flat=(12 * c30, 12 * s30, 6.5),
    )  # fmt: skip
    return _Built(ensure_min_faces(mesh, 300), kp)


@_register(
    "clamp",
    "C-clamp: C-shaped frame, screw with pad and T-bar.",
    material=_mat("red_cast_iron", _lin("#b3261e"), 0.4, 40.0, roughness=0.5),
    density=4500.0, friction=0.5, tags=("nonconvex", "novel"),
)  # fmt: skip
def _clamp() -> _Built:
    outline = _mm([(0, 0), (70, 0), (70, 16), (14, 16), (14, 84), (70, 84), (70, 100), (0, 100)])
    frame = extrude(outline, height=14 * MM, layers=2)
    frame = frame.transformed(rotation_matrix((1, 0, 0), np.pi / 2), (0.0, 7 * MM, 0.0))
    screw = _cylinder(5 * MM, -22 * MM, 55 * MM, 24, 6).translated((58 * MM, 0.0, 0.0))
    pad = _cylinder(9 * MM, 55 * MM, 61 * MM, 32).translated((58 * MM, 0.0, 0.0))
    bar = _cylinder(3.5 * MM, -25 * MM, 25 * MM, 16, 4).transformed(
        rotation_matrix((1, 0, 0), np.pi / 2), (58 * MM, 0.0, -18 * MM)
    )
    mesh = ensure_min_faces(union(frame, screw, pad, bar), 300)
    kp = _kp(
        screw_pad=(58, 0, 61), handle_end=(58, 25, -18), jaw=(58, 0, 84), back=(0, 0, 50),
        frame_top=(35, 0, 100),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "pear",
    "Pear-shaped fruit with a stem, 100 mm tall.",
    material=_mat("pear_green", _lin("#b5c64a"), 0.3, 25.0, roughness=0.45),
    density=980.0, friction=0.6,
)  # fmt: skip
def _pear(stem_steps: int = 10, stem_segments: int = 10) -> _Built:
    # The defaults of stem_steps / stem_segments were chosen so that the union leaves no
    # sliver triangles (every altitude > 10 micrometres).
    h = 100.0
    t = np.linspace(0, np.pi, 42)[1:-1]
    z = h * (1 - np.cos(t)) / 2
    r = np.sin(t) * (36 - 24 * (z / h) ** 1.6)
    body = revolve(_mm([(0, 0), *np.stack([r, z], axis=1), (0, h)]), 48)
    s = np.linspace(0, 1, stem_steps)
    stem_path = np.stack([3 * s**2, np.zeros_like(s), h - 4 + 18 * s], axis=1) * MM
    stem = sweep_circle(stem_path, 2.2 * MM, stem_segments)
    mesh = union(body, stem)
    k = int(np.argmax(r))
    kp = _kp(
        stem_tip=(3, 0, h + 14), bottom=(0, 0, 0), widest_front=(r[k], 0, z[k]),
        widest_back=(-r[k], 0, z[k]), neck=(0, 14, 82),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "tennis_ball",
    "Tennis ball, 67 mm diameter.",
    material=_mat("felt_yellow", _lin("#d4e83a"), 0.05, 5.0, roughness=0.95),
    density=360.0, friction=0.8,
)  # fmt: skip
def _tennis_ball() -> _Built:
    mesh = superellipsoid((33.5 * MM,) * 3, steps=14)
    kp = _kp(top=(0, 0, 33.5), bottom=(0, 0, -33.5), side=(33.5, 0, 0))
    return _Built(mesh, kp)


@_register(
    "marker_pen",
    "Marker pen with clip, 17 mm diameter, 142 mm long.",
    material=_mat("marker_blue", _lin("#1f4fb4"), 0.4, 40.0, roughness=0.3),
    density=600.0, friction=0.4, tags=("cylindrical",),
)  # fmt: skip
def _marker() -> _Built:
    # fmt: off
    prof = _mm([
        (0, 0), (1.2, 0.3), (2.2, 2), (2.4, 6), (4.5, 7), (6.5, 11), (7.5, 14),
        *[(7.5, z) for z in np.linspace(24, 94, 8)],
        (7.5, 100), (8.4, 100), *[(8.4, z) for z in np.linspace(110, 130, 3)], (8.4, 137),
        (7.8, 140), (6, 141.5), (0, 141.8),
    ])
    # fmt: on
    pen = revolve(prof, 48)
    clip = grid_box((2.3 * MM, 3 * MM, 34 * MM), max_edge=0.004, min_divisions=2)
    mesh = union(pen, clip.translated((9.05 * MM, 0.0, 121 * MM)))
    kp = _kp(
        tip=(0, 0, 0), cap_end=(0, 0, 141.8), clip=(10.2, 0, 121), grip=(-7.5, 0, 40),
        cap_edge=(0, 8.4, 100),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "cable_coil",
    "Black cable coiled in 3.5 turns, 6 mm cable, 86 mm coil diameter.",
    material=_mat("black_rubber", _BLACK, 0.2, 15.0, roughness=0.85),
    density=1800.0, friction=0.8, tags=("nonconvex", "black", "deformable", "novel"),
)  # fmt: skip
def _cable_coil() -> _Built:
    turns, radius, pitch, r = 3.5, 40.0, 9.5, 3.0  # pitch > 2 r: turns do not touch
    t = np.linspace(0, turns * 2 * np.pi, int(turns * 48) + 1)
    helix = np.stack([radius * np.cos(t), radius * np.sin(t), pitch * t / (2 * np.pi)], axis=1)
    mesh = sweep_circle(helix * MM, r * MM, 10)
    top_z = pitch * turns
    kp = _kp(
        end_a=helix[0], end_b=helix[-1], coil_top=(-radius, 0, top_z - pitch / 2 + r),
        coil_outer=(0, radius + r, pitch / 4),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "wine_glass",
    "Clear wine glass, 80 mm bowl diameter, 166 mm tall.",
    material=_GLASS, density=2500.0, friction=0.4, tags=("nonconvex", "transparent", "novel"),
)  # fmt: skip
def _wine_glass() -> _Built:
    # bowl: outer ellipse (40 x 50 mm) and inner ellipse 1.5 mm inside it, same centre
    bowl_out = _arc((0, 135), (40, 50), np.deg2rad(-80), np.arcsin(0.6), 22)
    bowl_in = _arc((0, 135), (38.5, 48.5), np.arcsin(30 / 48.5), -np.pi / 2, 24)[:-1]
    rim = (0.5 * (bowl_out[-1][0] + bowl_in[0][0]), 165.9)
    # fmt: off
    prof = _mm([
        (0, 0), (20, 0), (35, 0), (35, 2), (30, 3.5), (18, 5), (8, 6.5), (5, 9), (4, 14),
        *[(4, z) for z in np.linspace(24, 74, 6)],
        (4, 80), (5, 83.5), *bowl_out, rim, *bowl_in, (0, 86.5),
    ])
    # fmt: on
    mesh = revolve(prof, SEG)
    kp = _kp(
        rim=(rim[0], 0, 165.9), foot_centre=(0, 0, 0), foot_edge=(-35, 0, 1), stem=(0, 4, 45),
        bowl=(-40, 0, 135),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "bottle_clear",
    "Clear empty glass bottle with open mouth, 60 mm diameter, 200 mm tall.",
    material=_GLASS, density=2500.0, friction=0.4,
    tags=("nonconvex", "transparent", "cylindrical", "novel"),
)  # fmt: skip
def _bottle_clear() -> _Built:
    out_sh = _arc((12, 140), (18, 35), 0, np.pi / 2, 12)
    in_sh = _arc((10.5, 140), (17.5, 33), np.pi / 2, 0, 12)
    # fmt: off
    prof = _mm([
        (0, 0), (20, 0), (27, 0.5), (29.5, 2.5), (30, 6),
        *[(30, z) for z in np.linspace(20, 130, 12)],
        *out_sh, (12, 185), (12, 194), (13.5, 195.5), (13.5, 199), (12.5, 200), (11, 200),
        (10.5, 198), (10.5, 186), *in_sh,
        *[(28, z) for z in np.linspace(130, 20, 12)],
        (28, 8), (27, 5.5), (20, 4.2), (0, 4),
    ])
    # fmt: on
    mesh = revolve(prof, SEG)
    kp = _kp(
        mouth=(0, 0, 200), bottom_centre=(0, 0, 0), side_front=(30, 0, 80),
        side_back=(-30, 0, 80), neck=(0, 12, 188),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "remote_control",
    "Black remote control, rounded 180 x 48 x 22 mm with buttons.",
    material=_mat("black_abs", _BLACK, 0.3, 30.0, roughness=0.3),
    density=800.0, friction=0.5, tags=("black",),
)  # fmt: skip
def _remote() -> _Built:
    body = rounded_box((0.18, 0.048, 0.022), 0.007, max_edge=0.01)
    spots = [(-50, -11), (-50, 11), (-28, -11), (-28, 11), (-6, 0), (30, 0), (70, 0)]
    buttons = [
        _cylinder(4 * MM, 9 * MM, 12.5 * MM, 24).translated((x * MM, y * MM, 0.0)) for x, y in spots
    ]
    mesh = union(body, *buttons)
    kp = _kp(
        top_centre=(0, 0, 11), bottom_centre=(0, 0, -11), end_front=(90, 0, 0),
        end_back=(-90, 0, 0), power_button=(70, 0, 12.5),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "sack",
    "Small filled sack (pillow-like, static shape), 200 x 140 x 64 mm.",
    material=_mat("burlap", _lin("#b79a6b"), 0.05, 5.0, roughness=0.95),
    density=600.0, friction=0.9, tags=("deformable", "novel"),
)  # fmt: skip
def _sack() -> _Built:
    noise = _smooth_noise(7, 0.05)
    mesh = superellipsoid((0.10, 0.07, 0.032), e1=0.35, e2=0.5, steps=24, noise=noise)
    v = mesh.vertices

    def extreme(axis: int, sign: float) -> tuple[float, float, float]:
        p = v[int(np.argmax(sign * v[:, axis]))]
        return (float(p[0]), float(p[1]), float(p[2]))

    kp = (
        ("top_centre", extreme(2, 1.0)),
        ("bottom_centre", extreme(2, -1.0)),
        ("end_a", extreme(0, 1.0)),
        ("end_b", extreme(0, -1.0)),
        ("side", extreme(1, 1.0)),
    )
    return _Built(mesh, kp)


@_register(
    "sponge",
    "Kitchen sponge, 95 x 65 x 30 mm.",
    material=_mat("sponge_yellow", _lin("#f2d13a"), 0.05, 5.0, roughness=0.9),
    density=40.0, friction=1.0, tags=("deformable",),
)  # fmt: skip
def _sponge() -> _Built:
    mesh = rounded_box((0.095, 0.065, 0.03), 0.006, max_edge=0.008)
    kp = _kp(
        top_centre=(0, 0, 15), bottom_centre=(0, 0, -15), end_a=(47.5, 0, 0),
        end_b=(-47.5, 0, 0), side=(0, 32.5, 0),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "toothpaste_tube",
    "Toothpaste tube with cap, flattened at the crimped end.",
    material=_mat("tube_white", _lin("#f4f6f8"), 0.4, 40.0, roughness=0.3),
    density=1100.0, friction=0.5, tags=("deformable",),
)  # fmt: skip
def _toothpaste() -> _Built:
    # elliptic cross-sections: round shoulder (z 0..8 mm), then widening and flattening
    # towards the crimped seal (z 150..160 mm)
    zs = np.concatenate([np.linspace(0, 8, 6), np.linspace(8, 150, 40)[1:], [155.0, 160.0]])
    a = np.empty_like(zs)
    b = np.empty_like(zs)
    sh = zs <= 8
    a[sh] = b[sh] = 9 + 7 * np.sin(0.5 * np.pi * zs[sh] / 8)
    s = np.clip((zs[~sh] - 8) / 142, 0, 1)
    a[~sh] = 16 + 9 * s**1.5
    b[~sh] = 16 - 14.5 * s**0.8
    phi = np.arange(32) * (2 * np.pi / 32)
    rings = np.stack(
        [
            a[:, None] * np.cos(phi)[None, :],
            b[:, None] * np.sin(phi)[None, :],
            np.repeat(zs[:, None], 32, axis=1),
        ],
        axis=2,
    )
    tube = loft(rings * MM)
    cap = revolve(_mm([(0, -18), (10, -18), (11, -17), (11, -8), (11, 1), (0, 1)]), 32)
    mesh = union(tube, cap)
    kp = _kp(
        cap_end=(0, 0, -18), crimp=(0, 0, 160), body_front=(0, -15.2, 40),
        body_back=(0, 15.2, 40), crimp_corner=(25, 0, 158),
    )  # fmt: skip
    return _Built(mesh, kp)


@_register(
    "tape_roll",
    "Roll of packing tape, 110 mm outer / 76 mm inner diameter, 48 mm wide.",
    material=_mat("tape_brown", _lin("#a8763e"), 0.5, 50.0, roughness=0.25),
    density=1100.0, friction=0.6, tags=("nonconvex", "cylindrical"),
)  # fmt: skip
def _tape_roll() -> _Built:
    c = 1.5  # corner radius of the rectangular section r 38..55 mm, z 0..48 mm
    # fmt: off
    prof = _mm([
        *_arc((38 + c, c), (c, c), np.pi, 1.5 * np.pi, 4),
        *[(r, 0) for r in np.linspace(42, 51, 4)],
        *_arc((55 - c, c), (c, c), 1.5 * np.pi, 2 * np.pi, 4),
        *[(55, z) for z in np.linspace(8, 40, 5)],
        *_arc((55 - c, 48 - c), (c, c), 0, 0.5 * np.pi, 4),
        *[(r, 48) for r in np.linspace(51, 42, 4)],
        *_arc((38 + c, 48 - c), (c, c), 0.5 * np.pi, np.pi, 4),
        *[(38, z) for z in np.linspace(40, 8, 5)],
    ])
    # fmt: on
    mesh = revolve(prof, SEG, closed=True)
    kp = _kp(
        core_centre=(0, 0, 24), top_face=(46.5, 0, 48), outer_side=(0, -55, 24),
        inner_side=(-38, 0, 24), bottom_face=(0, 46.5, 0),
    )  # fmt: skip
    return _Built(mesh, kp)


def _size_tags(extents: np.ndarray) -> set[str]:
    tags = set()
    if extents.max() <= SMALL_MAX_EXTENT:
        tags.add("small")
    if extents.max() >= LARGE_MIN_EXTENT:
        tags.add("large")
    if extents.min() <= THIN_MAX_EXTENT:
        tags.add("thin")
    return tags


def _finish(category_id: int, entry: _Entry) -> ObjectSpec:
    built = entry.build()
    mesh = built.mesh
    centre = 0.5 * (mesh.vertices.min(axis=0) + mesh.vertices.max(axis=0))
    vertices = mesh.vertices - centre
    keypoints = tuple(
        Keypoint(k + 1, name, tuple(float(c) for c in np.asarray(pos) - centre))  # type: ignore[arg-type]
        for k, (name, pos) in enumerate(built.keypoints)
    )
    material = entry.material
    tags = set(entry.tags) | _size_tags(vertices.max(axis=0) - vertices.min(axis=0))
    if built.texture is not None:
        material = dataclasses.replace(material, texture=built.texture)
        tags.add("textured")
    return ObjectSpec(
        category_id=category_id,
        name=entry.name,
        description=entry.description,
        vertices=vertices,
        faces=mesh.faces,
        uvs=mesh.uvs if built.texture is not None else None,
        material=material,
        density=entry.density,
        friction=entry.friction,
        keypoints=keypoints,
        tags=frozenset(tags),
    )


@functools.lru_cache(maxsize=1)
def builtin_objects() -> tuple[ObjectSpec, ...]:
    """All built-in objects in category-id order (ids 1..N). Built once, then cached."""
    return tuple(_finish(i + 1, e) for i, e in enumerate(_CATALOGUE))


def object_names() -> list[str]:
    """Names of the built-in objects in category-id order (cheap: does not build meshes)."""
    return [e.name for e in _CATALOGUE]


def get_object(name_or_id: str | int) -> ObjectSpec:
    """Look up a built-in object by name (``"mug"``) or category id (``12`` or ``"12"``).

    Raises:
        KeyError: unknown name or id (the message lists the valid names).
        TypeError: ``name_or_id`` is neither a str nor an int.
    """
    names = object_names()
    if isinstance(name_or_id, bool) or not isinstance(name_or_id, (str, int, np.integer)):
        raise InvalidTypeError(
            "get_object expects a name (str) or a category id (int), "
            f"got {type(name_or_id).__name__}"
        )
    if isinstance(name_or_id, str) and not name_or_id.strip().isdigit():
        if name_or_id not in names:
            raise KeyError(f"unknown object name {name_or_id!r}; valid names: {', '.join(names)}")
        return builtin_objects()[names.index(name_or_id)]
    cid = int(name_or_id)
    if not 1 <= cid <= len(names):
        raise KeyError(
            f"unknown object id {name_or_id!r}: valid ids are 1..{len(names)} ({', '.join(names)})"
        )
    return builtin_objects()[cid - 1]
