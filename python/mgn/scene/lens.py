"""Lens distortion: the OpenCV camera model and the resampling of pinhole renders (docs/cameras.md).

A camera whose :class:`~mgn.scene.cameras.Intrinsics` carry ``distortion`` coefficients (OpenCV
order k1, k2, p1, p2[, k3[, k4, k5, k6[, s1, s2, s3, s4[, tau_x, tau_y]]]]) sees a point
``p_C = (x, y, z)`` of its OpenCV frame at the image point

    x' = x / z, y' = y / z, r^2 = x'^2 + y'^2,
    x'' = x' (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6)
          + 2 p1 x' y' + p2 (r^2 + 2 x'^2) + s1 r^2 + s2 r^4,
    y'' = y' (...) / (...) + p1 (r^2 + 2 y'^2) + 2 p2 x' y' + s3 r^2 + s4 r^4,
    (x''', y''') = the tilted-sensor projection of (x'', y'') by tau_x, tau_y,
    u = fx x''' + cx, v = fy y''' + cy

(continuous image coordinates: pixel (u, v) has its centre at (u + 0.5, v + 0.5), so OpenCV's
camera matrix has cx - 0.5 and cy - 0.5; :attr:`Intrinsics.K_opencv`).

mgn renders pinhole images only. :class:`Lens` is built once per camera (:func:`lens_for`): it
inverts the model for every pixel centre of the distorted image (where its ray meets the
pinhole image plane; the map ``cv2.initUndistortRectifyMap`` builds in the other direction),
chooses a pinhole camera with the same focal lengths that covers all of them (``render_K``) and
resamples the pinhole images into the distorted ones: nearest neighbour for ids and masks,
bilinear for RGB, and for depth bilinear in 1/z (exact on planes) only inside one surface.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError
from mgn.scene.cameras import Intrinsics

__all__ = ["Lens", "distort_normalized", "lens_for"]

#: Pixels added around the covered region of the pinhole render (bilinear neighbours).
_MARGIN = 2
#: Largest pinhole render, in distorted-image pixel counts (a wider lens needs a fisheye model).
_MAX_RENDER_FACTOR = 9.0
#: Largest tangent of the half field of view a pinhole render can cover (about 76 degrees).
_MAX_TAN = 4.0
#: Relative depth jump between bilinear neighbours treated as a discontinuity.
DEPTH_JUMP = 0.03


def _coefficients(dist: tuple[float, ...]) -> npt.NDArray[np.float64]:
    d = np.zeros(14)
    d[: len(dist)] = dist
    return d


def _tilt_matrix(tau_x: float, tau_y: float) -> npt.NDArray[np.float64]:
    """OpenCV's tilted-sensor projection (Scheimpflug): rotation about x then y, then the
    projection back onto the image plane."""
    cx, sx, cy, sy = math.cos(tau_x), math.sin(tau_x), math.cos(tau_y), math.sin(tau_y)
    rot_x = np.array([[1.0, 0.0, 0.0], [0.0, cx, sx], [0.0, -sx, cx]])
    rot_y = np.array([[cy, 0.0, -sy], [0.0, 1.0, 0.0], [sy, 0.0, cy]])
    rot = rot_y @ rot_x
    proj = np.array([[rot[2, 2], 0.0, -rot[0, 2]], [0.0, rot[2, 2], -rot[1, 2]], [0.0, 0.0, 1.0]])
    out: npt.NDArray[np.float64] = proj @ rot
    return out


def distort_normalized(
    x: npt.ArrayLike, y: npt.ArrayLike, distortion: tuple[float, ...]
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """The OpenCV model on normalised coordinates ``x = X/Z, y = Y/Z``: returns the distorted
    normalised coordinates (x''', y''') of the module docstring (multiply by fx, fy and add cx,
    cy for pixels)."""
    xa, ya = np.asarray(x, np.float64), np.asarray(y, np.float64)
    k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4, tx, ty = _coefficients(distortion)
    r2 = xa * xa + ya * ya
    r4 = r2 * r2
    radial = (1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1.0 + r2 * (k4 + r2 * (k5 + r2 * k6)))
    xd = xa * radial + 2.0 * p1 * xa * ya + p2 * (r2 + 2.0 * xa * xa) + s1 * r2 + s2 * r4
    yd = ya * radial + p1 * (r2 + 2.0 * ya * ya) + 2.0 * p2 * xa * ya + s3 * r2 + s4 * r4
    if tx != 0.0 or ty != 0.0:
        t = _tilt_matrix(tx, ty)
        w = t[2, 0] * xd + t[2, 1] * yd + t[2, 2]
        xd, yd = (
            (t[0, 0] * xd + t[0, 1] * yd + t[0, 2]) / w,
            (t[1, 0] * xd + t[1, 1] * yd + t[1, 2]) / w,
        )
    return xd, yd


def _undistort(
    xd: npt.NDArray[np.float64], yd: npt.NDArray[np.float64], distortion: tuple[float, ...]
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Solves ``distort_normalized(x, y) = (xd, yd)`` by Newton's method (forward-difference
    Jacobian) from ``(xd, yd)``; returns x, y and the Jacobian determinant at the solution."""
    x, y = xd.copy(), yd.copy()
    h = 1e-7
    det = np.ones_like(x)
    for _ in range(50):
        fx, fy = distort_normalized(x, y, distortion)
        rx, ry = fx - xd, fy - yd
        ax, ay = distort_normalized(x + h, y, distortion)
        cx, cy = distort_normalized(x, y + h, distortion)
        j11, j21 = (ax - fx) / h, (ay - fy) / h
        j12, j22 = (cx - fx) / h, (cy - fy) / h
        det = j11 * j22 - j12 * j21
        safe = np.where(np.abs(det) > 1e-12, det, 1e-12)
        step_x = (j22 * rx - j12 * ry) / safe
        step_y = (-j21 * rx + j11 * ry) / safe
        # Damped: a step never moves further than half the current radius (keeps the inner
        # branch of a polynomial that folds over further out).
        n = np.hypot(step_x, step_y)
        lim = 0.5 * (np.hypot(x, y) + 0.1)
        s = np.where(n > lim, lim / np.maximum(n, 1e-300), 1.0)
        x, y = x - s * step_x, y - s * step_y
        if float(np.max(np.abs(rx))) < 1e-12 and float(np.max(np.abs(ry))) < 1e-12:
            break
    return x, y, det


