"""Meshes, mass properties and surface sampling (typed façade over the C++ core).

Units: metres, kilograms, kg/m^3. Mesh vertices are in the mesh's own frame O; faces are wound
counter-clockwise seen from outside.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
import numpy.typing as npt

from mgn import _core

#: Indexed triangle mesh (vertices (V,3) float32 m, faces (F,3) int32, optional uvs (V,2)).
#: Invariants checked on construction: finite vertices, in-range indices, no zero-area face.
Mesh = _core.geometry.Mesh
#: Surface appearance (base colour RGBA, specular, shininess, opacity, texture).
Material = _core.geometry.Material
#: Validation report: watertightness, winding, boundary/non-manifold edges, signed volume, and
#: the edges and vertices split where closed pieces touch (``num_split_edges``,
#: ``num_split_vertices``).
MeshReport = _core.geometry.MeshReport
#: Volume (m^3), mass (kg), centre of mass (m, mesh frame), inertia about the CoM (kg m^2).
MassProperties = _core.geometry.MassProperties


def load_mesh(
    path: str | os.PathLike[str],
    *,
    scale: float = 1.0,
    merge: bool = True,
    drop_degenerate: bool = True,
) -> Mesh:
    """Load a mesh file (OBJ, STL, PLY, GLB/GLTF, DAE, ...) with assimp.

    Args:
        path: the file.
        scale: multiplies every coordinate (0.001 for a file in millimetres); result in metres.
        merge: merge sub-meshes (node transforms applied); if False the file must hold one mesh.
        drop_degenerate: remove zero-area faces; if False such a file raises InvalidArgumentError.

    Raises:
        IoError: missing, unreadable or non-mesh file.
        InvalidArgumentError: no triangles, non-finite vertices, bad scale.
    """
    return _core.geometry.load_mesh(os.fspath(path), scale, merge, drop_degenerate)


def mass_properties(
    mesh: Mesh,
    density: float = 1000.0,
    *,
    open_mesh: Literal["shell", "error"] = "shell",
    shell_thickness: float = 0.002,
) -> MassProperties:
    """Volume, mass, centre of mass and inertia of ``mesh`` for a uniform ``density`` (kg/m^3).

    Closed, consistently wound meshes are integrated exactly (divergence theorem). For an open
    mesh, ``open_mesh="shell"`` treats the surface as a shell ``shell_thickness`` metres thick
    (``is_exact`` is then False) and ``"error"`` raises InvalidArgumentError.
    """
    return _core.geometry.compute_mass_properties(mesh, density, open_mesh, shell_thickness)


_MTLLIB = re.compile(rb"^[ \t]*mtllib[ \t]+(.+?)[ \t]*\r?$", re.MULTILINE)


def missing_material_files(
    path: str | os.PathLike[str], mesh: Mesh | None = None
) -> list[tuple[str, str]]:
    """The material files a mesh file points to that are not there, as (what, file) pairs:
    the material libraries (``mtllib``) of an OBJ file, and the base-colour texture of each of
    the mesh's materials (``map_Kd`` of an MTL, an external glTF image, ...) when its file does
    not exist. Without them the mesh loads, but renders in its plain base colour.

    Args:
        path: the mesh file (an OBJ's ``mtllib`` names are relative to its folder).
        mesh: the mesh loaded from ``path`` (its materials give the texture paths); None: the
            ``mtllib`` check only.
    """
    p = Path(path)
    out: list[tuple[str, str]] = []
    if p.suffix.lower() == ".obj":
        try:
            data = p.read_bytes()
        except OSError:
            data = b""
        for m in _MTLLIB.finditer(data):
            name = m.group(1).decode("utf-8", "replace").strip()
            # One name, or (OBJ allows it) several separated by spaces; backslashes of Windows.
            candidates = [name, *name.split()] if " " in name else [name]
            found = [
                (p.parent / c.replace("\\", "/")).is_file() or (p.parent / c).is_file()
                for c in candidates
            ]
            if not (found[0] or (len(found) > 1 and all(found[1:]))):
                out.append(("material library (mtllib)", os.fspath(p.parent / name)))
    for mat in mesh.materials if mesh is not None else ():
        tex = str(mat.texture_path)
        if tex and not Path(tex).is_file():
            item = (f"texture of material '{mat.name}'", tex)
            if item not in out:
                out.append(item)
    return out


@dataclass(frozen=True)
class SurfaceSamples:
    """Points on a mesh surface, in the mesh frame.

    Attributes:
        points: (n, 3) float32, metres.
        normals: (n, 3) float32 unit outward face normals.
        face_ids: (n,) int32 index of the face each point lies on.
    """

    points: npt.NDArray[np.float32]
    normals: npt.NDArray[np.float32]
    face_ids: npt.NDArray[np.int32]

    def __len__(self) -> int:
        return int(self.points.shape[0])


def sample_surface(
    mesh: Mesh,
    count: int,
    *,
    method: Literal["random", "even"] = "random",
    seed: int = 0,
    oversampling: int = 6,
) -> SurfaceSamples:
    """Sample ``count`` points on the surface, deterministically for a ``seed``.

    ``"random"`` is area-weighted uniform; ``"even"`` is blue-noise (farthest-point selection
    from ``oversampling * count`` area-weighted candidates), as used for grasp candidates.
    """
    out = _core.geometry.sample_surface(mesh, int(count), method, int(seed), int(oversampling))
    return SurfaceSamples(out.points, out.normals, out.face_ids)


def make_box(extents: npt.ArrayLike) -> Mesh:
    """Closed box centred at the origin with edge lengths ``extents`` (x, y, z) in metres."""
    return _core.geometry.make_box(np.asarray(extents, dtype=np.float64).reshape(3))


def make_sphere(radius: float, segments: int = 64, rings: int = 32) -> Mesh:
    """Closed UV sphere of ``radius`` metres centred at the origin."""
    return _core.geometry.make_sphere(radius, segments, rings)


def make_cylinder(radius: float, height: float, segments: int = 64) -> Mesh:
    """Closed cylinder along z, centred at the origin (``radius``, ``height`` in metres)."""
    return _core.geometry.make_cylinder(radius, height, segments)


def mesh_from_arrays(
    vertices: npt.ArrayLike,
    faces: npt.ArrayLike,
    *,
    uvs: npt.ArrayLike | None = None,
    material: Material | None = None,
    name: str = "",
) -> Mesh:
    """A :data:`Mesh` from arrays (vertices (N, 3) m, faces (M, 3), optional uvs (N, 2)) with at
    most one material."""
    materials = [material] if material is not None else []
    return Mesh(
        np.asarray(vertices, dtype=np.float32),
        np.asarray(faces, dtype=np.int32),
        None if uvs is None else np.asarray(uvs, dtype=np.float32),
        materials,
        [],
        name,
    )
