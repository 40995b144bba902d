"""``mgn report DIR -o report.html``: a self-contained page about a dataset (opens offline).

Sections: the dataset's configuration summary; sample views (``mgn show`` overlays, embedded as
PNG); statistics with bar charts (embedded SVG, no scripts or remote files): objects per scene,
visible objects per view, occlusion histogram, layer distribution, difficulty levels, grasp score
histograms (parallel-jaw and suction, non-colliding), colliding share, invalid-depth share.
For large datasets the statistics are computed on an even sample of views (``max_views``).
"""

from __future__ import annotations

import base64
import contextlib
import html
import json
import os
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import h5py
import numpy as np
from PIL import Image

from mgn.base.atomic import atomic_write_text
from mgn.io.dataset import Dataset, View
from mgn.io.image_codecs import png_bytes
from mgn.view_labels.grasps import COLLISION_OBSTACLES, COLLISION_PARTS
from mgn.viz.overlay import render_overlay

__all__ = ["collect_stats", "svg_bars", "write_report"]


def svg_bars(
    labels: list[str],
    values: list[float],
    *,
    title: str,
    width: int = 460,
    height: int = 240,
    xlabel: str = "",
    ylabel: str = "count",
) -> str:
    """An SVG bar chart (inline in HTML) of ``values`` with category ``labels``: a labelled
    x axis (``xlabel``) and y axis (``ylabel``, ticks at 0, half and the top), the value of
    every bar as a tooltip and, when there are few bars, as text above it."""
    n = max(len(values), 1)
    top = max(max(values, default=0.0), 1e-12)
    left, bottom, head = 52, 44, 36
    plot_w, plot_h = width - left - 10, height - bottom - head
    bw = plot_w / n
    y0 = head + plot_h
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
        'font-family="sans-serif">',
        f'<text x="{width / 2}" y="16" text-anchor="middle" font-size="14" font-weight="bold">'
        f"{html.escape(title)}</text>",
        f'<line x1="{left}" y1="{y0}" x2="{left + plot_w}" y2="{y0}" stroke="#444"/>',
        f'<line x1="{left}" y1="{head}" x2="{left}" y2="{y0}" stroke="#444"/>',
    ]
    for frac in (0.0, 0.5, 1.0):
        y = y0 - plot_h * frac
        parts.append(f'<line x1="{left - 4}" y1="{y:.1f}" x2="{left}" y2="{y:.1f}" stroke="#444"/>')
        parts.append(
            f'<text x="{left - 6}" y="{y + 4:.1f}" text-anchor="end" font-size="11">'
            f"{_tick(top * frac)}</text>"
        )
    if ylabel:
        parts.append(
            f'<text x="12" y="{head + plot_h / 2:.1f}" text-anchor="middle" '
            f'font-size="12" transform="rotate(-90 12 {head + plot_h / 2:.1f})">'
            f"{html.escape(ylabel)}</text>"
        )
    if xlabel:
        parts.append(
            f'<text x="{left + plot_w / 2:.1f}" y="{height - 6}" text-anchor="middle" '
            f'font-size="12">{html.escape(xlabel)}</text>'
        )
    for k, (label, value) in enumerate(zip(labels, values, strict=True)):
        h = plot_h * value / top
        x = left + k * bw
        parts.append(
            f'<rect x="{x + 1:.1f}" y="{y0 - h:.1f}" width="{max(bw - 2, 1):.1f}" '
            f'height="{h:.1f}" fill="#3b75af"><title>{html.escape(label)}: {value:g}</title></rect>'
        )
        if n <= 12:
            parts.append(
                f'<text x="{x + bw / 2:.1f}" y="{y0 - h - 3:.1f}" text-anchor="middle" '
                f'font-size="10" fill="#333">{value:g}</text>'
            )
        if n <= 12 or k % max(n // 10, 1) == 0:
            parts.append(
                f'<text x="{x + bw / 2:.1f}" y="{y0 + 15}" text-anchor="middle" '
                f'font-size="11">{html.escape(label)}</text>'
            )
    parts.append("</svg>")
    return "".join(parts)


def _tick(v: float) -> str:
    """A y-axis tick: whole numbers without exponent (1070, 12.5k), else 3 digits."""
    if v >= 1e4:
        return f"{v / 1e3:.3g}k"
    return f"{v:.0f}" if v >= 100 or float(v).is_integer() else f"{v:.3g}"


def _hist(values: np.ndarray, bins: int, lo: float, hi: float) -> tuple[list[str], list[float]]:
    counts, edges = np.histogram(values, bins=bins, range=(lo, hi))
    return [f"{e:.1f}" for e in edges[:-1]], [float(c) for c in counts]


def _view_refs(ds: Dataset) -> list[tuple[Path, int]]:
    """(scene folder, view index) of every view, in order (no file of a view is read)."""
    return [(s.folder, v) for s in ds.scenes() for v in s.view_ids]


def _sample_views(ds: Dataset, max_views: int) -> list[tuple[Path, int]]:
    refs = _view_refs(ds)
    if len(refs) <= max_views:
        return refs
    idx = np.linspace(0, len(refs) - 1, max_views).round().astype(int)
    return [refs[i] for i in sorted(set(idx))]


def _grasp_scores(view: View) -> dict[tuple[str, str], np.ndarray]:
    """(non_colliding | colliding, kind) -> score_analytical of the view, reading nothing else
    of its HDF5 file."""

    out = {}
    with h5py.File(view.path("_scene.hdf5"), "r") as h5:
        for group in ("non_colliding", "colliding"):
            for kind in ("paralleljaw", "suctioncup"):
                name = f"{group}_grasps/{kind}/score_analytical"
                if name in h5:
                    out[group, kind] = np.asarray(h5[name][()], float).reshape(-1)
    return out


def _collision_reasons(view: View) -> Counter[tuple[str, str, str]]:
    """(kind, gripper part, obstacle) -> number of colliding grasps of the view
    (``colliding_grasps/<kind>/collision_part`` and ``collision_obstacle``)."""
    out: Counter[tuple[str, str, str]] = Counter()
    with h5py.File(view.path("_scene.hdf5"), "r") as h5:
        for kind in ("paralleljaw", "suctioncup"):
            g = f"colliding_grasps/{kind}/"
            if g + "collision_part" in h5 and g + "collision_obstacle" in h5:
                part = np.asarray(h5[g + "collision_part"][()], int).reshape(-1)
                obst = np.asarray(h5[g + "collision_obstacle"][()], int).reshape(-1)
                for pa, ob in zip(part, obst, strict=True):
                    out[kind, COLLISION_PARTS.get(pa, "?"), COLLISION_OBSTACLES.get(ob, "?")] += 1
    return out


def collect_stats(ds: Dataset, *, max_views: int = 400) -> dict[str, Any]:
    """Per-label statistics of ``ds`` over (a sample of) its views, JSON-ready. The views are
    read one at a time, and only the arrays the statistics need: memory does not grow with the
    dataset."""
    refs = _sample_views(ds, max_views)
    objects_per_scene = []
    for s in ds.scenes():
        sj = s.scene_json
        if sj is not None:
            objects_per_scene.append(len(sj.get("instances", [])))
        elif s.view_ids:
            objects_per_scene.append(s.view(s.view_ids[0]).num_instances)
    occl: list[float] = []
    visible_per_view: list[int] = []
    layers: Counter[int] = Counter()
    levels: Counter[int] = Counter()
    scores: dict[str, list[np.ndarray]] = {"paralleljaw": [], "suctioncup": []}
    counts: dict[str, Counter[str]] = {"non_colliding": Counter(), "colliding": Counter()}
    # Why grasps collide: (kind, part, obstacle) -> count, from colliding_grasps/*/collision_*.
    why: Counter[tuple[str, str, str]] = Counter()
    invalid = []
    for folder, index in refs:
        view = View(folder, index)  # dropped after this iteration, with the arrays it read
        inst = view.npz_array("instances_objects")
        vis_ids = np.unique(inst[inst > 0])
        visible_per_view.append(len(vis_ids))
        try:
            order = view.order
        except Exception:  # a view without layout labels
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
        for (group, kind), grasp_scores in _grasp_scores(view).items():
            if group == "non_colliding":
                scores[kind].append(grasp_scores)
            counts[group][kind] += len(grasp_scores)
        for (kind, pa, ob), n in _collision_reasons(view).items():
            why[(kind, pa, ob)] += n
        d = view.npz_array("depth")
        invalid.append(float(np.mean(~np.isfinite(d) | (d <= 0))))
    return {
        "scenes": len(ds),
        "views_sampled": len(refs),
        "objects_per_scene": objects_per_scene,
        "visible_per_view": visible_per_view,
        "occlusion": occl,
        "layers": {str(k): v for k, v in sorted(layers.items())},
        "difficulty": {str(k): v for k, v in sorted(levels.items())},
        "grasp_scores": {k: (np.concatenate(v).tolist() if v else []) for k, v in scores.items()},
        "grasp_counts": {k: dict(v) for k, v in counts.items()},
        "collision_reasons": {
            kind: {f"{pa} / {ob}": n for (k, pa, ob), n in sorted(why.items()) if k == kind}
            for kind in scores
        },
        "invalid_depth_share": invalid,
    }


def _warnings(ds: Dataset, stats: dict[str, Any]) -> list[str]:
    """What a user should look at first: objects lost from the tote, views with nothing
    visible, NaN grasp scores, a low collision-free share of the grasps."""
    out = []
    lost: Counter[str] = Counter()
    for s in ds.scenes():
        for r in (s.scene_json or {}).get("removed", []):
            lost[r.get("reason", "removed")] += 1
    if lost:
        out.append(
            f"{sum(lost.values())} object(s) did not stay in the tote while dropping ("
            + ", ".join(f"{v} {k}" for k, v in lost.items())
            + "): the scenes hold fewer "
            "objects than asked"
        )
    empty = sum(1 for n in stats["visible_per_view"] if n == 0)
    if empty:
        out.append(f"{empty} of {stats['views_sampled']} sampled views show no object")
    for kind, s in stats["grasp_scores"].items():
        bad = int(np.sum(~np.isfinite(np.asarray(s, float)))) if s else 0
        if bad:
            out.append(f"{bad} {kind} grasp score(s) are NaN")
    rec = (ds.info or {}).get("physics_scores")
    if isinstance(rec, dict) and rec.get("unscored"):
        out.append(
            f"{rec['unscored']} of {rec.get('grasps', '?')} parallel-jaw grasps have no "
            f"physics score (object_labels.physics_grasps = {rec.get('cap')}): "
            "quality_score_simulation is NaN for them"
        )
    for kind in stats["grasp_counts"]["non_colliding"]:
        free = stats["grasp_counts"]["non_colliding"].get(kind, 0)
        hit = stats["grasp_counts"]["colliding"].get(kind, 0)
        if free + hit and free / (free + hit) < 0.05:
            share = 100 * free / (free + hit)
            out.append(
                f"only {share:.1f}% of the {kind} grasps are collision-free in the "
                "scenes (gripper too large for the clutter?)"
            )
    return out


def _physics_text(rec: Any) -> str:
    """The ``dataset.json`` ``physics_scores`` record in words."""
    if not isinstance(rec, dict):
        return "not run"
    cap = rec.get("cap")
    text = (
        f"{rec.get('scored', '?')} of {rec.get('grasps', '?')} stored grasps scored "
        f"({rec.get('search', '?')} search, {rec.get('grid', '?')}x{rec.get('grid', '?')} grid"
    )
    if rec.get("unscored"):
        capped = ", ".join(rec.get("capped_objects", []))
        return text + f"; capped at {cap} per object, {rec['unscored']} left NaN: {capped})"
    return text + ("; no cap)" if cap is None else f"; cap {cap} not reached)")


def _png_tag(image: np.ndarray, width: int) -> str:

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
        with contextlib.suppress(OSError, ValueError):
            rec = json.loads((scene.folder / "manifest.json").read_text(encoding="utf-8"))
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


def _charts(stats: dict[str, Any]) -> list[str]:
    """The SVG bar charts of the report's statistics."""
    charts = []
    ops = Counter(stats["objects_per_scene"])
    if ops:
        keys = list(range(min(ops), max(ops) + 1))
        charts.append(
            svg_bars(
                [str(k) for k in keys],
                [ops[k] for k in keys],
                title="objects per scene",
                xlabel="objects in the tote",
                ylabel="scenes",
            )
        )
    vpv = Counter(stats["visible_per_view"])
    if vpv:
        keys = list(range(0, max(vpv) + 1))
        charts.append(
            svg_bars(
                [str(k) for k in keys],
                [vpv[k] for k in keys],
                title="visible objects per view",
                xlabel="objects visible",
                ylabel="views",
            )
        )
    if stats["occlusion"]:
        charts.append(
            svg_bars(
                *_hist(np.array(stats["occlusion"]), 10, 0, 1),
                title="occlusion rate of visible objects",
                xlabel="occluded share of the object (bin start)",
                ylabel="objects",
            )
        )
    names = {"0": "top", "1": "secondary", "2": "interlock", "3": "others"}
    if stats["layers"]:
        charts.append(
            svg_bars(
                [names.get(k, k) for k in stats["layers"]],
                list(stats["layers"].values()),
                title="layers",
                xlabel="layer (top = nothing lies on it)",
                ylabel="objects",
            )
        )
    if stats["difficulty"]:
        lv = [str(k) for k in range(1, 6)]
        charts.append(
            svg_bars(
                lv,
                [stats["difficulty"].get(k, 0) for k in lv],
                title="difficulty level of views",
                xlabel="level (1 easy - 5 hard)",
                ylabel="views",
            )
        )
    for kind, s in stats["grasp_scores"].items():
        if s:
            charts.append(
                svg_bars(
                    *_hist(np.array(s), 10, 0, 1),
                    title=f"{kind.replace('suctioncup', 'suction')} score (non-colliding)",
                    xlabel="analytic score (bin start)",
                    ylabel="grasps",
                )
            )
    if stats["invalid_depth_share"]:
        charts.append(
            svg_bars(
                *_hist(np.array(stats["invalid_depth_share"]), 10, 0, 1),
                title="invalid depth share per view",
                xlabel="share of pixels without depth (bin start)",
                ylabel="views",
            )
        )
    return charts


def write_report(
    root: str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    samples: int = 6,
    max_views: int = 400,
    progress: bool = False,
) -> Path:
    """Write the HTML report of the dataset at ``root`` to ``out`` (atomically). ``progress``
    prints what is being done to stderr."""

    def step(text: str) -> None:
        if progress:
            print(f"mgn report: {text}", file=sys.stderr, flush=True)

    ds = Dataset(root)
    step(f"statistics of up to {max_views} views of {len(ds)} scenes ...")
    stats = collect_stats(ds, max_views=max_views)
    charts = _charts(stats)

    all_views = _view_refs(ds)
    picks = []
    if all_views:
        idx = np.linspace(0, len(all_views) - 1, min(samples, len(all_views))).round()
        picks = [all_views[int(i)] for i in sorted(set(idx.astype(int)))]
    thumbs = []
    for i, (folder, index) in enumerate(picks):
        view = View(folder, index)
        step(f"sample view {i + 1}/{len(picks)}: {view.folder.name} view {view.index}")
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

    def kinds(counter: dict[str, int]) -> str:
        names = {"suctioncup": "suction"}
        return ", ".join(f"{names.get(k, k)} {v}" for k, v in counter.items()) or "none"

    summary = {
        "scenes": str(stats["scenes"]),
        "RGB images made by": image_engines(ds),
        "views sampled for statistics": str(stats["views_sampled"]),
        "mgn version": str(info.get("mgn_version", "?")),
        "seed": str(info.get("seed", "?")),
        "non-colliding grasps (sampled views)": kinds(gc["non_colliding"]),
        "colliding grasps (sampled views)": kinds(gc["colliding"]),
        "parallel-jaw physics scores": _physics_text(info.get("physics_scores")),
    }
    for kind, split in stats.get("collision_reasons", {}).items():
        if split:
            summary[f"why {kind} grasps collide (part / obstacle)"] = ", ".join(
                f"{k} {n}" for k, n in sorted(split.items(), key=lambda kv: -kv[1])
            )
    rows = "".join(
        f"<tr><th>{html.escape(k)}</th><td>{html.escape(v)}</td></tr>" for k, v in summary.items()
    )
    warnings = _warnings(ds, stats)
    warn_html = (
        '<div class="warn"><h2>Warnings</h2><ul>'
        + "".join(f"<li>{html.escape(w)}</li>" for w in warnings)
        + "</ul></div>"
        if warnings
        else '<p class="ok">No warnings: no object lost from the tote, every sampled view shows '
        "objects, no NaN labels.</p>"
    )
    config = html.escape(json.dumps(info.get("config", {}), indent=1))
    step("writing the page")
    page = f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>mgn dataset report: {html.escape(str(ds.root))}</title>
<style>body{{font-family:sans-serif;margin:20px}} figure{{display:inline-block;margin:6px}}
.charts svg{{margin:6px;border:1px solid #ddd}} th{{text-align:left;padding-right:12px}}
.warn{{background:#fff4e5;border:1px solid #f0a030;padding:4px 12px;margin:10px 0}}
.ok{{color:#2a7a2a}} summary{{cursor:pointer;font-weight:bold;font-size:1.2em}}</style>
</head><body>
<h1>mgn dataset report</h1><p>{html.escape(str(ds.root.resolve()))}</p>
{warn_html}
<table>{rows}</table>
<h2>Sample views</h2><div>{"".join(thumbs) or "<p>no views</p>"}</div>
<h2>Statistics</h2><div class="charts">{"".join(charts) or "<p>no labels</p>"}</div>
<details><summary>Configuration (click to unfold)</summary><pre>{config}</pre></details>
</body></html>
"""
    path = Path(out)
    atomic_write_text(path, page)
    return path
