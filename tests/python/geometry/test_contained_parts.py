"""Convex parts inside other parts: hull_distance and drop_contained_parts against analytic boxes
and spheres, and the shake shape that ShakeScorer simulates."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from conftest import random_rotation

import mgn
from mgn.errors import InvalidArgumentError
from mgn.geometry.convex import drop_contained_parts, hull_distance
from mgn.pj import physics

Mesh = mgn._core.geometry.Mesh
TOL = 1e-4  # m, the tolerance measured in docs/decisions/0048


def moved(mesh: Mesh, offset=(0.0, 0.0, 0.0), rotation: np.ndarray | None = None) -> Mesh:
    v = np.asarray(mesh.vertices, np.float64)
    if rotation is not None:
        v = v @ rotation.T
    v = v + np.asarray(offset, np.float64)
    return Mesh(v.astype(np.float32), np.asarray(mesh.faces), None, [], [], mesh.name)


def ids(parts) -> list[int]:
    return [id(p) for p in parts]


def box(half, center=(0.0, 0.0, 0.0)) -> Mesh:
    return moved(mgn.make_box([2 * h for h in half]), center)


def box_distance(points: np.ndarray, half, center=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Analytic distance from points to a solid axis-aligned box (0 inside)."""
    q = np.abs(np.asarray(points, np.float64) - center) - np.asarray(half, np.float64)
    return np.linalg.norm(np.maximum(q, 0.0), axis=1)


def test_hull_distance_of_a_box_is_the_analytic_distance(rng):
    half = (0.03, 0.02, 0.01)
    center = (0.1, -0.05, 0.02)
    near = rng.uniform(-0.08, 0.08, (400, 3))  # outside faces, edges and corners
    inside = rng.uniform(-0.99, 0.99, (50, 3)) * half
    points = np.concatenate([near, inside]) + center
    got = hull_distance(points, box(half, center))
    np.testing.assert_allclose(got, box_distance(points, half, center), atol=2e-8)
    assert np.all(got[len(near) :] == 0.0)


def test_hull_distance_of_a_rotated_box_and_a_sphere(rng):
    R = random_rotation(rng)
    half = (0.02, 0.03, 0.015)
    hull = moved(box(half), rotation=R)
    points = rng.uniform(-0.06, 0.06, (300, 3))
    np.testing.assert_allclose(
        hull_distance(points, hull), box_distance(points @ R, half), atol=2e-8
    )
    # A UV sphere (64 x 32): its polytope lies inside the sphere and contains the sphere of
    # radius r cos(pi / 64) cos(pi / 32) (> 0.994 r), so the distances differ by < 0.3 mm here
    # and the polytope's is never the smaller.
    r = 0.04
    d = hull_distance(points, mgn.make_sphere(r))
    truth = np.maximum(np.linalg.norm(points, axis=1) - r, 0.0)
    assert np.all(d >= truth - 1e-8)
    assert np.all(d <= truth + r * (1 - np.cos(np.pi / 64) * np.cos(np.pi / 32)) + 1e-8)


def test_contained_poking_out_and_identical_parts():
    big = box((0.03, 0.02, 0.01))
    inside = box((0.01, 0.01, 0.005), (0.015, 0.005, 0.0))
    # Pokes out of big's +x face by 3 tolerances, and by half a tolerance.
    out = box((0.01, 0.01, 0.005), (0.02 + 3 * TOL, 0.0, 0.0))
    barely = box((0.01, 0.01, 0.005), (0.02 + 0.5 * TOL, 0.0, 0.0))
    kept = drop_contained_parts([inside, big, out, barely], TOL)
    assert ids(kept) == ids([big, out])
    kept = drop_contained_parts([inside, big, out], 0.0)
    assert ids(kept) == ids([big, out])
    # Identical parts: the first stays, whatever the tolerance.
    twin = box((0.03, 0.02, 0.01))
    for tol in (0.0, TOL):
        kept = drop_contained_parts([big, twin], tol)
        assert ids(kept) == ids([big])
    # A sphere inside a box touching its faces, and one poking out by 2 tolerances (the UV
    # sphere's poles lie on the axes, at the radius).
    cube = box((0.02, 0.02, 0.02))
    kept = drop_contained_parts([cube, mgn.make_sphere(0.02)], TOL)
    assert ids(kept) == ids([cube])
    assert len(drop_contained_parts([cube, mgn.make_sphere(0.02 + 2 * TOL)], TOL)) == 2


