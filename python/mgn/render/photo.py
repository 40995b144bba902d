"""Photographs of a scene: the render engine choice, path-traced RGB, denoising and the domain
randomisation of lights, environment, tote / floor materials and exposure.

Two engines make the ``{v}_rgb.png`` of a view (:class:`RenderSettings`, config section
``render``):

- ``raster``: the OpenGL (OSMesa) Blinn-Phong preview of :class:`mgn.render.Renderer`; fast.
- ``path``: the physically based path tracer :mod:`mgn.render.path` (glTF metallic-roughness
  materials, glass, area lights, an environment dome), denoised with Intel Open Image Denoise
  (the optional ``pyoidn`` package) and developed with exposure, a filmic curve and optional
  sensor noise.

Labels never depend on the engine: depth, instance ids and every mask come from the raster's
geometry passes, which the path tracer matches pixel for pixel (same meshes, camera model and
pixel centres; ``tests/python/test_photo.py`` checks >= 99.9 % agreement).

Domain randomisation (each switchable, :class:`RandomizeSettings`) is drawn from the stream
(seed, view index) only, so a view looks the same whatever the number of threads or workers and
whichever other views are rendered: 1-3 rectangular area lights above the tote (size, position,
colour temperature, intensity), the environment (uniform / gradient / sky, intensity), the tote
and floor materials (colour, roughness and a procedural NumPy texture: value noise, checker or
stripes) and the exposure. No distractor objects are added.

Units: metres, radiance in the tracer's units (a white Lambertian surface under irradiance E
shows E / pi); poses (4, 4) float64 ``X_AB``.
"""

from __future__ import annotations

import atexit
import colorsys
import dataclasses
import math
import threading
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.errors import BackendError, InvalidArgumentError
from mgn.geometry import Material, Mesh
from mgn.render.path import (
    AreaLight,
    Environment,
    FilmOptions,
    PathScene,
    PathTraceOptions,
    PbrMaterial,
    develop,
)
from mgn.scene.cameras import CameraView

__all__ = [
    "ENGINES",
    "PhotoRenderer",
    "RandomizeSettings",
    "RenderSettings",
    "ViewLighting",
    "blackbody_rgb",
    "denoiser_available",
    "draw_lighting",
    "pbr_material",
    "procedural_texture",
]

#: Render engines of ``render.engine`` / ``--engine``.
ENGINES = ("raster", "path")
TONES = ("filmic", "linear")
DENOISE_QUALITIES = ("high", "balanced", "fast")
#: Guide images of ``render.denoise_guides`` (see :func:`denoise`).
DENOISE_GUIDES = ("smoothed", "raw", "albedo", "none")
#: Resolutions of ``render.denoise_resolution`` (see :func:`denoise`).
DENOISE_RESOLUTIONS = ("half", "full")
ENVIRONMENTS = ("uniform", "gradient", "sky")
TEXTURES = ("plain", "noise", "checker", "stripes")

#: The tote's plastic (polypropylene): a rough dielectric.
TOTE_ROUGHNESS = 0.55
#: The floor (sealed concrete / lino): a rough dielectric.
FLOOR_COLOR = (0.32, 0.31, 0.29)
FLOOR_ROUGHNESS = 0.75
#: Side of one repetition of a procedural texture on the tote and floor, m.
TEXTURE_TILE = 0.25


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

    def __post_init__(self) -> None:
        for key in ("lights", "environment", "materials", "exposure"):
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
        for key, lo, hi in (("light_size", 1e-3, None), ("light_height", 0.1, None),
                            ("light_irradiance", 0.0, None), ("light_temperature", 1000.0, 40000.0),
                            ("environment_intensity", 0.0, None)):  # fmt: skip
            rng = _range(getattr(self, key), f"RandomizeSettings.{key}", lo, hi)
            object.__setattr__(self, key, rng)
        for key in ("light_offset", "exposure_range"):
            v = getattr(self, key)
            if isinstance(v, bool) or not (math.isfinite(float(v)) and float(v) >= 0):
                raise InvalidArgumentError(f"RandomizeSettings.{key} must be >= 0, got {v!r}")
            object.__setattr__(self, key, float(v))


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
        for key, low in (("spp", 1), ("spp_without_denoiser", 1), ("max_bounces", 0),
                         ("adaptive_max", 1)):  # fmt: skip
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
            ("clamp", 0.0), ("aperture_radius", 0.0), ("shot_noise", 0.0), ("read_noise", 0.0),
            ("exposure", None), ("adaptive_samples", 0.0))  # fmt: skip
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
        return {"engine": "path", "spp": self.spp if d else self.spp_without_denoiser,
                "denoised": bool(d), "max_bounces": self.max_bounces}  # fmt: skip


