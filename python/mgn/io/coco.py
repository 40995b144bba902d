"""COCO export of a dataset (docs/format.md "COCO export"), made with pycocotools.

One ``annotations.json`` per split: ``images`` (one per view; ``file_name`` relative to the dataset
root), ``categories`` (the object classes, or the single class "object" when class-agnostic), and
``annotations`` (one per instance visible in a view) with the visible ``segmentation`` (RLE),
``bbox`` (visible, [x, y, w, h] px), ``area``, ``iscrowd`` 0, and mgn's fields:
``amodal_segmentation`` (RLE), ``amodal_bbox``, ``occlusion``, ``layer``, ``instance_id``,
``scene_id``, ``view_id``; images carry ``difficulty`` (1–5, when the layout was labelled).
Image ids are ``scene_id * 1000 + view_id``.

Streaming: :func:`export_coco` reads one view at a time (only the two npz arrays it needs and the
categories of the HDF5 file) and writes its annotations to the output as it goes, so memory does
not grow with the dataset; the file is byte-identical to ``json.dumps(coco_dict(...))``.
The runs of the masks are found without building one image per mask (visible: one pass over
the instance image; amodal: inside each mask's box); pycocotools compresses them.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import IO, Any

import numpy as np
from pycocotools import mask as mask_utils

from mgn.base.atomic import atomic_open
from mgn.io.dataset import Dataset, View

__all__ = ["coco_dict", "export_coco", "iter_coco_views", "rle"]

#: Category id of the class-agnostic mode.
AGNOSTIC_ID = 1


def rle(mask: np.ndarray) -> dict[str, Any]:
    """COCO RLE of an (H, W) bool mask, JSON-ready (``counts`` as str)."""

    r = mask_utils.encode(np.asfortranarray(np.asarray(mask, np.uint8)))
    return {"size": [int(r["size"][0]), int(r["size"][1])], "counts": r["counts"].decode("ascii")}


def _compress(counts: list[list[int]], h: int, w: int) -> list[dict[str, Any]]:
    """JSON-ready compressed RLEs from uncompressed COCO counts (pycocotools' string form)."""

    if not counts:
        return []
    enc = mask_utils.frPyObjects([{"counts": c, "size": [h, w]} for c in counts], h, w)
    return [{"size": [h, w], "counts": r["counts"].decode("ascii")} for r in enc]


def _counts(starts: np.ndarray, ends: np.ndarray, total: int) -> list[int]:
    """COCO counts (zeros first, alternating) of the runs [starts, ends) of ones, ascending and
    not touching, in a mask of ``total`` pixels (column-major order)."""
    edges = np.empty(2 * len(starts) + 2, np.int64)
    edges[0] = 0
    edges[1:-1:2] = starts
    edges[2:-1:2] = ends
    edges[-1] = total
    counts: list[int] = np.diff(edges).tolist()
    if len(counts) > 1 and counts[-1] == 0:
        counts.pop()  # ends with ones: no trailing zero run (as pycocotools writes it)
    return counts


def _runs_of_mask(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, tuple[float, ...], int]:
    """Column-major runs of ones of an (H, W) bool mask, read only inside its bounding box:
    (starts, ends, COCO box, area)."""
    h, _w = mask.shape
    cols = np.flatnonzero(mask.any(axis=0))
    if len(cols) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), (0.0, 0.0, 0.0, 0.0), 0
    rows = np.flatnonzero(mask[:, cols[0] : cols[-1] + 1].any(axis=1))
    x0, x1, y0, y1 = int(cols[0]), int(cols[-1]), int(rows[0]), int(rows[-1])
    crop = mask[y0 : y1 + 1, x0 : x1 + 1].T  # (columns, rows of the box)
    padded = np.zeros((crop.shape[0], crop.shape[1] + 2), np.int8)
    padded[:, 1:-1] = crop
    d = np.diff(padded, axis=1)
    cs, rs = np.nonzero(d == 1)
    ce, re = np.nonzero(d == -1)
    starts = (x0 + cs) * h + y0 + rs
    ends = (x0 + ce) * h + y0 + re
    # A run reaching the last row continues at the top of the next column when the box spans
    # every row: merge runs that touch.
    if len(starts) > 1:
        touch = starts[1:] == ends[:-1]
        if touch.any():
            keep_start = np.concatenate([[True], ~touch])
            keep_end = np.concatenate([~touch, [True]])
            starts, ends = starts[keep_start], ends[keep_end]
    area = int((ends - starts).sum())
    return starts, ends, (float(x0), float(y0), float(x1 - x0 + 1), float(y1 - y0 + 1)), area


