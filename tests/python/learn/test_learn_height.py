"""The height-above-floor input (``--modality height | rgb-height``): the floor plane fit of
:mod:`mgn.learn.floor` against analytic depth images, and the modality through training,
the model file and prediction."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
import pytest
import torch
from PIL import Image

import mgn
from mgn.cli.learn import add_model_arguments, add_train_arguments, configs_from_args
from mgn.errors import InvalidArgumentError
from mgn.learn import ModelConfig, Predictor, TrainConfig, train
from mgn.learn.checkpoint import MODEL_FORMAT, read_torch_file
from mgn.learn.floor import fit_floor, floor_footprint, height_above_floor, nominal_intrinsics
from mgn.learn.real_eval import evaluate_real
from mgn.learn.targets import (
    HEIGHT_RANGE_M,
    HEIGHT_SCALE_M,
    MODALITIES,
    height_channel,
    input_channels,
    network_input,
    resize_nearest,
)
from mgn.scene.cameras import Intrinsics

W, H = 160, 120
K = Intrinsics(W, H, 210.0, 205.0, 83.0, 57.0)  # far from the nominal pinhole (f = 160 px)


def _tilted_scene(
    tilt_deg: float, camera_height: float, boxes: list[tuple[float, float, float, float, float]]
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """Ray-cast z-depth (H, W) of a floor plane ``camera_height`` m below the camera, its
    normal tilted by ``tilt_deg`` about an oblique axis, with boxes ``(u0, u1, v0, v1,
    height)`` (footprint in the floor's own coordinates around the optical axis's floor point,
    m; top faces only). Returns the depth,
    the floor's unit normal towards the camera and each box top's pixel mask."""
    a = math.radians(tilt_deg)
    axis = np.array([1.0, 0.6, 0.0]) / math.hypot(1.0, 0.6)
    # Rodrigues: rotate -z (the normal of a floor facing the camera) about the axis
    kx = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    rot = np.eye(3) + math.sin(a) * kx + (1 - math.cos(a)) * kx @ kx
    normal = rot @ np.array([0.0, 0.0, -1.0])
    e1 = rot @ np.array([1.0, 0.0, 0.0])
    e2 = rot @ np.array([0.0, 1.0, 0.0])
    offset = -camera_height  # normal . P = offset on the floor
    uu, vv = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    rays = np.stack([(uu - K.cx) / K.fx, (vv - K.cy) / K.fy, np.ones_like(uu)], axis=-1)
    denom = rays @ normal
    depth = offset / denom  # z of the floor along each ray (the ray's z component is 1)
    origin = np.array([0.0, 0.0, offset / normal[2]])  # the floor on the optical axis
    seen = np.zeros(depth.shape, np.int64)  # 0 the floor, k box k's top
    for k, (u0, u1, v0, v1, hb) in enumerate(boxes, start=1):
        z = (offset + hb) / denom
        p = rays * z[..., None] - origin
        cu, cv = p @ e1, p @ e2
        top = (cu >= u0) & (cu <= u1) & (cv >= v0) & (cv <= v1) & (z < depth)
        depth = np.where(top, z, depth)
        seen[top] = k
    return depth, normal, [seen == k for k in range(1, len(boxes) + 1)]


BOXES = [
    (-0.24, 0.20, -0.20, 0.17, 0.03),  # a large flat box: more pixels than the visible floor
    (0.0, 0.08, 0.0, 0.08, 0.12),  # a tall box on top of it (its own height above the floor)
    (-0.28, -0.20, 0.18, 0.24, 0.075),
]


@pytest.mark.parametrize("tilt_deg", [0.0, 12.0, 25.0])
def test_the_floor_fit_recovers_a_tilted_plane_under_noise_and_outliers(tilt_deg: float):
    depth, normal, tops = _tilted_scene(tilt_deg, 0.72, BOXES)
    floor = ~np.any(tops, axis=0)
    # the flat box's top has more pixels than the floor: the floor is not the largest plane
    assert tops[0].sum() > floor.sum() > 0.15 * depth.size
    rng = np.random.default_rng(5)
    noisy = depth + rng.normal(0.0, 0.001, depth.shape)  # 1 mm sensor noise
    k = rng.random(depth.shape)
    noisy[k < 0.05] = rng.uniform(0.2, 1.5, int((k < 0.05).sum()))  # 5 % wild outliers
    noisy[(k >= 0.05) & (k < 0.10)] = np.nan  # 5 % without a value
    noisy[(k >= 0.10) & (k < 0.12)] = 0.0
    plane = fit_floor(noisy, K)
    angle = math.degrees(math.acos(min(1.0, float(np.dot(plane.normal, normal)))))
    assert angle < 0.3
    assert plane.camera_height_m == pytest.approx(0.72, abs=0.001)
    assert plane.tilt_deg == pytest.approx(tilt_deg, abs=0.3)
    h = height_above_floor(noisy, K, floor=plane)
    clean = k >= 0.12
    valid = np.isfinite(noisy) & (noisy > 0)
    assert np.isnan(h[~valid]).all()
    assert np.isfinite(h[valid]).all()
    for (*_, hb), top in zip(BOXES, tops, strict=True):
        assert abs(float(np.median(h[top & clean])) - hb) < 0.001, hb
    assert abs(float(np.median(h[floor & clean]))) < 0.001
    # the same from the noise-free depth, pixel by pixel
    exact = height_above_floor(depth, K)
    for (*_, hb), top in zip(BOXES, tops, strict=True):
        assert np.abs(exact[top] - hb).max() < 1e-4
    assert np.abs(exact[floor]).max() < 1e-4


def test_the_heights_do_not_depend_on_the_camera_distance_or_tilt():
    a, _, tops_a = _tilted_scene(3.0, 0.7, BOXES)
    b, _, tops_b = _tilted_scene(22.0, 1.1, BOXES)
    ha, hb = height_above_floor(a, K), height_above_floor(b, K)
    for (*_, hbox), ta, tb in zip(BOXES, tops_a, tops_b, strict=True):
        assert float(np.median(ha[ta])) == pytest.approx(hbox, abs=1e-4)
        assert float(np.median(hb[tb])) == pytest.approx(hbox, abs=1e-4)
    assert np.abs(a - b).max() > 0.3  # while the depths differ by decimetres


def test_without_intrinsics_a_nominal_pinhole_finds_the_same_floor():
    depth, _, tops = _tilted_scene(12.0, 0.8, BOXES)
    floor = ~np.any(tops, axis=0)
    h = height_above_floor(depth, None)
    assert np.abs(h[floor]).max() < 1e-4  # the same pixels are the floor
    for (*_, hb), top in zip(BOXES, tops, strict=True):
        # heights scaled by at most the cosine error of the tilt
        assert float(np.median(h[top])) == pytest.approx(hb, rel=0.03)
    k = nominal_intrinsics(H, W)
    assert (k.fx, k.fy, k.cx, k.cy) == (160.0, 160.0, 80.0, 60.0)


def test_the_height_channel_is_the_clipped_scaled_height():
    depth, _, tops = _tilted_scene(8.0, 0.75, BOXES)
    depth[:, :3] = np.nan
    depth[0, 10] = 0.3  # about 0.45 m above the floor: clipped to the range's top
    ch = height_channel(depth, K)
    lo, hi = HEIGHT_RANGE_M
    h = height_above_floor(depth, K)
    expect = np.clip(np.nan_to_num(h, nan=0.0), lo, hi) / HEIGHT_SCALE_M
    np.testing.assert_allclose(ch, expect, atol=1e-6)
    assert ch[0, 10] == pytest.approx(hi / HEIGHT_SCALE_M)
    assert (ch[:, :3] == 0).all()
    assert float(np.median(ch[tops[1]])) == pytest.approx(0.12 / HEIGHT_SCALE_M, abs=0.01)
    x = network_input(None, depth, "height", (64, 80), intrinsics=K)
    assert x.shape == (1, 64, 80)
    rgb = np.zeros((H, W, 3), np.uint8)
    y = network_input(rgb, depth, "rgb-height", (64, 80), intrinsics=K)
    assert y.shape == (4, 64, 80)
    np.testing.assert_array_equal(y[3], x[0])


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (
            lambda: network_input(
                np.zeros((H, W, 3), np.uint8), None, "rgb-height", (32, 32), name="photo_3.png"
            ),
            r"photo_3\.png: the model's input is rgb-height, but no depth",
        ),
        (
            lambda: network_input(None, None, "height", (32, 32), name="scene2/7"),
            r"scene2/7: the model's input is height, but no depth",
        ),
        (
            lambda: fit_floor(np.full((H, W), np.nan), name="photo_4.png"),
            r"photo_4\.png: depth has 0 pixel\(s\) with a value",
        ),
        (
            lambda: fit_floor(np.ones((H, W)), Intrinsics(W + 1, H, 100, 100, 80, 60)),
            r"intrinsics are 161 x 120 px but the depth image is 160 x 120 px",
        ),
    ],
)
def test_bad_input_gives_clear_errors(call, match):
    with pytest.raises(InvalidArgumentError, match=match):
        call()


def test_a_wall_is_not_taken_for_the_floor():
    """A plane seen edge-on (more than 60 degrees from facing the camera) is never the floor,
    however many pixels it has."""
    uu, _ = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    x = (uu - K.cx) / K.fx
    # a wall x = 0.05 + 0.5 (z - 0.5) filling the right part, a floor at z = 0.9 on the left
    z_wall = (0.05 - 0.25) / (x - 0.5)
    depth = np.where((z_wall > 0) & (z_wall < 0.9), z_wall, 0.9)
    assert ((z_wall > 0) & (z_wall < 0.9)).mean() > 0.5
    plane = fit_floor(depth, K)
    assert plane.tilt_deg < 0.1
    assert plane.camera_height_m == pytest.approx(0.9, abs=1e-6)


def test_the_height_modality_round_trips_through_the_model_file(
    small_dataset: Path, tmp_path: Path
):
    assert {"height", "rgb-height"} <= set(MODALITIES)
    assert (input_channels("height"), input_channels("rgb-height")) == (1, 4)
    for modality in ("height", "rgb-height"):
        mc = ModelConfig(
            modality=modality, image_size=32, width=4, floor_footprint=modality == "rgb-height"
        )
        assert ModelConfig.from_dict(mc.to_dict()) == mc
        res = train(
            small_dataset,
            tmp_path / modality,
            model_config=mc,
            train_config=TrainConfig(epochs=1, batch_size=3),
            views=[5],
            num_threads=1,
            progress=False,
        )
        data = read_torch_file(res.model_path, MODEL_FORMAT)
        assert data["model_config"]["modality"] == modality
        assert data["model_config"]["floor_footprint"] == (modality == "rgb-height")
        pred = Predictor(res.model_path, num_threads=1)
        assert pred.config == mc
        first = next(p for p in pred.model.parameters() if p.ndim == 4)
        assert first.shape[1] == input_channels(modality)
        view = mgn.Dataset(small_dataset).scene(0).view(5)
        rgb, depth = view.rgb, view.depth
        p = pred.predict(rgb, depth, name="v5", intrinsics=view.intrinsics)
        assert p.instances.labels.shape == depth.shape
        # the network sees the height channel of the depth, not the depth
        shape = (32, 32)
        fp = mc.floor_footprint
        x = network_input(
            rgb, depth, modality, shape, intrinsics=view.intrinsics, floor_footprint=fp
        )
        hc = height_channel(depth, view.intrinsics, footprint=fp)
        np.testing.assert_array_equal(x[-1], resize_nearest(hc, shape))
        maps = pred.maps(rgb if modality == "rgb-height" else None, depth)[0]
        assert torch.isfinite(torch.from_numpy(maps)).all()
        with pytest.raises(InvalidArgumentError, match=r"v5: the model's input is .*depth"):
            pred.predict(rgb, None, name="v5")
        # a photograph without a depth file beside it
        photos = tmp_path / f"photos_{modality}"
        photos.mkdir()
        Image.fromarray(rgb).save(photos / "a.png")
        h, w = depth.shape
        coco = {
            "images": [{"id": 1, "file_name": "a.png", "width": w, "height": h}],
            "annotations": [],
            "categories": [{"id": 1, "name": "object"}],
        }
        (photos / "annotations.json").write_text(json.dumps(coco))
        with pytest.raises(
            InvalidArgumentError,
            match=rf"a.png: the model's input is {modality}, but it has no depth",
        ):
            evaluate_real(res.model_path, photos, None, num_threads=1, progress=False)


def test_the_footprint_keeps_the_bin_floor_and_its_objects_and_drops_the_walls():
    """A bin: a tilted floor, a box on it, and walls sloping up (1 m per 1.25 m) beyond a
    0.36 x 0.26 m rectangle, ray-cast by fixed-point iteration."""
    depth, normal, tops = _tilted_scene(10.0, 0.8, [(0.02, 0.1, -0.05, 0.03, 0.06)])
    offset = -0.8
    a = math.radians(10.0)
    axis = np.array([1.0, 0.6, 0.0]) / math.hypot(1.0, 0.6)
    kx = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    rot = np.eye(3) + math.sin(a) * kx + (1 - math.cos(a)) * kx @ kx
    e1, e2 = rot @ np.array([1.0, 0.0, 0.0]), rot @ np.array([0.0, 1.0, 0.0])
    uu, vv = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    rays = np.stack([(uu - K.cx) / K.fx, (vv - K.cy) / K.fy, np.ones_like(uu)], axis=-1)
    denom = rays @ normal
    origin = np.array([0.0, 0.0, offset / normal[2]])

    def wall_height(z: np.ndarray) -> np.ndarray:
        p = rays * z[..., None] - origin
        out = np.maximum(np.abs(p @ e1) - 0.18, np.abs(p @ e2) - 0.13)
        return 0.8 * np.maximum(out, 0.0)

    z = depth.copy()
    for _ in range(60):
        z = np.minimum(depth, (offset + wall_height(z)) / denom)
    wall = wall_height(z) > 0.01
    assert 0.3 < wall.mean() < 0.7
    inner = ~wall & (wall_height(z) == 0)
    plane = fit_floor(z, K)
    assert plane.camera_height_m == pytest.approx(0.8, abs=1e-3)
    fp = floor_footprint(z, K, floor=plane)
    assert fp[tops[0]].all()  # the box on the floor is inside
    assert fp[inner].mean() > 0.97  # the floor (up to the hull's pixel rounding at its edge)
    assert not fp[wall].any()
    ch = height_channel(z, K, footprint=True)
    assert (ch[wall] == 0).all()
    assert float(np.median(ch[tops[0]])) == pytest.approx(0.06 / HEIGHT_SCALE_M, abs=0.01)
    assert (height_channel(z, K)[wall] > 0.09).all()  # walls more than 1 cm high
    # a view of the floor only: all of it inside (the image border does not erode it)
    assert floor_footprint(np.full((H, W), 0.7), K).all()


def test_the_command_line_sets_the_height_options():
    p = argparse.ArgumentParser()
    add_model_arguments(p)
    add_train_arguments(p)
    mc, _ = configs_from_args(p.parse_args(["--modality", "rgb-height", "--floor-footprint"]))
    assert (mc.modality, mc.floor_footprint) == ("rgb-height", True)
    mc, _ = configs_from_args(p.parse_args([]))
    assert (mc.modality, mc.floor_footprint) == ("rgb", False)
    with pytest.raises(InvalidArgumentError, match="floor_footprint must be true or false"):
        ModelConfig(floor_footprint="yes")  # type: ignore[arg-type]
