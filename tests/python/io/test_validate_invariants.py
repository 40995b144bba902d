"""``mgn validate`` rejects a dataset carrying each defect of the files' conventions, made by
editing one file of a good generated dataset (docs/format.md): ids with a gap, a relation with a
negative depth difference, a boundary counted for both directions of a pair, a parentless object
outside layer 0, layers that the graph does not give, degrees and metres where the files hold
radians and centimetres, occlusion rates beyond 4 decimals, the old keypts/com layout, grasps
without a physics score that dataset.json does not record, suction grasps with and without a
physics score in one view, scene_gt.json entries out of step."""

from __future__ import annotations

import io
import json
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

from mgn.io.order_files import derive_layers
from mgn.io.validate import validate_dataset


@pytest.fixture
def ds(small_dataset: Path, tmp_path: Path) -> Path:
    out = tmp_path / "ds"
    shutil.copytree(small_dataset, out)
    assert validate_dataset(out) == []
    return out


def _messages(root: Path, name: str) -> list[str]:
    """The problems reported for file ``name`` of scene 0."""
    return [p.message for p in validate_dataset(root) if p.path == f"scene0/{name}"]


def _edit_json(path: Path, edit) -> None:
    doc = json.loads(path.read_text())
    edit(doc)
    path.write_text(json.dumps(doc))


def _rewrite_npz(path: Path, **changes: np.ndarray) -> None:
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    arrays.update(changes)
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    path.write_bytes(buf.getvalue())


def _a_relation(order: dict) -> tuple[str, dict]:
    """(child key, its first parent entry) of the first object that has a parent."""
    for key, entry in order.items():
        for p in entry["parents"]:
            if p["id"]:
                return key, p
    raise AssertionError("the view has no relation")


def test_an_id_without_pixels_is_rejected(ds: Path) -> None:
    # As mgn wrote hidden objects before: the object keeps its id but shows no pixel.
    npz = ds / "scene0" / "0.npz"
    with np.load(npz) as z:
        ids = z["instances_objects"].copy()
    k = int(ids.max())
    ids[ids == k] = 0
    _rewrite_npz(npz, instances_objects=ids)
    assert any(f"instances [{k}] have no visible pixel" in m for m in _messages(ds, "0.npz"))


def test_a_negative_depth_difference_is_rejected(ds: Path) -> None:
    path = ds / "scene0" / "0_order.json"

    def flip(order: dict) -> None:
        child, p = _a_relation(order)
        p["depth_diff"] = -p["depth_diff"]
        for c in order[str(p["id"])]["children"]:
            if c["id"] == int(child):
                c["depth_diff"] = p["depth_diff"]

    _edit_json(path, flip)
    assert any("expected depth_diff >= 0" in m for m in _messages(ds, "0_order.json"))


def test_a_boundary_counted_for_both_directions_is_rejected(ds: Path) -> None:
    # The reverse of a relation added with the same boundary and the opposite sign, in every
    # file that holds the graph: depth_diff < 0, and the masks do not back it.
    path = ds / "scene0" / "0_order.json"
    order = json.loads(path.read_text())
    child, p = _a_relation(order)
    parent = str(p["id"])
    back = {"id": int(child), "depth_diff": -p["depth_diff"], "edge_size": p["edge_size"]}
    entry = order[parent]
    entry["parents"] = [e for e in entry["parents"] if e["id"]] + [back]
    order[child]["children"].append({**back, "id": int(parent)})
    order[child]["total_covered_edge"] += back["edge_size"]
    path.write_text(json.dumps(order))
    csv = ds / "scene0" / "0_order.csv"
    m = np.loadtxt(csv, delimiter=",", ndmin=2).astype(int)
    m[int(parent) - 1, int(child) - 1] = -1
    csv.write_text("".join(",".join(str(x) for x in row) + "\n" for row in m))
    found = _messages(ds, "0_order.json")
    assert any(f"{child} over {parent}" in m and "depth_diff >= 0" in m for m in found), found
    assert any(f"{child} over {parent}" in m and "seen on" in m for m in found), found


