"""``mgn show``: one view of a dataset with its labels drawn on the RGB image.

Drawn (each switchable): instance colours over the visible masks, amodal contours, per object
its id, occlusion and layer; parallel-jaw grasps as a line between the two contacts and suction
grasps as discs, coloured by score (red 0 → green 1; :func:`mgn.viz.pictures.score_colors`);
semantic keypoints (visible: white discs, occluded: grey rings); the layout graph as arrows from
each parent (on top) to its child. The picture has the size of the view (plus a one-line footer).
"""

from __future__ import annotations

import colorsys
import os
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from PIL import Image, ImageDraw

from mgn.base.atomic import atomic_write_bytes
from mgn.errors import InvalidArgumentError
from mgn.io.dataset import Dataset, View
from mgn.io.scene_format import png_bytes
from mgn.viz.pictures import score_colors

__all__ = ["instance_colors", "project", "render_overlay", "show"]


def instance_colors(n: int) -> npt.NDArray[np.uint8]:
    """(n + 1, 3) distinct colours; row 0 (background) is black. Golden-ratio hues."""
    out = np.zeros((n + 1, 3), np.uint8)
    for i in range(1, n + 1):
        r, g, b = colorsys.hsv_to_rgb((i * 0.618034) % 1.0, 0.75, 1.0)
        out[i] = (round(r * 255), round(g * 255), round(b * 255))
    return out


