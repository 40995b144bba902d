"""Symmetries found from a mesh (``mgn.geometry.symmetry``) checked against the shapes' known
symmetry groups: every transform found maps the mesh onto itself (vertex for vertex, or onto
the analytic surface), and the groups have the known sizes."""

from __future__ import annotations

import numpy as np
import pytest

from mgn.errors import InvalidArgumentError
from mgn.geometry.symmetry import find_symmetries, rotation_about
from mgn.objects.shapes import grid_box, revolve


def _mm(mesh) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(mesh.vertices, np.float64) * 1000.0, np.asarray(mesh.faces, np.int64)


def _maps_vertices(T: np.ndarray, v: np.ndarray, tol: float) -> bool:
    """Every transformed vertex lands on a vertex (brute force)."""
    moved = v @ T[:3, :3].T + T[:3, 3]
    d = np.linalg.norm(moved[:, None, :] - v[None, :, :], axis=2).min(axis=1)
    return bool(d.max() <= tol)


def _is_half_turn_about(T: np.ndarray, axis: np.ndarray) -> bool:
    return bool(np.allclose(T[:3, :3], rotation_about(axis, np.pi), atol=1e-9))


def test_box_with_three_different_sides_has_the_three_half_turns() -> None:
    v, f = _mm(grid_box((0.2, 0.07, 0.28)))
    v = v + [5.0, -3.0, 2.0]  # off the origin: the transforms rotate about the box's centre
    s = find_symmetries(v, f)
    assert len(s.continuous) == 0
    assert s.center == pytest.approx([5.0, -3.0, 2.0], abs=1e-6)
    assert len(s.discrete) == 3
    for axis in np.eye(3):
        assert sum(_is_half_turn_about(T, axis) for T in s.discrete) == 1
    for T in s.discrete:
        assert T[3].tolist() == [0, 0, 0, 1]
        assert _maps_vertices(T, v, 1e-6)


def test_square_prism_and_cube_groups() -> None:
    v, f = _mm(grid_box((0.1, 0.1, 0.2)))
    s = find_symmetries(v, f)
    assert len(s.discrete) == 7  # the dihedral group of the square, less the identity
    assert all(_maps_vertices(T, v, 1e-6) for T in s.discrete)
    assert any(
        np.allclose(T[:3, :3], rotation_about([0, 0, 1], np.pi / 2), atol=1e-9) for T in s.discrete
    )
    v, f = _mm(grid_box((0.1, 0.1, 0.1)))
    s = find_symmetries(v, f)
    assert len(s.discrete) == 23  # the rotations of the cube, less the identity
    assert all(_maps_vertices(T, v, 1e-6) for T in s.discrete)


def test_cylinder_continuous_axis_and_one_flip() -> None:
    r, h = 0.033, 0.12
    mesh = revolve(np.array([[0, -h / 2], [r, -h / 2], [r, h / 2], [0, h / 2]]), 64)
    v, f = _mm(mesh)
    v = v + [0.0, 0.0, 40.0]
    s = find_symmetries(v, f)
    assert len(s.continuous) == 1
    assert abs(s.continuous[0] @ [0, 0, 1]) == pytest.approx(1.0, abs=1e-9)
    assert s.center == pytest.approx([0, 0, 40.0], abs=0.05)
    assert len(s.discrete) == 1  # the flip end for end
    T = s.discrete[0]
    assert T[:3, :3] @ [0, 0, 1] == pytest.approx([0, 0, -1], abs=1e-9)
    moved = v @ T[:3, :3].T + T[:3, 3]
    # on the analytic surface: |z - 40| <= h / 2, radius <= r (mm)
    assert np.abs(moved[:, 2] - 40.0).max() <= h * 500 + 0.1
    assert np.hypot(moved[:, 0], moved[:, 1]).max() <= r * 1000 + 1e-6


def test_cone_has_no_flip_and_a_scalene_tetrahedron_no_symmetry() -> None:
    v, f = _mm(revolve(np.array([[0, -0.06], [0.033, -0.06], [0.0, 0.06]]), 64))
    s = find_symmetries(v, f)
    assert len(s.continuous) == 1
    assert len(s.discrete) == 0
    tet = np.array([[0, 0, 0], [60, 0, 0], [10, 45, 0], [20, 15, 70]], np.float64)
    faces = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    s = find_symmetries(tet, faces)
    assert len(s.continuous) == 0
    assert len(s.discrete) == 0


def test_bad_input() -> None:
    v, f = _mm(grid_box((0.1, 0.1, 0.1)))
    with pytest.raises(InvalidArgumentError, match="tolerance"):
        find_symmetries(v, f, tolerance=0)
    with pytest.raises(InvalidArgumentError, match="surface area"):
        find_symmetries(np.zeros((3, 3)), [[0, 1, 2]])
