"""The denoiser of the path-traced photographs: Intel Open Image Denoise (the optional
``pyoidn`` package) with its ray-tracing filter, guided by the tracer's albedo and normal, at full
or half resolution (:func:`denoise`).

One OIDN device and filter per thread count are kept for the process and released at exit; the
result does not depend on the thread count. The guide blur, the 2 x 2 block means, their
doubling and the half-resolution restore run in the C++ core.
"""

from __future__ import annotations

import atexit
import math
import threading
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.errors import BackendError, InvalidArgumentError

__all__ = [
    "DENOISE_GUIDES",
    "DENOISE_QUALITIES",
    "DENOISE_RESOLUTIONS",
    "denoise",
    "denoiser_available",
]

#: OIDN filter qualities of ``render.denoise_quality``.
DENOISE_QUALITIES = ("high", "balanced", "fast")
#: Guide images of ``render.denoise_guides`` (see :func:`denoise`).
DENOISE_GUIDES = ("smoothed", "raw", "albedo", "none")
#: Resolutions of ``render.denoise_resolution`` (see :func:`denoise`).
DENOISE_RESOLUTIONS = ("half", "full")

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
    """Denoise linear HDR radiance (H, W, 3) with OIDN's ray-tracing filter, guided by the albedo
    and normal when given (the tracer's guides: the first surface that is not smooth glass; at 1 spp
    they carry the pixel's jittered position, i.e. aliased edges and texture). ``guides`` (see
    :attr:`mgn.render.settings.RenderSettings.denoise_guides`): ``smoothed`` blurs each guide by a
    3 x 3 Gaussian (sigma 0.5 px) and declares them noise-free (OIDN's ``cleanAux``: the network
    then keeps the guides' detail instead of denoising it); ``raw`` passes them as they are,
    declared noisy; ``albedo`` drops the normal, ``none`` both. ``quality`` fast | balanced | high
    (see :attr:`mgn.render.settings.RenderSettings.denoise_quality`); ``num_threads`` OIDN threads
    (0 = all cores; the result does not depend on it). Albedo (clipped to [0, 1]) and normal
    (clipped to [-1, 1], any frame) must have the radiance's shape; NaN and +inf radiance count as
    0. ``resolution`` (see :attr:`mgn.render.settings.RenderSettings.denoise_resolution`): ``full``
    denoises every pixel; ``half`` denoises the 2 x 2 block means (an odd last row or column
    repeated) and returns full size: the denoised blocks interpolated bilinearly (pixel centres
    aligned) and multiplied by ``max(a, 0.02) / max(a_blocks, 0.02)`` per channel, ``a`` the
    full-size albedo (blurred when ``guides`` is ``smoothed``) and ``a_blocks`` the blocks' albedo
    interpolated alike (without an albedo: the interpolation alone); with a normal guide that ratio
    fades to 1 where the pixel's normal turns away from its blocks' (cosine 0.97 down to 0.85:
    silhouettes and creases, whose one-sample albedo would print aliasing).
    Returns a new (H, W, 3) float32 array, clamped to >= 0. One OIDN device and filter per thread
    count are kept for the process (the first call pays their set-up). Raises ImportError when
    pyoidn is missing."""
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
