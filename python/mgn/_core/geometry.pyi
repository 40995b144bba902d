"""
mgn/geometry: meshes, primitives, sampling, convex hulls.
"""

from __future__ import annotations

import collections.abc
import typing

import numpy
import numpy.typing

__all__: list[str] = [
    "ConvexDecompositionOptions",
    "MassProperties",
    "Material",
    "Mesh",
    "MeshReport",
    "SurfaceSamples",
    "compute_mass_properties",
    "convex_decomposition",
    "convex_hull",
    "load_mesh",
    "make_box",
    "make_cylinder",
    "make_sphere",
    "sample_surface",
]

class SurfaceSamples:
    """
    sample_surface() result (mgn/geometry/sampling.hpp), mesh frame.
    """
    @property
    def face_ids(self) -> numpy.ndarray:
        """
        (N,) int32 index of the face each point lies on
        """
    @property
    def normals(self) -> numpy.ndarray:
        """
        (N,3) float32 unit outward face normals
        """
    @property
    def points(self) -> numpy.ndarray:
        """
        (N,3) float32 points on the surface, m
        """

class Material:
    """
    Surface appearance of a mesh (colours linear RGBA in [0,1]).
    """

    name: str
    def __init__(self) -> None: ...
    def __repr__(self) -> str: ...
    @property
    def base_color(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float32], "[4, 1]"]:
        """
        RGBA in [0,1]
        """
    @base_color.setter
    def base_color(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[4, 1]"]
    ) -> None: ...
    @property
    def has_pbr(self) -> bool:
        """
        True when metallic/roughness/ior/transmission are given (glTF, built-in)
        """
    @has_pbr.setter
    def has_pbr(self, arg0: bool) -> None: ...
    @property
    def ior(self) -> float:
        """
        index of refraction >= 1 (KHR_materials_ior)
        """
    @ior.setter
    def ior(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def metallic(self) -> float:
        """
        [0,1] (glTF metallicFactor)
        """
    @metallic.setter
    def metallic(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def opacity(self) -> float:
        """
        1 opaque .. 0 invisible
        """
    @opacity.setter
    def opacity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def roughness(self) -> float:
        """
        perceptual roughness [0,1] (glTF roughnessFactor)
        """
    @roughness.setter
    def roughness(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def shininess(self) -> float:
        """
        Phong exponent
        """
    @shininess.setter
    def shininess(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def specular(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float32], "[3, 1]"]:
        """
        RGB in [0,1]
        """
    @specular.setter
    def specular(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[3, 1]"]
    ) -> None: ...
    @property
    def texture_data(self) -> bytes:
        """
        compressed bytes of an embedded texture, or b''
        """
    @texture_data.setter
    def texture_data(self, arg1: bytes) -> None: ...
    @property
    def texture_path(self) -> str:
        """
        absolute path of the diffuse texture or ''
        """
    @texture_path.setter
    def texture_path(self, arg0: str) -> None: ...
    @property
    def transmission(self) -> float:
        """
        [0,1], 1 = clear dielectric (KHR_materials_transmission)
        """
    @transmission.setter
    def transmission(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class MeshReport:
    """
    Validation report of a mesh (topology after welding by position and splitting where closed pieces touch along an edge or at a vertex).
    """
    def __repr__(self) -> str: ...
    @property
    def area(self) -> float:
        """
        m^2
        """
    @property
    def is_outward(self) -> bool: ...
    @property
    def is_watertight(self) -> bool: ...
    @property
    def is_winding_consistent(self) -> bool: ...
    @property
    def num_boundary_edges(self) -> int: ...
    @property
    def num_components(self) -> int:
        """
        connected components (by vertex, after splits)
        """
    @property
    def num_faces(self) -> int: ...
    @property
    def num_misoriented_edges(self) -> int: ...
    @property
    def num_nonmanifold_edges(self) -> int: ...
    @property
    def num_split_edges(self) -> int:
        """
        welded edges of more than two faces split between closed pieces that touch there (each piece then a closed 2-manifold)
        """
    @property
    def num_split_vertices(self) -> int:
        """
        welded vertices split between closed pieces that touch there
        """
    @property
    def num_vertices(self) -> int: ...
    @property
    def signed_volume(self) -> float:
        """
        m^3
        """

class MassProperties:
    """
    Mass properties in the mesh frame (SI units).
    """
    @property
    def center_of_mass(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]:
        """
        (3,) m, mesh frame
        """
    @property
    def inertia(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 3]"]:
        """
        (3,3) kg m^2 about the centre of mass
        """
    @property
    def is_exact(self) -> bool:
        """
        False when the open-mesh shell fallback was used
        """
    @property
    def mass(self) -> float:
        """
        kg
        """
    @property
    def volume(self) -> float:
        """
        m^3
        """

class Mesh:
    """
    Indexed triangle mesh in metres (see mgn.Mesh).
    """

    name: str
    @staticmethod
    def merge(meshes: collections.abc.Sequence[Mesh], name: str = "") -> Mesh: ...
    def __init__(
        self,
        vertices: typing.Any,
        faces: typing.Any,
        uvs: typing.Any | None = None,
        materials: collections.abc.Sequence[Material] = [],
        face_materials: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex] = [],
        name: str = "",
    ) -> None: ...
    def __repr__(self) -> str: ...
    def face_areas(self) -> numpy.ndarray: ...
    def face_normals(self) -> numpy.ndarray: ...
    def flipped(self) -> Mesh: ...
    def scaled(self, factor: typing.SupportsFloat | typing.SupportsIndex) -> Mesh: ...
    def transformed(self, X: typing.Any) -> Mesh: ...
    def validate(self) -> MeshReport: ...
    @property
    def area(self) -> float: ...
    @property
    def bounds(self) -> numpy.ndarray: ...
    @property
    def face_materials(self) -> list[int]: ...
    @property
    def faces(self) -> numpy.ndarray: ...
    @property
    def materials(self) -> list[Material]: ...
    @property
    def num_faces(self) -> int: ...
    @property
    def num_vertices(self) -> int: ...
    @property
    def uvs(self) -> typing.Any: ...
    @property
    def vertices(self) -> numpy.ndarray: ...

class ConvexDecompositionOptions:
    """
    Options of convex_decomposition (mgn/geometry/convex_decomposition.hpp); the defaults are the C++ struct's.
    """

    extra_concavity_points: bool
    def __init__(self) -> None: ...
    @property
    def compactness_weight(self) -> float: ...
    @compactness_weight.setter
    def compactness_weight(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def convex_volume_tolerance(self) -> float: ...
    @convex_volume_tolerance.setter
    def convex_volume_tolerance(
        self, arg0: typing.SupportsFloat | typing.SupportsIndex
    ) -> None: ...
    @property
    def grid_resolution(self) -> int: ...
    @grid_resolution.setter
    def grid_resolution(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def max_concavity(self) -> float: ...
    @max_concavity.setter
    def max_concavity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def max_hacd_faces(self) -> int: ...
    @max_hacd_faces.setter
    def max_hacd_faces(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def max_parts(self) -> int: ...
    @max_parts.setter
    def max_parts(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def merge_max_parts(self) -> int: ...
    @merge_max_parts.setter
    def merge_max_parts(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def merge_volume_tolerance(self) -> float: ...
    @merge_volume_tolerance.setter
    def merge_volume_tolerance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def min_parts(self) -> int: ...
    @min_parts.setter
    def min_parts(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def volume_weight(self) -> float: ...
    @volume_weight.setter
    def volume_weight(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

def compute_mass_properties(
    mesh: Mesh,
    density: typing.SupportsFloat | typing.SupportsIndex = 1000.0,
    open_mesh: str = "shell",
    shell_thickness: typing.SupportsFloat | typing.SupportsIndex = 0.002,
) -> MassProperties: ...
def convex_decomposition(mesh: Mesh, options: ConvexDecompositionOptions = ...) -> list[Mesh]: ...
def convex_hull(mesh: Mesh) -> Mesh: ...
def load_mesh(
    path: str,
    scale: typing.SupportsFloat | typing.SupportsIndex = 1.0,
    merge: bool = True,
    drop_degenerate: bool = True,
) -> Mesh: ...
def make_box(
    extents: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
) -> Mesh: ...
def make_cylinder(
    radius: typing.SupportsFloat | typing.SupportsIndex,
    height: typing.SupportsFloat | typing.SupportsIndex,
    segments: typing.SupportsInt | typing.SupportsIndex = 64,
) -> Mesh: ...
def make_sphere(
    radius: typing.SupportsFloat | typing.SupportsIndex,
    segments: typing.SupportsInt | typing.SupportsIndex = 64,
    rings: typing.SupportsInt | typing.SupportsIndex = 32,
) -> Mesh: ...
def sample_surface(
    mesh: Mesh,
    count: typing.SupportsInt | typing.SupportsIndex,
    method: str = "random",
    seed: typing.SupportsInt | typing.SupportsIndex = 0,
    oversampling: typing.SupportsInt | typing.SupportsIndex = 6,
) -> SurfaceSamples: ...
