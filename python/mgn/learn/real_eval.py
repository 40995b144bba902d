"""``mgn eval real``: a trained model on labelled real photographs, with a report.

The photographs are read by :func:`mgn.io.real.read_real_set` (MetaGraspNet's real layout or a
COCO folder), predicted one by one (:class:`mgn.learn.predict.Predictor`) and scored
(:mod:`mgn.learn.metrics`): mask AP and AP50 over all images (visible masks, or amodal masks
with ``amodal=True``; each image's own AP and AP50 are kept per image), foreground IoU (mean
over images), and suction precision@k (mean over the images that have a suction bitmap; the
predicted points are the k best of the suction map on predicted objects, 2 % of the image
diagonal apart). Beside the model, the trivial reference :func:`brightness_foreground` (every
pixel brighter than Otsu's threshold of the image's luminance is an object) is scored by the
same foreground IoU (``fg_IoU_brightness``): a model that does not beat it has learned nothing
about objects that brightness does not say.

Files in ``out`` (when given): ``results.json`` (:meth:`RealResults.to_dict`), ``overlays/``
with one PNG per image (labels | predicted instances and suction points | suction map; the
labelled suction pixels are outlined in the first panel) and ``report.html`` (the table and
the pictures).
"""

from __future__ import annotations

import html
import io
import json
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image
from tqdm import tqdm

from mgn.base.atomic import atomic_write_bytes, atomic_write_text
from mgn.errors import InvalidArgumentError
from mgn.io.real import RealImage, detect_real_format, read_real_set
from mgn.learn.metrics import foreground_iou, mask_ap, suction_precision
from mgn.learn.pictures import mask_panel, overlay
from mgn.learn.predict import Prediction, Predictor, as_predictor
from mgn.learn.targets import uses_depth

__all__ = ["DEFAULT_KS", "RealResults", "brightness_foreground", "evaluate_real"]

#: k of the suction precision@k.
DEFAULT_KS = (1, 5, 10)


def _mean(values: Sequence[float]) -> float | None:
    return float(np.mean(values)) if len(values) else None


def brightness_foreground(rgb: np.ndarray) -> np.ndarray:
    """(H, W) bool: the pixels of an (H, W, 3) uint8 image whose luminance (0.299 R + 0.587 G +
    0.114 B, rounded to 0-255) is above Otsu's threshold (the level that maximises the
    between-class variance of the image's histogram); all False for a uniform image."""
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise InvalidArgumentError(f"brightness_foreground: expected (H, W, 3), got {rgb.shape}")
    y = np.rint(rgb.astype(np.float64) @ np.array([0.299, 0.587, 0.114])).astype(np.int64)
    hist = np.bincount(y.ravel(), minlength=256)[:256].astype(np.float64)
    levels = np.arange(256, dtype=np.float64)
    w0 = np.cumsum(hist)  # pixels at or below each level
    w1 = w0[-1] - w0
    m0 = np.cumsum(hist * levels)
    with np.errstate(divide="ignore", invalid="ignore"):
        between = w0 * w1 * (m0 / w0 - (m0[-1] - m0) / w1) ** 2
    between[~np.isfinite(between)] = -1.0
    if between.max() <= 0:
        return np.zeros(y.shape, bool)
    t = int(np.argmax(between))
    fg: np.ndarray = y > t
    return fg


