"""COCO export of a dataset (docs/format.md "COCO export"), made with pycocotools.

One ``annotations.json`` per split: ``images`` (one per view; ``file_name`` relative to the dataset
root), ``categories`` (the object classes, or the single class "object" when class-agnostic), and
``annotations`` (one per instance visible in a view) with the visible ``segmentation`` (RLE),
``bbox`` (visible, [x, y, w, h] px), ``area``, ``iscrowd`` 0, and mgn's fields:
``amodal_segmentation`` (RLE), ``amodal_bbox``, ``occlusion``, ``layer``, ``instance_id``,
``scene_id``, ``view_id``; images carry ``difficulty`` (1–5, when the layout was labelled).
Image ids are ``scene_id * 1000 + view_id``.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from mgn.io.atomic import atomic_write_text
from mgn.io.dataset import Dataset, View

__all__ = ["coco_dict", "export_coco", "rle"]

#: Category id of the class-agnostic mode.
AGNOSTIC_ID = 1


def rle(mask: np.ndarray) -> dict[str, Any]:
    """COCO RLE of an (H, W) bool mask, JSON-ready (``counts`` as str)."""
    from pycocotools import mask as mask_utils

    r = mask_utils.encode(np.asfortranarray(np.asarray(mask, np.uint8)))
    return {"size": [int(r["size"][0]), int(r["size"][1])], "counts": r["counts"].decode("ascii")}


def _bbox(mask: np.ndarray) -> list[float]:
    ys, xs = np.nonzero(mask)
    if len(xs) == 0:
        return [0.0, 0.0, 0.0, 0.0]
    x0, y0 = int(xs.min()), int(ys.min())
    return [float(x0), float(y0), float(xs.max() - x0 + 1), float(ys.max() - y0 + 1)]


def _difficulty(view: View) -> int | None:
    layout = view.layout
    if not layout:
        return None
    d = layout.get("difficulty")
    if isinstance(d, dict):
        d = d.get("level")
    return None if d is None else int(d)


def _category_names(ds: Dataset) -> dict[int, str]:
    names: dict[int, str] = {}
    for scene in ds.scenes():
        for inst in (scene.scene_json or {}).get("instances", []):
            names.setdefault(int(inst["category_id"]), str(inst["name"]))
    return names


def coco_dict(
    ds: Dataset, *, scenes: Iterable[int] | None = None, class_agnostic: bool = False
) -> dict[str, Any]:
    """The COCO dictionary of the given scenes (default: all) of ``ds``."""
    scene_ids = ds.scene_ids if scenes is None else list(scenes)
    names = _category_names(ds)
    images: list[dict[str, Any]] = []
    anns: list[dict[str, Any]] = []
    seen_categories: set[int] = set()
    for sid in scene_ids:
        scene = ds.scene(sid)
        for view in scene.views():
            inst = view.instances
            amodal = view.amodal
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
            images.append(image)
            categories = view.hdf5["objects/categories"].astype(np.int64).reshape(-1)
            order = view.order
            for i in range(amodal.shape[0]):
                visible = inst == i + 1
                area = int(visible.sum())
                if area == 0:
                    continue
                cat = AGNOSTIC_ID if class_agnostic else int(categories[i])
                seen_categories.add(cat)
                entry = order.get(str(i + 1), {})
                a = amodal[i]
                anns.append({
                    "id": len(anns) + 1,
                    "image_id": image_id,
                    "category_id": cat,
                    "segmentation": rle(visible),
                    "bbox": _bbox(visible),
                    "area": float(area),
                    "iscrowd": 0,
                    "amodal_segmentation": rle(a),
                    "amodal_bbox": _bbox(a),
                    "amodal_area": float(a.sum()),
                    "occlusion": float(entry.get("occlusion", 1.0 - area / max(int(a.sum()), 1))),
                    "layer": int(entry["layer"]) if "layer" in entry else None,
                    "instance_id": i + 1,
                    "scene_id": sid,
                    "view_id": view.index,
                })  # fmt: skip
    if class_agnostic:
        categories_out = [{"id": AGNOSTIC_ID, "name": "object", "supercategory": "object"}]
    else:
        categories_out = [
            {"id": c, "name": names.get(c, f"category_{c}"), "supercategory": "object"}
            for c in sorted(seen_categories | set(names))
        ]
    return {
        "info": {"description": "mgn dataset", "version": str((ds.info or {}).get("mgn_version"))},
        "images": images,
        "annotations": anns,
        "categories": categories_out,
    }


def export_coco(
    ds: Dataset | str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    scenes: Iterable[int] | None = None,
    class_agnostic: bool = False,
) -> Path:
    """Write the COCO ``annotations.json`` of ``ds`` to ``out`` (atomically); returns the path."""
    d = ds if isinstance(ds, Dataset) else Dataset(ds)
    data = coco_dict(d, scenes=scenes, class_agnostic=class_agnostic)
    path = Path(out)
    atomic_write_text(path, json.dumps(data))
    return path
