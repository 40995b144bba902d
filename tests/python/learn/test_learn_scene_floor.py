"""The height modalities' training floor from the scene's own geometry
(``ModelConfig.training_floor = "scene"``): :func:`mgn.learn.floor.scene_floor` and
:func:`mgn.learn.floor.bin_interior` against a ray-cast bin, and the training views of a
generated dataset against the renderer's noise-free depth."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pytest

import mgn
import mgn.learn.floor as floor_module
from mgn.cli.learn import add_model_arguments, add_train_arguments, configs_from_args
from mgn.errors import InvalidArgumentError
from mgn.learn import ModelConfig
from mgn.learn.data import load_views, scene_geometry, training_views
from mgn.learn.floor import (
    BIN_INTERIOR_MARGIN_M,
    FloorPlane,
    bin_interior,
    fit_floor,
    floor_footprint,
    height_above_floor,
    scene_floor,
)
from mgn.learn.targets import HEIGHT_SCALE_M, height_channel, resize_nearest
from mgn.scene.cameras import Intrinsics

W, H = 200, 160
K = Intrinsics(W, H, 190.0, 190.0, 97.0, 83.0)
LENGTH, WIDTH, WALL, GROUND = 0.4, 0.3, 0.15, -0.01
BOX = (-0.05, 0.07, -0.04, 0.06, 0.05)  # x0, x1, y0, y1, top (tote frame, m)


def _camera(tilt_deg: float, height: float) -> np.ndarray:
    """X_WC of a camera ``height`` m above the tote's floor centre, looking down, tilted by
    ``tilt_deg`` about the tote's x axis (OpenCV axes: z forward, y down)."""
    a = math.radians(tilt_deg)
    down = np.array([[1.0, 0, 0], [0, -1.0, 0], [0, 0, -1.0]])  # camera z = world -z
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    X = np.eye(4)
    X[:3, :3] = rx @ down
    X[:3, 3] = rx @ np.array([0.0, 0.0, height])
    return X


