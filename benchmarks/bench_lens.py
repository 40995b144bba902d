"""Lens distortion: mgn.scene.lens against OpenCV (opencv-python-headless) on the same camera.

A 1200×1200 camera (600×600 in quick mode) with barrel distortion k1 = -0.3, k2 = 0.12,
p1 = 0.001, p2 = -0.002, k3 = -0.02. Two rows:

- *map*: once per camera, where the centre of every distorted pixel lies in the covering pinhole
  render. mgn: ``Lens`` built by Newton's method in NumPy; peer: ``cv2.undistortPoints`` on every
  pixel centre, run to convergence (200 iterations, 1e-12). Agreement: largest difference, px.
- *view*: per view, the pinhole render's RGB (bilinear), instance ids (nearest) and z-depth
  resampled into the distorted image. mgn: ``Lens.warp_rgb`` / ``warp_nearest`` / ``warp_depth``
  (depth: 1/z inside one surface, nearest at edges); peer: three ``cv2.remap`` calls on the
  same map (depth bilinear in z, interpolating across edges). Agreement: ids equal, RGB mean
  difference.

mgn's resampling is single-threaded NumPy (the thread columns other than 1 stay empty).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .common import PEER_NOT_INSTALLED, Row, measure_alternating

DIST = (-0.3, 0.12, 0.001, -0.002, -0.02)


def load_peer() -> tuple[Any | None, str]:
    try:
        import cv2  # optional on purpose (the test extra)
    except ImportError as exc:
        return None, f"{PEER_NOT_INSTALLED} (opencv-python-headless: {exc})"
    return cv2, ""


def _images(shape: tuple[int, int], seed: int = 3) -> dict[str, np.ndarray]:
    """A pinhole render's worth of images: smooth RGB with 30 rectangles of ids and depths."""
    rng = np.random.default_rng(seed)
    h, w = shape
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    rgb = np.stack([xx / w * 255, yy / h * 255, (xx + yy) / (w + h) * 255], 2).astype(np.uint8)
    ids = np.zeros((h, w), np.int32)
    depth = np.full((h, w), 1.0, np.float32)
    for i in range(1, 31):
        x0, y0 = rng.integers(0, w - 80), rng.integers(0, h - 80)
        sx, sy = rng.integers(20, 200, 2)
        ids[y0 : y0 + sy, x0 : x0 + sx] = i
        depth[y0 : y0 + sy, x0 : x0 + sx] = rng.uniform(0.6, 0.95)
        rgb[y0 : y0 + sy, x0 : x0 + sx] = rng.integers(0, 255, 3)
    return {"rgb": rgb, "ids": ids, "depth": depth}


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any | None,
    mgn_status: str,
    log: Callable[[str], None],
) -> list[Row]:
    size = 600 if quick else 1200
    log(f"  lens: {size}x{size}, k1 = {DIST[0]}")
    cv2, peer_status = load_peer()
    map_row = Row(
        group="lens",
        case=f"undistortion map, {size}×{size}, barrel k1 = -0.3",
        n=1,
        unit="cameras/s",
        peer_name="cv2.undistortPoints (every pixel centre)",
        mgn_status=mgn_status,
        peer_status=peer_status,
    )
    view_row = Row(
        group="lens",
        case=f"resample RGB + ids + depth, {size}×{size}",
        n=1,
        unit="views/s",
        peer_name="cv2.remap ×3 (linear, nearest, linear)",
        mgn_status=mgn_status,
        peer_status=peer_status,
    )
    if mgn is None:
        return [map_row, view_row]
    from mgn.scene.cameras import Intrinsics
    from mgn.scene.lens import _build

    f = size * 0.8
    K = Intrinsics(size, size, f, f, size / 2, size / 2, DIST)
    lens = _build(K)
    img = _images(lens.render_shape)
    map_cases: dict[str, Callable[[], object]] = {"mgn/1": lambda: _build(K)}
    view_cases: dict[str, Callable[[], object]] = {
        "mgn/1": lambda: (
            lens.warp_rgb(img["rgb"]),
            lens.warp_nearest(img["ids"]),
            lens.warp_depth(img["depth"], img["ids"]),
        )
    }
    if cv2 is not None:
        uu, vv = np.meshgrid(np.arange(size, dtype=np.float64), np.arange(size, dtype=np.float64))
        pts = np.stack([uu, vv], -1).reshape(-1, 1, 2)
        crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12)

        def peer_map() -> np.ndarray:
            return cv2.undistortPoints(
                pts, K.K_opencv, np.asarray(DIST), R=None, P=lens.render_K.K_opencv, criteria=crit
            )

        map_cases["peer"] = peer_map
        m = peer_map().reshape(size, size, 2).astype(np.float32)
        mx, my = np.ascontiguousarray(m[..., 0]), np.ascontiguousarray(m[..., 1])
        view_cases["peer"] = lambda: (
            cv2.remap(img["rgb"], mx, my, cv2.INTER_LINEAR),
            cv2.remap(img["ids"].astype(np.float32), mx, my, cv2.INTER_NEAREST),
            cv2.remap(img["depth"], mx, my, cv2.INTER_LINEAR),
        )
    out = {}
    for row, cases in ((map_row, map_cases), (view_row, view_cases)):
        results = {k: fn() for k, fn in cases.items()}
        timings = measure_alternating(cases, repeats)
        row.mgn = {1: timings["mgn/1"]}
        row.notes.append(
            f"mgn: {1000 * timings['mgn/1'].median:.0f} ms wall, "
            f"{1000 * float(np.median(timings['mgn/1'].cpu)):.0f} ms CPU"
        )
        if "peer" in cases:
            row.peer = timings["peer"]
            row.notes.append(f"peer: {1000 * timings['peer'].median:.0f} ms wall")
        out[id(row)] = results
    if cv2 is not None:
        peer = map_cases["peer"]().reshape(size, size, 2)
        diff = float(np.abs(np.stack([lens.map_u, lens.map_v], -1) - peer).max())
        map_row.agreement = f"max difference {diff:.1e} px"
        map_row.agreement_ok = diff < 0.01
        mine, theirs = out[id(view_row)]["mgn/1"], out[id(view_row)]["peer"]
        same_ids = float(np.mean(mine[1] == theirs[1].astype(np.int32)))
        rgb_diff = float(np.abs(mine[0].astype(np.int32) - theirs[0].astype(np.int32)).mean())
        view_row.agreement = f"ids equal {100 * same_ids:.3f} %, RGB mean difference {rgb_diff:.2f}"
        view_row.agreement_ok = same_ids > 0.999 and rgb_diff < 1.0
    return [map_row, view_row]


if __name__ == "__main__":
    import sys

    from .common import import_mgn, markdown_table, thread_counts

    mgn_mod, status = import_mgn()
    rows = run(quick="--quick" in sys.argv, repeats=3, mgn=mgn_mod, mgn_status=status, log=print)
    print(markdown_table(rows, thread_counts()))
    for r in rows:
        print("\n".join(r.notes))
    sys.exit(0 if all(r.agreement_ok is not False for r in rows) else 1)
