"""label_scene and `mgn scene label` end to end on a hand-built scene: a cube resting on a shoe
box on the tote floor, and a tea box on its own, seen from the MetaGraspNet rig at low
resolution. The numerics of each label are tested in their own files; here: the pieces agree
with each other and with the format once written and read back."""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest
from conftest import check_difficulty

from mgn.io.dataset import Dataset
from mgn.io.scene_json import write_scene_json
from mgn.io.validate import validate_dataset
from mgn.objects import ToteSpec, get_object
from mgn.pipeline.label_scene import LabelOptions, label_scene
from mgn.scene.cameras import CameraView, Intrinsics, mgn_rig
from mgn.scene.scene import BUILTIN, Scene, SceneInstance

VIEWS = (0, 3, 20)


def _pose(x: float, y: float, z: float) -> np.ndarray:
    X = np.eye(4)
    X[:3, 3] = (x, y, z)
    return X


def _scene() -> Scene:
    def inst(i: int, name: str, X: np.ndarray, contacts: tuple[str, ...]) -> SceneInstance:
        return SceneInstance(i, name, get_object(name).category_id, BUILTIN, X, contacts)

    return Scene(
        instances=(
            inst(1, "box_shoe", _pose(-0.02, -0.02, 0.045), ("floor",)),  # 240 x 150 x 90 mm
            inst(2, "box_cube", _pose(0.0, 0.0, 0.12), ()),  # 60 mm cube on top of the shoe box
            inst(3, "box_tea", _pose(0.0, 0.1125, 0.0325), ("floor", "+y")),  # against a wall
        ),
        tote=ToteSpec(),
        seed=3,
    )


def _views(scale: float = 0.2) -> list[tuple[int, CameraView]]:
    poses, _ = mgn_rig(3)
    K = Intrinsics.mgn_synthetic().scaled(scale)
    return [(v, CameraView(K, poses[v])) for v in VIEWS]


