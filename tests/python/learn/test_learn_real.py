"""Real photographs: MetaGraspNet's real layout (files written by hand here, with the keys of
its public sample scenes and scripts), COCO folders, the metrics, and ``mgn eval real``."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from pycocotools import mask as mask_utils
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval

import mgn
from mgn.cli.main import main
from mgn.errors import InvalidArgumentError, IoError
from mgn.io.real import detect_real_format, read_coco_folder, read_mgn_real, read_real_set
from mgn.learn import ModelConfig, Predictor, TrainConfig, train
from mgn.learn.instances import InstanceMaps
from mgn.learn.metrics import foreground_iou, mask_ap, suction_precision
from mgn.learn.predict import Prediction
from mgn.learn.real_eval import brightness_foreground, evaluate_real

H, W = 40, 50


def _rgb(seed: int) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, (H, W, 3), dtype=np.uint8)


def _boxes() -> tuple[np.ndarray, np.ndarray]:
    """Visible and hidden parts of two objects: B (rows 10-29, cols 25-39) lies on A (rows
    5-24, cols 5-34), so A's columns 25-34 of rows 10-24 are hidden."""
    vis = np.zeros((2, H, W), bool)
    hid = np.zeros((2, H, W), bool)
    vis[0, 5:25, 5:35] = True
    vis[1, 10:30, 25:40] = True
    hid[0] = vis[0] & vis[1]
    vis[0] &= ~vis[1]
    return vis, hid


def write_mgn_real(root: Path) -> Path:
    """dataset_real/ with scene46 (view 3 annotated with amodal + grasps files, view 28 with
    RGB and depth only) and scene418 (view 3 with ``instances_objects`` in its npz)."""
    vis, hid = _boxes()
    s46 = root / "scene46"
    s46.mkdir(parents=True)
    for v in (3, 28):
        Image.fromarray(_rgb(v)).save(s46 / f"{v}_rgb.png")
        depth = np.full((H, W), 80.0, np.float32)  # cm
        depth[0, 0] = np.nan
        np.savez_compressed(s46 / f"{v}.npz", depth=depth)
    np.savez_compressed(
        s46 / "3_amodal.npz",
        amodal_bitmaps_full_size_instances=np.stack([vis, hid], axis=1).astype(np.uint8),
        occlusion_bitmap_full_size=hid.any(0).astype(np.float32),
    )
    bitmap = np.zeros((H, W), np.uint8)
    bitmap[12:18, 10:16] = 1  # on A
    bitmap[20:24, 30:34] = 1  # on B
    pj = np.array([[[6, 8], [30, 8]], [[27, 15], [38, 15]]], np.int64)
    np.savez_compressed(s46 / "3_grasps.npz", suction_bitmap=bitmap, parallel_jaw_2d=pj)
    s418 = root / "scene418"
    s418.mkdir()
    Image.fromarray(_rgb(5)).save(s418 / "3_rgb.png")
    ids = np.zeros((H, W), np.float32)
    ids[2:12, 2:12] = 1
    ids[20:35, 30:45] = 2
    np.savez_compressed(
        s418 / "3.npz",
        depth=np.full((H, W), 75.0, np.float32),
        instances_objects=ids,
        instances_semantic=ids * 7,
    )
    return root


def write_coco_folder(folder: Path) -> Path:
    """Two images: one with a polygon and a compressed-RLE object, one with an
    uncompressed-RLE object; a depth PNG beside the first."""
    folder.mkdir(parents=True)
    vis, _ = _boxes()
    for k, name in enumerate(("a.png", "b.jpg")):
        Image.fromarray(_rgb(10 + k)).save(folder / name)
    Image.fromarray(np.full((H, W), 800, np.uint16)).save(folder / "a_depth.png")
    rle = mask_utils.encode(np.asfortranarray(vis[1].astype(np.uint8)))
    runs = []  # uncompressed counts of vis[0], column-major
    flat = vis[0].T.ravel()
    value, count = False, 0
    for px in flat:
        if px == value:
            count += 1
        else:
            runs.append(count)
            value, count = px, 1
    runs.append(count)
    doc = {
        "images": [
            {"id": 1, "file_name": "a.png", "width": W, "height": H},
            {"id": 7, "file_name": "b.jpg", "width": W, "height": H},
        ],
        "annotations": [
            {
                "id": 1,
                "image_id": 1,
                "category_id": 3,
                "segmentation": [[5.0, 5.0, 25.0, 5.0, 25.0, 25.0, 5.0, 25.0]],
            },
            {
                "id": 2,
                "image_id": 1,
                "category_id": 3,
                "segmentation": {"size": [H, W], "counts": rle["counts"].decode()},
            },
            {
                "id": 3,
                "image_id": 7,
                "category_id": 1,
                "segmentation": {"size": [H, W], "counts": runs},
            },
        ],
        "categories": [{"id": 1, "name": "x"}, {"id": 3, "name": "y"}],
    }
    (folder / "labels.json").write_text(json.dumps(doc))
    return folder


# ---------------------------------------------------------------------------------------------
# Readers


def test_dataset_reads_metagraspnet_real_views(tmp_path: Path):
    root = write_mgn_real(tmp_path / "dataset_real")
    vis, hid = _boxes()
    ds = mgn.Dataset(root)
    assert ds.scene_ids == [46, 418]
    v = ds.scene(46).view(3)
    expected_ids = np.zeros((H, W), np.int32)
    expected_ids[vis[0]] = 1
    expected_ids[vis[1]] = 2
    np.testing.assert_array_equal(v.instances, expected_ids)
    np.testing.assert_array_equal(v.amodal, vis | hid)
    assert v.num_instances == 2
    assert v.suction_bitmap is not None
    assert v.suction_bitmap.sum() == 36 + 16
    assert v.parallel_jaw_2d is not None
    assert v.parallel_jaw_2d.shape == (2, 2, 2)
    assert v.depth[1, 1] == pytest.approx(0.8)
    assert np.isnan(v.depth[0, 0])
    unlabelled = ds.scene(46).view(28)
    assert unlabelled.suction_bitmap is None
    assert unlabelled.real_amodal is None
    with pytest.raises(IoError, match=r"28\.npz' has no 'instances_objects'"):
        _ = unlabelled.instances
    v418 = ds.scene(418).view(3)
    assert v418.instances.max() == 2
    assert v418.suction_bitmap is None


