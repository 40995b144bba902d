"""Lens distortion (mgn.scene.lens, docs/cameras.md): images and labels of a camera with OpenCV
distortion coefficients match what that camera sees. The truth is OpenCV's own implementation
of the model (cv2.projectPoints, cv2.undistortPoints, cv2.initUndistortRectifyMap), analytic
ray-plane intersections, and the pinhole render of the same scene."""

from __future__ import annotations

import hashlib
import json

import cv2
import numpy as np
import pytest

from mgn.errors import InvalidArgumentError
from mgn.geometry.mesh import make_box, make_sphere
from mgn.io.dataset import Dataset
from mgn.io.validate import validate_dataset
from mgn.objects import ToteSpec
from mgn.pipeline.label_scene import LabelOptions, label_scene
from mgn.render.renderer import Renderer
from mgn.render.views import iter_views
from mgn.scene.cameras import CameraView, Intrinsics, look_at, mgn_rig
from mgn.scene.lens import lens_for
from mgn.scene.scene import BUILTIN, Scene, SceneInstance
from mgn.view_labels.objects import SceneRayModel, distort_view_object_labels, view_object_labels

#: Coefficient sets of every length OpenCV takes (all invertible over a 640 x 480 image).
COEFFS = [
    (-0.28, 0.09, 0.0012, -0.0008),
    (-0.3, 0.12, 0.001, -0.002, -0.02),
    (0.12, -0.05, 0.0005, 0.001, 0.01),
    (-0.25, 0.08, 0.001, 0.0005, -0.01, 0.02, -0.01, 0.005),
    (-0.2, 0.05, 0.001, 0.0, 0.0, 0.0, 0.0, 0.0, 0.001, -0.0005, 0.0008, 0.0002),
    (-0.2, 0.05, 0.001, 0.0, 0.0, 0.0, 0.0, 0.0, 0.001, -0.0005, 0.0008, 0.0002, 0.01, -0.015),
]
#: OpenCV's iterative undistortion, run to convergence.
CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12)


def _K(dist=(), w=640, h=480) -> Intrinsics:
    return Intrinsics(w, h, 500.0, 505.0, 0.5 * w + 3.3, 0.5 * h - 2.1, dist)


def _opencv_uv(K: Intrinsics, p_C: np.ndarray) -> np.ndarray:
    """cv2.projectPoints in mgn's continuous image coordinates (pixel centres at +0.5)."""
    uv, _ = cv2.projectPoints(
        np.asarray(p_C, np.float64).reshape(-1, 1, 3),
        np.zeros(3),
        np.zeros(3),
        K.K_opencv,
        np.asarray(K.distortion),
    )
    return uv.reshape(-1, 2) + 0.5


def _cam_down(K: Intrinsics, height: float = 0.5) -> CameraView:
    return CameraView(K, look_at([0.0, 0.0, height], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]))


def _render(objects, view, floor=True):
    return next(
        iter(
            iter_views(
                objects, None, [view], sensor="ideal", randomize=False, floor=floor, shadows=False
            )
        )
    )


@pytest.mark.parametrize("dist", COEFFS, ids=[f"{len(c)}coeffs" for c in COEFFS])
def test_model_and_map_agree_with_opencv(dist):
    K = _K(dist)
    lens = lens_for(K)
    assert lens is not None
    rng = np.random.default_rng(len(dist))
    p_C = rng.uniform([-0.35, -0.25, 0.5], [0.35, 0.25, 0.7], (400, 3))
    np.testing.assert_allclose(lens.project(p_C), _opencv_uv(K, p_C), atol=1e-6)
    # The map: where each distorted pixel centre lies in the pinhole render (OpenCV's iterative
    # undistortion, given enough iterations, as the second implementation).
    vs, us = rng.integers(0, K.height, 300), rng.integers(0, K.width, 300)
    R = lens.render_K
    und = cv2.undistortPoints(
        np.stack([us, vs], 1).astype(np.float64).reshape(-1, 1, 2),
        K.K_opencv,
        np.asarray(dist),
        R=None,
        P=R.K_opencv,
        criteria=CRITERIA,
    ).reshape(-1, 2)
    got = np.stack([lens.map_u[vs, us], lens.map_v[vs, us]], 1)
    np.testing.assert_allclose(got, und, atol=2e-3)
    # The render covers every pixel with its bilinear neighbours.
    assert lens.map_u.min() >= 1
    assert lens.map_u.max() <= R.width - 2
    assert lens.map_v.min() >= 1
    assert lens.map_v.max() <= R.height - 2