@pytest.fixture(scope="module")
def object_labels(tmp_path_factory):
    from mgn.pipeline.config import load_config
    from mgn.pipeline.label_cache import object_labels as labels_of

    config = load_config(
        {
            "labels": {"pj_physics": False},
            "object_labels": {"suction_points": 300, "pj_points": 300},
        }
    )
    mp = pytest.MonkeyPatch()
    mp.setenv("MGN_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))
    try:
        scene = _scene()
        got = [labels_of(scene.object_spec(i), config, use_cache=False) for i in range(3)]
    finally:
        mp.undo()
    return got


@pytest.fixture(scope="module")
def written(tmp_path_factory, object_labels):
    root = tmp_path_factory.mktemp("ds")
    timings = label_scene(
        _scene(),
        root / "scene0",
        _views(),
        pj_labels=[g.paralleljaw for g in object_labels],
        suction_labels=[g.suction for g in object_labels],
        options=LabelOptions(randomize=False, num_threads=2),
    )
    return root, timings


def test_every_file_is_written_and_valid(written):
    root, timings = written
    assert validate_dataset(root) == []
    scene = Dataset(root).scene(0)
    assert scene.view_ids == list(VIEWS)
    assert set(timings.seconds) >= {
        "render",
        "object labels",
        "layout",
        "scene grasps",
        "write (waiting)",
    }
    assert timings.views == len(VIEWS)
    gt = scene.scene_gt
    assert sorted(gt, key=int) == [str(v) for v in VIEWS]
    assert scene.scene_json["seed"] == 3


def test_top_view_layout(written):
    root, _ = written
    view = Dataset(root).scene(0).view(0)
    inst, amodal = view.instances, view.amodal
    assert amodal.shape[0] == 3
    for i in range(3):
        vis = inst == i + 1
        assert vis.any(), f"instance {i + 1} not seen from the top"
        assert not np.any(vis & ~amodal[i]), "a visible mask leaves its amodal mask"
    # The cube lies on the shoe box: the relation matrix, the graph and the layers say so.
    m = view.relation_matrix
    assert m[0, 1] == -1
    assert m[1, 0] == 1
    assert m[2].tolist() == [0, 0, 0]
    order = view.order
    assert [p["id"] for p in order["1"]["parents"]] == [2]
    assert order["1"]["layer"] == 1
    assert order["2"]["layer"] == 0
    assert order["3"]["layer"] == 0
    assert order["1"]["parents"][0]["edge_size"] > 0
    # The depth step from the cube's top to the shoe box's top is 60 mm (written in cm).
    assert order["1"]["parents"][0]["depth_diff"] == pytest.approx(6.0, abs=0.8)
    assert order["3"]["bin_rel"] == "edge"
    assert order["1"]["bin_rel"] == "no_rel"
    # Occlusion: the shoe box is partly covered, the others are not.
    assert 0.02 < order["1"]["occlusion"] < 0.5
    assert order["2"]["occlusion"] == pytest.approx(0.0, abs=1e-6)
    occ_map = view.occlusion_map
    assert np.allclose(occ_map[inst == 1], order["1"]["occlusion"], atol=1e-6)
    # Boxes: the loose (amodal) box of the shoe contains its visible pixels.
    x, y, w, h = view.hdf5["objects/bbox_loose"][0]
    ys, xs = np.nonzero(inst == 1)
    assert x <= xs.min()
    assert xs.max() < x + w
    assert y <= ys.min()
    assert ys.max() < y + h
    # Three distinct classes, all complete, two layers, small occlusion above 5 %: level 2.
    assert check_difficulty(view.layout) in (1, 2)
    assert view.layout["order"][:2] != [1, 2]  # the shoe box is never picked before the cube


def test_poses_and_keypoints_in_the_camera_frame(written):
    root, _ = written
    view = Dataset(root).scene(0).view(3)
    scene = _scene()
    X_CW = np.linalg.inv(view.X_WC)
    for i, inst in enumerate(scene.instances):
        assert np.allclose(view.X_CO[i], X_CW @ inst.X_WO, atol=1e-5)
    kp = view.hdf5["keypts/byhand/keypts_relative_to_camera"]
    occl = view.hdf5["keypts/byhand/occluded_keypts_relative_to_camera"]
    total = sum(len(get_object(inst.name).keypoints) for inst in scene.instances)
    assert len(kp) + len(occl) <= total
    assert len(kp) > 0
    assert np.all(kp[:, 3] > 0)  # in front of the camera (z forward, metres)


def test_com_keypoints_are_the_visible_ones_as_in_metagraspnet(written):
    # MetaGraspNet's {v}_scene.hdf5 has keypts/com/{keypts_relative_to_camera, object_id} only
    # (no occluded set, unlike keypts/byhand): the CoM points seen from the camera. A point is
    # seen when the camera ray's first hit is it: the noise-free depth at its pixel equals its z.
    import h5py

    root, _ = written
    view = Dataset(root).scene(0).view(0)
    z_img = view.depth_ideal
    K = view.intrinsics
    with h5py.File(view.path("_scene.hdf5"), "r") as h5:
        com = h5["keypts/com"]
        assert "visible" not in com
        seen = com["keypts_relative_to_camera"][()] / 100.0  # cm -> m
        hidden = com["occluded_keypts_relative_to_camera"][()] / 100.0
        assert len(com["object_id"]) == len(seen)
        assert len(com["occluded_object_id"]) == len(hidden)
    assert len(seen) + len(hidden) == 1000 * view.num_instances
    assert 0 < len(seen) < len(hidden)  # from above: the tops are seen, the rest is not

    def depth_agrees(p):
        u = np.floor(K.fx * p[:, 1] / p[:, 3] + K.cx).astype(int)
        v = np.floor(K.fy * p[:, 2] / p[:, 3] + K.cy).astype(int)
        ok = (u >= 0) & (u < K.width) & (v >= 0) & (v < K.height)
        z = np.full(len(p), np.nan)
        z[ok] = z_img[v[ok], u[ok]]
        return np.abs(z - p[:, 3]) < 0.005  # 5 mm: the point vs its pixel's centre ray

    assert depth_agrees(seen).mean() > 0.9
    assert depth_agrees(hidden).mean() < 0.3


def test_occlusion_is_written_to_four_decimals_everywhere(written):
    root, _ = written
    for v in VIEWS:
        view = Dataset(root).scene(0).view(v)
        occ_h5 = view.hdf5["objects/occlusion"]
        for key, entry in view.order.items():
            i = int(key)
            assert entry["occlusion"] == round(entry["occlusion"], 4)
            assert occ_h5[i - 1] == np.float32(entry["occlusion"])
            assert np.all(view.occlusion_map[view.instances == i] == np.float32(entry["occlusion"]))


def test_scene_grasps_are_split_and_in_range(written):
    root, _ = written
    view = Dataset(root).scene(0).view(0)
    for kind in ("paralleljaw", "suctioncup"):
        ok = view.grasps(kind)
        bad = view.grasps(kind, colliding=True)
        assert len(ok["object_id"]) > 0, kind
        assert set(np.unique(ok["object_id"]).astype(int)) <= {0, 1, 2}
        assert np.all((ok["score_analytical"] >= 0) & (ok["score_analytical"] <= 1))
        poses = ok["contact_poses_relative_to_camera"]
        assert np.allclose(np.linalg.det(poses[:, :3, :3]), 1.0, atol=1e-4)
        assert len(bad["object_id"]) >= 0
    # The shoe box lies on the floor: some of its suction grasps (bottom face) collide, or are
    # not visible from the top; none of the kept ones is on its bottom face.
    su = view.grasps("suctioncup")
    X_WC = view.X_WC
    shoe = su["object_id"] == 0
    p_W = (X_WC[:3, :3] @ su["contact_poses_relative_to_camera"][shoe, :3, 3].T).T + X_WC[:3, 3]
    assert np.all(p_W[:, 2] > 0.005)


def test_a_hidden_object_is_left_out_of_the_view(tmp_path):
    # A 60 mm cube inside the shoe box (scene instance 2 of 4) is hidden from every camera. As in
    # MetaGraspNet's files, the view holds the objects it sees with ids 1..N' that all appear in
    # the instance image: its visualize_layout.py takes num_objects = len(unique(ids)) - 1 and
    # draws ids 1..num_objects; scene_gt.json entry k is instance k + 1.
    import h5py

    def inst(i, name, X):
        return SceneInstance(i, name, get_object(name).category_id, BUILTIN, X, ())

    scene = Scene(
        instances=(
            inst(1, "box_shoe", _pose(-0.02, -0.02, 0.045)),
            inst(2, "box_cube", _pose(-0.02, -0.02, 0.045)),  # inside the shoe box
            inst(3, "box_cube", _pose(0.0, 0.0, 0.12)),  # on top of it
            inst(4, "box_tea", _pose(0.0, 0.1125, 0.0325)),
        ),
        tote=ToteSpec(),
        seed=3,
    )
    label_scene(
        scene,
        tmp_path / "scene0",
        _views(0.1)[:2],
        options=LabelOptions(randomize=False, num_threads=2),
    )
    folder = Dataset(tmp_path).scene(0)
    for v in VIEWS[:2]:
        view = folder.view(v)
        ids = np.unique(view.instances)
        n = len(ids) - 1  # visualize_layout.py's count
        assert ids.tolist() == list(range(n + 1))
        assert n == 3
        assert view.amodal.shape[0] == n
        assert len(view.order) == n
        assert len(folder.scene_gt[str(v)]) == n
        with h5py.File(view.path("_scene.hdf5"), "r") as h5:
            assert h5["objects/scene_instance_id"][()].tolist() == [1, 3, 4]
            assert h5["objects/categories"].shape == (n,)
            assert np.all(h5["keypts/com/object_id"][()] < n)
        gt_t = np.array([e["cam_t_m2c"] for e in folder.scene_gt[str(v)]]) / 100.0
        assert np.allclose(gt_t, view.X_CO[:, :3, 3], atol=1e-5)
        for entry in view.order.values():
            assert entry["occlusion"] < 1.0
            if [p["id"] for p in entry["parents"]] == [0]:
                assert entry["layer"] == 0
        # The cube on top (scene instance 3) is view instance 2 and lies on the shoe box (1).
        assert [p["id"] for p in view.order["1"]["parents"]] == [2]


def test_same_input_same_bytes(tmp_path, object_labels):
    def digest(folder):
        return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.iterdir()}

    runs = []
    for k, threads in enumerate((1, 2)):
        label_scene(
            _scene(),
            tmp_path / f"r{k}",
            _views(0.1)[:2],
            pj_labels=[g.paralleljaw for g in object_labels],
            suction_labels=None,
            options=LabelOptions(num_threads=threads),
        )
        runs.append(digest(tmp_path / f"r{k}"))
    assert runs[0] == runs[1]