def _ray_cast(X_WC: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """z-depth (H, W) of a tote (floor z = 0 inside |x| <= L/2, |y| <= W/2, thin walls up to
    WALL, the ground at GROUND outside) with a box on its floor; the surface each pixel hits
    (0 floor, 1 box top, 2 wall, 3 ground) and the hit points in the tote frame (H, W, 3)."""
    uu, vv = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    rays_c = np.stack([(uu - K.cx) / K.fx, (vv - K.cy) / K.fy, np.ones_like(uu)], axis=-1)
    R, c = X_WC[:3, :3], X_WC[:3, 3]
    d = rays_c @ R.T  # world direction per unit camera z
    best = np.full((H, W), np.inf)
    kind = np.full((H, W), -1)

    def offer(t: np.ndarray, ok: np.ndarray, k: int) -> None:
        take = ok & (t > 0) & (t < best)
        best[take] = t[take]
        kind[take] = k

    with np.errstate(divide="ignore", invalid="ignore"):
        for z0, k in ((0.0, 0), (BOX[4], 1), (GROUND, 3)):
            t = (z0 - c[2]) / d[..., 2]
            p = c + t[..., None] * d
            inside = (np.abs(p[..., 0]) <= LENGTH / 2) & (np.abs(p[..., 1]) <= WIDTH / 2)
            if k == 0:
                ok = inside
            elif k == 1:
                ok = (p[..., 0] >= BOX[0]) & (p[..., 0] <= BOX[1])
                ok &= (p[..., 1] >= BOX[2]) & (p[..., 1] <= BOX[3])
            else:
                ok = ~inside
            offer(t, ok, k)
        for axis, half in ((0, LENGTH / 2), (1, WIDTH / 2)):
            for sign in (-1.0, 1.0):
                t = (sign * half - c[axis]) / d[..., axis]
                p = c + t[..., None] * d
                other = np.abs(p[..., 1 - axis]) <= (WIDTH / 2 if axis == 0 else LENGTH / 2)
                offer(t, other & (p[..., 2] >= 0) & (p[..., 2] <= WALL), 2)
    assert (kind >= 0).all()
    points = c + best[..., None] * d
    return best, kind, points  # the ray's camera z is 1 per unit t: t is the z-depth


@pytest.mark.parametrize("tilt_deg", [0.0, 20.0])
def test_the_scene_floor_and_bin_interior_match_a_ray_cast_bin(tilt_deg: float):
    X = _camera(tilt_deg, 0.8)
    depth, kind, points = _ray_cast(X)
    plane = scene_floor(X)
    assert plane.camera_height_m == pytest.approx(0.8 * math.cos(math.radians(tilt_deg)), abs=1e-12)
    h = height_above_floor(depth, K, floor=plane)
    # the height is the hit point's z in the tote frame: 0 on the floor, the box top, the ground
    np.testing.assert_allclose(h, points[..., 2], atol=1e-9)
    assert np.abs(h[kind == 0]).max() < 1e-9
    np.testing.assert_allclose(h[kind == 1], BOX[4], atol=1e-9)
    np.testing.assert_allclose(h[kind == 3], GROUND, atol=1e-9)
    inside = bin_interior(depth, K, X, LENGTH, WIDTH)
    m = BIN_INTERIOR_MARGIN_M
    expected = (np.abs(points[..., 0]) <= LENGTH / 2 - m) & (
        np.abs(points[..., 1]) <= WIDTH / 2 - m
    )
    np.testing.assert_array_equal(inside, expected)
    assert inside[kind == 1].all()
    assert not inside[(kind == 2) | (kind == 3)].any()
    assert inside[kind == 0].mean() > 0.85  # the floor but its strip along the walls
    # no depth: not inside
    holes = depth.copy()
    holes[::7, ::5] = np.nan
    assert not bin_interior(holes, K, X, LENGTH, WIDTH)[::7, ::5].any()
    # with the interior as the footprint the walls and the ground read 0, the box its height
    hc = height_channel(depth, K, footprint=True, floor=plane, inside=inside)
    assert (hc[kind >= 2] == 0).all()
    np.testing.assert_allclose(hc[kind == 1], BOX[4] / HEIGHT_SCALE_M, rtol=1e-5)


@pytest.mark.parametrize("tilt_deg", [0.0, 20.0])
def test_a_bin_on_the_ground_is_fitted_by_its_own_floor(
    tilt_deg: float, monkeypatch: pytest.MonkeyPatch
):
    """A camera that sees the ground around the tote (68 % of the pixels, the tote's floor
    15-19 %): the lowest large plane is the ground, 1 cm below the tote's floor; the bin-floor
    step (walls around it) takes the tote's floor instead, the scene's own plane to 0.1 mm."""
    X = _camera(tilt_deg, 0.8)
    depth, kind, _ = _ray_cast(X)
    assert (kind == 3).mean() > 0.6
    ground = FloorPlane(scene_floor(X).normal, scene_floor(X).offset + GROUND, 0.0)
    assert np.abs(height_above_floor(depth, K, floor=ground)[kind == 3]).max() < 1e-9
    plane = fit_floor(depth, K)
    # without the bin-floor step the fit is the ground
    with monkeypatch.context() as m:
        m.setattr(floor_module, "_bin_floor_above", lambda *a: None)
        lowest = fit_floor(depth, K)
    assert lowest.camera_height_m == pytest.approx(ground.camera_height_m, abs=1e-4)
    assert plane.camera_height_m == pytest.approx(scene_floor(X).camera_height_m, abs=1e-4)
    assert np.dot(plane.normal, scene_floor(X).normal) > math.cos(math.radians(0.1))
    # the footprint of the fitted floor leaves the walls and the ground out
    fp = floor_footprint(depth, K)
    assert fp[kind == 2].mean() < 0.2
    assert not fp[kind == 3].any()


def test_the_bin_floor_step_leaves_a_flat_object_on_a_table_alone():
    """A 3 cm flat box covering a quarter of the view on a table, with the table all around it
    (below it): the box top is no bin floor, the table stays the floor."""
    X = _camera(0.0, 0.8)
    # the whole image a table at z = 0 with one flat box top at 3 cm
    R, c = X[:3, :3], X[:3, 3]
    uu, vv = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    d = np.stack([(uu - K.cx) / K.fx, (vv - K.cy) / K.fy, np.ones_like(uu)], axis=-1) @ R.T
    table = (0.0 - c[2]) / d[..., 2]
    top = (0.03 - c[2]) / d[..., 2]
    p = c + top[..., None] * d
    box = (np.abs(p[..., 0]) <= 0.2) & (np.abs(p[..., 1]) <= 0.15)
    depth = np.where(box, top, table)
    assert 0.2 < box.mean() < 0.5
    plane = fit_floor(depth, K)
    assert plane.camera_height_m == pytest.approx(0.8, abs=1e-4)
    np.testing.assert_allclose(height_above_floor(depth, K, floor=plane)[box], 0.03, atol=1e-4)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: scene_floor(np.eye(3)), "X_WC must be a finite"),
        (lambda: scene_floor(np.full((4, 4), np.nan)), "X_WC must be a finite"),
        (
            lambda: bin_interior(np.full((H, W), 0.8), K, np.eye(4), 0.008, 0.3),
            "must exceed twice the margin",
        ),
        (
            lambda: height_channel(
                np.full((H, W), 0.8), K, footprint=True, inside=np.ones((3, 3), bool), name="v7"
            ),
            r"v7: the footprint is \(3, 3\)",
        ),
        (lambda: ModelConfig(training_floor="truth"), "training_floor must be one of"),
    ],
)
def test_bad_input_gives_clear_errors(call, match):
    with pytest.raises(InvalidArgumentError, match=match):
        call()


