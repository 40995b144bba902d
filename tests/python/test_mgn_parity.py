"""MetaGraspNet parity of the files (issue 16, item 1): the layouts of ``scene_gt.json`` and
``{v}_order.json`` against values derived by hand from MetaGraspNet's sample scene format, the
suction tool pose convention and integer-valued labels."""

from __future__ import annotations

import json

import h5py
import numpy as np
import pytest
from view_labels.test_layout import layout_of, rect

from mgn.io.scene_folder import scene_gt_entries


def test_scene_gt_rotation_is_a_nested_3x3_list_as_metagraspnet_writes_it():
    # Object rotated by +90 deg about the camera z axis, 10, 20, 70 cm from the camera.
    X = np.eye(4)
    X[:3, :3] = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    X[:3, 3] = [0.1, 0.2, 0.7]
    (entry,) = json.loads(json.dumps(scene_gt_entries(X[None], [7])))
    assert entry["cam_R_m2c"] == [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    assert entry["cam_t_m2c"] == [10.0, 20.0, 70.0]
    assert entry["obj_id"] == 7
    assert isinstance(entry["obj_id"], int)
    # MetaGraspNet's colored_pcl.py --visualize_pose builds the pose as R[i][j], t[i] / 100.
    R, t = entry["cam_R_m2c"], entry["cam_t_m2c"]
    T = np.array([[R[i][0], R[i][1], R[i][2], t[i] / 100.0] for i in range(3)] + [[0, 0, 0, 1]])
    assert np.allclose(T, X)


def test_order_json_total_covered_edge_is_the_sum_of_the_childrens_edge_sizes():
    # A bar (id 1, rows 15..24, all columns) lies over B (id 2, cols 5..34) and C (id 3, cols
    # 45..74), both rows 10..29. B's visible pixels next to A: row 14 and row 25 over 30 columns
    # = 60 px; the same for C. In MetaGraspNet's sample scenes (dataset_sim/scene20/0_order.json)
    # an object's total_covered_edge is the sum of its children's edge_size (object 1: one child
    # of edge 800 -> 800) and 0 for an object without children.
    H, W = 40, 80
    L = layout_of(
        [rect(H, W, 15, 0, 25, 80), rect(H, W, 10, 5, 30, 35), rect(H, W, 10, 45, 30, 75)],
        [0.8, 0.9, 0.9],
        H,
        W,
    )
    order = json.loads(json.dumps(L.order_json()))
    assert [(c["id"], c["edge_size"]) for c in order["1"]["children"]] == [(2, 60), (3, 60)]
    assert order["1"]["total_covered_edge"] == 120
    assert order["2"]["total_covered_edge"] == 0
    assert order["3"]["total_covered_edge"] == 0
    assert [(p["id"], p["edge_size"]) for p in order["2"]["parents"]] == [(1, 60)]
    assert order["1"]["parents"] == [{"id": 0, "depth_diff": 0.0, "edge_size": 0.0}]
    for obj in order.values():
        assert obj["total_covered_edge"] == sum(c["edge_size"] for c in obj["children"])


def test_generated_files_follow_metagraspnet(small_dataset):
    scene = small_dataset / "scene0"
    gt = json.loads((scene / "scene_gt.json").read_text())
    for entries in gt.values():
        for e in entries:
            R = np.asarray(e["cam_R_m2c"])
            assert R.shape == (3, 3)
            assert np.allclose(R @ R.T, np.eye(3), atol=1e-5)
            assert isinstance(e["obj_id"], int)
    v = int(next(iter(gt)))
    with h5py.File(scene / f"{v}_scene.hdf5", "r") as h5:
        su = h5["non_colliding_grasps/suctioncup"]
        tool, contact = (
            su["suction_poses_relative_to_camera"][:],
            su["contact_poses_relative_to_camera"][:],
        )
        # Stored as a virtual dataset over the contact poses' rotation; h5py reads the array.
        assert len(tool) > 0
        assert su["suction_poses_relative_to_camera"].is_virtual
        assert np.array_equal(tool[:, :3, :3], contact[:, :3, :3])
        # MetaGraspNet: tool origin 2 cm (cup) + 11.21 cm (tool) behind the contact (cm files).
        back = contact[:, :3, 3] - tool[:, :3, 3]
        assert np.allclose(np.linalg.norm(back, axis=1), 13.21, atol=1e-3)
        assert np.allclose(back / 13.21, contact[:, :3, 2], atol=1e-4)
        for group in ("non_colliding_grasps", "colliding_grasps"):
            for kind in ("paralleljaw", "suctioncup"):
                assert h5[f"{group}/{kind}/object_id"].dtype.kind == "i"
        assert h5["objects/categories"].dtype.kind == "i"
        assert h5["keypts/byhand/object_id"].dtype.kind == "i"
    order = json.loads((scene / f"{v}_order.json").read_text())
    for obj in order.values():
        assert obj["total_covered_edge"] == sum(c["edge_size"] for c in obj["children"])


def test_object_failure_reason_is_stored_as_integers(small_dataset):
    files = sorted((small_dataset / "models").glob("*/textured.obj.hdf5"))
    assert files
    with h5py.File(files[0], "r") as h5:
        reason = h5["grasps/suctioncup/failure_reason"]
        assert reason.dtype.kind == "u"
        assert len(reason) == len(h5["grasps/suctioncup/quality_score"])


def test_camera_params_in_metagraspnet_units():
    # MetaGraspNet's dataset_sim/scene83/1_camera_params.json (its synthetic camera, 1200 px):
    # "fx": 2004.2949249780754, "focal_length": 35.0, "horizontal_aperture": 20.954999923706055,
    # "horizontal_fov": 0.581733823962242, "clipping_range": [1.0, 1000000.0]. By hand: the
    # field of view is 2 atan(600 / 2004.2949) = 2 * 0.2908669 = 0.5817338 rad (33.33 deg would
    # be degrees); the clipping range is in cm (its stage unit), 1 cm to 10 km.
    from mgn.scene.cameras import Intrinsics

    p = json.loads(json.dumps(Intrinsics.mgn_synthetic().camera_params()))
    assert p["horizontal_fov"] == pytest.approx(0.581733823962242, abs=1e-7)
    assert p["vertical_fov"] == pytest.approx(0.581733823962242, abs=1e-7)
    assert p["focal_length"] == 35.0
    assert p["horizontal_aperture"] == pytest.approx(20.954999923706055, abs=1e-6)
    assert p["fx"] == pytest.approx(2004.2949249780754, abs=1e-4)
    assert p["clipping_range"] == [1.0, 1000000.0]
    assert p["resolution"] == {"height": 1200, "width": 1200}
    # A 2:1 sensor: the vertical field from the height (2 atan(300 / 1000) = 0.5829135 rad).
    q = Intrinsics(1200, 600, 1000.0, 1000.0, 600.0, 300.0).camera_params()
    assert q["horizontal_fov"] == pytest.approx(2 * 0.5404195, abs=1e-6)
    assert q["vertical_fov"] == pytest.approx(0.5829135, abs=1e-6)


def test_order_json_occlusion_has_four_decimals():
    # MetaGraspNet's dataset_sim/scene20/0_order.json: "occlusion": 0.01679999940097332 (the
    # float32 of 0.0168) and 0.07540000230073929 (0.0754): rates to 4 decimals. A (a 1 x 13 px
    # strip at 0.7 m) lies on B (20 x 30 px at 0.8 m): B's occlusion is 13 / 600 = 0.021666...,
    # written as 0.0217.
    H, W = 40, 80
    L = layout_of([rect(H, W, 15, 5, 16, 18), rect(H, W, 10, 5, 30, 35)], [0.7, 0.8], H, W)
    assert L.occlusion[1] == pytest.approx(13 / 600)
    order = json.loads(json.dumps(L.order_json()))
    assert order["2"]["occlusion"] == 0.0217
    assert order["1"]["occlusion"] == 0.0
