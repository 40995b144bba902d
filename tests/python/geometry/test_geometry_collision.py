"""CollisionModel against analytic answers for boxes and spheres."""

import numpy as np
import pytest
from conftest import random_rotation, translation

import mgn


def test_two_boxes_collide_and_distance_match_analytic():
    a = mgn.CollisionModel(mgn.make_box([0.1, 0.1, 0.1]))
    b = mgn.CollisionModel(mgn.make_box([0.2, 0.2, 0.2]))
    xs = np.array([0.1, 0.149, 0.151, 0.2, 0.5])
    poses = np.stack([translation(x, 0.01, -0.02) for x in xs])
    hit = mgn.collide(a, np.eye(4), b, poses)
    np.testing.assert_array_equal(hit, xs < 0.15)
    d = mgn.distance(a, np.eye(4), b, poses)
    np.testing.assert_allclose(d.distance, np.maximum(xs - 0.15, 0.0), atol=1e-7)
    np.testing.assert_array_equal(d.collide, xs < 0.15)
    sep = ~d.collide
    np.testing.assert_allclose(d.points_a[sep, 0], 0.05, atol=1e-7)
    np.testing.assert_allclose(d.points_b[sep, 0], xs[sep] - 0.1, atol=1e-7)
    assert mgn.collide(a, np.eye(4), b, translation(0.12)) is True


def test_two_spheres_distance_matches_analytic_under_rotation(rng):
    r1, r2 = 0.05, 0.02
    a = mgn.CollisionModel(mgn.make_sphere(r1, 256, 128))
    b = mgn.CollisionModel(mgn.make_sphere(r2, 256, 128))
    centres = rng.normal(size=(200, 3))
    centres /= np.linalg.norm(centres, axis=1, keepdims=True)
    centres *= rng.uniform(0.03, 0.15, size=(200, 1))
    poses = []
    for c in centres:
        X = translation(*c)
        X[:3, :3] = random_rotation(rng)
        poses.append(X)
    d = mgn.distance(a, np.eye(4), b, np.stack(poses))
    analytic = np.linalg.norm(centres, axis=1) - r1 - r2
    clear = np.abs(analytic) > 1e-3  # away from the tessellation band
    np.testing.assert_array_equal(d.collide[clear], analytic[clear] < 0)
    apart = clear & (analytic > 0)
    np.testing.assert_allclose(d.distance[apart], analytic[apart], atol=2e-4)
    # closest points lie on the two spheres
    np.testing.assert_allclose(np.linalg.norm(d.points_a[apart], axis=1), r1, atol=2e-4)


def test_batches_broadcast_and_match_single_queries(rng):
    a = mgn.CollisionModel(mgn.make_cylinder(0.03, 0.1, 32))
    b = mgn.CollisionModel(mgn.make_box([0.05, 0.08, 0.02]))
    poses = []
    for _ in range(300):
        X = translation(*rng.uniform(-0.1, 0.1, 3))
        X[:3, :3] = random_rotation(rng)
        poses.append(X)
    poses = np.stack(poses)
    batch = mgn.collide(a, np.eye(4), b, poses, num_threads=2)
    single = np.array([mgn.collide(a, np.eye(4), b, X) for X in poses])
    np.testing.assert_array_equal(batch, single)
    np.testing.assert_array_equal(batch, mgn.collide(a, np.eye(4), b, poses, num_threads=1))
    # swapping the roles gives the same answer (symmetry)
    swapped = mgn.collide(b, poses, a, np.eye(4))
    np.testing.assert_array_equal(batch, swapped)
    assert 10 < batch.sum() < 290
    with pytest.raises(mgn.InvalidArgumentError, match="equal counts"):
        mgn.collide(a, poses[:2], b, poses[:3])
