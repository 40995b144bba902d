"""Detection and instance-segmentation metrics: ``mgn eval detections`` (COCO AP via pycocotools).

:func:`evaluate_detections` scores COCO result dicts against a dataset's labels and returns a
:class:`DetectionResults`: box AP and mask (segm) AP -- AP (mean over IoU 0.50:0.05:0.95), AP50
and AP75 at area range "all" and at most 100 detections per image, exactly as pycocotools'
``COCOeval`` computes them -- overall and broken down by

- **difficulty** 1..5 (image level, the ``difficulty`` of the view's ``{v}_layout.json``; views
  without a difficulty label are in no difficulty row): only the images of that level are
  evaluated;
- **seen / unseen** objects: a GT object is unseen when its category is one of the split's
  ``unseen_categories`` (``dataset.json`` ``"split"``; none when absent);
- **occlusion** bins of the GT objects' occlusion rates (``{v}_order.json``): bin ``k`` holds
  ``edges[k] <= occlusion < edges[k+1]`` (the last bin includes its upper edge).

*How the object-level subsets are evaluated.* For the seen/unseen and occlusion rows every image
is evaluated, and the GT objects **outside** the subset are marked *ignore* in the sense of
COCOeval's area-range ignore: a detection whose best match (IoU above the threshold) is an
ignored GT object is neither a true nor a false positive, and ignored GT objects do not count
as misses; detections that match nothing stay false positives. pycocotools' ``_prepare``
overwrites ``gt['ignore']`` with ``iscrowd`` (and ``iscrowd`` would also change the IoU), so
the flag is set by a small ``COCOeval`` subclass after ``_prepare`` has run; the matching and
the accumulation are pycocotools' own. With class-specific predictions this equals restricting
the AP average to the categories of the subset (split rows); with class-agnostic predictions
(``class_agnostic=True``: every prediction and GT object is of the one category "object") the
split is a property of the GT objects only, which is exactly what the ignore flag expresses.
A cell with no GT object to find (e.g. "unseen" when the split has no unseen category) is
``None`` (printed "-", ``null`` in JSON).

``amodal=True`` scores against the amodal labels: the GT ``segmentation`` and ``bbox`` are
replaced by ``amodal_segmentation`` and ``amodal_bbox`` (for the objects visible in the view,
the ones the COCO export lists).

Only the views of the dataset's ``"selection"`` (``dataset.json``; every view when absent) are
evaluated. Image ids are ``scene_id * 1000 + view_id`` (:mod:`mgn.io.coco`).

Example::

    res = evaluate_detections("out", "predictions.json")
    print(res.table())
    res.row("split", "unseen").seg_ap
"""

from __future__ import annotations

import contextlib
import copy
import io
import itertools
import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from numbers import Integral, Real
from pathlib import Path
from typing import Any

import numpy as np
from pycocotools import mask as mask_utils
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval

from mgn.errors import InvalidArgumentError, IoError
from mgn.eval.results import format_table
from mgn.io.coco import AGNOSTIC_ID, coco_dict
from mgn.io.dataset import Dataset

__all__ = [
    "DetectionResults",
    "DetectionRow",
    "evaluate_detections",
    "ground_truth_detections",
    "load_predictions_json",
    "selected_views",
]

DEFAULT_OCCLUSION_BINS = (0.0, 0.1, 0.3, 0.5, 0.7, 1.0)
_MAX_REPORTED = 10


# ---------------------------------------------------------------------------------------------
# Shared helpers (also used by mgn.eval.layout_metrics)


def as_dataset(dataset: Dataset | str | os.PathLike[str]) -> Dataset:
    """``dataset`` itself, or ``mgn.Dataset(dataset)`` for a path."""
    return dataset if isinstance(dataset, Dataset) else Dataset(dataset)


def selected_views(ds: Dataset) -> list[tuple[int, int]]:
    """(scene, view) pairs of the evaluated set, ascending: the ``dataset.json`` ``"selection"``
    views when present, else every view of every scene. A selected view missing from the dataset
    is an :class:`~mgn.errors.IoError` naming it."""
    info = ds.info or {}
    selection = info.get("selection")
    if selection is None:
        return [(s.scene_id, v) for s in ds.scenes() for v in s.view_ids]
    try:
        pairs = sorted({(int(e["scene"]), int(e["view"])) for e in selection["views"]})
    except (KeyError, TypeError, ValueError) as e:
        raise IoError(
            f"{ds.root}/dataset.json: 'selection' must hold 'views': [{{'scene', 'view', ...}}], "
            f"got {str(selection)[:200]}"
        ) from e
    missing = [(s, v) for s, v in pairs if s not in ds.scene_ids or v not in ds.scene(s).view_ids]
    if missing:
        raise IoError(
            f"{ds.root}/dataset.json: the selection names views the dataset lacks (scene, view): "
            f"{missing[:_MAX_REPORTED]}"
        )
    return pairs


