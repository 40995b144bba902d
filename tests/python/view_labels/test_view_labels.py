"""Tests of mgn.view_labels.objects: masks, occlusion, boxes, keypoints against analytic box scenes
and against the OSMesa renderer (an independent rasteriser)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import translation

import mgn
from mgn.errors import InvalidArgumentError
from mgn.geometry.mesh import make_box
from mgn.io.image_codecs import com_heatmap_prediction
from mgn.objects import ToteSpec, com_keypoints, get_object, tote_mesh
from mgn.render import Instance, Renderer
from mgn.scene import BUILTIN, Scene, SceneInstance
from mgn.scene.cameras import CameraView, Intrinsics, look_at
from mgn.view_labels.objects import SceneRayModel, ViewObjectLabels, view_object_labels

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


def silhouette(extents: list[float], X_WO: np.ndarray, view: CameraView) -> np.ndarray:
    """(H, W) bool: pixels whose centre lies in the convex hull of the 8 projected corners of a
    box (its exact pinhole silhouette, computed without ray tracing or rasterising)."""
    from scipy.spatial import ConvexHull

    half = np.asarray(extents) / 2
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
    p_W = corners @ X_WO[:3, :3].T + X_WO[:3, 3]
    X_CW = np.linalg.inv(view.X_WC)
    p_C = p_W @ X_CW[:3, :3].T + X_CW[:3, 3]
    K = view.K
    uv = np.column_stack([K.fx * p_C[:, 0] / p_C[:, 2] + K.cx, K.fy * p_C[:, 1] / p_C[:, 2] + K.cy])
    eq = ConvexHull(uv).equations
    vv, uu = np.mgrid[0 : K.height, 0 : K.width]
    centres = np.column_stack([uu.ravel() + 0.5, vv.ravel() + 0.5])
    inside = np.all(centres @ eq[:, :2].T + eq[:, 2] <= 0, axis=1)
    return inside.reshape(K.height, K.width)


def box_of(mask: np.ndarray) -> list[int]:
    rows, cols = np.nonzero(mask)
    return [cols.min(), rows.min(), cols.max() - cols.min() + 1, rows.max() - rows.min() + 1]


def near_equal(a: np.ndarray, b: np.ndarray, max_diff: int) -> bool:
    """Masks equal up to ``max_diff`` pixels (centres on an edge, float rounding)."""
    return int(np.count_nonzero(a != b)) <= max_diff


def test_boxes_side_by_side_have_no_occlusion() -> None:
    a, b = make_box([0.1, 0.1, 0.05]), make_box([0.08, 0.12, 0.04])
    Xa, Xb = translation(-0.1, 0.02, 0.025), translation(0.1, -0.03, 0.02)
    ids = render_ids(top_down(), [(a, Xa, 1), (b, Xb, 2)])
    model = SceneRayModel([a, b], np.stack([Xa, Xb]), [4, 5])
    L = view_object_labels(model, top_down(), ids)
    assert isinstance(L, ViewObjectLabels)
    assert L.num_objects == 2
    np.testing.assert_array_equal(L.instance_ids, [1, 2])
    np.testing.assert_array_equal(L.category_ids, [4, 5])
    sa = silhouette([0.1, 0.1, 0.05], Xa, top_down())
    sb = silhouette([0.08, 0.12, 0.04], Xb, top_down())
    assert near_equal(L.amodal[0], sa, 2)
    assert near_equal(L.amodal[1], sb, 2)
    np.testing.assert_array_equal(L.amodal_pixels, L.visible_pixels)
    np.testing.assert_array_equal(L.occlusion, [0.0, 0.0])
    np.testing.assert_array_equal(L.bbox_loose[0], box_of(sa))
    np.testing.assert_array_equal(L.bbox_tight, L.bbox_loose)
    np.testing.assert_array_equal(L.semantic, np.choose(ids, [0, 4, 5]))
    np.testing.assert_array_equal(L.visible, ids)
    assert L.amodal.shape == (2, 200, 200)
    assert L.amodal.dtype == np.bool_
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
    sa = silhouette([0.1, 0.1, 0.05], Xa, top_down())
    sb = silhouette([0.3, 0.2, 0.05], Xb, top_down())
    assert near_equal(L.amodal[1], sb, 2)
    assert not np.any(sa & ~sb)  # A lies inside B in the image
    # Analytic covered fraction: A's silhouette over B's (both boxes straddle the optical axis,
    # so the silhouettes are the projected top faces); the rasteriser may round edge pixels of A
    # differently, so allow one pixel along A's perimeter.
    covered = sa.sum() / sb.sum()
    w, h = box_of(sa)[2:]
    tol = 2 * (w + h) / sb.sum()
    assert L.occlusion[1] == pytest.approx(covered, abs=tol)
    # The continuous areas of the projected rectangles agree within the same rounding.
    area_a = (200 * 0.1 / 0.9) ** 2
    area_b = (200 * 0.3 / 0.95) * (200 * 0.2 / 0.95)
    assert L.occlusion[1] == pytest.approx(area_a / area_b, abs=2 * tol)
    assert L.occlusion[0] == pytest.approx(0.0, abs=1e-2)
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
    assert L.com_points.shape == (0, 4)
    assert L.com_visible.shape == (0,)
    assert L.com_heatmap.dtype == np.float32
    assert 0.0 <= L.com_heatmap.min()
    assert L.com_heatmap.max() <= 1.0
    assert np.all(L.com_heatmap[L.visible == 0] == 0)


@pytest.fixture(scope="module")
def library_scene() -> Scene:
    """Library objects standing in the tote, one of them hidden in part by a tote wall."""
    tote = ToteSpec()
    names = ["mug", "box_cereal", "pear", "can_soda", "bottle_clear"]
    spots = [
        (-0.08, -0.05, 0.3),
        (0.06, 0.04, 1.0),
        (-0.1, 0.08, 0.0),
        (0.1, -0.08, 2.0),
        (0.0, 0.02, 0.7),
    ]
    inst = []
    for k, (name, (x, y, yaw)) in enumerate(zip(names, spots, strict=True)):
        spec = get_object(name)
        mesh = spec.to_mesh()
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
    full = r.render(view, rgb=False, depth=True)
    ids = full.instance_ids
    L = view_object_labels(library_model, view, ids)
    assert L.num_objects == 5
    origins, directions = view.rays()
    for i in range(5):
        # Brute force: every pixel's centre ray against the object alone (no box, no hull).
        hit = mgn.RayScene(scene.mesh(i), scene.instances[i].X_WO).occluded(origins, directions)
        np.testing.assert_array_equal(L.amodal[i], hit.reshape(200, 200) | (ids == i + 1))
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
        np.testing.assert_array_equal(L.bbox_loose[i], box_of(L.amodal[i]))
        if vis.any():
            np.testing.assert_array_equal(L.bbox_tight[i], box_of(vis))
        else:
            np.testing.assert_array_equal(L.bbox_tight[i], [0, 0, 0, 0])
    # Semantic keypoints and CoM points: all of them, split by visibility.
    n_kp = sum(len(library_scene.object_spec(i).keypoints) for i in range(5))
    assert len(L.keypoints) + len(L.occluded_keypoints) == n_kp
    assert L.com_points.shape == (5000, 4)
    np.testing.assert_array_equal(L.com_object, np.repeat(np.arange(5), 1000))
    # CoM point visibility, first by brute force in Python: one ray per point through a RayScene
    # of every object and the tote, seen when the first hit is the point's own object within
    # 2 mm of the point.
    p_C = L.com_points[:, 1:]
    X_WC = view.X_WC
    p_W = p_C @ X_WC[:3, :3].T + X_WC[:3, 3]
    rays = p_W - X_WC[:3, 3]
    dist = np.linalg.norm(rays, axis=1)
    everything = mgn.RayScene(
        [scene.mesh(i) for i in range(5)] + [tote_mesh(scene.tote)],
        np.stack([inst.X_WO for inst in scene.instances] + [np.eye(4)]),
        instance_ids=[1, 2, 3, 4, 5, 0],
    )
    origins = np.repeat(X_WC[None, :3, 3], len(p_W), axis=0).astype(np.float32)
    hits = everything.intersect(origins, (rays / dist[:, None]).astype(np.float32))
    first = hits.distance
    own = np.asarray(hits.instance_ids) == L.com_object + 1
    np.testing.assert_array_equal(L.com_visible, own & (np.abs(first - dist) <= 0.002))
    assert 0.1 < L.com_visible.mean() < 0.9
    # Second opinion from the rasteriser's depth buffer at 4x the resolution (same field of
    # view): a point is seen when the rendered z-depth at its pixel is its own z within 2.5 mm;
    # points on silhouettes and grazing surfaces may differ.
    K4 = Intrinsics(800, 800, 800.0, 800.0, 400.0, 400.0)
    r4 = Renderer(800, 800)
    r4.set_instances(
        [Instance(r4.add_mesh(m), X, i) for m, X, i in items]
        + [Instance(r4.add_mesh(tote_mesh(scene.tote)), np.eye(4), 0)]
    )
    depth4 = r4.render(CameraView(K4, X_WC), rgb=False, depth=True).depth
    z = np.where(p_C[:, 2] > 0, p_C[:, 2], 1.0)
    u = np.floor(800 * p_C[:, 0] / z + 400).astype(int)
    v = np.floor(800 * p_C[:, 1] / z + 400).astype(int)
    inside = (p_C[:, 2] > 0) & (u >= 0) & (u < 800) & (v >= 0) & (v < 800)
    assert not np.any(L.com_visible & ~inside)
    seen = inside & (np.abs(depth4[v.clip(0, 799), u.clip(0, 799)] - p_C[:, 2]) < 0.0025)
    assert (seen == L.com_visible)[inside].mean() > 0.95
    # Heat map against the rasteriser: back-project each visible pixel with the rendered depth,
    # score its distance to the object's CoM with the d_min / d_max of its CoM points.
    vv, uu = np.nonzero(ids > 0)
    zz = full.depth[vv, uu]
    q_C = np.column_stack([(uu + 0.5 - 100) / 200 * zz, (vv + 0.5 - 100) / 200 * zz, zz])
    expected = np.zeros(len(vv))
    for i in range(5):
        spec = scene.object_spec(i)
        com_O = mgn.mass_properties(scene.mesh(i), spec.density).center_of_mass
        com_C = L.X_CO[i][:3, :3] @ com_O + L.X_CO[i][:3, 3]
        d_pts = np.linalg.norm(p_C[L.com_object == i] - com_C, axis=1)
        sel = ids[vv, uu] == i + 1
        d = np.linalg.norm(q_C[sel] - com_C, axis=1)
        expected[sel] = np.clip((d_pts.max() - d) / (d_pts.max() - d_pts.min()), 0, 1)
    err = np.abs(L.com_heatmap[vv, uu] - expected)
    assert np.median(err) < 0.01
    assert np.mean(err < 0.05) > 0.95
    # Given the depth image, the heat map is that formula on the rendered surface (no rays).
    Ld = view_object_labels(library_model, view, ids, depth=full.depth)
    np.testing.assert_allclose(Ld.com_heatmap[vv, uu], expected, atol=1e-5)
    assert np.all(Ld.com_heatmap[ids == 0] == 0)
    for name in ("amodal", "occlusion", "bbox_loose", "com_visible", "keypoints"):
        np.testing.assert_array_equal(getattr(Ld, name), getattr(L, name), err_msg=name)
    assert L.com_heatmap.max() <= 1.0
    assert L.com_heatmap.min() >= 0.0
    assert np.all(L.com_heatmap[L.visible == 0] == 0)
    assert L.com_heatmap[L.visible > 0].mean() > 0.2


def test_com_parameters_predict_the_heat_map_to_the_bit(library_scene, library_model) -> None:
    """The dataset writer stores the heat map as its difference from a prediction made from
    SceneRayModel.com_parameters and the depth: against the C++ model's own heat map (given the
    same depth) the prediction matches nearly every pixel to the bit. The parameters are the
    centre of mass and the nearest / farthest CoM point, worked out here from the object specs."""
    scene = library_scene
    view = CameraView(K200, look_at([0.35, -0.45, 0.55], [0.0, 0.0, 0.05]))
    r = Renderer(200, 200)
    items = [(scene.mesh(i), inst.X_WO, inst.instance_id) for i, inst in enumerate(scene.instances)]
    r.set_instances(
        [Instance(r.add_mesh(m), X, i) for m, X, i in items]
        + [Instance(r.add_mesh(tote_mesh(scene.tote)), np.eye(4), 0)]
    )
    full = r.render(view, rgb=False, depth=True)
    ids = full.instance_ids
    L = view_object_labels(library_model, view, ids, depth=full.depth)
    params = library_model.com_parameters()
    for i, inst in enumerate(scene.instances):
        spec = scene.object_spec(i)
        com_O = mgn.mass_properties(scene.mesh(i), spec.density).center_of_mass
        c_W = inst.X_WO[:3, :3] @ com_O + inst.X_WO[:3, 3]
        np.testing.assert_allclose(params[i, :3], c_W, atol=1e-12)
        cp = com_keypoints(scene.mesh(i), spec.density, seed=spec.category_id)
        d = np.linalg.norm(cp[:, 1:4] @ inst.X_WO[:3, :3].T + inst.X_WO[:3, 3] - c_W, axis=1)
        np.testing.assert_allclose(params[i, 3:], [d.min(), d.max()], atol=1e-12)
    assert np.all(params[:, 3] < params[:, 4])
    K = view.K
    pred = com_heatmap_prediction(full.depth, ids, view.X_WC, [K.fx, K.fy, K.cx, K.cy], params)
    seen = ids > 0
    assert np.array_equal(pred[~seen], L.com_heatmap[~seen])
    same = pred[seen].view(np.uint32) == L.com_heatmap[seen].view(np.uint32)
    assert same.mean() > 0.99
    np.testing.assert_allclose(pred, L.com_heatmap, atol=1e-6)


def test_tote_wall_counts_as_an_occluder(library_scene, library_model) -> None:
    # A low camera outside the tote: the near wall hides the lower part of the objects.
    view = CameraView(K200, look_at([0.0, -0.9, 0.12], [0.0, 0.0, 0.05]))
    r = Renderer(200, 200)
    r.set_instances(
        [
            Instance(r.add_mesh(library_scene.mesh(i)), inst.X_WO, inst.instance_id)
            for i, inst in enumerate(library_scene.instances)
        ]
        + [Instance(r.add_mesh(tote_mesh(library_scene.tote)), np.eye(4), 0)]
    )
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
        [
            (library_scene.mesh(i), inst.X_WO, inst.instance_id)
            for i, inst in enumerate(library_scene.instances)
        ],
    )
    a = view_object_labels(library_model, view, ids, num_threads=1)
    b = view_object_labels(library_model, view, ids, num_threads=2)
    for name in ViewObjectLabels.__dataclass_fields__:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


def test_amodal_masks_are_exact_for_objects_cut_by_the_image_border(
    library_scene, library_model
) -> None:
    # Close to the objects: several run off the image; amodal = every pixel whose centre ray
    # hits the object alone (brute force over the whole image), plus its visible pixels.
    view = CameraView(K200, look_at([0.05, -0.12, 0.22], [0.0, 0.0, 0.03]))
    items = [
        (library_scene.mesh(i), inst.X_WO, inst.instance_id)
        for i, inst in enumerate(library_scene.instances)
    ]
    ids = render_ids(view, items)
    L = view_object_labels(library_model, view, ids)
    origins, directions = view.rays()
    cut = 0
    for i, (mesh, X, _) in enumerate(items):
        hit = mgn.RayScene(mesh, X).occluded(origins, directions).reshape(200, 200)
        np.testing.assert_array_equal(L.amodal[i], hit | (ids == i + 1))
        m = L.amodal[i]
        cut += bool(m[0].any() or m[-1].any() or m[:, 0].any() or m[:, -1].any())
    assert cut >= 2


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
    with pytest.raises(InvalidArgumentError, match="depth has shape"):
        view_object_labels(
            library_model, view, np.zeros((200, 200), np.int32), depth=np.zeros((200, 100))
        )
    with pytest.raises(ValueError, match="no objects"):
        SceneRayModel([], np.zeros((0, 4, 4)), [])
    with pytest.raises(ValueError, match="no objects"):
        SceneRayModel.from_scene(Scene((), ToteSpec(), seed=0))
    with pytest.raises(ValueError, match="category id 0"):
        SceneRayModel([make_box([0.1, 0.1, 0.1])], np.eye(4)[None], [0])
    with pytest.raises(ValueError, match="expected one per mesh"):
        SceneRayModel([make_box([0.1, 0.1, 0.1])], np.eye(4)[None], [1], keypoints=[])
