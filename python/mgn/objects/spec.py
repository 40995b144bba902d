"""What an object class of mgn is: :class:`ObjectSpec` (geometry, appearance, physics and
semantics), its :class:`MaterialSpec` and :class:`Keypoint` s, and the tags it may carry.

Frames and units: every :class:`ObjectSpec` holds a closed triangle mesh in metres, in the
object frame, whose origin is the centre of the mesh's axis-aligned bounding box, z up (the
"natural" standing pose of the object). Densities are in kg/m^3 and are *effective* densities:
mass = density x enclosed mesh volume (so a closed cereal box is light, a full can is close to
water).

Tags (a subset of :data:`ALLOWED_TAGS`) describe the object for dataset splits:

- ``box`` a printed carton; ``cylindrical`` a body of revolution with a round side;
- ``nonconvex`` clearly non-convex (volume < 70 % of its convex hull: cups, pipes, brackets...);
- ``transparent`` material opacity < 0.5; ``black`` base colour below 0.05 in every channel;
- ``deformable`` soft in reality (the mesh is one static shape); ``textured`` has a texture;
- ``novel`` held out of training sets by default (the unseen split of ``mgn generate --split``):
  the paper's novel set of non-convex, black, shape-varying and transparent objects;
- ``random`` a seeded random procedural shape (:mod:`mgn.objects.random_shapes`);
- ``small`` largest extent <= 70 mm; ``large`` largest extent >= 180 mm; ``thin`` smallest
  extent <= 25 mm. The three size tags are derived from the mesh (:func:`size_tags`), never
  declared by hand.
"""

from __future__ import annotations

import io
from dataclasses import dataclass, field

import numpy as np
from PIL import Image

from mgn.errors import InvalidArgumentError
from mgn.geometry import mesh as geo

__all__ = [
    "ALLOWED_TAGS",
    "Keypoint",
    "MaterialSpec",
    "ObjectSpec",
    "size_tags",
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
        "random",
    }
)

SMALL_MAX_EXTENT = 0.070  # m, "small": largest bounding-box extent at most this
LARGE_MIN_EXTENT = 0.180  # m, "large": largest bounding-box extent at least this
THIN_MAX_EXTENT = 0.025  # m, "thin": smallest bounding-box extent at most this


def size_tags(extents: np.ndarray) -> set[str]:
    """The size tags (``small``, ``large``, ``thin``) of bounding-box ``extents`` (3,), metres."""
    tags = set()
    if extents.max() <= SMALL_MAX_EXTENT:
        tags.add("small")
    if extents.max() >= LARGE_MIN_EXTENT:
        tags.add("large")
    if extents.min() <= THIN_MAX_EXTENT:
        tags.add("thin")
    return tags


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
        out: np.ndarray = self.vertices.max(axis=0) - self.vertices.min(axis=0)
        return out

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
