"""Overlay pictures of predictions (and of ground truth) for people (Pillow, no PyTorch).

:func:`overlay` draws two panels side by side: left, the image with each predicted instance
tinted in its own colour, its outline, and the suction points (white rings, the best one
larger); right, the suction quality as a heat map (black 0 to yellow 1) over the greyed image.
:func:`mask_panel` draws masks alone (ground truth in the reports).
"""

from __future__ import annotations

import colorsys
from typing import Any

import numpy as np
import numpy.typing as npt
from PIL import Image, ImageDraw

__all__ = ["instance_palette", "mask_panel", "overlay"]


def instance_palette(n: int) -> npt.NDArray[np.uint8]:
    """(n, 3) uint8 distinct colours (hues a golden angle apart)."""
    cols = [colorsys.hsv_to_rgb((0.61803398875 * i) % 1.0, 0.75, 0.95) for i in range(n)]
    return np.asarray((np.array(cols, np.float64).reshape(-1, 3) * 255).round().astype(np.uint8))


def _outline(mask: np.ndarray) -> np.ndarray:
    m = np.pad(mask, 1)
    inner = m[:-2, 1:-1] & m[2:, 1:-1] & m[1:-1, :-2] & m[1:-1, 2:]
    return np.asarray(mask & ~inner)


def mask_panel(rgb: np.ndarray, masks: np.ndarray, alpha: float = 0.5) -> npt.NDArray[np.uint8]:
    """The image with masks (N, H, W) tinted and outlined, in order (later masks on top)."""
    img = np.asarray(rgb, np.float32).copy()
    colors = instance_palette(len(masks)).astype(np.float32)
    for i, m in enumerate(np.asarray(masks, bool)):
        img[m] = (1 - alpha) * img[m] + alpha * colors[i]
        img[_outline(m)] = colors[i]
    return np.asarray(img.round().astype(np.uint8))


def _heat(q: np.ndarray) -> npt.NDArray[np.float32]:
    q = np.clip(np.nan_to_num(q.astype(np.float32)), 0.0, 1.0)[..., None]
    return (
        np.concatenate(
            [np.clip(2 * q, 0, 1), np.clip(2 * q - 1, 0, 1) * 0.9 + 0.1 * q, np.zeros_like(q)],
            axis=-1,
        )
        * 255
    )


def overlay(rgb: np.ndarray | None, prediction: Any) -> npt.NDArray[np.uint8]:
    """(H, 2 W, 3) uint8: instances and suction points | suction heat map (module docstring).
    ``prediction`` is a :class:`mgn.learn.predict.Prediction`; ``rgb`` None draws on grey."""
    labels = prediction.instances.labels
    h, w = labels.shape
    base = np.full((h, w, 3), 128, np.uint8) if rgb is None else np.asarray(rgb, np.uint8)
    left = mask_panel(base, prediction.instances.masks())
    grey = base.astype(np.float32).mean(axis=2, keepdims=True)
    right = (0.35 * grey + 0.65 * _heat(prediction.suction)).round().astype(np.uint8)
    im = Image.fromarray(np.concatenate([left, right], axis=1))
    draw = ImageDraw.Draw(im)
    r = max(2.0, 0.012 * float(np.hypot(h, w)))
    for k, (u, v, _) in enumerate(prediction.suction_points(10)):
        rr = r * (1.6 if k == 0 else 1.0)
        for dx in (0, w):
            draw.ellipse(
                [u + dx - rr, v - rr, u + dx + rr, v + rr],
                outline=(255, 255, 255),
                width=max(1, round(r / 3)),
            )
    return np.asarray(im)
