"""Layout metrics: ``mgn eval layout`` -- how well predicted layers match the labelled ones.

Predictions are dicts ``{"image_id", "instance_id", "layer"}``: ``image_id`` = scene * 1000 +
view (:mod:`mgn.io.coco`), ``instance_id`` a GT instance id 1..N of that view, ``layer`` 0 top,
1 secondary, 2 interlock, 3 others (docs/format.md ``{v}_order.json``). The GT layer of an object is
the ``layer`` of its ``{v}_order.json`` entry.

Metrics, over the *visible* GT objects (at least one pixel in the view's instance map) of the
evaluated views (the ``dataset.json`` selection, or every view). An object without a prediction
is *missing*: a missing object counts as a wrong layer and as "not top". Predictions for objects
that are not visible are accepted and ignored. With ``w_i`` = the visible pixel count of object
``i``:

- ``accuracy`` = #{objects with predicted layer == GT layer} / #{objects};
- ``weighted_accuracy`` = sum of ``w_i`` over the correct objects / sum of ``w_i`` over all;
- ``confusion[g][p]``: number of objects of GT layer ``g`` (0..3) predicted as layer ``p``
  (0..3), column 4 = missing; ``per_layer_accuracy[g]`` = ``confusion[g][g]`` / row sum
  (``None`` when no object has GT layer ``g``);
- top-object set, per view: ``T`` = objects with GT layer 0, ``P`` = objects predicted layer 0;
  precision = |T ∩ P| / |P|, recall = |T ∩ P| / |T|, F1 = 2 precision recall / (precision +
  recall) (0 when both are 0); an empty ``P`` has precision 1 if ``T`` is empty too, else 0;
  an empty ``T`` has recall 1 if ``P`` is empty too, else 0. ``top_precision``, ``top_recall``
  and ``top_f1`` are the means over the views that have a visible object (``None`` when none).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mgn.errors import InvalidArgumentError
from mgn.eval.detections import as_dataset, as_prediction_list, is_int, selected_views
from mgn.eval.results import format_table
from mgn.io.dataset import Dataset

__all__ = ["LayoutResults", "evaluate_layout", "ground_truth_layout"]

NUM_LAYERS = 4
LAYER_NAMES = ("top", "secondary", "interlock", "others")
_MAX_REPORTED = 10


@dataclass(frozen=True)
class LayoutResults:
    """What :func:`evaluate_layout` returns (definitions in the module docstring).

    Attributes:
        num_views: views evaluated.
        num_objects: visible GT objects.
        num_missing: visible GT objects without a prediction.
        accuracy, weighted_accuracy: layer accuracy, unweighted and weighted by visible pixels
            (``None`` when there is no visible object).
        confusion: 4 x 5 counts [GT layer][predicted layer 0..3, missing].
        per_layer_accuracy: per GT layer 0..3.
        top_precision, top_recall, top_f1: top-set scores averaged over views.
    """

    num_views: int
    num_objects: int
    num_missing: int
    accuracy: float | None
    weighted_accuracy: float | None
    confusion: tuple[tuple[int, ...], ...]
    per_layer_accuracy: tuple[float | None, ...]
    top_precision: float | None
    top_recall: float | None
    top_f1: float | None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {
            "num_views": self.num_views,
            "num_objects": self.num_objects,
            "num_missing": self.num_missing,
            "accuracy": self.accuracy,
            "weighted_accuracy": self.weighted_accuracy,
            "confusion": [list(r) for r in self.confusion],
            "confusion_columns": [*LAYER_NAMES, "missing"],
            "per_layer_accuracy": list(self.per_layer_accuracy),
            "top_precision": self.top_precision,
            "top_recall": self.top_recall,
            "top_f1": self.top_f1,
        }

    def table(self) -> str:
        """Summary and confusion matrix as text."""
        summary = format_table(
            [
                {"metric": "layer accuracy", "value": self.accuracy},
                {"metric": "layer accuracy (pixel-weighted)", "value": self.weighted_accuracy},
                {"metric": "top-set precision (mean/view)", "value": self.top_precision},
                {"metric": "top-set recall (mean/view)", "value": self.top_recall},
                {"metric": "top-set F1 (mean/view)", "value": self.top_f1},
            ],
            ["metric", "value"],
            title=(
                f"Layout: {self.num_views} views, {self.num_objects} visible objects, "
                f"{self.num_missing} without prediction"
            ),
        )
        columns = ["GT layer", *LAYER_NAMES, "missing", "accuracy"]
        rows = []
        for g in range(NUM_LAYERS):
            row: dict[str, Any] = {"GT layer": f"{g} {LAYER_NAMES[g]}"}
            row.update(zip([*LAYER_NAMES, "missing"], self.confusion[g], strict=True))
            row["accuracy"] = self.per_layer_accuracy[g]
            rows.append(row)
        confusion = format_table(rows, columns, title="Confusion (rows GT, columns predicted)")
        return summary + "\n\n" + confusion


def _view_truth(ds: Dataset) -> dict[int, dict[int, tuple[int, int]]]:
    """image id -> {instance id: (GT layer, visible px)} over the visible objects."""
    out: dict[int, dict[int, tuple[int, int]]] = {}
    for s, v in selected_views(ds):
        view = ds.scene(s).view(v)
        inst = view.instances
        n = view.num_instances
        px = np.bincount(inst.reshape(-1), minlength=n + 1)[1 : n + 1]
        order = view.order
        objs: dict[int, tuple[int, int]] = {}
        for i in range(n):
            if px[i] == 0:
                continue
            entry = order.get(str(i + 1))
            if not isinstance(entry, Mapping) or "layer" not in entry:
                raise InvalidArgumentError(
                    f"evaluate_layout: {view.path('_order.json')} has no layer for visible "
                    f"instance {i + 1} (was the layout labelled?)"
                )
            objs[i + 1] = (int(entry["layer"]), int(px[i]))
        out[s * 1000 + v] = objs
    return out


def ground_truth_layout(dataset: Dataset | str | os.PathLike[str]) -> list[dict[str, int]]:
    """The GT layers of the visible objects of the evaluated views, as predictions."""
    truth = _view_truth(as_dataset(dataset))
    return [
        {"image_id": img, "instance_id": iid, "layer": layer}
        for img, objs in truth.items()
        for iid, (layer, _) in objs.items()
    ]


def _num_instances(ds: Dataset, image_id: int) -> int:
    return ds.scene(image_id // 1000).view(image_id % 1000).num_instances


def _predicted_layers(
    ds: Dataset, preds: Sequence[Any], truth: Mapping[int, Any]
) -> dict[tuple[int, int], int]:
    """The checked predictions of :func:`evaluate_layout`: (image id, instance id) -> layer."""
    counts: dict[int, int] = {}
    predicted: dict[tuple[int, int], int] = {}
    unknown_images: list[int] = []
    for k, p in enumerate(preds):
        where = f"evaluate_layout: prediction {k}"
        if not isinstance(p, Mapping):
            raise InvalidArgumentError(f"{where}: expected a dict, got {type(p).__name__}")
        for key in ("image_id", "instance_id", "layer"):
            if key not in p:
                raise InvalidArgumentError(f"{where}: missing '{key}' (keys: {sorted(p)})")
            if not is_int(p[key]):
                raise InvalidArgumentError(f"{where}: {key} must be an integer, got {p[key]!r}")
        img, iid, layer = int(p["image_id"]), int(p["instance_id"]), int(p["layer"])
        if img not in truth:
            unknown_images.append(img)
            continue
        if img not in counts:
            counts[img] = _num_instances(ds, img)
        if not 1 <= iid <= counts[img]:
            raise InvalidArgumentError(
                f"{where}: image {img} has instance ids 1..{counts[img]}, got {iid}"
            )
        if not 0 <= layer < NUM_LAYERS:
            raise InvalidArgumentError(f"{where}: layer must be 0..3, got {layer}")
        if (img, iid) in predicted:
            raise InvalidArgumentError(
                f"{where}: a second prediction for image {img} instance {iid}"
            )
        predicted[(img, iid)] = layer
    if unknown_images:
        names = sorted(set(unknown_images))
        raise InvalidArgumentError(
            f"evaluate_layout: predictions name images that are not evaluated (image_id = "
            f"scene * 1000 + view, only the dataset's selection): {names[:_MAX_REPORTED]}; "
            f"evaluated ids: {sorted(truth)[:_MAX_REPORTED]}..."
        )
    return predicted


def evaluate_layout(
    dataset: Dataset | str | os.PathLike[str],
    predictions: Sequence[Mapping[str, Any]] | str | os.PathLike[str],
) -> LayoutResults:
    """Score layer predictions (module docstring) against ``dataset``'s layout labels.

    Raises:
        IoError: a missing or unreadable predictions file.
        InvalidArgumentError: a malformed prediction, an image that is not evaluated, an
            instance id the view does not have, or two predictions for one object (each error
            names the prediction index and the value).
    """
    ds = as_dataset(dataset)
    preds = as_prediction_list(predictions, "evaluate_layout: predictions")
    truth = _view_truth(ds)
    predicted = _predicted_layers(ds, preds, truth)

    confusion = np.zeros((NUM_LAYERS, NUM_LAYERS + 1), np.int64)
    correct_w = total_w = 0
    precisions, recalls, f1s = [], [], []
    for img, objs in truth.items():
        if not objs:
            continue
        top_true, top_pred = set(), set()
        for iid, (layer, px) in objs.items():
            pred = predicted.get((img, iid))
            confusion[layer, NUM_LAYERS if pred is None else pred] += 1
            total_w += px
            if pred == layer:
                correct_w += px
            if layer == 0:
                top_true.add(iid)
            if pred == 0:
                top_pred.add(iid)
        hit = len(top_true & top_pred)
        prec = hit / len(top_pred) if top_pred else float(not top_true)
        rec = hit / len(top_true) if top_true else float(not top_pred)
        precisions.append(prec)
        recalls.append(rec)
        f1s.append(2 * prec * rec / (prec + rec) if prec + rec > 0 else 0.0)

    num_objects = int(confusion.sum())
    diag = int(np.trace(confusion[:, :NUM_LAYERS]))
    rows = confusion.sum(axis=1)
    return LayoutResults(
        num_views=len(truth),
        num_objects=num_objects,
        num_missing=int(confusion[:, NUM_LAYERS].sum()),
        accuracy=diag / num_objects if num_objects else None,
        weighted_accuracy=correct_w / total_w if total_w else None,
        confusion=tuple(tuple(int(x) for x in r) for r in confusion),
        per_layer_accuracy=tuple(
            float(confusion[g, g] / rows[g]) if rows[g] else None for g in range(NUM_LAYERS)
        ),
        top_precision=float(np.mean(precisions)) if precisions else None,
        top_recall=float(np.mean(recalls)) if recalls else None,
        top_f1=float(np.mean(f1s)) if f1s else None,
    )
