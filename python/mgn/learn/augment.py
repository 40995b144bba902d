"""Training-time augmentation of the baselines' views (numpy and Pillow, no PyTorch).

A view at the network's resolution is its input ``x`` (C, H, W) float32 (RGB in [0, 1] first,
then the depth or height channel for ``rgbd`` and ``rgb-height``; ``depth`` and ``height``
models have that channel only), its targets
``t`` (T, H, W) and its suction weight ``w`` (H, W). :func:`augment_view` changes them in one of
the :data:`AUGMENTS` modes:

- ``none``: unchanged.
- ``flips``: a horizontal and a vertical flip, each with probability 1/2 (drawn by the caller).
- ``full`` (the default of :class:`mgn.learn.config.TrainConfig`): geometric changes applied
  alike to input, targets and weight -- with probability :data:`ZOOM_PROBABILITY` a random
  window of 1 / z of each side (z log-uniform in :data:`ZOOM_RANGE`; z < 1 zooms out, the
  view mirrored at its borders to fill the window) resampled to the full size (input
  bilinear, targets and weight nearest-neighbour), a rotation by a multiple of 90 degrees
  (any multiple for square views, 0 or 180 degrees otherwise) and the two flips -- then
  photometric changes of the RGB channels only, in this order: a gain per colour channel
  (white balance), an exposure change (a factor ``2 ** ev``, reaching photographs several
  times darker or brighter than the rendered views), brightness, contrast, saturation, a hue
  rotation, a gamma curve, a Gaussian blur, Gaussian sensor noise and a JPEG round trip
  (ranges and probabilities in :data:`PHOTOMETRIC`). The targets of a photometric change are
  those of the unchanged view.

Every random number comes from the ``numpy.random.Generator`` passed in, so the same generator
state gives the same bytes on any machine and thread count.
"""

from __future__ import annotations

import io

import numpy as np
import numpy.typing as npt
from PIL import Image

from mgn.errors import InvalidArgumentError
from mgn.learn.targets import uses_rgb

__all__ = [
    "AUGMENTS",
    "PHOTOMETRIC",
    "ZOOM_PROBABILITY",
    "ZOOM_RANGE",
    "augment_view",
    "geometric",
    "photometric",
    "resample_window",
]

#: Augmentation modes (module docstring).
AUGMENTS = ("none", "flips", "full")
#: Probability of a zoomed-in window, and the range of its zoom factor z (window side = 1 / z).
ZOOM_PROBABILITY = 0.6
ZOOM_RANGE = (0.7, 1.5)
#: Photometric changes of the RGB channels: (range, probability) of each; factors multiply,
#: ``hue`` is a rotation of the chroma plane in turns, ``blur`` a Gaussian sigma in px,
#: ``noise`` the standard deviation of additive Gaussian noise (RGB in [0, 1]), ``jpeg`` the
#: JPEG quality, ``exposure`` an exposure value ``ev`` in stops (the values times ``2 ** ev``).
PHOTOMETRIC: dict[str, tuple[tuple[float, float], float]] = {
    "gain": ((0.85, 1.15), 1.0),
    "exposure": ((-3.0, 1.0), 0.5),
    "brightness": ((0.6, 1.4), 1.0),
    "contrast": ((0.6, 1.4), 1.0),
    "saturation": ((0.4, 1.5), 1.0),
    "hue": ((-0.08, 0.08), 1.0),
    "gamma": ((0.7, 1.5), 1.0),
    "blur": ((0.3, 1.2), 0.3),
    "noise": ((0.005, 0.04), 0.5),
    "jpeg": ((30.0, 90.0), 0.3),
}

# Luma and chroma (YIQ) of linear RGB, for the hue rotation.
_YIQ = np.array([[0.299, 0.587, 0.114], [0.596, -0.274, -0.322], [0.211, -0.523, 0.312]])
_YIQ_INV = np.linalg.inv(_YIQ)