def test_bad_input(tmp_path):
    from mgn.errors import InvalidArgumentError

    empty = Scene(instances=(), tote=ToteSpec(), seed=0)
    with pytest.raises(InvalidArgumentError, match="no objects"):
        label_scene(empty, tmp_path / "a", _views())
    with pytest.raises(InvalidArgumentError, match="no views"):
        label_scene(_scene(), tmp_path / "b", [])


def test_scene_label_command(tmp_path):
    from mgn.cli.main import main

    write_scene_json(_scene(), tmp_path / "scene.json")
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(
        "camera: {views: [0, 7], resolution_scale: 0.1, randomize: false}\n"
        "labels: {pj_physics: false}\n"
        "object_labels: {suction_points: 200, pj_points: 200}\n"
    )
    out = tmp_path / "scene5"
    args = ["scene", "label", str(tmp_path / "scene.json"), "--out", str(out), "--config", str(cfg)]
    assert main(args) == 0
    assert sorted(Dataset(tmp_path).scene(5).view_ids) == [0, 7]
    assert validate_dataset(tmp_path) == []
    assert main(args) == 1  # exists already, no --overwrite
    assert main([*args, "--view", "9"]) == 1  # not a configured view
    layout = json.loads((out / "7_layout.json").read_text())
    check_difficulty(layout)  # asserts the stored level is Table IV of its entries


