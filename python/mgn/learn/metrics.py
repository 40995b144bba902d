"""Metrics of the baselines on labelled images (numpy and pycocotools; no PyTorch).

- **mask AP, AP50** (:func:`mask_ap`): pycocotools' ``COCOeval`` with ``iouType="segm"``,
  class-agnostic (every mask one category), area range "all", at most 100 detections per
  image: AP is the mean over IoU thresholds 0.50:0.05:0.95, AP50 at IoU 0.5 (101-point
  interpolated precision). None when no image has a ground-truth object. Crowd regions
  (object pixels labelled without separating the objects) are COCO ``iscrowd`` annotations:
  predictions on them count neither as hits nor as false positives.
- **foreground IoU** (:func:`foreground_iou`): |P and G| / |P or G| of the union of the predicted
  masks P and of the ground-truth masks G (1 when both are empty).
- **suction precision@k** (:func:`suction_precision`): of the k best predicted suction points,
  the fraction that fall on a non-zero pixel of the labelled suction bitmap; fewer than k
  predicted points count the missing ones as misses.
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Sequence
from typing import Any

import numpy as np
from pycocotools import mask as mask_utils
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval

from mgn.errors import InvalidArgumentError

__all__ = ["foreground_iou", "mask_ap", "suction_precision"]


def _rle(mask: np.ndarray) -> dict[str, Any]:
    r: dict[str, Any] = mask_utils.encode(np.asfortranarray(mask.astype(np.uint8)))
    r["counts"] = r["counts"].decode("ascii")
    return r


def mask_ap(
    ground_truth: Sequence[np.ndarray],
    predictions: Sequence[np.ndarray],
    scores: Sequence[np.ndarray],
    crowds: Sequence[np.ndarray | None] | None = None,
) -> tuple[float | None, float | None]:
    """(AP, AP50) of predicted masks against ground-truth masks, image by image: ``ground_truth[i]``
    and ``predictions[i]`` (N_i, H, W) / (M_i, H, W) bool, ``scores[i]`` (M_i,); ``crowds[i]``
    an (H, W) bool crowd region of image i or None."""
    crowd_list = list(crowds) if crowds is not None else [None] * len(ground_truth)
    if len(crowd_list) != len(ground_truth):
        raise InvalidArgumentError(
            f"mask_ap: {len(ground_truth)} ground truths, {len(crowd_list)} crowd regions"
        )
    if not len(ground_truth) == len(predictions) == len(scores):
        raise InvalidArgumentError(
            f"mask_ap: {len(ground_truth)} ground truths, {len(predictions)} predictions, "
            f"{len(scores)} score lists; expected one each per image"
        )
    images: list[dict[str, Any]] = []
    anns: list[dict[str, Any]] = []
    dets: list[dict[str, Any]] = []
    n_objects = 0
    for i, (gt, pred, sc) in enumerate(zip(ground_truth, predictions, scores, strict=True)):
        h, w = gt.shape[-2:]
        if pred.shape[-2:] != (h, w) or len(sc) != len(pred):
            raise InvalidArgumentError(
                f"mask_ap: image {i}: ground truth {gt.shape}, predictions {pred.shape}, "
                f"{len(sc)} scores"
            )
        images.append({"id": i + 1, "width": int(w), "height": int(h)})
        crowd = crowd_list[i]
        if crowd is not None and crowd.shape != (h, w):
            raise InvalidArgumentError(
                f"mask_ap: image {i}: ground truth {gt.shape}, crowd region {crowd.shape}"
            )
        n_objects += len(gt)
        regions = [(m, 0) for m in gt] + ([(crowd, 1)] if crowd is not None and crowd.any() else [])
        for m, is_crowd in regions:
            r = _rle(m)
            anns.append(
                {
                    "id": len(anns) + 1,
                    "image_id": i + 1,
                    "category_id": 1,
                    "segmentation": r,
                    "area": float(mask_utils.area(r)),
                    "bbox": [float(v) for v in mask_utils.toBbox(r)],
                    "iscrowd": is_crowd,
                }
            )
        for m, s in zip(pred, sc, strict=True):
            dets.append(
                {"image_id": i + 1, "category_id": 1, "segmentation": _rle(m), "score": float(s)}
            )
    if not n_objects:
        return None, None
    gt_coco = COCO()
    gt_coco.dataset = {
        "images": images,
        "annotations": anns,
        "categories": [{"id": 1, "name": "object"}],
    }
    with contextlib.redirect_stdout(io.StringIO()):
        gt_coco.createIndex()
        if not dets:
            return 0.0, 0.0
        ev = COCOeval(gt_coco, gt_coco.loadRes(dets), "segm")
        ev.evaluate()
        ev.accumulate()
        ev.summarize()
    return float(ev.stats[0]), float(ev.stats[1])


def foreground_iou(ground_truth: np.ndarray, predicted: np.ndarray) -> float:
    """IoU of the union of ground-truth masks (N, H, W) and of predicted masks (M, H, W) (or
    (H, W) foreground images)."""
    g: np.ndarray = np.asarray(ground_truth, bool)
    p: np.ndarray = np.asarray(predicted, bool)
    g = np.asarray(g.any(axis=0) if g.ndim == 3 else g)
    p = np.asarray(p.any(axis=0) if p.ndim == 3 else p)
    if g.shape != p.shape:
        raise InvalidArgumentError(f"foreground_iou: ground truth {g.shape}, prediction {p.shape}")
    union = int((g | p).sum())
    return 1.0 if union == 0 else float((g & p).sum()) / union


def suction_precision(
    points: np.ndarray, bitmap: np.ndarray, ks: Sequence[int]
) -> dict[int, float]:
    """Precision@k for each k of ``ks``: ``points`` (P, >= 2) [u, v, ...] px, best first
    (pixel ``(row, col)`` covers ``col <= u < col + 1``, ``row <= v < row + 1``); ``bitmap``
    (H, W), non-zero = good."""
    b = np.asarray(bitmap)
    pts = np.asarray(points, np.float64).reshape(
        -1, np.asarray(points).shape[-1] if len(points) else 2
    )
    h, w = b.shape
    hits = []
    for u, v in pts[:, :2]:
        c, r = int(np.floor(u)), int(np.floor(v))
        hits.append(bool(0 <= r < h and 0 <= c < w and b[r, c] != 0))
    out = {}
    for k in ks:
        if k < 1:
            raise InvalidArgumentError(f"precision@k: k must be >= 1, got {k}")
        out[int(k)] = float(sum(hits[:k])) / k
    return out
