"""``mgn transfer``: which dataset variant trains the model that works best on your photographs?

An ablation harness: for every *variant* of a generation config, generate a dataset (or use an
existing one), train the same baseline with several seeds on it, evaluate every model on the
same labelled real set (:func:`mgn.learn.real_eval.evaluate_real`), and tabulate each metric's
mean, standard deviation (n - 1) and range over the seeds, plus *paired wins*: for how many
seeds the variant's model beats the first variant's model trained with the same seed.

The spec is a YAML file (or a mapping)::

    real: photos/                  # labelled real set (mgn eval real layouts); or --real
    scenes: 12                     # scenes per generated dataset (default 12)
    generate_seed: 0               # dataset seed, the same for every variant (default 0)
    seeds: [0, 1, 2]               # training seeds (default 0 1 2)
    metric: mask_AP50              # metric of the wins and the plot (default mask_AP50)
    config: base.yaml              # base generation config: a file or a mapping (default: none)
    model: {image_size: 256}       # ModelConfig keys for every variant
    train: {epochs: 10}            # TrainConfig keys for every variant (seed from seeds)
    variants:
      - name: baseline             # the reference of the paired wins
      - name: tof
        config: {camera: {sensor: tof}}   # merged into the base config, key by key
      - name: rgbd
        model: {modality: rgbd}
      - name: mine
        dataset: my_dataset/       # an existing dataset instead of a generated one

Relative paths are taken relative to the spec file. Everything goes to ``out``:
``<variant>/dataset/`` (generated; resumed when present), ``<variant>/seed<k>/`` (``model.pt``
etc.; a finished model is kept and not trained again, so an interrupted harness continues
where it stopped) with ``real/results.json``, and ``transfer.json``, ``transfer.md`` (the
table) and ``transfer.png`` (one column per variant: a dot per seed, a bar at the mean).
"""

from __future__ import annotations

import io
import json
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image, ImageDraw

from mgn.base.atomic import atomic_write_bytes, atomic_write_text
from mgn.base.yaml_file import read_yaml
from mgn.errors import InvalidArgumentError
from mgn.learn.config import ModelConfig, TrainConfig
from mgn.learn.pictures import instance_palette
from mgn.learn.real_eval import evaluate_real
from mgn.learn.training import train
from mgn.pipeline import generate
from mgn.pipeline.config import Config

__all__ = ["METRICS", "TransferResults", "run_transfer"]

#: Metrics tabulated (keys of :meth:`mgn.learn.real_eval.RealResults.summary`).
METRICS = ("mask_AP", "mask_AP50", "fg_IoU", "suction_P@1", "suction_P@5")
_SPEC_KEYS = {
    "real",
    "scenes",
    "generate_seed",
    "seeds",
    "metric",
    "config",
    "model",
    "train",
    "variants",
}
_VARIANT_KEYS = {"name", "config", "model", "train", "dataset"}