def test_strided_subset_keeps_grasps_evenly(object_labels):
    from mgn.pipeline.label_scene import strided_subset

    pj = object_labels[1].paralleljaw  # the cube (the shoe box is wider than the gripper)
    m = len(pj.width)
    assert m > 50
    sub = strided_subset(pj, 50)
    assert len(sub.width) == 50
    assert len(sub.approach) == 50
    assert len(sub.point_index) == 50
    assert np.array_equal(sub.p1[0], pj.p1[0])
    assert np.array_equal(sub.p1[-1], pj.p1[-1])
    assert len(sub.point_score) == len(pj.point_score)  # per-point data untouched
    assert strided_subset(pj, 0) is pj
    assert strided_subset(pj, m) is pj
    su = strided_subset(object_labels[0].suction, 7)
    assert len(su.points) == len(su.score) == len(su.reason) == 7
    assert strided_subset(None, 5) is None


def test_overlapped_views_write_what_the_serial_steps_write(tmp_path, object_labels):
    """label_scene renders view k + 1 and builds the grasp collisions in threads while view k is
    labelled; the files must be those of the plain serial loop over the same public steps."""
    from mgn.io.scene_folder import scene_gt_entries, write_scene_gt, write_view
    from mgn.pipeline.label_scene import strided_subset, view_grasps, view_record
    from mgn.render.views import iter_views
    from mgn.view_labels.grasps import SceneGraspModel
    from mgn.view_labels.layout import OCCLUSION_DECIMALS, compute_layout
    from mgn.view_labels.objects import (
        SceneRayModel,
        round_occlusion,
        seen_objects,
        view_object_labels,
    )

    scene, views = _scene(), _views(0.1)
    pj = [g.paralleljaw for g in object_labels]
    su = [g.suction for g in object_labels]
    opt = LabelOptions(seed=5, num_threads=2)
    label_scene(scene, tmp_path / "overlap", views, pj_labels=pj, suction_labels=su, options=opt)

    serial = tmp_path / "serial"
    serial.mkdir()
    rays = SceneRayModel.from_scene(scene)
    cap = opt.max_grasps_per_object
    sgm = SceneGraspModel(
        scene,
        [strided_subset(g, cap) for g in pj],
        [strided_subset(g, cap) for g in su],
        offsets=opt.grasp_offsets,
    )
    cats = np.array([inst.category_id for inst in scene.instances], np.int64)
    bins = [inst.bin_relation for inst in scene.instances]
    gt = {}
    frames = iter_views(scene.render_items(), get_tote(scene), views, seed=opt.seed)
    for (v, view), images in zip(views, frames, strict=True):
        labels = view_object_labels(rays, view, images.instance_ids, depth=images.depth_ideal)
        labels = round_occlusion(labels, OCCLUSION_DECIMALS)
        labels, index = seen_objects(labels)
        layout = compute_layout(
            labels.visible,
            labels.amodal,
            images.depth_ideal,
            cats[index],
            [bins[i] for i in index],
            occlusion=labels.occlusion,
        )
        grasps = view_grasps(sgm, view, index, len(scene.instances))
        com = rays.com_parameters()[index]
        write_view(
            serial,
            view_record(v, view, images, labels, layout, grasps, com, instance_ids=index + 1),
        )
        gt[v] = scene_gt_entries(labels.X_CO, cats[index])
    write_scene_gt(serial, gt)
    write_scene_json(scene, serial / "scene.json")

    def digest(folder):
        return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.iterdir()}

    a, b = digest(tmp_path / "overlap"), digest(serial)
    assert len(a) > 5 * len(views)  # every view's files (9 each) and the scene's
    assert a == b


