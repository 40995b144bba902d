"""mgn eval detections: AP against hand-computed values on a hand-built dataset, against plain
pycocotools on the generated small dataset, and the errors of bad input."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import h5py
import numpy as np
import pytest
from PIL import Image

from mgn.errors import InvalidArgumentError, IoError
from mgn.eval import evaluate_detections, ground_truth_detections
from mgn.io.coco import coco_dict, rle
from mgn.io.dataset import Dataset

H, W = 24, 40


def rect(y0: int, y1: int, x0: int, x1: int) -> np.ndarray:
    m = np.zeros((H, W), bool)
    m[y0:y1, x0:x1] = True
    return m


def write_tiny_view(folder: Path, v: int, objects: list[dict], difficulty: int) -> None:
    """Write the files the reader needs for one view. ``objects``: dicts with ``category``,
    ``amodal`` and ``visible`` (H, W) masks, ``occlusion`` and ``layer``."""
    folder.mkdir(parents=True, exist_ok=True)
    n = len(objects)
    inst = np.zeros((H, W), np.float32)
    for i, o in enumerate(objects):
        inst[o["visible"]] = i + 1
    amodal = np.stack([o["amodal"] for o in objects]) if n else np.zeros((0, H, W), bool)
    np.savez_compressed(folder / f"{v}.npz", instances_objects=inst, occlusion_objects=amodal)
    Image.fromarray(np.zeros((H, W, 3), np.uint8)).save(folder / f"{v}_rgb.png")
    with h5py.File(folder / f"{v}_scene.hdf5", "w") as h5:
        h5["objects/categories"] = np.array([o["category"] for o in objects], np.float32)
    order = {
        str(i + 1): {"id": i + 1, "occlusion": o["occlusion"], "layer": o["layer"]}
        for i, o in enumerate(objects)
    }
    (folder / f"{v}_order.json").write_text(json.dumps(order))
    (folder / f"{v}_layout.json").write_text(json.dumps({"difficulty": difficulty}))


def write_info(root: Path, info: dict) -> None:
    (root / "dataset.json").write_text(json.dumps(info))


def obj(
    category: int,
    visible: np.ndarray,
    amodal: np.ndarray | None = None,
    *,
    occlusion: float | None = None,
    layer: int = 0,
) -> dict:
    a = visible if amodal is None else amodal | visible
    occ = 1.0 - visible.sum() / a.sum() if occlusion is None else occlusion
    return {"category": category, "visible": visible, "amodal": a, "occlusion": occ, "layer": layer}


# Scene 0 view 0 (image 0), difficulty 4: two objects of category 1; the second is 36 %
# occluded (amodal 10 x 10, visible 8 x 8: visible/amodal IoU 0.64).
VIEW0 = [
    obj(1, rect(1, 7, 1, 11)),
    obj(1, rect(12, 20, 20, 28), rect(12, 22, 20, 30), layer=1),
]
# Scene 0 view 1 (image 1), difficulty 2: categories 1, 2, 3 (3 unseen), occlusion 0.0 / 0.1 /
# 0.8 (the values are the labels read; 0.1 sits on a bin edge).
VIEW1 = [
    obj(1, rect(1, 6, 1, 6), occlusion=0.0),
    obj(2, rect(8, 14, 8, 20), occlusion=0.1, layer=1),
    obj(3, rect(16, 22, 24, 38), occlusion=0.8, layer=2),
]


@pytest.fixture
def tiny(tmp_path: Path) -> Path:
    root = tmp_path / "tiny"
    write_tiny_view(root / "scene0", 0, VIEW0, difficulty=4)
    write_tiny_view(root / "scene0", 1, VIEW1, difficulty=2)
    write_info(root, {"split": {"name": "test", "unseen_categories": [3], "unseen_names": ["x"]}})
    return root


def only_view(root: Path, view: int) -> None:
    info = json.loads((root / "dataset.json").read_text())
    info["selection"] = {"views": [{"scene": 0, "view": view, "difficulty": 1}]}
    write_info(root, info)


def det(image_id: int, category: int, mask: np.ndarray, score: float) -> dict:
    ys, xs = np.nonzero(mask)
    box = [float(xs.min()), float(ys.min()), float(np.ptp(xs) + 1), float(np.ptp(ys) + 1)]
    return {
        "image_id": image_id,
        "category_id": category,
        "bbox": box,
        "segmentation": rle(mask),
        "score": score,
    }


def interpolated_ap(is_tp: list[bool], num_gt: int) -> float:
    """101-point interpolated AP of a ranked list (best score first), from its precision/recall
    curve: precision made non-increasing, then read at the first rank reaching each recall."""
    tp = np.cumsum(is_tp)
    precision = tp / np.arange(1, len(is_tp) + 1)
    recall = tp / num_gt
    total = 0.0
    for r in np.linspace(0, 1, 101):
        reach = [precision[k:].max() for k in range(len(is_tp)) if recall[k] >= r - 1e-12]
        total += reach[0] if reach else 0.0
    return total / 101


def test_interpolated_ap_reference() -> None:
    assert interpolated_ap([True, True], 2) == pytest.approx(1.0)
    assert interpolated_ap([True], 2) == pytest.approx(51 / 101)
    assert interpolated_ap([False, True, True], 2) == pytest.approx(2 / 3)


def test_ground_truth_scores_one(tiny: Path) -> None:
    for agnostic in (False, True):
        for amodal in (False, True):
            gt = ground_truth_detections(tiny, amodal=amodal, class_agnostic=agnostic)
            assert len(gt) == 5
            res = evaluate_detections(tiny, gt, amodal=amodal, class_agnostic=agnostic)
            r = res.overall
            assert (r.box_ap, r.box_ap50, r.box_ap75) == (1.0, 1.0, 1.0)
            assert (r.seg_ap, r.seg_ap50, r.seg_ap75) == (1.0, 1.0, 1.0)
            assert (r.num_images, r.num_gt) == (2, 5)


def test_missing_detection_gives_hand_computed_ap(tiny: Path) -> None:
    only_view(tiny, 0)
    preds = [det(0, 1, VIEW0[0]["visible"], 0.9)]
    r = evaluate_detections(tiny, preds).overall
    assert r.num_images == 1
    assert r.num_gt == 2
    expected = interpolated_ap([True], 2)
    assert expected == pytest.approx(51 / 101)
    for value in (r.box_ap, r.box_ap50, r.box_ap75, r.seg_ap, r.seg_ap50, r.seg_ap75):
        assert value == pytest.approx(expected)


def test_false_positive_ranking(tiny: Path) -> None:
    only_view(tiny, 0)
    tps = [det(0, 1, VIEW0[0]["visible"], 0.8), det(0, 1, VIEW0[1]["visible"], 0.7)]
    fp_mask = rect(14, 20, 2, 10)  # overlaps no object
    above = evaluate_detections(tiny, [det(0, 1, fp_mask, 0.9), *tps]).overall
    below = evaluate_detections(tiny, [det(0, 1, fp_mask, 0.1), *tps]).overall
    assert below.box_ap == pytest.approx(1.0)
    assert below.seg_ap == pytest.approx(1.0)
    expected = interpolated_ap([False, True, True], 2)
    assert expected == pytest.approx(2 / 3)
    assert above.box_ap == pytest.approx(expected)
    assert above.seg_ap == pytest.approx(expected)
    # a wrong category is a false positive too
    wrong = evaluate_detections(tiny, [{**tps[0], "category_id": 2}, tps[1]]).overall
    assert wrong.box_ap == pytest.approx(interpolated_ap([True], 2))


def test_amodal_masks_hand_computed(tiny: Path) -> None:
    only_view(tiny, 0)
    # visible masks scored against the amodal ones: object 0 is complete (IoU 1), object 1 has
    # IoU 64/100, a match at the thresholds 0.50, 0.55, 0.60 only.
    preds = [det(0, 1, VIEW0[0]["visible"], 0.9), det(0, 1, VIEW0[1]["visible"], 0.8)]
    r = evaluate_detections(tiny, preds, amodal=True).overall
    per_threshold = [1.0] * 3 + [interpolated_ap([True, False], 2)] * 7
    assert r.seg_ap == pytest.approx(np.mean(per_threshold))
    assert r.seg_ap50 == pytest.approx(1.0)
    assert r.seg_ap75 == pytest.approx(51 / 101)
    assert r.box_ap == pytest.approx(r.seg_ap)  # the boxes have the same IoUs here
    visible = evaluate_detections(tiny, preds).overall
    assert visible.seg_ap == pytest.approx(1.0)


def test_seen_unseen_split(tiny: Path) -> None:
    only_view(tiny, 1)
    unseen_only = [det(1, 3, VIEW1[2]["visible"], 0.9)]
    res = evaluate_detections(tiny, unseen_only)
    assert res.unseen_categories == (3,)
    assert res.row("split", "unseen").box_ap == pytest.approx(1.0)
    assert res.row("split", "seen").box_ap == pytest.approx(0.0)
    assert res.row("split", "seen").num_gt == 2
    assert res.row("split", "unseen").num_gt == 1
    # class-agnostic: the detection of the unseen object is ignored when scoring "seen"
    res = evaluate_detections(tiny, unseen_only, class_agnostic=True)
    assert res.row("split", "unseen").seg_ap == pytest.approx(1.0)
    assert res.row("split", "seen").seg_ap == pytest.approx(0.0)
    # all three found, the unseen one ranked first: seen AP stays 1 (it is neither TP nor FP);
    # had it counted as a false positive, seen AP would be 2/3
    preds = [
        det(1, 9, VIEW1[2]["visible"], 0.9),
        det(1, 9, VIEW1[0]["visible"], 0.8),
        det(1, 9, VIEW1[1]["visible"], 0.7),
    ]
    res = evaluate_detections(tiny, preds, class_agnostic=True)
    assert res.row("split", "seen").box_ap == pytest.approx(1.0)
    assert res.row("split", "unseen").box_ap == pytest.approx(1.0)
    # a detection on nothing stays a false positive in both subsets
    fp = det(1, 9, rect(18, 23, 1, 8), 0.95)
    res = evaluate_detections(tiny, [fp, *preds], class_agnostic=True)
    assert res.row("split", "seen").box_ap == pytest.approx(interpolated_ap([False, True, True], 2))
    assert res.row("split", "unseen").box_ap == pytest.approx(interpolated_ap([False, True], 1))
    # the unseen set can be given explicitly; with none, "unseen" is empty
    res = evaluate_detections(tiny, unseen_only, unseen_categories=[])
    assert res.row("split", "unseen").box_ap is None
    assert res.row("split", "unseen").num_gt == 0
    # every object seen now: per-category AP 0, 0, 1 (categories 1, 2, 3), averaged
    per_category = [0.0, 0.0, interpolated_ap([True], 1)]
    assert res.row("split", "seen").box_ap == pytest.approx(np.mean(per_category))


def test_occlusion_bins(tiny: Path) -> None:
    only_view(tiny, 1)
    res = evaluate_detections(tiny, [det(1, 2, VIEW1[1]["visible"], 0.9)])
    bins = {r.subset: r for r in res.rows if r.group == "occlusion"}
    assert list(bins) == ["[0, 0.1)", "[0.1, 0.3)", "[0.3, 0.5)", "[0.5, 0.7)", "[0.7, 1]"]
    assert [b.num_gt for b in bins.values()] == [1, 1, 0, 0, 1]
    assert bins["[0.1, 0.3)"].box_ap == pytest.approx(1.0)  # 0.1 is in the upper bin
    assert bins["[0, 0.1)"].box_ap == pytest.approx(0.0)
    assert bins["[0.7, 1]"].seg_ap == pytest.approx(0.0)
    assert bins["[0.3, 0.5)"].box_ap is None
    assert bins["[0.5, 0.7)"].seg_ap is None
    table = res.table()
    assert "occlusion [0.3, 0.5)" in table
    assert " -" in table
    # custom bins; the last bin includes its upper edge
    res = evaluate_detections(
        tiny, [det(1, 3, VIEW1[2]["visible"], 0.9)], occlusion_bins=(0.0, 0.5, 0.8)
    )
    bins = {r.subset: r for r in res.rows if r.group == "occlusion"}
    assert bins["[0.5, 0.8]"].num_gt == 1
    assert bins["[0.5, 0.8]"].box_ap == pytest.approx(1.0)


def test_difficulty_rows_and_empty_cells(tiny: Path, tmp_path: Path) -> None:
    res = evaluate_detections(tiny, [det(1, c + 1, o["visible"], 0.9) for c, o in enumerate(VIEW1)])
    d = {r.subset: r for r in res.rows if r.group == "difficulty"}
    assert d["2"].box_ap == pytest.approx(1.0)
    assert d["2"].num_images == 1
    assert d["4"].box_ap == pytest.approx(0.0)
    assert d["4"].num_gt == 2
    assert d["1"].box_ap is None
    assert d["1"].num_images == 0
    doc = res.to_dict()
    row1 = next(r for r in doc["rows"] if r["group"] == "difficulty" and r["subset"] == "1")
    assert row1["box_ap"] is None
    assert row1["seg_ap"] is None
    # no predictions at all: AP 0 where there is GT
    empty = evaluate_detections(tiny, []).overall
    assert empty.box_ap == 0.0
    assert empty.seg_ap == 0.0
    # box-only predictions: mask AP cells are empty
    boxes = [
        {k: v for k, v in p.items() if k != "segmentation"} for p in ground_truth_detections(tiny)
    ]
    r = evaluate_detections(tiny, boxes).overall
    assert r.box_ap == pytest.approx(1.0)
    assert r.seg_ap is None


def test_selection_restricts_images(tiny: Path) -> None:
    gt = ground_truth_detections(tiny)
    only_view(tiny, 1)
    with pytest.raises(InvalidArgumentError, match=r"not evaluated.*\[0\]"):
        evaluate_detections(tiny, gt)
    res = evaluate_detections(tiny, gt, strict=False)
    assert res.num_dropped == 2
    assert res.num_images == 1
    assert res.overall.box_ap == pytest.approx(1.0)


def test_bad_inputs(tiny: Path, tmp_path: Path) -> None:
    gt = ground_truth_detections(tiny)
    with pytest.raises(IoError, match="does not exist"):
        evaluate_detections(tiny, tmp_path / "nope.json")
    bad = tmp_path / "bad.json"
    bad.write_text('[{"image_id": 0,')
    with pytest.raises(IoError, match="not valid JSON"):
        evaluate_detections(tiny, bad)
    bad.write_text('{"image_id": 0}')
    with pytest.raises(InvalidArgumentError, match="JSON list"):
        evaluate_detections(tiny, bad)
    with pytest.raises(InvalidArgumentError, match=r"\[7005\]"):
        evaluate_detections(tiny, [{**gt[0], "image_id": 7005}])
    with pytest.raises(InvalidArgumentError, match="prediction 1: bbox"):
        evaluate_detections(tiny, [gt[0], {**gt[1], "bbox": [1.0, float("nan"), 3.0, 4.0]}])
    bad.write_text(json.dumps([gt[0]]).replace("1.0}", "NaN}"))  # score NaN in the file
    with pytest.raises(InvalidArgumentError, match="prediction 0: score"):
        evaluate_detections(tiny, bad)
    with pytest.raises(InvalidArgumentError, match="missing 'score'"):
        evaluate_detections(tiny, [{k: v for k, v in gt[0].items() if k != "score"}])
    seg = dict(gt[0]["segmentation"])
    with pytest.raises(InvalidArgumentError, match="size"):
        evaluate_detections(tiny, [{**gt[0], "segmentation": {**seg, "size": [5, 5]}}])
    short = {**seg, "counts": seg["counts"][:-1]}
    with pytest.raises(InvalidArgumentError, match="not a valid RLE"):  # runs don't fill H x W
        evaluate_detections(tiny, [{**gt[0], "segmentation": short}])
    with pytest.raises(InvalidArgumentError, match="not a valid RLE"):
        evaluate_detections(tiny, [{**gt[0], "segmentation": {"size": [H, W], "counts": [5, 3]}}])
    with pytest.raises(InvalidArgumentError, match="give it for all"):
        evaluate_detections(tiny, [gt[0], {k: v for k, v in gt[1].items() if k != "segmentation"}])
    with pytest.raises(InvalidArgumentError, match="occlusion_bins"):
        evaluate_detections(tiny, gt, occlusion_bins=(0.5, 0.1))
    with pytest.raises(InvalidArgumentError, match="list of prediction"):
        evaluate_detections(tiny, {"image_id": 0})
    # uncompressed RLE (a list of runs) is accepted
    m = VIEW0[0]["visible"]
    runs = [int(x) for x in _runs(m)]
    ok = evaluate_detections(tiny, [{**gt[0], "segmentation": {"size": [H, W], "counts": runs}}])
    assert ok.overall.seg_ap is not None
    assert ok.overall.seg_ap > 0


def _runs(mask: np.ndarray) -> list[int]:
    """Uncompressed COCO RLE runs (column-major, starting with a background run)."""
    flat = mask.T.reshape(-1).astype(np.int8)
    edges = np.flatnonzero(np.diff(flat)) + 1
    bounds = np.concatenate([[0], edges, [flat.size]])
    runs = np.diff(bounds).tolist()
    return ([0] + runs) if flat[0] else runs


# --------------------------------------------------------------------------------------------
# The generated small dataset


def test_small_dataset_ground_truth(small_dataset: Path) -> None:
    for amodal in (False, True):
        gt = ground_truth_detections(small_dataset, amodal=amodal)
        assert gt
        res = evaluate_detections(small_dataset, gt, amodal=amodal)
        assert res.overall.box_ap == 1.0
        assert res.overall.seg_ap == 1.0
        assert res.num_images == 6
    res = evaluate_detections(
        small_dataset, ground_truth_detections(small_dataset), class_agnostic=True
    )
    assert res.overall.box_ap == 1.0
    assert res.overall.seg_ap == 1.0


def _perturbed(gt: list[dict], seed: int) -> list[dict]:
    """GT detections with shifted boxes, random scores, some dropped, some duplicated."""
    rng = np.random.default_rng(seed)
    out = []
    for g in gt:
        if rng.random() < 0.2:
            continue
        d = copy.deepcopy(g)
        d["bbox"] = [float(x) for x in np.asarray(g["bbox"]) + rng.normal(0, 1.5, 4)]
        d["bbox"][2], d["bbox"][3] = max(d["bbox"][2], 1.0), max(d["bbox"][3], 1.0)
        d["score"] = float(rng.random())
        out.append(d)
        if rng.random() < 0.2:
            out.append({**d, "score": float(rng.random())})
    return out


def _plain_cocoeval_ap(gt_dict: dict, dets: list[dict], iou_type: str, img_ids=None) -> float:
    import contextlib
    import io

    from pycocotools.coco import COCO
    from pycocotools.cocoeval import COCOeval

    with contextlib.redirect_stdout(io.StringIO()):
        gt = COCO()
        gt.dataset = copy.deepcopy(gt_dict)
        gt.createIndex()
        ev = COCOeval(gt, gt.loadRes(copy.deepcopy(dets)), iou_type)
        if img_ids is not None:
            ev.params.imgIds = img_ids
        ev.evaluate()
        ev.accumulate()
        ev.summarize()
    return float(ev.stats[0])


def test_small_dataset_matches_plain_cocoeval(small_dataset: Path) -> None:
    ds = Dataset(small_dataset)
    gt_dict = coco_dict(ds)
    dets = _perturbed(ground_truth_detections(ds), seed=3)
    res = evaluate_detections(ds, dets)
    for iou_type, value in (("bbox", res.overall.box_ap), ("segm", res.overall.seg_ap)):
        assert value == pytest.approx(_plain_cocoeval_ap(gt_dict, dets, iou_type), abs=1e-12)
    assert 0.2 < res.overall.box_ap < 0.95
    for r in res.rows:
        if r.group != "difficulty" or r.num_images == 0:
            continue
        ids = [im["id"] for im in gt_dict["images"] if im.get("difficulty") == int(r.subset)]
        assert r.box_ap == pytest.approx(_plain_cocoeval_ap(gt_dict, dets, "bbox", ids))
    # object subsets: pycocotools' own area-range ignore as the second implementation (GT
    # outside the subset get area -1, below the "all" range)
    checked = 0
    for r in res.rows:
        if r.group != "occlusion" or r.num_gt == 0:
            continue
        lo, hi = (float(x) for x in r.subset.strip("[]()").split(","))
        sub = copy.deepcopy(gt_dict)
        for a in sub["annotations"]:
            inside = lo <= a["occlusion"] < hi or (r.subset.endswith("]") and a["occlusion"] == hi)
            if not inside:
                a["area"] = -1.0
        assert r.box_ap == pytest.approx(_plain_cocoeval_ap(sub, dets, "bbox"), abs=1e-12)
        assert r.seg_ap == pytest.approx(_plain_cocoeval_ap(sub, dets, "segm"), abs=1e-12)
        checked += 1
    assert checked >= 2


def test_cli_detections(small_dataset: Path, tmp_path: Path, capsys) -> None:
    from mgn.cli.main import main

    pred = tmp_path / "pred.json"
    pred.write_text(json.dumps(ground_truth_detections(small_dataset, class_agnostic=True)))
    out = tmp_path / "res.json"
    code = main(
        [
            "eval",
            "detections",
            str(pred),
            "--dataset",
            str(small_dataset),
            "--class-agnostic",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "box AP" in text
    assert "difficulty" in text
    assert "unseen" in text
    doc = json.loads(out.read_text())
    assert doc["class_agnostic"] is True
    assert doc["rows"][0]["box_ap"] == 1.0
    assert (
        main(
            ["eval", "detections", str(tmp_path / "missing.json"), "--dataset", str(small_dataset)]
        )
        == 1
    )
    assert "does not exist" in capsys.readouterr().err
