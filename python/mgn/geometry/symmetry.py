"""Rotational symmetries of a mesh, found by comparing the mesh with itself rotated.

:func:`find_symmetries` tries rotations about candidate axes through the surface's centroid: the
principal axes of the surface and the model frame's x, y, z. A rotation is a symmetry when the
rotated surface lies on the surface: ``samples`` points spread over the surface (area-weighted,
fixed seed) are rotated, and for 80 % of them the distance to the tangent plane of the nearest
point of a second, independent sampling is at most ``tolerance`` × the mesh's diameter, and
their distance to that nearest point is not larger than the two samplings' own spacing (the
80th percentile of the nearest-point distances between the unrotated samplings, times 1.5).
An axis has a continuous symmetry when the rotations by 0.137, 0.291 and 0.419 turns all pass
(a polygonal revolution surface of 32 or more sides passes within the default tolerance); a
mesh with one continuous axis has at most one discrete symmetry, a half turn about an axis
perpendicular to it. Otherwise each axis has the discrete symmetries of the largest order n in
(8, 6, 5, 4, 3, 2) whose rotation by 1 / n turn passes, and the rotations found are closed
under composition.
Everything is in the mesh's units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError

__all__ = ["DEFAULT_SYMMETRY_TOLERANCE", "Symmetries", "find_symmetries", "rotation_about"]

#: Largest deviation of a symmetric surface from itself, as a fraction of the mesh's diameter.
DEFAULT_SYMMETRY_TOLERANCE = 0.005
_CONTINUOUS_TURNS = (0.137, 0.291, 0.419)
_PERCENTILE = 80.0
_SPACING_FACTOR = 1.5
_MAX_GROUP = 48
_SAME_AXIS_COS = float(np.cos(np.radians(5.0)))


@dataclass(frozen=True)
class Symmetries:
    """The symmetries of a mesh (mesh units).

    Attributes:
        discrete: (K, 4, 4) rigid transforms x -> R x + t that map the mesh onto itself, the
            identity excluded; with a continuous axis, only a flip (rotations about the axis
            are implied).
        continuous: (A, 3) unit axes of continuous rotational symmetry.
        center: (3,) the point every symmetry fixes (the surface's centroid); the continuous
            axes pass through it.
    """

    discrete: npt.NDArray[np.float64]
    continuous: npt.NDArray[np.float64]
    center: npt.NDArray[np.float64]


def rotation_about(axis: npt.ArrayLike, angle: float) -> npt.NDArray[np.float64]:
    """(3, 3) rotation by ``angle`` (rad) about the unit vector ``axis`` (right-hand rule)."""
    a = np.asarray(axis, np.float64).reshape(3)
    a = a / np.linalg.norm(a)
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    R: npt.NDArray[np.float64] = np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)
    return R


def _sample(
    tri: np.ndarray, normals: np.ndarray, cdf: np.ndarray, n: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    idx = np.minimum(np.searchsorted(cdf, rng.random(n) * cdf[-1], side="right"), len(cdf) - 1)
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    bary = np.stack([1.0 - s, s * (1.0 - r2), s * r2], axis=1)
    points = np.einsum("nk,nkd->nd", bary, tri[idx])
    return points, normals[idx]


def _nearest(query: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index of the nearest of ``points`` and the distance, per row of ``query`` (exact)."""
    idx = np.empty(len(query), np.int64)
    dist = np.empty(len(query))
    p2 = np.einsum("ij,ij->i", points, points)
    for i in range(0, len(query), 512):
        q = query[i : i + 512]
        d2 = p2[None, :] - 2.0 * (q @ points.T) + np.einsum("ij,ij->i", q, q)[:, None]
        j = np.argmin(d2, axis=1)
        idx[i : i + 512] = j
        dist[i : i + 512] = np.sqrt(np.maximum(d2[np.arange(len(q)), j], 0.0))
    return idx, dist


def find_symmetries(
    vertices: npt.ArrayLike,
    faces: npt.ArrayLike,
    *,
    tolerance: float = DEFAULT_SYMMETRY_TOLERANCE,
    samples: int = 1000,
    seed: int = 0,
) -> Symmetries:
    """The rotational symmetries of the triangle mesh (``vertices`` (V, 3), ``faces`` (F, 3)),
    as described in the module docstring. ``tolerance``: fraction of the diameter (> 0);
    ``samples``: surface points per sampling (≥ 100). Deterministic for a given ``seed``."""
    v = np.asarray(vertices, np.float64).reshape(-1, 3)
    f = np.asarray(faces, np.int64).reshape(-1, 3)
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise InvalidArgumentError(f"find_symmetries: tolerance must be > 0, got {tolerance}")
    if samples < 100:
        raise InvalidArgumentError(f"find_symmetries: samples must be >= 100, got {samples}")
    tri = v[f]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(cross, axis=1)
    if len(f) == 0 or area2.sum() <= 0:
        raise InvalidArgumentError("find_symmetries: the mesh has no surface area")
    ok = area2 > 0
    tri, cross, area2 = tri[ok], cross[ok], area2[ok]
    normals = cross / area2[:, None]
    cdf = np.cumsum(area2)
    rng = np.random.default_rng(seed)
    a_pts, _ = _sample(tri, normals, cdf, samples, rng)
    b_pts, b_nrm = _sample(tri, normals, cdf, samples, rng)
    center = (tri.mean(axis=1) * area2[:, None]).sum(axis=0) / area2.sum()
    diameter = float(np.linalg.norm(v.max(axis=0) - v.min(axis=0)))
    match = _SelfMatch(a_pts, b_pts, b_nrm, center, tolerance * diameter)
    axes = _candidate_axes(a_pts - center)
    continuous = [
        axis
        for axis in axes
        if all(match(rotation_about(axis, 2 * np.pi * t)) for t in _CONTINUOUS_TURNS)
    ]
    if continuous:
        # rotations about a continuous axis are implied; with one such axis, a half turn about
        # an axis perpendicular to it (a flip) is the only other kind
        group = _flip(match, axes, continuous[0]) if len(continuous) == 1 else []
    else:
        generators = []
        for axis in axes:
            n = _order(match, axis)
            if n > 1:
                generators.append(rotation_about(axis, 2 * np.pi / n))
        group = _closure(generators)
    discrete = np.zeros((len(group), 4, 4))
    for k, R in enumerate(group):
        discrete[k, :3, :3] = R
        discrete[k, :3, 3] = center - R @ center
        discrete[k, 3, 3] = 1.0
    return Symmetries(discrete, np.array(continuous).reshape(-1, 3), center)


class _SelfMatch:
    """Whether a rotation about ``center`` maps the sampled surface onto itself."""

    def __init__(
        self, a: np.ndarray, b: np.ndarray, b_normals: np.ndarray, center: np.ndarray, tol: float
    ) -> None:
        self.a, self.b, self.b_normals, self.center, self.tol = a, b, b_normals, center, tol
        _, base = _nearest(a, b)
        self.spacing = _SPACING_FACTOR * float(np.percentile(base, _PERCENTILE))

    def __call__(self, R: np.ndarray) -> bool:
        # a quarter of the points first: most candidate rotations fail there
        for pts in (self.a[: len(self.a) // 4], self.a):
            moved = (pts - self.center) @ R.T + self.center
            j, d = _nearest(moved, self.b)
            plane = np.abs(np.einsum("ij,ij->i", moved - self.b[j], self.b_normals[j]))
            if not (
                np.percentile(plane, _PERCENTILE) <= self.tol
                and np.percentile(d, _PERCENTILE) <= self.spacing
            ):
                return False
        return True


def _candidate_axes(centered: np.ndarray) -> list[np.ndarray]:
    """The frame axes x, y, z and the principal axes of the centred points; a principal axis
    within 5 degrees of one already listed is that axis (sampling noise)."""
    _, _, vt = np.linalg.svd(centered, full_matrices=False)
    axes: list[np.ndarray] = []
    for cand in [*np.eye(3), *vt]:
        cand = cand / np.linalg.norm(cand)
        if all(abs(float(cand @ a)) < _SAME_AXIS_COS for a in axes):
            axes.append(cand)
    return axes


def _order(match: _SelfMatch, axis: np.ndarray) -> int:
    """The largest n of (8, 6, 5, 4, 3, 2) whose 1 / n turn about ``axis`` passes, or 1 (an
    order-4 or -8 symmetry has an order-2 one, an order-6 one orders 2 and 3)."""

    def turn(n: int) -> bool:
        return match(rotation_about(axis, 2 * np.pi / n))

    two, three = turn(2), turn(3)
    if two and three and turn(6):
        return 6
    if two and turn(4):
        return 8 if turn(8) else 4
    if turn(5):
        return 5
    return 3 if three else 2 if two else 1


def _flip(match: _SelfMatch, axes: list[np.ndarray], c: np.ndarray) -> list[np.ndarray]:
    """[the first half turn about a candidate axis perpendicular to ``c`` that passes], or []."""
    for axis in axes:
        perp = axis - c * float(axis @ c)
        if np.linalg.norm(perp) < np.sin(np.radians(85.0)):
            continue
        R = rotation_about(perp, np.pi)
        if match(R):
            return [R]
    return []


def _closure(generators: list[np.ndarray]) -> list[np.ndarray]:
    """Every product of the generators, the identity excluded, in a fixed order."""
    group = [np.eye(3)]
    frontier = list(generators)
    while frontier and len(group) < _MAX_GROUP:
        R = frontier.pop(0)
        if any(np.allclose(R, G, atol=1e-9) for G in group):
            continue
        group.append(R)
        frontier.extend(R @ G for G in group)
        frontier.extend(G @ R for G in group)
    return group[1:]
