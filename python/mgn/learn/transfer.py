"""``mgn transfer``: which dataset variant trains the model that works best on your photographs?

An ablation harness: for every *variant* of a generation config, generate a dataset (or use an
existing one), train the same baseline on it several times (*replicates*: each with its own
training seed and, optionally, its own dataset seed), and evaluate every model
(:func:`mgn.learn.real_eval.evaluate_real`) on the same labelled real set and on held-out
synthetic views of every variant. The table gives each metric's mean, standard deviation
(n - 1) and range over the replicates, and two paired comparisons with the first variant (the
reference): *replicate wins* (for how many replicates the variant's model beats the reference's
model of the same replicate) and *image wins* (over every (replicate, image) pair of the real
set, how many images the variant's model scores higher than the reference's model of the same
replicate, lower, or the same; with a two-sided sign-test p-value over the pairs that differ).

The spec is a YAML file (or a mapping)::

    real: photos/                  # labelled real set (mgn eval real layouts); or --real
    scenes: 12                     # scenes per generated dataset (default 12)
    generate_seed: 0               # dataset seed, the same for every variant (default 0)
    seeds: [0, 1, 2]               # training seeds, one per replicate (default 0 1 2)
    generate_seeds: [0, 1, 2]      # optional: one dataset seed per replicate (as many as seeds)
    heldout_scenes: 2              # scenes of each variant's held-out set (default 2; 0: none)
    heldout_seed: 1000             # their dataset seed (default 1000 + the largest training one)
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
        dataset: my_dataset/       # an existing dataset instead of a generated one (with
                                   # generate_seeds: a list, one dataset per replicate)
        heldout: my_heldout/       # optional: an existing dataset as its held-out set

Without ``generate_seeds`` replicate k trains with ``seeds[k]`` on the variant's one dataset
(dataset seed ``generate_seed``); with it, on a dataset of its own generated with
``generate_seeds[k]``, so that the spread over the replicates covers which piles a dataset
happens to hold as well as the training's randomness.

A generated variant's held-out set is ``heldout_scenes`` scenes of the variant's config with the
dataset seed ``heldout_seed`` (other piles than any training set); a variant with ``dataset:``
has the ``heldout:`` dataset or none. Each held-out set is exported as class-agnostic COCO
(:func:`mgn.io.coco.coco_dict`, as ``mgn coco --class-agnostic``) with its images and the
sensor's depth (``<stem>_depth.npy``, m) beside them, and every model is scored on every
variant's held-out set: a matrix of training variant x held-out variant.

Relative paths are taken relative to the spec file. Everything goes to ``out``:

- ``<variant>/dataset/`` (with ``generate_seeds``: ``<variant>/dataset_g<G>/``), generated;
  resumed when present;
- ``<variant>/heldout/`` (the generated held-out dataset) and ``<variant>/heldout_coco/`` (its
  COCO folder);
- ``<variant>/seed<S>/`` (with ``generate_seeds``: ``<variant>/g<G>_seed<S>/``): ``model.pt``
  etc., ``real/`` and ``heldout_<variant>/`` (``results.json`` and ``report.html`` of each
  evaluation);
- ``transfer.json``, ``transfer.md`` (the real-set table, then the held-out matrices) and
  ``transfer.png`` (one column per variant: a dot per replicate and a bar at the mean, on the
  real set and on the variant's own held-out views).

An interrupted harness continues where it stopped: a finished model is not trained again and
an evaluation whose ``results.json`` is newer than its model (and of the same set) is read back.
"""

from __future__ import annotations

import io
import json
import os
import re
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image, ImageDraw

from mgn.base.atomic import atomic_write_bytes, atomic_write_text
from mgn.base.yaml_file import read_yaml
from mgn.errors import InvalidArgumentError
from mgn.io.coco import coco_dict
from mgn.io.dataset import Dataset, View
from mgn.learn.config import ModelConfig, TrainConfig
from mgn.learn.pictures import instance_palette
from mgn.learn.real_eval import evaluate_real
from mgn.learn.training import train
from mgn.pipeline import generate
from mgn.pipeline.config import Config

