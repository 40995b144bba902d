"""The streaming COCO export equals the export built view by view with one pycocotools call per
mask (the algorithm mgn used before streaming, written out here as the reference)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mgn.io.coco import coco_dict, export_coco
from mgn.io.dataset import Dataset


def _rle(mask: np.ndarray) -> dict[str, Any]:
    from pycocotools import mask as mask_utils

    r = mask_utils.encode(np.asfortranarray(mask.astype(np.uint8)))
    return {"size": [int(r["size"][0]), int(r["size"][1])], "counts": r["counts"].decode("ascii")}


def _bbox(mask: np.ndarray) -> list[float]:
    ys, xs = np.nonzero(mask)
    if len(xs) == 0:
        return [0.0, 0.0, 0.0, 0.0]
    x0, y0 = int(xs.min()), int(ys.min())
    return [float(x0), float(y0), float(xs.max() - x0 + 1), float(ys.max() - y0 + 1)]


def reference_coco(ds: Dataset, class_agnostic: bool = False) -> dict[str, Any]:
    """Whole views in memory, one instance at a time, every mask encoded on its own."""
    names: dict[int, str] = {}
    for scene in ds.scenes():
        for inst in (scene.scene_json or {}).get("instances", []):
            names.setdefault(int(inst["category_id"]), str(inst["name"]))
    images, anns, seen = [], [], set()
    for sid in ds.scene_ids:
        for view in ds.scene(sid).views():
            inst, amodal = view.instances, view.amodal
            h, w = inst.shape
            image = {
                "id": sid * 1000 + view.index,
                "file_name": f"scene{sid}/{view.index}_rgb.png",
                "width": w,
                "height": h,
                "scene_id": sid,
                "view_id": view.index,
            }
            d = (view.layout or {}).get("difficulty")
            d = d.get("level") if isinstance(d, dict) else d
            if d is not None:
                image["difficulty"] = int(d)
            images.append(image)
            cats = view.hdf5["objects/categories"].astype(np.int64).reshape(-1)
            for i in range(amodal.shape[0]):
                vis = inst == i + 1
                if not vis.any():
                    continue
                cat = 1 if class_agnostic else int(cats[i])
                seen.add(cat)
                entry = view.order.get(str(i + 1), {})
                a = amodal[i]
                anns.append(
                    {
                        "id": len(anns) + 1,
                        "image_id": image["id"],
                        "category_id": cat,
                        "segmentation": _rle(vis),
                        "bbox": _bbox(vis),
                        "area": float(vis.sum()),
                        "iscrowd": 0,
                        "amodal_segmentation": _rle(a),
                        "amodal_bbox": _bbox(a),
                        "amodal_area": float(a.sum()),
                        "occlusion": float(entry.get("occlusion", 1 - vis.sum() / max(a.sum(), 1))),
                        "layer": int(entry["layer"]) if "layer" in entry else None,
                        "instance_id": i + 1,
                        "scene_id": sid,
                        "view_id": view.index,
                    }
                )
    if class_agnostic:
        categories = [{"id": 1, "name": "object", "supercategory": "object"}]
    else:
        categories = [
            {"id": c, "name": names.get(c, f"category_{c}"), "supercategory": "object"}
            for c in sorted(seen | set(names))
        ]
    info = {"description": "mgn dataset", "version": str((ds.info or {}).get("mgn_version"))}
    return {"info": info, "images": images, "annotations": anns, "categories": categories}


@pytest.mark.parametrize("agnostic", [False, True])
def test_streaming_coco_equals_the_reference(small_dataset: Path, tmp_path: Path, agnostic: bool):
    ds = Dataset(small_dataset)
    ref = reference_coco(ds, agnostic)
    assert len(ref["annotations"]) > 10  # the comparison covers real, partly hidden objects
    assert any(a["area"] < a["amodal_area"] for a in ref["annotations"])
    path = export_coco(small_dataset, tmp_path / "a.json", class_agnostic=agnostic)
    # Byte for byte what json.dumps gives for the reference dictionary.
    assert path.read_text() == json.dumps(ref)
    assert coco_dict(Dataset(small_dataset), class_agnostic=agnostic) == ref


def test_run_length_helpers_match_pycocotools_on_border_cases():
    """Masks touching the first and last rows (runs that continue into the next column), full
    columns, single pixels, empty masks: RLE, box and area equal pycocotools / numpy's."""
    from mgn.io.coco import _box_of_runs, _compress, _counts, _runs_of_mask, _visible_runs

    rng = np.random.default_rng(5)
    h, w = 9, 7
    ids = rng.integers(0, 4, size=(h, w))
    ids[:, 2] = 3  # a full column: its run continues from the columns around it
    ids[-1, 4], ids[0, 5] = 2, 2  # last row of one column, first row of the next
    masks = [ids == k for k in range(1, 4)]
    masks += [np.zeros((h, w), bool), np.ones((h, w), bool)]
    single = np.zeros((h, w), bool)
    single[h - 1, 0] = True
    masks.append(single)
    runs = _visible_runs(ids, np.arange(1, 4))
    for k, m in enumerate(masks):
        st, en, box, area = _runs_of_mask(m)
        assert _compress([_counts(st, en, h * w)], h, w)[0] == _rle(m)
        assert list(box) == _bbox(m)
        assert area == int(m.sum())
        if k < 3:
            vs, ve = runs[k + 1]
            assert _compress([_counts(vs, ve, h * w)], h, w)[0] == _rle(m)
            assert list(_box_of_runs(vs, ve, h)) == _bbox(m)