def _uniform(rng: np.random.Generator, key: str) -> float | None:
    """A value of ``PHOTOMETRIC[key]``'s range, or None when the change is not applied. Both
    numbers are always drawn, so every change consumes the same random numbers."""
    (lo, hi), p = PHOTOMETRIC[key]
    apply, value = rng.random(), rng.uniform(lo, hi)
    return float(value) if apply < p else None


def _mirror(s: np.ndarray, n: int) -> np.ndarray:
    """Coordinates ``s`` (px, edges at 0 and n) mirrored into [0, n]."""
    m = np.mod(s, 2 * n)
    return np.asarray(np.where(m <= n, m, 2 * n - m))


def resample_window(
    a: np.ndarray, r0: float, c0: float, h: float, w: float, *, nearest: bool
) -> np.ndarray:
    """The window of ``a`` (..., H, W) with top-left corner (r0, c0) and size (h, w) px, resampled
    to (H, W): output pixel centre ``i + 0.5`` samples the source at ``r0 + (i + 0.5) * h / H``
    (bilinear between pixel centres, edges clamped; or the pixel containing it when
    ``nearest``). Outside the image the source is mirrored at its borders."""
    H, W = a.shape[-2:]  # image size
    ys = _mirror(r0 + (np.arange(H) + 0.5) * (h / H), H)
    xs = _mirror(c0 + (np.arange(W) + 0.5) * (w / W), W)
    if nearest:
        rows = np.clip(np.floor(ys).astype(np.int64), 0, H - 1)
        cols = np.clip(np.floor(xs).astype(np.int64), 0, W - 1)
        return a[..., rows[:, None], cols[None, :]]
    ys, xs = np.clip(ys - 0.5, 0, H - 1), np.clip(xs - 0.5, 0, W - 1)
    y0, x0 = np.floor(ys).astype(np.int64), np.floor(xs).astype(np.int64)
    y1, x1 = np.minimum(y0 + 1, H - 1), np.minimum(x0 + 1, W - 1)
    fy, fx = (ys - y0)[:, None].astype(a.dtype), (xs - x0)[None, :].astype(a.dtype)
    top = a[..., y0[:, None], x0[None, :]] * (1 - fx) + a[..., y0[:, None], x1[None, :]] * fx
    bot = a[..., y1[:, None], x0[None, :]] * (1 - fx) + a[..., y1[:, None], x1[None, :]] * fx
    return np.asarray((top * (1 - fy) + bot * fy).astype(a.dtype))