@dataclass
class RealResults:
    """Scores of a model on a set of labelled photographs.

    Attributes:
        model, source, format: the model file, the set's path and layout.
        amodal: scored against amodal masks.
        num_images, num_objects: images and labelled objects.
        mask_ap, mask_ap50: COCO mask AP / AP50 (None without objects).
        foreground_iou: mean over images.
        brightness_iou: mean foreground IoU of :func:`brightness_foreground` over the images.
        suction: {k: mean precision@k} over the images with a suction bitmap (empty if none).
        suction_images: how many images have one.
        per_image: one dict per image (name, objects, predicted, foreground_iou, the image's
            own mask_AP and mask_AP50 (None for an image without outlined objects), p@k).
        tta: the test-time augmentation of the predictions
            (:data:`mgn.learn.predict.TTA_MODES`).
    """

    model: str
    source: str
    format: str
    amodal: bool
    num_images: int
    num_objects: int
    mask_ap: float | None
    mask_ap50: float | None
    foreground_iou: float | None
    brightness_iou: float | None = None
    suction: dict[int, float | None] = field(default_factory=dict)
    suction_images: int = 0
    per_image: list[dict[str, Any]] = field(default_factory=list)
    tta: str = "none"

    def summary(self) -> dict[str, Any]:
        """The one-row summary: images, objects, mask AP, AP50, foreground IoU, P@k."""
        row: dict[str, Any] = {
            "images": self.num_images,
            "objects": self.num_objects,
            "mask_AP": self.mask_ap,
            "mask_AP50": self.mask_ap50,
            "fg_IoU": self.foreground_iou,
            "fg_IoU_brightness": self.brightness_iou,
        }
        row.update({f"suction_P@{k}": v for k, v in self.suction.items()})
        return row

    def table(self) -> str:
        """The summary as an aligned text table, with a title."""
        row = self.summary()
        cells = [
            "-" if v is None else (f"{v:.3f}" if isinstance(v, float) else str(v))
            for v in row.values()
        ]
        widths = [max(len(k), len(c)) for k, c in zip(row, cells, strict=True)]
        head = "  ".join(k.rjust(w) for k, w in zip(row, widths, strict=True))
        body = "  ".join(c.rjust(w) for c, w in zip(cells, widths, strict=True))
        kind = "amodal" if self.amodal else "visible"
        aug = "" if self.tta == "none" else f", test-time augmentation {self.tta}"
        title = f"{self.source} ({self.format}, {kind} masks), model {self.model}{aug}"
        note = "" if self.suction_images else "\n(no suction bitmaps: no suction precision)"
        return f"{title}\n{head}\n{body}{note}"

    def to_dict(self) -> dict[str, Any]:
        return {
            "model": self.model,
            "source": self.source,
            "format": self.format,
            "amodal": self.amodal,
            "tta": self.tta,
            "summary": self.summary(),
            "suction_images": self.suction_images,
            "per_image": self.per_image,
        }


def _safe(name: str) -> str:
    stem = re.sub(r"\.(png|jpe?g)$", "", name, flags=re.IGNORECASE)
    return re.sub(r"[^A-Za-z0-9._-]+", "_", stem).strip("_") or "image"


def _outline(mask: np.ndarray) -> np.ndarray:
    m = np.pad(mask, 1)
    return np.asarray(mask & ~(m[:-2, 1:-1] & m[2:, 1:-1] & m[1:-1, :-2] & m[1:-1, 2:]))


def _picture(img: RealImage, gt: np.ndarray, pred: Prediction) -> bytes:
    shown = gt if img.crowd is None else np.concatenate([gt, img.crowd[None]])
    left = mask_panel(img.rgb, shown)
    if img.suction_bitmap is not None:
        left[_outline(img.suction_bitmap != 0)] = (255, 255, 255)
    right = overlay(img.rgb, pred)
    buf = io.BytesIO()
    Image.fromarray(np.concatenate([left, right], axis=1)).save(buf, format="PNG")
    return buf.getvalue()


def _report_html(res: RealResults, pictures: list[str]) -> str:
    head = "".join(f"<th>{html.escape(k)}</th>" for k in res.summary())
    cells = "".join(
        f"<td>{'-' if v is None else (f'{v:.3f}' if isinstance(v, float) else v)}</td>"
        for v in res.summary().values()
    )
    rows = []
    for entry, pic in zip(res.per_image, pictures, strict=True):
        facts = ", ".join(
            f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}"
            for k, v in entry.items()
            if k != "name"
        )
        rows.append(
            f"<h3>{html.escape(entry['name'])}</h3><p>{html.escape(facts)}</p>"
            f'<img src="{html.escape(pic)}" style="max-width:100%">'
        )
    return (
        "<!doctype html><meta charset='utf-8'><title>mgn eval real</title>"
        "<style>body{font-family:sans-serif;margin:2em}td,th{padding:4px 10px;"
        "border:1px solid #ccc}</style>"
        f"<h1>mgn eval real</h1><p>{html.escape(res.source)} ({res.format}), model "
        f"{html.escape(res.model)}, test-time augmentation {html.escape(res.tta)}</p>"
        f"<table><tr>{head}</tr><tr>{cells}</tr></table>"
        "<p>Pictures: labels (white outline: labelled suction pixels) | predicted instances "
        "and the 10 best suction points | predicted suction quality (black 0, yellow 1).</p>"
        + "".join(rows)
    )


