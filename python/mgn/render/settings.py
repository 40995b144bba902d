"""How the RGB image of a view is made (config section ``render``): the engine, its samples,
denoiser, film and sensor options (:class:`RenderSettings`) and the switches and ranges of the
per-view domain randomisation of the path-traced photographs (:class:`RandomizeSettings`).

Two engines make the ``{v}_rgb.png`` of a view (:data:`ENGINES`): ``raster``, the OpenGL
(OSMesa) preview of :class:`mgn.render.Renderer`, and ``path``, the path-traced photograph of
:class:`mgn.render.photo.PhotoRenderer`. Every value is checked when the settings are made, with a
message naming the field.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mgn.errors import InvalidArgumentError
from mgn.render.denoiser import (
    DENOISE_GUIDES,
    DENOISE_QUALITIES,
    DENOISE_RESOLUTIONS,
    denoiser_available,
)

__all__ = [
    "ENGINES",
    "TONES",
    "RandomizeSettings",
    "RenderSettings",
    "replace_settings",
    "with_engine",
]

#: Render engines of ``render.engine`` / ``--engine``.
ENGINES = ("raster", "path")
#: Tone curves of ``render.tone``.
TONES = ("filmic", "linear")


def _range(value: Any, name: str, lo: float, hi: float | None = None) -> tuple[float, float]:
    a = np.asarray(value, np.float64).reshape(-1)
    ok = a.shape == (2,) and np.all(np.isfinite(a)) and a[0] <= a[1] and a[0] >= lo
    ok = ok and (hi is None or a[1] <= hi)
    if not ok:
        bound = f"{lo:g} <= min <= max" + (f" <= {hi:g}" if hi is not None else "")
        raise InvalidArgumentError(f"{name} must be [min, max] with {bound}, got {value!r}")
    return (float(a[0]), float(a[1]))


@dataclass(frozen=True)
class RandomizeSettings:
    """Per-view domain randomisation of the path-traced photographs (each part switchable).

    The raster preview keeps its own simpler randomisation (light position and tote / floor
    colour). Everything is drawn from (seed, view index).

    Attributes:
        lights: number, size, position, colour temperature and intensity of the area lights.
        environment: kind (uniform / gradient / sky) and intensity of the environment.
        materials: tote and floor colour, roughness and procedural texture.
        exposure: exposure jitter of +- ``exposure_range`` EV.
        light_count: (min, max) area lights per view.
        light_size: (min, max) side of a rectangular light, m.
        light_height: (min, max) height of a light above the tote floor, m.
        light_offset: largest horizontal distance of a light from the tote centre, m.
        light_irradiance: (min, max) irradiance the lights together cast on the tote floor's
            centre (radiance units x sr; a white matte floor then shows irradiance / pi): the
            brightness of the scene, independent of the number, size and distance of the lights.
        light_temperature: (min, max) colour temperature, K.
        environment_intensity: (min, max) radiance scale of the environment.
        exposure_range: EV, the half width of the exposure jitter.
        object_appearance: object appearance (default off): in each view each object, with
            probability ``object_probability``, gets new materials, drawn per material slot:
            a colour of any hue (sRGB HSV: hue uniform in [0, 1), saturation and value
            uniform in ``object_saturation`` and ``object_value``, so black, dark grey and
            white occur), a roughness uniform in ``object_roughness``, metallic 0 (painted or
            coated metal is a dielectric), and a pattern in place of the slot's own texture:
            plain (the one colour), value noise, checker or stripes (equally likely;
            :func:`mgn.render.materials.procedural_pattern`) between that colour and a
            second one drawn alike (:func:`mgn.render.materials.two_colour_texture`; repeated
            every 6 cm on an object without its own uvs). Slots with transmission > 0 (glass,
            clear plastic) are kept as they are. Drawn from a stream per object (seed, view,
            object id): the lights, environment, tote, floor and exposure of the view are
            unchanged.
        object_probability: [0, 1], the probability that an object's materials are replaced
            in a view (default 0.5).
        object_saturation: (min, max) within [0, 1], sRGB HSV saturation of a replaced colour
            (default (0, 1)).
        object_value: (min, max) within [0, 1], sRGB HSV value of a replaced colour (default
            (0.05, 0.95): 0.05 is a reflectance of 0.4 %, 0.95 of 89 %).
        object_roughness: (min, max) within [0, 1], perceptual roughness of a replaced
            material (default (0.15, 0.9)).
        camera_light: a light at the camera (default off), as a 3D camera's projector or a
            ring light gives: in a view, with probability ``camera_light_probability``, one
            more square area light of side ``camera_light_size`` in the camera's image plane,
            ``camera_light_offset`` from the optical centre in a random direction, facing
            along the viewing direction, white (6500 K), casting ``camera_light_irradiance``
            on the tote floor's centre. Drawn from its own stream (seed, view): the other
            lights, environment, materials and exposure are unchanged (the lights and the
            environment scaled by ``camera_light_ambient`` only).
        camera_light_probability: [0, 1], the probability of the camera light in a view
            (default 0.5).
        camera_light_size: (min, max) side of the camera light, m (default (0.02, 0.1)).
        camera_light_offset: (min, max) distance of the camera light from the optical
            centre, m (default (0.03, 0.15)).
        camera_light_irradiance: (min, max) irradiance the camera light casts on the tote
            floor's centre, in the units of ``light_irradiance`` (default (1, 6)).
        camera_light_ambient: (min, max) within [0, 1], the factor the other lights and the
            environment are scaled by in a view that has the camera light (default (1, 1):
            unchanged). Near 0 gives the colour image of a structured-light 3D camera in a
            dark cell, lit by its own projector only: every object casts a sharp black
            shadow on the side away from the projector (with a small ``camera_light_size``
            and the projector's baseline as ``camera_light_offset``).
    """

    lights: bool = True
    environment: bool = True
    materials: bool = True
    exposure: bool = True
    light_count: tuple[int, int] = (1, 3)
    light_size: tuple[float, float] = (0.4, 1.2)
    light_height: tuple[float, float] = (1.2, 2.2)
    light_offset: float = 1.0
    light_irradiance: tuple[float, float] = (3.0, 9.0)
    light_temperature: tuple[float, float] = (3500.0, 7500.0)
    environment_intensity: tuple[float, float] = (0.2, 0.8)
    exposure_range: float = 0.5
    object_appearance: bool = False
    object_probability: float = 0.5
    object_saturation: tuple[float, float] = (0.0, 1.0)
    object_value: tuple[float, float] = (0.05, 0.95)
    object_roughness: tuple[float, float] = (0.15, 0.9)
    camera_light: bool = False
    camera_light_probability: float = 0.5
    camera_light_size: tuple[float, float] = (0.02, 0.1)
    camera_light_offset: tuple[float, float] = (0.03, 0.15)
    camera_light_irradiance: tuple[float, float] = (1.0, 6.0)
    camera_light_ambient: tuple[float, float] = (1.0, 1.0)

    def __post_init__(self) -> None:
        for key in (
            "lights",
            "environment",
            "materials",
            "exposure",
            "object_appearance",
            "camera_light",
        ):
            if not isinstance(getattr(self, key), bool):
                raise InvalidArgumentError(
                    f"RandomizeSettings.{key} must be true or false, got {getattr(self, key)!r}"
                )
        c = np.asarray(self.light_count).reshape(-1)
        if c.shape != (2,) or not all(float(x).is_integer() for x in c) or not 1 <= c[0] <= c[1]:
            raise InvalidArgumentError(
                "RandomizeSettings.light_count must be [min, max] integers with "
                f"1 <= min <= max, got {self.light_count!r}"
            )
        object.__setattr__(self, "light_count", (int(c[0]), int(c[1])))
        for key, lo, hi in (
            ("light_size", 1e-3, None),
            ("light_height", 0.1, None),
            ("light_irradiance", 0.0, None),
            ("light_temperature", 1000.0, 40000.0),
            ("environment_intensity", 0.0, None),
            ("object_saturation", 0.0, 1.0),
            ("object_value", 0.0, 1.0),
            ("object_roughness", 0.0, 1.0),
            ("camera_light_size", 1e-3, None),
            ("camera_light_offset", 0.0, None),
            ("camera_light_irradiance", 0.0, None),
            ("camera_light_ambient", 0.0, 1.0),
        ):
            rng = _range(getattr(self, key), f"RandomizeSettings.{key}", lo, hi)
            object.__setattr__(self, key, rng)
        for key in ("light_offset", "exposure_range"):
            v = getattr(self, key)
            if isinstance(v, bool) or not (math.isfinite(float(v)) and float(v) >= 0):
                raise InvalidArgumentError(f"RandomizeSettings.{key} must be >= 0, got {v!r}")
            object.__setattr__(self, key, float(v))
        for key in ("object_probability", "camera_light_probability"):
            p = getattr(self, key)
            ok = not isinstance(p, bool) and isinstance(p, (int, float)) and 0.0 <= p <= 1.0
            if not ok:
                raise InvalidArgumentError(
                    f"RandomizeSettings.{key} must be a number in [0, 1], got {p!r}"
                )
            object.__setattr__(self, key, float(p))


@dataclass(frozen=True)
class RenderSettings:
    """How the RGB image of a view is made (config section ``render``).

    Attributes:
        engine: ``raster`` (OpenGL preview) or ``path`` (physically based path tracer).
        spp: path samples per pixel with the denoiser (default 1: the lowest image error
            per CPU-second among 1, 2 and 4 samples with OIDN ``fast``;
            docs/decisions/0031-path-default-spp.md). Without the denoiser see
            ``spp_without_denoiser``.
        denoise: denoise with Intel Open Image Denoise (``pyoidn``). Without pyoidn installed
            a warning names the package and ``spp_without_denoiser`` samples are traced instead.
        spp_without_denoiser: samples per pixel when ``denoise`` is false or pyoidn is missing.
        denoise_quality: OIDN filter quality, ``fast`` (default), ``balanced`` or ``high``.
            On the CPU ``fast`` takes about half the time of ``high`` (1200x1200: ~2.4 vs ~4.6
            CPU-s) and is the better use of the time: at equal CPU time, more samples with
            ``fast`` give a lower image error than fewer with ``high``
            (docs/decisions/0027-denoiser-settings.md); ``balanced`` costs as much as ``high``.
        denoise_guides: the guide images OIDN gets with the radiance. ``smoothed`` (default):
            the tracer's albedo and normal, each blurred by a 3 x 3 Gaussian (sigma 0.5 px) and
            declared noise-free to OIDN (its ``cleanAux`` mode); ``raw``: both as traced,
            declared noisy; ``albedo``: the albedo alone, as traced (~0.15 CPU-s less per
            1200 x 1200 view); ``none``: the colour alone (blurs printed text). On five windows
            of the benchmark view ``smoothed`` scores better than ``raw`` on all of them at the
            same cost (docs/decisions/0027-denoiser-settings.md; docs/rendering.md).
        denoise_resolution: where OIDN runs. ``half`` (default): on 2 x 2 pixel blocks (the
            radiance and guides averaged, so at 1 spp each denoised pixel holds four samples),
            at a quarter of the cost; the result is brought back to full size by bilinear
            interpolation and multiplied by the ratio of the full-size to the block albedo, so
            print and texture keep their full-size detail. ``full``: on every pixel. On three
            windows of the benchmark view at 1 spp, ``half`` has the lower image error (FLIP
            0.097 against 0.106) for 0.57 instead of 2.0 CPU-s per 1200 x 1200 view
            (docs/decisions/0036-denoise-at-half-resolution.md).
        adaptive_samples: adaptive sampling: extra path samples per pixel on average (0 = off)
            traced after the ``spp`` samples of every pixel where that first pass looks
            noisiest (glass, indirectly lit walls), at most ``adaptive_max`` per pixel
            (docs/rendering.md, "Adaptive sampling"). The view then costs about
            spp + 2 x adaptive_samples samples (the noisy pixels are the expensive ones).
        adaptive_max: at most this many extra samples in one pixel (1..64).
        max_bounces: path segments after the camera ray.
        clamp: firefly clamp, the largest luminance of one sample (0 = off).
        exposure: EV added to the developed image.
        tone: ``filmic`` (soft shoulder, never clips) or ``linear`` (clip).
        aperture_radius: thin-lens aperture radius, m (0 = pinhole, everything sharp; 0.002
            gives a slight defocus away from the focus distance, the depth at the image centre).
        shot_noise: sensor shot noise (std sqrt(x) * shot_noise at exposed value x).
        read_noise: sensor read noise (additive std, linear units).
        randomize: :class:`RandomizeSettings` (used when the scene's randomisation is on).
    """

    engine: str = "raster"
    spp: int = 1
    denoise: bool = True
    spp_without_denoiser: int = 128
    denoise_quality: str = "fast"
    denoise_guides: str = "smoothed"
    denoise_resolution: str = "half"
    adaptive_samples: float = 0.0
    adaptive_max: int = 3
    max_bounces: int = 6
    clamp: float = 20.0
    exposure: float = 0.0
    tone: str = "filmic"
    aperture_radius: float = 0.0
    shot_noise: float = 0.0
    read_noise: float = 0.0
    randomize: RandomizeSettings = field(default_factory=RandomizeSettings)

    def __post_init__(self) -> None:
        if self.engine not in ENGINES:
            raise InvalidArgumentError(
                f"RenderSettings.engine must be one of {', '.join(ENGINES)}, got {self.engine!r}"
            )
        if self.denoise_quality not in DENOISE_QUALITIES:
            raise InvalidArgumentError(
                "RenderSettings.denoise_quality must be one of "
                f"{', '.join(DENOISE_QUALITIES)}, got {self.denoise_quality!r}"
            )
        if self.denoise_guides not in DENOISE_GUIDES:
            raise InvalidArgumentError(
                "RenderSettings.denoise_guides must be one of "
                f"{', '.join(DENOISE_GUIDES)}, got {self.denoise_guides!r}"
            )
        if self.denoise_resolution not in DENOISE_RESOLUTIONS:
            raise InvalidArgumentError(
                "RenderSettings.denoise_resolution must be one of "
                f"{', '.join(DENOISE_RESOLUTIONS)}, got {self.denoise_resolution!r}"
            )
        if self.tone not in TONES:
            raise InvalidArgumentError(
                f"RenderSettings.tone must be one of {', '.join(TONES)}, got {self.tone!r}"
            )
        for key, low in (
            ("spp", 1),
            ("spp_without_denoiser", 1),
            ("max_bounces", 0),
            ("adaptive_max", 1),
        ):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < low:
                raise InvalidArgumentError(
                    f"RenderSettings.{key} must be an integer >= {low}, got {v!r}"
                )
        if self.adaptive_max > 64:
            raise InvalidArgumentError(
                "RenderSettings.adaptive_max must be an integer in [1, 64], got "
                f"{self.adaptive_max!r}"
            )
        if not isinstance(self.denoise, bool):
            raise InvalidArgumentError(
                f"RenderSettings.denoise must be true or false, got {self.denoise!r}"
            )
        bounds: tuple[tuple[str, float | None], ...] = (
            ("clamp", 0.0),
            ("aperture_radius", 0.0),
            ("shot_noise", 0.0),
            ("read_noise", 0.0),
            ("exposure", None),
            ("adaptive_samples", 0.0),
        )
        for key, lo in bounds:
            v = getattr(self, key)
            ok = not isinstance(v, bool) and isinstance(v, (int, float)) and math.isfinite(v)
            if not ok or (lo is not None and v < lo):
                bound = "" if lo is None else f" >= {lo:g}"
                raise InvalidArgumentError(
                    f"RenderSettings.{key} must be a finite number{bound}, got {v!r}"
                )
            object.__setattr__(self, key, float(v))
        if not isinstance(self.randomize, RandomizeSettings):
            raise InvalidArgumentError("RenderSettings.randomize must be a RandomizeSettings")

    def describe(self, denoised: bool | None = None) -> dict[str, Any]:
        """What made the images, as recorded in scene manifests: ``engine``, and for ``path``
        ``spp`` (as traced) and ``denoised`` (default: whether the denoiser is available)."""
        if self.engine == "raster":
            return {"engine": "raster"}
        d = self.denoise and denoiser_available() if denoised is None else denoised
        return {
            "engine": "path",
            "spp": self.spp if d else self.spp_without_denoiser,
            "denoised": bool(d),
            "max_bounces": self.max_bounces,
        }


def replace_settings(settings: RenderSettings, **changes: Any) -> RenderSettings:
    """``settings`` with fields changed (e.g. ``engine`` from a ``--engine`` flag)."""
    return dataclasses.replace(settings, **changes)


def with_engine(
    settings: RenderSettings, engine: str | None = None, spp: int | None = None
) -> RenderSettings:
    """``settings`` with the engine and the samples per pixel overridden where given (the
    ``--engine`` / ``--spp`` flags of the commands). A new ``spp`` scales
    ``spp_without_denoiser`` alike (never below ``spp``). InvalidArgumentError naming ``--spp``
    for a value < 1."""
    changes: dict[str, Any] = {}
    if engine is not None:
        changes["engine"] = engine
    if spp is not None:
        if spp < 1:
            raise InvalidArgumentError(f"--spp must be >= 1, got {spp}")
        changes["spp"] = spp
        changes["spp_without_denoiser"] = max(
            spp, settings.spp_without_denoiser * spp // max(settings.spp, 1)
        )
    return dataclasses.replace(settings, **changes) if changes else settings