__all__ = ["HELDOUT_METRICS", "METRICS", "TransferResults", "run_transfer", "sign_test"]

#: Metrics tabulated (keys of :meth:`mgn.learn.real_eval.RealResults.summary`).
METRICS = ("mask_AP", "mask_AP50", "fg_IoU", "suction_P@1", "suction_P@5")
#: Metrics of the held-out matrices (the held-out sets have no suction labels).
HELDOUT_METRICS = ("fg_IoU", "mask_AP50")
#: Per-image keys of ``RealResults.per_image`` for the metrics that have one.
_PER_IMAGE = {
    "mask_AP": "mask_AP",
    "mask_AP50": "mask_AP50",
    "fg_IoU": "foreground_iou",
    "suction_P@1": "suction_P@1",
    "suction_P@5": "suction_P@5",
}
#: Offset of the default held-out dataset seed above the largest training dataset seed.
HELDOUT_SEED_OFFSET = 1000
_SPEC_KEYS = {
    "real",
    "scenes",
    "generate_seed",
    "generate_seeds",
    "seeds",
    "heldout_scenes",
    "heldout_seed",
    "metric",
    "config",
    "model",
    "train",
    "variants",
}
_VARIANT_KEYS = {"name", "config", "model", "train", "dataset", "heldout"}

#: A replicate's key: the training seed (one dataset per variant) or ``"g<G>_seed<S>"``.
Replicate = int | str


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


