"""
mgn compiled core (private): use the typed API of the `mgn` package instead.
"""

from __future__ import annotations

import collections.abc
import typing

import numpy
import numpy.typing

__all__: list[str] = [
    "SEAL_FAILURE_NAMES",
    "SUCTION_TOOL_OFFSET",
    "SURFACE_DARK",
    "SURFACE_MIRROR",
    "SURFACE_TRANSPARENT",
    "AntipodalOptions",
    "AntipodalResult",
    "AntipodalSampler",
    "AreaLight",
    "BackendError",
    "CalibrationResult",
    "ClassificationMetrics",
    "CollisionModel",
    "ConvexDecompositionOptions",
    "Cup",
    "DepthSensorParams",
    "DepthSensorPreset",
    "DepthSensorResult",
    "DistanceResult",
    "DropOptions",
    "DropResult",
    "Environment",
    "FilmOptions",
    "Intrinsics",
    "InvalidArgumentError",
    "IoError",
    "LayoutArrays",
    "LightSample",
    "MassProperties",
    "Material",
    "Mesh",
    "MeshReport",
    "MgnError",
    "MgnRigParams",
    "ObjectGraspLabels",
    "ParallelJawGripper",
    "PathScene",
    "PathTraceOptions",
    "PathTraceResult",
    "PbrMaterial",
    "PjWrenchOptions",
    "PlacedGraspArrays",
    "RayAllHits",
    "RayHits",
    "RayScene",
    "RenderOptions",
    "RenderResult",
    "Renderer",
    "SceneGraspModel",
    "SceneGraspOptions",
    "SealModel",
    "SealOptions",
    "SealResult",
    "SealTrial",
    "ShakeOptions",
    "ShakeResult",
    "ShakeTrajectoryResult",
    "StaircaseGridResult",
    "SuctionTool",
    "SuctionWrenchOptions",
    "SurfaceSamples",
    "ToolCollisionArrays",
    "UnsupportedError",
    "ViewGraspArrays",
    "ViewLabelArrays",
    "ViewLabelModel",
    "apply_depth_sensor",
    "block_means_2x2",
    "build_info",
    "calibrate_cup",
    "camera_rays",
    "classification_metrics",
    "collide",
    "color_temperature_rgb",
    "com_heatmap_prediction",
    "compute_layout",
    "compute_mass_properties",
    "convex_decomposition",
    "convex_hull",
    "develop_radiance",
    "distance",
    "double_blocks",
    "drop_objects",
    "gaussian_3x3",
    "gripper_meshes",
    "hand_poses",
    "hemisphere_rig",
    "load_mesh",
    "look_at",
    "make_box",
    "make_cylinder",
    "make_sphere",
    "material_texture_rgb",
    "mesh_surface_flags",
    "mgn_rig",
    "mgn_rig_from_params",
    "pj_wrench_scores",
    "predict_experiments",
    "resolve_num_threads",
    "restore_half_resolution",
    "sample_surface",
    "shake_test",
    "shake_trajectory",
    "staircase_grid",
    "suction_wrench_scores",
    "surface_flags",
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

class RayHits:
    """
    RayScene.intersect() result (mgn/raytrace/ray_scene.hpp), world frame; misses have distance inf and ids -1.
    """
    @property
    def barycentric(self) -> numpy.ndarray:
        """
        (N,2) float32 (u, v): p = (1-u-v) v0 + u v1 + v v2
        """
    @property
    def distance(self) -> numpy.ndarray:
        """
        (N,) float32 m
        """
    @property
    def face_ids(self) -> numpy.ndarray:
        """
        (N,) int32 face index within its mesh
        """
    @property
    def instance_ids(self) -> numpy.ndarray:
        """
        (N,) int32
        """
    @property
    def normals(self) -> numpy.ndarray:
        """
        (N,3) float32 unit geometric normal, outward for CCW faces
        """
    @property
    def points(self) -> numpy.ndarray:
        """
        (N,3) float32
        """

class RayAllHits:
    """
    RayScene.intersect_all() result: the hits of ray i are entries offsets[i] .. offsets[i+1]-1, sorted by distance.
    """
    @property
    def distance(self) -> numpy.ndarray:
        """
        (H,) float32 m
        """
    @property
    def face_ids(self) -> numpy.ndarray:
        """
        (H,) int32
        """
    @property
    def instance_ids(self) -> numpy.ndarray:
        """
        (H,) int32
        """
    @property
    def normals(self) -> numpy.ndarray:
        """
        (H,3) float32
        """
    @property
    def offsets(self) -> numpy.ndarray:
        """
        (N+1,) int64
        """
    @property
    def points(self) -> numpy.ndarray:
        """
        (H,3) float32
        """
    @property
    def ray_ids(self) -> numpy.ndarray:
        """
        (H,) int32 ray of each hit
        """

class RayScene:
    """
    Immutable Embree scene of meshes placed in the world frame.
    """
    def __init__(
        self,
        meshes: collections.abc.Sequence[Mesh],
        poses: typing.Any | None = None,
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
    ) -> RayHits: ...
    def intersect_all(
        self,
        origins: typing.Any,
        directions: typing.Any,
        max_hits_per_ray: typing.SupportsInt | typing.SupportsIndex = 64,
        tnear: typing.SupportsFloat | typing.SupportsIndex = 0.0,
        tfar: typing.SupportsFloat | typing.SupportsIndex = ...,
        num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
    ) -> RayAllHits: ...
    def intersect_ids(
        self,
        origins: typing.Any,
        directions: typing.Any,
        tnear: typing.SupportsFloat | typing.SupportsIndex = 0.0,
        tfar: typing.SupportsFloat | typing.SupportsIndex = ...,
        coherent: bool = False,
        num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
    ) -> tuple[numpy.ndarray, numpy.ndarray]: ...
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

class DistanceResult:
    """
    distance() result (mgn/collision/collision_model.hpp), one row per pose pair.
    """
    @property
    def collide(self) -> numpy.ndarray:
        """
        (N,) bool
        """
    @property
    def distance(self) -> numpy.ndarray:
        """
        (N,) float64 m, 0 for intersecting pairs
        """
    @property
    def points_a(self) -> numpy.ndarray:
        """
        (N,3) float64 closest point on A, world frame
        """
    @property
    def points_b(self) -> numpy.ndarray:
        """
        (N,3) float64 closest point on B, world frame
        """

class CollisionModel:
    """
    Immutable FCL BVH (OBBRSS) of a mesh.
    """
    def __init__(self, mesh: Mesh) -> None: ...
    @property
    def num_triangles(self) -> int: ...
    @property
    def num_vertices(self) -> int: ...

class SealResult:
    """
    SealModel.evaluate() result (mgn/grasp/seal_model.hpp); mgn.suction.seal.SealResult documents each array.
    """
    @property
    def quality(self) -> numpy.ndarray: ...
    @property
    def reason(self) -> numpy.ndarray: ...
    @property
    def score(self) -> numpy.ndarray: ...
    @property
    def trial_reason(self) -> numpy.ndarray: ...
    @property
    def trial_sealed(self) -> numpy.ndarray: ...

class SealTrial:
    """
    SealModel.trial() result: failure name, projected ring (object frame, m), spring forces (N).
    """
    @property
    def center(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]:
        """
        projected centre, m
        """
    @property
    def elastic_force(self) -> numpy.ndarray:
        """
        (N,) float64, N
        """
    @property
    def failure(self) -> str: ...
    @property
    def ring_force(self) -> numpy.ndarray:
        """
        (N,3) float64, N
        """
    @property
    def ring_normals(self) -> numpy.ndarray:
        """
        (N,3) float32
        """
    @property
    def ring_points(self) -> numpy.ndarray:
        """
        (N,3) float32
        """
    @property
    def total_elastic_force(self) -> float:
        """
        N
        """

class SealOptions:
    """
    Options of SealModel.evaluate (mgn/grasp/seal_model.hpp, SI units); the defaults are the C++ struct's, validate() checks the ranges.
    """
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def angle_sigma(self) -> float:
        """
        std of each Euler angle of the normal perturbation, rad
        """
    @angle_sigma.setter
    def angle_sigma(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def first_index(self) -> int:
        """
        candidate i draws from the stream (seed, first_index + i)
        """
    @first_index.setter
    def first_index(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def num_threads(self) -> int:
        """
        0 = all hardware threads
        """
    @num_threads.setter
    def num_threads(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def num_trials(self) -> int:
        """
        perturbed trials per candidate
        """
    @num_trials.setter
    def num_trials(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def on_surface_tolerance(self) -> float:
        """
        candidates must lie on the mesh within this distance along the normal, m
        """
    @on_surface_tolerance.setter
    def on_surface_tolerance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def perturb(self) -> bool:
        """
        false: one deterministic trial at the nominal pose
        """
    @perturb.setter
    def perturb(self, arg0: bool) -> None: ...
    @property
    def position_sigma(self) -> float:
        """
        std of the point jitter per axis, m (< 0: cup radius / 4)
        """
    @position_sigma.setter
    def position_sigma(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def seed(self) -> int: ...
    @seed.setter
    def seed(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...

class SuctionWrenchOptions:
    """
    Constants of suction_wrench_scores (mgn/grasp/wrench.hpp); the defaults are the C++ struct's, validate() checks the ranges.
    """
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def gravity(self) -> float:
        """
        m/s^2
        """
    @gravity.setter
    def gravity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def k(self) -> float:
        """
        tau_max = k * cup radius * pi * sqrt(2) (k in N, radius in m)
        """
    @k.setter
    def k(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class Cup:
    """
    Suction cup parameters for the seal models (SI units; see mgn.SuctionCup).
    """

    name: str
    def __init__(self) -> None: ...
    def compression_stiffness(self) -> float: ...
    def pressure_force(self) -> float: ...
    def validate(self) -> None: ...
    @property
    def approach_height(self) -> float: ...
    @approach_height.setter
    def approach_height(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def body_height(self) -> float: ...
    @body_height.setter
    def body_height(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def c1(self) -> float: ...
    @c1.setter
    def c1(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def c2(self) -> float: ...
    @c2.setter
    def c2(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def compensable_height(self) -> float: ...
    @compensable_height.setter
    def compensable_height(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def hole_rays(self) -> int: ...
    @hole_rays.setter
    def hole_rays(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def num_points(self) -> int: ...
    @num_points.setter
    def num_points(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def outer_radius(self) -> float: ...
    @outer_radius.setter
    def outer_radius(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def pressure_difference(self) -> float: ...
    @pressure_difference.setter
    def pressure_difference(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def radius(self) -> float: ...
    @radius.setter
    def radius(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def youngs_modulus(self) -> float: ...
    @youngs_modulus.setter
    def youngs_modulus(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class SealModel:
    """
    Immutable seal model of one object for one cup.
    """
    def __init__(self, mesh: Mesh, cup: Cup, model: str = "spring") -> None: ...
    def evaluate(
        self, points: typing.Any, normals: typing.Any, options: SealOptions = ...
    ) -> SealResult:
        """
        Seal scores of (N,3) candidates (object frame, m; unit outward normals).
        """
    def trial(
        self,
        point: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
        normal: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
    ) -> SealTrial: ...
    def with_cup(self, cup: Cup) -> SealModel: ...
    @property
    def cup(self) -> Cup: ...
    @property
    def model(self) -> str: ...

class ClassificationMetrics:
    """
    Confusion counts and rates (mgn/grasp/calibration.hpp); NaN for a zero denominator.
    """
    def to_dict(self) -> dict:
        """
        {name: value} of the fields above, for JSON.
        """
    @property
    def accuracy(self) -> float:
        """
        (tp + tn) / count
        """
    @property
    def fn(self) -> int: ...
    @property
    def fp(self) -> int: ...
    @property
    def npv(self) -> float:
        """
        tn / (tn + fn)
        """
    @property
    def ppv(self) -> float:
        """
        tp / (tp + fp), precision
        """
    @property
    def sensitivity(self) -> float:
        """
        tp / (tp + fn)
        """
    @property
    def specificity(self) -> float:
        """
        tn / (tn + fp)
        """
    @property
    def tn(self) -> int: ...
    @property
    def tp(self) -> int: ...

class CalibrationResult:
    """
    calibrate_cup() result (mgn/grasp/calibration.hpp).
    """
    @property
    def cup(self) -> Cup:
        """
        the initial cup with the fitted c1, c2
        """
    @property
    def evaluations(self) -> int: ...
    @property
    def objective(self) -> float:
        """
        training accuracy of the fitted cup
        """
    @property
    def predicted(self) -> numpy.ndarray:
        """
        (N,) bool nominal prediction of the fitted cup
        """
    @property
    def test(self) -> ClassificationMetrics: ...
    @property
    def test_indices(self) -> numpy.ndarray:
        """
        (H,) int64 ascending
        """
    @property
    def train(self) -> ClassificationMetrics: ...
    @property
    def train_indices(self) -> numpy.ndarray:
        """
        (T,) int64 ascending
        """

class LightSample:
    """
    The main point light (mgn/render/renderer.hpp): input of RenderOptions.light, and the light a view was rendered with. The defaults are the C++ struct's.
    """
    def __init__(self) -> None: ...
    @property
    def ambient(self) -> float:
        """
        relative to white
        """
    @ambient.setter
    def ambient(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def color_temperature(self) -> float:
        """
        K
        """
    @color_temperature.setter
    def color_temperature(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def intensity(self) -> float:
        """
        radiance scale (1 = nominal)
        """
    @intensity.setter
    def intensity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def position_W(self) -> tuple[float, float, float]:
        """
        point light position, world frame, m (NaN: 1.5 m above the centre of the scene)
        """
    @position_W.setter
    def position_W(
        self,
        arg1: tuple[
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
        ],
    ) -> None: ...

class RenderOptions:
    """
    What Renderer.render draws and how (mgn/render/renderer.hpp); the defaults are the C++ struct's, validate() checks the ranges.
    """
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def background(self) -> tuple[float, float, float]:
        """
        linear RGB of empty pixels
        """
    @background.setter
    def background(
        self,
        arg1: tuple[
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
        ],
    ) -> None: ...
    @property
    def check_camera_inside(self) -> bool:
        """
        raise if the camera centre is inside a closed mesh
        """
    @check_camera_inside.setter
    def check_camera_inside(self, arg0: bool) -> None: ...
    @property
    def depth(self) -> bool:
        """
        produce the z-depth image
        """
    @depth.setter
    def depth(self, arg0: bool) -> None: ...
    @property
    def instances(self) -> bool:
        """
        produce the instance-id image
        """
    @instances.setter
    def instances(self, arg0: bool) -> None: ...
    @property
    def light(self) -> LightSample:
        """
        the light used when randomize is false
        """
    @light.setter
    def light(self, arg0: LightSample) -> None: ...
    @property
    def randomize(self) -> bool:
        """
        draw the light and the randomize_color colours from (seed, view_index)
        """
    @randomize.setter
    def randomize(self, arg0: bool) -> None: ...
    @property
    def rgb(self) -> bool:
        """
        produce the colour image
        """
    @rgb.setter
    def rgb(self, arg0: bool) -> None: ...
    @property
    def seed(self) -> int: ...
    @seed.setter
    def seed(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def shadows(self) -> bool:
        """
        shadow mapping from the main light
        """
    @shadows.setter
    def shadows(self, arg0: bool) -> None: ...
    @property
    def view_index(self) -> int: ...
    @view_index.setter
    def view_index(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def visible_instances(self) -> list[int]:
        """
        draw only instances with these ids (empty: all)
        """
    @visible_instances.setter
    def visible_instances(
        self, arg0: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex]
    ) -> None: ...

class RenderResult:
    """
    Renderer.render() result: (H,W,3) uint8 rgb, (H,W) float32 depth (m), (H,W) int32 instance_ids (None when not requested), light.
    """
    @property
    def depth(self) -> typing.Any: ...
    @property
    def instance_ids(self) -> typing.Any: ...
    @property
    def light(self) -> LightSample: ...
    @property
    def rgb(self) -> typing.Any: ...

class DepthSensorResult:
    """
    apply_depth_sensor() result: (H,W) float32 depth and depth_ideal (m), (H,W) bool valid.
    """
    @property
    def depth(self) -> typing.Any: ...
    @property
    def depth_ideal(self) -> typing.Any: ...
    @property
    def valid(self) -> typing.Any: ...

class MgnRigParams:
    """
    Drawn parameters of the MetaGraspNet rig (mgn/render/camera.hpp): radii m, angles rad.
    """
    @property
    def R_end(self) -> float: ...
    @property
    def R_start(self) -> float: ...
    @property
    def phi_end(self) -> float: ...
    @property
    def theta_end(self) -> float: ...
    @property
    def theta_start(self) -> float: ...

class Intrinsics:
    """
    Pinhole intrinsics in pixels (OpenCV model).
    """
    @staticmethod
    def mgn_synthetic() -> Intrinsics: ...
    @staticmethod
    def zivid_two_like() -> Intrinsics: ...
    def __init__(
        self,
        width: typing.SupportsInt | typing.SupportsIndex,
        height: typing.SupportsInt | typing.SupportsIndex,
        fx: typing.SupportsFloat | typing.SupportsIndex,
        fy: typing.SupportsFloat | typing.SupportsIndex,
        cx: typing.SupportsFloat | typing.SupportsIndex,
        cy: typing.SupportsFloat | typing.SupportsIndex,
    ) -> None: ...
    def __repr__(self) -> str: ...
    @property
    def K(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 3]"]:
        """
        (3, 3) intrinsic matrix
        """
    @property
    def cx(self) -> float: ...
    @property
    def cy(self) -> float: ...
    @property
    def fx(self) -> float: ...
    @property
    def fy(self) -> float: ...
    @property
    def height(self) -> int: ...
    @property
    def width(self) -> int: ...

class Renderer:
    """
    Off-screen OSMesa renderer (one GL context, reused).
    """
    def __init__(
        self,
        max_width: typing.SupportsInt | typing.SupportsIndex,
        max_height: typing.SupportsInt | typing.SupportsIndex,
    ) -> None: ...
    def add_mesh(self, mesh: Mesh) -> int: ...
    def render(self, K: Intrinsics, X_WC: typing.Any, options: RenderOptions = ...) -> RenderResult:
        """
        Renders one view (camera frame OpenCV, X_WC in m): rgb, depth, instance_ids and the light used.
        """
    def set_instances(
        self,
        mesh_ids: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex],
        poses: typing.Any,
        instance_ids: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex],
        randomize_color: collections.abc.Sequence[bool] = [],
    ) -> None: ...
    @property
    def max_height(self) -> int: ...
    @property
    def max_width(self) -> int: ...
    @property
    def num_instances(self) -> int: ...
    @property
    def num_meshes(self) -> int: ...

class DepthSensorPreset:
    """
    Members:

      Ideal

      StructuredLight

      ToF
    """

    Ideal: typing.ClassVar[DepthSensorPreset]
    StructuredLight: typing.ClassVar[DepthSensorPreset]
    ToF: typing.ClassVar[DepthSensorPreset]
    __members__: typing.ClassVar[dict[str, DepthSensorPreset]]
    @typing.overload
    def __eq__(self, other: DepthSensorPreset) -> bool: ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool: ...
    def __getstate__(self) -> int: ...
    def __hash__(self) -> int: ...
    def __index__(self) -> int: ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    def __int__(self) -> int: ...
    @typing.overload
    def __ne__(self, other: DepthSensorPreset) -> bool: ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool: ...
    def __repr__(self) -> str: ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    def __str__(self) -> str: ...
    @property
    def name(self) -> str: ...
    @property
    def value(self) -> int: ...

class DepthSensorParams:
    """
    Depth sensor model parameters (SI).
    """

    invalid_dark: bool
    invalid_mirror: bool
    invalid_transparent: bool
    preset: DepthSensorPreset
    @staticmethod
    def preset_defaults(preset: DepthSensorPreset) -> DepthSensorParams: ...
    def __init__(self) -> None: ...
    def validate(self) -> None: ...
    @property
    def baseline(self) -> float:
        """
        m, projector along camera +x
        """
    @baseline.setter
    def baseline(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def depth_step(self) -> float:
        """
        m, grid of the reported z (0 = continuous)
        """
    @depth_step.setter
    def depth_step(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def depth_step_noise_fraction(self) -> float:
        """
        the grid at a pixel: the largest 2^k depth_step not above this times the noise sigma (0 = fixed depth_step)
        """
    @depth_step_noise_fraction.setter
    def depth_step_noise_fraction(
        self, arg0: typing.SupportsFloat | typing.SupportsIndex
    ) -> None: ...
    @property
    def edge_threshold(self) -> float:
        """
        m
        """
    @edge_threshold.setter
    def edge_threshold(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def flying_pixel_probability(self) -> float: ...
    @flying_pixel_probability.setter
    def flying_pixel_probability(
        self, arg0: typing.SupportsFloat | typing.SupportsIndex
    ) -> None: ...
    @property
    def max_range(self) -> float:
        """
        m
        """
    @max_range.setter
    def max_range(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def min_range(self) -> float:
        """
        m
        """
    @min_range.setter
    def min_range(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def shadow_tolerance_px(self) -> float:
        """
        px
        """
    @shadow_tolerance_px.setter
    def shadow_tolerance_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def sigma_a(self) -> float:
        """
        m
        """
    @sigma_a.setter
    def sigma_a(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def sigma_b(self) -> float:
        """
        1/m
        """
    @sigma_b.setter
    def sigma_b(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def sigma_z0(self) -> float:
        """
        m
        """
    @sigma_z0.setter
    def sigma_z0(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

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

class DropOptions:
    """
    Options of drop_objects (mgn/scene/drop.hpp, SI units); the defaults are the C++ struct's, validate() checks the ranges.
    """

    polyhedral_contacts: bool
    remove_unsettled: bool
    tote_collision: str
    two_friction_directions: bool
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def angular_damping(self) -> float: ...
    @angular_damping.setter
    def angular_damping(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def angular_rest(self) -> float: ...
    @angular_rest.setter
    def angular_rest(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def collision_margin(self) -> float: ...
    @collision_margin.setter
    def collision_margin(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def contact_distance(self) -> float: ...
    @contact_distance.setter
    def contact_distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def dt(self) -> float: ...
    @dt.setter
    def dt(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def gravity(self) -> float: ...
    @gravity.setter
    def gravity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def guard_height(self) -> float: ...
    @guard_height.setter
    def guard_height(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def hull_tolerance(self) -> float: ...
    @hull_tolerance.setter
    def hull_tolerance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def linear_rest(self) -> float: ...
    @linear_rest.setter
    def linear_rest(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def max_hull_vertices(self) -> int: ...
    @max_hull_vertices.setter
    def max_hull_vertices(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def max_time(self) -> float: ...
    @max_time.setter
    def max_time(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def resettle_time(self) -> float: ...
    @resettle_time.setter
    def resettle_time(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def rest_time(self) -> float: ...
    @rest_time.setter
    def rest_time(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def rolling_friction(self) -> float: ...
    @rolling_friction.setter
    def rolling_friction(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def seed(self) -> int: ...
    @seed.setter
    def seed(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def solver_iterations(self) -> int: ...
    @solver_iterations.setter
    def solver_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def tote_friction(self) -> float: ...
    @tote_friction.setter
    def tote_friction(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def tote_restitution(self) -> float: ...
    @tote_restitution.setter
    def tote_restitution(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def window_max(self) -> tuple[float, float, float]: ...
    @window_max.setter
    def window_max(
        self,
        arg1: tuple[
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
        ],
    ) -> None: ...
    @property
    def window_min(self) -> tuple[float, float, float]: ...
    @window_min.setter
    def window_min(
        self,
        arg1: tuple[
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
        ],
    ) -> None: ...

class DropResult:
    """
    drop_objects() result: one row per input object, in input order.
    """
    @property
    def X_WO(self) -> numpy.ndarray:
        """
        (N,4,4) float64 settled poses, m
        """
    @property
    def X_WO_release(self) -> numpy.ndarray:
        """
        (N,4,4) float64 release (or start) poses, m
        """
    @property
    def contacts(self) -> numpy.ndarray:
        """
        (N,) uint32 tote contact flags (bits -x, +x, -y, +y walls, floor)
        """
    @property
    def max_penetration(self) -> float:
        """
        deepest contact penetration on the simulated hulls, m
        """
    @property
    def object_settled(self) -> numpy.ndarray:
        """
        (N,) bool: at rest when the simulation stopped
        """
    @property
    def resettle_rounds(self) -> int: ...
    @property
    def settled(self) -> bool:
        """
        every remaining object came to rest
        """
    @property
    def simulated_time(self) -> float:
        """
        s
        """
    @property
    def status(self) -> numpy.ndarray:
        """
        (N,) int32: 0 kept, 1 left the tote, 2 not settled
        """
    @property
    def steps(self) -> int: ...

class AntipodalResult:
    """
    AntipodalSampler.sample() result (mgn/grasp/antipodal.hpp); mgn.pj.sampler.AntipodalResult documents each array.
    """
    @property
    def approach(self) -> numpy.ndarray: ...
    @property
    def closing(self) -> numpy.ndarray: ...
    @property
    def num_accepted_probes(self) -> int: ...
    @property
    def num_colliding(self) -> int: ...
    @property
    def num_kept(self) -> numpy.ndarray: ...
    @property
    def p1(self) -> numpy.ndarray: ...
    @property
    def point_index(self) -> numpy.ndarray: ...
    @property
    def point_score(self) -> numpy.ndarray: ...
    @property
    def probe(self) -> numpy.ndarray: ...
    @property
    def score(self) -> numpy.ndarray: ...
    @property
    def width(self) -> numpy.ndarray: ...

class AntipodalOptions:
    """
    Options of AntipodalSampler.sample (mgn/grasp/antipodal.hpp, SI units); the defaults are the C++ struct's (MetaGraspNet), validate() checks the ranges.
    """
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def approaches_kept(self) -> int:
        """
        collision-free approaches kept per accepted probe
        """
    @approaches_kept.setter
    def approaches_kept(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def approaches_tried(self) -> int:
        """
        random approach directions tried per accepted probe
        """
    @approaches_tried.setter
    def approaches_tried(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def check_collision(self) -> bool:
        """
        false: keep the first approaches_kept approaches unchecked
        """
    @check_collision.setter
    def check_collision(self, arg0: bool) -> None: ...
    @property
    def first_index(self) -> int:
        """
        point i uses the random stream (seed, first_index + i)
        """
    @first_index.setter
    def first_index(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def friction_coef(self) -> float:
        """
        mu; friction cone half-angle atan(mu)
        """
    @friction_coef.setter
    def friction_coef(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def num_threads(self) -> int:
        """
        0 = all hardware threads
        """
    @num_threads.setter
    def num_threads(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def offset(self) -> float:
        """
        bound of the start offset per axis, m
        """
    @offset.setter
    def offset(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def probes(self) -> int:
        """
        perturbed probes per contact point
        """
    @probes.setter
    def probes(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def seed(self) -> int: ...
    @seed.setter
    def seed(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def start_offset(self) -> float:
        """
        the probe ray starts this far outside the surface, m
        """
    @start_offset.setter
    def start_offset(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def tilt(self) -> float:
        """
        bound of each Euler angle of the probe tilt, rad
        """
    @tilt.setter
    def tilt(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class PjWrenchOptions:
    """
    Constants of pj_wrench_scores (mgn/grasp/pj_wrench.hpp, SI units); the defaults are the C++ struct's, validate() checks the ranges.
    """
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def contact_radius(self) -> float:
        """
        radius of the soft contact patch, m
        """
    @contact_radius.setter
    def contact_radius(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def friction(self) -> float:
        """
        mu between finger pads and object
        """
    @friction.setter
    def friction(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def gravity(self) -> float:
        """
        m/s^2
        """
    @gravity.setter
    def gravity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def grip_force(self) -> float:
        """
        normal force per finger, N
        """
    @grip_force.setter
    def grip_force(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class ParallelJawGripper:
    """
    Parallel-jaw gripper (SI units; see mgn.hardware.ParallelJawGripper). Box gripper unless palm_mesh, finger_left_mesh and finger_right_mesh are all set (closed, hand frame, fingers at opening 0).
    """

    finger_left_mesh: Mesh
    finger_right_mesh: Mesh
    name: str
    palm_mesh: Mesh
    def __init__(self) -> None: ...
    def collision_opening(self, width: typing.SupportsFloat | typing.SupportsIndex) -> float: ...
    def grasp_depth(self) -> float: ...
    def has_meshes(self) -> bool: ...
    def validate(self) -> None: ...
    @property
    def collision_margin(self) -> float: ...
    @collision_margin.setter
    def collision_margin(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def contact_from_tip(self) -> float: ...
    @contact_from_tip.setter
    def contact_from_tip(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def finger_size(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]: ...
    @finger_size.setter
    def finger_size(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"]
    ) -> None: ...
    @property
    def flange_to_tip(self) -> float: ...
    @flange_to_tip.setter
    def flange_to_tip(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def friction(self) -> float: ...
    @friction.setter
    def friction(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def max_opening(self) -> float: ...
    @max_opening.setter
    def max_opening(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def palm_size(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]: ...
    @palm_size.setter
    def palm_size(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"]
    ) -> None: ...

class AntipodalSampler:
    """
    Immutable antipodal grasp sampler of one object for one gripper.
    """
    def __init__(self, mesh: Mesh, gripper: ParallelJawGripper) -> None: ...
    def collides(
        self, X_OH: typing.Any, opening: typing.SupportsFloat | typing.SupportsIndex
    ) -> bool: ...
    def sample(
        self, points: typing.Any, normals: typing.Any, options: AntipodalOptions = ...
    ) -> AntipodalResult:
        """
        Antipodal grasps from (N,3) contact points and unit outward normals (object frame, m).
        """
    @property
    def gripper(self) -> ParallelJawGripper: ...

class ShakeOptions:
    """
    Options of the Bullet shake test (SI units; see mgn.pj.physics).
    """

    polyhedral_contacts: bool
    smooth_shake: bool
    staircase: bool
    def __init__(self) -> None: ...
    def density_factors(self) -> list[float]: ...
    def frictions(self) -> list[float]: ...
    def staircase_verified_rows(self) -> int:
        """
        Rows whose boundary the staircase verifies: ceil(staircase_verify_share * grid).
        """
    def validate(self) -> None: ...
    @property
    def angle_max(self) -> float: ...
    @angle_max.setter
    def angle_max(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def angle_min(self) -> float: ...
    @angle_min.setter
    def angle_min(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def close_speed(self) -> float: ...
    @close_speed.setter
    def close_speed(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def close_steps(self) -> int: ...
    @close_steps.setter
    def close_steps(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def contact_distance(self) -> float: ...
    @contact_distance.setter
    def contact_distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def controller_stiffness(self) -> float: ...
    @controller_stiffness.setter
    def controller_stiffness(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def density_max(self) -> float: ...
    @density_max.setter
    def density_max(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def density_min(self) -> float: ...
    @density_min.setter
    def density_min(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def dt(self) -> float: ...
    @dt.setter
    def dt(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def first_grasp_index(self) -> int: ...
    @first_grasp_index.setter
    def first_grasp_index(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def friction_max(self) -> float: ...
    @friction_max.setter
    def friction_max(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def friction_min(self) -> float: ...
    @friction_min.setter
    def friction_min(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def gravity(self) -> float: ...
    @gravity.setter
    def gravity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def grid(self) -> int: ...
    @grid.setter
    def grid(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def grip_force(self) -> float: ...
    @grip_force.setter
    def grip_force(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def hold_tolerance(self) -> float: ...
    @hold_tolerance.setter
    def hold_tolerance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def inertia_floor(self) -> float: ...
    @inertia_floor.setter
    def inertia_floor(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def iterations_per_hull_contact(self) -> float: ...
    @iterations_per_hull_contact.setter
    def iterations_per_hull_contact(
        self, arg0: typing.SupportsFloat | typing.SupportsIndex
    ) -> None: ...
    @property
    def lost_contact_steps(self) -> int: ...
    @lost_contact_steps.setter
    def lost_contact_steps(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def margin(self) -> float: ...
    @margin.setter
    def margin(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def max_hull_vertices(self) -> int: ...
    @max_hull_vertices.setter
    def max_hull_vertices(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def num_threads(self) -> int: ...
    @num_threads.setter
    def num_threads(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def pad_damping(self) -> float: ...
    @pad_damping.setter
    def pad_damping(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def pad_stiffness(self) -> float: ...
    @pad_stiffness.setter
    def pad_stiffness(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def rotate_cycles(self) -> int: ...
    @rotate_cycles.setter
    def rotate_cycles(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def rotate_steps(self) -> int: ...
    @rotate_steps.setter
    def rotate_steps(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def seed(self) -> int: ...
    @seed.setter
    def seed(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def settle_steps(self) -> int: ...
    @settle_steps.setter
    def settle_steps(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def shake_cycles(self) -> int: ...
    @shake_cycles.setter
    def shake_cycles(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def shake_speed(self) -> float: ...
    @shake_speed.setter
    def shake_speed(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def shake_steps(self) -> int: ...
    @shake_steps.setter
    def shake_steps(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def solver_iterations(self) -> int: ...
    @solver_iterations.setter
    def solver_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def staircase_checks(self) -> int: ...
    @staircase_checks.setter
    def staircase_checks(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def staircase_verify_share(self) -> float: ...
    @staircase_verify_share.setter
    def staircase_verify_share(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class ShakeResult:
    """
    shake_test() result (mgn/grasp/shake_trial.hpp): G grasps on an S x S friction x density grid.
    """
    @property
    def density_factors(self) -> numpy.ndarray:
        """
        (S,) density factors
        """
    @property
    def fallback(self) -> numpy.ndarray:
        """
        (G,) bool: a staircase check failed and the full grid was simulated
        """
    @property
    def frictions(self) -> numpy.ndarray:
        """
        (S,) friction coefficients
        """
    @property
    def score(self) -> numpy.ndarray:
        """
        (G,) float64 success fraction over the grid
        """
    @property
    def total_steps(self) -> int:
        """
        simulation steps of all trials
        """
    @property
    def trial_ended_early(self) -> numpy.ndarray:
        """
        (G, S, S) bool
        """
    @property
    def trial_simulated(self) -> numpy.ndarray:
        """
        (G, S, S) bool: simulated (else inferred by the staircase search)
        """
    @property
    def trial_steps(self) -> numpy.ndarray:
        """
        (G, S, S) int steps simulated
        """
    @property
    def trial_success(self) -> numpy.ndarray:
        """
        (G, S, S) bool [grasp][friction i][density j]
        """

class StaircaseGridResult:
    """
    staircase_grid() result: success and simulated (S, S) bool [friction i][density j], fallback, trials.
    """
    @property
    def fallback(self) -> bool:
        """
        a check contradicted its inference: every cell was simulated
        """
    @property
    def simulated(self) -> numpy.ndarray:
        """
        (S, S) bool: trial() was called
        """
    @property
    def success(self) -> numpy.ndarray:
        """
        (S, S) bool
        """
    @property
    def trials(self) -> int:
        """
        calls of trial()
        """

class ShakeTrajectoryResult:
    """
    shake_trajectory() result, one row per recorded step (world W: z up; poses (K, 4, 4) m).
    """
    @property
    def X_WH(self) -> numpy.ndarray:
        """
        (K, 4, 4) hand pose
        """
    @property
    def X_WO(self) -> numpy.ndarray:
        """
        (K, 4, 4) object pose
        """
    @property
    def contact_left(self) -> numpy.ndarray:
        """
        (K,) bool
        """
    @property
    def contact_right(self) -> numpy.ndarray:
        """
        (K,) bool
        """
    @property
    def density_factor(self) -> float: ...
    @property
    def ended_early(self) -> bool: ...
    @property
    def finger_left(self) -> numpy.ndarray:
        """
        (K,) finger opening, m
        """
    @property
    def finger_right(self) -> numpy.ndarray:
        """
        (K,) finger opening, m
        """
    @property
    def friction(self) -> float: ...
    @property
    def phase(self) -> numpy.ndarray:
        """
        (K,) int8 ShakePhase
        """
    @property
    def steps(self) -> int: ...
    @property
    def success(self) -> bool: ...
    @property
    def time(self) -> numpy.ndarray:
        """
        (K,) s since the start
        """

class LayoutArrays:
    """
    compute_layout() result (mgn/scene/layout.hpp): 0-based object indices; rel_* are the relations sorted by (child, parent).
    """
    @property
    def classes_unique(self) -> bool: ...
    @property
    def complete(self) -> numpy.ndarray:
        """
        (N,) bool
        """
    @property
    def difficulty(self) -> int:
        """
        1..5
        """
    @property
    def layer(self) -> numpy.ndarray:
        """
        (N,) int8
        """
    @property
    def max_occlusion(self) -> float: ...
    @property
    def num_layers(self) -> int: ...
    @property
    def num_regions(self) -> numpy.ndarray:
        """
        (N,) int32
        """
    @property
    def order(self) -> numpy.ndarray:
        """
        picking order, int32 1-based ids
        """
    @property
    def rel_child(self) -> numpy.ndarray:
        """
        (R,) int32 0-based
        """
    @property
    def rel_depth_diff(self) -> numpy.ndarray:
        """
        (R,) float64 m
        """
    @property
    def rel_edge_size(self) -> numpy.ndarray:
        """
        (R,) int32 px
        """
    @property
    def rel_parent(self) -> numpy.ndarray:
        """
        (R,) int32 0-based
        """
    @property
    def rel_seen_px(self) -> numpy.ndarray:
        """
        (R,) int64 px
        """
    @property
    def relation(self) -> numpy.ndarray:
        """
        (N,N) int8 relation matrix
        """
    @property
    def total_covered_edge(self) -> numpy.ndarray:
        """
        (N,) int64 px
        """
    @property
    def visible(self) -> numpy.ndarray:
        """
        (N,) bool
        """
    @property
    def visible_px(self) -> numpy.ndarray:
        """
        (N,) int64
        """

class PbrMaterial:
    """
    glTF 2.0 metallic-roughness material (path tracer).
    """
    def __init__(self) -> None: ...
    def set_texture(self, texture: typing.Any) -> None:
        """
        (H, W, 3) uint8 sRGB, top row first, or None
        """
    def validate(self) -> None: ...
    @property
    def base_color(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float32], "[3, 1]"]: ...
    @base_color.setter
    def base_color(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[3, 1]"]
    ) -> None: ...
    @property
    def emission(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float32], "[3, 1]"]: ...
    @emission.setter
    def emission(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[3, 1]"]
    ) -> None: ...
    @property
    def ior(self) -> float: ...
    @ior.setter
    def ior(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def metallic(self) -> float: ...
    @metallic.setter
    def metallic(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def roughness(self) -> float: ...
    @roughness.setter
    def roughness(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def transmission(self) -> float: ...
    @transmission.setter
    def transmission(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class AreaLight:
    """
    One-sided rect or disc area light emitting along +z_L.
    """

    shape: str
    def __init__(self) -> None: ...
    def validate(self) -> None: ...
    @property
    def X_WL(self) -> numpy.ndarray: ...
    @X_WL.setter
    def X_WL(self, arg1: typing.Any) -> None: ...
    @property
    def color(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float32], "[3, 1]"]: ...
    @color.setter
    def color(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[3, 1]"]
    ) -> None: ...
    @property
    def intensity(self) -> float: ...
    @intensity.setter
    def intensity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def size(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[2, 1]"]: ...
    @size.setter
    def size(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[2, 1]"]
    ) -> None: ...

class Environment:
    """
    Environment dome: uniform, gradient or sky.
    """

    kind: str
    def __init__(self) -> None: ...
    def validate(self) -> None: ...
    @property
    def color(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float32], "[3, 1]"]: ...
    @color.setter
    def color(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[3, 1]"]
    ) -> None: ...
    @property
    def ground(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float32], "[3, 1]"]: ...
    @ground.setter
    def ground(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[3, 1]"]
    ) -> None: ...
    @property
    def horizon(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float32], "[3, 1]"]: ...
    @horizon.setter
    def horizon(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[3, 1]"]
    ) -> None: ...
    @property
    def intensity(self) -> float: ...
    @intensity.setter
    def intensity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def sun_angular_radius(self) -> float: ...
    @sun_angular_radius.setter
    def sun_angular_radius(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def sun_direction(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]: ...
    @sun_direction.setter
    def sun_direction(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"]
    ) -> None: ...
    @property
    def sun_strength(self) -> float: ...
    @sun_strength.setter
    def sun_strength(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def zenith(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float32], "[3, 1]"]: ...
    @zenith.setter
    def zenith(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[3, 1]"]
    ) -> None: ...

class PathTraceOptions:
    """
    Path tracing settings of one view.
    """

    labels: bool
    sample_sky_dome: bool
    def __init__(self) -> None: ...
    def validate(self) -> None: ...
    @property
    def adaptive_max(self) -> int: ...
    @adaptive_max.setter
    def adaptive_max(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def adaptive_samples(self) -> float: ...
    @adaptive_samples.setter
    def adaptive_samples(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def aperture_radius(self) -> float: ...
    @aperture_radius.setter
    def aperture_radius(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def clamp(self) -> float: ...
    @clamp.setter
    def clamp(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def clamp_indirect(self) -> float: ...
    @clamp_indirect.setter
    def clamp_indirect(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def focus_distance(self) -> float: ...
    @focus_distance.setter
    def focus_distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def fresnel_split_min(self) -> float: ...
    @fresnel_split_min.setter
    def fresnel_split_min(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def guide_split_min(self) -> float: ...
    @guide_split_min.setter
    def guide_split_min(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def max_bounces(self) -> int: ...
    @max_bounces.setter
    def max_bounces(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def num_threads(self) -> int: ...
    @num_threads.setter
    def num_threads(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def reduced_nee_depth(self) -> int: ...
    @reduced_nee_depth.setter
    def reduced_nee_depth(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def rr_depth(self) -> int: ...
    @rr_depth.setter
    def rr_depth(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def seed(self) -> int: ...
    @seed.setter
    def seed(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def shadow_rays(self) -> int: ...
    @shadow_rays.setter
    def shadow_rays(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def spp(self) -> int: ...
    @spp.setter
    def spp(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def view_index(self) -> int: ...
    @view_index.setter
    def view_index(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...

class FilmOptions:
    """
    Radiance to 8-bit sRGB development settings.
    """

    tone: str
    def __init__(self) -> None: ...
    def validate(self) -> None: ...
    @property
    def exposure(self) -> float: ...
    @exposure.setter
    def exposure(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def num_threads(self) -> int: ...
    @num_threads.setter
    def num_threads(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def read_noise(self) -> float: ...
    @read_noise.setter
    def read_noise(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def seed(self) -> int: ...
    @seed.setter
    def seed(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def shot_noise(self) -> float: ...
    @shot_noise.setter
    def shot_noise(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def view_index(self) -> int: ...
    @view_index.setter
    def view_index(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...

class PathTraceResult:
    """
    PathScene.render() result (mgn/render/path_tracer.hpp), top row first.
    """
    @property
    def albedo(self) -> numpy.ndarray:
        """
        (H, W, 3) float32 first-hit base colour
        """
    @property
    def depth(self) -> numpy.ndarray:
        """
        (H, W) float32 z-depth in m, 0 = no hit
        """
    @property
    def instance_ids(self) -> numpy.ndarray:
        """
        (H, W) int32, 0 = background
        """
    @property
    def normal(self) -> numpy.ndarray:
        """
        (H, W, 3) float32 first-hit shading normal, world frame
        """
    @property
    def radiance(self) -> numpy.ndarray:
        """
        (H, W, 3) float32 linear RGB, sample mean
        """
    @property
    def rays(self) -> int:
        """
        rays cast (camera, bounce and shadow)
        """

class PathScene:
    """
    Immutable path-traced scene (Embree geometry + lights).
    """
    def __init__(
        self,
        meshes: collections.abc.Sequence[Mesh],
        poses: typing.Any,
        instance_ids: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex],
        materials: collections.abc.Sequence[collections.abc.Sequence[PbrMaterial]],
        lights: collections.abc.Sequence[AreaLight],
        environment: Environment,
    ) -> None: ...
    def render(
        self, K: Intrinsics, X_WC: typing.Any, options: PathTraceOptions
    ) -> PathTraceResult: ...
    def with_lighting(
        self, lights: collections.abc.Sequence[AreaLight], environment: Environment
    ) -> PathScene: ...
    @property
    def num_triangles(self) -> int: ...

class ObjectGraspLabels:
    """
    Object-level grasp labels of one object, the input of SceneGraspModel (mgn/scene/scene_grasps.hpp). Object frame O, metres; every argument is optional (None: no labels of that kind, or NaN scores).
    """
    def __init__(
        self,
        pj_p1: typing.Any | None = None,
        pj_closing: typing.Any = None,
        pj_approach: typing.Any = None,
        pj_width: typing.Any = None,
        pj_score_analytical: typing.Any = None,
        pj_score_simulation: typing.Any = None,
        suction_points: typing.Any = None,
        suction_approach: typing.Any = None,
        suction_score_analytical: typing.Any = None,
        suction_score_simulation: typing.Any = None,
    ) -> None: ...
    @property
    def pj_approach(self) -> numpy.ndarray:
        """
        (M,3) float64 unit approach direction, object frame
        """
    @property
    def pj_closing(self) -> numpy.ndarray:
        """
        (M,3) float64 unit closing direction v (p2 = p1 + w v), object frame
        """
    @property
    def pj_p1(self) -> numpy.ndarray:
        """
        (M,3) float64 first contact p1 of each parallel-jaw grasp, object frame, m
        """
    @property
    def pj_score_analytical(self) -> numpy.ndarray:
        """
        (M,) or (0,) float32 analytical score in [0, 1]
        """
    @property
    def pj_score_simulation(self) -> numpy.ndarray:
        """
        (M,) or (0,) float32 simulation score in [0, 1]
        """
    @property
    def pj_width(self) -> numpy.ndarray:
        """
        (M,) float32 contact width w, m
        """
    @property
    def suction_approach(self) -> numpy.ndarray:
        """
        (K,3) float32 approach directions into the surface, object frame
        """
    @property
    def suction_points(self) -> numpy.ndarray:
        """
        (K,3) float32 suction contacts, object frame, m
        """
    @property
    def suction_score_analytical(self) -> numpy.ndarray:
        """
        (K,) or (0,) float32 seal score in [0, 1]
        """
    @property
    def suction_score_simulation(self) -> numpy.ndarray:
        """
        (K,) or (0,) float32 simulation score in [0, 1]
        """

class SuctionTool:
    """
    Suction tool geometry behind the cup body for the scene collision check (mgn/scene/scene_grasps.hpp, m); defaults are the C++ struct's.
    """
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def clearance(self) -> float:
        """
        gap between the contact and the bottom of the cup body, m
        """
    @clearance.setter
    def clearance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def shaft_length(self) -> float:
        """
        m
        """
    @shaft_length.setter
    def shaft_length(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def shaft_radius(self) -> float:
        """
        m
        """
    @shaft_radius.setter
    def shaft_radius(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class SceneGraspOptions:
    """
    Options of SceneGraspModel (mgn/scene/scene_grasps.hpp, SI units); the defaults are the C++ struct's, validate() checks the ranges.
    """

    pj_wrench: PjWrenchOptions
    suction_wrench: SuctionWrenchOptions
    tool: SuctionTool
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def approach_step(self) -> float:
        """
        largest spacing of the poses checked between offsets, m
        """
    @approach_step.setter
    def approach_step(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def first_collision_only(self) -> bool:
        """
        stop at each label grasp's first colliding pose (hit of the later offsets = -2, not checked)
        """
    @first_collision_only.setter
    def first_collision_only(self, arg0: bool) -> None: ...
    @property
    def gravity_world(self) -> tuple[float, float, float]:
        """
        direction of gravity in the world (tote frame), normalised by the model
        """
    @gravity_world.setter
    def gravity_world(
        self,
        arg1: tuple[
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
        ],
    ) -> None: ...
    @property
    def near_plane(self) -> float:
        """
        m
        """
    @near_plane.setter
    def near_plane(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def num_threads(self) -> int:
        """
        0 = all hardware threads
        """
    @num_threads.setter
    def num_threads(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def offsets(self) -> list[float]:
        """
        distances back along the approach where the tool is checked, m
        """
    @offsets.setter
    def offsets(
        self, arg0: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex]
    ) -> None: ...
    @property
    def visibility_tolerance(self) -> float:
        """
        m
        """
    @visibility_tolerance.setter
    def visibility_tolerance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class PlacedGraspArrays:
    """
    SceneGraspModel.pj / .suction (mgn/scene/scene_grasps.hpp): world-frame grasps of every object; mgn.view_labels.grasps.PlacedGrasps documents each array.
    """
    @property
    def colliding(self) -> numpy.ndarray: ...
    @property
    def collision_obstacle(self) -> numpy.ndarray: ...
    @property
    def collision_part(self) -> numpy.ndarray: ...
    @property
    def contact_poses(self) -> numpy.ndarray: ...
    @property
    def contacts(self) -> numpy.ndarray: ...
    @property
    def hit(self) -> numpy.ndarray: ...
    @property
    def object_index(self) -> numpy.ndarray: ...
    @property
    def score_analytical(self) -> numpy.ndarray: ...
    @property
    def score_simulation(self) -> numpy.ndarray: ...
    @property
    def score_wrench(self) -> numpy.ndarray: ...
    @property
    def second_contacts(self) -> numpy.ndarray: ...
    @property
    def tool_poses(self) -> numpy.ndarray: ...
    @property
    def width(self) -> numpy.ndarray: ...

class ToolCollisionArrays:
    """
    SceneGraspModel.collides(): colliding (M,) bool, hit (M, K) int32.
    """
    @property
    def colliding(self) -> numpy.ndarray: ...
    @property
    def hit(self) -> numpy.ndarray: ...

class ViewGraspArrays:
    """
    SceneGraspModel.view_grasps(): row indices and camera-frame (N,4,4) tool and contact poses of the grasps kept in a view.
    """
    @property
    def pj_contact(self) -> numpy.ndarray: ...
    @property
    def pj_index(self) -> numpy.ndarray: ...
    @property
    def pj_tool(self) -> numpy.ndarray: ...
    @property
    def suction_contact(self) -> numpy.ndarray: ...
    @property
    def suction_index(self) -> numpy.ndarray: ...
    @property
    def suction_tool(self) -> numpy.ndarray: ...

class SceneGraspModel:
    """
    Per-scene grasp model: placement, collisions and wrench scores at construction; view_grasps per camera (see mgn/scene/scene_grasps.hpp).
    """
    def __init__(
        self,
        meshes: collections.abc.Sequence[Mesh],
        poses: typing.Any,
        masses: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
        coms: typing.Any,
        labels: collections.abc.Sequence[ObjectGraspLabels],
        tote: Mesh,
        X_WT: typing.Any,
        gripper: ParallelJawGripper,
        cup: Cup,
        options: SceneGraspOptions = ...,
    ) -> None: ...
    def collides(
        self,
        kind: str,
        X_W_contact: typing.Any,
        width: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
        target_object: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex],
        check_target_at_grasp: bool = False,
    ) -> ToolCollisionArrays:
        """
        Collision of arbitrary grasp (contact-frame) poses with the labels' test: colliding (M,) bool and hit (M, K) int32.
        """
    def pj(self) -> PlacedGraspArrays:
        """
        Parallel-jaw grasps in the world (PlacedGraspArrays).
        """
    def suction(self) -> PlacedGraspArrays:
        """
        Suction grasps in the world (PlacedGraspArrays).
        """
    def view_grasps(self, K: Intrinsics, X_WC: typing.Any, seen: typing.Any) -> ViewGraspArrays:
        """
        Grasps kept in a view: row indices and camera-frame poses.
        """
    def visible(self, K: Intrinsics, X_WC: typing.Any, points: typing.Any) -> numpy.ndarray:
        """
        (N,) bool: whether each world point is visible from the camera.
        """
    @property
    def num_objects(self) -> int: ...
    @property
    def offsets(self) -> list[float]: ...

class ViewLabelArrays:
    """
    ViewLabelModel.label_view() result (mgn/scene/view_labels.hpp); mgn.view_labels.objects.ViewObjectLabels documents each array.
    """
    @property
    def X_CO(self) -> numpy.ndarray: ...
    @property
    def amodal(self) -> numpy.ndarray: ...
    @property
    def amodal_pixels(self) -> numpy.ndarray: ...
    @property
    def bbox_loose(self) -> numpy.ndarray: ...
    @property
    def bbox_tight(self) -> numpy.ndarray: ...
    @property
    def com_heatmap(self) -> numpy.ndarray: ...
    @property
    def com_object(self) -> numpy.ndarray: ...
    @property
    def com_points(self) -> numpy.ndarray: ...
    @property
    def com_visible(self) -> numpy.ndarray: ...
    @property
    def keypoint_object(self) -> numpy.ndarray: ...
    @property
    def keypoints(self) -> numpy.ndarray: ...
    @property
    def occluded_keypoint_object(self) -> numpy.ndarray: ...
    @property
    def occluded_keypoints(self) -> numpy.ndarray: ...
    @property
    def occlusion(self) -> numpy.ndarray: ...
    @property
    def occlusion_map(self) -> numpy.ndarray: ...
    @property
    def semantic(self) -> numpy.ndarray: ...
    @property
    def visible(self) -> numpy.ndarray: ...
    @property
    def visible_pixels(self) -> numpy.ndarray: ...

class ViewLabelModel:
    """
    Ray-tracing model of one scene for per-view object labels.
    """
    def __init__(
        self,
        meshes: collections.abc.Sequence[Mesh],
        poses: typing.Any,
        category_ids: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex],
        keypoints: collections.abc.Sequence[typing.Any],
        com_points: collections.abc.Sequence[typing.Any],
        coms: typing.Any,
        tote: Mesh | None = None,
        X_W_tote: typing.Any = None,
    ) -> None: ...
    def label_view(
        self,
        K: Intrinsics,
        X_WC: typing.Any,
        instance_image: typing.Any,
        keypoint_tolerance: typing.SupportsFloat | typing.SupportsIndex = 0.002,
        keypoints: bool = True,
        num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
        depth: typing.Any = None,
    ) -> ViewLabelArrays: ...
    @property
    def has_tote(self) -> bool: ...
    @property
    def num_objects(self) -> int: ...

def apply_depth_sensor(
    depth: typing.Any,
    instance_ids: typing.Any,
    flags_by_id: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex],
    K: Intrinsics,
    params: DepthSensorParams,
    seed: typing.SupportsInt | typing.SupportsIndex,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> DepthSensorResult: ...
def block_means_2x2(
    image: typing.Any, num_threads: typing.SupportsInt | typing.SupportsIndex = 0
) -> numpy.ndarray:
    """
    Means of the 2 x 2 pixel blocks of an (H, W, C) float32 image (an odd last row or column repeated): (ceil(H/2), ceil(W/2), C).
    """

def build_info() -> list[tuple[str, str]]:
    """
    (library, version) pairs for mgn and every library the core was built against.
    """

def calibrate_cup(
    surfaces: collections.abc.Sequence[Mesh],
    surface_index: typing.Any,
    points: typing.Any,
    normals: typing.Any,
    sealed: typing.Any,
    cup: Cup,
    c1_min: typing.SupportsFloat | typing.SupportsIndex = 0.001,
    c1_max: typing.SupportsFloat | typing.SupportsIndex = 1.0,
    c2_min: typing.SupportsFloat | typing.SupportsIndex = 0.001,
    c2_max: typing.SupportsFloat | typing.SupportsIndex = 1.0,
    global_evaluations: typing.SupportsInt | typing.SupportsIndex = 200,
    local_evaluations: typing.SupportsInt | typing.SupportsIndex = 100,
    xtol_rel: typing.SupportsFloat | typing.SupportsIndex = 0.0001,
    ftol_abs: typing.SupportsFloat | typing.SupportsIndex = 1e-09,
    holdout_fraction: typing.SupportsFloat | typing.SupportsIndex = 0.3,
    seed: typing.SupportsInt | typing.SupportsIndex = 0,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> CalibrationResult:
    """
    Fit c1, c2 of the cup to measured outcomes (see mgn.calibration.fit).
    """

def camera_rays(
    K: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 3]"],
    width: typing.SupportsInt | typing.SupportsIndex,
    height: typing.SupportsInt | typing.SupportsIndex,
    X_WC: typing.Any,
) -> tuple[numpy.ndarray, numpy.ndarray]: ...
def classification_metrics(
    predicted: collections.abc.Sequence[bool], measured: collections.abc.Sequence[bool]
) -> ClassificationMetrics:
    """
    Confusion counts and PPV, NPV, sensitivity, specificity, accuracy (NaN for a zero denominator).
    """

def collide(
    a: CollisionModel,
    X_WA: typing.Any,
    b: CollisionModel,
    X_WB: typing.Any,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> numpy.ndarray: ...
def color_temperature_rgb(
    kelvin: typing.SupportsFloat | typing.SupportsIndex,
) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]: ...
def com_heatmap_prediction(
    depth_m: typing.Any,
    instances: typing.Any,
    X_WC: typing.Any,
    fx: typing.SupportsFloat | typing.SupportsIndex,
    fy: typing.SupportsFloat | typing.SupportsIndex,
    cx: typing.SupportsFloat | typing.SupportsIndex,
    cy: typing.SupportsFloat | typing.SupportsIndex,
    com_parameters: typing.Any,
) -> numpy.typing.NDArray[numpy.float32]:
    """
    (H, W) float32 CoM heat map predicted from the noise-free depth (m), see mgn/scene/view_labels.hpp and docs/format.md.
    """

def compute_layout(
    visible: typing.Any,
    amodal: typing.Any,
    depth: typing.Any,
    categories: typing.Any,
    occlusion: typing.Any,
    min_overlap_px: typing.SupportsInt | typing.SupportsIndex = 10,
    min_overlap_fraction: typing.SupportsFloat | typing.SupportsIndex = 0.1,
    min_region_px: typing.SupportsInt | typing.SupportsIndex = 10,
    min_region_fraction: typing.SupportsFloat | typing.SupportsIndex = 0.005,
    max_occlusion_level1: typing.SupportsFloat | typing.SupportsIndex = 0.05,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> LayoutArrays:
    """
    Layout labels of one view (see mgn/scene/layout.hpp); use mgn.view_labels.layout.compute_layout.
    """

def compute_mass_properties(
    mesh: Mesh,
    density: typing.SupportsFloat | typing.SupportsIndex = 1000.0,
    open_mesh: str = "shell",
    shell_thickness: typing.SupportsFloat | typing.SupportsIndex = 0.002,
) -> MassProperties: ...
def convex_decomposition(mesh: Mesh, options: ConvexDecompositionOptions = ...) -> list[Mesh]: ...
def convex_hull(mesh: Mesh) -> Mesh: ...
def develop_radiance(radiance: typing.Any, film: FilmOptions) -> numpy.ndarray: ...
def distance(
    a: CollisionModel,
    X_WA: typing.Any,
    b: CollisionModel,
    X_WB: typing.Any,
    rel_err: typing.SupportsFloat | typing.SupportsIndex = 0.0,
    abs_err: typing.SupportsFloat | typing.SupportsIndex = 0.0,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> DistanceResult: ...
def double_blocks(
    blocks: typing.Any,
    height: typing.SupportsInt | typing.SupportsIndex,
    width: typing.SupportsInt | typing.SupportsIndex,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> numpy.ndarray:
    """
    Bilinear doubling of a 2 x 2 block image to (height, width), block centres at the centres of their pixels, border blocks repeated.
    """

def drop_objects(
    parts: collections.abc.Sequence[collections.abc.Sequence[Mesh]],
    masses: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
    coms: typing.Any,
    inertias: typing.Any,
    frictions: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
    restitutions: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
    names: collections.abc.Sequence[str],
    tote: Mesh,
    tote_box: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
    options: DropOptions,
    X_WO_start: typing.Any = None,
) -> DropResult: ...
def gaussian_3x3(
    image: typing.Any,
    sigma: typing.SupportsFloat | typing.SupportsIndex = 0.5,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> numpy.ndarray:
    """
    Separable 3 x 3 Gaussian (sigma in pixels) of an (H, W, C) float32 image, border pixels repeated.
    """

def gripper_meshes(
    gripper: ParallelJawGripper, opening: typing.SupportsFloat | typing.SupportsIndex
) -> tuple[Mesh, Mesh, Mesh]:
    """
    (palm, finger_left, finger_right) closed meshes in the hand frame at an opening (m).
    """

def hand_poses(
    p1: typing.Any,
    closing: typing.Any,
    approach: typing.Any,
    width: typing.Any,
    gripper: ParallelJawGripper,
) -> numpy.ndarray:
    """
    (N,4,4) hand (flange) poses X_OH of grasps in the object frame.
    """

def hemisphere_rig(
    radii: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
    tilts: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
    azimuths: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
    target: typing.Any,
) -> numpy.ndarray: ...
def load_mesh(
    path: str,
    scale: typing.SupportsFloat | typing.SupportsIndex = 1.0,
    merge: bool = True,
    drop_degenerate: bool = True,
) -> Mesh: ...
def look_at(eye: typing.Any, target: typing.Any, up: typing.Any) -> numpy.ndarray: ...
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
def material_texture_rgb(material: Material) -> typing.Any:
    """
    The material's base colour texture decoded to (H, W, 3) uint8 sRGB (top row first), or None.
    """

def mesh_surface_flags(mesh: Mesh) -> int: ...
def mgn_rig(
    seed: typing.SupportsInt | typing.SupportsIndex, target: typing.Any
) -> tuple[numpy.ndarray, MgnRigParams]: ...
def mgn_rig_from_params(
    R_start: typing.SupportsFloat | typing.SupportsIndex,
    R_end: typing.SupportsFloat | typing.SupportsIndex,
    theta_start: typing.SupportsFloat | typing.SupportsIndex,
    theta_end: typing.SupportsFloat | typing.SupportsIndex,
    phi_end: typing.SupportsFloat | typing.SupportsIndex,
    target: typing.Any,
) -> numpy.ndarray: ...
def pj_wrench_scores(
    p1: typing.Any,
    closing: typing.Any,
    width: typing.Any,
    mass: typing.SupportsFloat | typing.SupportsIndex,
    com: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
    gravity_direction: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
    options: PjWrenchOptions = ...,
) -> numpy.ndarray: ...
def predict_experiments(
    surfaces: collections.abc.Sequence[Mesh],
    surface_index: typing.Any,
    points: typing.Any,
    normals: typing.Any,
    cup: Cup,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> numpy.ndarray:
    """
    Nominal spring-model seal prediction (bool per experiment) for a cup.
    """

def resolve_num_threads(requested: typing.SupportsInt | typing.SupportsIndex) -> int:
    """
    Thread count used for `requested` (0 = all hardware threads).
    """

def restore_half_resolution(
    denoised: typing.Any,
    height: typing.SupportsInt | typing.SupportsIndex,
    width: typing.SupportsInt | typing.SupportsIndex,
    albedo: typing.Any | None = None,
    albedo_blocks: typing.Any = None,
    normal: typing.Any = None,
    normal_blocks: typing.Any = None,
    albedo_floor: typing.SupportsFloat | typing.SupportsIndex = 0.019999999552965164,
    edge_cos_lo: typing.SupportsFloat | typing.SupportsIndex = 0.85,
    edge_cos_hi: typing.SupportsFloat | typing.SupportsIndex = 0.97,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> numpy.ndarray:
    """
    Full-size image of a half-resolution denoise: the denoised blocks doubled, times the albedo ratio max(a, floor) / max(double(albedo_blocks), floor) faded to 1 where the normal turns away from double(normal_blocks) (cosine edge_cos_lo..edge_cos_hi); clamped to >= 0.
    """

def sample_surface(
    mesh: Mesh,
    count: typing.SupportsInt | typing.SupportsIndex,
    method: str = "random",
    seed: typing.SupportsInt | typing.SupportsIndex = 0,
    oversampling: typing.SupportsInt | typing.SupportsIndex = 6,
) -> SurfaceSamples: ...
def shake_test(
    parts: collections.abc.Sequence[Mesh],
    mass: typing.SupportsFloat | typing.SupportsIndex,
    com: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
    inertia: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 3]"],
    grasps: typing.Any,
    gripper: ParallelJawGripper,
    options: ShakeOptions,
) -> ShakeResult:
    """
    Shake test of (N, 10) grasps [a, v, p1, w] (m); a ShakeResult (GIL released).
    """

def shake_trajectory(
    parts: collections.abc.Sequence[Mesh],
    mass: typing.SupportsFloat | typing.SupportsIndex,
    com: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
    inertia: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 3]"],
    grasp: typing.Any,
    gripper: ParallelJawGripper,
    friction: typing.SupportsFloat | typing.SupportsIndex,
    density_factor: typing.SupportsFloat | typing.SupportsIndex,
    options: ShakeOptions,
    record_every: typing.SupportsInt | typing.SupportsIndex = 5,
    trial_index: typing.SupportsInt | typing.SupportsIndex = 0,
) -> ShakeTrajectoryResult:
    """
    One recorded shake trial (poses in the world W: z up, gravity -z).
    """

def staircase_grid(
    S: typing.SupportsInt | typing.SupportsIndex,
    trial: collections.abc.Callable[[int, int], bool],
    checks: typing.SupportsInt | typing.SupportsIndex,
    verified_rows: typing.SupportsInt | typing.SupportsIndex = -1,
) -> StaircaseGridResult:
    """
    The staircase search of shake_test on an S x S grid: trial(i, j) -> bool is called for the cells it simulates (friction index i, density index j); the boundary is verified in rows i < verified_rows (-1: every row); a StaircaseGridResult.
    """

def suction_wrench_scores(
    contacts: typing.Any,
    approach: typing.Any,
    mass: typing.SupportsFloat | typing.SupportsIndex,
    com: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
    gravity_direction: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
    cup_radius: typing.SupportsFloat | typing.SupportsIndex,
    options: SuctionWrenchOptions = ...,
) -> numpy.ndarray: ...
def surface_flags(material: Material) -> int: ...

SEAL_FAILURE_NAMES: tuple = (
    "none",
    "miss",
    "obstruction",
    "hill",
    "hole",
    "force",
    "strain",
    "rough",
)
SUCTION_TOOL_OFFSET: float = 0.1321
SURFACE_DARK: int = 2
SURFACE_MIRROR: int = 4
SURFACE_TRANSPARENT: int = 1
__version__: str = "0.1.0"
