"""The scene-folder writer, the Dataset reader, the COCO export and the validator, on hand-made
views whose every value is known."""

from __future__ import annotations

import hashlib
import json
import math
import time

import numpy as np
import pytest
from conftest import coco_ground_truth_ap

from mgn.base.deterministic import npz_bytes
from mgn.errors import InvalidArgumentError
from mgn.io.coco import coco_dict, export_coco, rle
from mgn.io.dataset import Dataset, intrinsics_from_params
from mgn.io.image_codecs import com_heatmap_prediction
from mgn.io.scene_folder import scene_gt_entries, write_scene_gt, write_view
from mgn.io.scene_hdf5 import hdf5_bytes
from mgn.io.scene_schema import ViewRecord, from_cm, to_cm, view_file_names
from mgn.io.validate import validate_dataset
from mgn.scene.cameras import Intrinsics
from mgn.view_labels.layout import compute_layout

H, W = 40, 60


def _pose(t: tuple[float, float, float]) -> np.ndarray:
    X = np.eye(4)
    X[:3, 3] = t
    return X


def _record(v: int, shift: int = 0) -> ViewRecord:
    """Two boxes: instance 2 (0.65 m) lies on instance 1 (0.7 m) and hides its right part; a
    third instance is a 3 x 3 px speck on its own. The layout files are compute_layout's."""
    K = Intrinsics(W, H, 50.0, 50.0, W / 2, H / 2)
    amodal = np.zeros((3, H, W), bool)
    amodal[0, 5:25, 5 + shift : 35 + shift] = True
    amodal[1, 10:30, 25 + shift : 50 + shift] = True
    amodal[2, 1:4, 55:58] = True
    inst = np.zeros((H, W), np.int32)
    inst[amodal[0]] = 1
    inst[amodal[1]] = 2
    inst[amodal[2]] = 3
    occ = np.round(np.array([1 - (inst == 1).sum() / amodal[0].sum(), 0.0, 0.0]), 4)
    occ_map = np.zeros((H, W), np.float32)
    for i in range(3):
        occ_map[inst == i + 1] = occ[i]
    sem = np.where(inst > 0, inst + 10, 0)
    depth = np.full((H, W), 0.7, np.float32)
    depth[inst == 2] = 0.65
    depth[0, 0] = np.nan
    X_CO = np.stack([_pose((0.01, 0.02, 0.7)), _pose((0.02, 0.02, 0.65)), _pose((0.1, -0.1, 0.7))])
    hand = np.tile(_pose((0.0, 0.0, 0.5)), (2, 1, 1))
    pj = "non_colliding_grasps/paralleljaw/"
    h5 = {
        "camera/pose_relative_to_world": _pose((0.0, 0.0, 0.7))[None],
        "objects/poses_relative_to_camera": X_CO,
        "objects/categories": np.array([11, 12, 13]),
        "objects/bbox_loose": np.array(
            [[5 + shift, 5, 30, 20], [25 + shift, 10, 25, 20], [55, 1, 3, 3]]
        ),
        "objects/bbox_tight": np.array(
            [[5 + shift, 5, 30, 20], [25 + shift, 10, 25, 20], [55, 1, 3, 3]]
        ),
        "objects/occlusion": occ,
        "objects/scene_instance_id": np.array([1, 2, 3]),
        pj + "franka_poses_relative_to_camera": hand,
        pj + "contact_poses_relative_to_camera": hand,
        pj + "contact_width": np.array([0.05, 0.031]),
        pj + "score_analytical": np.array([1.0, 0.5]),
        pj + "score_simulation": np.array([0.75, 0.25]),
        pj + "score_wrench": np.array([0.5, 0.5]),
        pj + "object_id": np.array([0, 1]),
        "keypts/byhand/keypts_relative_to_camera": np.array([[1, 0.01, 0.02, 0.6]]),
        "keypts/byhand/object_id": np.array([1]),
        "keypts/byhand/occluded_keypts_relative_to_camera": np.zeros((0, 4)),
        "keypts/byhand/occluded_object_id": np.zeros(0, np.int32),
    }
    layout = compute_layout(
        inst, amodal, depth, [11, 12, 13], ["no_rel", "edge", "no_rel"], occlusion=occ
    )
    rgb = np.zeros((H, W, 3), np.uint8)
    rgb[..., 0] = inst * 100
    return ViewRecord(
        index=v,
        rgb=rgb,
        depth=depth,
        depth_ideal=depth,
        valid_depth=np.isfinite(depth),
        instances=inst,
        semantic=sem,
        occlusion_map=occ_map,
        amodal=amodal,
        intrinsics=K,
        scene_hdf5=h5,
        order_json=layout.order_json(),
        order_csv=layout.order_csv(),
        layout_json=layout.layout_json(),
        extra_npz={"com_heatmap": np.zeros((H, W), np.float32)},
    )