def _int(value: Any, key: str, *, minimum: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise InvalidArgumentError(f"transfer spec: '{key}' must be a whole number, got {value!r}")
    if minimum is not None and value < minimum:
        raise InvalidArgumentError(f"transfer spec: '{key}' must be >= {minimum}, got {value}")
    return int(value)


def _int_list(value: Any, key: str) -> list[int]:
    if not isinstance(value, (list, tuple)) or not value:
        raise InvalidArgumentError(
            f"transfer spec: '{key}' must be a non-empty list of whole numbers, got {value!r}"
        )
    return [_int(v, f"{key}[{i}]") for i, v in enumerate(value)]


def sign_test(wins: int, losses: int) -> float | None:
    """Two-sided sign-test p-value of ``wins`` against ``losses`` (ties left out): the
    probability, were either side equally likely to win each pair, of a split at least as
    uneven; None without pairs."""
    n = wins + losses
    if n == 0:
        return None
    from scipy.stats import binomtest

    return float(binomtest(wins, n, 0.5, alternative="two-sided").pvalue)


@dataclass
class TransferResults:
    """Scores of every (variant, replicate) model and the tables.

    Attributes:
        variants: names, in the spec's order (the first is the reference).
        seeds: training seeds, one per replicate.
        metric: the metric of the paired wins.
        scores: {variant: {replicate: {metric: value}}} on the real set; a replicate is its
            training seed, or ``"g<G>_seed<S>"`` with ``generate_seeds``.
        rows: one dict per variant: mean, std, min, max of each metric, wins, image wins.
        generate_seeds: dataset seeds, one per replicate (None: one dataset per variant).
        per_image: {variant: {replicate: [{metric: value} per real image]}} (the metrics of
            ``_PER_IMAGE``; None where an image has none).
        heldout: {training variant: {held-out variant: {replicate: {metric: value}}}}.
        heldout_rows: one dict per (training variant, held-out variant): mean and std of each
            of :data:`HELDOUT_METRICS`.
    """

    variants: list[str]
    seeds: list[int]
    metric: str
    scores: dict[str, dict[Replicate, dict[str, float | None]]]
    rows: list[dict[str, Any]] = field(default_factory=list)
    generate_seeds: list[int] | None = None
    per_image: dict[str, dict[Replicate, list[dict[str, float | None]]]] = field(
        default_factory=dict
    )
    heldout: dict[str, dict[str, dict[Replicate, dict[str, float | None]]]] = field(
        default_factory=dict
    )
    heldout_rows: list[dict[str, Any]] = field(default_factory=list)

    @property
    def replicates(self) -> list[Replicate]:
        """The replicates' keys, in order."""
        if self.generate_seeds is None:
            return list(self.seeds)
        return [f"g{g}_seed{s}" for g, s in zip(self.generate_seeds, self.seeds, strict=True)]

    def _image_metrics(self) -> list[str]:
        """The metrics of the image-wins columns: ``fg_IoU`` and the harness metric."""
        return list(dict.fromkeys(["fg_IoU", self.metric]))

    def table(self) -> str:
        """The real-set Markdown table: per variant the mean ± std [min, max] of each metric,
        the replicate wins and the image wins (wins/pairs, ties, sign-test p)."""
        metrics = [m for m in METRICS if any(r.get(f"{m} mean") is not None for r in self.rows)]
        ref = self.variants[0]
        image_metrics = [
            m for m in self._image_metrics() if any(r.get(f"image {m}") for r in self.rows)
        ]
        head = [
            "variant",
            *metrics,
            f"wins vs {ref} ({self.metric})",
            *[f"image wins vs {ref} ({m})" for m in image_metrics],
        ]
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
            for m in image_metrics:
                w = r.get(f"image {m}")
                if not w:
                    cells.append("-")
                    continue
                p = "-" if w["p"] is None else f"{w['p']:.2g}"
                cells.append(f"{w['wins']}/{w['pairs']}, {w['ties']} tied, p {p}")
            lines.append("| " + " | ".join(cells) + " |")
        return "\n".join(lines)

    def heldout_table(self) -> str:
        """The held-out Markdown matrices, one per metric of :data:`HELDOUT_METRICS`: rows the
        training variant, columns the held-out variant, cells mean ± std over the replicates
        (empty when no variant has a held-out set)."""
        cols = [h for h in self.variants if any(h in d for d in self.heldout.values())]
        if not cols:
            return ""
        by = {(r["train"], r["heldout"]): r for r in self.heldout_rows}
        parts = []
        for m in HELDOUT_METRICS:
            head = ["trained on \\ held-out views of", *cols]
            lines = [
                f"Held-out synthetic views, {m} (mean ± std over the replicates):",
                "",
                "| " + " | ".join(head) + " |",
                "|" + "---|" * len(head),
            ]
            for t in self.variants:
                cells = [t]
                for h in cols:
                    r = by.get((t, h), {})
                    mean = r.get(f"{m} mean")
                    cells.append("-" if mean is None else f"{mean:.3f} ± {r[f'{m} std']:.3f}")
                lines.append("| " + " | ".join(cells) + " |")
            parts.append("\n".join(lines))
        return "\n\n".join(parts)

    def markdown(self) -> str:
        """``transfer.md``: the real-set table, then the held-out matrices."""
        held = self.heldout_table()
        return f"Real set:\n\n{self.table()}\n" + (f"\n{held}\n" if held else "")

    def to_dict(self) -> dict[str, Any]:
        doc: dict[str, Any] = {
            "variants": self.variants,
            "seeds": self.seeds,
            "metric": self.metric,
            "scores": {v: {str(s): m for s, m in d.items()} for v, d in self.scores.items()},
            "rows": self.rows,
        }
        if self.generate_seeds is not None:
            doc["generate_seeds"] = self.generate_seeds
        doc["heldout"] = {
            t: {h: {str(s): m for s, m in d.items()} for h, d in row.items()}
            for t, row in self.heldout.items()
        }
        doc["heldout_rows"] = self.heldout_rows
        return doc


def _stats(
    values: Sequence[float | None],
) -> tuple[float | None, float, float | None, float | None]:
    arr = np.array([v for v in values if v is not None], np.float64)
    if not len(arr):
        return None, 0.0, None, None
    std = float(arr.std(ddof=1)) if len(arr) > 1 else 0.0
    return float(arr.mean()), std, float(arr.min()), float(arr.max())


def _image_wins(res: TransferResults, name: str, metric: str) -> dict[str, Any] | None:
    """Per-image paired comparison of ``name`` with the reference on ``metric``."""
    ref = res.per_image.get(res.variants[0], {})
    mine = res.per_image.get(name, {})
    wins = losses = ties = 0
    for rep in res.replicates:
        a_imgs, b_imgs = mine.get(rep), ref.get(rep)
        if a_imgs is None or b_imgs is None:
            continue
        for a_img, b_img in zip(a_imgs, b_imgs, strict=True):
            a, b = a_img.get(metric), b_img.get(metric)
            if a is None or b is None:
                continue
            wins += a > b
            losses += a < b
            ties += a == b
    pairs = wins + losses + ties
    if not pairs:
        return None
    return {
        "wins": wins,
        "losses": losses,
        "ties": ties,
        "pairs": pairs,
        "p": sign_test(wins, losses),
    }


def _rows(res: TransferResults) -> list[dict[str, Any]]:
    ref = res.scores[res.variants[0]]
    rows = []
    for name in res.variants:
        row: dict[str, Any] = {"variant": name}
        for m in METRICS:
            vals = [v.get(m) for v in res.scores[name].values()]
            row[f"{m} mean"], row[f"{m} std"], row[f"{m} min"], row[f"{m} max"] = _stats(vals)
        pairs: list[tuple[float, float]] = []
        for s in res.replicates:
            a, b = res.scores[name][s].get(res.metric), ref[s].get(res.metric)
            if a is not None and b is not None:
                pairs.append((a, b))
        wins = sum(a > b for a, b in pairs)
        row["wins"] = "-" if name == res.variants[0] else f"{wins}/{len(pairs)}"
        if name != res.variants[0] and res.per_image:
            for m in METRICS:
                row[f"image {m}"] = _image_wins(res, name, m)
        rows.append(row)
    return rows


def _heldout_rows(res: TransferResults) -> list[dict[str, Any]]:
    rows = []
    for t in res.variants:
        for h, reps in res.heldout.get(t, {}).items():
            row: dict[str, Any] = {"train": t, "heldout": h}
            for m in HELDOUT_METRICS:
                mean, std, lo, hi = _stats([v.get(m) for v in reps.values()])
                row[f"{m} mean"], row[f"{m} std"] = mean, std
                row[f"{m} min"], row[f"{m} max"] = lo, hi
            rows.append(row)
    return rows


def _panel(
    draw: ImageDraw.ImageDraw,
    columns: Sequence[tuple[str, list[float]]],
    title: str,
    y0: int,
    height: int,
) -> None:
    """One panel of :func:`_plot`: per column a dot per value and a bar at their mean."""
    left, bottom, top = 60, 50, 30

    def y(v: float) -> float:
        return y0 + top + (1.0 - min(max(v, 0.0), 1.0)) * (height - top - bottom)

    right = left + 140 * len(columns) + 20
    for tick in np.linspace(0, 1, 6):
        draw.line([(left, y(tick)), (right, y(tick))], fill=(225, 225, 225))
        draw.text((8, y(tick) - 6), f"{tick:.1f}", fill=(0, 0, 0))
    draw.text((left, y0 + 8), title, fill=(0, 0, 0))
    colors = instance_palette(len(columns))
    for k, (name, vals) in enumerate(columns):
        cx = left + 70 + 140 * k
        col = tuple(int(c) for c in colors[k])
        if vals:
            mean = float(np.mean(vals))
            draw.line([(cx - 35, y(mean)), (cx + 35, y(mean))], fill=col, width=3)
        else:
            draw.text((cx - 12, y(0.5)), "none", fill=(150, 150, 150))
        for j, v in enumerate(vals):
            dx = (j - (len(vals) - 1) / 2) * 10
            draw.ellipse([cx + dx - 4, y(v) - 4, cx + dx + 4, y(v) + 4], fill=col)
        draw.text((cx - 60, y0 + height - bottom + 12), name[:20], fill=(0, 0, 0))


def _heldout_metric(metric: str) -> str:
    return metric if metric in HELDOUT_METRICS else "fg_IoU"


def _plot(res: TransferResults) -> bytes:
    """Real set: dots per replicate and a bar at the mean, one column per variant, metric in
    [0, 1]; below it the same for each variant's own held-out views, when there are any."""
    h = 360
    real = [
        (n, [float(x) for v in res.scores[n].values() if (x := v.get(res.metric)) is not None])
        for n in res.variants
    ]
    hm = _heldout_metric(res.metric)
    own = {n: res.heldout.get(n, {}).get(n, {}) for n in res.variants}
    diag = [
        (n, [float(x) for v in own[n].values() if (x := v.get(hm)) is not None])
        for n in res.variants
    ]
    w = 140 * len(res.variants) + 80
    with_heldout = any(vals for _, vals in diag)
    im = Image.new("RGB", (w, h * (2 if with_heldout else 1)), (255, 255, 255))
    draw = ImageDraw.Draw(im)
    _panel(draw, real, f"real set: {res.metric} per replicate (dots) and mean (bar)", 0, h)
    if with_heldout:
        _panel(draw, diag, f"own held-out synthetic views: {hm}", h, h)
    buf = io.BytesIO()
    im.save(buf, format="PNG")
    return buf.getvalue()


def _spec(spec: str | os.PathLike[str] | Mapping[str, Any]) -> tuple[dict[str, Any], Path]:
    if isinstance(spec, Mapping):
        return dict(spec), Path.cwd()
    path = Path(spec)
    data = read_yaml(path, "transfer spec")
    return _mapping(data, f"'{path}'"), path.parent


def _generate(config: Config, ds: Path, scenes: int, seed: int, name: str, progress: bool) -> Path:
    report = generate(ds, scenes, config=config, seed=seed, resume=ds.exists(), progress=progress)
    if not report.complete:
        raise InvalidArgumentError(
            f"variant {name}: the dataset '{ds}' is incomplete: {report.format_summary()}"
        )
    return ds


def _heldout_coco(ds: Path, out: Path) -> Path:
    """The class-agnostic COCO folder of dataset ``ds`` in ``out`` (images copied, sensor depth
    ``<stem>_depth.npy`` beside them; kept when present); returns its ``annotations.json``."""
    js = out / "annotations.json"
    if js.exists():
        return js
    d = Dataset(ds)
    doc = coco_dict(d, class_agnostic=True)
    out.mkdir(parents=True, exist_ok=True)
    for image in doc["images"]:
        sid, vid = int(image["scene_id"]), int(image["view_id"])
        name = f"scene{sid}_view{vid}.png"  # no "_rgb.png": read as COCO, not as MGN scenes
        view = View(d.scene(sid).folder, vid)
        shutil.copyfile(ds / image["file_name"], out / name)
        buf = io.BytesIO()
        np.save(buf, view.depth)
        atomic_write_bytes(out / f"scene{sid}_view{vid}_depth.npy", buf.getvalue())
        image["file_name"] = name
    atomic_write_text(js, json.dumps(doc) + "\n")
    return js


def _evaluate(
    model: Path, data: Path, out: Path, device: str, num_threads: int
) -> tuple[dict[str, float | None], list[dict[str, float | None]]]:
    """Summary metrics and per-image metrics of ``model`` on ``data``; read back from
    ``out/results.json`` when that is newer than the model and of the same set."""
    js = out / "results.json"
    doc: dict[str, Any] | None = None
    if js.exists() and js.stat().st_mtime_ns >= model.stat().st_mtime_ns:
        try:
            doc = json.loads(js.read_text())
        except (OSError, ValueError):
            doc = None
        if not (
            isinstance(doc, dict)
            and doc.get("source") == os.fspath(data)
            and all("mask_AP50" in e for e in doc.get("per_image", []))
        ):
            doc = None
    if doc is None:
        res = evaluate_real(
            model, data, out, device=device, num_threads=num_threads, progress=False
        )
        doc = res.to_dict()
    summary = doc["summary"]
    per_image = [{m: e.get(k) for m, k in _PER_IMAGE.items()} for e in doc["per_image"]]
    return {m: summary.get(m) for m in METRICS}, per_image


@dataclass
class _Variant:
    name: str
    spec: dict[str, Any]
    datasets: list[Path | None]  # one per replicate; None: generated
    heldout: Path | None  # an existing held-out dataset


def _variants(
    data: dict[str, Any], here: Path, n_replicates: int, replicated_data: bool
) -> list[_Variant]:
    variants = data.get("variants")
    if not isinstance(variants, list) or not variants:
        raise InvalidArgumentError("transfer spec: 'variants' must be a non-empty list")
    out: list[_Variant] = []
    for v in variants:
        if not isinstance(v, Mapping) or not re.fullmatch(r"[A-Za-z0-9_.-]+", str(v.get("name"))):
            raise InvalidArgumentError(
                f"transfer spec: each variant needs a 'name' of letters, "
                f"digits, '.', '_', '-'; got {v!r}"
            )
        name = str(v["name"])
        bad = sorted(set(v) - _VARIANT_KEYS)
        if bad:
            raise InvalidArgumentError(
                f"transfer spec: variant {name}: unknown key(s) "
                f"{bad}; known: {sorted(_VARIANT_KEYS)}"
            )
        datasets: list[Path | None] = [None] * n_replicates
        if "dataset" in v:
            given = v["dataset"]
            if replicated_data:
                if not isinstance(given, (list, tuple)) or len(given) != n_replicates:
                    raise InvalidArgumentError(
                        f"transfer spec: variant {name}: with 'generate_seeds' its 'dataset' "
                        f"must be a list of {n_replicates} dataset folders (one per "
                        f"replicate), got {given!r}"
                    )
                datasets = [here / str(p) for p in given]
            else:
                if not isinstance(given, (str, os.PathLike)):
                    raise InvalidArgumentError(
                        f"transfer spec: variant {name}: 'dataset' must be one dataset folder "
                        f"(a list only with 'generate_seeds'), got {given!r}"
                    )
                datasets = [here / str(given)] * n_replicates
        if "heldout" in v and "dataset" not in v:
            raise InvalidArgumentError(
                f"transfer spec: variant {name}: 'heldout' names the held-out set of a variant "
                "with 'dataset'; a generated variant's held-out set is generated "
                "('heldout_scenes')"
            )
        if "heldout" in v and not isinstance(v["heldout"], (str, os.PathLike)):
            raise InvalidArgumentError(
                f"transfer spec: variant {name}: 'heldout' must be one dataset folder, "
                f"got {v['heldout']!r}"
            )
        heldout = here / str(v["heldout"]) if "heldout" in v else None
        out.append(_Variant(name, dict(v), datasets, heldout))
    names = [v.name for v in out]
    if len(set(names)) != len(names):
        raise InvalidArgumentError(f"transfer spec: variant names repeat: {names}")
    return out


@dataclass
class _Settings:
    seeds: list[int]
    generate_seeds: list[int] | None
    replicates: list[tuple[int | None, int]]  # (dataset seed or None, training seed)
    scenes: int
    generate_seed: int
    heldout_scenes: int
    heldout_seed: int
    metric: str


def _settings(data: dict[str, Any], seeds: Sequence[int] | None) -> _Settings:
    """The spec's scalar keys, checked (errors name the key)."""
    seed_list = (
        _int_list(list(seeds), "seeds (--seeds)")
        if seeds is not None
        else _int_list(data.get("seeds", [0, 1, 2]), "seeds")
    )
    scenes = _int(data.get("scenes", 12), "scenes", minimum=1)
    generate_seed = _int(data.get("generate_seed", 0), "generate_seed")
    gseeds: list[int] | None = None
    if "generate_seeds" in data:
        gseeds = _int_list(data["generate_seeds"], "generate_seeds")
        if len(gseeds) != len(seed_list):
            raise InvalidArgumentError(
                f"transfer spec: 'generate_seeds' has {len(gseeds)} entries but 'seeds' has "
                f"{len(seed_list)}: one dataset seed per training seed (replicate)"
            )
    reps: list[tuple[int | None, int]] = (
        list(zip(gseeds, seed_list, strict=True)) if gseeds else [(None, s) for s in seed_list]
    )
    if len(set(reps)) != len(reps):
        raise InvalidArgumentError(
            "transfer spec: replicates repeat: "
            + ("('generate_seeds', 'seeds') pairs " if gseeds else "'seeds' ")
            + f"{reps if gseeds else seed_list}"
        )
    heldout_scenes = _int(data.get("heldout_scenes", 2), "heldout_scenes", minimum=0)
    train_gseeds = gseeds or [generate_seed]
    heldout_seed = _int(
        data.get("heldout_seed", max(train_gseeds) + HELDOUT_SEED_OFFSET), "heldout_seed"
    )
    if heldout_scenes and heldout_seed in train_gseeds:
        raise InvalidArgumentError(
            f"transfer spec: 'heldout_seed' {heldout_seed} is a training dataset seed "
            f"({train_gseeds}): the held-out views would be the training piles"
        )
    metric = str(data.get("metric", "mask_AP50"))
    if metric not in METRICS:
        raise InvalidArgumentError(
            f"transfer spec: metric must be one of {METRICS}, got {metric!r}"
        )
    return _Settings(
        seed_list, gseeds, reps, scenes, generate_seed, heldout_scenes, heldout_seed, metric
    )


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
    st = _settings(data, seeds)
    variants = _variants(data, here, len(st.replicates), st.generate_seeds is not None)
    base_cfg = data.get("config")
    base = (
        _mapping(read_yaml(here / base_cfg, "config file"), str(base_cfg))
        if isinstance(base_cfg, (str, os.PathLike))
        else _mapping(base_cfg, "config")
    )
    out_dir = Path(out)

    def config_of(v: _Variant) -> Config:
        over = _mapping(v.spec.get("config"), f"variant {v.name}: config")
        return Config.from_dict(_merge(base, over), base_dir=here)

    # Held-out sets first: every model is scored on all of them.
    heldout_sets: dict[str, Path] = {}
    for v in variants:
        if v.heldout is not None:
            heldout_sets[v.name] = _heldout_coco(v.heldout, out_dir / v.name / "heldout_coco")
        elif v.datasets[0] is None and st.heldout_scenes:
            ds = _generate(
                config_of(v),
                out_dir / v.name / "heldout",
                st.heldout_scenes,
                st.heldout_seed,
                v.name,
                progress,
            )
            heldout_sets[v.name] = _heldout_coco(ds, out_dir / v.name / "heldout_coco")

    result = TransferResults([v.name for v in variants], st.seeds, st.metric, {})
    result.generate_seeds = st.generate_seeds
    for v in variants:
        mc = ModelConfig.from_dict(
            _merge(
                _mapping(data.get("model"), "model"),
                _mapping(v.spec.get("model"), f"variant {v.name}: model"),
            )
        )
        tdict = _merge(
            _mapping(data.get("train"), "train"),
            _mapping(v.spec.get("train"), f"variant {v.name}: train"),
        )
        result.scores[v.name] = {}
        result.per_image[v.name] = {}
        result.heldout[v.name] = {h: {} for h in heldout_sets}
        generated: dict[int | None, Path] = {}  # by dataset seed: each generated once
        for k, ((gseed, seed), rep) in enumerate(
            zip(st.replicates, result.replicates, strict=True)
        ):
            given = v.datasets[k]
            if given is not None:
                ds = given
            elif gseed in generated:
                ds = generated[gseed]
            else:
                folder = "dataset" if gseed is None else f"dataset_g{gseed}"
                g = st.generate_seed if gseed is None else gseed
                ds = generated[gseed] = _generate(
                    config_of(v), out_dir / v.name / folder, st.scenes, g, v.name, progress
                )
            run = out_dir / v.name / (f"seed{seed}" if gseed is None else f"g{gseed}_seed{seed}")
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
            model = run / "model.pt"
            summary, per_image = _evaluate(model, real_set, run / "real", device, num_threads)
            result.scores[v.name][rep] = summary
            result.per_image[v.name][rep] = per_image
            for h, hset in heldout_sets.items():
                hs, _ = _evaluate(model, hset, run / f"heldout_{h}", device, num_threads)
                result.heldout[v.name][h][rep] = {m: hs.get(m) for m in HELDOUT_METRICS}
    result.rows = _rows(result)
    result.heldout_rows = _heldout_rows(result)
    atomic_write_text(out_dir / "transfer.json", json.dumps(result.to_dict(), indent=1) + "\n")
    atomic_write_text(out_dir / "transfer.md", result.markdown())
    atomic_write_bytes(out_dir / "transfer.png", _plot(result))
    return result