def test_in_image_matches_opencv_bounds_and_rejects_folded_points():
    K = _K((-0.3, 0.12, 0.001, -0.002, -0.02))
    lens = lens_for(K)
    rng = np.random.default_rng(1)
    p_C = rng.uniform([-1.6, -1.6, 0.5], [1.6, 1.6, 1.0], (6000, 3))
    uv = _opencv_uv(K, p_C)
    r = np.hypot(p_C[:, 0] / p_C[:, 2], p_C[:, 1] / p_C[:, 2])
    by_cv = (uv[:, 0] >= 0) & (uv[:, 0] < K.width) & (uv[:, 1] >= 0) & (uv[:, 1] < K.height)
    got = lens.in_image(p_C)
    assert got.sum() > 500
    assert (~got).sum() > 500
    # Far outside the field of view the polynomial folds back into the image: those points
    # are not seen, whatever OpenCV's formula gives.
    folded = by_cv & (r > lens.max_radius)
    assert folded.sum() > 0
    np.testing.assert_array_equal(got, by_cv & ~folded)
    assert not lens.in_image([[0.0, 0.0, -1.0]])[0]


def test_zero_distortion_is_the_pinhole_byte_for_byte(tmp_path):
    assert _K((0.0, 0.0, 0.0, 0.0, 0.0)) == _K()
    assert lens_for(_K((0.0,) * 5)) is None

    def inst(i, name, X):
        from mgn.objects import get_object

        return SceneInstance(i, name, get_object(name).category_id, BUILTIN, X, ())

    X1, X2 = np.eye(4), np.eye(4)
    X1[:3, 3] = (-0.02, -0.02, 0.045)
    X2[:3, 3] = (0.0, 0.1125, 0.0325)
    scene = Scene((inst(1, "box_shoe", X1), inst(2, "box_tea", X2)), ToteSpec(), seed=3)
    poses, _ = mgn_rig(3)
    digests = []
    for dist in ((), (0.0, 0.0, 0.0, 0.0, 0.0)):
        K = Intrinsics(240, 240, 400.0, 400.0, 120.0, 120.0, dist)
        folder = tmp_path / f"d{len(dist)}"
        label_scene(
            scene,
            folder,
            [(v, CameraView(K, poses[v])) for v in (0, 20)],
            options=LabelOptions(randomize=False, num_threads=2),
        )
        digests.append(
            {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}
        )
    assert len(digests[0]) > 10
    assert digests[0] == digests[1]