def test_training_views_take_the_scene_floor_and_the_bin_interior(small_dataset: Path):
    """On a generated dataset's views the training input's height is the height above the tote's
    inner floor: the renderer's noise-free depth of the visible floor reads 0 (to 0.1 mm), the
    objects above it; the footprint is that of the floor's pixels (``scene``) or the bin's
    interior (``interior``), outside which the channel is 0."""
    views = training_views(small_dataset)[::3]
    shape = (64, 64)
    scene = load_views(
        views, ModelConfig(modality="rgb-height", floor_footprint=True, image_size=64)
    )
    interior = load_views(
        views,
        ModelConfig(
            modality="rgb-height", floor_footprint=True, image_size=64, training_floor="interior"
        ),
    )
    tote = mgn.Dataset(small_dataset).info["config"]["tote"]
    size = (tote["inner_length"], tote["inner_width"])
    seen_floor = 0
    for i, view in enumerate(views):
        floor, inside = scene_geometry(view, size)
        assert floor is not None
        assert inside is not None
        assert scene_geometry(view, size, interior=False) == (floor, None)
        ideal = view.depth_ideal
        assert ideal is not None
        ids = view.instances
        h = height_above_floor(ideal, view.intrinsics, floor=floor)
        bg = (ids == 0) & inside & np.isfinite(h)
        if bg.sum() > 50:
            seen_floor += 1
            assert np.median(np.abs(h[bg])) < 1e-4
        obj = (ids > 0) & inside & np.isfinite(h)
        assert np.median(h[obj]) > 0.005
        # the network's input is this height, 0 outside the footprint
        hc = height_channel(view.depth, view.intrinsics, footprint=True, floor=floor, inside=inside)
        np.testing.assert_array_equal(interior.inputs[i, -1], resize_nearest(hc, shape))
        assert (hc[~inside] == 0).all()
        hull = floor_footprint(view.depth, view.intrinsics, floor=floor)
        hc = height_channel(view.depth, view.intrinsics, footprint=True, floor=floor)
        np.testing.assert_array_equal(scene.inputs[i, -1], resize_nearest(hc, shape))
        assert (hc[~hull] == 0).all()
    assert seen_floor >= 1
    # without the scene's geometry (training_floor fit) the views get the fitted plane
    fitted = load_views(views, ModelConfig(modality="rgb-height", training_floor="fit"))
    view = views[0]
    direct = height_channel(view.depth, view.intrinsics)
    np.testing.assert_array_equal(
        fitted.inputs[0, -1], resize_nearest(direct, fitted.inputs.shape[2:])
    )
    # a bin of unknown size or a view without a camera pose falls back to the fit
    assert scene_geometry(views[0], None) == (None, None)


def test_the_command_line_sets_the_training_floor():
    p = argparse.ArgumentParser()
    add_model_arguments(p)
    add_train_arguments(p)
    mc, _ = configs_from_args(p.parse_args(["--modality", "rgb-height"]))
    assert mc.training_floor == "scene"
    for choice in ("interior", "fit"):
        mc, _ = configs_from_args(p.parse_args(["--training-floor", choice]))
        assert mc.training_floor == choice
    assert ModelConfig.from_dict(mc.to_dict()) == mc
