"""RayScene against a brute-force numpy ray/triangle test and analytic shapes."""

import numpy as np
import pytest
from conftest import random_rotation, translation

import mgn


def brute_force_all_hits(V, F, origins, dirs):
    """Möller–Trumbore for every (ray, triangle) pair: (N, F) distances, inf where no hit."""
    v0, v1, v2 = (V[F[:, k]].astype(np.float64) for k in range(3))
    e1, e2 = v1 - v0, v2 - v0
    d = dirs.astype(np.float64)[:, None, :]
    o = origins.astype(np.float64)[:, None, :]
    p = np.cross(d, e2[None])
    det = np.einsum("nfk,fk->nf", p, e1)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        s = o - v0[None]
        u = np.einsum("nfk,nfk->nf", s, p) * inv
        q = np.cross(s, e1[None])
        v = np.einsum("nfk,nk->nf", q, dirs.astype(np.float64)) * inv
        t = np.einsum("nfk,fk->nf", q, e2) * inv
    ok = (np.abs(det) > 1e-15) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    return np.where(ok, t, np.inf)


@pytest.fixture(scope="module")
def two_object_scene():
    rng = np.random.default_rng(7)
    a = mgn.make_sphere(0.06, 48, 24)
    b = mgn.make_cylinder(0.03, 0.12, 40)
    Xa = translation(-0.04, 0.01, 0.0)
    Xb = translation(0.05, -0.02, 0.03)
    Xb[:3, :3] = random_rotation(rng)
    V = np.concatenate([a.transformed(Xa).vertices, b.transformed(Xb).vertices])
    F = np.concatenate([a.faces, b.faces + a.num_vertices])
    inst = np.concatenate([np.full(a.num_faces, 10), np.full(b.num_faces, 20)])
    scene = mgn.RayScene([a, b], poses=np.stack([Xa, Xb]), instance_ids=[10, 20])
    return scene, V, F, inst