def _visible_runs(ids: np.ndarray, wanted: np.ndarray) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Column-major runs [start, end) of every id in ``wanted`` of an (H, W) id image, from one
    pass over the image."""
    flat = np.ascontiguousarray(ids.T).reshape(-1)
    change = np.flatnonzero(flat[1:] != flat[:-1]) + 1
    starts = np.concatenate([[0], change])
    ends = np.concatenate([change, [flat.size]])
    values = flat[starts]
    out = {}
    for k in wanted.tolist():
        sel = values == k
        out[k] = (starts[sel], ends[sel])
    return out


def _box_of_runs(starts: np.ndarray, ends: np.ndarray, h: int) -> tuple[float, ...]:
    """COCO box of a mask given by its column-major runs (a run may continue from the last row
    of one column to the first row of the next: it then covers every row)."""
    xs0, xs1 = starts // h, (ends - 1) // h
    x0, x1 = int(xs0.min()), int(xs1.max())
    span = xs1 > xs0
    y0 = 0 if span.any() else int((starts % h).min())
    y1 = h - 1 if span.any() else int(((ends - 1) % h).max())
    return (float(x0), float(y0), float(x1 - x0 + 1), float(y1 - y0 + 1))


def _box(b: Any) -> list[float]:
    return [float(b[0]), float(b[1]), float(b[2]), float(b[3])]


def _difficulty(view: View) -> int | None:
    layout = view.layout
    if not layout:
        return None
    d = layout.get("difficulty")
    if isinstance(d, dict):
        d = d.get("level")
    return None if d is None else int(d)


def _category_names(ds: Dataset, scene_ids: Iterable[int] | None = None) -> dict[int, str]:
    names: dict[int, str] = {}
    scenes = ds.scenes() if scene_ids is None else [ds.scene(s) for s in scene_ids]
    for scene in scenes:
        for inst in (scene.scene_json or {}).get("instances", []):
            names.setdefault(int(inst["category_id"]), str(inst["name"]))
    return names


def _view_entries(
    sid: int, view: View, class_agnostic: bool
) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The image entry and the annotations (ids not yet set) of one view."""
    inst = view.npz_array("instances_objects")
    amodal = view.npz_array("occlusion_objects")
    h, w = inst.shape
    image_id = sid * 1000 + view.index
    image: dict[str, Any] = {
        "id": image_id,
        "file_name": f"scene{sid}/{view.index}_rgb.png",
        "width": int(w),
        "height": int(h),
        "scene_id": sid,
        "view_id": view.index,
    }
    level = _difficulty(view)
    if level is not None:
        image["difficulty"] = level
    n = amodal.shape[0]
    present = np.bincount(inst.reshape(-1).astype(np.int64), minlength=n + 1)[1 : n + 1] > 0
    visible_ids = np.flatnonzero(present) + 1  # instance ids with at least one visible pixel
    if len(visible_ids) == 0:
        return image, []
    vis_runs = _visible_runs(inst, visible_ids)
    vis_counts, vis_area, vis_box = [], [], []
    for iid in visible_ids.tolist():
        st, en = vis_runs[iid]
        vis_counts.append(_counts(st, en, h * w))
        vis_area.append(int((en - st).sum()))
        vis_box.append(_box_of_runs(st, en, h))
    am_counts, am_area, am_box = [], [], []
    for iid in visible_ids.tolist():
        st, en, box, area = _runs_of_mask(np.asarray(amodal[iid - 1], bool))
        am_counts.append(_counts(st, en, h * w))
        am_area.append(area)
        am_box.append(box)
    vis_rle = _compress(vis_counts, h, w)
    am_rle = _compress(am_counts, h, w)
    categories = view.hdf5_dataset("objects/categories").astype(np.int64).reshape(-1)
    order = view.order
    anns: list[dict[str, Any]] = []
    for j, iid in enumerate(visible_ids.tolist()):
        area = int(vis_area[j])
        a_area = int(am_area[j])
        cat = AGNOSTIC_ID if class_agnostic else int(categories[iid - 1])
        entry = order.get(str(iid), {})
        anns.append(
            {
                "id": 0,
                "image_id": image_id,
                "category_id": cat,
                "segmentation": vis_rle[j],
                "bbox": _box(vis_box[j]),
                "area": float(area),
                "iscrowd": 0,
                "amodal_segmentation": am_rle[j],
                "amodal_bbox": _box(am_box[j]),
                "amodal_area": float(a_area),
                "occlusion": float(entry.get("occlusion", 1.0 - area / max(a_area, 1))),
                "layer": int(entry["layer"]) if "layer" in entry else None,
                "instance_id": iid,
                "scene_id": sid,
                "view_id": view.index,
            }
        )
    return image, anns


