"""User objects: a mesh file plus a small YAML description.

Example ``my_objects.yaml`` (paths relative to the YAML file; SI units)::

    objects:
      - name: bracket_a            # unique name: a letter, then letters, digits, _ or -
        mesh: meshes/bracket.stl   # any format mgn.load_mesh reads
        scale: 0.001               # file in millimetres
        density: 2700              # kg/m^3
        friction: 0.4
        category_id: 101           # optional; default: after the built-in objects
        color: [0.6, 0.6, 0.65, 1.0]   # optional linear RGBA; default: the file's material
        opacity: 1.0               # optional
        metallic: 0.0              # optional, [0, 1]        (physically based, path tracer;
        roughness: 0.4             # optional, [0, 1]         default: the file's glTF/GLB
        ior: 1.5                   # optional, [1, 4]         factors, else derived from its
        transmission: 0.0          # optional, [0, 1]         Phong material)
        keypoints:                 # optional, object frame, metres (default: top/bottom)
          tip: [0.0, 0.0, 0.05]
          hole: [0.01, 0.0, 0.0]
        tags: [nonconvex]          # optional, see mgn.objects.ALLOWED_TAGS
        description: Aluminium bracket
        repair: false              # optional: repair a nearly closed mesh as it is read
        allow_open: false          # optional: accept an open mesh (shell mass, no pj labels)

The mesh keeps its own frame. It must be watertight and consistently wound (mass properties
are exact); closed solids that touch along an edge or at a vertex are (:meth:`mgn.Mesh.validate`
splits them into closed pieces; the volume is that of all pieces). ``repair: true`` repairs a
nearly closed mesh as it is read (:func:`mgn.geometry.repair.repair_mesh`: duplicate and stray
faces removed, faces turned to one winding, holes up to 1 % of the surface closed; the file is
not changed), when that closes it.
A mesh that stays open needs ``allow_open: true``: the documented shell model is then used
(2 mm walls: its mass is that of a shell, not of a solid) and the object gets suction labels
only: its parallel-jaw label set is empty (``pj_skipped`` in the metadata says why), since the
antipodal sampler needs a closed volume. ``mgn objects add`` sets either key when the mesh needs
it and says what the repair changed.

Any mesh file works: a material the file does not give (an OBJ without ``.mtl``, ``Ns 0``) gets
the default grey plastic. Numbers may be written ``2.7e3`` or ``1.0e-3``. Every error names the
YAML file, the object and the key; a part whose largest extent (after ``scale``) is above 1 m or
below 1 mm gets a :class:`ImplausibleSizeWarning` (a file in millimetres read as metres is the
usual cause), and a material file the mesh points to that is missing or unreadable (an OBJ's
``.mtl``, a ``map_Kd`` or glTF image) a :class:`MissingMaterialWarning` naming the file.
``mgn objects add MESH... --to my_objects.yaml`` writes this file for you.
"""

from __future__ import annotations

import io
import math
import os
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from mgn.base.yaml_file import read_yaml
from mgn.errors import InvalidArgumentError, MgnError
from mgn.geometry.mesh import Material, load_mesh, missing_material_files
from mgn.geometry.repair import repair_mesh
from mgn.objects.library import builtin_objects
from mgn.objects.spec import Keypoint, MaterialSpec, ObjectSpec

__all__ = [
    "OBJECT_NAME_PATTERN",
    "ImplausibleSizeWarning",
    "MissingMaterialWarning",
    "UserObjectWarning",
    "check_object_name",
    "describe_material",
    "load_objects_yaml",
    "warn_implausible_size",
    "warn_missing_material_files",
]

#: Largest extents (m) outside which a part is reported as implausible for a tote.
PLAUSIBLE_EXTENT_M = (1e-3, 1.0)
#: A user object's name: a letter, then at most 63 letters, digits, ``_`` or ``-``. No spaces or
#: commas (command lines split name lists at both), and never all digits (a number names a
#: category id, e.g. ``12`` is the built-in ``mug``).
OBJECT_NAME_PATTERN = re.compile(r"[A-Za-z][A-Za-z0-9_-]{0,63}")


