"""Height above the floor from a depth image: the input of the ``height`` and ``rgb-height``
modalities (:mod:`mgn.learn.targets`).

A camera looking into a bin sees the bin's floor (or the table under it) as the largest plane
that faces it. :func:`fit_floor` finds that plane in a z-depth image:

1. every pixel with a depth is back-projected to a camera-frame point ``P = z (x, y, 1)``
   (OpenCV axes, m), ``(x, y)`` the normalised ray of the pixel's centre from the intrinsics
   (lens distortion included); without intrinsics a nominal pinhole is used
   (:func:`nominal_intrinsics`: principal point at the image centre, focal length the longer
   image side in px, a 53-degree field of view across it);
2. RANSAC, scored on up to :data:`FLOOR_SAMPLES` of these points (fixed-seed draws, so the
   result is a function of the image alone): :data:`FLOOR_ITERATIONS` candidate planes through
   three points each (a random pixel and two within :data:`FLOOR_PATCH` of the image's longer
   side of it: a floor seen in small patches between objects is still found); planes whose
   normal is more than :data:`FLOOR_MAX_TILT_DEG` from the optical axis (walls seen from
   above) are skipped. Each candidate's score is the number of points within
   :data:`FLOOR_TOLERANCE_M` of it ("on") less the number more than :data:`FLOOR_BELOW_M`
   below it; the best-scoring one is chosen. Then, while some candidate is parallel to the
   chosen one (within :data:`FLOOR_PARALLEL_DEG`), has at least :data:`FLOOR_MIN_SHARE` of
   its points on it and lies below it (its points on average more than
   :data:`FLOOR_BELOW_M` below the chosen plane), the best-scoring such candidate is chosen
   instead: the floor is the lowest large plane, and the top of a large flat object that
   covers more of the image than the floor does is not taken for it;
3. least-squares refinement: the plane through the centroid of the points within the
   tolerance, normal the direction of least variance (SVD), repeated
   :data:`FLOOR_REFINE_STEPS` times on all the image's points;
4. a bin standing on the ground: a camera that sees the ground around a bin finds the ground
   (larger, and a floor's thickness lower) as the lowest large plane. The most populated
   height, in 1 mm steps, :data:`BIN_FLOOR_RISE_M` above that plane, is taken as the bin's
   floor instead when at least :data:`BIN_FLOOR_MIN_SHARE` of the image's depth pixels lie
   within the tolerance of it and it is enclosed by walls: of the pixels in a ring
   (:data:`BIN_RING` of the longer image side wide) around its footprint
   (:func:`floor_footprint`), at least :data:`BIN_ENCLOSED_SHARE` lie more than
   :data:`BIN_WALL_M` above it. The top of a flat object on a table has the table around it,
   below it, and is not taken.

The height of a point is its signed distance to the plane, positive on the camera's side: 0 on
the floor, an object's top at its height above the floor, the walls of a bin up to the bin's
height. The height does not depend on the camera's distance to the floor or on its tilt.

With nominal intrinsics the fitted plane is the same set of pixels (a plane's inverse depth is
affine in the pixel coordinates for any pinhole), and the heights are scaled by a factor that
grows with the camera's tilt and the focal length's error: 1.00-1.21 (median 1.04) on mgn's
synthetic views, whose focal length the nominal pinhole misses by 40 %.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError
from mgn.scene.cameras import Intrinsics
from mgn.scene.lens import lens_for

__all__ = [
    "BIN_ENCLOSED_SHARE",
    "BIN_FLOOR_MIN_SHARE",
    "BIN_FLOOR_RISE_M",
    "BIN_INTERIOR_MARGIN_M",
    "BIN_RING",
    "BIN_WALL_M",
    "FLOOR_BELOW_M",
    "FLOOR_ITERATIONS",
    "FLOOR_MAX_TILT_DEG",
    "FLOOR_MIN_POINTS",
    "FLOOR_MIN_SHARE",
    "FLOOR_PARALLEL_DEG",
    "FLOOR_PATCH",
    "FLOOR_REFINE_STEPS",
    "FLOOR_SAMPLES",
    "FLOOR_TOLERANCE_M",
    "FloorPlane",
    "bin_interior",
    "fit_floor",
    "floor_footprint",
    "height_above_floor",
    "nominal_intrinsics",
    "pixel_rays",
    "scene_floor",
]

#: Points within this distance of a candidate plane count as on it, m.
FLOOR_TOLERANCE_M = 0.005
#: RANSAC candidate planes.
FLOOR_ITERATIONS = 1024
#: The three points of a candidate plane lie within this fraction of the longer image side of
#: the first one.
FLOOR_PATCH = 0.1
#: Most points RANSAC scores each candidate on (a fixed-seed subsample of the valid pixels).
FLOOR_SAMPLES = 4096
#: Largest angle between a floor's normal and the optical axis, degrees.
FLOOR_MAX_TILT_DEG = 60.0
#: Points further than this below a candidate plane count as below it, m.
FLOOR_BELOW_M = 0.01
#: A plane parallel to the chosen one and below it replaces it when it has at least this
#: share of the chosen one's points on it.
FLOOR_MIN_SHARE = 0.2
#: Largest angle between two planes taken as parallel, degrees.
FLOOR_PARALLEL_DEG = 10.0
#: Least-squares refinements of the RANSAC plane.
FLOOR_REFINE_STEPS = 3
#: Fewest pixels with a depth a floor is fitted to.
FLOOR_MIN_POINTS = 16
#: Heights above the lowest large plane where a bin's floor is looked for, m (min, max).
BIN_FLOOR_RISE_M = (0.005, 0.05)
#: Least share of the image's depth pixels on a bin's floor.
BIN_FLOOR_MIN_SHARE = 0.01
#: Width of the ring around a bin floor's footprint that must show its walls, as a fraction of
#: the longer image side.
BIN_RING = 0.03
#: Points of the ring more than this above the bin's floor count as walls, m.
BIN_WALL_M = 0.03
#: Least share of the ring's points that must be walls.
BIN_ENCLOSED_SHARE = 0.5
#: :func:`bin_interior` keeps the points this far inside the bin's inner walls, m: the walls'
#: own pixels (their depth noise included) stay out.
BIN_INTERIOR_MARGIN_M = 0.005


@dataclass(frozen=True)
class FloorPlane:
    """The plane ``normal . P = offset`` (camera frame, m), ``normal`` a unit vector towards
    the camera's side (``offset < 0``: the camera lies ``-offset`` m above the plane).

    Attributes:
        normal: (3,) unit normal.
        offset: m.
        inlier_fraction: share of the image's depth pixels within :data:`FLOOR_TOLERANCE_M`.
    """

    normal: tuple[float, float, float]
    offset: float
    inlier_fraction: float

    @property
    def camera_height_m(self) -> float:
        """The camera's distance to the plane, m."""
        return -self.offset

    @property
    def tilt_deg(self) -> float:
        """Angle between the plane's normal and the optical axis, degrees."""
        return math.degrees(math.acos(min(1.0, abs(self.normal[2]))))