def test_read_mgn_real(tmp_path: Path):
    root = write_mgn_real(tmp_path / "dataset_real")
    vis, hid = _boxes()
    images = read_mgn_real(root)
    assert [img.name for img in images] == ["scene46/3", "scene418/3"]
    a, b = images
    np.testing.assert_array_equal(a.masks, vis)
    assert a.amodal is not None
    np.testing.assert_array_equal(a.amodal, vis | hid)
    assert a.suction_bitmap is not None
    assert a.depth is not None
    assert b.masks.shape == (2, H, W)
    assert b.amodal is None
    assert b.suction_bitmap is None
    assert [i.name for i in read_mgn_real(root / "scene46")] == ["scene46/3"]
    assert detect_real_format(root) == detect_real_format(root / "scene46") == "metagraspnet"


def test_read_mgn_real_as_published_without_view_npz(tmp_path: Path):
    """The sample scenes in MetaGraspNet's repository have no ``{v}.npz``: per view
    ``{v}_rgb.png``, ``{v}_depth.png`` (and hdf5/json files), the annotated view also
    ``{v}_amodal.npz`` and ``{v}_grasps.npz``. They read with their masks and suction bitmap and
    without depth."""
    vis, hid = _boxes()
    scene = tmp_path / "dataset_real" / "scene46"
    scene.mkdir(parents=True)
    for v in (3, 28):
        Image.fromarray(_rgb(v)).save(scene / f"{v}_rgb.png")
        Image.fromarray(np.full((H, W), 800, np.uint16)).save(scene / f"{v}_depth.png")
        (scene / f"{v}_scene.hdf5").write_bytes(b"")
    (scene / "scene_gt.json").write_text("{}")
    np.savez_compressed(
        scene / "3_amodal.npz",
        amodal_bitmaps_full_size_instances=np.stack([vis, hid], axis=1).astype(np.uint8),
    )
    bitmap = np.zeros((H, W), np.uint8)
    bitmap[12:18, 10:16] = 1
    np.savez_compressed(scene / "3_grasps.npz", suction_bitmap=bitmap)
    (img,) = read_real_set(tmp_path / "dataset_real")
    assert img.name == "scene46/3"
    assert img.depth is None
    assert img.crowd is None
    np.testing.assert_array_equal(img.masks, vis)
    assert img.amodal is not None
    np.testing.assert_array_equal(img.amodal, vis | hid)
    assert img.suction_bitmap is not None
    assert int(img.suction_bitmap.sum()) == 36


def test_read_coco_folder(tmp_path: Path):
    folder = write_coco_folder(tmp_path / "photos")
    vis, _ = _boxes()
    for path in (folder, folder / "labels.json"):
        assert detect_real_format(path) == "coco"
        a, b = read_coco_folder(path)
        assert (a.name, b.name) == ("a.png", "b.jpg")
        assert a.masks.shape == (2, H, W)
        assert b.masks.shape == (1, H, W)
        np.testing.assert_array_equal(a.masks[1], vis[1])
        np.testing.assert_array_equal(b.masks[0], vis[0])
        # The polygon's square, 20 px a side from (5, 5): inside its box, about 400 px.
        ys, xs = np.nonzero(a.masks[0])
        assert ys.min() >= 5
        assert xs.min() >= 5
        assert ys.max() <= 25
        assert xs.max() <= 25
        assert abs(int(a.masks[0].sum()) - 400) <= 45
        assert a.depth is not None
        assert np.allclose(a.depth, 0.8)
        assert b.depth is None


def test_coco_crowd_annotations_are_foreground_only(tmp_path: Path):
    """An ``iscrowd: 1`` annotation (objects not outlined one by one) becomes the image's crowd
    region: part of the labelled foreground, not an object."""
    vis, _ = _boxes()
    folder = tmp_path / "fg"
    folder.mkdir()
    Image.fromarray(_rgb(3)).save(folder / "a.png")
    crowd = np.zeros((H, W), bool)
    crowd[30:38, 2:20] = True
    crowd[0:3, 40:50] = True  # two blobs in one crowd annotation
    anns = []
    for k, (m, is_crowd) in enumerate([(vis[1], 0), (crowd, 1)]):
        r = mask_utils.encode(np.asfortranarray(m.astype(np.uint8)))
        seg = {"size": [H, W], "counts": r["counts"].decode()}
        anns.append({"id": k + 1, "image_id": 7, "segmentation": seg, "iscrowd": is_crowd})
    doc = {"images": [{"id": 7, "file_name": "a.png"}], "annotations": anns}
    (folder / "labels.json").write_text(json.dumps(doc))
    (img,) = read_real_set(folder)
    assert img.masks.shape == (1, H, W)
    np.testing.assert_array_equal(img.masks[0], vis[1])
    assert img.crowd is not None
    np.testing.assert_array_equal(img.crowd, crowd)
    np.testing.assert_array_equal(img.foreground, vis[1] | crowd)
    assert int(img.foreground.sum()) == 15 * 20 + 8 * 18 + 3 * 10


def test_real_set_bad_input(tmp_path: Path):
    (tmp_path / "empty").mkdir()
    with pytest.raises(IoError, match="no known annotation format"):
        read_real_set(tmp_path / "empty")
    voc = tmp_path / "voc"
    voc.mkdir()
    (voc / "a.xml").write_text("<annotation/>")
    Image.fromarray(_rgb(0)).save(voc / "a.png")
    with pytest.raises(IoError, match="no known annotation format"):
        read_real_set(voc)
    (voc / "x.json").write_text(json.dumps({"shapes": []}))  # a LabelMe-like file
    with pytest.raises(IoError, match=r"x\.json' is in no known annotation format"):
        read_real_set(voc)
    folder = write_coco_folder(tmp_path / "photos")
    doc = json.loads((folder / "labels.json").read_text())
    doc["annotations"][1]["segmentation"]["size"] = [H + 1, W]
    (folder / "labels.json").write_text(json.dumps(doc))
    with pytest.raises(IoError, match=r"a\.png.*mask is 50 x 41 px but its image is 50 x 40"):
        read_real_set(folder)
    root = write_mgn_real(tmp_path / "real")
    np.savez_compressed(root / "scene46" / "3_grasps.npz", suction_bitmap=np.zeros((H, W + 2)))
    with pytest.raises(IoError, match="suction_bitmap is 52 x 40 px but the image is 50 x 40"):
        read_real_set(root)
    with pytest.raises(IoError, match="does not exist"):
        read_real_set(tmp_path / "nothing")