def check_object_name(name: object, where: str) -> str:
    """``name`` when it matches :data:`OBJECT_NAME_PATTERN`; else InvalidArgumentError naming
    ``where``, the name and the rule."""
    text = str(name)
    if isinstance(name, str) and OBJECT_NAME_PATTERN.fullmatch(text):
        return text
    why = ""
    if text.strip().isdigit():
        why = " (a number names a category id: it would shadow category " + text.strip() + ")"
    elif "," in text or any(c.isspace() for c in text):
        why = " (name lists on the command line are split at commas and spaces)"
    raise InvalidArgumentError(
        f"{where}: object name {text!r} is not allowed{why}; expected a letter followed by at "
        "most 63 letters, digits, '_' or '-', e.g. 'my_part_2'"
    )


class UserObjectWarning(UserWarning):
    """A warning about one user object (its message names the YAML file, the object and the
    mesh). ``object_name``: the object's name, or None for a mesh outside a YAML file."""

    def __init__(self, message: str, object_name: str | None = None) -> None:
        super().__init__(message)
        self.object_name = object_name


class ImplausibleSizeWarning(UserObjectWarning):
    """A part is larger than 1 m or smaller than 1 mm: probably a wrong ``scale``."""


class MissingMaterialWarning(UserObjectWarning):
    """A material file of a mesh (an OBJ's ``.mtl``, a ``map_Kd`` or glTF texture image) is not
    where the mesh file points, or cannot be read as an image: the object renders in its plain
    base colour."""


def warn_missing_material_files(
    path: str | os.PathLike[str],
    mesh: Any,
    source: str,
    object_name: str | None = None,
    unreadable: list[tuple[str, str]] | None = None,
    notes: list[UserObjectWarning] | None = None,
) -> list[str]:
    """Warn (:class:`MissingMaterialWarning`, naming ``source`` and each file) for every
    material file the mesh file ``path`` points to that is missing
    (:func:`mgn.geometry.mesh.missing_material_files`), and for the (what, file) pairs of
    ``unreadable`` (files there, but not images); with ``notes`` the warnings are appended to it
    instead of being given. Returns the files warned about."""
    found = missing_material_files(path, mesh) + list(unreadable or ())
    mat = mesh.materials[0] if mesh.materials else None
    rgb = ", ".join(f"{c:.2f}" for c in (mat.base_color[:3] if mat is not None else (0.7,) * 3))
    for what, file in found:
        missing = "cannot be read" if "readable" in what else "is missing"
        _give(
            MissingMaterialWarning(
                f"{source}: its {what} '{file}' {missing}; the object renders in its plain "
                f"base colour ({rgb}) instead (put the file there, or set 'color' in the YAML "
                "entry)",
                object_name,
            ),
            notes,
        )
    return [file for _, file in found]


def _give(w: UserObjectWarning, notes: list[UserObjectWarning] | None) -> None:
    """Give warning ``w`` (to the caller of the public function), or append it to ``notes``."""
    if notes is None:
        warnings.warn(w, stacklevel=4)
    else:
        notes.append(w)


def warn_implausible_size(
    vertices: np.ndarray,
    source: str,
    object_name: str | None = None,
    notes: list[UserObjectWarning] | None = None,
) -> bool:
    """Warn (:class:`ImplausibleSizeWarning`, naming ``source``) when the largest extent of
    ``vertices`` (m) is outside :data:`PLAUSIBLE_EXTENT_M` (with ``notes``: append the warning
    to it instead). Returns True when it warned."""
    v = np.asarray(vertices, np.float64).reshape(-1, 3)
    if len(v) == 0:
        return False
    extent = float(np.ptp(v, axis=0).max())
    lo, hi = PLAUSIBLE_EXTENT_M
    if extent > hi:
        msg = (
            f"{source} is {extent:.3g} m across, too large for a part in a tote; if the file "
            "is in millimetres, use scale 0.001"
        )
    elif extent < lo:
        msg = (
            f"{source} is {extent * 1e3:.3g} mm across, too small for a picked part; check "
            "its scale (the file's unit)"
        )
    else:
        return False
    _give(ImplausibleSizeWarning(msg, object_name), notes)
    return True