def project(points_C: npt.ArrayLike, K: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates (N, 2) of camera-frame points (N, 3) and whether each is in front."""
    p = np.asarray(points_C, np.float64).reshape(-1, 3)
    z = p[:, 2]
    front = z > 1e-6
    uv = (p @ np.asarray(K, np.float64).T)[:, :2] / np.where(front, z, 1.0)[:, None]
    return uv, front


def _contours(mask: np.ndarray) -> np.ndarray:
    inner = mask.copy()
    inner[1:, :] &= mask[:-1, :]
    inner[:-1, :] &= mask[1:, :]
    inner[:, 1:] &= mask[:, :-1]
    inner[:, :-1] &= mask[:, 1:]
    return mask & ~inner


def _draw_grasps(
    draw: ImageDraw.ImageDraw, view: View, grasps: str, K: np.ndarray, max_grasps: int
) -> str:
    """Draw the best ``max_grasps`` non-colliding grasps of a kind; returns the footer note."""
    kind = {"pj": "paralleljaw", "suction": "suctioncup"}.get(grasps)
    if kind is None:
        raise InvalidArgumentError(
            f"render_overlay: grasps must be 'pj' or 'suction', got {grasps!r}"
        )
    g = view.grasps(kind)
    poses = g.get("contact_poses_relative_to_camera", np.zeros((0, 4, 4)))
    score = g.get("score_analytical", np.ones(len(poses)))
    if len(score) != len(poses):
        raise InvalidArgumentError(
            f"{view}: {kind} grasps have {len(poses)} poses, {len(score)} scores"
        )
    keep = np.argsort(-np.nan_to_num(score, nan=-1.0), kind="stable")[:max_grasps][::-1]
    cols = score_colors(np.nan_to_num(score, nan=0.0))
    p0, f0 = project(poses[:, :3, 3], K)
    if kind == "paralleljaw":
        width = g.get("contact_width", np.zeros(len(poses)))[: len(poses)]
        p_far = poses[:, :3, 3] + poses[:, :3, 0] * width[:, None]
        p1, f1 = project(p_far, K)
        for k in keep:
            if f0[k] and f1[k]:
                c = tuple(int(x) for x in cols[k])
                draw.line([tuple(p0[k]), tuple(p1[k])], fill=c, width=2)
    else:
        for k in keep:
            if f0[k]:
                u, v = p0[k]
                draw.ellipse([u - 3, v - 3, u + 3, v + 3], fill=tuple(int(x) for x in cols[k]))
    return f"{len(poses)} {grasps} grasps (best {len(keep)} drawn)"


def _draw_keypoints(draw: ImageDraw.ImageDraw, view: View, K: np.ndarray) -> None:
    """Semantic keypoints: visible as white discs, occluded as grey rings."""
    for key, visible in (("keypts_relative_to_camera", True),
                         ("occluded_keypts_relative_to_camera", False)):  # fmt: skip
        kp = view.hdf5.get(f"keypts/byhand/{key}")
        if kp is None or len(kp) == 0:
            continue
        uv, front = project(kp[:, 1:4], K)
        for (u, v), ok in zip(uv, front, strict=True):
            if not ok:
                continue
            if visible:
                draw.ellipse([u - 3, v - 3, u + 3, v + 3], fill="white", outline="black")
            else:
                draw.ellipse([u - 3, v - 3, u + 3, v + 3], outline=(150, 150, 150))


def _draw_relations(
    draw: ImageDraw.ImageDraw,
    order: dict[str, Any],
    centroids: dict[int, tuple[float, float]],
) -> None:
    """The layout graph: an arrow from each parent (on top) to its child."""
    for key, entry in order.items():
        child = int(key)
        for parent in entry.get("parents", []):
            pid = int(parent["id"])
            if pid in centroids and child in centroids:
                (x0, y0), (x1, y1) = centroids[pid], centroids[child]
                draw.line([(x0, y0), (x1, y1)], fill="white", width=2)
                # Arrow head at the child.
                d = np.array([x1 - x0, y1 - y0])
                length = float(np.linalg.norm(d))
                if length > 1:
                    d /= length
                    nrm = np.array([-d[1], d[0]])
                    tip = np.array([x1, y1])
                    a = tip - 9 * d + 5 * nrm
                    b = tip - 9 * d - 5 * nrm
                    draw.polygon([tuple(tip), tuple(a), tuple(b)], fill="white")


def render_overlay(
    view: View,
    *,
    grasps: str | None = None,
    layout: bool = False,
    keypoints: bool = True,
    max_grasps: int = 300,
) -> npt.NDArray[np.uint8]:
    """The overlay picture of ``view`` as (H + 20, W, 3) uint8.

    Args:
        grasps: None, ``"pj"`` or ``"suction"``: draw the non-colliding scene grasps of that kind
            (at most ``max_grasps``, the best-scored first).
        layout: draw the relation graph (parent → child arrows) and each object's layer.
        keypoints: draw the semantic keypoints.
    """

    rgb = view.rgb.astype(np.float64)
    inst = view.instances
    amodal = view.amodal
    n = amodal.shape[0]
    colors = instance_colors(n)
    out = rgb.copy()
    fg = inst > 0
    out[fg] = 0.55 * rgb[fg] + 0.45 * colors[inst[fg]]
    for i in range(n):
        edge = _contours(amodal[i])
        out[edge] = colors[i + 1] * 0.6
    h, w = inst.shape
    canvas = Image.new("RGB", (w, h + 20), "white")
    canvas.paste(Image.fromarray(out.clip(0, 255).astype(np.uint8)), (0, 0))
    draw = ImageDraw.Draw(canvas)
    K = view.intrinsics.K
    order = view.order if view.path("_order.json").exists() else {}

    centroids: dict[int, tuple[float, float]] = {}
    for i in range(n):
        ys, xs = np.nonzero(inst == i + 1)
        if len(xs):
            centroids[i + 1] = (float(xs.mean()), float(ys.mean()))

    notes = []
    if grasps is not None:
        notes.append(_draw_grasps(draw, view, grasps, K, max_grasps))

    if keypoints:
        _draw_keypoints(draw, view, K)

    if layout:
        _draw_relations(draw, order, centroids)

    for oid, (x, y) in centroids.items():
        entry = order.get(str(oid), {})
        text = f"{oid}"
        if "occlusion" in entry:
            text += f" {100 * float(entry['occlusion']):.0f}%"
        if layout and "layer" in entry:
            text += f" L{entry['layer']}"
        draw.text((x - 8, y - 6), text, fill="black", stroke_width=2, stroke_fill="white")

    level = (view.layout or {}).get("difficulty") if view.path("_layout.json").exists() else None
    if isinstance(level, dict):
        level = level.get("level")
    footer = f"view {view.index}: {len(centroids)} objects visible"
    if level is not None:
        footer += f", difficulty {level}"
    if notes:
        footer += ", " + ", ".join(notes)
    draw.text((4, h + 4), footer, fill=(40, 40, 40))
    return np.asarray(canvas)


def show(
    root: str | os.PathLike[str],
    scene: int,
    view: int,
    out: str | os.PathLike[str],
    **kwargs: object,
) -> Path:
    """Write the overlay of ``scene``/``view`` of the dataset at ``root`` to ``out`` (PNG)."""

    image = render_overlay(Dataset(root).scene(scene).view(view), **kwargs)  # type: ignore[arg-type]
    path = Path(out)
    atomic_write_bytes(path, png_bytes(image))
    return path