def geometric(
    x: np.ndarray, t: np.ndarray, w: np.ndarray, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The random zoom window, rotation and flips of ``full`` (module docstring), alike on
    input, targets and weight."""
    H, W = x.shape[-2:]  # image size
    zoom_draw = rng.random()
    z = float(np.exp(rng.uniform(np.log(ZOOM_RANGE[0]), np.log(ZOOM_RANGE[1]))))
    fr, fc = rng.random(), rng.random()
    k = int(rng.integers(0, 4))
    fh, fv = bool(rng.integers(0, 2)), bool(rng.integers(0, 2))
    if zoom_draw < ZOOM_PROBABILITY:
        h, wd = H / z, W / z
        r0, c0 = fr * (H - h), fc * (W - wd)
        x = resample_window(x, r0, c0, h, wd, nearest=False)
        t = resample_window(t, r0, c0, h, wd, nearest=True)
        w = resample_window(w, r0, c0, h, wd, nearest=True)
    if H != W:
        k = 2 * (k % 2)
    if k:
        x, t, w = (np.rot90(a, k, axes=(-2, -1)) for a in (x, t, w))
    if fh:
        x, t, w = x[..., ::-1], t[..., ::-1], w[..., ::-1]
    if fv:
        x, t, w = x[..., ::-1, :], t[..., ::-1, :], w[..., ::-1, :]
    return x, t, w


def photometric(rgb: np.ndarray, rng: np.random.Generator) -> npt.NDArray[np.float32]:
    """The photometric changes of ``full`` (module docstring) of an RGB image (3, H, W) in
    [0, 1]; the result is in [0, 1]."""
    if rgb.ndim != 3 or rgb.shape[0] != 3:
        raise InvalidArgumentError(f"photometric: RGB must be (3, H, W), got {rgb.shape}")
    x = np.asarray(rgb, np.float64)
    gains = rng.uniform(*PHOTOMETRIC["gain"][0], size=3)
    x = x * gains[:, None, None]
    ev = _uniform(rng, "exposure")
    b = _uniform(rng, "brightness")
    c = _uniform(rng, "contrast")
    s = _uniform(rng, "saturation")
    hue = _uniform(rng, "hue")
    g = _uniform(rng, "gamma")
    sigma = _uniform(rng, "blur")
    noise = _uniform(rng, "noise")
    quality = _uniform(rng, "jpeg")
    noise_seed = int(rng.integers(0, 2**31))
    if ev is not None:
        x = x * 2.0**ev
    if b is not None:
        x = x * b
    if c is not None:
        mean = float(np.tensordot(_YIQ[0], x, axes=1).mean())
        x = (x - mean) * c + mean
    if s is not None or hue is not None:
        yiq = np.tensordot(_YIQ, x, axes=1)
        chroma = yiq[1:] * (s if s is not None else 1.0)
        if hue is not None:
            a = 2.0 * np.pi * hue
            ca, sa = np.cos(a), np.sin(a)
            chroma = np.stack([ca * chroma[0] - sa * chroma[1], sa * chroma[0] + ca * chroma[1]])
        x = np.tensordot(_YIQ_INV, np.concatenate([yiq[:1], chroma]), axes=1)
    x = np.clip(x, 0.0, 1.0)
    if g is not None:
        x = x**g
    if sigma is not None:
        from scipy import ndimage

        x = np.stack([ndimage.gaussian_filter(p, sigma, mode="nearest") for p in x])
    if noise is not None:
        x = x + np.random.default_rng(noise_seed).normal(0.0, noise, size=x.shape)
    x = np.clip(x, 0.0, 1.0)
    if quality is not None:
        img = Image.fromarray(np.moveaxis(np.round(x * 255.0).astype(np.uint8), 0, 2))
        buf = io.BytesIO()
        img.save(buf, format="JPEG", quality=int(round(quality)))
        buf.seek(0)
        x = np.moveaxis(np.asarray(Image.open(buf).convert("RGB"), np.float64), 2, 0) / 255.0
    return x.astype(np.float32)


def augment_view(
    x: np.ndarray,
    t: np.ndarray,
    w: np.ndarray,
    mode: str,
    modality: str,
    rng: np.random.Generator,
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32], npt.NDArray[np.float32]]:
    """One view's input (C, H, W), targets (T, H, W) and weight (H, W) augmented in ``mode``
    (module docstring; ``flips`` draws its two flips from ``rng``); the RGB channels of
    ``rgb`` / ``rgbd`` / ``rgb-height`` inputs get the photometric changes. Returns new
    contiguous arrays."""
    if mode not in AUGMENTS:
        raise InvalidArgumentError(f"augment must be one of {AUGMENTS}, got {mode!r}")
    if not (x.shape[-2:] == t.shape[-2:] == w.shape[-2:]):
        raise InvalidArgumentError(
            f"augment: input {x.shape}, targets {t.shape} and weight {w.shape} differ in size"
        )
    if mode == "flips":
        fh, fv = bool(rng.integers(0, 2)), bool(rng.integers(0, 2))
        if fh:
            x, t, w = x[..., ::-1], t[..., ::-1], w[..., ::-1]
        if fv:
            x, t, w = x[..., ::-1, :], t[..., ::-1, :], w[..., ::-1, :]
    elif mode == "full":
        x, t, w = geometric(x, t, w, rng)
        if uses_rgb(modality):
            x = np.concatenate([photometric(x[:3], rng), x[3:]])
    return tuple(np.ascontiguousarray(a, dtype=np.float32) for a in (x, t, w))  # type: ignore[return-value]
