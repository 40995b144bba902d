"""
mgn/render: cameras, rasteriser, depth sensors, path tracer.
"""

from __future__ import annotations

import collections.abc
import typing

import numpy
import numpy.typing

import mgn._core.geometry

__all__: list[str] = [
    "SURFACE_DARK",
    "SURFACE_MIRROR",
    "SURFACE_TRANSPARENT",
    "AreaLight",
    "DepthSensorParams",
    "DepthSensorPreset",
    "DepthSensorResult",
    "Environment",
    "FilmOptions",
    "Intrinsics",
    "LightSample",
    "MgnRigParams",
    "PathScene",
    "PathTraceOptions",
    "PathTraceResult",
    "PbrMaterial",
    "RenderOptions",
    "RenderResult",
    "Renderer",
    "apply_depth_sensor",
    "block_means_2x2",
    "color_temperature_rgb",
    "develop_radiance",
    "double_blocks",
    "gaussian_3x3",
    "hemisphere_rig",
    "look_at",
    "material_texture_rgb",
    "mesh_surface_flags",
    "mgn_rig",
    "mgn_rig_from_params",
    "restore_half_resolution",
    "surface_flags",
]

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
    def add_mesh(self, mesh: mgn._core.geometry.Mesh) -> int: ...
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
        meshes: collections.abc.Sequence[mgn._core.geometry.Mesh],
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

def color_temperature_rgb(
    kelvin: typing.SupportsFloat | typing.SupportsIndex,
) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]: ...
def develop_radiance(radiance: typing.Any, film: FilmOptions) -> numpy.ndarray: ...
def double_blocks(
    blocks: typing.Any,
    height: typing.SupportsInt | typing.SupportsIndex,
    width: typing.SupportsInt | typing.SupportsIndex,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> numpy.ndarray:
    """
    Bilinear doubling of a 2 x 2 block image to (height, width), block centres at the centres of their pixels, border blocks repeated.
    """

def gaussian_3x3(
    image: typing.Any,
    sigma: typing.SupportsFloat | typing.SupportsIndex = 0.5,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> numpy.ndarray:
    """
    Separable 3 x 3 Gaussian (sigma in pixels) of an (H, W, C) float32 image, border pixels repeated.
    """

def hemisphere_rig(
    radii: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
    tilts: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
    azimuths: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
    target: typing.Any,
) -> numpy.ndarray: ...
def look_at(eye: typing.Any, target: typing.Any, up: typing.Any) -> numpy.ndarray: ...
def material_texture_rgb(material: mgn._core.geometry.Material) -> typing.Any:
    """
    The material's base colour texture decoded to (H, W, 3) uint8 sRGB (top row first), or None.
    """

def mesh_surface_flags(mesh: mgn._core.geometry.Mesh) -> int: ...
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

def surface_flags(material: mgn._core.geometry.Material) -> int: ...

SURFACE_DARK: int = 2
SURFACE_MIRROR: int = 4
SURFACE_TRANSPARENT: int = 1