# -------------------------------------------------------------------------------- denoiser

_DENOISER: Any = None
_DENOISER_CHECKED = False


def _pyoidn() -> Any:
    global _DENOISER, _DENOISER_CHECKED  # noqa: PLW0603 -- the optional denoiser, looked up once
    if not _DENOISER_CHECKED:
        _DENOISER_CHECKED = True
        try:
            import pyoidn

            _DENOISER = pyoidn
        except (ImportError, OSError):
            _DENOISER = None
    return _DENOISER


def denoiser_available() -> bool:
    """True when Intel Open Image Denoise (the ``pyoidn`` package) can be imported."""
    return _pyoidn() is not None


class _OidnFilter:
    """One OIDN CPU device and ``RT`` filter, kept for the process and reused by every
    :func:`denoise` call with the same thread count.

    OIDN's first execution on a device prepares the network and allocates its scratch memory
    (~0.46 GB for a 1200 x 1200 image, one tile): about 0.3-0.6 CPU-s once per process; later
    calls re-bind the images (any shape) and cost the network alone
    (docs/decisions/0027-denoiser-settings.md). The output does not depend on the thread
    count."""

    def __init__(self, oidn: Any, num_threads: int) -> None:
        self.oidn = oidn
        self.device = oidn.Device()
        self.filter: Any = None
        try:
            if num_threads > 0:
                self.device.set_int("numThreads", num_threads)
            self.device.commit()
            self._check("device creation")
            self.filter = oidn.Filter(self.device, "RT")
            self._check("filter creation")
        except BaseException:
            self.release()
            raise
        self.bound: dict[str, npt.NDArray[np.float32]] = {}  # kept alive while OIDN holds them

    def _check(self, step: str) -> None:
        err = self.device.get_error()
        if err is not None:
            raise BackendError(f"Intel Open Image Denoise: {step} failed: {err}")

    def run(
        self, images: dict[str, npt.NDArray[np.float32] | None], quality: str, clean_aux: bool
    ) -> None:
        """Bind ``images`` (color, albedo, normal, output; None unbinds) and execute;
        ``clean_aux``: the guides are noise-free (OIDN's ``cleanAux``)."""
        oidn = self.oidn
        for name, img in images.items():
            if img is None:
                if name in self.bound:
                    self.filter.unset_image(name)
                    del self.bound[name]
            else:
                self.filter.set_image(name, img, oidn.OIDN_FORMAT_FLOAT3)
                self.bound[name] = img
        self.filter.set_bool("hdr", True)
        self.filter.set_bool("cleanAux", clean_aux)
        self.filter.set_quality(_OIDN_QUALITY[quality](oidn))
        self.filter.commit()
        self._check("filter setup")
        self.filter.execute()
        self._check("denoising")

    def release(self) -> None:
        if self.filter is not None:
            self.filter.release()
            self.filter = None
        if self.device is not None:
            self.device.release()
            self.device = None


_OIDN_QUALITY = {
    "fast": lambda oidn: oidn.OIDN_QUALITY_FAST,
    "balanced": lambda oidn: oidn.OIDN_QUALITY_BALANCED,
    "high": lambda oidn: oidn.OIDN_QUALITY_HIGH,
}
_OIDN_FILTERS: dict[int, _OidnFilter] = {}  # by thread count (0 = all cores)
_OIDN_LOCK = threading.Lock()


def _release_oidn_filters() -> None:
    with _OIDN_LOCK:
        for f in _OIDN_FILTERS.values():
            f.release()
        _OIDN_FILTERS.clear()


atexit.register(_release_oidn_filters)


#: Weights of the 3 x 3 Gaussian (sigma 0.5 px, separable) of the ``smoothed`` guides.
_GUIDE_SIGMA = 0.5
_GUIDE_SIDE = math.exp(-0.5 / _GUIDE_SIGMA**2)
_GUIDE_WEIGHTS = (
    _GUIDE_SIDE / (1.0 + 2.0 * _GUIDE_SIDE),
    1.0 / (1.0 + 2.0 * _GUIDE_SIDE),
)


def _smooth3(img: npt.NDArray[np.float32], num_threads: int = 0) -> npt.NDArray[np.float32]:
    """3 x 3 Gaussian (``_GUIDE_SIGMA``) of an (H, W, C) float32 image: separable, the border
    pixels repeated outwards (C++ ``mgn::gaussian_3x3``, row-parallel on ``num_threads``, 0 =
    all cores)."""
    out: npt.NDArray[np.float32] = _core.render.gaussian_3x3(img, _GUIDE_SIGMA, num_threads)
    return out


