"""User objects: a mesh file plus a small YAML description.

Example ``my_objects.yaml`` (paths relative to the YAML file; SI units)::

    objects:
      - name: bracket_a            # unique snake_case name
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

The mesh keeps its own frame. It must be watertight (mass properties are exact), unless
``allow_open: true`` is given, in which case the documented shell model is used.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from mgn.errors import InvalidArgumentError, IoError
from mgn.geometry import Material, load_mesh
from mgn.objects.library import Keypoint, MaterialSpec, ObjectSpec, builtin_objects

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
}


def _texture(path: str) -> np.ndarray | None:
    if not path:
        return None
    from PIL import Image

    try:
        with Image.open(path) as img:
            return np.asarray(img.convert("RGB"), dtype=np.uint8)
    except OSError:
        return None  # a missing texture leaves the base colour; the mesh is still usable


def _embedded_texture(data: bytes) -> np.ndarray | None:
    """An embedded (GLB) texture's PNG/JPEG bytes as an RGB image; None if absent or broken."""
    if not data:
        return None
    import io

    from PIL import Image

    try:
        with Image.open(io.BytesIO(data)) as img:
            return np.asarray(img.convert("RGB"), dtype=np.uint8)
    except OSError:
        return None


def _number(entry: dict[str, Any], key: str, where: str, lo: float, hi: float) -> float | None:
    """``entry[key]`` as a float in [lo, hi], None when absent; else an error naming the field."""
    if key not in entry:
        return None
    value = entry[key]
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    if not ok or not (math.isfinite(float(value)) and lo <= float(value) <= hi):
        raise InvalidArgumentError(
            f"{where}: field '{key}' must be a number in [{lo:g}, {hi:g}], got {value!r}"
        )
    return float(value)


def pbr_defaults(mat: Material | None, opacity: float = 1.0) -> dict[str, float]:
    """metallic, roughness, ior, transmission of a mesh file's material: its glTF/GLB factors
    when it has them (``Material.has_pbr``), else derived from the Phong description: roughness
    from the Phong exponent n through the Beckmann correspondence alpha = sqrt(2 / (n + 2)),
    roughness = sqrt(alpha) (clamped to [0.05, 1]); a mirror-like specular (luminance >= 0.8,
    n >= 200) is a metal; opacity < 0.5 a clear dielectric (transmission 1)."""
    if mat is not None and mat.has_pbr:
        return {"metallic": float(mat.metallic), "roughness": float(mat.roughness),
                "ior": float(mat.ior), "transmission": float(mat.transmission)}  # fmt: skip
    n = float(mat.shininess) if mat is not None else 20.0
    roughness = min(1.0, max(0.05, math.sqrt(math.sqrt(2.0 / (max(n, 0.0) + 2.0)))))
    spec = np.asarray(mat.specular if mat is not None else (0.2, 0.2, 0.2), np.float64)
    lum = float(0.2126 * spec[0] + 0.7152 * spec[1] + 0.0722 * spec[2])
    metallic = 1.0 if lum >= 0.8 and n >= 200.0 else 0.0
    transmission = 1.0 if opacity < 0.5 else 0.0
    if transmission:
        roughness = 0.02
    return {"metallic": metallic, "roughness": roughness, "ior": 1.5,
            "transmission": transmission}  # fmt: skip


