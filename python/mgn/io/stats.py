"""``mgn stats DS [--json]``: what a dataset holds, as numbers.

:func:`dataset_stats` reads every view (or the first ``max_views``) and returns a JSON-ready
summary: scenes, views, object instances per name, label counts per grasp kind, histograms of
grasp scores (10 bins over [0, 1]), occlusion (10 bins over [0, 1]) and difficulty (levels 1-5),
and the views where nothing is visible.
"""

from __future__ import annotations

import os
from collections import Counter
from typing import Any

import numpy as np

from mgn.io.dataset import Dataset

__all__ = ["dataset_stats", "format_stats"]

_BINS = np.linspace(0.0, 1.0, 11)


def _hist(values: list[float] | np.ndarray) -> dict[str, Any]:
    v = np.asarray(values, np.float64)
    v = v[np.isfinite(v)]
    counts, _ = np.histogram(np.clip(v, 0.0, 1.0), bins=_BINS)
    return {"bins": [round(float(b), 2) for b in _BINS], "counts": counts.astype(int).tolist()}


def _spread(values: list[int]) -> dict[str, float]:
    if not values:
        return {"min": 0, "mean": 0.0, "max": 0}
    return {
        "min": int(min(values)),
        "mean": round(float(np.mean(values)), 3),
        "max": int(max(values)),
    }


def dataset_stats(root: str | os.PathLike[str], *, max_views: int | None = None) -> dict[str, Any]:
    """The summary of the dataset at ``root`` (see the module doc); ``max_views`` limits the
    views read (None = all), in scene then view order."""
    ds = Dataset(root)
    names: Counter[str] = Counter()
    per_scene: list[int] = []
    removed = 0
    for s in ds.scenes():
        sj = s.scene_json
        if sj is not None:
            per_scene.append(len(sj.get("instances", [])))
            names.update(i["name"] for i in sj.get("instances", []))
            removed += len(sj.get("removed", []))
    kinds = {"suction": "suctioncup", "paralleljaw": "paralleljaw"}
    scores: dict[str, list[np.ndarray]] = {k: [] for k in kinds}
    counts = {k: {"non_colliding": 0, "colliding": 0} for k in kinds}
    occlusion: list[float] = []
    levels: Counter[int] = Counter()
    visible: list[int] = []
    empty: list[str] = []
    nviews = 0
    for s in ds.scenes():
        for v in s.view_ids:
            if max_views is not None and nviews >= max_views:
                break
            view = s.view(v)
            nviews += 1
            inst = view.instances
            ids = np.unique(inst[inst > 0])
            visible.append(len(ids))
            if len(ids) == 0:
                empty.append(f"scene{s.scene_id}/{v}")
            order = view.order if view.path("_order.json").exists() else {}
            occlusion += [
                float(order[str(int(i))]["occlusion"])
                for i in ids
                if "occlusion" in order.get(str(int(i)), {})
            ]
            layout = view.layout if view.path("_layout.json").exists() else None
            level = (layout or {}).get("difficulty")
            if isinstance(level, dict):
                level = level.get("level")
            if level is not None:
                levels[int(level)] += 1
            for kind, folder in kinds.items():
                sc = view.grasps(folder).get("score_analytical")
                if sc is not None:
                    scores[kind].append(np.asarray(sc, np.float64))
                    counts[kind]["non_colliding"] += len(sc)
                col = view.grasps(folder, colliding=True).get("score_analytical")
                if col is not None:
                    counts[kind]["colliding"] += len(col)
    return {
        "dataset": os.fspath(root),
        "scenes": len(ds),
        "views": nviews,
        "objects": dict(sorted(names.items())),
        "objects_per_scene": _spread(per_scene),
        "objects_removed": removed,
        "visible_per_view": _spread(visible),
        "views_with_nothing_visible": empty,
        "grasp_labels": counts,
        "grasp_score_histograms": {
            k: _hist(np.concatenate(v) if v else np.zeros(0)) for k, v in scores.items()
        },
        "occlusion_histogram": _hist(occlusion),
        "difficulty": {str(k): int(levels.get(k, 0)) for k in range(1, 6)},
    }


def format_stats(st: dict[str, Any]) -> str:
    """The summary as lines of text."""
    objs = st["objects_per_scene"]
    lines = [
        f"{st['dataset']}: {st['scenes']} scenes, {st['views']} views",
        f"objects per scene: {objs['min']}-{objs['max']} (mean {objs['mean']}); "
        f"{st['objects_removed']} left the tote while dropping",
        "instances: " + ", ".join(f"{k} {v}" for k, v in st["objects"].items()),
        f"visible per view: {st['visible_per_view']['min']}-{st['visible_per_view']['max']} "
        f"(mean {st['visible_per_view']['mean']}); views with nothing visible: "
        f"{len(st['views_with_nothing_visible'])}",
        "difficulty 1-5: " + " ".join(f"{k}:{v}" for k, v in st["difficulty"].items()),
        "occlusion (0-1, 10 bins): " + " ".join(map(str, st["occlusion_histogram"]["counts"])),
    ]
    for kind, c in st["grasp_labels"].items():
        h = st["grasp_score_histograms"][kind]["counts"]
        lines.append(
            f"{kind} grasps: {c['non_colliding']} collision-free, {c['colliding']} "
            f"colliding; scores (0-1, 10 bins): {' '.join(map(str, h))}"
        )
    return "\n".join(lines)