def _guide(
    img: npt.NDArray[np.float32] | None, name: str, shape: tuple[int, ...], lo: float, smooth: bool
) -> npt.NDArray[np.float32] | None:
    if img is None:
        return None
    arr = np.asarray(img)
    if arr.shape != shape:
        raise InvalidArgumentError(
            f"denoise: {name} must have the radiance's shape {shape}, got {arr.shape}"
        )
    g = np.ascontiguousarray(np.clip(arr, lo, 1.0), np.float32)
    return _smooth3(g) if smooth else g


def denoise(
    radiance: npt.NDArray[np.float32],
    albedo: npt.NDArray[np.float32] | None = None,
    normal: npt.NDArray[np.float32] | None = None,
    quality: str = "fast",
    *,
    num_threads: int = 0,
    guides: str = "smoothed",
    resolution: str = "full",
) -> npt.NDArray[np.float32]:
    """Denoise linear HDR radiance (H, W, 3) with OIDN's ray-tracing filter, guided by the
    albedo and normal when given (the tracer's guides: the first surface that is not smooth
    glass; at 1 spp they carry the pixel's jittered position, i.e. aliased edges and texture).
    ``guides`` (see :attr:`RenderSettings.denoise_guides`): ``smoothed`` blurs each guide by a
    3 x 3 Gaussian (sigma 0.5 px) and declares them noise-free (OIDN's ``cleanAux``: the
    network then keeps the guides' detail instead of denoising it); ``raw`` passes them as they
    are, declared noisy; ``albedo`` drops the normal, ``none`` both. ``quality`` fast | balanced
    | high (see :attr:`RenderSettings.denoise_quality`); ``num_threads`` OIDN threads (0 = all
    cores; the result does not depend on it). Albedo (clipped to [0, 1]) and normal (clipped to
    [-1, 1], any frame) must have the radiance's shape; NaN and +inf radiance count as 0.
    ``resolution`` (see :attr:`RenderSettings.denoise_resolution`): ``full`` denoises every
    pixel; ``half`` denoises the 2 x 2 block means (an odd last row or column repeated) and
    returns full size: the denoised blocks interpolated bilinearly (pixel centres aligned) and
    multiplied by ``max(a, 0.02) / max(a_blocks, 0.02)`` per channel, ``a`` the full-size albedo
    (blurred when ``guides`` is ``smoothed``) and ``a_blocks`` the blocks' albedo interpolated
    alike (without an albedo: the interpolation alone); with a normal guide that ratio fades
    to 1 where the pixel's normal turns away from its blocks' (cosine 0.97 down to 0.85:
    silhouettes and creases, whose one-sample albedo would print aliasing).
    Returns a new (H, W, 3) float32 array, clamped to >= 0. One OIDN device and filter per
    thread count are kept for the process (the first call pays their set-up). Raises
    ImportError when pyoidn is missing."""
    oidn = _pyoidn()
    if oidn is None:
        raise ImportError("denoising needs the 'pyoidn' package: pip install 'mgn[render]'")
    if quality not in DENOISE_QUALITIES:
        raise InvalidArgumentError(
            f"denoise quality must be one of {DENOISE_QUALITIES}, got {quality!r}"
        )
    if guides not in DENOISE_GUIDES:
        raise InvalidArgumentError(
            f"denoise: guides must be one of {DENOISE_GUIDES}, got {guides!r}"
        )
    if resolution not in DENOISE_RESOLUTIONS:
        raise InvalidArgumentError(
            f"denoise: resolution must be one of {DENOISE_RESOLUTIONS}, got {resolution!r}"
        )
    if isinstance(num_threads, bool) or not isinstance(num_threads, int) or num_threads < 0:
        raise InvalidArgumentError(
            f"denoise: num_threads must be an integer >= 0 (0 = all cores), got {num_threads!r}"
        )
    rad = np.asarray(radiance)
    if rad.ndim != 3 or rad.shape[2] != 3 or rad.shape[0] == 0 or rad.shape[1] == 0:
        raise InvalidArgumentError(
            f"denoise: radiance must have shape (H, W, 3) with H, W > 0, got {rad.shape}"
        )
    # OIDN only reads the colour: finite float32 radiance (the tracer's) is passed as it is.
    c = np.ascontiguousarray(rad, np.float32)
    if not np.isfinite(c).all():  # in place only on a copy of our own, never the caller's
        c = np.nan_to_num(c, nan=0.0, posinf=0.0, copy=c is rad)
    smooth = guides == "smoothed"
    if resolution == "half" and min(rad.shape[0], rad.shape[1]) >= 2:
        return _denoise_half(c, albedo, normal, quality, num_threads, guides)
    a = _guide(albedo, "albedo", rad.shape, 0.0, smooth) if guides != "none" else None
    n = _guide(normal, "normal", rad.shape, -1.0, smooth) if guides in ("smoothed", "raw") else None
    return _run_oidn(c, a, n, quality, num_threads, smooth)


