"""The MetaGraspNet object folder: ``<root>/models/<3-digit id>/`` (docs/format.md).

Written files (all atomically, the folder renamed into place when complete):

- ``textured.obj`` + ``textured.mtl`` (+ ``texture.png``): the mesh in metres, object frame.
- ``textured.urdf``: one link with mass, inertia about the centre of mass, and friction.
- ``textured.obj.hdf5``: ``keypts/byhand`` (P, 4) [id, x, y, z] and ``keypts/com`` (1000, 4)
  [score, x, y, z] in **centimetres**, the ``grasps/paralleljaw`` and ``grasps/suctioncup``
  groups (empty until labels are computed; readers open them) and a ``metadata`` group.

Every HDF5 dataset is float32, as in the original files.
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import numpy.typing as npt
from PIL import Image

from mgn import _core
from mgn.base.atomic import atomic_dir
from mgn.base.units import M_TO_CM
from mgn.geometry.mesh import Mesh, load_mesh, mass_properties
from mgn.objects import MaterialSpec, ObjectSpec, ToteSpec, com_keypoints, make_tote


def obj_text(
    vertices: npt.ArrayLike,
    faces: npt.ArrayLike,
    uvs: npt.ArrayLike | None,
    *,
    header: str,
    mtllib: str = "textured.mtl",
) -> str:
    """Wavefront OBJ text (metres) using material ``material_0`` of ``mtllib``."""
    out = io.StringIO()
    for line in header.splitlines():
        out.write(f"# {line}\n")
    out.write(f"mtllib {mtllib}\n")
    np.savetxt(out, np.asarray(vertices, np.float64), fmt="v %.7f %.7f %.7f")
    if uvs is not None:
        np.savetxt(out, np.asarray(uvs, np.float64), fmt="vt %.6f %.6f")
    out.write("usemtl material_0\n")
    f = np.asarray(faces, np.int64) + 1
    if uvs is not None:
        np.savetxt(out, np.repeat(f, 2, axis=1), fmt="f %d/%d %d/%d %d/%d")
    else:
        np.savetxt(out, f, fmt="f %d %d %d")
    return out.getvalue()


def mtl_text(m: MaterialSpec, has_texture: bool) -> str:
    """MTL text of material ``material_0`` (linear colours; ``texture.png`` when textured)."""
    lines = [
        "newmtl material_0",
        "Kd {:.6f} {:.6f} {:.6f}".format(*m.base_color[:3]),
        "Ks {:.6f} {:.6f} {:.6f}".format(*m.specular),
        f"Ns {m.shininess:.3f}",
        f"d {m.opacity:.6f}",
        "illum 2",
    ]
    if has_texture:
        lines.append("map_Kd texture.png")
    return "\n".join(lines) + "\n"


def _urdf_text(spec: ObjectSpec, mass: float, com: np.ndarray, inertia: np.ndarray) -> str:
    I = inertia  # noqa: E741 (the usual symbol)
    return f"""<?xml version="1.0"?>
<robot name="{spec.name}">
  <link name="base_link">
    <contact>
      <lateral_friction value="{spec.friction:.4f}"/>
    </contact>
    <inertial>
      <origin xyz="{com[0]:.7f} {com[1]:.7f} {com[2]:.7f}" rpy="0 0 0"/>
      <mass value="{mass:.7f}"/>
      <inertia ixx="{I[0, 0]:.9e}" ixy="{I[0, 1]:.9e}" ixz="{I[0, 2]:.9e}"
               iyy="{I[1, 1]:.9e}" iyz="{I[1, 2]:.9e}" izz="{I[2, 2]:.9e}"/>
    </inertial>
    <visual>
      <geometry><mesh filename="textured.obj" scale="1 1 1"/></geometry>
    </visual>
    <collision>
      <geometry><mesh filename="textured.obj" scale="1 1 1"/></geometry>
    </collision>
  </link>