@pytest.fixture
def dataset(tmp_path):
    root = tmp_path / "ds"
    for s in range(2):
        folder = root / f"scene{s}"
        recs = [_record(v, shift=3 * v + s) for v in range(2)]
        for r in recs:
            write_view(folder, r)
        key = "objects/poses_relative_to_camera"
        gt = {r.index: scene_gt_entries(r.scene_hdf5[key], [11, 12, 13]) for r in recs}
        write_scene_gt(folder, gt)
        (folder / "scene.json").write_text(
            json.dumps(
                {
                    "instances": [
                        {"instance_id": 1, "name": "box_a", "category_id": 11},
                        {"instance_id": 2, "name": "box_b", "category_id": 12},
                        {"instance_id": 3, "name": "box_c", "category_id": 13},
                    ]
                }
            )
        )
    return root


def test_cm_rules_round_trip():
    X = np.tile(_pose((0.1, -0.2, 0.3)), (3, 1, 1))
    cm = to_cm("a/franka_poses_relative_to_camera", X)
    assert np.allclose(cm[:, :3, 3], [10, -20, 30])
    assert np.allclose(cm[:, :3, :3], np.eye(3))
    kp = np.array([[7.0, 0.01, 0.02, 0.03]])
    assert np.allclose(to_cm("keypts/com/keypts_relative_to_camera", kp), [[7, 1, 2, 3]])
    assert np.allclose(to_cm("x/contact_width", [0.05]), [5.0])
    assert np.allclose(to_cm("x/score_analytical", [0.5]), [0.5])
    assert np.allclose(from_cm("a/poses_relative_to_camera", cm), X)


def test_written_view_reads_back_in_si(dataset):
    ds = Dataset(dataset)
    assert ds.scene_ids == [0, 1]
    assert len(ds) == 2
    scene = ds.scene(1)
    assert scene.view_ids == [0, 1]
    rec = _record(1, shift=4)
    view = scene.view(1)
    assert np.array_equal(view.rgb, rec.rgb)
    d = view.depth
    assert np.isnan(d[0, 0])
    assert np.allclose(d[1:, :], rec.depth[1:, :], atol=1e-6)
    # The file itself is in cm.
    assert np.isclose(np.nanmax(view.npz["depth"]), 70.0)
    assert np.array_equal(view.instances, rec.instances)
    assert np.array_equal(view.semantic, rec.semantic)
    assert np.array_equal(view.amodal, rec.amodal)
    assert np.allclose(view.X_CO, rec.scene_hdf5["objects/poses_relative_to_camera"], atol=1e-6)
    assert np.allclose(view.X_WC[:3, 3], [0, 0, 0.7], atol=1e-6)
    pj = view.grasps("paralleljaw")
    assert np.allclose(pj["contact_width"], [0.05, 0.031], atol=1e-6)
    assert np.allclose(pj["franka_poses_relative_to_camera"][:, 2, 3], 0.5, atol=1e-6)
    assert view.grasps("suctioncup") == {}
    kp = view.hdf5["keypts/byhand/keypts_relative_to_camera"]
    assert np.allclose(kp, [[1, 0.01, 0.02, 0.6]], atol=1e-6)
    assert view.relation_matrix[0, 1] == -1
    assert view.relation_matrix[1, 0] == 1
    assert np.count_nonzero(view.relation_matrix) == 2
    assert view.order["1"]["parents"][0]["id"] == 2
    assert view.layout["difficulty"] == 2
    K = view.intrinsics
    assert (K.width, K.height, K.fx) == (W, H, 50.0)
    gt = scene.scene_gt
    assert [e["obj_id"] for e in gt["1"]] == [11, 12, 13]
    assert np.allclose(gt["1"][1]["cam_t_m2c"], [2, 2, 65])
    with h5_open(view.path("_scene.hdf5")) as h5:
        assert h5["objects/bbox_loose"].dtype == np.float32
        assert h5["objects/categories"].dtype == np.int32  # integer-valued labels as integers