def _run_oidn(
    c: npt.NDArray[np.float32],
    a: npt.NDArray[np.float32] | None,
    n: npt.NDArray[np.float32] | None,
    quality: str,
    num_threads: int,
    clean_aux: bool,
) -> npt.NDArray[np.float32]:
    """OIDN on checked, contiguous float32 images (the process's filter for ``num_threads``),
    clamped to >= 0."""
    oidn = _pyoidn()
    out = np.empty_like(c)
    with _OIDN_LOCK:
        flt = _OIDN_FILTERS.get(num_threads)
        if flt is None:
            flt = _OIDN_FILTERS[num_threads] = _OidnFilter(oidn, num_threads)
        try:
            flt.run({"color": c, "albedo": a, "normal": n, "output": out}, quality, clean_aux)
        except BaseException:
            flt.release()  # a failed filter is not reused
            del _OIDN_FILTERS[num_threads]
            raise
    np.maximum(out, 0.0, out=out)
    return out


#: Albedo floor of the ratio that restores full-size detail after a ``half`` denoise.
_HALF_ALBEDO_FLOOR = 0.02


def _blocks2(img: npt.NDArray[np.float32], num_threads: int = 0) -> npt.NDArray[np.float32]:
    """Means of the 2 x 2 pixel blocks of an (H, W, C) image, an odd last row or column
    repeated: (ceil(H/2), ceil(W/2), C) float32 (C++ ``mgn::block_means_2x2``)."""
    out: npt.NDArray[np.float32] = _core.render.block_means_2x2(img, num_threads)
    return out


def _double(
    img: npt.NDArray[np.float32], h: int, w: int, num_threads: int = 0
) -> npt.NDArray[np.float32]:
    """Bilinear interpolation of a block image to twice its size, cropped to (h, w): block
    centres at the centres of their 2 x 2 pixels, so pixel 2i takes 3/4 of block i and 1/4 of
    block i - 1, pixel 2i + 1 3/4 of block i and 1/4 of block i + 1 (the border blocks
    repeated outwards; C++ ``mgn::double_blocks``)."""
    out: npt.NDArray[np.float32] = _core.render.double_blocks(img, h, w, num_threads)
    return out


#: Cosine between a pixel's normal and its blocks' interpolated normal below which the albedo
#: ratio of a ``half`` denoise is not applied, and above which it is applied in full (linear in
#: between): at silhouettes and creases the one-sample albedo of a pixel belongs to another
#: surface than its block, and the ratio would print that sample's aliasing into the image.
_EDGE_COS = (0.85, 0.97)


def _denoise_half(
    c: npt.NDArray[np.float32],
    albedo: npt.NDArray[np.float32] | None,
    normal: npt.NDArray[np.float32] | None,
    quality: str,
    num_threads: int,
    guides: str,
) -> npt.NDArray[np.float32]:
    """:func:`denoise` with ``resolution="half"`` on the checked radiance ``c``: the block
    means, OIDN on them, then C++ ``mgn::restore_half_resolution`` (doubling, albedo ratio,
    silhouette fade) on ``num_threads`` threads."""
    h, w = c.shape[:2]
    smooth = guides == "smoothed"
    a_full = _guide(albedo, "albedo", c.shape, 0.0, False) if guides != "none" else None
    n_full = (
        _guide(normal, "normal", c.shape, -1.0, False) if guides in ("smoothed", "raw") else None
    )
    a_blk = None if a_full is None else _blocks2(a_full, num_threads)
    n_blk = None if n_full is None else _blocks2(n_full, num_threads)
    den = _run_oidn(
        _blocks2(c, num_threads),
        None if a_blk is None else (_smooth3(a_blk, num_threads) if smooth else a_blk),
        None if n_blk is None else (_smooth3(n_blk, num_threads) if smooth else n_blk),
        quality,
        num_threads,
        smooth,
    )
    if smooth:
        a_full = None if a_full is None else _smooth3(a_full, num_threads)
        n_full = None if n_full is None else _smooth3(n_full, num_threads)
    lo, hi = _EDGE_COS
    out: npt.NDArray[np.float32] = _core.render.restore_half_resolution(
        den,
        h,
        w,
        albedo=a_full,
        albedo_blocks=a_blk,
        normal=n_full,
        normal_blocks=n_blk,
        albedo_floor=_HALF_ALBEDO_FLOOR,
        edge_cos_lo=lo,
        edge_cos_hi=hi,
        num_threads=num_threads,
    )
    return out