</robot>
"""


def _write_hdf5(
    path: Path,
    spec: ObjectSpec,
    com_kp: np.ndarray,
    metadata: dict[str, Any],
) -> None:
    f4 = np.float32
    with h5py.File(path, "w") as h5:
        byhand = np.array(
            [[kp.id, *(np.asarray(kp.position) * M_TO_CM)] for kp in spec.keypoints], dtype=f4
        ).reshape(-1, 4)
        com_cm = com_kp.copy()
        com_cm[:, 1:] *= M_TO_CM
        h5.create_dataset("keypts/byhand", data=byhand)
        h5.create_dataset("keypts/com", data=com_cm.astype(f4))
        pj = h5.create_group("grasps/paralleljaw")
        pj.create_dataset("pregrasp_transform", data=np.zeros((0, 10), f4))
        pj.create_dataset("quality_score", data=np.zeros((0,), f4))
        pj.create_dataset("quality_score_simulation", data=np.zeros((0,), f4))
        sc = h5.create_group("grasps/suctioncup")
        sc.create_dataset("pregrasp_transform", data=np.zeros((0, 6), f4))
        sc.create_dataset("quality_score", data=np.zeros((0,), f4))
        meta = h5.create_group("metadata")
        for key, value in metadata.items():
            meta.attrs[key] = json.dumps(value) if isinstance(value, (dict, list)) else value


def write_model_folder(
    spec: ObjectSpec, root: str | os.PathLike[str], *, overwrite: bool = False
) -> Path:
    """Write ``spec`` as ``<root>/models/<category_id:03d>/`` and return that folder.

    The folder is built under a temporary name and renamed when complete, so an interrupted
    export never leaves a partial object folder.
    """

    target = Path(root) / "models" / f"{spec.category_id:03d}"
    mesh = spec.to_mesh()
    props = mass_properties(mesh, spec.density)
    com_kp = com_keypoints(mesh, spec.density, seed=spec.category_id)
    has_texture = spec.material.texture is not None and spec.uvs is not None
    metadata = {
        "name": spec.name,
        "category_id": int(spec.category_id),
        "description": spec.description,
        "tags": sorted(spec.tags),
        "density_kg_m3": float(spec.density),
        "friction": float(spec.friction),
        "mass_kg": float(props.mass),
        "volume_m3": float(props.volume),
        "center_of_mass_m": [float(x) for x in props.center_of_mass],
        "inertia_kg_m2": np.asarray(props.inertia).tolist(),
        "keypoint_names": [kp.name for kp in spec.keypoints],
        "com_keypoint_seed": int(spec.category_id),
        "units": "textured.obj in metres; keypts in centimetres",
        "mgn_version": _core.__version__,
    }
    with atomic_dir(target, overwrite=overwrite) as tmp:
        header = f"{spec.name}: {spec.description}\nunits: metres, object frame (z up)"
        uvs = spec.uvs if has_texture else None
        (tmp / "textured.obj").write_text(obj_text(spec.vertices, spec.faces, uvs, header=header))
        (tmp / "textured.mtl").write_text(mtl_text(spec.material, has_texture))
        if has_texture:
            Image.fromarray(np.asarray(spec.material.texture, np.uint8)).save(tmp / "texture.png")
        (tmp / "textured.urdf").write_text(
            _urdf_text(
                spec, props.mass, np.asarray(props.center_of_mass), np.asarray(props.inertia)
            )
        )
        _write_hdf5(tmp / "textured.obj.hdf5", spec, com_kp, metadata)
    return target


@dataclass(frozen=True)
class ModelFolder:
    """An object folder read back (lengths converted to metres).

    Attributes:
        path: the folder.
        mesh: ``textured.obj`` loaded with its material.
        keypoints_byhand: (P, 4) [id, x, y, z], m.
        keypoints_com: (Q, 4) [score, x, y, z], m.
        metadata: the ``metadata`` attributes (JSON values decoded).
    """

    path: Path
    mesh: Mesh
    keypoints_byhand: npt.NDArray[np.float64]
    keypoints_com: npt.NDArray[np.float64]
    metadata: dict[str, Any]


def object_folders(root: str | os.PathLike[str]) -> list[Path]:
    """The object folders ``models/NNN`` of an export root, sorted by id (may be empty)."""
    return sorted(p for p in (Path(root) / "models").glob("[0-9][0-9][0-9]") if p.is_dir())


def read_model_folder(path: str | os.PathLike[str]) -> ModelFolder:
    """Read an object folder written by mgn or MetaGraspNet (keypoints converted to metres)."""
    folder = Path(path)
    mesh = load_mesh(folder / "textured.obj")
    with h5py.File(folder / "textured.obj.hdf5", "r") as h5:
        byhand = np.asarray(h5["keypts/byhand"], np.float64).reshape(-1, 4)
        com = np.asarray(h5["keypts/com"], np.float64).reshape(-1, 4)
        meta: dict[str, Any] = {}
        if "metadata" in h5:
            for k, v in h5["metadata"].attrs.items():
                if isinstance(v, str) and v[:1] in "[{":
                    v = json.loads(v)
                meta[k] = v.item() if isinstance(v, np.generic) else v
    byhand[:, 1:] /= M_TO_CM
    com[:, 1:] /= M_TO_CM
    return ModelFolder(folder, mesh, byhand, com, meta)


def write_tote(spec: ToteSpec, root: str | os.PathLike[str]) -> Path:
    """Write the tote as ``<root>/tote/`` (``tote.obj`` + ``.mtl`` in metres, ``tote.json``).

    Tote frame: origin at the centre of the inner floor surface, z up.
    """
    vertices, faces = make_tote(spec)
    params = {f.name: getattr(spec, f.name) for f in dataclasses.fields(spec)}
    material = MaterialSpec(name="tote", base_color=spec.color)
    with atomic_dir(Path(root) / "tote", overwrite=True) as tmp:
        header = "tote: origin at the centre of the inner floor, z up; metres"
        (tmp / "tote.obj").write_text(
            obj_text(vertices, faces, None, header=header, mtllib="tote.mtl")
        )
        (tmp / "tote.mtl").write_text(mtl_text(material, False))
        (tmp / "tote.json").write_text(json.dumps(params, indent=2))
    return Path(root) / "tote"
