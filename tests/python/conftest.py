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
    dets = [
        {
            "image_id": a["image_id"],
            "category_id": a["category_id"],
            "bbox": a["bbox"],
            "segmentation": a["segmentation"],
            "score": 1.0,
        }
        for a in anns
    ]
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
    assert layout["classes_unique"] == unique
    assert layout["all_complete"] == complete
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


# A small labelled dataset shared by the evaluation tests: 2 scenes x 3 views at 120 x 120 px,
# object labels (suction and parallel-jaw grasps) with tiny sizes.
SMALL_DATASET_CONFIG = {
    # The first drop of each scene (no refill): the scenes the evaluation tests were written for.
    "objects": {
        "categories": ["box_tea", "can_soda", "box_cereal"],
        "copies": [1, 2],
        "refill": False,
    },
    "camera": {"views": [0, 5, 17], "resolution_scale": 0.1},
    "object_labels": {
        "suction_points": 60,
        "pj_points": 60,
        "pj_grasps": None,  # every grasp found (~500-3,000 per object at 60 points)
        "physics_grasps": 3,
        "physics_grid": 2,
    },
    "drop": {"max_time": 2.0},
}
SMALL_DATASET_SEED = 11


@pytest.fixture(scope="session")
def small_dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Root of a generated dataset (SMALL_DATASET_CONFIG, seed SMALL_DATASET_SEED), made once per
    test session with its own label cache. Treat it as read-only."""
    from mgn.pipeline import generate
    from mgn.pipeline.config import load_config

    out = tmp_path_factory.mktemp("small_dataset") / "ds"
    cache = tmp_path_factory.mktemp("small_dataset_cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MGN_CACHE_DIR", str(cache))
        report = generate(
            out,
            2,
            config=load_config(SMALL_DATASET_CONFIG),
            seed=SMALL_DATASET_SEED,
            progress=False,
        )
    assert report.complete, report.format_summary()
    return out