# -------------------------------------------------------------------------------- materials


def pbr_material(m: Material, texture: npt.NDArray[np.uint8] | None = None) -> Any:
    """The path tracer's :class:`mgn.render.path.PbrMaterial` of a mesh material: its own PBR
    parameters when it has them (``has_pbr``: built-in objects, glTF/GLB files, user objects),
    else :meth:`PbrMaterial.from_material` (derived from the Phong description)."""

    if not m.has_pbr:
        return PbrMaterial.from_material(m)
    base = np.clip(np.asarray(m.base_color, np.float64)[:3], 0.0, 1.0)
    tex = texture if texture is not None else _core.render.material_texture_rgb(m)
    transmission = float(m.transmission)
    return PbrMaterial(
        base_color=(float(base[0]), float(base[1]), float(base[2])),
        metallic=float(m.metallic),
        roughness=float(m.roughness),
        ior=max(1.0, float(m.ior)),
        transmission=transmission,
        base_color_texture=tex,
    )


def _srgb_to_linear(c: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _linear_to_srgb8(c: npt.NDArray[np.float64]) -> npt.NDArray[np.uint8]:
    c = np.clip(c, 0.0, 1.0)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    return np.round(s * 255.0).astype(np.uint8)


def procedural_texture(
    kind: str, rng: np.random.Generator, size: int = 128, contrast: float = 0.3
) -> npt.NDArray[np.uint8] | None:
    """A tileable grey (H, W, 3) uint8 sRGB texture around white that multiplies a base colour:
    ``noise`` (smooth value noise, two octaves), ``checker``, ``stripes`` (random period and
    direction), ``plain`` (None). ``contrast`` is the darkening of the darkest texels (linear)."""
    if kind == "plain":
        return None
    if kind not in TEXTURES:
        raise InvalidArgumentError(f"texture kind must be one of {TEXTURES}, got {kind!r}")
    y, x = np.mgrid[0:size, 0:size] / size
    if kind == "noise":
        v = np.zeros((size, size))
        for cells, weight in ((4, 0.65), (16, 0.35)):
            g = rng.random((cells, cells))
            # Bilinear (smoothstep) interpolation of a periodic lattice: tileable.
            fx, fy = x * cells, y * cells
            i0, j0 = np.floor(fx).astype(int) % cells, np.floor(fy).astype(int) % cells
            i1, j1 = (i0 + 1) % cells, (j0 + 1) % cells
            tx, ty = fx - np.floor(fx), fy - np.floor(fy)
            tx, ty = tx * tx * (3 - 2 * tx), ty * ty * (3 - 2 * ty)
            top = g[j0, i0] * (1 - tx) + g[j0, i1] * tx
            bot = g[j1, i0] * (1 - tx) + g[j1, i1] * tx
            v += weight * (top * (1 - ty) + bot * ty)
    elif kind == "checker":
        n = int(rng.integers(2, 5))
        v = ((np.floor(x * 2 * n) + np.floor(y * 2 * n)) % 2).astype(np.float64)
    else:  # stripes
        n = int(rng.integers(2, 7))
        v = (np.floor((x if rng.random() < 0.5 else y) * 2 * n) % 2).astype(np.float64)
    lin = 1.0 - contrast * v
    grey = _linear_to_srgb8(lin)
    return np.repeat(grey[:, :, None], 3, axis=2)


def _box_uv_mesh(mesh: Mesh, tile: float, name: str) -> Mesh:
    """``mesh`` with every face given its own vertices and uvs from a box projection (the two
    world axes across the face's dominant normal axis, divided by ``tile`` m): same triangles,
    texturable."""
    V = np.asarray(mesh.vertices, np.float64)
    F = np.asarray(mesh.faces, np.int64)
    P = V[F]  # (F, 3, 3)
    n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    axis = np.argmax(np.abs(n), axis=1)
    uv_axes = np.array([[1, 2], [0, 2], [0, 1]])[axis]  # (F, 2)
    uv = np.take_along_axis(P, uv_axes[:, None, :].repeat(3, axis=1), axis=2) / tile
    return Mesh(
        P.reshape(-1, 3).astype(np.float32),
        np.arange(3 * len(F), dtype=np.int32).reshape(-1, 3),
        uv.reshape(-1, 2).astype(np.float32),
        list(mesh.materials),
        [],
        name,
    )


# -------------------------------------------------------------------------------- lighting


def blackbody_rgb(temperature: float) -> tuple[float, float, float]:
    """Linear RGB tint of a black body at ``temperature`` K, white (1, 1, 1) at 6500 K and unit
    luminance: Planck's law sampled at the dominant wavelengths of the sRGB primaries (611, 549,
    464 nm), divided by the same at 6500 K. Accurate to a few percent in tint for 2500-10000 K,
    which is all lighting randomisation needs."""
    if not (math.isfinite(temperature) and temperature > 0):
        raise InvalidArgumentError(f"colour temperature must be > 0 K, got {temperature!r}")
    lam = np.array([611e-9, 549e-9, 464e-9])
    c2 = 1.4387769e-2  # m K, second radiation constant

    def planck(t: float) -> npt.NDArray[np.float64]:
        return 1.0 / (lam**5 * np.expm1(c2 / (lam * t)))

    rgb = planck(temperature) / planck(6500.0)
    rgb /= float(0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2])
    return (float(rgb[0]), float(rgb[1]), float(rgb[2]))


