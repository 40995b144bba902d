"""Keypoint and CoM-point visibility of view_object_labels against a brute-force ray cast: one
first-hit ray per point through the whole scene (RayScene.intersect, tnear 0, tfar +inf) and the
visibility rule of docs/models.md §7 applied to that hit in NumPy."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import translation

from mgn.geometry.raytrace import RayScene
from mgn.objects import ToteSpec, com_keypoints, get_object, tote_mesh
from mgn.render import Instance, Renderer
from mgn.scene import BUILTIN, Scene, SceneInstance
from mgn.scene.cameras import CameraView, Intrinsics, look_at
from mgn.view_labels.objects import SceneRayModel, view_object_labels

K = Intrinsics(160, 120, 150.0, 150.0, 80.0, 60.0)


@pytest.fixture(scope="module")
def scene() -> Scene:
    """Library objects in the tote, close enough that they hide one another's points."""
    names = ["mug", "box_cereal", "pear", "can_soda", "bottle_clear", "tennis_ball"]
    spots = [
        (-0.06, -0.04, 0.3),
        (0.05, 0.03, 1.0),
        (-0.08, 0.07, 0.0),
        (0.08, -0.07, 2.0),
        (0.0, 0.0, 0.7),
        (-0.02, 0.09, 0.4),
    ]
    inst = []
    for k, (name, (x, y, yaw)) in enumerate(zip(names, spots, strict=True)):
        spec = get_object(name)
        X = translation(x, y, -float(np.asarray(spec.to_mesh().bounds)[0, 2]))
        c, s = math.cos(yaw), math.sin(yaw)
        X[:2, :2] = [[c, -s], [s, c]]
        inst.append(SceneInstance(k + 1, name, spec.category_id, BUILTIN, X))
    return Scene(tuple(inst), ToteSpec(), seed=0)


def brute_force(scene: Scene, view: CameraView, tolerance: float) -> tuple[list, list]:
    """Per object: (semantic keypoints visible, CoM points visible), each a bool array in the
    objects' point order, from one first-hit ray per point through objects and tote."""
    meshes = [scene.mesh(i) for i in range(len(scene.instances))]
    rays = RayScene(
        [*meshes, tote_mesh(scene.tote)],
        np.concatenate([scene.poses, np.eye(4)[None]]),
        [*range(1, len(meshes) + 1), 0],
    )
    X_CW = np.linalg.inv(view.X_WC)
    centre = view.X_WC[:3, 3]
    tol2 = np.float32(2.0) * np.float32(tolerance)
    out_kp, out_com = [], []
    for i, inst in enumerate(scene.instances):
        spec = scene.object_spec(i)
        kp = np.array([k.position for k in spec.keypoints], np.float64).reshape(-1, 3)
        com = com_keypoints(meshes[i], spec.density, seed=spec.category_id)[:, 1:]
        R, t = inst.X_WO[:3, :3], inst.X_WO[:3, 3]
        result = []
        for p_O in (kp, com):
            p_W = p_O @ R.T + t
            p_C = p_W @ X_CW[:3, :3].T + X_CW[:3, 3]
            z = p_C[:, 2]
            with np.errstate(divide="ignore", invalid="ignore"):
                u = K.fx * p_C[:, 0] / z + K.cx
                v = K.fy * p_C[:, 1] / z + K.cy
            cand = (z > 1e-9) & (u >= 0) & (u < K.width) & (v >= 0) & (v < K.height)
            seen = np.zeros(len(p_W), bool)
            k = np.nonzero(cand)[0]
            d = p_W[k] - centre
            dist = np.linalg.norm(d, axis=1)
            # One unbounded first-hit ray per point (each ray's hit is its own; one batch).
            hit = rays.intersect(
                np.tile(centre.astype(np.float32), (len(k), 1)),
                (d / dist[:, None]).astype(np.float32),
                num_threads=1,
            )
            lo = np.maximum(dist - tolerance, 0.0).astype(np.float32)
            h = np.asarray(hit.distance, np.float32)
            seen[k] = (
                np.isfinite(h)
                & (h >= lo)
                & (h <= lo + tol2)
                & (np.asarray(hit.instance_ids) == i + 1)
            )
            result.append(seen)
        out_kp.append(result[0])
        out_com.append(result[1])
    return out_kp, out_com


VIEWS = [
    look_at([0.3, -0.4, 0.55], [0.0, 0.0, 0.05]),  # oblique, objects hide one another
    look_at([0.0, -0.9, 0.12], [0.0, 0.0, 0.05]),  # low: the tote wall hides the lower parts
    look_at([0.02, 0.01, 0.9], [0.0, 0.0, 0.0]),  # from above
    look_at([-0.12, 0.05, 0.2], [0.0, 0.0, 0.05]),  # close: points nearer than a large tolerance
]


@pytest.mark.parametrize("tolerance", [0.0005, 0.002, 0.02, 0.5])
@pytest.mark.parametrize("view_index", range(len(VIEWS)))
def test_visibility_equals_one_first_hit_ray_per_point(scene, view_index, tolerance) -> None:
    view = CameraView(K, VIEWS[view_index])
    model = SceneRayModel.from_scene(scene)
    r = Renderer(K.width, K.height)
    r.set_instances(
        [
            Instance(r.add_mesh(scene.mesh(i)), inst.X_WO, inst.instance_id)
            for i, inst in enumerate(scene.instances)
        ]
        + [Instance(r.add_mesh(tote_mesh(scene.tote)), np.eye(4), 0)]
    )
    ids = r.render(view, rgb=False, depth=False).instance_ids
    L = view_object_labels(model, view, ids, keypoint_tolerance=tolerance, num_threads=1)
    kp_seen, com_seen = brute_force(scene, view, tolerance)
    expected_com = np.concatenate(com_seen)
    np.testing.assert_array_equal(L.com_visible, expected_com)
    n = len(scene.instances)
    vis_owner = np.concatenate([np.full(int(s.sum()), i) for i, s in enumerate(kp_seen)])
    occ_owner = np.concatenate([np.full(int((~s).sum()), i) for i, s in enumerate(kp_seen)])
    np.testing.assert_array_equal(L.keypoint_object, vis_owner)
    np.testing.assert_array_equal(L.occluded_keypoint_object, occ_owner)
    ids_all = [np.array([k.id for k in scene.object_spec(i).keypoints]) for i in range(n)]
    np.testing.assert_array_equal(
        L.keypoints[:, 0], np.concatenate([a[s] for a, s in zip(ids_all, kp_seen, strict=True)])
    )
    # The cases are not trivial: some points seen, some hidden.
    if tolerance < 0.5:
        assert 0 < expected_com.sum() < 0.8 * expected_com.size


def test_two_threads_give_the_same_visibility(scene) -> None:
    view = CameraView(K, VIEWS[0])
    model = SceneRayModel.from_scene(scene)
    ids = np.zeros((K.height, K.width), np.int32)
    a = view_object_labels(model, view, ids, num_threads=1)
    b = view_object_labels(model, view, ids, num_threads=2)
    np.testing.assert_array_equal(a.com_visible, b.com_visible)
    np.testing.assert_array_equal(a.keypoints, b.keypoints)
