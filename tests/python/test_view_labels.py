"""Tests of mgn.scene.view_labels: masks, occlusion, boxes, keypoints against analytic box scenes
and against the OSMesa renderer (an independent rasteriser)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import translation

import mgn
from mgn.errors import InvalidArgumentError
from mgn.geometry import make_box
from mgn.io.model_folder import object_mesh
from mgn.objects import ToteSpec, get_object
from mgn.render import CameraView, Instance, Intrinsics, Renderer, look_at, tote_mesh
from mgn.scene import (
    BUILTIN,
    Scene,
    SceneInstance,
    SceneRayModel,
    ViewObjectLabels,
    view_object_labels,
)

H_CAM = 1.0
K200 = Intrinsics(200, 200, 200.0, 200.0, 100.0, 100.0)


def top_down() -> CameraView:
    """1 m above the origin looking down: image x = world x, image down = world -y."""
    X = np.eye(4)
    X[:3, :3] = np.diag([1.0, -1.0, -1.0])
    X[2, 3] = H_CAM
    return CameraView(K200, X)


def render_ids(view: CameraView, items: list[tuple[mgn.Mesh, np.ndarray, int]]) -> np.ndarray:
    r = Renderer(view.K.width, view.K.height)
    r.set_instances([Instance(r.add_mesh(m), X, i) for m, X, i in items])
    return r.render(view, rgb=False, depth=False).instance_ids


def project_count(x0: float, x1: float, y0: float, y1: float, z: float) -> tuple[int, int, int, int]:
    """Pixel range (inclusive u0, u1, v0, v1) whose centres fall in the projection of the world
    rectangle [x0, x1] x [y0, y1] at height z under :func:`top_down`."""
    d = H_CAM - z
    ua, ub = 200 * x0 / d + 100, 200 * x1 / d + 100
    va, vb = -200 * y1 / d + 100, -200 * y0 / d + 100
    return (
        math.ceil(ua - 0.5),
        math.floor(ub - 0.5),
        math.ceil(va - 0.5),
        math.floor(vb - 0.5),
    )


def area(r: tuple[int, int, int, int]) -> int:
    return (r[1] - r[0] + 1) * (r[3] - r[2] + 1)


def test_boxes_side_by_side_have_no_occlusion() -> None:
    a, b = make_box([0.1, 0.1, 0.05]), make_box([0.08, 0.12, 0.04])
    Xa, Xb = translation(-0.1, 0.02, 0.025), translation(0.1, -0.03, 0.02)
    ids = render_ids(top_down(), [(a, Xa, 1), (b, Xb, 2)])
    model = SceneRayModel([a, b], np.stack([Xa, Xb]), [4, 5])
    L = view_object_labels(model, top_down(), ids)
    assert isinstance(L, ViewObjectLabels) and L.num_objects == 2
    np.testing.assert_array_equal(L.instance_ids, [1, 2])
    np.testing.assert_array_equal(L.category_ids, [4, 5])
    ra = project_count(-0.15, -0.05, -0.03, 0.07, 0.05)
    rb = project_count(0.06, 0.14, -0.09, 0.03, 0.04)
    np.testing.assert_array_equal(L.amodal_pixels, [area(ra), area(rb)])
    np.testing.assert_array_equal(L.visible_pixels, [area(ra), area(rb)])
    np.testing.assert_array_equal(L.occlusion, [0.0, 0.0])
    np.testing.assert_array_equal(L.bbox_loose[0], [ra[0], ra[2], ra[1] - ra[0] + 1, ra[3] - ra[2] + 1])
    np.testing.assert_array_equal(L.bbox_tight, L.bbox_loose)
    np.testing.assert_array_equal(L.semantic, np.choose(ids, [0, 4, 5]))
    np.testing.assert_array_equal(L.visible, ids)
    assert L.amodal.shape == (2, 200, 200) and L.amodal.dtype == np.bool_
    # X_CO = X_WC^-1 X_WO.
    np.testing.assert_allclose(L.X_CO[1], np.linalg.inv(top_down().X_WC) @ Xb, atol=1e-12)


def test_box_on_larger_box_occlusion_is_the_covered_fraction() -> None:
    a, b = make_box([0.1, 0.1, 0.05]), make_box([0.3, 0.2, 0.05])
    Xa, Xb = translation(0.02, 0.01, 0.075), translation(0.0, 0.0, 0.025)
    ids = render_ids(top_down(), [(a, Xa, 1), (b, Xb, 2)])
    model = SceneRayModel(
        [a, b],
        np.stack([Xa, Xb]),
        [1, 2],
        keypoints=[[[1, 0, 0, 0.025]], [[1, 0.02, 0.01, 0.025], [2, 0.13, 0.0, 0.025]]],
    )
    L = view_object_labels(model, top_down(), ids)
    rb = project_count(-0.15, 0.15, -0.1, 0.1, 0.05)
    ra = project_count(-0.03, 0.07, -0.04, 0.06, 0.10)
    # Analytic covered fraction: pixels of A's projected top over B's; the rasteriser may round
    # a pixel row or column differently, so allow one pixel along A's perimeter.
    covered = area(ra) / area(rb)
    tol = 2 * (ra[1] - ra[0] + ra[3] - ra[2] + 2) / area(rb)
    assert L.occlusion[1] == pytest.approx(covered, abs=tol)
    assert L.occlusion[0] == pytest.approx(0.0, abs=1e-2)
    assert L.amodal_pixels[1] == area(rb)
    for i in range(2):
        vis = L.visible == i + 1
        assert np.all(L.amodal[i][vis])
        np.testing.assert_array_equal(L.occlusion_map[vis], np.float32(L.occlusion[i]))
    assert np.all(L.occlusion_map[L.visible == 0] == 0)
    # Keypoints: on top of A and B's uncovered corner visible; B's under A occluded.
    np.testing.assert_array_equal(L.keypoints[:, 0], [1, 2])
    np.testing.assert_array_equal(L.keypoint_object, [0, 1])
    np.testing.assert_array_equal(L.occluded_keypoints[:, 0], [1])
    np.testing.assert_array_equal(L.occluded_keypoint_object, [1])
    np.testing.assert_allclose(L.keypoints[1, 1:], [0.13, 0.0, 0.95], atol=1e-12)
    # Without CoM points: the CoM lists are empty, the heat map still lives in [0, 1].
    assert L.com_points.shape == (0, 4) and L.com_visible.shape == (0,)
    assert L.com_heatmap.dtype == np.float32
    assert 0.0 <= L.com_heatmap.min() and L.com_heatmap.max() <= 1.0
    assert np.all(L.com_heatmap[L.visible == 0] == 0)


@pytest.fixture(scope="module")
def library_scene() -> Scene:
    """Library objects standing in the tote, one of them hidden in part by a tote wall."""
    tote = ToteSpec()
    names = ["mug", "box_cereal", "pear", "can_soda", "bottle_clear"]
    spots = [(-0.08, -0.05, 0.3), (0.06, 0.04, 1.0), (-0.1, 0.08, 0.0), (0.1, -0.08, 2.0),
             (0.0, 0.02, 0.7)]  # fmt: skip
    inst = []
    for k, (name, (x, y, yaw)) in enumerate(zip(names, spots, strict=True)):
        spec = get_object(name)
        mesh = object_mesh(spec)
        X = translation(x, y, -float(np.asarray(mesh.bounds)[0, 2]))
        c, s = math.cos(yaw), math.sin(yaw)
        X[:2, :2] = [[c, -s], [s, c]]
        inst.append(SceneInstance(k + 1, name, spec.category_id, BUILTIN, X))
    return Scene(tuple(inst), tote, seed=0)


@pytest.fixture(scope="module")
def library_model(library_scene: Scene) -> SceneRayModel:
    return SceneRayModel.from_scene(library_scene)


def test_amodal_matches_the_renderer_alone_on_99_percent(library_scene, library_model) -> None:
    scene = library_scene
    view = CameraView(K200, look_at([0.35, -0.45, 0.55], [0.0, 0.0, 0.05]))
    r = Renderer(200, 200)
    items = [(scene.mesh(i), inst.X_WO, inst.instance_id) for i, inst in enumerate(scene.instances)]
    tote = Instance(r.add_mesh(tote_mesh(scene.tote)), np.eye(4), 0)
    r.set_instances([Instance(r.add_mesh(m), X, i) for m, X, i in items] + [tote])
    ids = r.render(view, rgb=False, depth=False).instance_ids
    L = view_object_labels(library_model, view, ids)
    assert L.num_objects == 5
    for i in range(5):
        alone = r.render(view, rgb=False, depth=False, visible_instances=[i + 1]).instance_ids
        rendered = alone == i + 1
        union = rendered | L.amodal[i]
        assert union.sum() > 50
        agree = (rendered == L.amodal[i])[union].mean()
        assert agree >= 0.99, (i, agree)
        vis = L.visible == i + 1
        assert np.all(L.amodal[i][vis])
        if vis.any():
            assert 0.0 <= L.occlusion[i] < 1.0
        assert L.occlusion[i] == pytest.approx(1 - vis.sum() / L.amodal[i].sum())
        x, y, w, h = L.bbox_loose[i]
        rows, cols = np.nonzero(L.amodal[i])
        assert (x, y, w, h) == (cols.min(), rows.min(), cols.ptp() + 1, rows.ptp() + 1)
    # Semantic keypoints and CoM points: all of them, split by visibility.
    n_kp = sum(len(library_scene.object_spec(i).keypoints) for i in range(5))
    assert len(L.keypoints) + len(L.occluded_keypoints) == n_kp
    assert L.com_points.shape == (5000, 4)
    np.testing.assert_array_equal(L.com_object, np.repeat(np.arange(5), 1000))
    # A visible CoM point projects onto a pixel of its own object (or its edge), an occluded
    # one mostly does not.
    p = L.com_points[:, 1:]
    u = np.floor(200 * p[:, 0] / p[:, 2] + 100).astype(int).clip(0, 199)
    v = np.floor(200 * p[:, 1] / p[:, 2] + 100).astype(int).clip(0, 199)
    own = L.visible[v, u] == L.com_object + 1
    assert own[L.com_visible].mean() > 0.95
    assert own[~L.com_visible].mean() < 0.1
    # Heat map: the CoM score, highest on the object's face nearest to its centre of mass.
    assert L.com_heatmap.max() <= 1.0 and L.com_heatmap.min() >= 0.0
    assert np.all(L.com_heatmap[L.visible == 0] == 0)
    assert L.com_heatmap[L.visible > 0].mean() > 0.2


def test_tote_wall_counts_as_an_occluder(library_scene, library_model) -> None:
    # A low camera outside the tote: the near wall hides the lower part of the objects.
    view = CameraView(K200, look_at([0.0, -0.9, 0.12], [0.0, 0.0, 0.05]))
    r = Renderer(200, 200)
    r.set_instances(
        [Instance(r.add_mesh(library_scene.mesh(i)), inst.X_WO, inst.instance_id)
         for i, inst in enumerate(library_scene.instances)]
        + [Instance(r.add_mesh(tote_mesh(library_scene.tote)), np.eye(4), 0)]
    )  # fmt: skip
    ids = r.render(view, rgb=False, depth=False).instance_ids
    L = view_object_labels(library_model, view, ids)
    seen = L.visible_pixels > 0
    assert np.any(seen & (L.occlusion > 0.2))
    # Amodal masks ignore the tote: they continue below the wall's top edge.
    for i in np.nonzero(seen)[0]:
        assert L.amodal_pixels[i] > L.visible_pixels[i]


def test_one_and_two_threads_are_identical(library_scene, library_model) -> None:
    view = CameraView(K200, look_at([-0.3, 0.25, 0.6], [0.0, 0.0, 0.0]))
    ids = render_ids(
        view,
        [(library_scene.mesh(i), inst.X_WO, inst.instance_id)
         for i, inst in enumerate(library_scene.instances)],
    )  # fmt: skip
    a = view_object_labels(library_model, view, ids, num_threads=1)
    b = view_object_labels(library_model, view, ids, num_threads=2)
    for name in ViewObjectLabels.__dataclass_fields__:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


def test_bad_input_gives_clear_errors(library_model) -> None:
    view = top_down()
    with pytest.raises(InvalidArgumentError, match=r"shape \(100, 200\); expected \(H, W\)"):
        view_object_labels(library_model, view, np.zeros((100, 200), np.int32))
    bad = np.zeros((200, 200), np.int32)
    bad[5, 7] = 6
    with pytest.raises(InvalidArgumentError, match=r"ids must be in 0\.\.5"):
        view_object_labels(library_model, view, bad)
    with pytest.raises(InvalidArgumentError, match="integer"):
        view_object_labels(library_model, view, np.zeros((200, 200), np.float32))
    with pytest.raises(ValueError, match="no objects"):
        SceneRayModel([], np.zeros((0, 4, 4)), [])
    with pytest.raises(ValueError, match="no objects"):
        SceneRayModel.from_scene(Scene((), ToteSpec(), seed=0))
    with pytest.raises(ValueError, match="category id 0"):
        SceneRayModel([make_box([0.1, 0.1, 0.1])], np.eye(4)[None], [0])
    with pytest.raises(ValueError, match="expected one per mesh"):
        SceneRayModel([make_box([0.1, 0.1, 0.1])], np.eye(4)[None], [1], keypoints=[])