def get_tote(scene):
    from mgn.objects import tote_mesh

    return tote_mesh(scene.tote)


def test_render_ahead_keeps_order_errors_and_stops():
    """The render thread of label_scene: same items in the same order, made in another thread;
    the iterator's error reaches the consumer after the items before it; closing early stops the
    producer within one item and closes the iterator in its own thread."""
    import threading
    import time

    from mgn.pipeline.label_scene import _RenderAhead

    main = threading.get_ident()
    made, closed = [], []

    def gen(n, fail_at=None):
        try:
            for i in range(n):
                if i == fail_at:
                    raise OSError(f"item {i} failed")
                made.append((i, threading.get_ident()))
                yield i * i
        finally:
            closed.append(threading.get_ident())

    ahead = _RenderAhead(lambda: gen(50))
    assert list(ahead) == [i * i for i in range(50)]
    ahead.close()
    assert all(t != main for _, t in made)
    assert closed
    assert closed[0] != main
    assert ahead.busy >= 0.0

    made.clear(), closed.clear()
    ahead = _RenderAhead(lambda: gen(10, fail_at=4))
    got = []
    with pytest.raises(OSError, match="item 4 failed"):  # noqa: PT012 -- the loop is the statement
        for x in ahead:
            got.append(x)  # noqa: PERF402 -- element by element, up to the item that fails
    ahead.close()
    assert got == [0, 1, 4, 9]

    made.clear(), closed.clear()
    ahead = _RenderAhead(lambda: gen(1000), depth=1)
    it = iter(ahead)
    assert [next(it) for _ in range(3)] == [0, 1, 4]
    time.sleep(0.3)  # the producer fills the queue and blocks
    ahead.close()
    assert len(made) <= 3 + 2  # consumed, one queued, one in hand
    assert len(closed) == 1
    assert closed[0] != main


def test_scene_label_applies_the_io_section(tmp_path):
    # `mgn scene label --config` writes what `mgn generate` writes with the same config: here the
    # io section's archival mode (the npz's sensor depth as an LZMA zip entry, method 14).
    import zipfile

    from mgn.cli.main import main

    write_scene_json(_scene(), tmp_path / "scene.json")
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(
        "camera: {views: [0], resolution_scale: 0.1, randomize: false}\n"
        "labels: {scene_grasps: false}\n"
        "io: {archival: true}\n"
    )
    out = tmp_path / "scene0"
    assert (
        main(
            [
                "scene",
                "label",
                str(tmp_path / "scene.json"),
                "--out",
                str(out),
                "--config",
                str(cfg),
            ]
        )
        == 0
    )
    with zipfile.ZipFile(out / "0.npz") as z:
        assert z.getinfo("depth.npy").compress_type == zipfile.ZIP_LZMA
