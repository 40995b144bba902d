"""The drop's final separation pass: render meshes of resting objects that sink into each other
are pulled apart, and what floats afterwards is lowered onto what holds it.

Independent truth: the exact render-mesh measures (`render_penetration`, checked against brute
force and analytic cases in test_scene_drop.py; `float_gaps`, analytic there) and analytic
positions of boxes and spheres."""

from __future__ import annotations

import numpy as np
import pytest

import mgn
from mgn.errors import InvalidArgumentError
from mgn.objects import ToteSpec
from mgn.scene.drop import SEPARATION_THRESHOLD, separate_overlaps
from mgn.scene.penetration import (
    MeshCache,
    edge_points,
    float_gaps,
    mesh_overlaps,
    meshes_overlap,
    render_penetration,
)

TOTE = ToteSpec()


@pytest.fixture(autouse=True, scope="module")
def _cache(tmp_path_factory):
    """Decompositions are cached in a folder of this test module, never in the user's home."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MGN_CACHE_DIR", str(tmp_path_factory.mktemp("mgn_cache")))
        yield


def _at(x: float, y: float, z: float) -> np.ndarray:
    X = np.eye(4)
    X[:3, 3] = (x, y, z)
    return X


def test_overlap_of_two_spheres_has_its_depth_and_way_out():
    """Analytic: spheres of radius r whose centres lie 2r - d apart on x overlap by d; the
    deepest point of one inside the other lies d below the other's surface, and its way out
    points along the line of centres (up to the tessellation's chord error, r (1 - cos(pi/32))
    ~ 0.14 mm)."""
    r, d = 0.03, 0.003
    ball = mgn.make_sphere(r, 64, 32)
    X1, X2 = _at(-(r - d / 2), 0.0, 0.05), _at(r - d / 2, 0.0, 0.05)
    found = mesh_overlaps([ball, ball], [X1, X2])
    assert [(o.a, o.b) for o in found] == [(0, 1), (1, 0)]
    for o in found:
        assert o.depth == pytest.approx(d, abs=2e-4)
        way = o.exit - o.point
        assert np.linalg.norm(way) == pytest.approx(o.depth, rel=1e-9)
        # a's point leaves b away from b's centre: towards a's side.
        assert np.sign(way[0]) == (-1.0 if o.a == 0 else 1.0)
        assert abs(way[0]) / np.linalg.norm(way) > 0.99
    assert mesh_overlaps([ball, ball], [X1, X2], above=d + 3e-4) == []
    assert meshes_overlap(ball, X1, ball, X2)
    assert not meshes_overlap(ball, X1, ball, _at(X1[0, 3] + 2 * r + 1e-3, 0.0, 0.05))


def test_a_box_sunk_into_a_can_beside_it_is_pulled_out_and_rests_on_the_floor():
    """A 40 mm box on the floor sunk 3 mm into the side of a can standing on the floor: after
    the pass they overlap by < 1 mm, both still touch the floor (float gap < 1 mm), neither
    enters the tote, and the box moved out sideways by about the overlap."""
    box = mgn.make_box((0.04, 0.04, 0.04))
    can = mgn.make_cylinder(0.03, 0.1, 48)
    X_can = _at(0.0, 0.0, 0.05)  # centred: base on the floor
    X_box = _at(0.03 + 0.02 - 0.003, 0.0, 0.02)  # 3 mm into the can's side
    meshes, poses = [can, box], [X_can, X_box]
    assert render_penetration(meshes, poses, TOTE) == pytest.approx(0.003, abs=2e-4)
    out, rounds = separate_overlaps(meshes, poses, TOTE)
    assert rounds >= 1
    assert render_penetration(meshes, list(out), TOTE) < 1e-3
    assert float_gaps(meshes, list(out), TOTE).max() < 1e-3
    moved = [np.linalg.norm(out[k, :3, 3] - poses[k][:3, 3]) for k in range(2)]
    assert 0.002 < max(moved) < 0.006
    for k in range(2):  # turned by nothing
        np.testing.assert_array_equal(out[k, :3, :3], poses[k][:3, :3])


def test_a_stack_sunk_into_itself_is_lifted_layer_by_layer_and_still_rests():
    """Three 40 mm boxes stacked on the floor: the middle one sunk 3 mm into the bottom one, the
    top one resting on the middle one. After the pass no pair overlaps by 1 mm (the middle box
    lifted ~3 mm, then the top box out of it) and every box still rests on the one below (gap
    < 1 mm); the bottom box stays on the floor."""
    box = mgn.make_box((0.04, 0.04, 0.04))
    poses = [_at(0.0, 0.0, 0.02), _at(0.0, 0.0, 0.06 - 0.003), _at(0.0, 0.0, 0.1 - 0.003)]
    meshes = [box, box, box]
    assert render_penetration(meshes, poses, TOTE) == pytest.approx(0.003, abs=1e-6)
    out, _ = separate_overlaps(meshes, poses, TOTE)
    assert render_penetration(meshes, list(out), TOTE) < 1e-3
    assert float_gaps(meshes, list(out), TOTE).max() < 1e-3
    z = out[:, 2, 3]
    assert z[0] == pytest.approx(0.02, abs=1e-9)
    assert 0.06 - 1e-3 < z[1] < 0.06 + 1e-3  # lifted out of the bottom box
    assert 0.1 - 1e-3 < z[2] < 0.1 + 1e-3  # resting on the middle box again


def test_the_pass_is_deterministic_and_leaves_a_clean_pile_alone():
    """Same input, same poses bit for bit; poses whose meshes overlap by less than the
    threshold (a sphere resting on a box, 0.1 mm in) come back unchanged, in zero rounds."""
    box = mgn.make_box((0.04, 0.04, 0.04))
    can = mgn.make_cylinder(0.03, 0.1, 48)
    poses = [_at(0.0, 0.0, 0.05), _at(0.047, 0.0, 0.02), _at(0.047, 0.0, 0.0605)]
    meshes = [can, box, box]
    first, r1 = separate_overlaps(meshes, poses, TOTE)
    second, r2 = separate_overlaps(meshes, poses, TOTE)
    np.testing.assert_array_equal(first, second)
    assert r1 == r2 >= 1
    ball = mgn.make_sphere(0.02, 48, 24)
    clean = [_at(0.0, 0.0, 0.02), _at(0.0, 0.0, 0.06 - 1e-4)]
    assert 0 < render_penetration([box, ball], clean, TOTE) < SEPARATION_THRESHOLD
    out, rounds = separate_overlaps([box, ball], clean, TOTE)
    assert rounds == 0
    np.testing.assert_array_equal(out, np.array(clean))


def test_a_demo_scene_whose_meshes_interlocked_rests_without_overlap():
    """Scene 4 of the demo's composition (12 built-in objects, seed scene_seed(0, 4)): Bullet
    left a pear 3.02 mm inside a soda can (its hull contact reported 0.03 mm). After the drop
    the render meshes overlap by < 1 mm and nothing floats 1 mm."""
    from mgn.objects import builtin_objects
    from mgn.pipeline.seeds import scene_seed
    from mgn.scene import compose_objects, drop_scene

    seed = scene_seed(0, 4)
    objects = compose_objects(count=12, seed=seed, catalogue=builtin_objects())
    scene = drop_scene(objects, seed=seed)
    assert scene.stats["separation_rounds"] >= 1
    assert scene.stats["max_penetration"] < 1e-3
    assert scene.stats["max_float_gap"] < 1e-3
    meshes = [scene.mesh(k) for k in range(len(scene))]
    assert render_penetration(meshes, scene.poses, scene.tote) == scene.stats["max_penetration"]


def test_objects_sunk_into_the_floor_or_a_wall_are_moved_out_and_what_they_held_follows():
    """A 40 mm box 1.5 mm into the floor with a second box resting on it, and one pressed
    1.5 mm into the +x wall (analytic: the planes z = 0 and x = inner_length / 2): after the
    pass nothing sinks into the tote or each other by 1 mm, the boxes touch the floor and the
    wall (exact positions), and the box on top rests on the lifted one."""
    box = mgn.make_box((0.04, 0.04, 0.04))
    hx = 0.5 * TOTE.inner_length
    poses = [
        _at(0.0, 0.0, 0.02 - 0.0015),
        _at(0.0, 0.0, 0.06 - 0.0015),  # resting on the sunk box
        _at(hx - 0.02 + 0.0015, 0.0, 0.02),  # into the +x wall
    ]
    meshes = [box, box, box]
    assert render_penetration(meshes, poses, TOTE) == pytest.approx(0.0015, abs=1e-6)
    out, rounds = separate_overlaps(meshes, poses, TOTE)
    assert rounds >= 1
    assert render_penetration(meshes, list(out), TOTE) < 1e-3
    assert float_gaps(meshes, list(out), TOTE).max() < 1e-3
    assert out[0, 2, 3] == pytest.approx(0.02, abs=1e-9)  # on the floor
    assert out[2, 0, 3] == pytest.approx(hx - 0.02, abs=1e-9)  # against the wall
    assert 0.06 - 1e-3 < out[1, 2, 3] < 0.06 + 1e-3  # on the lifted box


def test_mesh_cache_box_query_equals_brute_force():
    """MeshCache.points_in_box (an x-sorted slab, then y and z) keeps exactly the surface
    points a full scan keeps, in the same order, for random boxes (some empty, some holding
    every point)."""
    mesh = mgn.make_box([0.05, 0.03, 0.02])
    cache = MeshCache()
    points = edge_points(mesh, 1e-3)
    rng = np.random.default_rng(7)
    sizes = []
    for _ in range(200):
        a, b = rng.uniform(-0.04, 0.04, (2, 3))
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        want = points[np.all((points >= lo) & (points <= hi), axis=1)]
        got = cache.points_in_box(mesh, 1e-3, lo, hi)
        np.testing.assert_array_equal(got, want)
        sizes.append(len(want))
    whole = cache.points_in_box(mesh, 1e-3, [-1, -1, -1], [1, 1, 1])
    np.testing.assert_array_equal(whole, points)
    assert min(sizes) == 0
    assert max(sizes) > 0


def test_a_shared_cache_changes_no_overlap():
    """The separation pass reuses one MeshCache over many calls on moving poses: every
    overlap found with the shared cache equals the one found with a fresh cache per call."""
    ball = mgn.make_sphere(0.03, 32)
    box = mgn.make_box([0.06, 0.04, 0.03])
    cache = MeshCache()
    for shift in (0.055, 0.05, 0.045, 0.07):
        poses = [_at(0, 0, 0.03), _at(shift, 0.0, 0.03), _at(0.0, shift, 0.03)]
        meshes = [ball, box, ball]
        fresh = mesh_overlaps(meshes, poses, exact=False)
        shared = mesh_overlaps(meshes, poses, exact=False, cache=cache)
        assert [(o.a, o.b, o.depth) for o in shared] == [(o.a, o.b, o.depth) for o in fresh]
        for o, p in zip(shared, fresh, strict=True):
            np.testing.assert_array_equal(o.point, p.point)
        for m, n in ((0, 1), (0, 2), (1, 2)):
            assert meshes_overlap(meshes[m], poses[m], meshes[n], poses[n], cache=cache) == (
                meshes_overlap(meshes[m], poses[m], meshes[n], poses[n])
            )


def test_overlaps_involving_one_mesh_are_those_of_every_pair_that_include_it():
    """``mesh_overlaps(..., involving=k)`` (the separation pass's test of one moved object)
    returns exactly the overlaps of the full search whose pair includes mesh k; a bad index
    names the setting."""
    ball = mgn.make_sphere(0.03, 32)
    box = mgn.make_box([0.06, 0.04, 0.03])
    meshes = [ball, box, ball, box]
    poses = [_at(0, 0, 0.03), _at(0.045, 0.0, 0.03), _at(0.0, 0.05, 0.03), _at(0.05, 0.05, 0.03)]
    every = mesh_overlaps(meshes, poses, exact=False)
    for k in range(len(meshes)):
        mine = mesh_overlaps(meshes, poses, exact=False, involving=k)
        want = [o for o in every if k in (o.a, o.b)]
        assert [(o.a, o.b, o.depth) for o in mine] == [(o.a, o.b, o.depth) for o in want]
    assert len({(o.a, o.b) for o in every}) > 2
    with pytest.raises(InvalidArgumentError, match="involving"):
        mesh_overlaps(meshes, poses, involving=4)
