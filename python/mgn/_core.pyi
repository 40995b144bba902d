"""
mgn compiled core (private): use the typed API of the `mgn` package instead.
"""

from __future__ import annotations

import collections.abc
import typing

import numpy
import numpy.typing

__all__: list[str] = [
    "BackendError",
    "CollisionModel",
    "InvalidArgumentError",
    "IoError",
    "MassProperties",
    "Material",
    "Mesh",
    "MeshReport",
    "MgnError",
    "RayScene",
    "UnsupportedError",
    "build_info",
    "camera_rays",
    "collide",
    "compute_mass_properties",
    "distance",
    "load_mesh",
    "make_box",
    "make_cylinder",
    "make_sphere",
    "resolve_num_threads",
    "sample_surface",
]

class MgnError(Exception):
    """
    Base class of every error raised by mgn.
    """

class InvalidArgumentError(MgnError, ValueError):
    """
    An argument has a wrong value, shape or range (also a ValueError).
    """

class IoError(MgnError, OSError):
    """
    A file could not be read or written (also an OSError).
    """

class UnsupportedError(MgnError, ValueError):
    """
    A valid request that this build or format does not support (also a ValueError).
    """

class BackendError(MgnError, RuntimeError):
    """
    A third-party backend reported a failure (also a RuntimeError).
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
    def opacity(self) -> float:
        """
        1 opaque .. 0 invisible
        """
    @opacity.setter
    def opacity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
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

class MeshReport:
    """
    Validation report of a mesh (topology after welding by position).
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
    def num_components(self) -> int: ...
    @property
    def num_faces(self) -> int: ...
    @property
    def num_misoriented_edges(self) -> int: ...
    @property
    def num_nonmanifold_edges(self) -> int: ...
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
        uvs: typing.Any = None,
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

class RayScene:
    """
    Immutable Embree scene of meshes placed in the world frame.
    """
    def __init__(
        self,
        meshes: collections.abc.Sequence[Mesh],
        poses: typing.Any = None,
        instance_ids: typing.Any = None,
    ) -> None: ...
    def intersect(
        self,
        origins: typing.Any,
        directions: typing.Any,
        tnear: typing.SupportsFloat | typing.SupportsIndex = 0.0,
        tfar: typing.SupportsFloat | typing.SupportsIndex = ...,
        coherent: bool = False,
        num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
    ) -> dict: ...
    def intersect_all(
        self,
        origins: typing.Any,
        directions: typing.Any,
        max_hits_per_ray: typing.SupportsInt | typing.SupportsIndex = 64,
        tnear: typing.SupportsFloat | typing.SupportsIndex = 0.0,
        tfar: typing.SupportsFloat | typing.SupportsIndex = ...,
        num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
    ) -> dict: ...
    def occluded(
        self,
        origins: typing.Any,
        directions: typing.Any,
        tnear: typing.SupportsFloat | typing.SupportsIndex = 0.0,
        tfar: typing.SupportsFloat | typing.SupportsIndex = ...,
        coherent: bool = False,
        num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
    ) -> numpy.ndarray: ...
    @property
    def bounds(self) -> numpy.ndarray: ...
    @property
    def num_geometries(self) -> int: ...
    @property
    def num_triangles(self) -> int: ...

class CollisionModel:
    """
    Immutable FCL BVH (OBBRSS) of a mesh.
    """
    def __init__(self, mesh: Mesh) -> None: ...
    @property
    def num_triangles(self) -> int: ...
    @property
    def num_vertices(self) -> int: ...

def build_info() -> list[tuple[str, str]]:
    """
    (library, version) pairs for mgn and every library the core was built against.
    """

def camera_rays(
    K: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 3]"],
    width: typing.SupportsInt | typing.SupportsIndex,
    height: typing.SupportsInt | typing.SupportsIndex,
    X_WC: typing.Any,
) -> tuple[numpy.ndarray, numpy.ndarray]: ...
def collide(
    a: CollisionModel,
    X_WA: typing.Any,
    b: CollisionModel,
    X_WB: typing.Any,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> numpy.ndarray: ...
def compute_mass_properties(
    mesh: Mesh,
    density: typing.SupportsFloat | typing.SupportsIndex = 1000.0,
    open_mesh: str = "shell",
    shell_thickness: typing.SupportsFloat | typing.SupportsIndex = 0.002,
) -> MassProperties: ...
def distance(
    a: CollisionModel,
    X_WA: typing.Any,
    b: CollisionModel,
    X_WB: typing.Any,
    rel_err: typing.SupportsFloat | typing.SupportsIndex = 0.0,
    abs_err: typing.SupportsFloat | typing.SupportsIndex = 0.0,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> dict: ...
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
def resolve_num_threads(requested: typing.SupportsInt | typing.SupportsIndex) -> int:
    """
    Thread count used for `requested` (0 = all hardware threads).
    """

def sample_surface(
    mesh: Mesh,
    count: typing.SupportsInt | typing.SupportsIndex,
    method: str = "random",
    seed: typing.SupportsInt | typing.SupportsIndex = 0,
    oversampling: typing.SupportsInt | typing.SupportsIndex = 6,
) -> dict: ...

__version__: str = "0.1.0"