# ---------------------------------------------------------------------------------------------
# Metrics


def _masks(*boxes: tuple[int, int, int, int]) -> np.ndarray:
    out = np.zeros((len(boxes), 20, 20), bool)
    for k, (r0, r1, c0, c1) in enumerate(boxes):
        out[k, r0:r1, c0:c1] = True
    return out


def test_mask_ap_hand_computed_cases():
    gt = _masks((0, 4, 0, 4), (10, 14, 10, 14))
    assert mask_ap([gt], [gt], [np.array([0.9, 0.8])]) == (1.0, 1.0)
    # One of two objects found (exact mask), nothing else: precision 1 up to recall 0.5 on the
    # 101 recall points 0, 0.01, ..., 1 -> 51 / 101 at every IoU threshold.
    ap, ap50 = mask_ap([gt], [gt[:1]], [np.array([0.9])])
    assert ap == pytest.approx(51 / 101)
    assert ap50 == pytest.approx(51 / 101)
    # A prediction of IoU 10/16 = 0.625 with the one object: a match at thresholds 0.50, 0.55,
    # 0.60 of the ten -> AP 0.3, AP50 1.
    one = _masks((0, 4, 0, 4))
    pred = _masks((0, 4, 0, 4))
    pred[0, 2:4] = False
    pred[0, 0:2, 2:4] = True
    pred[0, 0, 0:4] = True
    part = _masks((0, 4, 0, 4))
    part[0, 1:4] = False  # 4 px
    part[0, 1:3, 0:3] = True  # + 6 px = 10 px inside the 16-px object
    ap, ap50 = mask_ap([one], [part], [np.array([0.5])])
    assert ap == pytest.approx(0.3)
    assert ap50 == pytest.approx(1.0)
    # A false positive ranked above the true one: precision 1/2 at recall 1 -> AP50 0.5.
    ap, ap50 = mask_ap(
        [one], [np.concatenate([_masks((15, 19, 15, 19)), one])], [np.array([0.9, 0.1])]
    )
    assert ap50 == pytest.approx(0.5)
    assert mask_ap([np.zeros((0, 20, 20), bool)], [one], [np.array([1.0])]) == (None, None)
    assert mask_ap([one], [np.zeros((0, 20, 20), bool)], [np.zeros(0)]) == (0.0, 0.0)
    with pytest.raises(InvalidArgumentError, match="one each per image"):
        mask_ap([one], [], [])


def test_mask_ap_ignores_predictions_on_crowd_regions():
    one = _masks((0, 4, 0, 4))
    crowd = _masks((10, 20, 10, 20))[0]
    stray = _masks((12, 16, 12, 16))  # inside the crowd region, ranked first
    preds = np.concatenate([stray, one])
    sc = np.array([0.9, 0.1])
    # Without the crowd region the stray mask is a false positive ranked first: AP50 0.5.
    assert mask_ap([one], [preds], [sc])[1] == pytest.approx(0.5)
    # On a crowd region it is ignored (COCO's iscrowd rule): the one object is found exactly.
    assert mask_ap([one], [preds], [sc], [crowd]) == (pytest.approx(1.0), pytest.approx(1.0))
    # A stray mask outside the crowd region is still a false positive.
    outside = np.concatenate([_masks((5, 9, 0, 4)), one])
    assert mask_ap([one], [outside], [sc], [crowd])[1] == pytest.approx(0.5)
    # Crowd regions only: no object to find, no AP.
    empty = np.zeros((0, 20, 20), bool)
    assert mask_ap([empty], [stray], [np.array([0.9])], [crowd]) == (None, None)
    with pytest.raises(InvalidArgumentError, match="crowd region"):
        mask_ap([one], [one], [np.array([1.0])], [crowd[:5]])


def test_brightness_foreground_is_otsu_by_brute_force():
    # Two grey levels: the bright one is the foreground.
    img = np.full((10, 12, 3), 40, np.uint8)
    img[2:6, 3:9] = 200
    expected = np.zeros((10, 12), bool)
    expected[2:6, 3:9] = True
    np.testing.assert_array_equal(brightness_foreground(img), expected)
    assert not brightness_foreground(np.full((5, 5, 3), 90, np.uint8)).any()
    # Random images: the threshold maximises the between-class variance, searched directly.
    rng = np.random.default_rng(4)
    for _ in range(3):
        rgb = rng.integers(0, 256, (30, 40, 3), dtype=np.uint8)
        rgb[:10] //= 3
        y = np.rint(rgb @ np.array([0.299, 0.587, 0.114])).ravel()
        best, best_t = -1.0, 0
        for t in range(256):
            lo, hi = y[y <= t], y[y > t]
            if len(lo) == 0 or len(hi) == 0:
                continue
            v = len(lo) * len(hi) * (lo.mean() - hi.mean()) ** 2
            if v > best:
                best, best_t = v, t
        fg = brightness_foreground(rgb).ravel()
        np.testing.assert_array_equal(fg, y > best_t)