def h5_open(path):
    import h5py

    return h5py.File(path, "r")


def test_intrinsics_from_metagraspnet_keys():
    K = Intrinsics.mgn_synthetic()
    p = K.camera_params()
    for k in ("fx", "fy", "cx", "cy", "width", "height"):
        del p[k]
    K2 = intrinsics_from_params(p)
    assert (K2.width, K2.height) == (K.width, K.height)
    assert np.isclose(K2.fx, K.fx, rtol=1e-9)
    assert np.isclose(K2.cx, K.cx)


def test_files_are_reproducible(tmp_path):
    arrays = {"a": np.arange(6, dtype=np.float32).reshape(2, 3), "b": np.ones(3, bool)}
    assert npz_bytes(**arrays) == npz_bytes(**arrays)
    with np.load(__import__("io").BytesIO(npz_bytes(**arrays))) as z:
        assert np.array_equal(z["a"], arrays["a"])
        assert z["b"].dtype == bool
    assert hdf5_bytes({"g/x": np.ones(3)}) == hdf5_bytes({"g/x": np.ones(3)})
    digests = []
    for k in range(2):
        write_view(tmp_path / str(k), _record(0))
        digests.append(
            {
                p.name: hashlib.sha256(p.read_bytes()).hexdigest()
                for p in (tmp_path / str(k)).iterdir()
            }
        )
    assert digests[0] == digests[1]
    assert len(digests[0]) == len(view_file_names(0))
    # Timing the parts (the benchmark's breakdown) changes no byte, and accounts for the
    # calling thread's CPU time of the call.
    times: dict[str, float] = {}
    t0 = time.thread_time()
    write_view(tmp_path / "timed", _record(0), times=times)
    spent = time.thread_time() - t0
    assert {
        p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in (tmp_path / "timed").iterdir()
    } == digests[0]
    assert set(times) == {
        "arrays",
        "rgb.png",
        "npz",
        "depth.png",
        "scene.hdf5",
        "mgn.hdf5",
        "json and csv",
        "files",
    }
    assert all(t >= 0.0 for t in times.values())
    assert sum(times.values()) <= spent + 1e-6


def test_record_checks_shapes():
    rec = _record(0)
    with pytest.raises(ValueError, match="depth must be"):
        ViewRecord(**{**rec.__dict__, "depth": np.zeros((3, 3), np.float32)})
    with pytest.raises(ValueError, match=r"instance ids must be in 0..3"):
        ViewRecord(**{**rec.__dict__, "instances": np.full((H, W), 4)})
    h5 = dict(rec.scene_hdf5)
    del h5["objects/categories"]
    with pytest.raises(ValueError, match="lacks 'objects/categories'"):
        ViewRecord(**{**rec.__dict__, "scene_hdf5": h5})


def test_coco_ground_truth_scores_ap_one(dataset, tmp_path):
    from pycocotools.coco import COCO

    path = export_coco(dataset, tmp_path / "annotations.json")
    gt = COCO(str(path))
    assert len(gt.getImgIds()) == 4
    assert sorted(c["name"] for c in gt.loadCats(gt.getCatIds())) == ["box_a", "box_b", "box_c"]
    anns = gt.loadAnns(gt.getAnnIds())
    assert len(anns) == 12  # 3 instances x 4 views
    a0 = next(a for a in anns if a["instance_id"] == 1 and a["image_id"] == 0)
    # Instance 2 covers rows 10..24 x cols 25..34 of instance 1: its box keeps the full width.
    assert a0["bbox"] == [5.0, 5.0, 30.0, 20.0]
    assert a0["area"] == 600 - 150
    assert a0["amodal_bbox"] == [5.0, 5.0, 30.0, 20.0]
    assert np.isclose(a0["occlusion"], 150 / 600)
    assert a0["layer"] == 1
    assert gt.loadImgs([0])[0]["difficulty"] == 2
    assert coco_ground_truth_ap(gt) == (pytest.approx(1.0), pytest.approx(1.0))
    agnostic = coco_dict(Dataset(dataset), class_agnostic=True)
    assert agnostic["categories"] == [{"id": 1, "name": "object", "supercategory": "object"}]
    assert {a["category_id"] for a in agnostic["annotations"]} == {1}