def _merge(base: Mapping[str, Any], over: Mapping[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for k, v in over.items():
        out[k] = (
            _merge(out[k], v) if isinstance(v, Mapping) and isinstance(out.get(k), Mapping) else v
        )
    return out


def _mapping(value: Any, what: str) -> dict[str, Any]:
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise InvalidArgumentError(f"transfer spec: {what} must be a mapping, got {value!r}")
    return dict(value)


@dataclass
class TransferResults:
    """Scores of every (variant, seed) model and the table.

    Attributes:
        variants: names, in the spec's order (the first is the reference).
        seeds: training seeds.
        metric: the metric of the paired wins.
        scores: {variant: {seed: {metric: value}}}.
        rows: one dict per variant: mean, std, min, max of each metric, wins.
    """

    variants: list[str]
    seeds: list[int]
    metric: str
    scores: dict[str, dict[int, dict[str, float | None]]]
    rows: list[dict[str, Any]] = field(default_factory=list)

    def table(self) -> str:
        """A Markdown table: per variant the mean ± std [min, max] of each metric and wins."""
        metrics = [m for m in METRICS if any(r.get(f"{m} mean") is not None for r in self.rows)]
        head = ["variant", *metrics, f"wins vs {self.variants[0]} ({self.metric})"]
        lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for r in self.rows:
            cells = [r["variant"]]
            for m in metrics:
                mean = r.get(f"{m} mean")
                cells.append(
                    "-"
                    if mean is None
                    else f"{mean:.3f} ± {r[f'{m} std']:.3f} "
                    f"[{r[f'{m} min']:.3f}, {r[f'{m} max']:.3f}]"
                )
            cells.append(r["wins"])
            lines.append("| " + " | ".join(cells) + " |")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        return {
            "variants": self.variants,
            "seeds": self.seeds,
            "metric": self.metric,
            "scores": {v: {str(s): m for s, m in d.items()} for v, d in self.scores.items()},
            "rows": self.rows,
        }


def _rows(res: TransferResults) -> list[dict[str, Any]]:
    ref = res.scores[res.variants[0]]
    rows = []
    for name in res.variants:
        row: dict[str, Any] = {"variant": name}
        for m in METRICS:
            vals = [v[m] for v in res.scores[name].values() if v.get(m) is not None]
            arr = np.array(vals, np.float64)
            row[f"{m} mean"] = float(arr.mean()) if len(arr) else None
            row[f"{m} std"] = float(arr.std(ddof=1)) if len(arr) > 1 else 0.0
            row[f"{m} min"] = float(arr.min()) if len(arr) else None
            row[f"{m} max"] = float(arr.max()) if len(arr) else None
        pairs: list[tuple[float, float]] = []
        for s in res.seeds:
            a, b = res.scores[name][s].get(res.metric), ref[s].get(res.metric)
            if a is not None and b is not None:
                pairs.append((a, b))
        wins = sum(a > b for a, b in pairs)
        row["wins"] = "-" if name == res.variants[0] else f"{wins}/{len(pairs)}"
        rows.append(row)
    return rows


def _plot(res: TransferResults) -> bytes:
    """Dots per seed and a bar at the mean, one column per variant, metric in [0, 1]."""
    w, h, left, bottom, top = 140 * len(res.variants) + 80, 360, 60, 50, 30
    im = Image.new("RGB", (w, h), (255, 255, 255))
    draw = ImageDraw.Draw(im)

    def y(v: float) -> float:
        return top + (1.0 - min(max(v, 0.0), 1.0)) * (h - top - bottom)

    for tick in np.linspace(0, 1, 6):
        draw.line([(left, y(tick)), (w - 20, y(tick))], fill=(225, 225, 225))
        draw.text((8, y(tick) - 6), f"{tick:.1f}", fill=(0, 0, 0))
    draw.text((left, 8), f"{res.metric} per seed (dots) and mean (bar)", fill=(0, 0, 0))
    colors = instance_palette(len(res.variants))
    for k, name in enumerate(res.variants):
        cx = left + 70 + 140 * k
        vals = [float(x) for v in res.scores[name].values() if (x := v.get(res.metric)) is not None]
        col = tuple(int(c) for c in colors[k])
        if vals:
            draw.line(
                [(cx - 35, y(float(np.mean(vals)))), (cx + 35, y(float(np.mean(vals))))],
                fill=col,
                width=3,
            )
        for j, v in enumerate(vals):
            dx = (j - (len(vals) - 1) / 2) * 10
            draw.ellipse([cx + dx - 4, y(v) - 4, cx + dx + 4, y(v) + 4], fill=col)
        draw.text((cx - 60, h - bottom + 12), name[:20], fill=(0, 0, 0))
    buf = io.BytesIO()
    im.save(buf, format="PNG")
    return buf.getvalue()


def _spec(spec: str | os.PathLike[str] | Mapping[str, Any]) -> tuple[dict[str, Any], Path]:
    if isinstance(spec, Mapping):
        return dict(spec), Path.cwd()
    path = Path(spec)
    data = read_yaml(path, "transfer spec")
    return _mapping(data, f"'{path}'"), path.parent


def _variant_dataset(
    v: dict[str, Any],
    spec: dict[str, Any],
    base: dict[str, Any],
    here: Path,
    out: Path,
    progress: bool,
) -> Path:
    if "dataset" in v:
        return here / str(v["dataset"])
    config = Config.from_dict(
        _merge(base, _mapping(v.get("config"), "a variant's config")), base_dir=here
    )
    ds = out / str(v["name"]) / "dataset"
    report = generate(
        ds,
        int(spec.get("scenes", 12)),
        config=config,
        seed=int(spec.get("generate_seed", 0)),
        resume=ds.exists(),
        progress=progress,
    )
    if not report.complete:
        raise InvalidArgumentError(
            f"variant {v['name']}: the dataset '{ds}' is incomplete: {report.format_summary()}"
        )
    return ds


def run_transfer(
    spec: str | os.PathLike[str] | Mapping[str, Any],
    out: str | os.PathLike[str],
    *,
    real: str | os.PathLike[str] | None = None,
    seeds: Sequence[int] | None = None,
    device: str = "auto",
    num_threads: int = 0,
    progress: bool = True,
) -> TransferResults:
    """Run the harness of ``spec`` (module docstring) into ``out``; ``real`` and ``seeds``
    override the spec's."""
    data, here = _spec(spec)
    unknown = sorted(set(data) - _SPEC_KEYS)
    if unknown:
        raise InvalidArgumentError(
            f"transfer spec: unknown key(s) {unknown}; known: {sorted(_SPEC_KEYS)}"
        )
    real_set = Path(real) if real is not None else (here / data["real"] if "real" in data else None)
    if real_set is None:
        raise InvalidArgumentError("transfer: no real set (spec key 'real' or --real)")
    variants = data.get("variants")
    if not isinstance(variants, list) or not variants:
        raise InvalidArgumentError("transfer spec: 'variants' must be a non-empty list")
    names = []
    for v in variants:
        if not isinstance(v, Mapping) or not re.fullmatch(r"[A-Za-z0-9_.-]+", str(v.get("name"))):
            raise InvalidArgumentError(
                f"transfer spec: each variant needs a 'name' of letters, "
                f"digits, '.', '_', '-'; got {v!r}"
            )
        bad = sorted(set(v) - _VARIANT_KEYS)
        if bad:
            raise InvalidArgumentError(
                f"transfer spec: variant {v['name']}: unknown key(s) "
                f"{bad}; known: {sorted(_VARIANT_KEYS)}"
            )
        names.append(str(v["name"]))
    if len(set(names)) != len(names):
        raise InvalidArgumentError(f"transfer spec: variant names repeat: {names}")
    seed_list = [int(s) for s in (seeds if seeds is not None else data.get("seeds", [0, 1, 2]))]
    metric = str(data.get("metric", "mask_AP50"))
    if metric not in METRICS:
        raise InvalidArgumentError(
            f"transfer spec: metric must be one of {METRICS}, got {metric!r}"
        )
    base_cfg = data.get("config")
    base = (
        _mapping(read_yaml(here / base_cfg, "config file"), str(base_cfg))
        if isinstance(base_cfg, (str, os.PathLike))
        else _mapping(base_cfg, "config")
    )
    out_dir = Path(out)
    scores: dict[str, dict[int, dict[str, float | None]]] = {}
    for v in variants:
        v = dict(v)
        ds = _variant_dataset(v, data, base, here, out_dir, progress)
        mc = ModelConfig.from_dict(
            _merge(
                _mapping(data.get("model"), "model"), _mapping(v.get("model"), "a variant's model")
            )
        )
        tdict = _merge(_mapping(data.get("train"), "train"), _mapping(v.get("train"), "train"))
        scores[v["name"]] = {}
        for seed in seed_list:
            run = out_dir / v["name"] / f"seed{seed}"
            if not (run / "model.pt").exists():
                tc = TrainConfig.from_dict(tdict | {"seed": seed})
                train(
                    ds,
                    run,
                    model_config=mc,
                    train_config=tc,
                    resume=True,
                    device=device,
                    num_threads=num_threads,
                    progress=progress,
                )
            res = evaluate_real(
                run / "model.pt",
                real_set,
                run / "real",
                device=device,
                num_threads=num_threads,
                progress=False,
            )
            scores[v["name"]][seed] = {m: res.summary().get(m) for m in METRICS}
    result = TransferResults(names, seed_list, metric, scores)
    result.rows = _rows(result)
    atomic_write_text(out_dir / "transfer.json", json.dumps(result.to_dict(), indent=1) + "\n")
    atomic_write_text(out_dir / "transfer.md", result.table() + "\n")
    atomic_write_bytes(out_dir / "transfer.png", _plot(result))
    return result
