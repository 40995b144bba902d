"""What a ``mgn generate`` run records about itself in ``dataset.json``, and what ``--resume``
checks against that record.

- :func:`dataset_doc`: the content of ``dataset.json`` (:data:`DATASET_SCHEMA_VERSION`, the mgn
  version, the full config, the seed, the scene count and rule of the scene seeds, the
  ``status``); :func:`physics_record` its ``physics_scores``. Written (atomically) by
  :func:`mgn.io.dataset_record.write_dataset_record`.
- :func:`check_resume`: the recorded seed, split and config must be those of the resumed run
  (``selection.max_scenes`` and ``output`` may change); :func:`clean_tmp` removes the temporary
  folders a stopped run left behind.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from mgn._core import __version__
from mgn.errors import InvalidArgumentError, IoError
from mgn.io.dataset_record import read_dataset_record
from mgn.pipeline.config import Config
from mgn.pipeline.exports import clean_export_tmp
from mgn.pipeline.label_cache import ObjectLabels
from mgn.pipeline.scene_task import TMP_PREFIX
from mgn.pipeline.seeds import SCENE_SEED_RULE
from mgn.render.settings import RenderSettings

__all__ = [
    "DATASET_SCHEMA_VERSION",
    "check_resume",
    "clean_tmp",
    "dataset_doc",
    "physics_record",
]

#: ``schema_version`` of ``dataset.json``.
DATASET_SCHEMA_VERSION = 1


def dataset_doc(
    config: Config, seed: int, num_scenes: int, status: str, **extra: Any
) -> dict[str, Any]:
    """The content of ``dataset.json`` of a run with ``config`` and ``seed``; ``extra``: further
    keys (``split``, ``selection``, ``removed_objects``, ``error``, ...)."""
    return {
        "schema_version": DATASET_SCHEMA_VERSION,
        "mgn_version": __version__,
        "seed": int(seed),
        "num_scenes": int(num_scenes),
        "scene_seed": SCENE_SEED_RULE,
        "scene_folders": "scene<i>, i = 0..num_scenes-1",
        "depth_invalid": "NaN",
        "config": config.to_dict(),
        "splits": {"train": [], "val": [], "test": []},
        "status": status,
        **extra,
    }


def physics_record(config: Config, labels: Mapping[str, ObjectLabels]) -> dict[str, Any] | None:
    """``dataset.json`` ``physics_scores``: how the parallel-jaw physics scores were made and how
    many stored grasps of each object got one (``scored``) or kept NaN because of the cap
    ``object_labels.physics_grasps`` (``unscored``). None without physics labels."""

    if not (config.labels.paralleljaw and config.labels.pj_physics):
        return None
    ol = config.object_labels
    objects: dict[str, dict[str, int]] = {}
    for name in sorted(labels):
        pj = labels[name].paralleljaw
        if pj is None:
            continue
        sim = np.asarray(pj.quality_score_simulation)
        scored = int(np.count_nonzero(np.isfinite(sim)))
        objects[name] = {"grasps": int(sim.shape[0]), "scored": scored}
    total = sum(o["grasps"] for o in objects.values())
    scored = sum(o["scored"] for o in objects.values())
    return {
        "cap": ol.physics_grasps,
        "search": ol.physics_search,
        "checks": ol.staircase_checks if ol.physics_search == "staircase" else None,
        "calibration": ol.physics_calibration if ol.physics_search == "staircase" else None,
        "calibration_min": (
            ol.physics_calibration_min if ol.physics_search == "staircase" else None
        ),
        "grid": ol.physics_grid,
        "grasps": total,
        "scored": scored,
        "unscored": total - scored,
        "capped_objects": sorted(n for n, o in objects.items() if o["scored"] < o["grasps"]),
        "objects": objects,
    }


def clean_tmp(out: Path) -> list[Path]:
    """Remove the temporary folders of scenes (:data:`TMP_PREFIX`) and exports under ``out``;
    returns the folders removed."""
    removed = []
    for p in out.glob(f"{TMP_PREFIX}*"):
        if p.is_dir():
            shutil.rmtree(p, ignore_errors=True)
            removed.append(p)
    return removed + clean_export_tmp(out)


def _comparable(config_doc: Any) -> Any:
    """A config dict as compared by ``--resume`` (``selection.max_scenes`` and ``output`` may
    change: the exports are made from the scene folders, which they do not change)."""
    doc = json.loads(json.dumps(config_doc))
    if isinstance(doc, dict) and isinstance(doc.get("selection"), dict):
        doc["selection"].pop("max_scenes", None)
    if isinstance(doc, dict):
        doc.pop("output", None)
    if isinstance(doc, dict) and "render" not in doc:
        # Recorded before the render section existed: those images came from the raster.

        doc["render"] = json.loads(json.dumps(Config(render=RenderSettings()).to_dict()["render"]))
    return doc


def check_resume(out: Path, config: Config, seed: int) -> dict[str, Any] | None:
    """The recorded ``dataset.json`` of ``out`` (None: nothing started yet), checked against
    the seed and config of the resumed run."""
    try:
        doc = read_dataset_record(out)
    except IoError as e:
        raise IoError(f"--resume: {e}") from e
    if doc is None:
        return None  # nothing started yet: a fresh run
    if doc.get("seed") != seed:
        raise InvalidArgumentError(
            f"--resume: '{out}' was generated with seed {doc.get('seed')}, got --seed {seed}"
        )
    recorded: dict[str, Any] = doc["config"] if isinstance(doc.get("config"), dict) else {}
    split = json.loads(json.dumps(config.split.to_dict()))
    if recorded.get("split", {"name": "all", "unseen": "novel"}) != split:
        raise InvalidArgumentError(
            f"--resume: '{out}' was generated with split {recorded.get('split')}, got {split} "
            "(--split / config key 'split'); use the same split or a new output folder"
        )
    diffs = _config_differences(_comparable(recorded), _comparable(config.to_dict()))
    if diffs:
        shown = "; ".join(f"{k}: recorded {a!r}, now {b!r}" for k, a, b in diffs[:5])
        more = f" (and {len(diffs) - 5} more)" if len(diffs) > 5 else ""
        raise InvalidArgumentError(
            f"--resume: the config differs from the one recorded in '{out / 'dataset.json'}' in "
            f"{len(diffs)} key(s): {shown}{more}; use the same config (or a new output folder)"
        )
    return doc


_MISSING = "<not set>"


def _config_differences(recorded: Any, current: Any, key: str = "") -> list[tuple[str, Any, Any]]:
    """(dotted key, recorded value, current value) of every leaf where two config dicts
    differ, in key order; a key only one side has shows ``<not set>`` on the other."""
    if isinstance(recorded, dict) and isinstance(current, dict):
        out: list[tuple[str, Any, Any]] = []
        for k in sorted(set(recorded) | set(current), key=str):
            sub = f"{key}.{k}" if key else str(k)
            out += _config_differences(recorded.get(k, _MISSING), current.get(k, _MISSING), sub)
        return out
    return [] if recorded == current else [(key or "<config>", recorded, current)]