@dataclass(frozen=True, eq=False)
class Lens:
    """A distorted camera and the pinhole render it is resampled from (build with
    :func:`lens_for`, which caches one per camera).

    Attributes:
        K: the distorted camera (its ``distortion`` is not empty).
        render_K: the pinhole camera to render (same fx, fy; shifted principal point, larger or
            smaller image) covering every pixel centre of ``K``.
        map_u, map_v: (H, W) float64: where the centre of each distorted pixel lies in the
            pinhole render, in render pixel indices (pixel (i, j) centred on (i, j)).
        max_radius: largest normalised radius sqrt(x'^2 + y'^2) of a pixel ray; points further
            out are outside the image (the polynomial can fold them back into it).
    """

    K: Intrinsics
    render_K: Intrinsics
    map_u: npt.NDArray[np.float64] = field(repr=False)
    map_v: npt.NDArray[np.float64] = field(repr=False)
    max_radius: float
    _nearest: npt.NDArray[np.int64] = field(repr=False)
    _corner: npt.NDArray[np.int64] = field(repr=False)
    _weights: npt.NDArray[np.float32] = field(repr=False)

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W) of the distorted image."""
        h, w = self.map_u.shape
        return (int(h), int(w))

    @property
    def render_shape(self) -> tuple[int, int]:
        """(H, W) of the pinhole render."""
        return (int(self.render_K.height), int(self.render_K.width))

    def _check(self, a: npt.NDArray[np.generic], name: str) -> None:
        if a.shape[:2] != self.render_shape and a.shape[-2:] != self.render_shape:
            raise InvalidArgumentError(
                f"Lens: {name} has shape {a.shape}; expected the pinhole render's (H, W) = "
                f"{self.render_shape}"
            )

    def warp_nearest(self, image: npt.ArrayLike, *, stacked: bool = False) -> npt.NDArray[Any]:
        """Nearest-neighbour resampling of a pinhole image (H_r, W_r[, C]) or, with ``stacked``,
        of a stack (N, H_r, W_r) (masks of N objects) into the distorted image. Any dtype."""
        a = np.asarray(image)
        self._check(a, "image")
        h, w = self.shape
        if stacked:
            flat = a.reshape(a.shape[0], -1)
            return np.ascontiguousarray(flat[:, self._nearest].reshape(a.shape[0], h, w))
        flat = a.reshape(a.shape[0] * a.shape[1], *a.shape[2:])
        return np.ascontiguousarray(flat[self._nearest].reshape(h, w, *a.shape[2:]))

    def _bilinear(self, values: list[npt.NDArray[np.float32]]) -> npt.NDArray[np.float32]:
        w = self._weights
        out = w[:, 0] * values[0]
        for k in range(1, 4):
            out += w[:, k] * values[k]
        return out

    def warp_rgb(self, rgb: npt.ArrayLike) -> npt.NDArray[np.uint8]:
        """Bilinear resampling of a (H_r, W_r, C) uint8 image into the distorted image."""
        a = np.asarray(rgb)
        self._check(a, "rgb")
        h, w = self.shape
        out = np.empty((h * w, a.shape[2]), np.uint8)
        for c in range(a.shape[2]):
            flat = np.ascontiguousarray(a[:, :, c]).reshape(-1)
            v = self._bilinear([flat[self._corner[:, k]].astype(np.float32) for k in range(4)])
            out[:, c] = np.clip(np.rint(v), 0, 255).astype(np.uint8)
        return out.reshape(h, w, a.shape[2])

    def warp_depth(
        self,
        depth: npt.ArrayLike,
        instance_ids: npt.ArrayLike | None = None,
        *,
        at_edges: str = "nearest",
    ) -> npt.NDArray[np.float32]:
        """Resampling of a pinhole z-depth image (H_r, W_r), m, into the distorted image.

        z along the optical axis does not change with the image-plane warp. A pixel whose four
        pinhole neighbours are valid (finite, > 0), show the same instance and differ by less
        than :data:`DEPTH_JUMP` (relative) is interpolated bilinearly in 1/z (exact on a plane).
        Elsewhere (an edge, or next to an invalid pixel): ``at_edges="nearest"`` takes the nearest
        pinhole pixel (the one the instance ids come from; 0 or NaN there stays as given),
        ``"invalid"`` gives NaN, as a depth sensor does at edges.
        """
        if at_edges not in ("nearest", "invalid"):
            raise InvalidArgumentError(
                f"Lens.warp_depth: at_edges must be 'nearest' or 'invalid', got {at_edges!r}"
            )
        d = np.asarray(depth, np.float32)
        self._check(d, "depth")
        flat = d.reshape(-1)
        n4 = [flat[self._corner[:, k]] for k in range(4)]
        with np.errstate(invalid="ignore", divide="ignore"):
            lo = np.minimum(np.minimum(n4[0], n4[1]), np.minimum(n4[2], n4[3]))
            hi = np.maximum(np.maximum(n4[0], n4[1]), np.maximum(n4[2], n4[3]))
            ok = (lo > 0) & np.isfinite(hi) & ((hi - lo) <= DEPTH_JUMP * lo)
            if instance_ids is not None:
                ids = np.asarray(instance_ids).reshape(-1)
                i0 = ids[self._corner[:, 0]]
                for k in range(1, 4):
                    ok &= ids[self._corner[:, k]] == i0
            inv = self._bilinear([np.float32(1.0) / x for x in n4])
            interp = np.float32(1.0) / inv
        fill = flat[self._nearest] if at_edges == "nearest" else np.float32(np.nan)
        out = np.where(ok, interp, fill)
        return out.astype(np.float32).reshape(self.shape)

    def project(self, points_C: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """(N, 2) continuous image coordinates (u, v) of camera-frame points (N, 3), m, through the
        lens (the ``cv2.projectPoints`` model); NaN for points not in front of the camera."""
        p = np.asarray(points_C, np.float64).reshape(-1, 3)
        z = p[:, 2]
        with np.errstate(invalid="ignore", divide="ignore"):
            x, y = p[:, 0] / z, p[:, 1] / z
        k = self.K
        xd, yd = distort_normalized(x, y, k.distortion)
        uv = np.stack([k.fx * xd + k.cx, k.fy * yd + k.cy], axis=1)
        uv[~(z > 0)] = np.nan
        return uv

    def normalized(self, u: npt.ArrayLike, v: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """(N, 2) normalised ray coordinates (x/z, y/z) of image points (u, v) of the distorted
        image (continuous image coordinates, px): the inverse of :meth:`project`."""
        k = self.K
        ua = np.atleast_1d(np.asarray(u, np.float64)).reshape(-1)
        va = np.atleast_1d(np.asarray(v, np.float64)).reshape(-1)
        x, y, _ = _undistort((ua - k.cx) / k.fx, (va - k.cy) / k.fy, k.distortion)
        return np.stack([x, y], axis=1)

    def in_image(self, points_C: npt.ArrayLike, near: float = 0.0) -> npt.NDArray[np.bool_]:
        """(N,) bool: camera-frame points (N, 3) in front of the camera (z > ``near``, m) whose
        distorted projection lies inside the image and whose ray is one of the image's rays
        (normalised radius at most :attr:`max_radius`)."""
        p = np.asarray(points_C, np.float64).reshape(-1, 3)
        uv = self.project(p)
        h, w = self.shape
        with np.errstate(invalid="ignore", divide="ignore"):
            r = np.hypot(p[:, 0] / p[:, 2], p[:, 1] / p[:, 2])
            inside = (uv[:, 0] >= 0) & (uv[:, 0] < w) & (uv[:, 1] >= 0) & (uv[:, 1] < h)
        return (p[:, 2] > near) & inside & (r <= self.max_radius * (1 + 1e-9))


def _build(k: Intrinsics) -> Lens:
    dist = k.distortion
    w, h = int(k.width), int(k.height)
    fx, fy, cx, cy = k.fx, k.fy, k.cx, k.cy
    uu, vv = np.meshgrid(np.arange(w, dtype=np.float64) + 0.5, np.arange(h, dtype=np.float64) + 0.5)
    xd, yd = (uu - cx) / fx, (vv - cy) / fy
    x, y, det = _undistort(xd, yd, dist)
    fx_back, fy_back = distort_normalized(x, y, dist)
    err = np.hypot((fx_back - xd) * fx, (fy_back - yd) * fy)
    bad = ~(
        np.isfinite(err)
        & (err < 1e-3)
        & (det > 0)
        & (np.abs(x) < _MAX_TAN)
        & (np.abs(y) < _MAX_TAN)
    )
    if bad.any():
        j = int(np.flatnonzero(bad.reshape(-1))[0])
        raise InvalidArgumentError(
            f"camera distortion {list(dist)}: the lens model cannot be inverted at pixel "
            f"(u, v) = ({j % w}, {j // w}) (the polynomial folds over, or the ray is wider than "
            f"{math.degrees(math.atan(_MAX_TAN)):.0f} deg from the axis); expected coefficients "
            "of a lens whose image covers less than that"
        )
    # Pinhole pixel coordinates (continuous) with the same focal lengths.
    pu, pv = fx * x + cx, fy * y + cy
    u0 = math.floor(float(pu.min())) - _MARGIN
    v0 = math.floor(float(pv.min())) - _MARGIN
    u1 = math.ceil(float(pu.max())) + _MARGIN
    v1 = math.ceil(float(pv.max())) + _MARGIN
    rw, rh = u1 - u0, v1 - v0
    if rw * rh > _MAX_RENDER_FACTOR * w * h:
        raise InvalidArgumentError(
            f"camera distortion {list(dist)}: the pinhole render covering the image would be "
            f"{rw} x {rh} px, more than {_MAX_RENDER_FACTOR:g} times the {w} x {h} image; "
            "expected a lens of moderate distortion"
        )
    render_K = Intrinsics(rw, rh, fx, fy, cx - u0, cy - v0)  # integer shift: same pixel grid
    map_u, map_v = pu - u0 - 0.5, pv - v0 - 0.5  # render pixel indices
    iu = np.floor(map_u + 0.5).astype(np.int64)
    iv = np.floor(map_v + 0.5).astype(np.int64)
    nearest = (iv * rw + iu).reshape(-1)
    bu, bv = np.floor(map_u).astype(np.int64), np.floor(map_v).astype(np.int64)
    fu, fv = (map_u - bu).reshape(-1), (map_v - bv).reshape(-1)
    base = (bv * rw + bu).reshape(-1)
    corner = np.stack([base, base + 1, base + rw, base + rw + 1], axis=1)
    weights = np.stack([(1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv], axis=1).astype(
        np.float32
    )
    for a in (map_u, map_v):
        a.setflags(write=False)
    return Lens(
        K=k,
        render_K=render_K,
        map_u=map_u,
        map_v=map_v,
        max_radius=float(np.max(np.hypot(x, y))),
        _nearest=nearest,
        _corner=corner,
        _weights=weights,
    )


@functools.lru_cache(maxsize=4)
def _cached(K: Intrinsics) -> Lens:
    return _build(K)


def lens_for(K: Intrinsics) -> Lens | None:
    """The :class:`Lens` of intrinsics ``K`` (an :class:`~mgn.scene.cameras.Intrinsics`), built
    once per camera and cached; None for a pinhole camera (no distortion).

    Raises:
        InvalidArgumentError: coefficients whose model cannot be inverted over the image.
    """
    if not K.distortion:
        return None
    return _cached(K)
