"""mgn eval layout: hand-computed accuracies, top-set scores and confusion on a hand-built
dataset, ground truth on the generated small dataset, and the errors of bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from test_eval_detections import obj, rect, write_info, write_tiny_view

from mgn.errors import InvalidArgumentError, IoError
from mgn.eval import evaluate_layout, ground_truth_layout
from mgn.io.dataset import Dataset

# image 0: layers 0, 1, 0 with 60, 72 and 84 visible px; object 4 is hidden (no visible pixel)
VIEW0 = [
    obj(1, rect(1, 7, 1, 11), layer=0),  # 6 x 10 = 60
    obj(2, rect(8, 14, 8, 20), layer=1),  # 6 x 12 = 72
    obj(3, rect(16, 22, 24, 38), layer=0),  # 6 x 14 = 84
    {**obj(4, rect(0, 1, 0, 1), layer=3), "visible": np.zeros((24, 40), bool)},
]
# image 1: one interlock pair (layer 2) under a top object
VIEW1 = [
    obj(1, rect(0, 4, 0, 4), layer=0),  # 16
    obj(2, rect(10, 12, 0, 10), layer=2),  # 20
    obj(3, rect(14, 16, 0, 10), layer=2),  # 20
]
PX = {(0, 1): 60, (0, 2): 72, (0, 3): 84, (1, 1): 16, (1, 2): 20, (1, 3): 20}


@pytest.fixture
def tiny(tmp_path: Path) -> Path:
    root = tmp_path / "tiny"
    write_tiny_view(root / "scene0", 0, VIEW0, difficulty=3)
    write_tiny_view(root / "scene0", 1, VIEW1, difficulty=2)
    return root


def test_ground_truth_is_perfect(tiny: Path) -> None:
    gt = ground_truth_layout(tiny)
    assert {(p["image_id"], p["instance_id"]) for p in gt} == set(PX)  # the hidden one is left out
    res = evaluate_layout(tiny, gt)
    assert res.accuracy == 1.0
    assert res.weighted_accuracy == 1.0
    assert (res.top_precision, res.top_recall, res.top_f1) == (1.0, 1.0, 1.0)
    assert res.confusion == ((3, 0, 0, 0, 0), (0, 1, 0, 0, 0), (0, 0, 2, 0, 0), (0, 0, 0, 0, 0))
    assert res.per_layer_accuracy == (1.0, 1.0, 1.0, None)
    assert (res.num_views, res.num_objects, res.num_missing) == (2, 6, 0)
    # predicting the hidden object is accepted and does not count
    assert evaluate_layout(tiny, [*gt, {"image_id": 0, "instance_id": 4, "layer": 0}]).top_f1 == 1


def test_one_wrong_layer_hand_computed(tiny: Path) -> None:
    preds = ground_truth_layout(tiny)
    for p in preds:
        if (p["image_id"], p["instance_id"]) == (0, 2):
            p["layer"] = 0  # secondary predicted as top
    res = evaluate_layout(tiny, preds)
    total = sum(PX.values())
    assert res.accuracy == pytest.approx(5 / 6)
    assert res.weighted_accuracy == pytest.approx((total - PX[(0, 2)]) / total)
    assert res.confusion[1] == (1, 0, 0, 0, 0)
    assert res.per_layer_accuracy[1] == 0.0
    # view 0: T = {1, 3}, P = {1, 2, 3}: precision 2/3, recall 1, F1 0.8; view 1 perfect
    assert res.top_precision == pytest.approx((2 / 3 + 1) / 2)
    assert res.top_recall == pytest.approx(1.0)
    assert res.top_f1 == pytest.approx((0.8 + 1) / 2)


def test_missing_predictions_count_as_wrong(tiny: Path) -> None:
    preds = [p for p in ground_truth_layout(tiny) if (p["image_id"], p["instance_id"]) != (0, 3)]
    preds = [p for p in preds if p["image_id"] != 1]  # nothing for view 1
    res = evaluate_layout(tiny, preds)
    assert res.num_missing == 4
    assert res.accuracy == pytest.approx(2 / 6)
    assert res.weighted_accuracy == pytest.approx((60 + 72) / sum(PX.values()))
    assert res.confusion[0] == (1, 0, 0, 0, 2)
    assert res.confusion[2] == (0, 0, 0, 0, 2)
    # view 0: T = {1, 3}, P = {1}: precision 1, recall 1/2, F1 2/3; view 1: P empty, T = {1}:
    # precision 0, recall 0, F1 0
    assert res.top_precision == pytest.approx(0.5)
    assert res.top_recall == pytest.approx(0.25)
    assert res.top_f1 == pytest.approx(1 / 3)
    empty = evaluate_layout(tiny, [])
    assert empty.accuracy == 0.0
    assert empty.top_f1 == 0.0
    assert empty.num_missing == 6


def test_selection_and_bad_inputs(tiny: Path, tmp_path: Path) -> None:
    gt = ground_truth_layout(tiny)
    write_info(tiny, {"selection": {"views": [{"scene": 0, "view": 1, "difficulty": 2}]}})
    with pytest.raises(InvalidArgumentError, match=r"not evaluated.*\[0\]"):
        evaluate_layout(tiny, gt)
    sel = [p for p in gt if p["image_id"] == 1]
    res = evaluate_layout(tiny, sel)
    assert res.num_views == 1
    assert res.num_objects == 3
    assert res.accuracy == 1.0
    with pytest.raises(InvalidArgumentError, match=r"instance ids 1..3, got 7"):
        evaluate_layout(tiny, [{"image_id": 1, "instance_id": 7, "layer": 0}])
    with pytest.raises(InvalidArgumentError, match=r"layer must be 0..3, got 4"):
        evaluate_layout(tiny, [{"image_id": 1, "instance_id": 1, "layer": 4}])
    with pytest.raises(InvalidArgumentError, match="second prediction"):
        evaluate_layout(tiny, [sel[0], sel[0]])
    with pytest.raises(InvalidArgumentError, match="missing 'layer'"):
        evaluate_layout(tiny, [{"image_id": 1, "instance_id": 1}])
    with pytest.raises(InvalidArgumentError, match="layer must be an integer"):
        evaluate_layout(tiny, [{"image_id": 1, "instance_id": 1, "layer": 0.5}])
    with pytest.raises(IoError, match="does not exist"):
        evaluate_layout(tiny, tmp_path / "none.json")
    bad = tmp_path / "bad.json"
    bad.write_text("[{")
    with pytest.raises(IoError, match="not valid JSON"):
        evaluate_layout(tiny, bad)
    bad.write_text(json.dumps(sel))
    assert evaluate_layout(tiny, bad).accuracy == 1.0


def test_small_dataset_ground_truth(small_dataset: Path) -> None:
    ds = Dataset(small_dataset)
    gt = ground_truth_layout(ds)
    res = evaluate_layout(ds, gt)
    assert res.accuracy == 1.0
    assert res.weighted_accuracy == 1.0
    assert res.top_f1 == 1.0
    assert res.num_views == 6
    assert res.num_objects == len(gt) > 0
    # independent count of the visible objects from the instance maps
    visible = sum(
        len(np.setdiff1d(np.unique(v.instances), [0])) for s in ds.scenes() for v in s.views()
    )
    assert res.num_objects == visible
    # every visible object predicted "others": accuracy = share of layer-3 objects
    others = [{**p, "layer": 3} for p in gt]
    res3 = evaluate_layout(ds, others)
    assert res3.accuracy == pytest.approx(sum(p["layer"] == 3 for p in gt) / len(gt))
    assert res3.top_recall == 0.0


def test_cli_layout(small_dataset: Path, tmp_path: Path, capsys) -> None:
    from mgn.cli.main import main

    pred = tmp_path / "layout.json"
    pred.write_text(json.dumps(ground_truth_layout(small_dataset)))
    out = tmp_path / "res.json"
    assert (
        main(["eval", "layout", str(pred), "--dataset", str(small_dataset), "--out", str(out)]) == 0
    )
    assert "layer accuracy" in capsys.readouterr().out
    doc = json.loads(out.read_text())
    assert doc["accuracy"] == 1.0
    assert len(doc["confusion"]) == 4
    pred.write_text(json.dumps([{"image_id": 99999, "instance_id": 1, "layer": 0}]))
    assert main(["eval", "layout", str(pred), "--dataset", str(small_dataset)]) == 1
    assert "99999" in capsys.readouterr().err