def test_the_union_moves_by_at_most_the_tolerance(rng):
    """Random nested and overlapping boxes: every dropped part is within the tolerance of a kept
    one (analytic box distance), every kept part is one of the inputs, and a part that pokes out
    of every other by more than the tolerance is kept."""
    for _ in range(30):
        specs = []
        for _ in range(int(rng.integers(2, 7))):
            half = rng.uniform(0.002, 0.02, 3)
            center = rng.uniform(-0.01, 0.01, 3)
            specs.append((half, center))
            if rng.random() < 0.5:  # a part inside it, up to 2 tolerances out
                h2 = half * rng.uniform(0.2, 1.0, 3)
                c2 = center + (half - h2) * rng.uniform(-1, 1, 3) + rng.uniform(-2, 2, 3) * TOL
                specs.append((h2, c2))
        parts = [box(h, c) for h, c in specs]
        kept = drop_contained_parts(parts, TOL)
        ids = [next(k for k, p in enumerate(parts) if p is q) for q in kept]
        assert ids == sorted(ids)
        corners = [np.asarray(p.vertices, np.float64) for p in parts]
        for k in range(len(parts)):
            within = [np.max(box_distance(corners[k], *specs[j])) <= TOL + 1e-9 for j in ids]
            if k not in ids:
                assert any(within), k
        for k in ids:  # a kept part is not inside another kept part (tolerance with margin)
            assert not any(
                np.max(box_distance(corners[k], *specs[j])) <= TOL - 1e-9 for j in ids if j != k
            )


def test_bad_tolerance_and_points():
    big = box((0.03, 0.02, 0.01))
    for bad in (-1e-4, float("nan"), True, "0.1"):
        with pytest.raises(InvalidArgumentError, match="tolerance"):
            drop_contained_parts([big], bad)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match="points"):
        hull_distance(np.zeros((3, 2)), big)


def test_the_scorer_leaves_out_contained_parts_when_asked(monkeypatch):
    big = box((0.03, 0.02, 0.01))
    inside = box((0.01, 0.01, 0.005))
    other = box((0.01, 0.01, 0.005), (0.05, 0.0, 0.0))
    monkeypatch.setattr(physics, "cached_convex_decomposition", lambda mesh: [inside, big, other])
    seen = []

    def fake(parts, mass, com, inertia, rows, gripper, options):
        seen.append(list(parts))
        n = len(rows)
        return SimpleNamespace(score=np.ones(n), num_trials=n, trial_success=np.ones((n, 5, 5)))

    monkeypatch.setattr(physics, "shake_scores", fake)
    n = 3

    class Labels(SimpleNamespace):
        def __len__(self) -> int:
            return n

    labels = Labels(
        approach=np.tile([0.0, 0.0, -1.0], (n, 1)),
        closing=np.tile([1.0, 0.0, 0.0], (n, 1)),
        p1=np.zeros((n, 3)),
        width=np.full(n, 0.05),
    )
    mesh = mgn.make_box([0.06, 0.04, 0.02])
    physics.ShakeScorer(progress=False, calibration_grasps=0)(mesh, labels)
    assert seen
    assert all(ids(p) == ids([inside, big, other]) for p in seen)  # off by default
    for tol in (0.0, TOL):  # exactly inside
        seen.clear()
        physics.ShakeScorer(progress=False, calibration_grasps=0, contained_part_tolerance=tol)(
            mesh, labels
        )
        assert seen
        assert all(ids(p) == ids([big, other]) for p in seen)
    with pytest.raises(InvalidArgumentError, match=r"ShakeScorer\.contained_part_tolerance"):
        physics.ShakeScorer(contained_part_tolerance=-1.0)(mesh, labels)