def unseen_category_ids(ds: Dataset) -> set[int]:
    """The split's ``unseen_categories`` (``dataset.json``), empty when there is no split."""
    split = (ds.info or {}).get("split") or {}
    try:
        return {int(c) for c in split.get("unseen_categories", [])}
    except (TypeError, ValueError) as e:
        raise IoError(
            f"{ds.root}/dataset.json: split.unseen_categories must be a list of integers, "
            f"got {split.get('unseen_categories')!r}"
        ) from e


def load_predictions_json(path: str | os.PathLike[str], what: str = "predictions") -> list[Any]:
    """A JSON file holding a list (``IoError`` if missing or unreadable, ``InvalidArgumentError``
    if it holds something else)."""
    p = Path(path)
    try:
        text = p.read_text()
    except FileNotFoundError:
        raise IoError(f"{what} file '{p}' does not exist") from None
    except OSError as e:
        raise IoError(f"{what} file '{p}' is not readable: {e}") from e
    try:
        data = json.loads(text)
    except ValueError as e:
        raise IoError(f"{what} file '{p}' is not valid JSON: {e}") from e
    if not isinstance(data, list):
        raise InvalidArgumentError(
            f"{what} file '{p}' must hold a JSON list of prediction objects, "
            f"got {type(data).__name__}"
        )
    return data


def as_prediction_list(predictions: Any, what: str) -> list[Any]:
    if isinstance(predictions, (str, os.PathLike)):
        return load_predictions_json(predictions, what)
    if isinstance(predictions, Mapping) or not isinstance(predictions, Sequence):
        raise InvalidArgumentError(
            f"{what}: expected a list of prediction dicts or a path to a JSON file, "
            f"got {type(predictions).__name__}"
        )
    return list(predictions)


def is_int(x: Any) -> bool:
    return isinstance(x, Integral) and not isinstance(x, bool)


# ---------------------------------------------------------------------------------------------
# Results


@dataclass(frozen=True)
class DetectionRow:
    """One line of the results: a subset and its AP values (``None``: nothing to evaluate).

    Attributes:
        group: "all", "difficulty", "split" or "occlusion".
        subset: "all", "1".."5", "seen"/"unseen", or the occlusion bin, e.g. "[0.1, 0.3)".
        num_images: images evaluated.
        num_gt: GT objects that count (not ignored) in those images.
        box_ap, box_ap50, box_ap75: box AP over IoU 0.50:0.95, at 0.50 and at 0.75.
        seg_ap, seg_ap50, seg_ap75: the same for masks (``None`` when the predictions have no
            ``segmentation``).
    """

    group: str
    subset: str
    num_images: int
    num_gt: int
    box_ap: float | None
    box_ap50: float | None
    box_ap75: float | None
    seg_ap: float | None
    seg_ap50: float | None
    seg_ap75: float | None

    @property
    def label(self) -> str:
        """The row name printed in the table."""
        if self.group == "all":
            return "all"
        if self.group == "split":
            return self.subset
        return f"{self.group} {self.subset}"