def _number(entry: dict[str, Any], key: str, where: str, default: float | None = None) -> float:
    value = entry.get(key, default)
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    if not ok or not math.isfinite(float(value)) or float(value) <= 0:  # type: ignore[arg-type]
        raise InvalidArgumentError(f"{where}: key '{key}': expected a number > 0, got {value!r}")
    return float(value)  # type: ignore[arg-type]


_KEYS = {
    "name",
    "mesh",
    "scale",
    "density",
    "friction",
    "category_id",
    "color",
    "opacity",
    "metallic",
    "roughness",
    "ior",
    "transmission",
    "keypoints",
    "tags",
    "description",
    "allow_open",
    "repair",
}


def _rgba(v: Any) -> tuple[float, float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]), float(v[3]))


def _rgb(v: Any) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def _texture(path: str) -> np.ndarray | None:
    if not path:
        return None

    try:
        with Image.open(path) as img:
            return np.asarray(img.convert("RGB"), dtype=np.uint8)
    except OSError:
        return None  # a missing texture leaves the base colour; the mesh is still usable


def _embedded_texture(data: bytes) -> np.ndarray | None:
    """An embedded (GLB) texture's PNG/JPEG bytes as an RGB image; None if absent or broken."""
    if not data:
        return None
    try:
        with Image.open(io.BytesIO(data)) as img:
            return np.asarray(img.convert("RGB"), dtype=np.uint8)
    except OSError:
        return None


def _base_color_texture(
    mat: Any, mesh_path: Path
) -> tuple[np.ndarray | None, list[tuple[str, str]]]:
    """The RGB texture of material ``mat`` (its file, else its embedded image), and the
    (what, file) pairs of the images that are there but cannot be read."""
    if mat is None:
        return None, []
    unreadable = []
    texture = _texture(mat.texture_path)
    if texture is None and mat.texture_path and Path(mat.texture_path).is_file():
        unreadable.append(
            (f"texture of material '{mat.name}' (not a readable image)", str(mat.texture_path))
        )
    if texture is None:
        texture = _embedded_texture(bytes(mat.texture_data))
        if texture is None and len(mat.texture_data):
            unreadable.append(
                (
                    f"embedded texture of material '{mat.name}' (not a readable image)",
                    os.fspath(mesh_path),
                )
            )
    return texture, unreadable


def _number_in(entry: dict[str, Any], key: str, where: str, lo: float, hi: float) -> float | None:
    """``entry[key]`` as a float in [lo, hi], None when absent; else an error naming the key."""
    if key not in entry:
        return None
    value = entry[key]
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    if not ok or not (math.isfinite(float(value)) and lo <= float(value) <= hi):
        raise InvalidArgumentError(
            f"{where}: key '{key}': expected a number in [{lo:g}, {hi:g}], got {value!r}"
        )
    return float(value)


#: Roughness range of a material derived from a Phong description. Exporters write large Phong
#: exponents by default, so an exponent alone never makes a polished (mirror-like) surface.
PHONG_ROUGHNESS = (0.3, 1.0)
#: A Phong material reads as a metal only with a diffuse colour at most this bright (luminance;
#: a metal has no diffuse part), a specular colour of luminance >= 0.8 and an exponent >= 200.
PHONG_METAL_DIFFUSE = 0.05


def _luminance(rgb: Any) -> float:
    c = np.asarray(rgb, np.float64)[:3]
    return float(0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2])