@dataclass(frozen=True)
class ViewLighting:
    """Everything drawn for one view: the lights, the environment, tote / floor materials and
    the exposure (EV, including the configured base)."""

    lights: tuple[Any, ...]
    environment: Any
    tote: Any
    floor: Any
    exposure: float
    summary: dict[str, Any] = field(default_factory=dict, compare=False)


def _look_down_pose(
    position: npt.NDArray[np.float64], target: npt.NDArray[np.float64], yaw: float
) -> npt.NDArray[np.float64]:
    """X_WL of a light at ``position`` whose +z axis points at ``target``."""
    z = target - position
    z /= np.linalg.norm(z)
    a = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    x = a - z * float(a @ z)
    if np.linalg.norm(x) < 1e-6:
        x = np.array([1.0, 0.0, 0.0]) - z * z[0]
    x /= np.linalg.norm(x)
    X = np.eye(4)
    X[:3, 0], X[:3, 1], X[:3, 2], X[:3, 3] = x, np.cross(z, x), z, position
    return X


def draw_lighting(
    settings: RenderSettings,
    seed: int,
    view_index: int,
    *,
    target_W: npt.ArrayLike = (0.0, 0.0, 0.0),
    tote_color: Sequence[float] = (0.2, 0.35, 0.6),
    randomize: bool = True,
) -> ViewLighting:
    """The lights, environment, tote / floor materials and exposure of view ``view_index``,
    drawn from (seed, view_index) by the switches of ``settings.randomize`` (all off when
    ``randomize`` is false: one 1 m x 1 m light 1.6 m above ``target_W``, a soft gradient
    environment, the tote in ``tote_color``, a grey floor, the configured exposure)."""

    r = settings.randomize
    target = np.asarray(target_W, np.float64)
    ss = np.random.SeedSequence([int(seed) & (2**63 - 1), int(view_index), 0x50484F54])
    # One independent stream per part: switching one part off does not change the others.
    g_light, g_env, g_mat, g_exp = (np.random.Generator(np.random.PCG64(s)) for s in ss.spawn(4))
    summary: dict[str, Any] = {}

    lights = []
    if randomize and r.lights:
        n = int(g_light.integers(r.light_count[0], r.light_count[1] + 1))
        for _ in range(n):
            side = g_light.uniform(*r.light_size)
            aspect = g_light.uniform(0.5, 1.0)
            h = g_light.uniform(*r.light_height)
            rad = r.light_offset * math.sqrt(g_light.random())
            phi = g_light.uniform(0.0, 2 * math.pi)
            pos = target + np.array([rad * math.cos(phi), rad * math.sin(phi), h])
            temp = g_light.uniform(*r.light_temperature)
            # Each light casts 1/n of the drawn irradiance on the target: a small light facing
            # the target at distance d and height h gives E = L A h / d^3 (A cos0 cos(theta)/d^2).
            e = g_light.uniform(*r.light_irradiance) / n
            area = side * side * aspect
            d = float(np.linalg.norm(pos - target))
            lights.append(
                AreaLight(
                    _look_down_pose(pos, target, g_light.uniform(0.0, math.pi)),
                    "rect",
                    (side, side * aspect),
                    blackbody_rgb(temp),
                    e * d**3 / (area * h),
                )
            )
        summary["lights"] = n
    else:
        lights.append(
            AreaLight(
                _look_down_pose(target + np.array([0.25, -0.2, 1.6]), target, 0.0),
                "rect",
                (1.0, 1.0),
                (1.0, 1.0, 1.0),
                20.0,
            )
        )
    if randomize and r.environment:
        kind = ENVIRONMENTS[int(g_env.integers(len(ENVIRONMENTS)))]
        inten = float(g_env.uniform(*r.environment_intensity))
        tint = blackbody_rgb(float(g_env.uniform(5000.0, 9000.0)))
        sun = g_env.normal(size=3)
        sun[2] = abs(sun[2]) + 0.5
        sun /= np.linalg.norm(sun)
        env = Environment(
            kind=kind, color=tint, zenith=tuple(0.8 * np.asarray(tint) * (0.75, 0.85, 1.0)),
            horizon=(0.9, 0.9, 0.9), ground=(0.25, 0.24, 0.22),
            sun_direction=tuple(sun), intensity=inten,
        )  # fmt: skip
        summary["environment"] = kind
    else:
        env = Environment(kind="gradient", zenith=(0.55, 0.6, 0.7), horizon=(0.8, 0.8, 0.8),
                          ground=(0.25, 0.24, 0.22), intensity=0.4)  # fmt: skip
    if randomize and r.materials:
        hue = g_mat.random()
        sat = g_mat.uniform(0.2, 0.8)
        val = g_mat.uniform(0.15, 0.75)
        tote_rgb = _srgb_to_linear(np.array(_hsv_to_rgb(hue, sat, val)))
        tote = PbrMaterial(
            base_color=tuple(tote_rgb),
            roughness=float(g_mat.uniform(0.35, 0.75)),
            base_color_texture=procedural_texture("noise", g_mat, contrast=0.15),
        )
        kind = TEXTURES[int(g_mat.integers(len(TEXTURES)))]
        floor_rgb = _srgb_to_linear(
            np.array(_hsv_to_rgb(g_mat.random(), g_mat.uniform(0, 0.4), g_mat.uniform(0.25, 0.8)))
        )
        floor = PbrMaterial(
            base_color=tuple(floor_rgb),
            roughness=float(g_mat.uniform(0.3, 0.95)),
            base_color_texture=procedural_texture(kind, g_mat, contrast=0.35),
        )
        summary["floor_texture"] = kind
    else:
        rgb = (float(tote_color[0]), float(tote_color[1]), float(tote_color[2]))
        tote = PbrMaterial(base_color=rgb, roughness=TOTE_ROUGHNESS)
        floor = PbrMaterial(base_color=FLOOR_COLOR, roughness=FLOOR_ROUGHNESS)
    exposure = settings.exposure
    if randomize and r.exposure and r.exposure_range > 0:
        exposure += float(g_exp.uniform(-r.exposure_range, r.exposure_range))
    return ViewLighting(tuple(lights), env, tote, floor, exposure, summary)