@dataclass(frozen=True)
class DetectionResults:
    """What :func:`evaluate_detections` returns.

    Attributes:
        rows: "all", then difficulty 1..5, seen, unseen, then one row per occlusion bin.
        class_agnostic, amodal: the evaluation mode.
        num_images: images (views) evaluated.
        num_predictions: predictions scored (after dropping those for other images when
            ``strict=False``).
        num_dropped: predictions dropped because their image is not evaluated.
        unseen_categories: the category ids counted as unseen.
        occlusion_bins: the bin edges.
    """

    rows: tuple[DetectionRow, ...]
    class_agnostic: bool
    amodal: bool
    num_images: int
    num_predictions: int
    num_dropped: int
    unseen_categories: tuple[int, ...]
    occlusion_bins: tuple[float, ...]

    @property
    def overall(self) -> DetectionRow:
        """The row of every image and GT object."""
        return self.rows[0]

    def row(self, group: str, subset: str = "all") -> DetectionRow:
        """The row of ``group`` ("all", "difficulty", "split", "occlusion") and ``subset``
        (e.g. ``row("difficulty", "3")``, ``row("split", "unseen")``)."""
        for r in self.rows:
            if r.group == group and r.subset == subset:
                return r
        known = [(r.group, r.subset) for r in self.rows]
        raise KeyError(f"DetectionResults.row: no row ({group!r}, {subset!r}); rows: {known}")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (``None`` for empty cells)."""
        return {
            "class_agnostic": self.class_agnostic,
            "amodal": self.amodal,
            "num_images": self.num_images,
            "num_predictions": self.num_predictions,
            "num_dropped": self.num_dropped,
            "unseen_categories": list(self.unseen_categories),
            "occlusion_bins": list(self.occlusion_bins),
            "rows": [asdict(r) for r in self.rows],
        }

    def table(self) -> str:
        """The results as a text table (empty cells "-")."""
        columns = [
            "subset",
            "images",
            "gt",
            "box AP",
            "box AP50",
            "box AP75",
            "seg AP",
            "seg AP50",
            "seg AP75",
        ]
        rows = [
            {
                "subset": r.label,
                "images": r.num_images,
                "gt": r.num_gt,
                "box AP": r.box_ap,
                "box AP50": r.box_ap50,
                "box AP75": r.box_ap75,
                "seg AP": r.seg_ap,
                "seg AP50": r.seg_ap50,
                "seg AP75": r.seg_ap75,
            }
            for r in self.rows
        ]
        mode = ("class-agnostic" if self.class_agnostic else "per category") + (
            ", amodal" if self.amodal else ""
        )
        title = f"Detections ({mode}): {self.num_images} images, {self.num_predictions} predictions"
        return format_table(rows, columns, title=title)


# ---------------------------------------------------------------------------------------------
# Ground truth


def _ground_truth(ds: Dataset, *, amodal: bool, class_agnostic: bool) -> dict[str, Any]:
    """The COCO dict of the selected views; annotations keep their true category in
    ``object_category_id``; amodal: segmentation/bbox replaced by the amodal ones."""
    views = selected_views(ds)
    wanted = {s * 1000 + v for s, v in views}
    gt = coco_dict(ds, scenes=sorted({s for s, _ in views}))
    gt["images"] = [im for im in gt["images"] if im["id"] in wanted]
    anns: list[dict[str, Any]] = []
    for a in gt["annotations"]:
        if a["image_id"] not in wanted:
            continue
        a = dict(a)
        a["object_category_id"] = a["category_id"]
        if class_agnostic:
            a["category_id"] = AGNOSTIC_ID
        if amodal:
            a["segmentation"] = a["amodal_segmentation"]
            a["bbox"] = a["amodal_bbox"]
            a["area"] = a["amodal_area"]
        a["id"] = len(anns) + 1
        anns.append(a)
    gt["annotations"] = anns
    if class_agnostic:
        gt["categories"] = [{"id": AGNOSTIC_ID, "name": "object", "supercategory": "object"}]
    return gt


def ground_truth_detections(
    dataset: Dataset | str | os.PathLike[str], *, amodal: bool = False, class_agnostic: bool = False
) -> list[dict[str, Any]]:
    """The GT objects of the evaluated views as COCO results (``score`` 1.0): ``image_id``,
    ``category_id`` (1 when class-agnostic), ``bbox`` [x, y, w, h] px and ``segmentation`` (RLE;
    both amodal when ``amodal``). Scored by :func:`evaluate_detections` they give AP 1.0."""
    gt = _ground_truth(as_dataset(dataset), amodal=amodal, class_agnostic=class_agnostic)
    return [
        {
            "image_id": a["image_id"],
            "category_id": a["category_id"],
            "bbox": list(a["bbox"]),
            "segmentation": dict(a["segmentation"]),
            "score": 1.0,
        }
        for a in gt["annotations"]
    ]


# ---------------------------------------------------------------------------------------------
# Prediction checks


def _rle_string_counts(s: str) -> list[int] | None:
    """The run lengths of a compressed COCO RLE string (None if malformed). The format: each run
    is a little-endian sequence of 5-bit groups (char - 48), bit 0x20 = more groups follow, bit
    0x10 of the last group = negative; runs after the second are stored as differences to the
    run two places before."""
    counts: list[int] = []
    p, n = 0, len(s)
    while p < n:
        x, k, more = 0, 0, True
        while more:
            if p >= n:
                return None
            c = ord(s[p]) - 48
            if not 0 <= c < 64:
                return None
            x |= (c & 0x1F) << (5 * k)
            more = bool(c & 0x20)
            p += 1
            k += 1
            if not more and (c & 0x10):
                x -= 1 << (5 * k)
        if len(counts) > 2:
            x += counts[-2]
        counts.append(x)
    return counts


def _check_rle(seg: Any, shape: tuple[int, int], where: str) -> dict[str, Any]:
    """A validated compressed RLE (``counts`` as bytes) for an image of ``shape`` (h, w)."""

    h, w = shape
    if not isinstance(seg, Mapping) or "size" not in seg or "counts" not in seg:
        raise InvalidArgumentError(
            f"{where}: segmentation must be a COCO RLE {{'size': [h, w], 'counts': ...}}, "
            f"got {str(seg)[:80]}"
        )
    size = seg["size"]
    if not (isinstance(size, Sequence) and len(size) == 2 and [*size] == [h, w]):
        raise InvalidArgumentError(
            f"{where}: segmentation size must be the image size [{h}, {w}], got {size!r}"
        )
    raw = seg["counts"]
    if isinstance(raw, bytes):
        try:
            raw = raw.decode("ascii")
        except UnicodeDecodeError:
            raw = None
    if isinstance(raw, str):
        counts = _rle_string_counts(raw)
    elif isinstance(raw, Sequence) and all(is_int(c) for c in raw):
        counts = [int(c) for c in raw]
    else:
        counts = None
    if counts is None or any(c < 0 for c in counts) or sum(counts) != h * w:
        raise InvalidArgumentError(
            f"{where}: segmentation counts are not a valid RLE of a {h} x {w} mask "
            f"(non-negative runs summing to {h * w})"
        )
    if isinstance(raw, str):
        return {"size": [h, w], "counts": raw.encode("ascii")}
    rle: dict[str, Any] = mask_utils.frPyObjects({"size": [h, w], "counts": counts}, h, w)
    return rle


def _finite(x: Any) -> bool:
    return isinstance(x, Real) and not isinstance(x, bool) and math.isfinite(float(x))


def _required_fields(p: Any, where: str) -> tuple[Any, Any, Any]:
    """(image_id, category_id, score) of one prediction, checked."""
    if not isinstance(p, Mapping):
        raise InvalidArgumentError(f"{where}: expected a dict, got {type(p).__name__}")
    for key in ("image_id", "category_id", "score"):
        if key not in p:
            raise InvalidArgumentError(f"{where}: missing '{key}' (keys: {sorted(p)})")
    image_id, cat, score = p["image_id"], p["category_id"], p["score"]
    if not is_int(image_id):
        raise InvalidArgumentError(f"{where}: image_id must be an integer, got {image_id!r}")
    if not is_int(cat):
        raise InvalidArgumentError(f"{where}: category_id must be an integer, got {cat!r}")
    if not _finite(score):
        raise InvalidArgumentError(f"{where}: score must be a finite number, got {score!r}")
    return image_id, cat, score


def _check_predictions(
    preds: list[Any], images: Mapping[int, tuple[int, int]], *, class_agnostic: bool, strict: bool
) -> tuple[list[dict[str, Any]], int, bool]:
    """(cleaned detections, number dropped, have segmentation)."""

    out: list[dict[str, Any]] = []
    unknown: list[int] = []
    with_seg = 0
    for k, p in enumerate(preds):
        where = f"prediction {k}"
        image_id, cat, score = _required_fields(p, where)
        if int(image_id) not in images:
            unknown.append(int(image_id))
            continue
        shape = images[int(image_id)]
        det: dict[str, Any] = {
            "image_id": int(image_id),
            "category_id": AGNOSTIC_ID if class_agnostic else int(cat),
            "score": float(score),
        }
        if p.get("segmentation") is not None:
            det["segmentation"] = _check_rle(p["segmentation"], shape, where)
            with_seg += 1
        if "bbox" in p:
            bb = p["bbox"]
            ok = isinstance(bb, Sequence) and len(bb) == 4 and all(_finite(x) for x in bb)
            if not ok or bb[2] < 0 or bb[3] < 0:
                raise InvalidArgumentError(
                    f"{where}: bbox must be 4 finite numbers [x, y, w, h] (px) with w, h >= 0, "
                    f"got {bb!r}"
                )
            det["bbox"] = [float(x) for x in bb]
        elif "segmentation" in det:
            det["bbox"] = [float(x) for x in mask_utils.toBbox(det["segmentation"])]
        else:
            raise InvalidArgumentError(f"{where}: needs a 'bbox' or a 'segmentation'")
        det["area"] = (
            float(mask_utils.area(det["segmentation"]))
            if "segmentation" in det
            else det["bbox"][2] * det["bbox"][3]
        )
        out.append(det)
    if unknown and strict:
        names = sorted(set(unknown))
        raise InvalidArgumentError(
            f"evaluate_detections: {len(unknown)} prediction(s) name images that are not "
            f"evaluated (image_id = scene * 1000 + view, only the dataset's selection): "
            f"{names[:_MAX_REPORTED]}{' ...' if len(names) > _MAX_REPORTED else ''}; "
            f"evaluated ids: {sorted(images)[:_MAX_REPORTED]}... (pass strict=False to drop them)"
        )
    if 0 < with_seg < len(out):
        raise InvalidArgumentError(
            f"evaluate_detections: {with_seg} of {len(out)} predictions have a segmentation; "
            f"give it for all of them (mask AP) or none (box AP only)"
        )
    for i, d in enumerate(out):
        d["id"] = i + 1
        d["iscrowd"] = 0
    return out, len(unknown), bool(out) and with_seg == len(out)


# ---------------------------------------------------------------------------------------------
# Evaluation


def _coco(data: dict[str, Any]) -> Any:

    c = COCO()
    c.dataset = data
    with contextlib.redirect_stdout(io.StringIO()):
        c.createIndex()
    return c


def _make_eval_class() -> type:

    class _SubsetEval(COCOeval):  # type: ignore[misc]  # pycocotools has no type information
        """COCOeval that marks the GT annotations of ``ignore_ids`` as ignored (after
        ``_prepare``, which resets the flag from iscrowd) and reuses IoUs across subsets."""

        def __init__(
            self,
            gt: Any,
            dt: Any,
            iou_type: str,
            ignore_ids: frozenset[int],
            iou_cache: dict[tuple[int, int], Any],
        ) -> None:
            super().__init__(gt, dt, iou_type)
            self._ignore_ids = ignore_ids
            self._iou_cache = iou_cache

        def _prepare(self) -> None:
            super()._prepare()
            for gts in self._gts.values():
                for g in gts:
                    if g["id"] in self._ignore_ids:
                        g["ignore"] = 1

        def computeIoU(self, imgId: int, catId: int) -> Any:  # pycocotools
            key = (imgId, catId)
            if key not in self._iou_cache:
                self._iou_cache[key] = super().computeIoU(imgId, catId)
            return self._iou_cache[key]

    return _SubsetEval


def _ap_values(ev: Any) -> tuple[float | None, float | None, float | None]:
    """(AP, AP50, AP75) from ``ev.eval['precision']`` [T, R, K, A, M] at area "all", the
    largest maxDets, averaged like ``COCOeval.summarize`` (cells of -1 left out)."""
    prec = ev.eval["precision"][:, :, :, 0, -1]
    thr = np.asarray(ev.params.iouThrs)

    def mean(s: np.ndarray) -> float | None:
        s = s[s > -1]
        return float(np.mean(s)) if s.size else None

    t50 = int(np.flatnonzero(np.isclose(thr, 0.5))[0])
    t75 = int(np.flatnonzero(np.isclose(thr, 0.75))[0])
    return mean(prec), mean(prec[t50]), mean(prec[t75])


def _check_bins(bins: Sequence[float]) -> tuple[float, ...]:
    try:
        edges = tuple(float(b) for b in bins)
    except (TypeError, ValueError):
        raise InvalidArgumentError(
            f"evaluate_detections: occlusion_bins must be numbers, got {bins!r}"
        ) from None
    if (
        len(edges) < 2
        or not all(math.isfinite(e) for e in edges)
        or any(b <= a for a, b in itertools.pairwise(edges))
    ):
        raise InvalidArgumentError(
            f"evaluate_detections: occlusion_bins must be >= 2 finite, strictly increasing edges, "
            f"got {bins!r}"
        )
    return edges


def evaluate_detections(
    dataset: Dataset | str | os.PathLike[str],
    predictions: Sequence[Mapping[str, Any]] | str | os.PathLike[str],
    *,
    class_agnostic: bool = False,
    amodal: bool = False,
    occlusion_bins: Sequence[float] = DEFAULT_OCCLUSION_BINS,
    unseen_categories: Sequence[int] | None = None,
    strict: bool = True,
) -> DetectionResults:
    """Box and mask AP of ``predictions`` on ``dataset`` (see the module docstring for the
    subsets and how they are evaluated).

    Args:
        dataset: a dataset folder or :class:`mgn.Dataset`.
        predictions: COCO result dicts (``image_id`` = scene * 1000 + view, ``category_id``,
            ``bbox`` [x, y, w, h] px, ``segmentation`` RLE (optional for all or none: without
            it the mask AP cells are ``None``), ``score``) or the path of a JSON file of them.
        class_agnostic: evaluate with one category: every ``category_id`` is ignored.
        amodal: score against the amodal GT masks and boxes.
        occlusion_bins: edges of the occlusion-rate bins of the GT objects.
        unseen_categories: the category ids counted as unseen (default: the dataset's split).
        strict: predictions for images that are not evaluated are an error (else dropped).

    Raises:
        IoError: a missing or unreadable predictions file or dataset file.
        InvalidArgumentError: a malformed prediction (naming its index and the field), or a
            prediction for an image that is not evaluated (with ``strict``).
    """
    ds = as_dataset(dataset)
    bins = _check_bins(occlusion_bins)
    preds = as_prediction_list(predictions, "evaluate_detections: predictions")
    if unseen_categories is None:
        unseen = unseen_category_ids(ds)
    else:
        if not all(is_int(c) for c in unseen_categories):
            raise InvalidArgumentError(
                f"evaluate_detections: unseen_categories must be integers, "
                f"got {unseen_categories!r}"
            )
        unseen = {int(c) for c in unseen_categories}

    gt_data = _ground_truth(ds, amodal=amodal, class_agnostic=class_agnostic)
    images = {im["id"]: (int(im["height"]), int(im["width"])) for im in gt_data["images"]}
    dets, dropped, have_seg = _check_predictions(
        preds, images, class_agnostic=class_agnostic, strict=strict
    )
    gt = _coco(gt_data)
    dt = _coco(
        {
            "images": gt_data["images"],
            "categories": copy.deepcopy(gt_data["categories"]),
            "annotations": dets,
        }
    )
    anns = gt_data["annotations"]
    all_images = sorted(images)

    # (group, subset, image ids, ignored GT ids)
    subsets: list[tuple[str, str, list[int], frozenset[int]]] = [
        ("all", "all", all_images, frozenset())
    ]
    for level in range(1, 6):
        ids = [im["id"] for im in gt_data["images"] if im.get("difficulty") == level]
        subsets.append(("difficulty", str(level), ids, frozenset()))
    is_unseen = {a["id"]: a["object_category_id"] in unseen for a in anns}
    subsets.append(("split", "seen", all_images, frozenset(i for i, u in is_unseen.items() if u)))
    subsets.append(
        ("split", "unseen", all_images, frozenset(i for i, u in is_unseen.items() if not u))
    )
    for k, (lo, hi) in enumerate(itertools.pairwise(bins)):
        last = k == len(bins) - 2
        inside = {
            a["id"] for a in anns if lo <= a["occlusion"] < hi or (last and a["occlusion"] == hi)
        }
        label = f"[{lo:g}, {hi:g}{']' if last else ')'}"
        ignore = frozenset(a["id"] for a in anns if a["id"] not in inside)
        subsets.append(("occlusion", label, all_images, ignore))

    evaluator = _make_eval_class()
    caches: dict[str, dict[tuple[int, int], Any]] = {"bbox": {}, "segm": {}}
    rows = []
    for group, name, img_ids, ignore in subsets:
        img_set = set(img_ids)
        num_gt = sum(1 for a in anns if a["image_id"] in img_set and a["id"] not in ignore)
        values: dict[str, tuple[float | None, ...]] = {}
        for iou_type in ("bbox", "segm"):
            if not img_ids or (iou_type == "segm" and not have_seg and dets):
                values[iou_type] = (None, None, None)
                continue
            ev = evaluator(gt, dt, iou_type, ignore, caches[iou_type])
            ev.params.imgIds = img_ids
            with contextlib.redirect_stdout(io.StringIO()):
                ev.evaluate()
                ev.accumulate()
            values[iou_type] = _ap_values(ev)
        rows.append(
            DetectionRow(group, name, len(img_ids), num_gt, *values["bbox"], *values["segm"])
        )
    return DetectionResults(
        rows=tuple(rows),
        class_agnostic=class_agnostic,
        amodal=amodal,
        num_images=len(all_images),
        num_predictions=len(dets),
        num_dropped=dropped,
        unseen_categories=tuple(sorted(unseen)),
        occlusion_bins=bins,
    )
