"""``mgn show``: one view of a dataset with its labels drawn on the RGB image.

Drawn (each switchable): instance colours over the visible masks, amodal contours, per object
its id, occlusion and layer; parallel-jaw grasps as a line between the two contacts, suction
grasps as discs, or the 2-D grasp rectangles of the parallel-jaw grasps whose approach is near
the optical axis (``grasps="rectangles"``, :func:`mgn.io.graspnet.view_rectangles`; the jaws
drawn thick), coloured by score (red 0 → green 1; :func:`mgn.viz.pictures.score_colors`);
semantic keypoints (visible: white discs, occluded: grey rings); the layout graph as arrows from
each parent (on top) to its child. ``alpha`` sets how strongly the masks tint the RGB
(0 = outlines only); ``panels`` adds the amodal masks and the depth image beside the overlay. A
legend below the picture explains every mark, e.g. ``4 14% L0`` = instance 4, 14 % occluded,
layer 0 (top).
"""

from __future__ import annotations

import colorsys
import os
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from PIL import Image, ImageDraw, ImageFont

from mgn.base.atomic import atomic_write_bytes
from mgn.errors import InvalidArgumentError, IoError
from mgn.hardware import MGN_FOLDER, ParallelJawGripper, normalize_grasp_kind
from mgn.io.dataset import Dataset, SceneFolder, View
from mgn.io.graspnet import (
    DEFAULT_MAX_TILT_DEG,
    graspnet_gripper,
    gripper_of,
    view_rectangles,
)
from mgn.io.image_codecs import png_bytes
from mgn.scene.cameras import Intrinsics
from mgn.scene.lens import lens_for
from mgn.viz.pictures import score_colors

__all__ = ["instance_colors", "project", "render_overlay", "show"]


def instance_colors(n: int) -> npt.NDArray[np.uint8]:
    """(n + 1, 3) distinct colours; row 0 (background) is black. Golden-ratio hues."""
    out = np.zeros((n + 1, 3), np.uint8)
    for i in range(1, n + 1):
        r, g, b = colorsys.hsv_to_rgb((i * 0.618034) % 1.0, 0.75, 1.0)
        out[i] = (round(r * 255), round(g * 255), round(b * 255))
    return out