def _hsv_to_rgb(h: float, s: float, v: float) -> tuple[float, float, float]:

    return colorsys.hsv_to_rgb(h, s, v)


# -------------------------------------------------------------------------------- renderer


_WARNED_NO_DENOISER = False


class PhotoRenderer:
    """Path-traced photographs of one scene: the geometry is built once, each view draws its
    lighting and materials from (seed, view) and is traced, denoised and developed.

    Args:
        objects: (mesh, X_WO, instance id >= 1) per object.
        tote: the tote mesh or None (instance id 0), placed at ``X_W_tote``.
        floor: (floor mesh, X_W_floor) or None (instance id 0).
        settings: the engine settings (engine must be ``path``).
        tote_color: linear RGB of the tote when materials are not randomised.
        randomize: the scene's randomisation master switch (``camera.randomize``).
        seed: scene seed of the randomisation, the sampler and the sensor noise.
        num_threads: tracer and denoiser threads (0 = all cores); images do not depend on it.
    """

    def __init__(
        self,
        objects: Sequence[tuple[Mesh, npt.ArrayLike, int]],
        tote: Mesh | None,
        X_W_tote: npt.ArrayLike,
        floor: tuple[Mesh, npt.ArrayLike] | None,
        settings: RenderSettings,
        *,
        tote_color: Sequence[float] = (0.2, 0.35, 0.6),
        randomize: bool = True,
        seed: int = 0,
        num_threads: int = 0,
    ) -> None:
        global _WARNED_NO_DENOISER  # noqa: PLW0603 -- warn once per process
        self.settings = settings
        self.randomize = randomize
        self.seed = int(seed)
        self.num_threads = int(num_threads)
        self._X_tote = np.asarray(X_W_tote, np.float64)
        self._tote_color = tuple(float(c) for c in tote_color[:3])
        self.denoised = settings.denoise and denoiser_available()
        if settings.denoise and not self.denoised and not _WARNED_NO_DENOISER:
            _WARNED_NO_DENOISER = True
            warnings.warn(
                "render.denoise: the 'pyoidn' package (Intel Open Image Denoise) is not "
                "installed; tracing render.spp_without_denoiser = "
                f"{settings.spp_without_denoiser} samples per pixel instead "
                "(pip install 'mgn[render]' to denoise)",
                RuntimeWarning,
                stacklevel=2,
            )
        self.spp = settings.spp if self.denoised else settings.spp_without_denoiser
        # Object geometry and materials (fixed); tote and floor materials are per view.
        meshes: list[Mesh] = []
        poses: list[npt.NDArray[np.float64]] = []
        ids: list[int] = []
        mats: list[list[Any]] = []
        cache: dict[int, list[Any]] = {}
        for mesh, X_WO, inst in objects:
            if id(mesh) not in cache:
                cache[id(mesh)] = [pbr_material(m) for m in mesh.materials] or [pbr_default()]
            meshes.append(mesh)
            poses.append(np.asarray(X_WO, np.float64))
            ids.append(int(inst))
            mats.append(cache[id(mesh)])
        self._n_objects = len(meshes)
        if tote is not None:
            meshes.append(_box_uv_mesh(tote, TEXTURE_TILE, "tote"))
            poses.append(self._X_tote)
            ids.append(0)
            mats.append([None] * max(1, len(tote.materials)))
        if floor is not None:
            meshes.append(_box_uv_mesh(floor[0], TEXTURE_TILE * 2, "floor"))
            poses.append(np.asarray(floor[1], np.float64))
            ids.append(0)
            mats.append([None] * max(1, len(floor[0].materials)))
        self._meshes, self._poses, self._ids, self._mats = meshes, poses, ids, mats
        self._has_tote, self._has_floor = tote is not None, floor is not None
        self._scene: Any = None
        self._scene_materials: Any = None
        #: Wall seconds of the last :meth:`render`: ``trace``, ``denoise``, ``develop``.
        self.last_seconds: dict[str, float] = {}

    def describe(self) -> dict[str, Any]:
        """The engine record of the images this renderer makes (see RenderSettings.describe)."""
        return self.settings.describe(self.denoised)

    def lighting(self, view_index: int) -> ViewLighting:
        return draw_lighting(
            self.settings, self.seed, view_index, target_W=self._X_tote[:3, 3],
            tote_color=self._tote_color, randomize=self.randomize,
        )  # fmt: skip

    def _scene_for(self, lit: ViewLighting) -> Any:
        key = (lit.tote, lit.floor, id(lit.tote.base_color_texture),
               id(lit.floor.base_color_texture))  # fmt: skip
        if self._scene is None or self._scene_materials != key:
            mats = [list(m) for m in self._mats]
            k = self._n_objects
            if self._has_tote:
                mats[k] = [lit.tote] * len(mats[k])
                k += 1
            if self._has_floor:
                mats[k] = [lit.floor] * len(mats[k])
            self._scene = PathScene(self._meshes, np.stack(self._poses) if self._poses
                                    else np.zeros((0, 4, 4)), self._ids, mats,
                                    lit.lights, lit.environment)  # fmt: skip
            self._scene_materials = key
            return self._scene
        return self._scene.with_lighting(lit.lights, lit.environment)

    def render(
        self, view: CameraView, view_index: int, labels: bool = False
    ) -> tuple[npt.NDArray[np.uint8], Any]:
        """(H, W, 3) uint8 sRGB photograph of one view and the tracer output (radiance,
        albedo, normal; depth and instance ids only with ``labels``, else 0: the dataset's
        labels come from the ray-cast label pass, and skipping the tracer's own label rays
        saves ~1.4 % of a view's tracing)."""

        s = self.settings
        t0 = time.perf_counter()
        lit = self.lighting(view_index)
        scene = self._scene_for(lit)
        out = scene.render(
            view,
            PathTraceOptions(
                spp=self.spp, max_bounces=s.max_bounces, seed=self.seed & (2**63 - 1),
                view_index=int(view_index), num_threads=self.num_threads,
                aperture_radius=s.aperture_radius, clamp=s.clamp,
                adaptive_samples=s.adaptive_samples, adaptive_max=s.adaptive_max, labels=labels,
            ),
        )  # fmt: skip
        radiance = out.radiance
        t1 = time.perf_counter()
        if self.denoised:
            radiance = denoise(
                radiance, out.albedo, out.normal, s.denoise_quality,
                num_threads=self.num_threads, guides=s.denoise_guides,
                resolution=s.denoise_resolution,
            )  # fmt: skip
        t2 = time.perf_counter()
        rgb = develop(
            radiance,
            FilmOptions(
                exposure=lit.exposure, tone=s.tone, shot_noise=s.shot_noise,
                read_noise=s.read_noise, seed=self.seed & (2**63 - 1),
                view_index=int(view_index), num_threads=self.num_threads,
            ),
        )  # fmt: skip
        self.last_seconds = {"trace": t1 - t0, "denoise": t2 - t1,
                             "develop": time.perf_counter() - t2}  # fmt: skip
        return rgb, out


def pbr_default() -> Any:

    return PbrMaterial()


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