def iter_coco_views(
    ds: Dataset, *, scenes: Iterable[int] | None = None, class_agnostic: bool = False
) -> Iterator[tuple[dict[str, Any], list[dict[str, Any]]]]:
    """(image, annotations) of every view of the given scenes (default: all), one view at a
    time, in scene then view order; annotation ids are numbered from 1 across the views."""
    scene_ids = ds.scene_ids if scenes is None else list(scenes)
    next_id = 1
    for sid in scene_ids:
        scene = ds.scene(sid)
        for v in scene.view_ids:
            image, anns = _view_entries(sid, View(scene.folder, v), class_agnostic)
            for a in anns:
                a["id"] = next_id
                next_id += 1
            yield image, anns


def _categories(
    names: dict[int, str], seen: set[int], class_agnostic: bool
) -> list[dict[str, Any]]:
    if class_agnostic:
        return [{"id": AGNOSTIC_ID, "name": "object", "supercategory": "object"}]
    return [
        {"id": c, "name": names.get(c, f"category_{c}"), "supercategory": "object"}
        for c in sorted(seen | set(names))
    ]


def _info(ds: Dataset) -> dict[str, Any]:
    return {"description": "mgn dataset", "version": str((ds.info or {}).get("mgn_version"))}


def coco_dict(
    ds: Dataset, *, scenes: Iterable[int] | None = None, class_agnostic: bool = False
) -> dict[str, Any]:
    """The COCO dictionary of the given scenes (default: all) of ``ds``."""
    scene_ids = ds.scene_ids if scenes is None else list(scenes)
    images: list[dict[str, Any]] = []
    anns: list[dict[str, Any]] = []
    for image, view_anns in iter_coco_views(ds, scenes=scene_ids, class_agnostic=class_agnostic):
        images.append(image)
        anns.extend(view_anns)
    seen = {a["category_id"] for a in anns}
    return {
        "info": _info(ds),
        "images": images,
        "annotations": anns,
        "categories": _categories(_category_names(ds), seen, class_agnostic),
    }


def _write_coco(fh: IO[str], ds: Dataset, scene_ids: list[int], class_agnostic: bool) -> None:
    """``json.dumps(coco_dict(...))`` written piece by piece: the annotations go to ``fh`` as
    each view is done; the image entries (a few hundred bytes per view) are kept until the end.
    """
    dumps = json.dumps
    images: list[dict[str, Any]] = []
    seen: set[int] = set()
    # The key order of coco_dict is info, images, annotations, categories; the images are only
    # known at the end, so the annotations are spooled and the parts joined afterwards.

    with tempfile.TemporaryFile("w+", encoding="utf-8") as spool:
        first = True
        for image, anns in iter_coco_views(ds, scenes=scene_ids, class_agnostic=class_agnostic):
            images.append(image)
            for a in anns:
                seen.add(a["category_id"])
                spool.write(dumps(a) if first else ", " + dumps(a))
                first = False
        fh.write('{"info": ' + dumps(_info(ds)) + ', "images": ' + dumps(images))
        fh.write(', "annotations": [')
        spool.seek(0)
        while chunk := spool.read(1 << 20):
            fh.write(chunk)
        cats = _categories(_category_names(ds), seen, class_agnostic)
        fh.write('], "categories": ' + dumps(cats) + "}")


def export_coco(
    ds: Dataset | str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    scenes: Iterable[int] | None = None,
    class_agnostic: bool = False,
) -> Path:
    """Write the COCO ``annotations.json`` of ``ds`` to ``out`` (atomically, streaming one view
    at a time); returns the path."""
    d = ds if isinstance(ds, Dataset) else Dataset(ds)
    scene_ids = d.scene_ids if scenes is None else list(scenes)
    path = Path(out)
    with atomic_open(path) as fh:
        _write_coco(fh, d, scene_ids, class_agnostic)
    return path