def project(
    points_C: npt.ArrayLike, K: Intrinsics | npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates (N, 2) of camera-frame points (N, 3) and whether each is in front.
    ``K``: a (3, 3) pinhole matrix, or :class:`~mgn.scene.cameras.Intrinsics` (with its lens
    distortion, if any: the points land where the distorted image shows them)."""
    p = np.asarray(points_C, np.float64).reshape(-1, 3)
    z = p[:, 2]
    front = z > 1e-6
    if isinstance(K, Intrinsics):
        lens = lens_for(K)
        if lens is not None:
            with np.errstate(invalid="ignore", divide="ignore"):
                r = np.hypot(p[:, 0] / z, p[:, 1] / z)
            seen = front & (r <= 1.1 * lens.max_radius)  # beyond, the model folds back
            return np.nan_to_num(lens.project(p)), seen
        K = K.K
    uv = (p @ np.asarray(K, np.float64).T)[:, :2] / np.where(front, z, 1.0)[:, None]
    return uv, front


def _contours(mask: np.ndarray) -> np.ndarray:
    inner = mask.copy()
    inner[1:, :] &= mask[:-1, :]
    inner[:-1, :] &= mask[1:, :]
    inner[:, 1:] &= mask[:, :-1]
    inner[:, :-1] &= mask[:, 1:]
    return np.asarray(mask & ~inner)


def _draw_rectangles(
    draw: ImageDraw.ImageDraw, view: View, max_grasps: int, max_tilt_deg: float
) -> str:
    """Draw the best ``max_grasps`` grasp rectangles (worst first, so the best lie on top);
    returns the footer note."""
    root = view.folder.parent
    has_record = (root / "dataset.json").exists()
    gripper = gripper_of(Dataset(root)) if has_record else ParallelJawGripper()
    rects = view_rectangles(view, graspnet_gripper(gripper), max_tilt_deg=max_tilt_deg)
    corners = rects.corners()
    cols = score_colors(rects.score)
    shown = min(len(rects), max_grasps)
    for k in range(shown - 1, -1, -1):
        c = tuple(int(x) for x in cols[k])
        q = [tuple(float(x) for x in pt) for pt in corners[k]]
        draw.line([q[1], q[2]], fill=c, width=1)
        draw.line([q[3], q[0]], fill=c, width=1)
        draw.line([q[0], q[1]], fill=c, width=3)
        draw.line([q[2], q[3]], fill=c, width=3)
    return (
        f"{len(rects)} grasp rectangles (approach within {max_tilt_deg:g} deg of the "
        f"optical axis; best {shown} drawn)"
    )


def _draw_grasps(
    draw: ImageDraw.ImageDraw,
    view: View,
    grasps: str,
    K: Intrinsics,
    max_grasps: int,
    max_tilt_deg: float = DEFAULT_MAX_TILT_DEG,
) -> str:
    """Draw the best ``max_grasps`` non-colliding grasps of a kind; returns the footer note."""
    if grasps == "rectangles":
        return _draw_rectangles(draw, view, max_grasps, max_tilt_deg)
    kind = MGN_FOLDER[normalize_grasp_kind(grasps)]
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


def _draw_keypoints(draw: ImageDraw.ImageDraw, view: View, K: Intrinsics) -> None:
    """Semantic keypoints: visible as white discs, occluded as grey rings."""
    for key, visible in (
        ("keypts_relative_to_camera", True),
        ("occluded_keypts_relative_to_camera", False),
    ):
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


def _tinted(
    rgb: np.ndarray, inst: np.ndarray, amodal: np.ndarray, colors: np.ndarray, alpha: float
) -> np.ndarray:
    """The RGB with the visible masks tinted by ``alpha`` and the amodal contours drawn."""
    out = rgb.copy()
    fg = inst > 0
    out[fg] = (1.0 - alpha) * rgb[fg] + alpha * colors[inst[fg]]
    for i in range(amodal.shape[0]):
        edge = _contours(amodal[i])
        out[edge] = colors[i + 1] * 0.6
        if alpha == 0:
            out[_thick(_contours(inst == i + 1))] = colors[i + 1]
    return np.asarray(out)


def _draw_object_labels(
    draw: ImageDraw.ImageDraw,
    order: dict[str, Any],
    centroids: dict[int, tuple[float, float]],
    layout: bool,
    font: Any,
) -> None:
    """Per visible object its id, occlusion and (with ``layout``) layer, at its centroid."""
    for oid, (x, y) in centroids.items():
        entry = order.get(str(oid), {})
        text = f"{oid}"
        if "occlusion" in entry:
            text += f" {100 * float(entry['occlusion']):.0f}%"
        if layout and "layer" in entry:
            text += f" L{entry['layer']}"
        draw.text(
            (x - 8, y - 6), text, fill="black", stroke_width=2, stroke_fill="white", font=font
        )


def _summary(view: View, num_visible: int, notes: list[str]) -> str:
    """The first footer line: view, visible objects, difficulty, grasp notes."""
    level = (view.layout or {}).get("difficulty") if view.path("_layout.json").exists() else None
    if isinstance(level, dict):
        level = level.get("level")
    summary = f"view {view.index}: {num_visible} objects visible"
    if level is not None:
        summary += f", difficulty {level} (1 easy - 5 hard)"
    if notes:
        summary += ", " + ", ".join(notes)
    return summary


def render_overlay(
    view: View,
    *,
    grasps: str | None = None,
    layout: bool = False,
    keypoints: bool = True,
    max_grasps: int = 300,
    alpha: float = 0.45,
    panels: bool = False,
    max_tilt_deg: float = DEFAULT_MAX_TILT_DEG,
) -> npt.NDArray[np.uint8]:
    """The overlay picture of ``view`` as (H + legend, W, 3) uint8 (3 W wide with ``panels``).

    Args:
        grasps: None, ``"suction"`` or ``"paralleljaw"`` (also ``"pj"``, ``"suctioncup"``):
            draw the non-colliding scene grasps of that kind (at most ``max_grasps``, the
            best-scored first); ``"rectangles"``: the 2-D grasp rectangles of the parallel-jaw
            grasps whose approach is within ``max_tilt_deg`` (degrees, default 20) of the
            optical axis.
        layout: draw the relation graph (parent → child arrows) and each object's layer.
        keypoints: draw the semantic keypoints.
        alpha: weight of the instance colours over the RGB in [0, 1]; 0 draws the visible masks
            as outlines only, so the RGB shows through.
        panels: add two panels to the right: the amodal masks (whole objects, overlaps darker)
            and the depth image (near = bright, invalid = black).
    """

    if not (isinstance(alpha, (int, float)) and 0.0 <= float(alpha) <= 1.0):
        raise InvalidArgumentError(f"render_overlay: alpha must be in [0, 1], got {alpha!r}")
    inst = view.instances
    amodal = view.amodal
    n = amodal.shape[0]
    colors = instance_colors(n)
    out = _tinted(view.rgb.astype(np.float64), inst, amodal, colors, float(alpha))
    h, w = inst.shape
    font = _font(max(11, w // 70))
    legend_lines = [
        part
        for line in _legend_lines(grasps, layout, keypoints, alpha)
        for part in _wrap(line, font, w * (3 if panels else 1) - 8)
    ]
    line_h = font.size + 6 if hasattr(font, "size") else 18
    footer = line_h * (len(legend_lines) + 1) + 8
    canvas = Image.new("RGB", (w * (3 if panels else 1), h + footer), "white")
    canvas.paste(Image.fromarray(out.clip(0, 255).astype(np.uint8)), (0, 0))
    if panels:
        canvas.paste(Image.fromarray(_amodal_panel(amodal, colors)), (w, 0))
        canvas.paste(Image.fromarray(_depth_panel(view)), (2 * w, 0))
    draw = ImageDraw.Draw(canvas)
    if panels:
        for k, title in ((1, "amodal masks (whole objects)"), (2, "depth (near = bright)")):
            draw.text(
                (k * w + 6, 4), title, fill="white", font=font, stroke_width=2, stroke_fill="black"
            )
    K = view.intrinsics
    order = view.order if view.path("_order.json").exists() else {}

    centroids: dict[int, tuple[float, float]] = {}
    for i in range(n):
        ys, xs = np.nonzero(inst == i + 1)
        if len(xs):
            centroids[i + 1] = (float(xs.mean()), float(ys.mean()))

    notes = []
    if grasps is not None:
        notes.append(_draw_grasps(draw, view, grasps, K, max_grasps, max_tilt_deg))

    if keypoints:
        _draw_keypoints(draw, view, K)

    if layout:
        _draw_relations(draw, order, centroids)

    _draw_object_labels(draw, order, centroids, layout, font)
    summary = _summary(view, len(centroids), notes)
    y = h + 4
    draw.text((4, y), summary, fill=(20, 20, 20), font=font)
    for line in legend_lines:
        y += line_h
        if line == "<scorebar>":
            _score_bar(draw, 4, y, font, line_h)
        else:
            draw.text((4, y), line, fill=(60, 60, 60), font=font)
    return np.asarray(canvas)


def _font(size: int) -> Any:  # a PIL font

    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1: the fixed bitmap font
        return ImageFont.load_default()


def _wrap(text: str, font: Any, width: float) -> list[str]:
    """``text`` broken at spaces into lines no wider than ``width`` px in ``font``."""
    if text == "<scorebar>":
        return [text]
    lines: list[str] = []
    for word in text.split(" "):
        if lines and font.getlength(lines[-1] + " " + word) <= width:
            lines[-1] += " " + word
        else:
            lines.append(word)
    return lines


def _thick(edge: np.ndarray) -> np.ndarray:
    out = edge.copy()
    out[1:, :] |= edge[:-1, :]
    out[:, 1:] |= edge[:, :-1]
    return np.asarray(out)


def _legend_lines(grasps: str | None, layout: bool, keypoints: bool, alpha: float) -> list[str]:
    lines = [
        "label '4 14%"
        + (" L0" if layout else "")
        + "' = instance 4, 14% of it occluded"
        + (", layer 0 (0 = top of the pile)" if layout else "")
        + "; "
        + ("tint" if alpha > 0 else "thick outline")
        + " = visible mask, thin dark "
        "outline = amodal mask (the whole object)",
    ]
    if grasps is not None:
        lines.append(
            "grasps: "
            + (
                "rectangles seen along the approach, thick edges = the jaws, across = the opening"
                if grasps == "rectangles"
                else "lines between the two finger contacts"
                if "j" in grasps.lower() or grasps == "pj"
                else "discs at the cup contact"
            )
            + ", coloured by score:"
        )
        lines.append("<scorebar>")
    if keypoints:
        lines.append("keypoints: white disc = visible, grey ring = occluded")
    if layout:
        lines.append("white arrow: from a parent (lying on top) to its child (below it)")
    return lines


def _score_bar(draw: Any, x: int, y: int, font: Any, height: int) -> None:
    draw.text((x, y), "score 0", fill=(60, 60, 60), font=font)
    x0 = x + int(draw.textlength("score 0 ", font=font))
    cols = score_colors(np.linspace(0.0, 1.0, 200))
    for i, c in enumerate(cols):
        draw.line([(x0 + i, y + 2), (x0 + i, y + height - 6)], fill=tuple(int(v) for v in c))
    draw.text((x0 + 206, y), "1", fill=(60, 60, 60), font=font)


def _amodal_panel(amodal: np.ndarray, colors: np.ndarray) -> np.ndarray:
    """Every amodal mask in its instance colour, averaged where masks overlap, darker there."""
    n, h, w = amodal.shape
    acc = np.zeros((h, w, 3))
    count = amodal.sum(axis=0)
    for i in range(n):
        acc[amodal[i]] += colors[i + 1]
    out = np.zeros((h, w, 3))
    hit = count > 0
    out[hit] = acc[hit] / count[hit, None] / np.sqrt(count[hit, None])
    return out.clip(0, 255).astype(np.uint8)


def _depth_panel(view: View) -> np.ndarray:
    d = np.asarray(view.depth, np.float64)
    valid = np.isfinite(d) & (d > 0)
    out = np.zeros(d.shape + (3,), np.uint8)
    if valid.any():
        lo, hi = np.percentile(d[valid], [1, 99])
        t = np.clip((hi - d[valid]) / max(hi - lo, 1e-9), 0, 1)
        g = (40 + 215 * t).astype(np.uint8)
        out[valid] = np.stack([g, g, g], axis=-1)
    return out


def _scene_folder(root: str | os.PathLike[str], scene: int | None) -> SceneFolder:
    """The scene folder: ``root`` itself when it is one (``mgn scene label``), else
    ``root/scene<scene>`` of a dataset."""

    r = Path(root)
    if not r.is_dir():
        what = "is not a folder" if r.exists() else "does not exist"
        raise IoError(f"'{r}' {what}: expected a dataset folder (with --scene N) or a scene folder")
    if any(r.glob("*_rgb.png")):
        return SceneFolder(r, scene if scene is not None else 0)
    if not any(r.glob("scene*/*_rgb.png")):
        raise IoError(
            f"'{r}' holds no views ({{v}}_rgb.png) and no scene folders with views "
            "(scene<N>/): expected a dataset folder (with --scene N) or a scene folder"
        )
    if scene is None:
        raise InvalidArgumentError(
            f"'{r}' is a dataset folder: give --scene N (or pass a scene folder)"
        )
    return Dataset(r).scene(scene)


def show(
    root: str | os.PathLike[str],
    scene: int | None,
    view: int,
    out: str | os.PathLike[str],
    **kwargs: object,
) -> Path:
    """Write the overlay of ``scene``/``view`` to ``out`` (PNG). ``root`` is a dataset (then
    ``scene`` is required) or a single scene folder (``mgn scene label --out``)."""

    image = render_overlay(_scene_folder(root, scene).view(view), **kwargs)  # type: ignore[arg-type]
    path = Path(out)
    atomic_write_bytes(path, png_bytes(image))
    return path