def test_rle_decodes_to_the_mask():
    from pycocotools import mask as mask_utils

    m = np.zeros((7, 9), bool)
    m[2:5, 3:8] = True
    r = rle(m)
    back = mask_utils.decode({"size": r["size"], "counts": r["counts"].encode()})
    assert np.array_equal(back.astype(bool), m)


def test_validate_finds_corruption(dataset):
    assert validate_dataset(dataset) == []
    # A truncated npz, a missing csv, a visible mask outside its amodal mask.
    npz = dataset / "scene0" / "1.npz"
    npz.write_bytes(npz.read_bytes()[:100])
    (dataset / "scene1" / "0_order.csv").unlink()
    bad = _record(1, shift=4)
    amodal = bad.amodal.copy()
    amodal[1, :, :] = False
    write_view(dataset / "scene1", ViewRecord(**{**bad.__dict__, "amodal": amodal}))
    found = [str(p) for p in validate_dataset(dataset)]
    assert any("scene0/1.npz" in p and "not a readable npz" in p for p in found), found
    assert any("scene1/0_order.csv: missing" in p for p in found), found
    assert any("scene1/1.npz" in p and "not inside its amodal mask" in p for p in found), found


def test_validate_checks_the_manifest(dataset):
    folder = dataset / "scene0"
    files = {
        p.name: {"size": p.stat().st_size, "sha256": hashlib.sha256(p.read_bytes()).hexdigest()}
        for p in folder.iterdir()
    }
    (folder / "manifest.json").write_text(json.dumps({"files": files}))
    assert validate_dataset(dataset) == []
    rgb = folder / "0_rgb.png"
    data = bytearray(rgb.read_bytes())
    data[-20] ^= 0xFF
    rgb.write_bytes(bytes(data))
    found = [str(p) for p in validate_dataset(dataset)]
    assert any("scene0/manifest.json: '0_rgb.png' does not match its checksum" in p for p in found)


def test_dataset_errors(tmp_path):
    from mgn.errors import IoError

    with pytest.raises(IoError, match="is not a folder"):
        Dataset(tmp_path / "nope")
    (tmp_path / "empty").mkdir()
    assert Dataset(tmp_path / "empty").scene_ids == []
    assert [str(p) for p in validate_dataset(tmp_path / "empty")] == [".: no scene<N> folders"]
    with pytest.raises(IoError, match="no scene3"):
        Dataset(tmp_path / "empty").scene(3)


def test_validate_and_coco_commands(dataset, tmp_path, capsys):
    from mgn.cli.main import main

    assert main(["validate", str(dataset)]) == 0
    assert "valid" in capsys.readouterr().out
    out = tmp_path / "coco.json"
    assert main(["coco", str(dataset), "-o", str(out), "--scenes", "1", "--class-agnostic"]) == 0
    data = json.loads(out.read_text())
    assert {im["scene_id"] for im in data["images"]} == {1}
    assert len(data["annotations"]) == 6
    (dataset / "scene0" / "0_camera_params.json").unlink()
    assert main(["validate", str(dataset)]) == 1
    assert "scene0/0_camera_params.json: missing" in capsys.readouterr().out


