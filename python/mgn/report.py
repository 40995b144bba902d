"""``mgn report DIR -o report.html``: a self-contained page about a dataset (opens offline).

Sections: the dataset's configuration summary; sample views (``mgn show`` overlays, embedded as
PNG); statistics with bar charts (embedded SVG, no scripts or remote files): objects per scene,
visible objects per view, occlusion histogram, layer distribution, difficulty levels, grasp score
histograms (parallel-jaw and suction, non-colliding), colliding share, invalid-depth share.
For large datasets the statistics are computed on an even sample of views (``max_views``).
"""

from __future__ import annotations

import base64
import html
import json
import os
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from mgn.io.dataset import Dataset, View

__all__ = ["collect_stats", "svg_bars", "write_report"]


def svg_bars(
    labels: list[str], values: list[float], *, title: str, width: int = 420, height: int = 200
) -> str:
    """An SVG bar chart (inline in HTML) of ``values`` with category ``labels``."""
    n = max(len(values), 1)
    top = max(max(values, default=0.0), 1e-12)
    left, bottom, head = 40, 28, 22
    plot_w, plot_h = width - left - 10, height - bottom - head
    bw = plot_w / n
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}">',
        f'<text x="{width / 2}" y="15" text-anchor="middle" font-size="13">{html.escape(title)}'
        "</text>",
        f'<line x1="{left}" y1="{head + plot_h}" x2="{left + plot_w}" y2="{head + plot_h}" '
        'stroke="#444"/>',
        f'<text x="{left - 4}" y="{head + 8}" text-anchor="end" font-size="10">{top:.3g}</text>',
    ]
    for k, (label, value) in enumerate(zip(labels, values, strict=True)):
        h = plot_h * value / top
        x = left + k * bw
        parts.append(
            f'<rect x="{x + 1:.1f}" y="{head + plot_h - h:.1f}" width="{max(bw - 2, 1):.1f}" '
            f'height="{h:.1f}" fill="#3b75af"><title>{html.escape(label)}: {value:g}</title></rect>'
        )
        if n <= 12 or k % max(n // 10, 1) == 0:
            parts.append(
                f'<text x="{x + bw / 2:.1f}" y="{head + plot_h + 14}" text-anchor="middle" '
                f'font-size="10">{html.escape(label)}</text>'
            )
    parts.append("</svg>")
    return "".join(parts)


def _hist(values: np.ndarray, bins: int, lo: float, hi: float) -> tuple[list[str], list[float]]:
    counts, edges = np.histogram(values, bins=bins, range=(lo, hi))
    return [f"{e:.2g}" for e in edges[:-1]], [float(c) for c in counts]


def _sample_views(ds: Dataset, max_views: int) -> list[View]:
    views = [v for s in ds.scenes() for v in s.views()]
    if len(views) <= max_views:
        return views
    idx = np.linspace(0, len(views) - 1, max_views).round().astype(int)
    return [views[i] for i in sorted(set(idx))]


def collect_stats(ds: Dataset, *, max_views: int = 400) -> dict[str, Any]:
    """Per-label statistics of ``ds`` over (a sample of) its views, JSON-ready."""
    views = _sample_views(ds, max_views)
    objects_per_scene = []
    for s in ds.scenes():
        sj = s.scene_json
        if sj is not None:
            objects_per_scene.append(len(sj.get("instances", [])))
        elif s.view_ids:
            objects_per_scene.append(s.view(s.view_ids[0]).num_instances)
    occl, visible_per_view, layers, levels = [], [], Counter(), Counter()
    scores: dict[str, list[np.ndarray]] = {"paralleljaw": [], "suctioncup": []}
    counts = {"non_colliding": Counter(), "colliding": Counter()}
    invalid = []
    for view in views:
        inst = view.instances
        vis_ids = np.unique(inst[inst > 0])
        visible_per_view.append(len(vis_ids))
        try:
            order = view.order
        except Exception:  # noqa: BLE001 (a view without layout labels)
            order = {}
        for i in vis_ids:
            entry = order.get(str(int(i)), {})
            if "occlusion" in entry:
                occl.append(float(entry["occlusion"]))
            if "layer" in entry:
                layers[int(entry["layer"])] += 1
        lay = view.layout or {}
        level = lay.get("difficulty")
        if isinstance(level, dict):
            level = level.get("level")
        if level is not None:
            levels[int(level)] += 1
        for kind in scores:
            g = view.grasps(kind)
            s = g.get("score_analytical")
            if s is not None:
                scores[kind].append(np.asarray(s, float))
                counts["non_colliding"][kind] += len(s)
            c = view.grasps(kind, colliding=True).get("score_analytical")
            if c is not None:
                counts["colliding"][kind] += len(c)
        d = view.npz["depth"]
        invalid.append(float(np.mean(~np.isfinite(d) | (d <= 0))))
    return {
        "scenes": len(ds),
        "views_sampled": len(views),
        "objects_per_scene": objects_per_scene,
        "visible_per_view": visible_per_view,
        "occlusion": occl,
        "layers": {str(k): v for k, v in sorted(layers.items())},
        "difficulty": {str(k): v for k, v in sorted(levels.items())},
        "grasp_scores": {k: (np.concatenate(v).tolist() if v else []) for k, v in scores.items()},
        "grasp_counts": {k: dict(v) for k, v in counts.items()},
        "invalid_depth_share": invalid,
    }


def _png_tag(image: np.ndarray, width: int) -> str:
    from mgn.io.scene_format import png_bytes

    data = base64.b64encode(png_bytes(image)).decode("ascii")
    return f'<img src="data:image/png;base64,{data}" width="{width}">'


def _engine_text(d: dict[str, Any]) -> str:
    if d.get("engine") == "path":
        den = "denoised (Open Image Denoise)" if d.get("denoised") else "not denoised"
        return f"path tracer, {d.get('spp', '?')} spp, {den}"
    if d.get("engine") == "raster":
        return "raster (OpenGL preview)"
    return "unknown"


def image_engines(ds: Dataset) -> str:
    """Which engine made the RGB images, as recorded per scene (``render`` of each scene's
    manifest.json) or else by the dataset's config (``render`` section of dataset.json; none:
    the raster engine, the only one before it was recorded): e.g. ``"path tracer, 16 spp,
    denoised (Open Image Denoise): 3 scenes"``."""
    counts: Counter[str] = Counter()
    for scene in ds.scenes():
        rec = None
        try:
            rec = json.loads((scene.folder / "manifest.json").read_text(encoding="utf-8"))
        except (OSError, ValueError):
            pass
        d = rec.get("render") if isinstance(rec, dict) else None
        if not isinstance(d, dict):
            cfg = (ds.info or {}).get("config", {})
            d = cfg.get("render") if isinstance(cfg, dict) else None
            d = d if isinstance(d, dict) else {"engine": "raster"}
            if d.get("engine") == "path":
                d = {"engine": "path", "spp": d.get("spp"), "denoised": d.get("denoise")}
        counts[_engine_text(d)] += 1
    if not counts:
        return "no scenes"
    return "; ".join(f"{k}: {n} scene{'s' * (n != 1)}" for k, n in sorted(counts.items()))


def write_report(
    root: str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    samples: int = 6,
    max_views: int = 400,
) -> Path:
    """Write the HTML report of the dataset at ``root`` to ``out`` (atomically)."""
    from PIL import Image

    from mgn.io.atomic import atomic_write_text
    from mgn.overlay import render_overlay

    ds = Dataset(root)
    stats = collect_stats(ds, max_views=max_views)
    charts = []
    ops = Counter(stats["objects_per_scene"])
    if ops:
        keys = list(range(min(ops), max(ops) + 1))
        charts.append(svg_bars([str(k) for k in keys], [ops[k] for k in keys],
                               title="objects per scene"))  # fmt: skip
    vpv = Counter(stats["visible_per_view"])
    if vpv:
        keys = list(range(0, max(vpv) + 1))
        charts.append(svg_bars([str(k) for k in keys], [vpv[k] for k in keys],
                               title="visible objects per view"))  # fmt: skip
    if stats["occlusion"]:
        charts.append(svg_bars(*_hist(np.array(stats["occlusion"]), 10, 0, 1),
                               title="occlusion rate of visible objects"))  # fmt: skip
    names = {"0": "top", "1": "secondary", "2": "interlock", "3": "others"}
    if stats["layers"]:
        charts.append(svg_bars([names.get(k, k) for k in stats["layers"]],
                               list(stats["layers"].values()), title="layers"))  # fmt: skip
    if stats["difficulty"]:
        lv = [str(k) for k in range(1, 6)]
        charts.append(svg_bars(lv, [stats["difficulty"].get(k, 0) for k in lv],
                               title="difficulty level of views"))  # fmt: skip
    for kind, s in stats["grasp_scores"].items():
        if s:
            charts.append(svg_bars(*_hist(np.array(s), 10, 0, 1),
                                   title=f"{kind} score (non-colliding)"))  # fmt: skip
    if stats["invalid_depth_share"]:
        charts.append(svg_bars(*_hist(np.array(stats["invalid_depth_share"]), 10, 0, 1),
                               title="invalid depth share per view"))  # fmt: skip

    all_views = [v for s in ds.scenes() for v in s.views()]
    picks = []
    if all_views:
        idx = np.linspace(0, len(all_views) - 1, min(samples, len(all_views))).round()
        picks = [all_views[int(i)] for i in sorted(set(idx.astype(int)))]
    thumbs = []
    for view in picks:
        img = render_overlay(view, layout=True)
        h, w = img.shape[:2]
        scale = min(1.0, 360 / w)
        small = np.asarray(Image.fromarray(img).resize((round(w * scale), round(h * scale))))
        thumbs.append(
            f"<figure>{_png_tag(small, small.shape[1])}<figcaption>"
            f"{html.escape(view.folder.name)} view {view.index}</figcaption></figure>"
        )
    info = ds.info or {}
    gc = stats["grasp_counts"]
    summary = {
        "scenes": stats["scenes"],
        "RGB images made by": image_engines(ds),
        "views sampled for statistics": stats["views_sampled"],
        "mgn version": info.get("mgn_version", "?"),
        "seed": info.get("seed", "?"),
        "non-colliding grasps (sampled views)": gc["non_colliding"],
        "colliding grasps (sampled views)": gc["colliding"],
    }
    rows = "".join(
        f"<tr><th>{html.escape(k)}</th><td>{html.escape(json.dumps(v))}</td></tr>"
        for k, v in summary.items()
    )
    page = f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>mgn dataset report: {html.escape(str(ds.root))}</title>
<style>body{{font-family:sans-serif;margin:20px}} figure{{display:inline-block;margin:6px}}
.charts svg{{margin:6px;border:1px solid #ddd}} th{{text-align:left;padding-right:12px}}</style>
</head><body>
<h1>mgn dataset report</h1><p>{html.escape(str(ds.root.resolve()))}</p>
<table>{rows}</table>
<h2>Sample views</h2><div>{"".join(thumbs) or "<p>no views</p>"}</div>
<h2>Statistics</h2><div class="charts">{"".join(charts) or "<p>no labels</p>"}</div>
<h2>Configuration</h2><pre>{html.escape(json.dumps(info.get("config", {}), indent=1))}</pre>
</body></html>
"""
    path = Path(out)
    atomic_write_text(path, page)
    return path