def pbr_defaults(mat: Material | None, opacity: float = 1.0) -> dict[str, float]:
    """metallic, roughness, ior, transmission of a mesh file's material: its glTF/GLB factors
    when it has them (``Material.has_pbr``), else derived from the Phong description,
    conservatively: roughness from the Phong exponent n through the Beckmann correspondence
    alpha = sqrt(2 / (n + 2)), roughness = sqrt(alpha), clamped to :data:`PHONG_ROUGHNESS`
    ([0.3, 1]: never polished); a metal only when the diffuse colour is dark (luminance <=
    :data:`PHONG_METAL_DIFFUSE`), the specular one mirror-like (luminance >= 0.8) and n >= 200
    (its base colour is then the specular colour); opacity < 0.5 a clear dielectric
    (transmission 1, roughness 0.02). :func:`describe_material` says which rule applied."""
    if mat is not None and mat.has_pbr:
        return {
            "metallic": float(mat.metallic),
            "roughness": float(mat.roughness),
            "ior": float(mat.ior),
            "transmission": float(mat.transmission),
        }
    n = max(float(mat.shininess), 0.0) if mat is not None else 20.0
    lo, hi = PHONG_ROUGHNESS
    roughness = min(hi, max(lo, math.sqrt(math.sqrt(2.0 / (n + 2.0)))))
    spec = _luminance(mat.specular if mat is not None else (0.2, 0.2, 0.2))
    diffuse = _luminance(mat.base_color) if mat is not None else 0.7
    metal = spec >= 0.8 and n >= 200.0 and diffuse <= PHONG_METAL_DIFFUSE
    transmission = 1.0 if opacity < 0.5 else 0.0
    if transmission:
        roughness = 0.02
    return {
        "metallic": 1.0 if metal else 0.0,
        "roughness": roughness,
        "ior": 1.5,
        "transmission": transmission,
    }


def describe_material(mat: Material | None, material: MaterialSpec, entry: dict[str, Any]) -> str:
    """One line for people: where the physically based material of a user object came from
    (the YAML entry, the file's glTF factors, or the Phong description and which rule of
    :func:`pbr_defaults`) and what it is."""
    m = material
    kind = (
        "clear dielectric"
        if m.transmission > 0.5
        else "metal"
        if m.metallic > 0.5
        else "dielectric"
    )
    what = f"{kind}, roughness {m.roughness:.2f}"
    given = [k for k in ("metallic", "roughness", "ior", "transmission") if k in entry]
    if mat is None:
        source = "no material in the file: grey plastic"
    elif mat.has_pbr:
        source = "the file's PBR factors"
    else:
        source = (
            f"derived from the file's Phong material (luminance of Kd "
            f"{_luminance(mat.base_color):.2f}, of Ks {_luminance(mat.specular):.2f}; Ns "
            f"{float(mat.shininess):g})"
        )
        if m.metallic > 0.5 and "metallic" not in given:
            source += ": a dark diffuse and mirror-like specular read as a metal"
        elif "metallic" not in given:
            source += f": not a metal, roughness at least {PHONG_ROUGHNESS[0]:g}"
    if given:
        source += f"; {', '.join(given)} from the YAML entry"
    return f"{what} ({source}; set metallic / roughness in the entry to change it)"


def _material(entry: dict[str, Any], mat: Any, texture: Any, name: str, where: str) -> MaterialSpec:
    """The material of a user object: the entry's color/opacity/PBR keys over the file's
    material (:func:`pbr_defaults`)."""
    color = entry.get("color", list(mat.base_color) if mat is not None else [0.7, 0.7, 0.7, 1.0])
    opacity_hint = float(mat.opacity) if mat is not None else 1.0
    if (
        "color" not in entry
        and mat is not None
        and not mat.has_pbr
        and "metallic" not in entry
        and pbr_defaults(mat, opacity_hint)["metallic"] == 1.0  # a Phong metal: its Ks colour
    ):
        color = [*(float(c) for c in mat.specular), float(mat.base_color[3])]
    if len(color) == 3:
        color = [*color, 1.0]
    if not isinstance(color, (list, tuple)) or len(color) != 4:
        raise InvalidArgumentError(
            f"{where}: key 'color': expected [r, g, b] or [r, g, b, a] in "
            f"[0, 1], got {entry.get('color')!r}"
        )
    opacity = _number_in(entry, "opacity", where, 1e-6, 1.0)
    opacity = opacity if opacity is not None else (float(mat.opacity) if mat is not None else 1.0)
    pbr = pbr_defaults(mat, opacity)
    for key, lo, hi in (
        ("metallic", 0.0, 1.0),
        ("roughness", 0.0, 1.0),
        ("ior", 1.0, 4.0),
        ("transmission", 0.0, 1.0),
    ):
        value = _number_in(entry, key, where, lo, hi)
        if value is not None:
            pbr[key] = value
    try:
        material = MaterialSpec(
            name=f"{name}_material",
            base_color=_rgba(color),
            specular=_rgb(mat.specular if mat is not None else (0.2,) * 3),
            # A file without a material (OBJ without .mtl, `Ns 0`) gets the default shininess.
            shininess=float(mat.shininess) if mat is not None and mat.shininess > 0 else 20.0,
            opacity=opacity,
            texture=texture,
            **pbr,
        )
    except (TypeError, ValueError) as e:
        key = "opacity" if "opacity" in str(e) else "color"
        raise InvalidArgumentError(f"{where}: key '{key}' (or the file's material): {e}") from e
    return material


