"""mgn.learn: targets, instance extraction, training (overfit, determinism, resume), prediction,
the commands, and the errors without PyTorch.

The small dataset of conftest (2 scenes x 3 views, 120 x 120 px, suction labels) is the training
set; networks are tiny (width 4-8, 32-96 px) so the file runs in seconds on 2 CPU cores.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
import torch
from PIL import Image
from pycocotools import mask as mask_utils

import mgn
from mgn.cli.main import main
from mgn.errors import InvalidArgumentError, IoError, UnsupportedError
from mgn.io.dataset import View
from mgn.io.real import read_depth
from mgn.learn import ModelConfig, Predictor, TrainConfig, instances_from_maps, train
from mgn.learn.backend import require_torch
from mgn.learn.data import training_views, view_targets
from mgn.learn.predict import suction_peaks
from mgn.learn.targets import (
    core_target,
    hidden_target,
    network_shape,
    project_points,
    resize_nearest,
    suction_target,
)
from mgn.scene.cameras import Intrinsics

TINY = ModelConfig(image_size=32, width=4)


def _png(path: Path) -> np.ndarray:
    with Image.open(path) as im:
        return np.asarray(im)


# ---------------------------------------------------------------------------------------------
# Targets


def _brute_suction(contacts, scores, oids, ids, K, radius_m):
    """Per pixel, every label: the direct definition, pixel by pixel."""
    h, w = ids.shape
    q = np.zeros((h, w))
    cov = np.zeros((h, w), bool)
    for (x, y, z), s, o in zip(contacts, scores, oids, strict=True):
        if z <= 0:
            continue
        u, v = K.fx * x / z + K.cx, K.fy * y / z + K.cy
        if not (0 <= u < w and 0 <= v < h):
            continue
        r = K.fx * radius_m / z
        for row in range(h):
            for col in range(w):
                if (col + 0.5 - u) ** 2 + (row + 0.5 - v) ** 2 <= r * r and ids[row, col] == o:
                    q[row, col] = max(q[row, col], s)
                    cov[row, col] = True
    return q, (cov | (ids == 0)).astype(np.float32)


def test_suction_target_is_the_projection_of_the_labels():
    K = Intrinsics(60, 40, 50.0, 50.0, 30.0, 20.0)
    ids = np.zeros((40, 60), np.int32)
    ids[5:25, 5:25] = 1
    ids[5:25, 25:50] = 2
    # A label seen at the centre of pixel (10, 10) with a 1 px disc covers that pixel and its
    # four neighbours: z = 0.5 m, radius 0.01 m -> r = 50 * 0.01 / 0.5 = 1 px.
    z = 0.5
    p1 = [(10.5 - K.cx) * z / K.fx, (10.5 - K.cy) * z / K.fy, z]
    q, w = suction_target(np.array([p1]), np.array([0.7]), np.array([1]), ids, K, radius_m=0.01)
    assert sorted(zip(*np.nonzero(q), strict=True)) == [
        (9, 10),
        (10, 9),
        (10, 10),
        (10, 11),
        (11, 10),
    ]
    assert np.all(q[q > 0] == np.float32(0.7))
    assert w[10, 10] == 1
    assert w[0, 0] == 1
    assert w[15, 15] == 0
    # Several labels: one straddling the two objects (only its own object's pixels), two
    # overlapping (the larger score wins), one behind the camera, one outside the image.
    rng = np.random.default_rng(3)
    contacts = [
        [(24.0 - K.cx) * z / K.fx, (12.0 - K.cy) * z / K.fy, z],
        [(15.21 - K.cx) * 0.4 / K.fx, (15.04 - K.cy) * 0.4 / K.fy, 0.4],
        [(16.03 - K.cx) * 0.4 / K.fx, (15.47 - K.cy) * 0.4 / K.fy, 0.4],
        [0.0, 0.0, -0.5],
        [10.0, 0.0, 0.5],
    ]
    contacts += [
        [(u - K.cx) * 0.6 / K.fx, (v - K.cy) * 0.6 / K.fy, 0.6]
        for u, v in rng.uniform([0, 0], [60, 40], size=(20, 2))
    ]
    scores = np.concatenate([[0.9, 0.3, 0.8, 1.0, 1.0], rng.uniform(0, 1, 20)])
    oids = np.concatenate([[2, 1, 1, 1, 1], rng.integers(1, 3, 20)])
    q, w = suction_target(np.array(contacts), scores, oids, ids, K, radius_m=0.02)
    q_ref, w_ref = _brute_suction(contacts, scores, oids, ids, K, 0.02)
    np.testing.assert_allclose(q, q_ref, atol=1e-7)
    np.testing.assert_array_equal(w, w_ref)
    assert q[12, 24] == 0
    assert q[12, 25] == np.float32(0.9)


def test_suction_target_of_a_dataset_view(small_dataset: Path):
    view = mgn.Dataset(small_dataset).scene(0).view(0)
    t = view_targets(view, ModelConfig(suction_radius_m=0.008))
    g = view.grasps("suction")
    assert len(g["object_id"]) > 0
    q_ref, w_ref = _brute_suction(
        g["contact_poses_relative_to_camera"][:, :3, 3],
        g["score_analytical"],
        g["object_id"] + 1,
        view.instances,
        view.intrinsics,
        0.008,
    )
    np.testing.assert_allclose(t["suction"], q_ref, atol=1e-6)
    np.testing.assert_array_equal(t["suction_weight"], w_ref)
    assert (t["suction"] > 0).sum() > 20


def test_projection_with_distortion_matches_opencv():
    cv2 = pytest.importorskip("cv2")
    K = Intrinsics(80, 60, 70.0, 72.0, 41.0, 29.0, (0.1, -0.05, 0.001, 0.002, 0.01))
    pts = np.array([[0.05, -0.03, 0.5], [-0.1, 0.08, 0.7], [0.0, 0.0, 0.4]])
    u, v, inside = project_points(pts, K)
    ref, _ = cv2.projectPoints(pts, np.zeros(3), np.zeros(3), K.K_opencv, np.array(K.distortion))
    np.testing.assert_allclose(np.stack([u, v], 1), ref[:, 0] + 0.5, atol=1e-6)
    assert inside.all()


def test_core_and_hidden_targets_by_hand():
    ids = np.zeros((5, 9), np.int32)
    ids[1:4, 1:4] = 1  # 3 x 3: its centre is 2 px from anything else, its rim 1 px
    ids[1:4, 4:8] = 2  # 3 x 4 touching it: the middle row's inner two pixels are 2 px inside
    half, one = np.float32(0.5), np.float32(1.0)
    expected = np.zeros((5, 9), np.float32)
    expected[1:4, 1:8] = half
    expected[2, 2] = one
    expected[2, 5:7] = one
    np.testing.assert_array_equal(core_target(ids), expected)
    amodal = np.zeros((2, 5, 9), bool)
    amodal[0, 1:4, 1:6] = True  # object 1 continues under object 2 for two columns
    amodal[1] = ids == 2
    hidden = np.zeros((5, 9), bool)
    hidden[1:4, 4:6] = True
    np.testing.assert_array_equal(hidden_target(ids, amodal), hidden)


def test_network_shape_and_nearest_resize():
    assert network_shape(120, 120, 96) == (96, 96)
    assert network_shape(1200, 1944, 256) == (160, 256)
    assert network_shape(10, 1000, 64) == (16, 64)
    a = np.arange(16).reshape(4, 4)
    # output pixel centres 0.5, 1.5 land on input coordinates 1.0, 3.0 -> pixels 1, 3
    np.testing.assert_array_equal(resize_nearest(a, (2, 2)), [[5, 7], [13, 15]])
    np.testing.assert_array_equal(resize_nearest(a, (8, 8))[::2, ::2], a)
    with pytest.raises(InvalidArgumentError, match="image_size"):
        network_shape(10, 10, 8)


# ---------------------------------------------------------------------------------------------
# Instances


def test_instances_from_maps_by_hand():
    fg = np.zeros((12, 20), np.float32)
    fg[2:10, 2:9] = 0.9  # object A, columns 2..8
    fg[2:10, 9:17] = 0.8  # object B touching it, columns 9..16
    fg[0, 19] = 0.9  # a 1-px speck: no seed, stays background
    core = np.zeros_like(fg)
    core[4:8, 4:7] = 0.9  # A's seed: column 8 is 2 px from it, 3 px from B's
    core[4:8, 11:15] = 0.9  # B's seed: column 9 is 2 px from it, 3 px from A's
    core[0, 19] = 0.9
    inst = instances_from_maps(fg, core, min_area=4)
    assert inst.num_instances == 2
    masks = inst.masks()
    np.testing.assert_array_equal(masks[0], np.pad(np.ones((8, 7), bool), ((2, 2), (2, 11))))
    np.testing.assert_array_equal(masks[1], np.pad(np.ones((8, 8), bool), ((2, 2), (9, 3))))
    np.testing.assert_allclose(inst.scores, [0.9, 0.8], rtol=1e-6)
    assert inst.amodal is None
    assert np.array_equal(inst.masks(amodal=True), masks)
    # Hidden: A continues for 3 columns under B -> A's amodal mask, not B's (the occluder).
    hid = np.zeros_like(fg)
    hid[3:9, 9:12] = 0.9
    am = instances_from_maps(fg, core, hidden=hid, min_area=4).amodal
    assert am is not None
    np.testing.assert_array_equal(am[0], masks[0] | (hid > 0.5))
    np.testing.assert_array_equal(am[1], masks[1])
    empty = instances_from_maps(np.zeros((5, 5)), np.zeros((5, 5)))
    assert empty.num_instances == 0
    assert empty.labels.max() == 0
    # A foreground part the core map missed (no seed; rows 0..3, columns 18..19: 8 px >=
    # min_area, apart from B by the empty column 17) is one instance of its own, numbered after
    # the seeded ones; with no core anywhere every part of min_area px or more is one.
    lone_fg = fg.copy()
    lone_fg[0:4, 18:20] = 0.6
    lone = instances_from_maps(lone_fg, core, min_area=4)
    assert lone.num_instances == 3
    expected = np.zeros((12, 20), bool)
    expected[0:4, 18:20] = True
    np.testing.assert_array_equal(lone.masks()[2], expected)
    np.testing.assert_array_equal(lone.masks()[0], masks[0])
    np.testing.assert_array_equal(lone.masks()[1], masks[1])
    assert lone.scores[2] == pytest.approx(0.6)
    no_core = instances_from_maps(lone_fg, np.zeros_like(fg), min_area=4)
    assert no_core.num_instances == 2  # A and B touch: one part; the lone part: another
    np.testing.assert_array_equal(no_core.labels > 0, lone_fg > 0.5)
    assert instances_from_maps(lone_fg, np.zeros_like(fg), min_area=9).num_instances == 1


def test_suction_peaks_by_hand():
    q = np.zeros((10, 10))
    q[2, 3], q[2, 4], q[7, 7], q[5, 0] = 0.9, 0.8, 0.7, 0.6
    peaks = suction_peaks(q, 3, radius=2.0)
    np.testing.assert_allclose(peaks, [[3.5, 2.5, 0.9], [7.5, 7.5, 0.7], [0.5, 5.5, 0.6]])
    assert len(suction_peaks(q, 10, radius=2.0, min_quality=0.65)) == 2


# ---------------------------------------------------------------------------------------------
# Training


def _state(path: Path) -> dict[str, torch.Tensor]:
    return torch.load(path, weights_only=True)["state_dict"]


def test_overfits_the_training_views(small_dataset: Path, tmp_path: Path):
    """Trained on the three views of one scene (flips only: memorising, not generalising), the
    network reproduces their masks."""
    mc = ModelConfig(image_size=96, width=8)
    tc = TrainConfig(epochs=150, batch_size=3, lr=5e-3, augment="flips")
    res = train(
        small_dataset,
        tmp_path / "m",
        model_config=mc,
        train_config=tc,
        scenes=[1],
        num_threads=1,
        progress=False,
    )
    assert res.num_views == 3
    assert res.history[-1]["loss"] < 0.5 * res.history[0]["loss"]
    pred = Predictor(res.model_path, num_threads=1)
    for view in mgn.Dataset(small_dataset).scene(1).views():
        p = pred.predict(view.rgb)
        gt, fg = view.instances > 0, p.instances.labels > 0
        assert (gt & fg).sum() / (gt | fg).sum() > 0.9, view
        assert p.instances.num_instances >= 1


def test_same_seed_same_weights_and_resume(
    small_dataset: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    tc = TrainConfig(epochs=3, batch_size=2, seed=5)
    kw = {"model_config": TINY, "scenes": [0], "num_threads": 1, "progress": False}
    a = train(small_dataset, tmp_path / "a", train_config=tc, **kw)
    b = train(small_dataset, tmp_path / "b", train_config=tc, **kw)
    c = train(
        small_dataset,
        tmp_path / "c",
        train_config=TrainConfig(epochs=3, batch_size=2, seed=6),
        **kw,
    )
    sa, sb, sc = _state(a.model_path), _state(b.model_path), _state(c.model_path)
    assert all(torch.equal(sa[k], sb[k]) for k in sa)
    assert not all(torch.equal(sa[k], sc[k]) for k in sa)
    # Interrupted after epoch 1's checkpoint, then resumed: the weights of the straight run.
    import mgn.learn.training as train_module

    real_write = train_module.write_torch_file
    calls = []

    def stop_after_first(path, obj):
        real_write(path, obj)
        calls.append(path)
        if len(calls) == 1:
            raise KeyboardInterrupt

    monkeypatch.setattr(train_module, "write_torch_file", stop_after_first)
    with pytest.raises(KeyboardInterrupt):
        train(small_dataset, tmp_path / "r", train_config=tc, **kw)
    monkeypatch.setattr(train_module, "write_torch_file", real_write)
    assert not (tmp_path / "r" / "model.pt").exists()
    with pytest.raises(IoError, match="--resume"):
        train(small_dataset, tmp_path / "r", train_config=tc, **kw)
    with pytest.raises(InvalidArgumentError, match="epochs 3 -> 4"):
        train(
            small_dataset,
            tmp_path / "r",
            train_config=TrainConfig(epochs=4, batch_size=2, seed=5),
            resume=True,
            **kw,
        )
    r = train(small_dataset, tmp_path / "r", train_config=tc, resume=True, **kw)
    sr = _state(r.model_path)
    assert all(torch.equal(sa[k], sr[k]) for k in sa)
    assert [h["epoch"] for h in r.history] == [1, 2, 3]
    log = json.loads((tmp_path / "r" / "train_log.json").read_text())
    assert log["views"] == ["scene0/0", "scene0/5", "scene0/17"]


def test_depth_rgbd_and_amodal_models_train_and_predict(small_dataset: Path, tmp_path: Path):
    view = mgn.Dataset(small_dataset).scene(0).view(5)
    for mc in (
        ModelConfig(image_size=32, width=4, modality="depth", amodal=True),
        ModelConfig(image_size=32, width=4, modality="rgbd", backbone="resnet18"),
    ):
        res = train(
            small_dataset,
            tmp_path / mc.modality,
            model_config=mc,
            train_config=TrainConfig(epochs=1, batch_size=3),
            views=[5],
            num_threads=1,
            progress=False,
        )
        p = Predictor(res.model_path, num_threads=1).predict(view.rgb, view.depth)
        assert p.suction.shape == p.foreground.shape == (120, 120)
        assert (p.instances.amodal is not None) == mc.amodal
        with pytest.raises(InvalidArgumentError, match="depth"):
            Predictor(res.model_path).predict(view.rgb, None, name="x.png")


def test_resnet18_backbone_takes_a_local_state_dict(tmp_path: Path):
    from mgn.learn.model import build_model, load_backbone_weights

    torch.manual_seed(0)
    src = build_model(ModelConfig(backbone="resnet18")).encoder.state_dict()
    state = {k: torch.randn_like(v.float()).to(v.dtype) for k, v in src.items()}
    state["fc.weight"] = torch.zeros(1000, 512)  # a classifier head is ignored
    path = tmp_path / "resnet18.pth"
    torch.save(state, path)
    model = build_model(ModelConfig(backbone="resnet18", modality="rgbd"))
    assert load_backbone_weights(model, path) == len(src)
    got = model.encoder.state_dict()
    assert torch.equal(got["layer3.1.conv2.weight"], state["layer3.1.conv2.weight"])
    w = state["conv1.weight"]
    assert torch.equal(got["conv1.weight"], torch.cat([w, w.mean(1, keepdim=True)], 1))
    with pytest.raises(InvalidArgumentError, match="resnet18"):
        load_backbone_weights(build_model(TINY), path)
    torch.save({"x": torch.zeros(1)}, tmp_path / "bad.pth")
    with pytest.raises(IoError, match="ResNet-18 state dict"):
        load_backbone_weights(model, tmp_path / "bad.pth")


# ---------------------------------------------------------------------------------------------
# Commands and files


@pytest.fixture(scope="module")
def tiny_model(small_dataset: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("tiny_model")
    train(
        small_dataset,
        out,
        model_config=TINY,
        train_config=TrainConfig(epochs=2),
        num_threads=1,
        progress=False,
    )
    return out / "model.pt"


def test_train_and_predict_commands(
    small_dataset: Path, tiny_model: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
):
    assert (
        main(
            [
                "train",
                str(small_dataset),
                "--out",
                str(tmp_path / "m"),
                "--image-size",
                "32",
                "--width",
                "4",
                "--epochs",
                "1",
                "--views",
                "0",
                "--num-threads",
                "1",
                "--quiet",
            ]
        )
        == 0
    )
    assert "trained on 2 views" in capsys.readouterr().out
    images = [small_dataset / "scene0" / "0_rgb.png", small_dataset / "scene1" / "0_rgb.png"]
    jpg = tmp_path / "photo.jpg"
    Image.fromarray(_png(images[1])).convert("RGB").save(jpg)
    out = tmp_path / "pred"
    assert (
        main(
            [
                "predict",
                str(tiny_model),
                str(images[0]),
                str(jpg),
                "--out",
                str(out),
                "--quiet",
                "--num-threads",
                "1",
            ]
        )
        == 0
    )
    doc = json.loads((out / "predictions.json").read_text())
    assert [e["stem"] for e in doc["images"]] == ["0_rgb", "photo"]
    for entry in doc["images"]:
        ids = _png(out / f"{entry['stem']}_instances.png")
        assert ids.shape == (120, 120)
        assert ids.max() == len(entry["instances"])
        for inst in entry["instances"]:
            rle = dict(inst["segmentation"], counts=inst["segmentation"]["counts"].encode())
            np.testing.assert_array_equal(mask_utils.decode(rle).astype(bool), ids == inst["id"])
        assert _png(out / f"{entry['stem']}_overlay.png").shape == (120, 240, 3)
        assert _png(out / f"{entry['stem']}_suction.png").dtype == np.uint8


def test_depth_files(tmp_path: Path):
    d = np.array([[0.5, np.nan], [0.0, 1.25]], np.float32)
    np.save(tmp_path / "d.npy", d)
    np.savez(tmp_path / "d.npz", depth=d * 100)
    Image.fromarray((np.nan_to_num(d) * 1000).astype(np.uint16)).save(tmp_path / "d.png")
    for name in ("d.npy", "d.npz", "d.png"):
        got = read_depth(tmp_path / name)
        np.testing.assert_allclose(got, [[0.5, np.nan], [np.nan, 1.25]], rtol=1e-6)
    (tmp_path / "d.tiff").write_bytes(b"x")
    with pytest.raises(IoError, match=r"d\.tiff"):
        read_depth(tmp_path / "d.tiff")
    Image.fromarray(np.zeros((2, 2, 3), np.uint8)).save(tmp_path / "rgb.png")
    with pytest.raises(IoError, match="16-bit"):
        read_depth(tmp_path / "rgb.png")


def test_bad_input_errors(
    small_dataset: Path, tiny_model: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
):
    (tmp_path / "empty").mkdir()
    with pytest.raises(InvalidArgumentError, match="no views to train on"):
        training_views(tmp_path / "empty")
    with pytest.raises(InvalidArgumentError, match="no views to train on"):
        training_views(small_dataset, scenes=[7])
    assert main(["train", str(tmp_path / "empty"), "--out", str(tmp_path / "o")]) == 1
    assert "no views to train on" in capsys.readouterr().err
    # The suction physics score is a target like the others; a dataset whose labels have none
    # (NaN in every grasp) is an error naming the setting.
    view = mgn.Dataset(small_dataset).scene(0).view(0)
    sim = view_targets(view, ModelConfig(suction_score="score_simulation"))["suction"]
    assert np.isfinite(sim).all()
    assert sim.min() >= 0
    assert sim.max() <= 1
    shutil.copytree(small_dataset / "scene0", tmp_path / "nan" / "scene0")
    with h5py.File(tmp_path / "nan" / "scene0" / "0_scene.hdf5", "a") as h5:
        for group in ("non_colliding_grasps", "colliding_grasps"):
            name = f"{group}/suctioncup/score_simulation"
            if name in h5:
                h5[name][...] = np.nan
    nan_view = View(tmp_path / "nan" / "scene0", 0)
    with pytest.raises(InvalidArgumentError, match="score_simulation' is NaN"):
        view_targets(nan_view, ModelConfig(suction_score="score_simulation"))
    # An image and its depth of different sizes.
    Image.fromarray(np.zeros((20, 30, 3), np.uint8)).save(tmp_path / "a.png")
    np.save(tmp_path / "a_depth.npy", np.ones((20, 31), np.float32))
    depth_model = tmp_path / "dm"
    train(
        small_dataset,
        depth_model,
        model_config=ModelConfig(image_size=32, width=4, modality="rgbd"),
        train_config=TrainConfig(epochs=1),
        views=[0],
        num_threads=1,
        progress=False,
    )
    with pytest.raises(InvalidArgumentError, match=r"a_depth\.npy.*they must match"):
        mgn.learn.predict_files(
            depth_model / "model.pt",
            [tmp_path / "a.png"],
            tmp_path / "p",
            depths=[tmp_path / "a_depth.npy"],
            progress=False,
        )
    with pytest.raises(InvalidArgumentError, match="--depth"):
        mgn.learn.predict_files(
            depth_model / "model.pt", [tmp_path / "a.png"], tmp_path / "p", progress=False
        )
    (tmp_path / "notes.txt").write_text("x")
    with pytest.raises(IoError, match="PNG or JPEG"):
        mgn.learn.predict_files(
            tiny_model, [tmp_path / "notes.txt"], tmp_path / "p", progress=False
        )
    with pytest.raises(IoError, match="not an mgn-learn-model file"):
        Predictor(depth_model / "checkpoint.pt")
    with pytest.raises(IoError, match="does not exist"):
        Predictor(tmp_path / "none.pt")


def test_without_torch_the_error_names_the_extra(
    small_dataset: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
):
    monkeypatch.setitem(sys.modules, "torch", None)  # import torch -> ImportError
    with pytest.raises(UnsupportedError, match=r"mgn\[learn\]"):
        require_torch()
    assert main(["train", str(small_dataset), "--out", str(tmp_path / "o")]) == 1
    assert "mgn[learn]" in capsys.readouterr().err
    # import mgn and the whole command line work without torch (a fresh interpreter).
    code = (
        "import sys; sys.modules['torch'] = None\n"
        "import mgn, mgn.learn\n"
        "from mgn.cli.main import build_parser\n"
        "build_parser().parse_args(['train', 'DS', '--out', 'O'])\n"
        "print('ok')"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "ok", run.stderr


def test_auto_epochs_give_small_datasets_more_passes() -> None:
    """epochs=None: ceil(AUTO_VIEW_PASSES / views) clipped to AUTO_EPOCHS (4,800 passes, 40-80)."""
    from mgn.learn.config import AUTO_EPOCHS, AUTO_VIEW_PASSES, auto_epochs

    assert (AUTO_EPOCHS, AUTO_VIEW_PASSES) == ((40, 80), 4800)
    cases = {1: 80, 60: 80, 61: 79, 96: 50, 119: 41, 120: 40, 192: 40, 10_000: 40}
    for views, epochs in cases.items():
        assert auto_epochs(views) == epochs, views
        brute = min(80, max(40, next(e for e in range(1, 10_000) if e * views >= 4800)))
        assert auto_epochs(views) == brute, views
    # Never more view passes than the 40 epochs of 12 scenes x 16 views.
    assert max(v * auto_epochs(v) for v in range(1, 1000) if v <= 192) <= 40 * 192
    with pytest.raises(InvalidArgumentError, match="num_views"):
        auto_epochs(0)
    assert TrainConfig().epochs is None
    with pytest.raises(InvalidArgumentError, match="epochs"):
        TrainConfig(epochs=0)


def test_a_run_with_auto_epochs_records_the_epochs_it_ran(
    small_dataset: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import mgn.learn.config as config_module

    monkeypatch.setattr(config_module, "AUTO_EPOCHS", (2, 5))
    monkeypatch.setattr(config_module, "AUTO_VIEW_PASSES", 9)  # 3 views -> 3 epochs
    kw = {"model_config": TINY, "scenes": [0], "num_threads": 1, "progress": False}
    res = train(small_dataset, tmp_path / "m", train_config=TrainConfig(batch_size=2), **kw)
    assert res.num_views == 3
    assert [h["epoch"] for h in res.history] == [1, 2, 3]
    log = json.loads((tmp_path / "m" / "train_log.json").read_text())
    assert log["train_config"]["epochs"] == 3