def test_known_point_lands_where_opencv_projects_it():
    K = _K((-0.3, 0.12, 0.001, -0.002, -0.02))
    view = _cam_down(K)
    # A 12 mm ball near the image corner, where the lens moves it by tens of pixels.
    P_W = np.array([0.25, -0.16, 0.02])
    X = np.eye(4)
    X[:3, 3] = P_W
    ball = make_sphere(0.006, 48, 24)
    img = _render([(ball, X, 1)], view)
    X_CW = np.linalg.inv(view.X_WC)
    p_C = X_CW[:3, :3] @ P_W + X_CW[:3, 3]
    uv_cv = _opencv_uv(K, p_C)[0]
    uv_pin = np.array([K.fx * p_C[0] / p_C[2] + K.cx, K.fy * p_C[1] / p_C[2] + K.cy])
    assert np.linalg.norm(uv_cv - uv_pin) > 20.0  # the test would notice a pinhole
    vs, us = np.nonzero(img.instance_ids == 1)
    assert len(us) > 40
    assert us.mean() + 0.5 == pytest.approx(uv_cv[0], abs=0.3)
    assert vs.mean() + 0.5 == pytest.approx(uv_cv[1], abs=0.3)
    # The labels: computed on the pinhole render, resampled through the lens.
    kp = np.array([[1.0, 0.0, 0.0, 0.0]])  # the ball's centre, object frame (hidden inside it)
    model = SceneRayModel([ball], X[None], [1], keypoints=[kp], com_points=None)
    assert img.pinhole is not None
    assert img.lens is not None
    pin = view_object_labels(
        model,
        img.pinhole.view,
        img.pinhole.instance_ids,
        depth=img.pinhole.depth_ideal,
        num_threads=1,
    )
    with pytest.raises(InvalidArgumentError, match="distort_view_object_labels"):
        view_object_labels(model, view, img.instance_ids)
    labels = distort_view_object_labels(pin, img.lens)
    np.testing.assert_array_equal(labels.visible, img.instance_ids)
    x, y, w, h = labels.bbox_tight[0]
    assert (x + w / 2, y + h / 2) == pytest.approx(tuple(uv_cv), abs=0.75)
    assert labels.visible_pixels[0] == len(us) == labels.amodal_pixels[0]
    assert labels.occlusion[0] == pytest.approx(0.0)
    # The ideal depth on the floor (plane z = 0) is the plane's depth along each pixel's ray.
    fv, fu = np.nonzero(img.instance_ids == 0)
    pick = np.random.default_rng(0).choice(len(fu), 2000, replace=False)
    fu, fv = fu[pick], fv[pick]
    rays = cv2.undistortPoints(
        np.stack([fu, fv], 1).astype(np.float64).reshape(-1, 1, 2),
        K.K_opencv,
        np.asarray(K.distortion),
        criteria=CRITERIA,
    ).reshape(-1, 2)
    d_C = np.column_stack([rays, np.ones(len(rays))])
    d_W = d_C @ view.X_WC[:3, :3].T
    t = -view.X_WC[2, 3] / d_W[:, 2]  # camera height 0.5 m above the floor z = 0
    z_truth = t  # d_C has z = 1, so the ray parameter is the z-depth
    got = img.depth_ideal[fv, fu]
    close = np.abs(got - z_truth) < 1e-4 * z_truth
    assert close.mean() > 0.98, np.abs(got - z_truth).max()


def test_a_straight_bar_bends_as_the_model_says():
    K = _K((-0.3, 0.12, 0.0, 0.0, -0.02))
    view = _cam_down(K)
    # A flat 0.9 m strip, 8 mm wide, 0.15 m off the optical axis: a straight line in the scene
    # (0.5 mm thin, so its side faces add no width seen from above).
    X = np.eye(4)
    X[:3, 3] = (0.0, 0.15, 0.02)
    bar = make_box((0.9, 0.008, 0.0005))
    img = _render([(bar, X, 1)], view, floor=False)
    mask = img.instance_ids == 1
    cols = np.flatnonzero(mask.sum(axis=0) >= 3)
    assert len(cols) > 400
    rows = np.arange(K.height)[:, None] + 0.5
    centre_v = (mask[:, cols] * rows).sum(axis=0) / mask[:, cols].sum(axis=0)
    # Truth: the strip's top centre line, projected by OpenCV.
    xs = np.linspace(-0.45, 0.45, 4001)
    line_W = np.column_stack([xs, np.full_like(xs, 0.15), np.full_like(xs, 0.02025)])
    X_CW = np.linalg.inv(view.X_WC)
    uv = _opencv_uv(K, line_W @ X_CW[:3, :3].T + X_CW[:3, 3])
    order = np.argsort(uv[:, 0])
    truth_v = np.interp(cols + 0.5, uv[order, 0], uv[order, 1])
    err = centre_v - truth_v
    assert np.abs(err).mean() < 0.25
    assert np.abs(err).max() < 0.8
    # Barrel distortion (k1 < 0): the line bows away from the image centre; its middle lies
    # further from the centre than the chord through its ends, by many pixels.
    chord = np.interp(cols, [cols[0], cols[-1]], [centre_v[0], centre_v[-1]])
    mid = len(cols) // 2
    side = np.sign(centre_v[mid] - K.cy)
    sagitta = side * (centre_v[mid] - chord[mid])
    assert sagitta > 8.0