def test_mask_ap_agrees_with_pycocotools_on_files(tmp_path: Path):
    """The same masks through pycocotools' documented file route (COCO(json), loadRes(json))."""
    rng = np.random.default_rng(0)
    gts, preds, scores = [], [], []
    for _ in range(3):
        boxes = [
            (r, r + int(rng.integers(3, 8)), c, c + int(rng.integers(3, 8)))
            for r, c in rng.integers(0, 12, (4, 2))
        ]
        g = _masks(*boxes)
        p = np.roll(g, int(rng.integers(-1, 2)), axis=2)[: int(rng.integers(1, 5))]
        gts.append(g)
        preds.append(np.concatenate([p, _masks((0, 3, 15, 19))]))
        scores.append(rng.uniform(0, 1, len(preds[-1])))
    ours = mask_ap(gts, preds, scores)
    images, anns, dets = [], [], []
    for i, (g, p, s) in enumerate(zip(gts, preds, scores, strict=True)):
        images.append({"id": i + 1, "width": 20, "height": 20})
        for m in g:
            r = mask_utils.encode(np.asfortranarray(m.astype(np.uint8)))
            anns.append(
                {
                    "id": len(anns) + 1,
                    "image_id": i + 1,
                    "category_id": 1,
                    "segmentation": {"size": r["size"], "counts": r["counts"].decode()},
                    "area": int(m.sum()),
                    "bbox": list(mask_utils.toBbox(r)),
                    "iscrowd": 0,
                }
            )
        for m, sc in zip(p, s, strict=True):
            r = mask_utils.encode(np.asfortranarray(m.astype(np.uint8)))
            dets.append(
                {
                    "image_id": i + 1,
                    "category_id": 1,
                    "score": float(sc),
                    "segmentation": {"size": r["size"], "counts": r["counts"].decode()},
                }
            )
    (tmp_path / "gt.json").write_text(
        json.dumps({"images": images, "annotations": anns, "categories": [{"id": 1, "name": "o"}]})
    )
    (tmp_path / "dt.json").write_text(json.dumps(dets))
    with contextlib.redirect_stdout(io.StringIO()):
        gt = COCO(str(tmp_path / "gt.json"))
        ev = COCOeval(gt, gt.loadRes(str(tmp_path / "dt.json")), "segm")
        ev.evaluate()
        ev.accumulate()
        ev.summarize()
    assert ours == (pytest.approx(ev.stats[0]), pytest.approx(ev.stats[1]))
    assert 0 < ours[0] < ours[1] < 1


def test_foreground_iou_and_suction_precision_by_hand():
    gt = _masks((0, 4, 0, 4), (10, 12, 10, 12))  # 16 + 4 px
    pred = np.zeros((20, 20), bool)
    pred[0:4, 2:6] = True  # 8 px on the first object, 8 outside
    assert foreground_iou(gt, pred) == pytest.approx(8 / 28)
    assert foreground_iou(np.zeros((0, 20, 20), bool), np.zeros((20, 20), bool)) == 1.0
    bitmap = np.zeros((20, 20))
    bitmap[5, 5] = bitmap[8, 2] = 1
    points = np.array([[5.5, 5.5, 0.9], [0.5, 0.5, 0.8], [2.9, 8.1, 0.7]])  # hit, miss, hit
    assert suction_precision(points, bitmap, [1, 2, 3, 5]) == {1: 1.0, 2: 0.5, 3: 2 / 3, 5: 0.4}
    assert suction_precision(np.zeros((0, 3)), bitmap, [1]) == {1: 0.0}


# ---------------------------------------------------------------------------------------------
# mgn eval real