def evaluate_real(
    model: Predictor | str | os.PathLike[str],
    real: str | os.PathLike[str],
    out: str | os.PathLike[str] | None = None,
    *,
    fmt: str = "auto",
    amodal: bool = False,
    ks: Sequence[int] = DEFAULT_KS,
    threshold: float = 0.5,
    core_threshold: float = 0.4,
    device: str = "auto",
    num_threads: int = 0,
    progress: bool = True,
    tta: str | None = None,
) -> RealResults:
    """Score ``model`` on the labelled photographs at ``real`` (module docstring); ``tta`` the
    test-time augmentation (:data:`mgn.learn.predict.TTA_MODES`; None: the ``Predictor``'s own,
    or :data:`mgn.learn.predict.DEFAULT_TTA` for a model file)."""
    pred_model = as_predictor(model, device=device, num_threads=num_threads, tta=tta)
    if amodal and not pred_model.config.amodal:
        raise InvalidArgumentError(
            f"--amodal: '{pred_model.path}' predicts visible masks only (train it with --amodal)"
        )
    fmt = detect_real_format(real) if fmt == "auto" else fmt
    images = read_real_set(real, fmt)
    if amodal and any(img.amodal is None for img in images):
        missing = [img.name for img in images if img.amodal is None][:5]
        raise InvalidArgumentError(f"--amodal: '{real}' has no amodal masks for {missing}")
    gts: list[np.ndarray] = []
    crowds: list[np.ndarray | None] = []
    preds: list[np.ndarray] = []
    scores: list[np.ndarray] = []
    per_image: list[dict[str, Any]] = []
    pictures: list[str] = []
    suction: dict[int, list[float]] = {int(k): [] for k in ks}
    out_dir = Path(out) if out is not None else None
    for img in tqdm(images, desc="eval real", unit="img", disable=not progress):
        depth = img.depth if uses_depth(pred_model.config.modality) else None
        if uses_depth(pred_model.config.modality) and depth is None:
            raise InvalidArgumentError(
                f"{img.name}: the model's input is "
                f"{pred_model.config.modality}, but it has no depth"
            )
        pred = pred_model.predict(
            img.rgb, depth, name=img.name, threshold=threshold, core_threshold=core_threshold
        )
        gt = img.amodal if amodal and img.amodal is not None else img.masks
        gts.append(gt)
        crowds.append(img.crowd)
        preds.append(pred.instances.masks(amodal=amodal))
        scores.append(pred.instances.scores)
        entry: dict[str, Any] = {
            "name": img.name,
            "objects": len(gt),
            "predicted": pred.instances.num_instances,
            "foreground_iou": foreground_iou(img.foreground, pred.instances.labels > 0),
            "brightness_iou": foreground_iou(img.foreground, brightness_foreground(img.rgb)),
        }
        entry["mask_AP"], entry["mask_AP50"] = mask_ap(
            [gt], [preds[-1]], [scores[-1]], [crowds[-1]]
        )
        if img.suction_bitmap is not None:
            pk = suction_precision(pred.suction_points(max(ks)), img.suction_bitmap, ks)
            for k, v in pk.items():
                suction[k].append(v)
                entry[f"suction_P@{k}"] = v
        per_image.append(entry)
        if out_dir is not None:
            name = f"overlays/{len(pictures):03d}_{_safe(img.name)}.png"
            atomic_write_bytes(out_dir / name, _picture(img, gt, pred))
            pictures.append(name)
    ap, ap50 = mask_ap(gts, preds, scores, crowds)
    n_suction = len(next(iter(suction.values()))) if suction else 0
    res = RealResults(
        model=os.fspath(pred_model.path),
        source=os.fspath(real),
        format=fmt,
        amodal=amodal,
        num_images=len(images),
        num_objects=int(sum(len(g) for g in gts)),
        mask_ap=ap,
        mask_ap50=ap50,
        foreground_iou=_mean([e["foreground_iou"] for e in per_image]),
        brightness_iou=_mean([e["brightness_iou"] for e in per_image]),
        suction={k: _mean(v) for k, v in suction.items()} if n_suction else {},
        suction_images=n_suction,
        per_image=per_image,
        tta=pred_model.tta,
    )
    if out_dir is not None:
        atomic_write_text(out_dir / "results.json", json.dumps(res.to_dict(), indent=1) + "\n")
        atomic_write_text(out_dir / "report.html", _report_html(res, pictures))
    return res