def test_undistorting_reproduces_the_pinhole_render():
    dist = (-0.3, 0.12, 0.001, -0.002, -0.02)
    K, K0 = _K(dist), _K()
    view, view0 = _cam_down(K, 0.6), _cam_down(K0, 0.6)
    objs = []
    for i, (x, y, s) in enumerate(
        [
            (0.0, 0.0, 0.1),
            (0.17, 0.1, 0.08),
            (-0.2, -0.12, 0.09),
            (0.22, -0.14, 0.06),
            (-0.15, 0.15, 0.07),
        ]
    ):
        X = np.eye(4)
        X[:3, :3] = cv2.Rodrigues(np.array([0.0, 0.0, 0.4 * i]))[0]
        X[:3, 3] = (x, y, s / 2)
        objs.append((make_box((s, 0.7 * s, s)), X, i + 1))
    img = _render(objs, view)
    ref = _render(objs, view0)
    mx, my = cv2.initUndistortRectifyMap(
        K.K_opencv, np.asarray(dist), None, K0.K_opencv, (K.width, K.height), cv2.CV_32FC1
    )
    inside = (mx >= 0) & (mx <= K.width - 1) & (my >= 0) & (my <= K.height - 1)
    ids = cv2.remap(img.instance_ids.astype(np.float32), mx, my, cv2.INTER_NEAREST)
    agree = (ids.astype(np.int32) == ref.instance_ids)[inside]
    assert agree.mean() > 0.99
    rgb = cv2.undistort(img.rgb, K.K_opencv, np.asarray(dist))
    core = inside & (cv2.erode(inside.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0)
    diff = np.abs(rgb.astype(np.int32) - ref.rgb.astype(np.int32))[core]
    assert diff.mean() < 2.5
    assert np.percentile(diff, 99) < 60
    z = cv2.remap(img.depth_ideal, mx, my, cv2.INTER_NEAREST)
    same = inside & (ids.astype(np.int32) == ref.instance_ids) & (ref.depth_ideal > 0)
    rel = np.abs(z[same] - ref.depth_ideal[same]) / ref.depth_ideal[same]
    assert np.median(rel) < 1e-3
    assert np.percentile(rel, 99) < 0.02


def test_sensor_depth_is_invalid_at_edges_and_errors_name_the_lens():
    K = _K((-0.3, 0.12, 0.001, -0.002, -0.02))
    view = _cam_down(K)
    X = np.eye(4)
    X[:3, 3] = (0.05, 0.0, 0.05)
    img = next(
        iter(
            iter_views(
                [(make_box((0.1, 0.1, 0.1)), X, 1)],
                None,
                [view],
                sensor="ideal",
                randomize=False,
                shadows=False,
            )
        )
    )
    ids = img.instance_ids
    edge = np.zeros_like(ids, bool)
    edge[:, 1:] |= ids[:, 1:] != ids[:, :-1]
    edge[1:, :] |= ids[1:, :] != ids[:-1, :]
    # Interpolating across the box's outline would invent depths between box and floor.
    assert not img.valid[edge].all()
    assert np.isnan(img.depth[~img.valid]).all()
    assert np.isfinite(img.depth[img.valid]).all()
    assert (img.depth_ideal > 0).all()  # the ideal depth takes the nearest pixel at edges
    assert img.valid.mean() > 0.95
    with pytest.raises(InvalidArgumentError, match="distortion"):
        Renderer(640, 480).render(view)
    with pytest.raises(InvalidArgumentError, match="cannot be inverted"):
        lens_for(_K((-0.3, 0.12, 0.001, -0.002, -0.02, 0.01, 0.02, 0.03)))
    with pytest.raises(InvalidArgumentError, match="4, 5, 8, 12 or 14"):
        _K((0.1, 0.2, 0.3))


def test_a_distorted_dataset_records_its_lens(tmp_path):
    from mgn.objects import get_object

    X = np.eye(4)
    X[:3, 3] = (0.0, 0.0, 0.045)
    scene = Scene(
        (SceneInstance(1, "box_shoe", get_object("box_shoe").category_id, BUILTIN, X, ("floor",)),),
        ToteSpec(),
        seed=1,
    )
    dist = (-0.2, 0.05, 0.001, 0.0005, 0.0)
    K = Intrinsics(240, 200, 250.0, 250.0, 120.0, 100.0, dist)
    poses, _ = mgn_rig(1)
    label_scene(
        scene,
        tmp_path / "ds" / "scene0",
        [(0, CameraView(K, poses[0]))],
        options=LabelOptions(randomize=False, num_threads=2),
    )
    assert validate_dataset(tmp_path / "ds") == []
    view = Dataset(tmp_path / "ds").scenes()[0].views()[0]
    assert view.intrinsics == K
    assert view.intrinsics.distortion == dist
    params = json.loads((tmp_path / "ds" / "scene0" / "0_camera_params.json").read_text())
    assert params["distortion_model"] == "opencv"
    assert params["distortion"] == list(dist)


def test_grasps_are_kept_where_the_lens_sees_their_contacts():
    from mgn.pj.labels import PjLabels
    from mgn.suction.labels import SuctionLabels
    from mgn.view_labels.grasps import SceneGraspModel

    # A 0.8 m plate, 20 mm thick, wider than the image; grasp points on its top face.
    g = np.linspace(-0.38, 0.38, 39)
    pts = np.array([[x, y, 0.01] for x in g for y in g], np.float32)
    n = len(pts)
    down = np.tile(np.float32([0, 0, 1]), (n, 1))  # object frame: approach into the face
    su = SuctionLabels(
        points=pts,
        approach=-down,
        score=np.ones(n, np.float32),
        wrench=np.zeros(n, np.float32),
        reason=np.zeros(n, np.uint8),
        num_candidates=n,
        num_colliding=0,
    )
    closing = np.tile(np.float32([1, 0, 0]), (n, 1))
    pj = PjLabels(
        approach=-down,
        closing=closing,
        p1=pts,
        width=np.full(n, 0.06, np.float32),
        quality_score=np.ones(n, np.float32),
        score_wrench=np.zeros(n, np.float32),
        quality_score_simulation=np.ones(n, np.float32),
        point_index=np.arange(n),
        point_score=np.ones(n, np.float32),
        num_points=n,
        num_colliding=0,
    )
    X = np.eye(4)
    X[2, 3] = 0.01
    floor = make_box((1.0, 1.0, 0.01))
    X_floor = np.eye(4)
    X_floor[2, 3] = -0.005
    sgm = SceneGraspModel.from_meshes(
        [make_box((0.8, 0.8, 0.02))],
        X[None],
        [1.0],
        np.zeros((1, 3)),
        [pj],
        [su],
        floor,
        X_floor,
        num_threads=1,
    )
    for dist in [(0.25, 0.05, 0.002, 0.001, 0.0), (-0.3, 0.12, 0.001, -0.002, -0.02)]:
        K = Intrinsics(320, 240, 300.0, 300.0, 161.0, 118.0, dist)
        view = _cam_down(K, 0.45)
        got = sgm.view_grasps(view, np.array([True]))
        X_CW = np.linalg.inv(view.X_WC)

        def seen(p_W, K=K, X_CW=X_CW):
            uv = _opencv_uv(K, p_W @ X_CW[:3, :3].T + X_CW[:3, 3])
            return (uv[:, 0] >= 0) & (uv[:, 0] < K.width) & (uv[:, 1] >= 0) & (uv[:, 1] < K.height)

        top = pts.astype(np.float64) + [0.0, 0.0, 0.01]
        want_su = np.flatnonzero(seen(top))
        want_pj = np.flatnonzero(seen(top) | seen(top + [0.06, 0.0, 0.0]))
        assert 0 < len(want_su) < n
        assert len(want_pj) > len(want_su)
        su_idx = np.sort(
            np.concatenate([got.non_colliding.suctioncup.index, got.colliding.suctioncup.index])
        )
        pj_idx = np.sort(
            np.concatenate([got.non_colliding.paralleljaw.index, got.colliding.paralleljaw.index])
        )
        np.testing.assert_array_equal(su_idx, want_su)
        np.testing.assert_array_equal(pj_idx, want_pj)
        # The pinhole with the same K keeps a different set: the lens matters here.
        pin = sgm.view_grasps(_cam_down(K.pinhole(), 0.45), np.array([True]))
        pin_su = np.concatenate(
            [pin.non_colliding.suctioncup.index, pin.colliding.suctioncup.index]
        )
        assert len(pin_su) != len(want_su)


def test_config_rejects_a_lens_that_folds_over():
    from mgn.pipeline.config import ConfigError, load_config

    with pytest.raises(ConfigError, match=r"camera\.intrinsics\.distortion.*cannot be inverted"):
        load_config(
            {
                "camera": {
                    "intrinsics": {
                        "width": 320,
                        "height": 240,
                        "fx": 300,
                        "fy": 300,
                        "cx": 160,
                        "cy": 120,
                        "distortion": [-2.0, 0, 0, 0, 0],
                    }
                }
            }
        )


def test_the_path_tracer_goes_through_the_same_lens():
    from mgn.render.settings import RenderSettings

    K = _K((-0.3, 0.12, 0.001, -0.002, -0.02), 320, 240)
    K = Intrinsics(320, 240, 250.0, 250.0, 161.0, 118.0, K.distortion)
    view = _cam_down(K, 0.5)
    X = np.eye(4)
    X[:3, 3] = (0.2, -0.14, 0.03)  # near the corner, where the lens moves it most
    objs = [(make_box((0.06, 0.06, 0.06)), X, 1)]
    settings = RenderSettings(
        engine="path", spp=4, denoise=False, spp_without_denoiser=4, max_bounces=1
    )
    path = next(
        iter(iter_views(objs, None, [view], sensor="ideal", randomize=False, render=settings))
    )
    raster = _render(objs, view)
    assert path.engine["engine"] == "path"
    assert path.rgb.shape == raster.rgb.shape
    np.testing.assert_array_equal(path.instance_ids, raster.instance_ids)
    # The box's colour edge in the traced picture follows the lens: the box is where its ids are.
    grey = path.rgb.astype(np.float32).mean(axis=2)
    inside = raster.instance_ids == 1
    ring = cv2.dilate(inside.astype(np.uint8), np.ones((7, 7), np.uint8)).astype(bool) & ~inside
    assert abs(float(grey[inside].mean()) - float(grey[ring].mean())) > 10.0
    edge_in = inside & ~cv2.erode(inside.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    gy, gx = np.gradient(cv2.GaussianBlur(grey, (3, 3), 0))
    mag = np.hypot(gx, gy)
    assert mag[edge_in].mean() > 3.0 * mag[~(inside | ring)].mean()


def test_pictures_and_pixel_predictions_go_through_the_lens():
    from mgn.viz.overlay import project

    K = _K((-0.3, 0.12, 0.001, -0.002, -0.02))
    lens = lens_for(K)
    rng = np.random.default_rng(5)
    p_C = rng.uniform([-0.3, -0.2, 0.5], [0.3, 0.2, 0.7], (200, 3))
    uv, front = project(p_C, K)  # what `mgn show` draws keypoints and grasps with
    assert front.all()
    np.testing.assert_allclose(uv, _opencv_uv(K, p_C), atol=1e-6)
    # A pixel prediction (u, v) and its depth back-project onto the ray OpenCV gives.
    xy = lens.normalized(uv[:, 0], uv[:, 1])
    np.testing.assert_allclose(xy, p_C[:, :2] / p_C[:, 2:], atol=1e-9)