def test_show_draws_the_view(dataset, tmp_path):
    from PIL import Image

    from mgn.cli.main import main
    from mgn.viz.overlay import instance_colors, project, render_overlay

    out = tmp_path / "v.png"
    assert (
        main(
            [
                "show",
                str(dataset),
                "--scene",
                "0",
                "--view",
                "1",
                "--grasps",
                "pj",
                "--layout",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    with Image.open(out) as im:
        assert im.size[0] == W
        assert im.size[1] > H
    view = Dataset(dataset).scene(0).view(1)
    img = render_overlay(view, keypoints=False)
    # Instance colours are blended over the visible pixels only; the background below the
    # objects (rows 32.., clear of their id labels too) is unchanged.
    inst = view.instances
    assert np.array_equal(img[32:H], view.rgb[32:])
    assert not inst[32:].any()
    assert not np.array_equal(img[:H][inst == 2], view.rgb[inst == 2])
    cols = instance_colors(5)
    assert len({tuple(c) for c in cols[1:]}) == 5
    assert tuple(cols[0]) == (0, 0, 0)
    uv, front = project(
        [[0.0, 0.0, 1.0], [0.1, 0.0, -1.0]], np.array([[50, 0, 30], [0, 50, 20], [0, 0, 1.0]])
    )
    assert np.allclose(uv[0], [30, 20])
    assert list(front) == [True, False]
    with pytest.raises(ValueError, match="unknown grasp kind 'magnetic'"):
        render_overlay(view, grasps="magnetic")


def test_show_outline_mode_panels_and_a_single_scene_folder(dataset, tmp_path):
    from PIL import Image

    from mgn.cli import main
    from mgn.viz.overlay import render_overlay

    view = Dataset(dataset).scene(0).view(1)
    inst = view.instances
    fg = inst > 0

    def unchanged(alpha: float) -> int:  # visible-mask pixels where the RGB shows through
        img = render_overlay(view, keypoints=False, alpha=alpha)
        return int(np.all(img[:H][fg] == view.rgb[fg], axis=-1).sum())

    # Outline mode: only the mask borders, amodal contours and labels cover the RGB; with a
    # tint every visible pixel changes but those under the labels' white strokes.
    assert unchanged(0.0) > unchanged(0.45) + 0.15 * fg.sum()
    assert unchanged(1.0) <= unchanged(0.45)
    panels = render_overlay(view, keypoints=False, panels=True)
    assert panels.shape[1] == 3 * W
    amodal_panel = panels[24:H, W : 2 * W]  # below the panel's title
    any_amodal = view.amodal.any(axis=0)[24:]
    assert any_amodal.any()
    assert (amodal_panel.sum(axis=-1) > 0)[any_amodal].all()
    assert (amodal_panel.sum(axis=-1) == 0)[~any_amodal].all()
    with pytest.raises(ValueError, match="alpha"):
        render_overlay(view, alpha=1.5)
    # A single scene folder (as `mgn scene label` writes it) works without --scene.
    out = tmp_path / "s.png"
    assert (
        main(
            [
                "show",
                str(dataset / "scene0"),
                "--view",
                "1",
                "--alpha",
                "0",
                "--panels",
                "--grasps",
                "paralleljaw",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    with Image.open(out) as im:
        assert im.size[0] == 3 * W
    assert main(["show", str(dataset), "--view", "1", "-o", str(out)]) == 1  # which scene?


def test_report_is_a_self_contained_page(dataset, tmp_path):
    from mgn.cli.main import main
    from mgn.viz.report import collect_stats

    out = tmp_path / "r.html"
    assert main(["report", str(dataset), "-o", str(out)]) == 0
    page = out.read_text()
    assert page.startswith("<!DOCTYPE html>")
    assert "data:image/png;base64," in page
    assert "<svg" in page
    assert "http://" not in page.replace("http://www.w3.org/2000/svg", "")
    stats = collect_stats(Dataset(dataset))
    assert stats["scenes"] == 2
    assert stats["views_sampled"] == 4
    assert stats["visible_per_view"] == [3, 3, 3, 3]
    assert stats["layers"] == {"0": 8, "1": 4}
    assert stats["difficulty"] == {"2": 4}
    assert stats["grasp_counts"]["non_colliding"] == {"paralleljaw": 8}


def test_large_hdf5_datasets_are_compressed_and_exact():
    import io as _io

    import h5py

    rng = np.random.default_rng(0)
    big = np.repeat(rng.normal(size=(1, 4, 4)), 5000, axis=0).astype(np.float32)
    data = hdf5_bytes({"g/poses": big, "g/small": np.arange(3, dtype=np.float32)})
    assert len(data) < big.nbytes / 4
    with h5py.File(_io.BytesIO(data), "r") as h5:
        assert h5["g/poses"].compression == "gzip"
        assert h5["g/small"].compression is None
        assert np.array_equal(h5["g/poses"][()], big)


def _com_pixel(u, v, z, X, K, p):
    """One pixel of the CoM heat-map prediction, in plain Python floats (IEEE float64, the
    documented order of operations)."""
    fx, fy, cx, cy = K
    x = (((u + 0.5) - cx) * z) / fx
    y = (((v + 0.5) - cy) * z) / fy
    d2 = 0.0
    for r in range(3):
        a = (((x * X[r][0] + y * X[r][1]) + z * X[r][2]) + X[r][3]) - p[r]
        d2 += a * a
    span = max(p[4] - p[3], 1e-12)
    return np.float32(min(max((p[4] - math.sqrt(d2)) / span, 0.0), 1.0))


def _com_prediction_numpy(depth, inst, X, K, params) -> np.ndarray:
    """The prediction in numpy float64 arrays, element-wise in the documented order (mgn's
    implementation before the C++ one): a second implementation for every pixel."""
    fx, fy, cx, cy = (float(k) for k in K)
    out = np.zeros(inst.shape, np.float32)
    v, u = np.nonzero(inst > 0)
    z = depth[v, u].astype(np.float64)
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(z) & (z > 0.0)
    v, u, z = v[ok], u[ok], z[ok]
    c = params[inst[v, u] - 1]
    x = (u.astype(np.float64) + 0.5 - cx) * z / fx
    y = (v.astype(np.float64) + 0.5 - cy) * z / fy
    d2 = np.zeros_like(z)
    for r in range(3):
        a = x * X[r, 0]
        a += y * X[r, 1]
        a += z * X[r, 2]
        a += X[r, 3]
        a -= c[:, r]
        d2 = a * a if r == 0 else d2 + a * a
    span = np.maximum(c[:, 4] - c[:, 3], 1e-12)
    out[v, u] = np.clip((c[:, 4] - np.sqrt(d2)) / span, 0.0, 1.0)
    return out


def test_com_heatmap_prediction_matches_the_per_pixel_formula_to_the_bit():
    """The prediction (C++ core) equals, bit for bit, the formula computed one pixel at a time
    in Python floats (every ~11th pixel) and the numpy element-wise version (every pixel); an
    instance id beyond the parameters' rows is an error naming both counts."""
    rng = np.random.default_rng(7)
    h, w, n = 240, 310, 5  # 74,400 pixels: several blocks
    inst = rng.integers(0, n + 1, (h, w))
    depth = rng.uniform(0.3, 0.9, (h, w)).astype(np.float32)
    depth[rng.random((h, w)) < 0.01] = np.nan  # no depth: prediction 0
    X = np.eye(4)
    X[:3, :3] = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    X[:3, 3] = rng.normal(size=3)
    K = [301.5, 299.25, 154.7, 121.3]
    # Centres of mass on the rays of random pixels at 0.6 m, so the scores span [0, 1].
    u0, v0 = rng.uniform(0, w, n), rng.uniform(0, h, n)
    p_C = np.column_stack([0.6 * (u0 - K[2]) / K[0], 0.6 * (v0 - K[3]) / K[1], np.full(n, 0.6)])
    c_W = p_C @ X[:3, :3].T + X[:3, 3]
    params = np.column_stack([c_W, rng.uniform(0.0, 0.05, n), rng.uniform(0.2, 0.4, n)])
    pred = com_heatmap_prediction(depth, inst, X, K, params)
    assert pred.dtype == np.float32
    assert pred.shape == (h, w)
    assert pred.tobytes() == _com_prediction_numpy(depth, inst, X, K, params).tobytes()
    # Instance ids as the npz stores them (uint8) give the same bits.
    assert (
        pred.tobytes()
        == com_heatmap_prediction(depth, inst.astype(np.uint8), X, K, params).tobytes()
    )
    with pytest.raises(InvalidArgumentError, match="instance id 6 but only 5 rows"):
        com_heatmap_prediction(depth, np.where(inst == 1, 6, inst), X, K, params)
    ok = (inst > 0) & np.isfinite(depth)
    assert np.all(pred[~ok] == 0)
    assert 0.05 < np.mean(pred[ok] > 0) < 1.0
    Xl = X.tolist()
    for v, u in zip(*np.nonzero(ok), strict=True):
        if (u * 7 + v * 13) % 11:
            continue  # every ~11th pixel: ~6,000 of them
        p = params[inst[v, u] - 1].tolist()
        want = _com_pixel(float(u), float(v), float(depth[v, u]), Xl, K, p)
        assert pred[v, u].view(np.uint32) == want.view(np.uint32), (v, u)