def nominal_intrinsics(height: int, width: int) -> Intrinsics:
    """The pinhole assumed for a depth image without intrinsics: principal point at the image
    centre, focal length ``max(height, width)`` px in both axes."""
    f = float(max(height, width))
    return Intrinsics(int(width), int(height), f, f, width / 2.0, height / 2.0)


def pixel_rays(
    height: int, width: int, intrinsics: Intrinsics | None = None
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(x, y), each (H, W): the normalised ray ``(X / Z, Y / Z)`` of every pixel centre, from
    ``intrinsics`` (lens distortion included; their size must be the image's) or
    :func:`nominal_intrinsics`."""
    k = intrinsics if intrinsics is not None else nominal_intrinsics(height, width)
    if (k.width, k.height) != (width, height):
        raise InvalidArgumentError(
            f"intrinsics are {k.width} x {k.height} px but the depth image is "
            f"{width} x {height} px; they must match"
        )
    uu, vv = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    lens = lens_for(k)
    if lens is None:
        return (uu - k.cx) / k.fx, (vv - k.cy) / k.fy
    xy = lens.normalized(uu.reshape(-1), vv.reshape(-1))
    return xy[:, 0].reshape(height, width), xy[:, 1].reshape(height, width)


def _points(
    depth_m: np.ndarray, intrinsics: Intrinsics | None, name: str
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.bool_]]:
    d = np.asarray(depth_m, np.float64)
    if d.ndim != 2:
        raise InvalidArgumentError(f"{name}: depth must be an (H, W) image in m, got {d.shape}")
    x, y = pixel_rays(d.shape[0], d.shape[1], intrinsics)
    valid = np.isfinite(d) & (d > 0)
    z = np.where(valid, d, 0.0)
    return np.stack([x * z, y * z, z], axis=-1), valid


def _refine(p: np.ndarray) -> tuple[np.ndarray, float]:
    centre = p.mean(axis=0)
    _, _, vt = np.linalg.svd(p - centre, full_matrices=False)
    n = vt[2]
    return n, float(n @ centre)


def fit_floor(
    depth_m: np.ndarray, intrinsics: Intrinsics | None = None, *, name: str = "image"
) -> FloorPlane:
    """The floor plane of a z-depth image (H, W) in m (NaN or <= 0: no value), module
    docstring. ``name`` (a file or view) is named in the errors: a depth with fewer than
    :data:`FLOOR_MIN_POINTS` values, or without a plane facing the camera."""
    pts, valid = _points(depth_m, intrinsics, name)
    p = pts[valid]
    if len(p) < FLOOR_MIN_POINTS:
        raise InvalidArgumentError(
            f"{name}: depth has {len(p)} pixel(s) with a value; a floor plane needs at least "
            f"{FLOOR_MIN_POINTS}"
        )
    rng = np.random.default_rng(0)
    sample = p if len(p) <= FLOOR_SAMPLES else p[rng.choice(len(p), FLOOR_SAMPLES, replace=False)]
    # Candidate planes through three nearby pixels (a floor may show in small patches only).
    hgt, wid = valid.shape
    rows, cols = np.nonzero(valid)
    first = rng.integers(0, len(rows), size=FLOOR_ITERATIONS)
    reach = max(2, round(FLOOR_PATCH * max(hgt, wid)))
    r = np.clip(
        rows[first][:, None] + rng.integers(-reach, reach + 1, (FLOOR_ITERATIONS, 2)), 0, hgt - 1
    )
    c = np.clip(
        cols[first][:, None] + rng.integers(-reach, reach + 1, (FLOOR_ITERATIONS, 2)), 0, wid - 1
    )
    rr = np.concatenate([rows[first][:, None], r], axis=1)
    cc = np.concatenate([cols[first][:, None], c], axis=1)
    tri = pts[rr, cc]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norm = np.linalg.norm(n, axis=1)
    ok = (norm > 1e-12) & valid[rr, cc].all(axis=1)
    n = n / np.where(ok, norm, 1.0)[:, None]
    ok &= np.abs(n[:, 2]) >= math.cos(math.radians(FLOOR_MAX_TILT_DEG))
    if not ok.any():
        raise InvalidArgumentError(
            f"{name}: no plane within {FLOOR_MAX_TILT_DEG:g} degrees of facing the camera in "
            "the depth; expected a view of a floor or bin from above"
        )
    offsets = np.einsum("ij,ij->i", n, tri[:, 0])
    flip = offsets > 0  # normals towards the camera: heights positive on its side
    n[flip], offsets[flip] = -n[flip], -offsets[flip]
    h = sample @ n.T - offsets
    near = np.abs(h) <= FLOOR_TOLERANCE_M
    on = np.where(ok, near.sum(axis=0), 0)
    score = np.where(ok, on - (h < -FLOOR_BELOW_M).sum(axis=0), np.iinfo(np.int64).min)
    best = int(np.argmax(score))
    cos_parallel = math.cos(math.radians(FLOOR_PARALLEL_DEG))
    for _ in range(FLOOR_ITERATIONS):  # down to the lowest large parallel plane
        lower = ok & (np.abs(n @ n[best]) >= cos_parallel) & (on >= FLOOR_MIN_SHARE * on[best])
        level = (h[:, best] @ near) / np.maximum(on, 1)  # mean height of each one's points
        lower &= level < -FLOOR_BELOW_M
        if not lower.any():
            break
        best = int(np.argmax(np.where(lower, score, np.iinfo(np.int64).min)))
    normal, offset = n[best], float(offsets[best])
    for _ in range(FLOOR_REFINE_STEPS):
        on = np.abs(p @ normal - offset) <= FLOOR_TOLERANCE_M
        if on.sum() < 3:
            break
        normal, offset = _refine(p[on])
    if offset > 0:
        normal, offset = -normal, -offset
    on = np.abs(p @ normal - offset) <= FLOOR_TOLERANCE_M
    ground = FloorPlane(
        (float(normal[0]), float(normal[1]), float(normal[2])), offset, float(on.mean())
    )
    return _bin_floor_above(depth_m, intrinsics, pts, valid, ground, name) or ground


def _bin_floor_above(
    depth_m: np.ndarray,
    intrinsics: Intrinsics | None,
    pts: npt.NDArray[np.float64],
    valid: npt.NDArray[np.bool_],
    ground: FloorPlane,
    name: str,
) -> FloorPlane | None:
    """Step 4 of the module docstring: the floor of a bin standing on ``ground``, or None.
    ``pts``, ``valid``: the depth's camera-frame points and their mask (:func:`_points`)."""
    from scipy import ndimage

    h = pts @ np.asarray(ground.normal, np.float64) - ground.offset
    lo, hi = BIN_FLOOR_RISE_M
    edges = np.arange(lo, hi + 0.0005, 0.001)
    counts, _ = np.histogram(h[valid], edges)
    if counts.max(initial=0) == 0:
        return None
    k = int(np.argmax(counts))
    level = 0.5 * (edges[k] + edges[k + 1])
    on = valid & (np.abs(h - level) <= FLOOR_TOLERANCE_M)
    if on.sum() < max(FLOOR_MIN_POINTS, BIN_FLOOR_MIN_SHARE * valid.sum()):
        return None
    normal, offset = _refine(pts[on])
    if offset > 0:
        normal, offset = -normal, -offset
    if float(np.asarray(ground.normal) @ normal) < math.cos(math.radians(FLOOR_PARALLEL_DEG)):
        return None
    plane = FloorPlane(
        (float(normal[0]), float(normal[1]), float(normal[2])), offset, float(on[valid].mean())
    )
    hull = floor_footprint(depth_m, intrinsics, floor=plane, name=name)
    width = max(2, round(BIN_RING * max(depth_m.shape)))
    ring = ndimage.binary_dilation(hull, iterations=width) & ~hull & valid
    if not ring.any():
        return None
    walls = float(((pts[ring] @ normal - offset) > BIN_WALL_M).mean())
    return plane if walls >= BIN_ENCLOSED_SHARE else None


def height_above_floor(
    depth_m: np.ndarray,
    intrinsics: Intrinsics | None = None,
    *,
    floor: FloorPlane | None = None,
    name: str = "image",
) -> npt.NDArray[np.float32]:
    """(H, W) float32 height of every depth pixel above the floor (:func:`fit_floor`, or
    ``floor`` when given), m, positive towards the camera; NaN where the depth has no value."""
    pts, valid = _points(depth_m, intrinsics, name)
    plane = floor if floor is not None else fit_floor(depth_m, intrinsics, name=name)
    h = pts @ np.asarray(plane.normal, np.float64) - plane.offset
    return np.where(valid, h, np.nan).astype(np.float32)


def floor_footprint(
    depth_m: np.ndarray,
    intrinsics: Intrinsics | None = None,
    *,
    floor: FloorPlane | None = None,
    name: str = "image",
) -> npt.NDArray[np.bool_]:
    """(H, W) bool: the pixels inside the convex hull (in the image) of the floor's pixels --
    those within :data:`FLOOR_TOLERANCE_M` of the plane (:func:`fit_floor`, or ``floor``),
    after a 3 x 3 binary opening that drops specks. In a bin this is the bin's floor with the
    objects on it, without the bin's walls and rim; all True when the floor's pixels span no
    area."""
    from scipy import ndimage
    from scipy.spatial import ConvexHull, QhullError

    h = height_above_floor(depth_m, intrinsics, floor=floor, name=name)
    near = np.abs(np.nan_to_num(h, nan=1.0)) <= FLOOR_TOLERANCE_M
    # opening whose erosion does not eat the image border
    on = ndimage.binary_dilation(ndimage.binary_erosion(near, border_value=1)) & near
    rows, cols = np.nonzero(on)
    full = np.ones(h.shape, bool)
    if len(rows) < 3:
        return full
    pts = np.stack([cols + 0.5, rows + 0.5], axis=1)
    try:
        hull = ConvexHull(pts)
    except QhullError:
        return full
    corners = pts[hull.vertices]  # counter-clockwise
    uu, vv = np.meshgrid(np.arange(h.shape[1]) + 0.5, np.arange(h.shape[0]) + 0.5)
    inside = full
    for a, b in zip(corners, np.roll(corners, -1, axis=0), strict=True):
        inside &= (b[0] - a[0]) * (vv - a[1]) - (b[1] - a[1]) * (uu - a[0]) >= -0.5
    return inside


def scene_floor(X_WC: npt.ArrayLike) -> FloorPlane:
    """The floor of an mgn scene seen by a camera at pose ``X_WC`` ((4, 4), camera frame in the
    tote frame, m): the tote frame's z = 0 plane, the bin's inner floor (docs/cameras.md), in
    the camera frame. ``inlier_fraction`` is 0 (no image was fitted)."""
    X = np.asarray(X_WC, np.float64)
    if X.shape != (4, 4) or not np.isfinite(X).all():
        raise InvalidArgumentError(f"scene_floor: X_WC must be a finite (4, 4) pose, got {X.shape}")
    normal = X[2, :3]
    return FloorPlane((float(normal[0]), float(normal[1]), float(normal[2])), -float(X[2, 3]), 0.0)


def bin_interior(
    depth_m: np.ndarray,
    intrinsics: Intrinsics | None,
    X_WC: npt.ArrayLike,
    inner_length: float,
    inner_width: float,
    *,
    margin: float = BIN_INTERIOR_MARGIN_M,
    name: str = "image",
) -> npt.NDArray[np.bool_]:
    """(H, W) bool: the depth pixels whose point lies inside an mgn bin's inner walls -- in the
    tote frame (camera pose ``X_WC``, m), ``|x| <= inner_length / 2 - margin`` and
    ``|y| <= inner_width / 2 - margin`` (m) at any height; False without a depth value. The
    exact counterpart, for a synthetic view, of :func:`floor_footprint` on a photograph: the
    bin's floor with the objects on it, without its walls, rim and what lies outside."""
    if not (inner_length > 2 * margin >= 0 and inner_width > 2 * margin):
        raise InvalidArgumentError(
            f"bin_interior: inner size {inner_length} x {inner_width} m must exceed twice the "
            f"margin {margin} m"
        )
    pts, valid = _points(depth_m, intrinsics, name)
    X = np.asarray(X_WC, np.float64)
    world = pts.reshape(-1, 3) @ X[:3, :3].T + X[:3, 3]
    inside = (np.abs(world[:, 0]) <= inner_length / 2 - margin) & (
        np.abs(world[:, 1]) <= inner_width / 2 - margin
    )
    return np.asarray(inside.reshape(valid.shape) & valid)
