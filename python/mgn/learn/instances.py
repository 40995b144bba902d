"""Instances from the network's maps (class-agnostic instance segmentation, no PyTorch).

:func:`instances_from_maps` turns per-pixel probabilities into instances:

1. *seeds*: the connected parts (4-neighbourhood) of ``foreground > threshold`` (default 0.5)
   and ``core > core_threshold`` (default 0.4; the objects' inner parts,
   :mod:`mgn.learn.targets`); parts under ``min_area`` px are dropped;
2. *growth*: every foreground pixel joins the seed nearest to it (Euclidean distance) within
   its connected foreground part, so the pixels between the seeds go back to the objects on
   both sides; a connected foreground part (4-neighbourhood) that holds no seed is one
   instance when it has at least ``min_area`` px (the core map missed it: on photos unlike the
   training images the core map can stay below its threshold where the foreground does not)
   and background otherwise (a speck);
3. *score* of an instance: the mean foreground probability over its pixels;
4. *amodal* masks (when a hidden map is given): each connected part (8-neighbourhood) of
   ``hidden > threshold`` is the hidden part of one object: of the instances it touches
   (a 1 px ring around it) other than the one it lies on (the occluder, the most frequent label
   under it), the one with the longest contact; an instance's amodal mask is its visible mask
   plus the hidden parts given to it.

Connected parts, dilation and the nearest-seed transform are ``scipy.ndimage``'s.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError, UnsupportedError

__all__ = ["InstanceMaps", "instances_from_maps"]


@dataclass(frozen=True)
class InstanceMaps:
    """Instances of one image.

    Attributes:
        labels: (H, W) int32, 0 background, instance ``i`` is ``labels == i + 1``.
        scores: (N,) float32 confidence in [0, 1].
        amodal: (N, H, W) bool amodal masks, or None (the model predicts visible masks only).
    """

    labels: npt.NDArray[np.int32]
    scores: npt.NDArray[np.float32]
    amodal: npt.NDArray[np.bool_] | None = None

    @property
    def num_instances(self) -> int:
        """N."""
        return int(len(self.scores))

    def masks(self, amodal: bool = False) -> npt.NDArray[np.bool_]:
        """(N, H, W) bool: the visible masks, or the amodal ones (``amodal=True``; visible
        masks when the model has none)."""
        if amodal and self.amodal is not None:
            return self.amodal
        n = self.num_instances
        return np.asarray(self.labels[None] == np.arange(1, n + 1, dtype=np.int32)[:, None, None])


def _ndimage() -> Any:  # the scipy.ndimage module
    try:
        from scipy import ndimage
    except ImportError as e:
        raise UnsupportedError(
            f"instance extraction needs scipy ({e}): pip install 'mgn[learn]'"
        ) from None
    return ndimage


def _hidden_owners(
    labels: np.ndarray, hidden: np.ndarray, n: int, ndimage: Any
) -> npt.NDArray[np.bool_]:
    amodal = labels[None] == np.arange(1, n + 1)[:, None, None]
    parts, count = ndimage.label(hidden, structure=np.ones((3, 3), bool))
    for k in range(1, count + 1):
        part = parts == k
        under = labels[part]
        occluder = int(np.bincount(under, minlength=n + 1)[1:].argmax() + 1) if under.any() else 0
        ring = ndimage.binary_dilation(part, structure=np.ones((3, 3), bool)) & ~part
        touching = np.bincount(labels[ring], minlength=n + 1)
        touching[0] = 0
        if occluder:
            touching[occluder] = 0
        if touching.max() == 0:
            continue
        amodal[int(touching.argmax()) - 1] |= part
    return np.asarray(amodal)


def _grow(seeds: np.ndarray, fgm: np.ndarray, ndimage: Any) -> npt.NDArray[np.int32]:
    """Seed labels grown over the foreground: each pixel takes its nearest seed when that seed
    lies in the pixel's connected foreground part; the rest of a part that has seeds is filled by
    4-neighbour growth from the labelled pixels; parts without a seed stay background."""
    parts, _ = ndimage.label(fgm)
    _, (iy, ix) = ndimage.distance_transform_edt(seeds == 0, return_indices=True)
    labels = np.where(fgm & (parts == parts[iy, ix]), seeds[iy, ix], 0).astype(np.int32)
    seeded = np.zeros(parts.max() + 1, bool)
    seeded[parts[seeds > 0]] = True
    todo = fgm & (labels == 0) & seeded[parts]
    while todo.any():
        grown = labels.copy()
        for axis, shift in ((0, 1), (0, -1), (1, 1), (1, -1)):
            nb = np.roll(labels, shift, axis=axis)
            edge = [slice(None), slice(None)]
            edge[axis] = slice(0, 1) if shift == 1 else slice(-1, None)
            nb[tuple(edge)] = 0
            grown = np.where(todo & (grown == 0), nb, grown)
        if np.array_equal(grown, labels):
            break
        labels = grown
        todo = fgm & (labels == 0) & seeded[parts]
    return labels


def instances_from_maps(
    foreground: np.ndarray,
    core: np.ndarray,
    *,
    hidden: np.ndarray | None = None,
    threshold: float = 0.5,
    core_threshold: float = 0.4,
    min_area: int = 8,
) -> InstanceMaps:
    """Instances of probability maps (H, W) in [0, 1] (module docstring)."""
    fg = np.asarray(foreground, np.float32)
    bd = np.asarray(core, np.float32)
    if fg.ndim != 2 or fg.shape != bd.shape or (hidden is not None and hidden.shape != fg.shape):
        raise InvalidArgumentError(
            f"foreground {fg.shape}, core {bd.shape}"
            + ("" if hidden is None else f", hidden {hidden.shape}")
            + ": expected equal (H, W) maps"
        )
    for name, t in (("threshold", threshold), ("core_threshold", core_threshold)):
        if not 0.0 < t < 1.0:
            raise InvalidArgumentError(f"{name} must be in (0, 1), got {t}")
    if min_area < 1:
        raise InvalidArgumentError(f"min_area must be >= 1 px, got {min_area}")
    ndimage = _ndimage()
    fgm = fg > threshold
    seeds, count = ndimage.label(fgm & (bd > core_threshold))
    areas = np.bincount(seeds.ravel(), minlength=count + 1)
    keep = np.flatnonzero(areas >= min_area)
    keep = keep[keep > 0]
    remap = np.zeros(count + 1, np.int32)
    remap[keep] = np.arange(1, len(keep) + 1, dtype=np.int32)
    seeds = remap[seeds]
    n = len(keep)
    parts, n_parts = ndimage.label(fgm)
    seeded = np.zeros(n_parts + 1, bool)
    seeded[parts[seeds > 0]] = True
    part_areas = np.bincount(parts.ravel(), minlength=n_parts + 1)
    lone = np.flatnonzero(~seeded & (part_areas >= min_area))
    lone = lone[lone > 0]
    if len(lone):
        extra = np.zeros(n_parts + 1, np.int32)
        extra[lone] = np.arange(n + 1, n + 1 + len(lone), dtype=np.int32)
        seeds = np.where(seeds > 0, seeds, extra[parts])
        n += len(lone)
    if n == 0:
        empty = np.zeros(fg.shape, np.int32)
        am = None if hidden is None else np.zeros((0, *fg.shape), bool)
        return InstanceMaps(empty, np.zeros(0, np.float32), am)
    labels = _grow(seeds, fgm, ndimage)
    sums = np.bincount(labels.ravel(), weights=fg.ravel(), minlength=n + 1)[1:]
    counts = np.bincount(labels.ravel(), minlength=n + 1)[1:]
    scores = (sums / np.maximum(counts, 1)).astype(np.float32)
    amodal = None
    if hidden is not None:
        amodal = _hidden_owners(labels, np.asarray(hidden) > threshold, n, ndimage)
    return InstanceMaps(labels, scores, amodal)
