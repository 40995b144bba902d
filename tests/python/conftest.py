"""Shared fixtures of the Python tests."""

from pathlib import Path

import numpy as np
import pytest

DATA = Path(__file__).resolve().parents[1] / "data"


@pytest.fixture(scope="session")
def data_dir() -> Path:
    return DATA


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


def translation(x: float, y: float = 0.0, z: float = 0.0) -> np.ndarray:
    X = np.eye(4)
    X[:3, 3] = (x, y, z)
    return X


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1
    return q


def coco_ground_truth_ap(gt: object) -> tuple[float, float]:
    """(box AP, mask AP) of a pycocotools COCO ground truth scored against itself as detections
    (every annotation submitted with score 1): both must be 1.0 for a consistent export."""
    from pycocotools.cocoeval import COCOeval

    anns = gt.loadAnns(gt.getAnnIds())  # type: ignore[attr-defined]
    dets = [{"image_id": a["image_id"], "category_id": a["category_id"], "bbox": a["bbox"],
             "segmentation": a["segmentation"], "score": 1.0} for a in anns]  # fmt: skip
    out = []
    for iou in ("bbox", "segm"):
        ev = COCOeval(gt, gt.loadRes(dets), iou)  # type: ignore[attr-defined]
        ev.evaluate()
        ev.accumulate()
        ev.summarize()
        out.append(float(ev.stats[0]))
    return out[0], out[1]


def check_difficulty(layout: dict) -> int:
    """Re-derive a ``{v}_layout.json``'s difficulty from its per-object entries by the paper's
    Table IV (MODELS.md §8), assert it equals the stored level and ingredients; return it."""
    seen = [o for o in layout["objects"].values() if o["visible"]]
    cats = [o["category_id"] for o in seen]
    unique = len(cats) == len(set(cats))
    complete = all(o["complete"] for o in seen)
    layers = len({o["layer"] for o in seen})
    assert layout["classes_unique"] == unique and layout["all_complete"] == complete
    assert layout["num_layers"] == layers
    if complete and unique:
        level = 1 if layers <= 2 and layout["max_occlusion"] <= 0.05 else 2
    elif unique:
        level = 3
    elif complete:
        level = 4
    else:
        level = 5
    assert layout["difficulty"] == level
    return level
