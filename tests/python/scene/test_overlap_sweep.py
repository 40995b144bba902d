"""The fast paths of the separation pass's overlap tests give the results of their definitions.

Independent truth: the definitions themselves, run on every point (`meshes_overlap` at each
moved pose for `OverlapSweep`; the box-by-box selection of a pair's surface points over the
whole point set for the grid-pruned selection; a full scan for the grid queries; the overlaps
of `mesh_overlaps` for `deepest_overlap`; `clearance` without kept boxes)."""

from __future__ import annotations

import numpy as np
import pytest

import mgn
from mgn.errors import InvalidArgumentError
from mgn.geometry import Mesh
from mgn.objects import ToteSpec
from mgn.scene.penetration import (
    _BOX_SLACK,
    MeshCache,
    OverlapSweep,
    _PointGrid,
    _points_inside_box,
    clearance,
    deepest_overlap,
    edge_points,
    float_gaps,
    mesh_overlaps,
    meshes_overlap,
)


def _pose(rng: np.random.Generator, centre: np.ndarray) -> np.ndarray:
    """A random rotation (QR of a Gaussian matrix, det +1) about ``centre``."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q @ np.diag(np.sign(np.diag(r)))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    X = np.eye(4)
    X[:3, :3], X[:3, 3] = q, centre
    return X


def _two_boxes() -> Mesh:
    """One object made of two overlapping closed boxes (tested part by part)."""
    a, b = mgn.make_box([0.04, 0.02, 0.02]), mgn.make_box([0.02, 0.02, 0.04])
    va, vb = np.asarray(a.vertices), np.asarray(b.vertices) + [0.01, 0.0, 0.0]
    faces = np.concatenate([np.asarray(a.faces), np.asarray(b.faces) + len(va)])
    return Mesh(np.concatenate([va, vb]).astype(np.float32), faces.astype(np.int32))


MESHES = {
    "sphere": mgn.make_sphere(0.025, 32),
    "box": mgn.make_box([0.05, 0.03, 0.02]),
    "cylinder": mgn.make_cylinder(0.02, 0.06, 24),
    "two boxes": _two_boxes(),
}


@pytest.mark.parametrize(("first", "second"), [("box", "sphere"), ("cylinder", "two boxes")])
def test_a_sweep_answers_as_meshes_overlap_at_every_distance(first, second):
    """Two meshes in random orientations, one moved along a random line through contact:
    `OverlapSweep.overlap(t, spacing)` equals `meshes_overlap` at the moved pose for 40
    distances in a random order (forwards, backwards, beyond the stretch of the first block),
    at both spacings of the pass; both answers occur."""
    rng = np.random.default_rng(11)
    mesh, other = MESHES[first], MESHES[second]
    answers = set()
    for _ in range(3):
        X = _pose(rng, np.array([0.0, 0.0, 0.05]))
        Y = _pose(rng, np.array([0.03, 0.0, 0.05]) + rng.uniform(-0.005, 0.005, 3))
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        cache = MeshCache()
        sweep = OverlapSweep(mesh, X, other, Y, direction, cache)
        for t in rng.uniform(-0.01, 0.04, 40):
            for spacing in (1e-3, 2e-4):
                moved = X.copy()
                moved[:3, 3] += t * direction
                want = meshes_overlap(mesh, moved, other, Y, spacing, MeshCache())
                assert sweep.overlap(float(t), spacing) == want, (t, spacing)
                answers.add(want)
    assert answers == {True, False}


def _selection_by_definition(
    mesh_a: Mesh, Xa: np.ndarray, mesh_b: Mesh, Xb: np.ndarray, spacing: float
) -> np.ndarray:
    """The surface points of a in b's world box, in b's frame, in b's local box: every point
    of a tested box by box (the steps `_points_inside_box` defines)."""
    wb = np.asarray(mesh_b.vertices, np.float64) @ Xb[:3, :3].T + Xb[:3, 3]
    lo_b, hi_b = wb.min(axis=0), wb.max(axis=0)
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    corners = lo_b + corners * (hi_b - lo_b)
    in_a = (corners - Xa[:3, 3]) @ Xa[:3, :3]
    a_lo, a_hi = in_a.min(axis=0) - _BOX_SLACK, in_a.max(axis=0) + _BOX_SLACK
    pa = edge_points(mesh_a, spacing)
    pa = pa[np.all((pa >= a_lo) & (pa <= a_hi), axis=1)]
    pa = pa @ Xa[:3, :3].T + Xa[:3, 3]
    pa = pa[np.all((pa >= lo_b) & (pa <= hi_b), axis=1)]
    pa = (pa - Xb[:3, 3]) @ Xb[:3, :3]
    vb = np.asarray(mesh_b.vertices, np.float64)
    return pa[np.all((pa >= vb.min(axis=0)) & (pa <= vb.max(axis=0)), axis=1)]


def test_the_pruned_selection_of_a_pair_is_the_definition_bit_for_bit():
    """`_points_inside_box` (grid cells pruned by their rotated image) returns the same points,
    bit for bit and in the same order, as the definition run on every point, for random
    poses of a large and of a tiny second mesh (selections of none, one and several
    points occur)."""
    rng = np.random.default_rng(5)
    big, tiny = MESHES["cylinder"], mgn.make_box([0.0012, 0.0012, 0.0012])
    surface = edge_points(big, 1e-3)
    cache = MeshCache()
    counts = []
    for i in range(120):
        Xa = _pose(rng, np.array([0.0, 0.0, 0.05]))
        if i % 2:
            other, Xb = MESHES["box"], _pose(rng, Xa[:3, 3] + rng.uniform(-0.03, 0.03, 3))
        else:  # a tiny box at one of a's surface points: few points in its box
            at = Xa[:3, :3] @ surface[rng.integers(len(surface))] + Xa[:3, 3]
            other, Xb = tiny, _pose(rng, at + rng.uniform(-5e-4, 5e-4, 3))
        wb = np.asarray(other.vertices, np.float64) @ Xb[:3, :3].T + Xb[:3, 3]
        got = _points_inside_box(cache, big, Xa, other, Xb, wb.min(axis=0), wb.max(axis=0), 1e-3)
        want = _selection_by_definition(big, Xa, other, Xb, 1e-3)
        np.testing.assert_array_equal(got, want)
        counts.append(len(want))
    assert {0, 1} <= set(counts)
    assert max(counts) > 50


def test_rotated_cell_candidates_hold_every_point_in_both_boxes():
    """`_PointGrid.candidates_rotated` returns a superset of the points inside the box whose
    rotated image lies inside the second box (full scan), and fewer than the box alone when
    the second box is small."""
    rng = np.random.default_rng(3)
    points = edge_points(MESHES["two boxes"], 5e-4)
    grid = _PointGrid(points)
    pruned = []
    for _ in range(100):
        R = _pose(rng, np.zeros(3))[:3, :3]
        a, b = rng.uniform(-0.03, 0.03, (2, 3))
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        c = rng.uniform(-0.03, 0.03, 3)
        rlo, rhi = c - rng.uniform(0, 0.01, 3), c + rng.uniform(0, 0.01, 3)
        rotated = points @ R.T
        want = np.flatnonzero(
            np.all((points >= lo) & (points <= hi), axis=1)
            & np.all((rotated >= rlo) & (rotated <= rhi), axis=1)
        )
        got = grid.candidates_rotated(lo, hi, R, rlo, rhi)
        assert len(np.unique(got)) == len(got)
        assert set(want) <= set(got)
        pruned.append(len(got) < len(grid.candidates(lo, hi)))
    assert any(pruned)


def test_indices_in_box_are_ascending_and_give_points_in_box():
    """`MeshCache.indices_in_box` lists, ascending, exactly the points a full scan keeps."""
    mesh = MESHES["sphere"]
    cache = MeshCache()
    points = edge_points(mesh, 1e-3)
    rng = np.random.default_rng(9)
    for _ in range(100):
        a, b = rng.uniform(-0.03, 0.03, (2, 3))
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        want = np.flatnonzero(np.all((points >= lo) & (points <= hi), axis=1))
        np.testing.assert_array_equal(cache.indices_in_box(mesh, 1e-3, lo, hi), want)
        np.testing.assert_array_equal(cache.points_in_box(mesh, 1e-3, lo, hi), points[want])


def test_deepest_overlap_is_the_largest_depth_of_mesh_overlaps():
    """`deepest_overlap` (depths only) equals the largest depth of `mesh_overlaps` (with exits),
    0 without overlaps, for every `involving` index."""
    ball, box = MESHES["sphere"], MESHES["box"]
    meshes = [ball, box, ball]
    poses = [np.eye(4) for _ in meshes]
    for k, x in enumerate((0.0, 0.035, 0.07)):
        poses[k][:3, 3] = (x, 0.0, 0.03)
    for involving in (None, 0, 1, 2):
        found = mesh_overlaps(meshes, poses, 0.0, 1e-3, False, involving=involving)
        want = max([0.0] + [o.depth for o in found])
        assert deepest_overlap(meshes, poses, 1e-3, False, involving=involving) == want
    assert want > 0
    apart = [poses[0], poses[0] + np.pad(np.array([[0.2]]), ((0, 3), (3, 0)))[:4, :4]]
    assert deepest_overlap([ball, ball], apart, 1e-3, False) == 0.0
    with pytest.raises(InvalidArgumentError, match="deepest_overlap: involving"):
        deepest_overlap(meshes, poses, involving=3)
    with pytest.raises(InvalidArgumentError, match="deepest_overlap: 3 meshes but 2 poses"):
        deepest_overlap(meshes, poses[:2])


def test_clearance_with_kept_boxes_equals_a_fresh_one():
    """`clearance` with world boxes kept across calls (moving poses) equals one without."""
    tote = ToteSpec()
    ball, box = MESHES["sphere"], MESHES["box"]
    meshes = [ball, box, ball]
    boxes: dict = {}
    models: dict = {}
    for z in (0.03, 0.031, 0.04, 0.03):
        poses = [np.eye(4) for _ in meshes]
        for k, x in enumerate((0.0, 0.06, -0.06)):
            poses[k][:3, 3] = (x, 0.0, z + 0.005 * k)
        for k in range(len(meshes)):
            assert clearance(meshes, poses, tote, k, models, boxes) == clearance(
                meshes, poses, tote, k
            )
        assert float_gaps(meshes, poses, tote).max() > 0


def test_a_pruned_selection_of_one_point_is_formed_as_the_definition_forms_it():
    """A one-row matrix product rounds differently from the same row of a larger one, so where
    the pruned selection holds one point but the definition's first step holds several, the
    result must still be the definition's bit for bit. A 4 cm rod in random orientations
    across the edges of a 16 cm box, surface points 8 mm apart (few points per box, many
    cells pruned): 2000 placements equal the definition."""
    rng = np.random.default_rng(1)
    big, rod = mgn.make_box([0.16, 0.16, 0.16]), mgn.make_box([0.04, 0.001, 0.001])
    spacing = 8e-3
    surface = edge_points(big, spacing)
    cache = MeshCache()
    counts = []
    for _ in range(2000):
        Xa = _pose(rng, np.zeros(3))
        at = Xa[:3, :3] @ surface[rng.integers(len(surface))] + Xa[:3, 3]
        Xb = _pose(rng, at + rng.uniform(-0.004, 0.004, 3))
        wb = np.asarray(rod.vertices, np.float64) @ Xb[:3, :3].T + Xb[:3, 3]
        got = _points_inside_box(cache, big, Xa, rod, Xb, wb.min(axis=0), wb.max(axis=0), spacing)
        want = _selection_by_definition(big, Xa, rod, Xb, spacing)
        np.testing.assert_array_equal(got, want)
        counts.append(len(want))
    assert counts.count(1) > 20