def random_rays(rng, n, radius=0.3, box=0.1):
    start = rng.normal(size=(n, 3))
    start = radius * start / np.linalg.norm(start, axis=1, keepdims=True)
    target = rng.uniform(-box, box, size=(n, 3))
    d = target - start
    return start.astype(np.float32), (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(
        np.float32
    )


def test_first_hits_agree_with_brute_force(two_object_scene, rng):
    scene, V, F, inst = two_object_scene
    o, d = random_rays(rng, 600)
    t = brute_force_all_hits(V, F, o, d)
    first = t.argmin(axis=1)
    t_min = t[np.arange(len(o)), first]
    hits = scene.intersect(o, d)
    expect_hit = np.isfinite(t_min)
    assert expect_hit.sum() > 150
    assert (~expect_hit).sum() > 50
    # Rays grazing an edge may legitimately differ by one ulp-decision; allow none here.
    np.testing.assert_array_equal(hits.hit, expect_hit)
    np.testing.assert_allclose(hits.distance[expect_hit], t_min[expect_hit], atol=1e-5)
    np.testing.assert_array_equal(hits.instance_ids[expect_hit], inst[first[expect_hit]])
    sphere_faces = int((inst == 10).sum())
    global_face = hits.face_ids + np.where(hits.instance_ids == 20, sphere_faces, 0)
    np.testing.assert_array_equal(global_face[expect_hit], first[expect_hit])
    np.testing.assert_allclose(
        hits.points[expect_hit], o[expect_hit] + t_min[expect_hit, None] * d[expect_hit], atol=1e-5
    )
    occluded = scene.occluded(o, d)
    np.testing.assert_array_equal(occluded, expect_hit)


def test_intersect_ids_agree_with_brute_force_and_intersect(two_object_scene, rng):
    scene, V, F, inst = two_object_scene
    o, d = random_rays(rng, 600)
    t = brute_force_all_hits(V, F, o, d)
    first = t.argmin(axis=1)
    expect_hit = np.isfinite(t[np.arange(len(o)), first])
    instance_ids, face_ids = scene.intersect_ids(o, d)
    assert instance_ids.dtype == np.int32
    assert face_ids.dtype == np.int32
    np.testing.assert_array_equal(instance_ids >= 0, expect_hit)
    np.testing.assert_array_equal(face_ids[~expect_hit], -1)
    np.testing.assert_array_equal(instance_ids[expect_hit], inst[first[expect_hit]])
    sphere_faces = int((inst == 10).sum())
    global_face = face_ids + np.where(instance_ids == 20, sphere_faces, 0)
    np.testing.assert_array_equal(global_face[expect_hit], first[expect_hit])
    # The same ids as intersect's, for single rays and packets, any number of threads.
    o, d = random_rays(rng, 20_011)
    full = scene.intersect(o, d, num_threads=1)
    for coherent in (False, True):
        for threads in (1, 2):
            ids = scene.intersect_ids(o, d, coherent=coherent, num_threads=threads)
            np.testing.assert_array_equal(ids[0], full.instance_ids)
            np.testing.assert_array_equal(ids[1], full.face_ids)
    with pytest.raises(mgn.errors.InvalidArgumentError, match="directions"):
        scene.intersect_ids(o, d[:-1])


def test_all_hits_agree_with_brute_force(two_object_scene, rng):
    scene, V, F, _ = two_object_scene
    o, d = random_rays(rng, 300)
    t = brute_force_all_hits(V, F, o, d)
    all_hits = scene.intersect_all(o, d)
    for i in range(len(o)):
        expect = np.sort(np.unique(np.round(t[i][np.isfinite(t[i])], 6)))
        got = all_hits.distance[all_hits.offsets[i] : all_hits.offsets[i + 1]]
        np.testing.assert_allclose(got, expect, atol=1e-5)
        assert np.all(all_hits.ray_ids[all_hits.offsets[i] : all_hits.offsets[i + 1]] == i)


def test_results_do_not_depend_on_threads_or_packets(two_object_scene, rng):
    scene, *_ = two_object_scene
    o, d = random_rays(rng, 50_003)
    one = scene.intersect(o, d, num_threads=1)
    two = scene.intersect(o, d, num_threads=2)
    packets = scene.intersect(o, d, num_threads=2, coherent=True)
    for field in ("distance", "points", "normals", "instance_ids", "face_ids", "barycentric"):
        np.testing.assert_array_equal(getattr(one, field), getattr(two, field))
    np.testing.assert_array_equal(one.face_ids, packets.face_ids)
    np.testing.assert_allclose(one.distance[one.hit], packets.distance[one.hit], atol=1e-6)
    a1 = scene.intersect_all(o[:5000], d[:5000], num_threads=1)
    a2 = scene.intersect_all(o[:5000], d[:5000], num_threads=2)
    np.testing.assert_array_equal(a1.offsets, a2.offsets)
    np.testing.assert_array_equal(a1.distance, a2.distance)


def test_normals_are_outward_unit_vectors_on_a_sphere(rng):
    scene = mgn.RayScene(mgn.make_sphere(0.1, 128, 64))
    o, d = random_rays(rng, 2000, box=0.05)
    h = scene.intersect(o, d)
    n = h.normals[h.hit]
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-5)
    radial = h.points[h.hit] / np.linalg.norm(h.points[h.hit], axis=1, keepdims=True)
    assert np.all(np.einsum("ij,ij->i", n, radial) > 0.99)
    assert np.all(np.einsum("ij,ij->i", n, d[h.hit]) < 0)  # rays hit the outside first


def test_camera_rays_see_a_box_at_the_right_depth():
    box = mgn.make_box([0.4, 0.3, 0.1])
    scene = mgn.RayScene([box], poses=translation(0, 0, 0.05)[None])
    K = np.array([[500.0, 0, 64], [0, 500.0, 48], [0, 0, 1]])
    X_WC = translation(0, 0, 1.0)
    X_WC[:3, :3] = np.diag([1.0, -1.0, -1.0])  # looking straight down
    o, d = mgn.camera_rays(K, 128, 96, X_WC)
    assert o.shape == (128 * 96, 3)
    h = scene.intersect(o, d, coherent=True)
    z_depth = h.distance * (d @ np.array([0, 0, -1.0], np.float32))
    assert h.hit.all()  # the 0.4 x 0.3 box fills this narrow view
    np.testing.assert_allclose(z_depth, 0.9, atol=1e-5)