def _object_from_entry(
    entry: dict[str, Any], base: Path, default_id: int, where: str
) -> ObjectSpec:
    if not isinstance(entry, dict):
        raise InvalidArgumentError(f"{where}: expected a mapping, got {type(entry).__name__}")
    unknown = sorted(set(entry) - _KEYS)
    if unknown:
        raise InvalidArgumentError(f"{where}: unknown key(s) {unknown}; valid: {sorted(_KEYS)}")
    for key in ("name", "mesh", "density", "friction"):
        if key not in entry:
            raise InvalidArgumentError(f"{where}: missing required key '{key}'")
    name = str(entry["name"])
    where = f"{where} ('{name}')"
    mesh_path = base / str(entry["mesh"])
    mesh = load_mesh(mesh_path, scale=float(entry.get("scale", 1.0)))
    report = mesh.validate()
    if not (report.is_watertight and report.is_winding_consistent) and not entry.get("allow_open"):
        raise InvalidArgumentError(
            f"{where}: mesh '{mesh_path}' is not closed ({report.num_boundary_edges} boundary, "
            f"{report.num_nonmanifold_edges} non-manifold edges); repair it, or set "
            "allow_open: true to use the thin-shell mass model"
        )
    if report.signed_volume < 0:
        mesh = mesh.flipped()  # inward-wound file: make the normals point outward
    mat = mesh.materials[0] if mesh.materials else None
    texture = None
    if mat is not None:
        texture = _texture(mat.texture_path)
        if texture is None:
            texture = _embedded_texture(bytes(mat.texture_data))
    uvs = mesh.uvs if texture is not None else None
    if uvs is not None and (np.any(uvs < 0) or np.any(uvs > 1)):
        uvs = np.mod(uvs, 1.0)  # wrap repeating uvs into the unit square
    color = entry.get("color", list(mat.base_color) if mat is not None else [0.7, 0.7, 0.7, 1.0])
    if len(color) == 3:
        color = [*color, 1.0]
    opacity = _number(entry, "opacity", where, 1e-6, 1.0)
    opacity = opacity if opacity is not None else (float(mat.opacity) if mat is not None else 1.0)
    pbr = pbr_defaults(mat, opacity)
    for key, lo, hi in (("metallic", 0.0, 1.0), ("roughness", 0.0, 1.0), ("ior", 1.0, 4.0),
                        ("transmission", 0.0, 1.0)):  # fmt: skip
        value = _number(entry, key, where, lo, hi)
        if value is not None:
            pbr[key] = value
    material = MaterialSpec(
        name=f"{name}_material",
        base_color=tuple(float(c) for c in color),
        specular=tuple(float(s) for s in (mat.specular if mat is not None else (0.2,) * 3)),
        shininess=float(mat.shininess) if mat is not None else 20.0,
        opacity=opacity,
        texture=texture,
        **pbr,
    )
    lo, hi = mesh.bounds
    centre = (lo + hi) / 2
    named = entry.get("keypoints") or {
        "top": [centre[0], centre[1], hi[2]],
        "bottom": [centre[0], centre[1], lo[2]],
    }
    if not isinstance(named, dict):
        raise InvalidArgumentError(f"{where}: keypoints must map names to [x, y, z] in metres")
    keypoints = []
    for i, (kp_name, pos) in enumerate(named.items(), start=1):
        p = np.asarray(pos, dtype=np.float64)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise InvalidArgumentError(
                f"{where}: keypoint '{kp_name}' must be [x, y, z], got {pos}"
            )
        keypoints.append(Keypoint(i, str(kp_name), (float(p[0]), float(p[1]), float(p[2]))))
    if len(keypoints) == 1:
        keypoints.append(Keypoint(2, "centre", tuple(float(x) for x in centre)))
    try:
        return ObjectSpec(
            category_id=int(entry.get("category_id", default_id)),
            name=name,
            description=str(entry.get("description", f"user object from {mesh_path.name}")),
            vertices=np.asarray(mesh.vertices, np.float64),
            faces=np.asarray(mesh.faces, np.int32),
            uvs=uvs,
            material=material,
            density=float(entry["density"]),
            friction=float(entry["friction"]),
            keypoints=tuple(keypoints),
            tags=frozenset(entry.get("tags", ())),
        )
    except ValueError as e:
        raise InvalidArgumentError(f"{where}: {e}") from e


def load_objects_yaml(path: str | os.PathLike[str]) -> tuple[ObjectSpec, ...]:
    """Read user objects from a YAML file (format in this module's docstring).

    Category ids default to consecutive numbers after the built-in objects; names and ids must
    not clash with the built-in ones or each other.
    """
    p = Path(path)
    try:
        data = yaml.safe_load(p.read_text(encoding="utf-8"))
    except FileNotFoundError as e:
        raise IoError(f"load_objects_yaml: file not found: '{p}'") from e
    except yaml.YAMLError as e:
        raise InvalidArgumentError(f"load_objects_yaml: '{p}' is not valid YAML: {e}") from e
    if not isinstance(data, dict) or not isinstance(data.get("objects"), list):
        raise InvalidArgumentError(f"load_objects_yaml: '{p}' needs a top-level 'objects:' list")
    builtin = builtin_objects()
    taken_ids = {s.category_id for s in builtin}
    taken_names = {s.name for s in builtin}
    next_id = max(taken_ids) + 1
    out = []
    for i, entry in enumerate(data["objects"]):
        spec = _object_from_entry(entry, p.parent, next_id, f"{p.name}: objects[{i}]")
        if spec.category_id in taken_ids or spec.name in taken_names:
            raise InvalidArgumentError(
                f"{p.name}: objects[{i}] ('{spec.name}', id {spec.category_id}) clashes with an "
                "existing object name or category id"
            )
        taken_ids.add(spec.category_id)
        taken_names.add(spec.name)
        next_id = max(next_id, spec.category_id + 1)
        out.append(spec)
    return tuple(out)