@pytest.fixture(scope="module")
def tiny_model(small_dataset: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("tiny_real_model")
    train(
        small_dataset,
        out,
        model_config=ModelConfig(image_size=32, width=4, amodal=True, modality="rgbd"),
        train_config=TrainConfig(epochs=1),
        views=[0],
        num_threads=1,
        progress=False,
    )
    return out / "model.pt"


def test_eval_real_scores_perfect_predictions_as_perfect(
    tiny_model: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    """With a predictor that returns the labels themselves, every score is 1."""
    root = write_mgn_real(tmp_path / "dataset_real")
    labels = {img.name: img for img in read_mgn_real(root)}

    def perfect(self, rgb, depth=None, *, name="image", **settings):
        img = labels[name]
        ids = np.zeros(img.masks.shape[1:], np.int32)
        for i, m in enumerate(img.masks):
            ids[m] = i + 1
        suction = np.zeros(ids.shape, np.float32)
        if img.suction_bitmap is not None:
            suction[img.suction_bitmap != 0] = 1.0
        inst = InstanceMaps(ids, np.ones(len(img.masks), np.float32), img.amodal)
        return Prediction(inst, (ids > 0).astype(np.float32), suction)

    monkeypatch.setattr(Predictor, "predict", perfect)
    res = evaluate_real(tiny_model, root, tmp_path / "out", ks=(1, 2), progress=False)
    assert (res.num_images, res.num_objects) == (2, 4)
    assert res.mask_ap == pytest.approx(1.0)
    assert res.mask_ap50 == pytest.approx(1.0)
    assert res.foreground_iou == 1.0
    assert res.suction == {1: 1.0, 2: 1.0}
    assert res.suction_images == 1
    am = evaluate_real(tiny_model, root / "scene46", amodal=True, progress=False)
    assert am.mask_ap == pytest.approx(1.0)
    with pytest.raises(InvalidArgumentError, match="no amodal masks"):
        evaluate_real(tiny_model, root, amodal=True, progress=False)


def test_eval_real_per_image_ap_is_each_images_own(
    tiny_model: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    """Both objects of scene46/3 predicted, one of the two of scene418/3: per image AP50 1 and
    51/101 (COCO's 101 recall points: precision 1 up to recall 0.5, then nothing); over both
    images 76/101 (3 of 4 objects, all found before any miss)."""
    root = write_mgn_real(tmp_path / "dataset_real")
    labels = {img.name: img for img in read_mgn_real(root)}

    def partial(self, rgb, depth=None, *, name="image", **settings):
        img = labels[name]
        keep = img.masks if name == "scene46/3" else img.masks[:1]
        ids = np.zeros(img.masks.shape[1:], np.int32)
        for i, m in enumerate(keep):
            ids[m] = i + 1
        inst = InstanceMaps(ids, np.ones(len(keep), np.float32), None)
        return Prediction(inst, (ids > 0).astype(np.float32), np.zeros(ids.shape, np.float32))

    monkeypatch.setattr(Predictor, "predict", partial)
    res = evaluate_real(tiny_model, root, tmp_path / "out", progress=False)
    assert [e["mask_AP50"] for e in res.per_image] == pytest.approx([1.0, 51 / 101])
    assert [e["mask_AP"] for e in res.per_image] == pytest.approx([1.0, 51 / 101])
    assert res.mask_ap50 == pytest.approx(76 / 101)
    doc = json.loads((tmp_path / "out" / "results.json").read_text())
    assert doc["per_image"][1]["mask_AP50"] == pytest.approx(51 / 101)


def test_eval_real_command(tiny_model: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]):
    root = write_mgn_real(tmp_path / "dataset_real")
    out = tmp_path / "out"
    assert (
        main(
            [
                "eval",
                "real",
                str(root),
                "--model",
                str(tiny_model),
                "--out",
                str(out),
                "--quiet",
                "--num-threads",
                "1",
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert "mask_AP50" in text
    assert "suction_P@10" in text
    doc = json.loads((out / "results.json").read_text())
    assert doc["format"] == "metagraspnet"
    assert doc["summary"]["images"] == 2
    assert [e["name"] for e in doc["per_image"]] == ["scene46/3", "scene418/3"]
    assert 0.0 <= doc["summary"]["fg_IoU"] <= 1.0
    pictures = sorted((out / "overlays").iterdir())
    assert len(pictures) == 2
    with Image.open(pictures[0]) as im:
        assert im.size == (3 * W, H)
    assert "overlays/000_scene46_3.png" in (out / "report.html").read_text()
    coco = write_coco_folder(tmp_path / "photos")
    assert main(["eval", "real", str(coco), "--model", str(tiny_model), "--quiet"]) == 1
    assert "b.jpg: the model's input is rgbd, but it has no depth" in capsys.readouterr().err
    np.save(coco / "b_depth.npy", np.full((H, W), 0.8, np.float32))
    assert main(["eval", "real", str(coco), "--model", str(tiny_model), "--quiet"]) == 0
    assert "(no suction bitmaps" in capsys.readouterr().out
    (tmp_path / "empty").mkdir()
    assert main(["eval", "real", str(tmp_path / "empty"), "--model", str(tiny_model)]) == 1
    assert "no known annotation format" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------
# mgn transfer


def test_transfer_table_by_hand():
    from mgn.learn.transfer import TransferResults, _rows

    scores = {
        "base": {0: {"mask_AP50": 0.5}, 1: {"mask_AP50": 0.7}, 2: {"mask_AP50": 0.6}},
        "new": {0: {"mask_AP50": 0.6}, 1: {"mask_AP50": 0.6}, 2: {"mask_AP50": 0.9}},
    }
    res = TransferResults(["base", "new"], [0, 1, 2], "mask_AP50", scores)  # type: ignore[arg-type]
    rows = _rows(res)
    assert rows[1]["mask_AP50 mean"] == pytest.approx(0.7)
    assert rows[1]["mask_AP50 std"] == pytest.approx(np.sqrt((0.01 + 0.01 + 0.04) / 2))
    assert (rows[1]["mask_AP50 min"], rows[1]["mask_AP50 max"]) == (0.6, 0.9)
    assert rows[1]["wins"] == "2/3"
    assert rows[0]["wins"] == "-"
    res.rows = rows
    assert "| new | 0.700 ± 0.173 [0.600, 0.900] | 2/3 |" in res.table()
    assert "image wins" not in res.table()  # no per-image scores: no such column


def test_transfer_image_wins_and_heldout_matrix_by_hand():
    from mgn.learn.transfer import TransferResults, _heldout_rows, _rows

    def imgs(*fg: float | None) -> list[dict[str, float | None]]:
        return [{"fg_IoU": v, "mask_AP50": None} for v in fg]

    scores = {v: {s: {"fg_IoU": 0.5} for s in (3, 4)} for v in ("base", "new")}
    per_image = {  # replicate 3: 2 wins, 1 tie; replicate 4: 1 win, 1 loss, one image unscored
        "base": {3: imgs(0.5, 0.6, 0.7), 4: imgs(0.2, 0.9, 0.4)},
        "new": {3: imgs(0.6, 0.6, 0.8), 4: imgs(0.3, 0.8, None)},
    }
    res = TransferResults(["base", "new"], [3, 4], "fg_IoU", scores)  # type: ignore[arg-type]
    res.per_image = per_image  # type: ignore[assignment]
    res.rows = _rows(res)
    w = res.rows[1]["image fg_IoU"]
    # sign test of 3 wins, 1 loss: 2 * P(X <= 1), X ~ Binomial(4, 1/2) = 2 * 5/16
    assert w == {"wins": 3, "losses": 1, "ties": 1, "pairs": 5, "p": pytest.approx(0.625)}
    assert res.rows[1]["image mask_AP50"] is None  # no image has one
    assert "| new | 0.500 ± 0.000 [0.500, 0.500] | 0/2 | 3/5, 1 tied, p 0.62 |" in res.table()
    res.heldout = {
        "base": {"base": {3: {"fg_IoU": 0.8, "mask_AP50": 0.1}, 4: {"fg_IoU": 0.6}}},
        "new": {"base": {3: {"fg_IoU": 0.7, "mask_AP50": 0.3}, 4: {"fg_IoU": 0.7}}},
    }  # type: ignore[dict-item]
    res.heldout_rows = _heldout_rows(res)
    assert res.heldout_rows[0]["fg_IoU mean"] == pytest.approx(0.7)
    assert res.heldout_rows[0]["fg_IoU std"] == pytest.approx(np.sqrt(0.02))
    assert res.heldout_rows[1]["mask_AP50 mean"] == pytest.approx(0.3)
    md = res.markdown()
    assert "| trained on \\ held-out views of | base |" in md
    assert "| base | 0.700 ± 0.141 |" in md
    assert "| new | 0.300 ± 0.000 |" in md  # mask_AP50 of one replicate


@pytest.mark.parametrize(("wins", "losses"), [(0, 0), (1, 0), (3, 1), (9, 1), (5, 5), (2, 11)])
def test_sign_test_is_the_two_sided_binomial_tail(wins: int, losses: int):
    from math import comb

    from mgn.learn.transfer import sign_test

    n = wins + losses
    if n == 0:
        assert sign_test(wins, losses) is None
        return
    k = min(wins, losses)
    p = min(1.0, 2 * sum(comb(n, i) for i in range(k + 1)) / 2**n)
    assert sign_test(wins, losses) == pytest.approx(p)


def test_transfer_command(small_dataset: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]):
    from conftest import SMALL_DATASET_CONFIG

    root = write_mgn_real(tmp_path / "dataset_real")
    spec = {
        "real": str(root),
        "scenes": 1,
        "heldout_scenes": 1,
        "seeds": [0, 1],
        "config": SMALL_DATASET_CONFIG,
        "model": {"image_size": 32, "width": 4},
        "train": {"epochs": 1, "batch_size": 3},
        "variants": [
            {"name": "given", "dataset": str(small_dataset)},
            {"name": "wider", "dataset": str(small_dataset), "model": {"width": 8}},
            {"name": "two-views", "config": {"camera": {"views": [0, 5]}}},
        ],
    }
    (tmp_path / "spec.yaml").write_text(json.dumps(spec))  # JSON is YAML
    out = tmp_path / "out"
    args = [
        "transfer",
        str(tmp_path / "spec.yaml"),
        "--out",
        str(out),
        "--quiet",
        "--num-threads",
        "1",
    ]
    assert main(args) == 0
    table = (out / "transfer.md").read_text().split("\n\n")[1]
    assert [line.split(" | ")[0] for line in table.splitlines()[2:]] == [
        "| given",
        "| wider",
        "| two-views",
    ]
    assert "wins vs given (mask_AP50)" in table
    assert "image wins vs given (fg_IoU)" in table
    doc = json.loads((out / "transfer.json").read_text())
    res = json.loads((out / "wider" / "seed1" / "real" / "results.json").read_text())
    assert doc["scores"]["wider"]["1"]["mask_AP50"] == res["summary"]["mask_AP50"]
    assert mgn.Dataset(out / "two-views" / "dataset").scene(0).view_ids == [0, 5]
    with Image.open(out / "transfer.png") as im:
        assert im.size[0] > 400
    stamp = (out / "given" / "seed0" / "model.pt").stat().st_mtime_ns
    assert main(args) == 0  # finished models are kept
    assert (out / "given" / "seed0" / "model.pt").stat().st_mtime_ns == stamp
    capsys.readouterr()
    spec["variants"] = [{"name": "x", "datasett": "y"}]
    (tmp_path / "bad.yaml").write_text(json.dumps(spec))
    assert main(["transfer", str(tmp_path / "bad.yaml"), "--out", str(out)]) == 1
    assert "unknown key(s) ['datasett']" in capsys.readouterr().err


class _FakeTransfer:
    """Stand-ins for ``generate`` (a copy of the small dataset) and ``train`` (the tiny model
    with its weights scaled by random factors drawn from the training seed and the call
    count, so that the models differ), recording their calls; ``evaluate_real`` is the real
    one, counted."""

    def __init__(self, small_dataset: Path, tiny_model: Path, monkeypatch: pytest.MonkeyPatch):
        from mgn.learn import transfer

        self.generated: list[tuple[Path, int, int]] = []
        self.trained: list[tuple[Path, Path, int]] = []
        self.evaluated = 0
        real_evaluate = transfer.evaluate_real

        def generate(out, scenes, *, config, seed, resume, progress):
            import shutil
            from types import SimpleNamespace

            self.generated.append((Path(out), scenes, seed))
            if not Path(out).exists():
                shutil.copytree(small_dataset, out)
            return SimpleNamespace(complete=True)

        def train(ds, run, *, model_config, train_config, **kwargs):
            import torch

            from mgn.learn.checkpoint import MODEL_FORMAT, read_torch_file, write_torch_file

            self.trained.append((Path(ds), Path(run), train_config.seed))
            obj = read_torch_file(tiny_model, MODEL_FORMAT)
            g = torch.Generator().manual_seed(1000 * train_config.seed + len(self.trained))
            for v in obj["state_dict"].values():
                if v.is_floating_point():
                    v.mul_(torch.exp(0.5 * torch.randn(v.shape, generator=g)))
            write_torch_file(Path(run) / "model.pt", obj)

        def evaluate(*args, **kwargs):
            self.evaluated += 1
            return real_evaluate(*args, **kwargs)

        monkeypatch.setattr(transfer, "generate", generate)
        monkeypatch.setattr(transfer, "train", train)
        monkeypatch.setattr(transfer, "evaluate_real", evaluate)


def test_transfer_replicates_over_dataset_seeds_and_heldout_matrix(
    small_dataset: Path, tiny_model: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    from mgn.learn.transfer import run_transfer, sign_test

    fake = _FakeTransfer(small_dataset, tiny_model, monkeypatch)
    real = write_mgn_real(tmp_path / "dataset_real")
    spec = {
        "real": str(real),
        "scenes": 3,
        "seeds": [0, 1],
        "generate_seeds": [5, 7],
        "metric": "fg_IoU",
        "variants": [
            {"name": "a"},
            {"name": "b", "config": {"camera": {"views": [0]}}},
            {
                "name": "given",
                "dataset": [str(small_dataset), str(small_dataset)],
                "heldout": str(small_dataset),
            },
        ],
    }
    out = tmp_path / "out"
    res = run_transfer(spec, out, num_threads=1, progress=False)
    # datasets: one per (generated variant, dataset seed); held-out: 2 scenes, seed 7 + 1000
    assert sorted(fake.generated) == sorted(
        [(out / v / f"dataset_g{g}", 3, g) for v in ("a", "b") for g in (5, 7)]
        + [(out / v / "heldout", 2, 1007) for v in ("a", "b")]
    )
    # replicate k: dataset seed generate_seeds[k], training seed seeds[k]
    assert sorted(fake.trained) == sorted(
        [
            (out / v / f"dataset_g{g}", out / v / f"g{g}_seed{s}", s)
            for v in ("a", "b")
            for g, s in ((5, 0), (7, 1))
        ]
        + [(small_dataset, out / "given" / f"g{g}_seed{s}", s) for g, s in ((5, 0), (7, 1))]
    )
    assert not (out / "a" / "seed0").exists()
    assert not (out / "a" / "dataset").exists()
    # the held-out COCO folder: the class-agnostic export with the sensor's depth beside
    coco = json.loads((out / "a" / "heldout_coco" / "annotations.json").read_text())
    assert [c["id"] for c in coco["categories"]] == [1]
    assert detect_real_format(out / "a" / "heldout_coco") == "coco"  # mgn eval real reads it
    ds = mgn.Dataset(small_dataset)
    images = read_coco_folder(out / "given" / "heldout_coco")
    views = [(s, v) for s in ds.scene_ids for v in ds.scene(s).view_ids]
    assert len(images) == len(views) == 6
    for img, (s, v) in zip(images, views, strict=True):
        view = ds.scene(s).view(v)
        ids = view.instances
        present = [i for i in range(1, int(ids.max()) + 1) if (ids == i).any()]
        assert np.array_equal(img.masks, np.stack([ids == i for i in present]))
        np.testing.assert_array_equal(img.depth, view.depth)
        assert np.array_equal(img.rgb, view.rgb)
    # every model on every held-out set; the matrix holds each results.json's numbers
    doc = json.loads((out / "transfer.json").read_text())
    assert doc["generate_seeds"] == [5, 7]
    reps = ["g5_seed0", "g7_seed1"]
    assert sorted(doc["scores"]["b"]) == reps
    for t in ("a", "b", "given"):
        assert sorted(doc["heldout"][t]) == ["a", "b", "given"]
        for h in ("a", "b", "given"):
            for rep in reps:
                js = out / t / rep / f"heldout_{h}" / "results.json"
                summary = json.loads(js.read_text())["summary"]
                assert doc["heldout"][t][h][rep] == {m: summary[m] for m in ("fg_IoU", "mask_AP50")}
        # the held-out sets are copies of one dataset: one model scores the same on each
        assert len({json.dumps(doc["heldout"][t][h]) for h in ("a", "b", "given")}) == 1
    row = next(r for r in doc["heldout_rows"] if (r["train"], r["heldout"]) == ("b", "a"))
    vals = [doc["heldout"]["b"]["a"][rep]["fg_IoU"] for rep in reps]
    assert row["fg_IoU mean"] == pytest.approx(np.mean(vals))
    assert row["fg_IoU std"] == pytest.approx(np.std(vals, ddof=1))
    # image wins: brute force over the per-image results of replicate k against replicate k
    for name, r in zip(("b", "given"), doc["rows"][1:], strict=True):
        counts = [0, 0, 0]
        for rep in reps:
            mine = json.loads((out / name / rep / "real" / "results.json").read_text())
            ref = json.loads((out / "a" / rep / "real" / "results.json").read_text())
            for x, y in zip(mine["per_image"], ref["per_image"], strict=True):
                assert x["name"] == y["name"]
                a, b = x["foreground_iou"], y["foreground_iou"]
                counts[0 if a > b else 1 if a < b else 2] += 1
        w = r["image fg_IoU"]
        assert [w["wins"], w["losses"], w["ties"]] == counts
        assert w["pairs"] == 4  # 2 replicates x 2 photos
        assert w["p"] == sign_test(counts[0], counts[1])
    assert len({doc["scores"][v][rep]["fg_IoU"] for v in ("a", "b") for rep in reps}) > 1
    md = (out / "transfer.md").read_text()
    assert "image wins vs a (fg_IoU)" in md
    assert "Held-out synthetic views, fg_IoU" in md
    assert "Held-out synthetic views, mask_AP50" in md
    with Image.open(out / "transfer.png") as im:
        assert im.size == (140 * 3 + 80, 720)  # the real set and the own held-out views
    # resumed: nothing is generated anew, trained or evaluated again; the same numbers
    fake.trained.clear()
    fake.evaluated = 0
    again = run_transfer(spec, out, num_threads=1, progress=False)
    assert (fake.trained, fake.evaluated) == ([], 0)
    assert again.to_dict() == res.to_dict()
    # a rebuilt model is evaluated again
    (out / "b" / "g7_seed1" / "model.pt").unlink()
    run_transfer(spec, out, num_threads=1, progress=False)
    assert [t[1] for t in fake.trained] == [out / "b" / "g7_seed1"]
    assert fake.evaluated == 1 + 3  # the real set and the three held-out sets


def test_transfer_without_generate_seeds_keeps_the_one_dataset_layout(
    small_dataset: Path, tiny_model: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    from mgn.learn.transfer import run_transfer

    fake = _FakeTransfer(small_dataset, tiny_model, monkeypatch)
    real = write_mgn_real(tmp_path / "dataset_real")
    spec = {
        "real": str(real),
        "scenes": 3,
        "generate_seed": 4,
        "seeds": [2, 0],
        "variants": [{"name": "a"}, {"name": "given", "dataset": str(small_dataset)}],
    }
    out = tmp_path / "out"
    run_transfer(spec, out, num_threads=1, progress=False)
    assert sorted(fake.generated) == [
        (out / "a" / "dataset", 3, 4),
        (out / "a" / "heldout", 2, 1004),
    ]
    assert sorted(p.name for p in (out / "a").iterdir()) == [
        "dataset",
        "heldout",
        "heldout_coco",
        "seed0",
        "seed2",
    ]
    assert sorted(p.name for p in (out / "given").iterdir()) == ["seed0", "seed2"]
    assert sorted(p.name for p in (out / "a" / "seed2").iterdir() if p.is_dir()) == [
        "heldout_a",
        "real",
    ]
    doc = json.loads((out / "transfer.json").read_text())
    assert doc["seeds"] == [2, 0]
    assert "generate_seeds" not in doc
    assert list(doc["scores"]["given"]) == ["2", "0"]
    res = json.loads((out / "given" / "seed0" / "real" / "results.json").read_text())
    assert doc["scores"]["given"]["0"]["mask_AP50"] == res["summary"]["mask_AP50"]
    assert sorted(doc["heldout"]["given"]) == ["a"]  # the given variant has no held-out set
    # heldout_scenes 0: no held-out set, no held-out section
    fake.generated.clear()
    out2 = tmp_path / "out2"
    run_transfer(spec | {"heldout_scenes": 0}, out2, num_threads=1, progress=False)
    assert fake.generated == [(out2 / "a" / "dataset", 3, 4)]
    assert not (out2 / "a" / "heldout").exists()
    assert not (out2 / "a" / "seed0" / "heldout_a").exists()
    md = (out2 / "transfer.md").read_text()
    assert "Held-out" not in md
    with Image.open(out2 / "transfer.png") as im:
        assert im.size == (140 * 2 + 80, 360)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"heldout_scenes": -1}, "'heldout_scenes' must be >= 0, got -1"),
        ({"heldout_scenes": 1.5}, "'heldout_scenes' must be a whole number"),
        ({"seeds": [0, 1.5]}, r"'seeds\[1\]' must be a whole number, got 1.5"),
        ({"seeds": "0 1"}, "'seeds' must be a non-empty list"),
        ({"generate_seeds": [0, 1]}, "'generate_seeds' has 2 entries but 'seeds' has 3"),
        ({"generate_seeds": [0, 1, "x"]}, r"'generate_seeds\[2\]' must be a whole number"),
        ({"generate_seed": True}, "'generate_seed' must be a whole number"),
        ({"scenes": 0}, "'scenes' must be >= 1"),
        ({"heldout_seed": 0}, "'heldout_seed' 0 is a training dataset seed"),
        ({"seeds": [1, 1, 2]}, r"replicates repeat: 'seeds' \[1, 1, 2\]"),
        (
            {"generate_seeds": [0, 1, 2], "variants": [{"name": "m", "dataset": "d"}]},
            "variant m: with 'generate_seeds' its 'dataset' must be a list of 3",
        ),
        (
            {"generate_seeds": [0, 1, 2], "variants": [{"name": "m", "dataset": ["d", "e"]}]},
            "variant m: with 'generate_seeds' its 'dataset' must be a list of 3",
        ),
        (
            {"variants": [{"name": "m", "dataset": ["d", "e", "f"]}]},
            "variant m: 'dataset' must be one dataset folder",
        ),
        ({"variants": [{"name": "m", "heldout": "h"}]}, "variant m: 'heldout' names the held-out"),
    ],
)
def test_transfer_spec_errors_name_the_key(
    change: dict, message: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    from mgn.learn import transfer

    def nothing(*args, **kwargs):
        raise AssertionError("nothing is generated or trained from a bad spec")

    monkeypatch.setattr(transfer, "generate", nothing)
    monkeypatch.setattr(transfer, "train", nothing)
    spec = {"real": "photos", "seeds": [0, 1, 2], "variants": [{"name": "a"}]} | change
    with pytest.raises(InvalidArgumentError, match=message):
        transfer.run_transfer(spec, tmp_path / "out", progress=False)


def _load_script(name: str):
    import importlib.util

    path = Path(__file__).resolve().parents[3] / "scripts" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_get_real_photos_on_a_hand_written_gqcnn_layout(
    tiny_model: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    """scripts/get_real_photos.py on files written in gqcnn's data/examples/clutter layout (PhoXi
    colour at twice the mask's size): COCO folders whose foreground is the mask; scored by
    ``mgn eval real`` as foreground IoU only (no mask AP)."""
    src = tmp_path / "gqcnn" / "data" / "examples" / "clutter"
    h, w = 6, 8
    masks = {}
    for sub, n, scale in (
        ("phoxi/dex-net_4.0", 5, 2),
        ("phoxi/fcgqcnn", 5, 2),
        ("primesense", 5, 1),
    ):
        (src / sub).mkdir(parents=True)
        for i in range(n):
            seg = np.zeros((h, w), np.uint8)
            seg[1 : 2 + i % 4, 2:6] = 255
            masks[f"{sub.replace('/', '_').replace('.', '')}_{i}.png"] = seg > 0
            big = np.kron(seg > 0, np.ones((scale, scale), bool))
            rgb = np.where(big[..., None], 220, 20).astype(np.uint8).repeat(3, axis=2)
            rgb[0, 0] = 24 if scale == 2 else 20  # a 2 x 2 block of 24, 20, 20, 20 -> 21
            Image.fromarray(rgb).save(src / sub / f"color_{i}.png")
            Image.fromarray(seg).save(src / sub / f"segmask_{i}.png")
            np.save(src / sub / f"depth_{i}.npy", np.full((h, w, 1), 0.7, np.float32))
    out = tmp_path / "real"
    assert _load_script("get_real_photos").main([str(tmp_path / "gqcnn"), str(out)]) == 0
    phoxi = read_real_set(out / "gqcnn_phoxi")
    assert len(phoxi) == 10
    assert len(read_real_set(out / "gqcnn_primesense")) == 5
    first = phoxi[0]
    assert first.rgb.shape == (h, w, 3)
    assert first.rgb[0, 0, 0] == 21
    assert first.masks.shape == (0, h, w)
    assert first.depth is not None
    assert np.allclose(first.depth, 0.7)
    for img in phoxi:
        np.testing.assert_array_equal(img.foreground, masks[img.name])

    def perfect(self, rgb, depth=None, *, name="image", **settings):
        ids = masks[name].astype(np.int32)
        inst = InstanceMaps(ids, np.ones(1, np.float32), None)
        return Prediction(inst, ids.astype(np.float32), np.zeros(ids.shape, np.float32))

    monkeypatch.setattr(Predictor, "predict", perfect)
    res = evaluate_real(tiny_model, out / "gqcnn_phoxi", progress=False)
    assert res.foreground_iou == 1.0
    assert res.brightness_iou == 1.0
    assert (res.num_objects, res.mask_ap, res.mask_ap50) == (0, None, None)
    assert res.summary()["fg_IoU_brightness"] == 1.0
