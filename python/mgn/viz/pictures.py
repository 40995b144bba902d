"""Small pictures for people: a shaded view of a mesh with coloured points on it.

No plotting library is needed: the object is ray cast with :class:`mgn.RayScene` from a camera
looking at the object's centre, shaded by its normals, and points are drawn where they are visible
(their depth agrees with the ray-cast depth). Used by ``mgn suction compare`` and the label CLIs.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from PIL import Image, ImageDraw

from mgn.geometry.mesh import Mesh
from mgn.geometry.raytrace import RayScene, camera_rays
from mgn.scene.cameras import look_at


@dataclass(frozen=True)
class Snapshot:
    """A shaded view of one object.

    Attributes:
        image: (H, W, 3) uint8 RGB, white background.
        depth: (H, W) float32 z-depth in metres, +inf on background.
        K: (3, 3) intrinsics (pixels); X_WC: (4, 4) camera pose (OpenCV frame) in the mesh frame.
    """

    image: npt.NDArray[np.uint8]
    depth: npt.NDArray[np.float32]
    K: npt.NDArray[np.float64]
    X_WC: npt.NDArray[np.float64]


def snapshot(
    mesh: Mesh,
    *,
    size: int = 360,
    direction: Sequence[float] = (1.0, -0.8, 0.9),
    base_color: Sequence[float] = (0.78, 0.78, 0.8),
) -> Snapshot:
    """Shaded picture of ``mesh`` seen from ``direction`` (from the object towards the camera)."""
    v = mesh.vertices.astype(np.float64)
    lo, hi = v.min(0), v.max(0)
    centre = 0.5 * (lo + hi)
    radius = 0.5 * float(np.linalg.norm(hi - lo))
    d = np.asarray(direction, float)
    d /= np.linalg.norm(d)
    fov = np.deg2rad(25.0)
    dist = radius / np.sin(0.5 * fov) * 1.05
    X_WC = look_at(centre + dist * d, centre)
    f = 0.5 * size / np.tan(0.5 * fov)
    K = np.array([[f, 0, 0.5 * size], [0, f, 0.5 * size], [0, 0, 1]])
    origins, dirs = camera_rays(K, size, size, X_WC)
    hits = RayScene(mesh).intersect(origins, dirs, coherent=True)
    hit = hits.hit.reshape(size, size)
    n = hits.normals.reshape(size, size, 3).astype(np.float64)
    light = X_WC[:3, :3] @ np.array([-0.4, -0.6, -1.0])  # from above-left of the camera
    light /= np.linalg.norm(light)
    lambert = np.clip(n @ light, 0.0, 1.0)
    shade = 0.35 + 0.65 * lambert
    image = np.full((size, size, 3), 255.0)
    image[hit] = (shade[hit, None] * np.asarray(base_color)[None, :]) * 255.0
    z_cam = (dirs @ X_WC[:3, 2]).reshape(size, size)  # cos of the ray to the optical axis
    depth = np.where(hit, hits.distance.reshape(size, size) * z_cam, np.inf).astype(np.float32)
    return Snapshot(image.astype(np.uint8), depth, K, X_WC)


def score_colors(scores: npt.ArrayLike) -> npt.NDArray[np.uint8]:
    """Red (0) → yellow (0.5) → green (1) RGB colours for scores in [0, 1]."""
    s = np.clip(np.asarray(scores, float), 0.0, 1.0)
    r = np.clip(2.0 * (1.0 - s), 0.0, 1.0)
    g = np.clip(2.0 * s, 0.0, 1.0)
    return (np.stack([r, g, np.zeros_like(s)], axis=1) * 230).astype(np.uint8)


def draw_points(
    snap: Snapshot,
    points: npt.ArrayLike,
    colors: npt.ArrayLike,
    *,
    radius: int = 2,
    depth_tolerance: float = 2e-3,
) -> npt.NDArray[np.uint8]:
    """Copy of the snapshot image with the visible ``points`` (N, 3; mesh frame, m) drawn as
    discs of ``colors`` (N, 3) uint8. A point is visible if its depth is within
    ``depth_tolerance`` m of the ray-cast depth at its pixel."""
    img = snap.image.copy()
    h, w = snap.depth.shape
    p = np.asarray(points, float)
    X_CW = np.linalg.inv(snap.X_WC)
    pc = p @ X_CW[:3, :3].T + X_CW[:3, 3]
    z = pc[:, 2]
    uv = (pc @ snap.K.T)[:, :2] / z[:, None]
    ui, vi = np.floor(uv[:, 0]).astype(int), np.floor(uv[:, 1]).astype(int)
    inside = (z > 0) & (ui >= 0) & (ui < w) & (vi >= 0) & (vi < h)
    visible = np.zeros(len(p), bool)
    visible[inside] = z[inside] <= snap.depth[vi[inside], ui[inside]] + depth_tolerance
    cols = np.asarray(colors, np.uint8)
    offsets = [
        (dx, dy)
        for dx in range(-radius, radius + 1)
        for dy in range(-radius, radius + 1)
        if dx * dx + dy * dy <= radius * radius
    ]
    idx = np.flatnonzero(visible)
    order = idx[np.argsort(-z[idx])]  # far first, near points on top
    for dx, dy in offsets:
        uu = np.clip(ui[order] + dx, 0, w - 1)
        vv = np.clip(vi[order] + dy, 0, h - 1)
        img[vv, uu] = cols[order]
    return np.asarray(img)


def panels(
    images: Sequence[npt.NDArray[np.uint8]], titles: Sequence[str], *, footer: str = ""
) -> npt.NDArray[np.uint8]:
    """Images side by side with a title above each (and an optional footer line)."""

    h = max(i.shape[0] for i in images)
    w = sum(i.shape[1] for i in images)
    top, bottom = 22, 22 if footer else 0
    canvas = Image.new("RGB", (w, h + top + bottom), "white")
    draw = ImageDraw.Draw(canvas)
    x = 0
    for img, title in zip(images, titles, strict=True):
        canvas.paste(Image.fromarray(img), (x, top))
        draw.text((x + 6, 5), title, fill=(0, 0, 0))
        x += img.shape[1]
    if footer:
        draw.text((6, h + top + 5), footer, fill=(60, 60, 60))
    return np.asarray(canvas)