def test_a_parentless_object_outside_layer_0_is_rejected(ds: Path) -> None:
    path = ds / "scene0" / "0_order.json"
    order = json.loads(path.read_text())
    top = next(k for k, e in order.items() if [p["id"] for p in e["parents"]] == [0])
    order[top]["layer"] = 3
    path.write_text(json.dumps(order))
    _edit_json(ds / "scene0" / "0_layout.json", lambda d: d["objects"][top].update(layer=3))
    found = _messages(ds, "0_order.json")
    assert any(f"object {top} has layer 3" in m and "give layer 0" in m for m in found), found


def test_a_layer_the_graph_does_not_give_is_rejected(ds: Path) -> None:
    path = ds / "scene0" / "0_order.json"
    order = json.loads(path.read_text())
    child, _ = _a_relation(order)
    order[child]["layer"] = 2  # no cycle holds it
    path.write_text(json.dumps(order))
    assert any(f"object {child} has layer 2" in m for m in _messages(ds, "0_order.json"))


def test_occlusion_beyond_four_decimals_is_rejected(ds: Path) -> None:
    path = ds / "scene0" / "0_order.json"
    order = json.loads(path.read_text())
    key = max(order, key=lambda k: order[k]["occlusion"])
    assert order[key]["occlusion"] > 0
    order[key]["occlusion"] += 3e-6  # the unrounded rate
    path.write_text(json.dumps(order))
    assert any(f"occlusion of {key}" in m for m in _messages(ds, "0_order.json"))


@pytest.mark.parametrize(
    ("key", "value", "expected"),
    [
        ("horizontal_fov", "degrees", "expected radians"),
        ("clipping_range", [0.01, 10.0], "(cm)"),
    ],
)
def test_camera_params_in_other_units_are_rejected(
    ds: Path, key: str, value: object, expected: str
) -> None:
    def edit(p: dict) -> None:
        p[key] = float(np.degrees(p[key])) if value == "degrees" else value

    _edit_json(ds / "scene0" / "0_camera_params.json", edit)
    assert any(expected in m for m in _messages(ds, "0_camera_params.json"))


def test_depth_in_metres_is_rejected(ds: Path) -> None:
    npz = ds / "scene0" / "0.npz"
    with np.load(npz) as z:
        depth = z["depth"] / np.float32(100)
    _rewrite_npz(npz, depth=depth)
    assert any("must be in cm" in m for m in _messages(ds, "0.npz"))


def test_object_poses_in_metres_are_rejected(ds: Path) -> None:
    with h5py.File(ds / "scene0" / "0_scene.hdf5", "r+") as h5:
        h5["objects/poses_relative_to_camera"][:, :3, 3] /= 100.0
    assert any("must be in cm" in m for m in _messages(ds, "0.npz"))
    assert any("differ from objects/poses" in m for m in _messages(ds, "scene_gt.json"))


def test_the_old_com_keypoint_layout_is_rejected(ds: Path) -> None:
    # keypts/com with every point and a visible flag instead of the visible points.
    with h5py.File(ds / "scene0" / "0_scene.hdf5", "r+") as h5:
        com = h5["keypts/com"]
        n = len(com["keypts_relative_to_camera"]) + len(com["occluded_keypts_relative_to_camera"])
        del com["occluded_keypts_relative_to_camera"], com["occluded_object_id"]
        com.create_dataset("visible", data=np.ones(n, np.float32))
    assert any("keypts/com' lacks" in m for m in _messages(ds, "0_scene.hdf5"))


def test_grasps_without_a_physics_score_need_a_record(ds: Path) -> None:
    # The small dataset caps the physics scores (physics_grasps 3): the others are NaN, as
    # dataset.json records. Without that record they are unexplained.
    _edit_json(ds / "dataset.json", lambda d: d["physics_scores"].update(unscored=0))
    found = _messages(ds, "0_scene.hdf5")
    assert any("without a physics score" in m for m in found), found


