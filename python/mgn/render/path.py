"""Physically based path tracing on the CPU (typed façade over the C++ core, Embree).

A :class:`PathScene` is built once from meshes placed in the world frame W, one
:class:`PbrMaterial` per mesh material slot, area lights and an environment;
:meth:`PathScene.render` then renders any number of camera views and :func:`develop` turns the
linear radiance into an 8-bit sRGB picture.

Units and frames: metres, radians; poses are (4, 4) float64 ``X_AB`` (frame B in frame A); the
camera model is :class:`mgn.render.CameraView` (OpenCV frame, pixel (u, v) covers the square
[u, u+1) x [v, v+1) with its centre at (u + 0.5, v + 0.5)), so the depth and instance-id passes
equal the raster passes and :func:`mgn.camera_rays`.

Radiance convention: linear RGB radiance; an emitter of radiance L seen directly shows L, a white
Lambertian surface under irradiance E shows E / pi. Lights and the environment use the same units.

Algorithm (see ``cpp/include/mgn/render/path_tracer.hpp``): unidirectional path tracing with
next-event estimation and multiple importance sampling (power heuristic) for the area lights and
the environment, Russian roulette, glTF 2.0 metallic-roughness materials (Lambert + GGX with
height-correlated Smith masking, visible-normal sampling) and dielectrics (Fresnel,
refraction, total internal reflection; smooth below roughness ~0.055, GGX microfacet reflection
and refraction above; each refraction tints by sqrt(base colour), so a closed wall tints once),
emissive meshes sampled as lights, Owen-scrambled Sobol samples stratified across neighbouring
pixels (blue-noise error), seeded from (seed, view_index, pixel block): the image is identical
for any number of threads. Long calls release
the GIL.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.base.core_result import from_core, to_core
from mgn.errors import InvalidArgumentError, InvalidTypeError
from mgn.geometry import Material, Mesh
from mgn.scene.cameras import CameraView

__all__ = [
    "AreaLight",
    "Environment",
    "FilmOptions",
    "PathScene",
    "PathTraceOptions",
    "PathTraceOutput",
    "PbrMaterial",
    "develop",
]

Color = tuple[float, float, float]


def _color(value: Sequence[float], name: str) -> Color:
    a = np.asarray(value, dtype=np.float64)
    if a.shape != (3,):
        raise InvalidArgumentError(f"{name} must be 3 numbers (linear RGB), got shape {a.shape}")
    return (float(a[0]), float(a[1]), float(a[2]))


#: The C++ defaults of the tracer and the film (mgn/render/path_tracer.hpp): the one place they
#: are written.
_TRACE = _core.render.PathTraceOptions()
_FILM = _core.render.FilmOptions()


@dataclass(frozen=True)
class PbrMaterial:
    """glTF 2.0 metallic-roughness material (+ KHR_materials_transmission / ior).

    Attributes:
        base_color: linear RGB in [0, 1] (diffuse albedo of dielectrics, F0 of metals, tint of
            light transmitted through a closed wall: sqrt(base_color) per refraction).
        metallic: [0, 1].
        roughness: perceptual roughness in [0, 1]; GGX alpha = roughness ** 2.
        ior: index of refraction (>= 1) of the specular layer and of the dielectric; 1 removes
            the specular layer (a pure Lambertian surface when metallic = 0).
        transmission: [0, 1]; 1 = clear dielectric (glass, clear plastic): smooth when
            roughness < ~0.055, frosted (GGX microfacet refraction) above.
        emission: emitted radiance (front side), linear RGB >= 0, same units as the lights;
            faces with emission > 0 are sampled by next-event estimation like area lights.
        base_color_texture: (H, W, 3) uint8 sRGB image, top row first, multiplying base_color,
            looked up at the mesh uvs (u right, v up), bilinear, repeating; None = none.
    """

    base_color: Color = (0.8, 0.8, 0.8)
    metallic: float = 0.0
    roughness: float = 0.5
    ior: float = 1.5
    transmission: float = 0.0
    emission: Color = (0.0, 0.0, 0.0)
    base_color_texture: npt.NDArray[np.uint8] | None = field(
        default=None, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        object.__setattr__(self, "base_color", _color(self.base_color, "PbrMaterial.base_color"))
        object.__setattr__(self, "emission", _color(self.emission, "PbrMaterial.emission"))
        for name in ("metallic", "roughness", "ior", "transmission"):
            object.__setattr__(self, name, float(getattr(self, name)))
        if self.base_color_texture is not None:
            tex = np.ascontiguousarray(self.base_color_texture)
            if tex.dtype != np.uint8 or tex.ndim != 3 or tex.shape[2] != 3:
                raise InvalidArgumentError(
                    "PbrMaterial.base_color_texture must be an (H, W, 3) uint8 array, got "
                    f"{tex.dtype} {tex.shape}"
                )
            tex.setflags(write=False)
            object.__setattr__(self, "base_color_texture", tex)
        self.to_core().validate()  # InvalidArgumentError naming the setting

    def to_core(self) -> _core.render.PbrMaterial:
        m = _core.render.PbrMaterial()
        m.base_color = self.base_color
        m.metallic = self.metallic
        m.roughness = self.roughness
        m.ior = self.ior
        m.transmission = self.transmission
        m.emission = self.emission
        m.set_texture(self.base_color_texture)
        return m

    @staticmethod
    def from_material(m: Material) -> PbrMaterial:
        """A plausible PBR material for a legacy (Phong) mesh material.

        base colour = the material's RGB (and its texture); roughness from the Phong exponent n
        through the Beckmann correspondence alpha = sqrt(2 / (n + 2)), roughness = sqrt(alpha),
        clamped to [0.08, 1]; a mirror-like material (specular luminance >= 0.8 and n >= 200) is a
        metal with the specular colour as base colour; a transparent one (opacity < 1) becomes a
        clear dielectric (transmission = min(1, 2 (1 - opacity)), its tint moved 70 % towards
        white: a Phong colour describes the surface, clear plastic barely tints what is seen
        through it; roughness 0.05, a smooth dielectric).
        """
        base = np.clip(np.asarray(m.base_color, np.float64)[:3], 0.0, 1.0)
        spec = np.clip(np.asarray(m.specular, np.float64)[:3], 0.0, 1.0)
        n = max(float(m.shininess), 0.0)
        alpha = math.sqrt(2.0 / (n + 2.0))
        roughness = min(1.0, max(0.08, math.sqrt(alpha)))
        metallic = 0.0
        spec_lum = float(0.2126 * spec[0] + 0.7152 * spec[1] + 0.0722 * spec[2])
        if spec_lum >= 0.8 and n >= 200.0:
            metallic, base = 1.0, spec
        opacity = float(m.opacity) * float(np.asarray(m.base_color)[3])
        transmission = 0.0
        if opacity < 1.0:
            transmission = min(1.0, 2.0 * (1.0 - opacity))
            base = base + 0.7 * (1.0 - base)
            roughness = 0.05
        texture = _core.render.material_texture_rgb(m)
        return PbrMaterial(
            base_color=(float(base[0]), float(base[1]), float(base[2])),
            metallic=metallic,
            roughness=roughness,
            transmission=transmission,
            base_color_texture=texture,
        )


@dataclass(frozen=True)
class AreaLight:
    """One-sided area light emitting uniformly (Lambertian) towards +z of its frame L.

    Attributes:
        X_WL: (4, 4) pose of the light frame in the world (rigid).
        shape: "rect" | "disc".
        size: rect: full side lengths along x_L, y_L (m); disc: (radius, radius) (m).
        color: linear RGB >= 0.
        intensity: radiance scale (>= 0): the light's radiance is color * intensity.
    """

    X_WL: npt.NDArray[np.float64] = field(repr=False)
    shape: str = "rect"
    size: tuple[float, float] = (0.5, 0.5)
    color: Color = (1.0, 1.0, 1.0)
    intensity: float = 10.0

    def __post_init__(self) -> None:
        X = np.array(self.X_WL, dtype=np.float64)
        if X.shape != (4, 4):
            raise InvalidArgumentError(f"AreaLight.X_WL must be a (4, 4) pose, got shape {X.shape}")
        X.setflags(write=False)
        object.__setattr__(self, "X_WL", X)
        s = np.asarray(self.size, np.float64).reshape(-1)
        if s.shape != (2,):
            raise InvalidArgumentError(f"AreaLight.size must be 2 numbers (m), got shape {s.shape}")
        object.__setattr__(self, "size", (float(s[0]), float(s[1])))
        object.__setattr__(self, "color", _color(self.color, "AreaLight.color"))
        object.__setattr__(self, "intensity", float(self.intensity))
        self.to_core().validate()

    def to_core(self) -> _core.render.AreaLight:
        return to_core(self, _core.render.AreaLight())


@dataclass(frozen=True)
class Environment:
    """Infinitely distant dome seen by rays that escape; world +z is up.

    Attributes:
        kind: "uniform" (radiance ``color``) | "gradient" (``horizon`` to ``zenith`` linearly in
            sqrt(d.z) above the horizon, ``ground`` below) | "sky" (the gradient plus a sun disc
            of angular radius ``sun_angular_radius`` towards ``sun_direction`` whose irradiance
            at normal incidence is ``sun_strength`` * pi * luminance(zenith)).
        intensity: scales everything (>= 0).
    """

    kind: str = "uniform"
    color: Color = (1.0, 1.0, 1.0)
    zenith: Color = (0.6, 0.7, 0.9)
    horizon: Color = (0.9, 0.9, 0.9)
    ground: Color = (0.3, 0.3, 0.3)
    sun_direction: tuple[float, float, float] = (0.3, 0.2, 0.93)
    intensity: float = 1.0
    sun_strength: float = 3.0
    sun_angular_radius: float = 0.035

    def __post_init__(self) -> None:
        for name in ("color", "zenith", "horizon", "ground", "sun_direction"):
            object.__setattr__(self, name, _color(getattr(self, name), f"Environment.{name}"))
        for name in ("intensity", "sun_strength", "sun_angular_radius"):
            object.__setattr__(self, name, float(getattr(self, name)))
        self.to_core().validate()

    def to_core(self) -> _core.render.Environment:
        return to_core(self, _core.render.Environment())


@dataclass(frozen=True)
class PathTraceOptions:
    """Settings of one path-traced view.

    Attributes:
        spp: samples per pixel (>= 1).
        max_bounces: path segments after the camera ray (>= 0; 0 = directly seen emission only,
            1 = direct lighting only).
        seed, view_index: the sample streams derive from (seed, view_index, pixel).
        num_threads: 0 = all hardware threads; the image is identical for any value.
        rr_depth: Russian roulette from this bounce on (>= 0); vertices at smooth glass (a
            delta reflection or refraction) are not counted. Default 2 (docs/rendering.md,
            "Russian roulette's depth").
        aperture_radius: thin-lens aperture radius, m (0 = pinhole).
        focus_distance: distance in focus along the optical axis, m (0 = the depth at the image
            centre, or 1 m if nothing is seen there).
        clamp: maximum luminance of one sample (0 = off; > 0 biases but removes fireflies).
        clamp_indirect: maximum luminance of one indirect contribution of a sample (light found
            at the second path vertex or later) (0 = off). The default 10 leaves ordinary
            indirect light alone and removes the fireflies of caustics (diffuse -> glass -> sun)
            at the cost of dimming those caustics.
        fresnel_split_min: after the first glass walls (whose reflected and refracted branches
            are both traced in full), both directions of a smooth dielectric meet their first
            light (Fresnel splitting) only while the path's throughput (largest channel) is at
            least this (>= 0; 0 = always); dimmer paths follow their random direction alone
            (unbiased, one ray fewer per such glass vertex).
        guide_split_min: the denoiser guides of the other direction at a split smooth dielectric
            are followed behind further glass only when its share of the pixel's guide is at
            least this (>= 0; 0 = always); guides only, the radiance is unchanged.
        shadow_rays: shadow rays per path vertex (1 or 2). 2: one to a light (area light or
            emissive triangle) and one to the environment; 1: one, to either of the two (each
            with probability 1/2 when the scene has both).
        sample_sky_dome: next-event estimation of the environment's dome (all of it but the
            sun): True, a shadow ray per vertex towards it; False, the dome is found by the
            BSDF-sampled ray that continues the path, and shadow rays aim at the sun only.
        reduced_nee_depth: path vertices from this depth on (0 = the camera ray's hit, 1 = the
            first bounce's hit, ...) follow ``shadow_rays`` and ``sample_sky_dome``; the
            vertices before it cast both shadow rays.
        labels: also make the label images (``depth`` and ``instance_ids`` of the output: one
            coherent packet of pinhole rays through the pixel centres per tile row); False skips
            those rays and leaves both images 0 (the dataset pipeline labels its views from the
            ray-cast label pass and keeps only the photograph).
        adaptive_samples: adaptive sampling, extra samples per pixel on average (>= 0; 0 =
            off) traced after the ``spp`` samples of every pixel where that first pass looks
            noisiest (docs/rendering.md, "Adaptive sampling"); the image stays identical for
            any ``num_threads``.
        adaptive_max: at most this many extra samples in one pixel (1..64).
    """

    spp: int = _TRACE.spp
    max_bounces: int = _TRACE.max_bounces
    seed: int = _TRACE.seed
    view_index: int = _TRACE.view_index
    num_threads: int = _TRACE.num_threads
    rr_depth: int = _TRACE.rr_depth
    aperture_radius: float = _TRACE.aperture_radius
    focus_distance: float = _TRACE.focus_distance
    clamp: float = _TRACE.clamp
    clamp_indirect: float = _TRACE.clamp_indirect
    fresnel_split_min: float = _TRACE.fresnel_split_min
    guide_split_min: float = _TRACE.guide_split_min
    shadow_rays: int = _TRACE.shadow_rays
    sample_sky_dome: bool = _TRACE.sample_sky_dome
    reduced_nee_depth: int = _TRACE.reduced_nee_depth
    labels: bool = _TRACE.labels
    adaptive_samples: float = _TRACE.adaptive_samples
    adaptive_max: int = _TRACE.adaptive_max

    def __post_init__(self) -> None:
        for name in (
            "spp",
            "max_bounces",
            "seed",
            "view_index",
            "num_threads",
            "rr_depth",
            "shadow_rays",
            "reduced_nee_depth",
            "adaptive_max",
        ):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise InvalidArgumentError(
                    f"PathTraceOptions.{name} must be an integer, got {value!r}"
                )
        for name in ("seed", "view_index"):
            if getattr(self, name) < 0:
                raise InvalidArgumentError(
                    f"PathTraceOptions.{name} must be >= 0, got {getattr(self, name)}"
                )
        self.to_core().validate()

    def to_core(self) -> _core.render.PathTraceOptions:
        o = _core.render.PathTraceOptions()
        o.spp = max(-(2**31), min(2**31 - 1, int(self.spp)))
        o.max_bounces = max(-(2**31), min(2**31 - 1, int(self.max_bounces)))
        o.seed = int(self.seed) & (2**64 - 1)
        o.view_index = int(self.view_index) & (2**64 - 1)
        o.num_threads = max(-(2**31), min(2**31 - 1, int(self.num_threads)))
        o.rr_depth = max(-(2**31), min(2**31 - 1, int(self.rr_depth)))
        o.aperture_radius = float(self.aperture_radius)
        o.focus_distance = float(self.focus_distance)
        o.clamp = float(self.clamp)
        o.clamp_indirect = float(self.clamp_indirect)
        o.fresnel_split_min = float(self.fresnel_split_min)
        o.guide_split_min = float(self.guide_split_min)
        o.shadow_rays = max(-(2**31), min(2**31 - 1, int(self.shadow_rays)))
        o.sample_sky_dome = bool(self.sample_sky_dome)
        o.reduced_nee_depth = max(-(2**31), min(2**31 - 1, int(self.reduced_nee_depth)))
        o.labels = bool(self.labels)
        o.adaptive_samples = float(self.adaptive_samples)
        o.adaptive_max = max(-(2**31), min(2**31 - 1, int(self.adaptive_max)))
        return o


@dataclass(frozen=True)
class FilmOptions:
    """Development of linear radiance into 8-bit sRGB.

    The exposed value is x = radiance * 2 ** exposure. Sensor noise (optional) is added to x:
    x + shot_noise * sqrt(x) * N1 + read_noise * N2 (N1, N2 standard normal per pixel and
    channel, drawn from (seed, view_index, pixel)). Tone "filmic" maps each channel through
    y = 1 - exp(-x) (an exponential film response: about linear in the shadows, a soft shoulder,
    never clipping; mid grey 0.18 -> 0.165); "linear" clips to [0, 1]. Then the sRGB OETF.
    """

    exposure: float = _FILM.exposure
    tone: str = _FILM.tone
    shot_noise: float = _FILM.shot_noise
    read_noise: float = _FILM.read_noise
    seed: int = _FILM.seed
    view_index: int = _FILM.view_index
    num_threads: int = _FILM.num_threads

    def __post_init__(self) -> None:
        for name in ("seed", "view_index"):
            if int(getattr(self, name)) < 0:
                raise InvalidArgumentError(
                    f"FilmOptions.{name} must be >= 0, got {getattr(self, name)}"
                )
        self.to_core().validate()

    def to_core(self) -> _core.render.FilmOptions:
        f = _core.render.FilmOptions()
        f.exposure = float(self.exposure)
        f.tone = self.tone
        f.shot_noise = float(self.shot_noise)
        f.read_noise = float(self.read_noise)
        f.seed = int(self.seed) & (2**64 - 1)
        f.view_index = int(self.view_index) & (2**64 - 1)
        f.num_threads = int(self.num_threads)
        return f


@dataclass(frozen=True)
class PathTraceOutput:
    """Images of one path-traced view (top row first).

    Attributes:
        radiance: (H, W, 3) float32 linear RGB, mean over the samples (before exposure).
        albedo: (H, W, 3) float32 mean first-hit base colour (denoiser auxiliary; the clipped
            environment radiance where nothing is hit).
        normal: (H, W, 3) float32 unit mean first-hit shading normal, world frame, facing the
            camera (0 where nothing is hit).
        depth: (H, W) float32 z-depth in m of the hit through the pixel centre, 0 = none.
        instance_ids: (H, W) int32 instance id hit through the pixel centre, 0 = background.
        rays: number of rays cast (camera, bounce and shadow rays).
    """

    radiance: npt.NDArray[np.float32]
    albedo: npt.NDArray[np.float32]
    normal: npt.NDArray[np.float32]
    depth: npt.NDArray[np.float32]
    instance_ids: npt.NDArray[np.int32]
    rays: int = 0


class PathScene:
    """Immutable path-traced scene, built once (Embree geometry shared with the ray scene's
    loader, per-corner shading normals), then rendered for any number of views.

    Args:
        meshes: the meshes (copied at construction).
        poses: (N, 4, 4) float64 poses X_WO of the meshes in the world.
        instance_ids: per mesh, the id reported in the instance pass (>= 0; 0 = background).
        materials: per mesh, one :class:`PbrMaterial` per mesh material slot
            (``max(1, len(mesh.materials))`` entries; face f uses slot ``mesh.face_materials[f]``).
        lights: area lights.
        environment: the dome.

    Raises:
        InvalidArgumentError: mismatched lengths, bad pose, negative id, wrong material count,
            an invalid material, light or environment (the message names the setting).
    """

    def __init__(
        self,
        meshes: Sequence[Mesh],
        poses: npt.ArrayLike,
        instance_ids: Sequence[int],
        materials: Sequence[Sequence[PbrMaterial]],
        lights: Sequence[AreaLight] = (),
        environment: Environment | None = None,
    ) -> None:
        env = environment if environment is not None else Environment()
        mesh_list = list(meshes)
        P = np.asarray(poses, dtype=np.float64)
        if len(mesh_list) == 0:
            P = np.zeros((0, 4, 4))
        mats = [[_as_material(m, i, k) for k, m in enumerate(ms)] for i, ms in enumerate(materials)]
        self._lights = tuple(lights)
        self._environment = env
        self._scene = _core.render.PathScene(
            mesh_list,
            P,
            [int(i) for i in instance_ids],
            [[m.to_core() for m in ms] for ms in mats],
            [_as_light(a, i).to_core() for i, a in enumerate(self._lights)],
            env.to_core(),
        )

    @classmethod
    def _wrap(
        cls, scene: _core.render.PathScene, lights: tuple[AreaLight, ...], env: Environment
    ) -> PathScene:
        self = cls.__new__(cls)
        self._scene = scene
        self._lights = lights
        self._environment = env
        return self

    @property
    def lights(self) -> tuple[AreaLight, ...]:
        return self._lights

    @property
    def environment(self) -> Environment:
        return self._environment

    @property
    def num_triangles(self) -> int:
        return int(self._scene.num_triangles)

    def with_lighting(
        self, lights: Sequence[AreaLight], environment: Environment | None = None
    ) -> PathScene:
        """A scene sharing this one's geometry (no copy, cheap) with other lights and
        environment (default: the uniform default environment)."""
        env = environment if environment is not None else Environment()
        lights_t = tuple(lights)
        core = self._scene.with_lighting(
            [_as_light(a, i).to_core() for i, a in enumerate(lights_t)], env.to_core()
        )
        return PathScene._wrap(core, lights_t, env)

    def render(self, view: CameraView, options: PathTraceOptions | None = None) -> PathTraceOutput:
        """Path-trace one view (GIL released; ``options.num_threads`` threads)."""
        opts = options if options is not None else PathTraceOptions()
        if not isinstance(view, CameraView):
            raise InvalidTypeError(f"view must be a CameraView, got {type(view).__name__}")
        if view.K.distortion:
            raise InvalidArgumentError(
                f"PathScene.render traces pinhole images; the camera has distortion "
                f"{list(view.K.distortion)}: render it with mgn.render.iter_views (which resamples "
                "through the lens) or trace lens_for(K).render_K (mgn.scene.lens)"
            )
        d = self._scene.render(view.K.to_core(), view.X_WC, opts.to_core())
        return from_core(PathTraceOutput, d, rays=int(d.rays))


def _as_material(m: object, i: int, k: int) -> PbrMaterial:
    if not isinstance(m, PbrMaterial):
        raise InvalidTypeError(
            f"PathScene: materials[{i}][{k}] must be a PbrMaterial, got {type(m).__name__}"
        )
    return m


def _as_light(a: object, i: int) -> AreaLight:
    if not isinstance(a, AreaLight):
        raise InvalidTypeError(
            f"PathScene: lights[{i}] must be an AreaLight, got {type(a).__name__}"
        )
    return a


def develop(radiance: npt.ArrayLike, film: FilmOptions | None = None) -> npt.NDArray[np.uint8]:
    """(H, W, 3) linear radiance -> (H, W, 3) uint8 sRGB (see :class:`FilmOptions`).

    Non-finite values become 0. Deterministic for any ``film.num_threads``.
    """
    f = film if film is not None else FilmOptions()
    a = np.ascontiguousarray(radiance, dtype=np.float32)
    return _core.render.develop_radiance(a, f.to_core())