def _keypoints(
    entry: dict[str, Any], centre: np.ndarray, hi: np.ndarray, lo: np.ndarray, where: str
) -> tuple[Keypoint, ...]:
    """The semantic keypoints of a user object (default: top and bottom of the box)."""
    named = entry.get("keypoints") or {
        "top": [centre[0], centre[1], hi[2]],
        "bottom": [centre[0], centre[1], lo[2]],
    }
    if not isinstance(named, dict):
        raise InvalidArgumentError(
            f"{where}: key 'keypoints': expected a mapping of names to [x, y, z] in metres, got "
            f"{named!r}"
        )
    keypoints = []
    for i, (kp_name, pos) in enumerate(named.items(), start=1):
        p = np.asarray(pos, dtype=np.float64)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise InvalidArgumentError(
                f"{where}: key 'keypoints.{kp_name}': expected [x, y, z] in metres, got {pos!r}"
            )
        keypoints.append(Keypoint(i, str(kp_name), (float(p[0]), float(p[1]), float(p[2]))))
    if len(keypoints) == 1:
        keypoints.append(Keypoint(2, "centre", _rgb(centre)))
    return tuple(keypoints)


def _flag(entry: dict[str, Any], key: str, where: str) -> bool:
    value = entry.get(key, False)
    if not isinstance(value, bool):
        raise InvalidArgumentError(f"{where}: key '{key}': expected true or false, got {value!r}")
    return value


def _closed_mesh(entry: dict[str, Any], mesh: Any, mesh_path: Path, where: str) -> tuple[Any, Any]:
    """(mesh, its validation): repaired with ``repair: true``; an error when it is not closed
    and ``allow_open`` is not set."""
    allow_open, repair = _flag(entry, "allow_open", where), _flag(entry, "repair", where)
    report = mesh.validate()
    if repair and not (report.is_watertight and report.is_winding_consistent):
        fixed = repair_mesh(mesh)
        if fixed.closed:  # a repair that leaves the mesh open is not applied
            mesh, report = fixed.mesh, fixed.after
    if not (report.is_watertight and report.is_winding_consistent) and not allow_open:
        raise InvalidArgumentError(
            f"{where}: key 'mesh': '{mesh_path}' is not closed ({report.num_boundary_edges} "
            f"boundary, {report.num_nonmanifold_edges} non-manifold, "
            f"{report.num_misoriented_edges} misoriented edges)"
            + (
                " even after repair"
                if repair
                else "; set repair: true to repair it as it is read "
                "(winding, duplicate and stray faces, small holes), or"
            )
            + (";" if repair else "")
            + " set allow_open: true to use the thin-shell mass model (no parallel-jaw labels)"
        )
    return mesh, report