def test_unscored_grasps_are_marked_in_the_view_file(ds: Path) -> None:
    # The capped physics scores (physics_grasps 3) leave NaN scores; the view file's root
    # attribute counts them per dataset, and validate checks the count.
    with h5py.File(ds / "scene0" / "0_scene.hdf5", "r") as h5:
        want = {}
        for g in ("non_colliding_grasps", "colliding_grasps"):
            name = f"{g}/paralleljaw/score_simulation"
            if name in h5:
                nan = int(np.isnan(h5[name][()]).sum())
                if nan:
                    want[name] = nan
        assert want, "the small dataset caps the physics scores: some must be NaN"
        assert json.loads(h5.attrs["mgn_unscored_grasps"]) == want
        assert "physics_grasps" in h5.attrs["mgn_unscored_reason"]
    with h5py.File(ds / "scene0" / "0_scene.hdf5", "a") as h5:
        h5.attrs["mgn_unscored_grasps"] = json.dumps({k: v + 1 for k, v in want.items()})
    found = _messages(ds, "0_scene.hdf5")
    assert any("mgn_unscored_grasps" in m for m in found), found


def test_a_suction_grasp_without_its_physics_score_is_rejected(ds: Path) -> None:
    # Every suction grasp has a physics score (seal x hold) or, in labels without one, none has.
    with h5py.File(ds / "scene0" / "0_scene.hdf5", "a") as h5:
        groups = [
            f"{g}/suctioncup/score_simulation" for g in ("non_colliding_grasps", "colliding_grasps")
        ]
        name = next(n for n in groups if n in h5 and h5[n].shape[0] >= 2)
        sim = np.asarray(h5[name][()])
        assert np.isfinite(sim).all()
        sim[0] = np.nan
        h5[name][...] = sim
    found = _messages(ds, "0_scene.hdf5")
    assert any("suctioncup/score_simulation': 1 of" in m for m in found), found


def test_scene_gt_entries_out_of_step_are_rejected(ds: Path) -> None:
    _edit_json(ds / "scene0" / "scene_gt.json", lambda d: d["0"].pop(0))
    assert any("view 0: expected" in m for m in _messages(ds, "scene_gt.json"))


def test_layers_of_metagraspnets_sample_graph() -> None:
    # MetaGraspNet dataset_sim/scene1557/0_order.json, the parents of objects 1..10 and their
    # stored layers: 1 none (0); 2 <- 3, 4, 5 (3); 3 <- 1, 10 (3); 4 none (0); 5 <- 1, 4 (3);
    # 6 <- 3 (one parent, in layer 3: 3); 7 <- 4 (one parent in layer 0: 1); 8 <- 3 (3);
    # 9 <- 3 (3); 10 <- 1 (1). scene20/0_order.json: 4 <- 5 (1), 6 <- 1, 3 (3), the rest 0.
    parents = [[], [3, 4, 5], [1, 10], [], [1, 4], [3], [4], [3], [3], [1]]
    assert derive_layers([[p - 1 for p in ps] for ps in parents]) == [0, 3, 3, 0, 3, 3, 1, 3, 3, 1]
    parents = [[], [], [], [5], [], [1, 3], []]
    assert derive_layers([[p - 1 for p in ps] for ps in parents]) == [0, 0, 0, 1, 0, 3, 0]
    # An interlocked pair (each covers the other) with one outside parent each: layer 2; with
    # a second outside parent on one member: 3 for both.
    assert derive_layers([[1], [0]]) == [2, 2]
    assert derive_layers([[1, 2], [0], []]) == [2, 2, 0]
    assert derive_layers([[1, 2, 3], [0], [], []]) == [3, 3, 0, 0]