def _object_from_entry(
    entry: dict[str, Any],
    base: Path,
    default_id: int,
    where: str,
    notes: list[UserObjectWarning] | None = None,
) -> ObjectSpec:
    if not isinstance(entry, dict):
        raise InvalidArgumentError(f"{where}: expected a mapping, got {type(entry).__name__}")
    unknown = sorted(set(entry) - _KEYS)
    if unknown:
        raise InvalidArgumentError(f"{where}: unknown key(s) {unknown}; valid: {sorted(_KEYS)}")
    for key in ("name", "mesh", "density", "friction"):
        if key not in entry:
            raise InvalidArgumentError(f"{where}: missing required key '{key}'")
    name = check_object_name(entry["name"], f"{where}: key 'name'")
    where = f"{where} ('{name}')"
    if isinstance(entry.get("scale"), (list, tuple)):
        raise InvalidArgumentError(
            f"{where}: key 'scale': only a uniform scale is supported (one number > 0 that "
            f"multiplies every coordinate), got {entry['scale']!r}; scale the mesh file itself "
            "for different factors per axis"
        )
    scale = _number(entry, "scale", where, 1.0)
    density = _number(entry, "density", where)
    friction = _number(entry, "friction", where)
    if not isinstance(entry["mesh"], str) or not entry["mesh"]:
        raise InvalidArgumentError(
            f"{where}: key 'mesh': expected a file path, got {entry['mesh']!r}"
        )
    mesh_path = base / entry["mesh"]
    try:
        mesh = load_mesh(mesh_path, scale=scale)
    except MgnError as e:
        raise type(e)(f"{where}: key 'mesh': {e}") from e
    mesh, report = _closed_mesh(entry, mesh, mesh_path, where)
    warn_implausible_size(
        mesh.vertices, f"{where}: mesh '{mesh_path}' (scale {scale:g})", name, notes
    )
    mat = mesh.materials[0] if mesh.materials else None
    texture, unreadable = _base_color_texture(mat, mesh_path)
    warn_missing_material_files(
        mesh_path, mesh, f"{where}: mesh '{mesh_path}'", name, unreadable, notes
    )
    if report.signed_volume < 0:
        mesh = mesh.flipped()  # inward-wound file: make the normals point outward
        mat = mesh.materials[0] if mesh.materials else None
    uvs = mesh.uvs if texture is not None else None
    if uvs is not None and (np.any(uvs < 0) or np.any(uvs > 1)):
        uvs = np.mod(uvs, 1.0)  # wrap repeating uvs into the unit square
    material = _material(entry, mat, texture, name, where)
    lo, hi = mesh.bounds
    centre = (lo + hi) / 2
    keypoints = _keypoints(entry, centre, hi, lo, where)
    try:
        return ObjectSpec(
            category_id=int(entry.get("category_id", default_id)),
            name=name,
            description=str(entry.get("description", f"user object from {mesh_path.name}")),
            vertices=np.asarray(mesh.vertices, np.float64),
            faces=np.asarray(mesh.faces, np.int32),
            uvs=uvs,
            material=material,
            density=density,
            friction=friction,
            keypoints=keypoints,
            tags=frozenset(entry.get("tags", ())),
        )
    except ValueError as e:
        raise InvalidArgumentError(f"{where}: mesh '{mesh_path}': {e}") from e


def load_objects_yaml(
    path: str | os.PathLike[str], *, notes: list[UserObjectWarning] | None = None
) -> tuple[ObjectSpec, ...]:
    """Read user objects from a YAML file (format in this module's docstring).

    Category ids default to consecutive numbers after the built-in objects; names and ids must
    not clash with the built-in ones or each other.

    Args:
        path: the YAML file.
        notes: when given, the warnings about the objects (:class:`UserObjectWarning`: size,
            missing material files) are appended to this list instead of being given as Python
            warnings (thread-safe, and the caller decides which to show).
    """

    p = Path(path)
    data = read_yaml(p, "user-object YAML")
    if not isinstance(data, dict) or not isinstance(data.get("objects"), list):
        raise InvalidArgumentError(
            f"user-object YAML '{p}': expected a top-level 'objects:' list (see "
            "mgn.objects.user), got "
            + (f"keys {sorted(map(str, data))}" if isinstance(data, dict) else type(data).__name__)
        )
    builtin = builtin_objects()
    taken_ids = {s.category_id for s in builtin}
    taken_names = {s.name for s in builtin}
    next_id = max(taken_ids) + 1
    out = []
    for i, entry in enumerate(data["objects"]):
        spec = _object_from_entry(entry, p.parent, next_id, f"{p}: objects[{i}]", notes)
        if spec.category_id in taken_ids or spec.name in taken_names:
            raise InvalidArgumentError(
                f"{p}: objects[{i}] ('{spec.name}', id {spec.category_id}) clashes with an "
                "existing object name or category id"
            )
        taken_ids.add(spec.category_id)
        taken_names.add(spec.name)
        next_id = max(next_id, spec.category_id + 1)
        out.append(spec)
    return tuple(out)
