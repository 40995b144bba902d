"""``dataset.json``: the record of a ``mgn generate`` run (docs/format.md).

The pipeline decides what the record holds (schema version, mgn version, config, seed, status,
split, selection, removed objects); this module writes and reads the file.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from mgn.base.atomic import atomic_write_text
from mgn.errors import IoError

__all__ = ["DATASET_RECORD", "read_dataset_record", "removed_objects", "write_dataset_record"]

#: File name of the record in the dataset folder.
DATASET_RECORD = "dataset.json"


def write_dataset_record(out: Path, doc: dict[str, Any]) -> Path:
    """Write ``doc`` as ``out/dataset.json`` (atomically). Returns the path."""
    path = Path(out) / DATASET_RECORD
    atomic_write_text(path, json.dumps(doc, indent=1) + "\n")
    return path


def read_dataset_record(out: Path) -> dict[str, Any] | None:
    """``out/dataset.json`` as a dict; None if the file does not exist.

    Raises:
        IoError: the file exists but cannot be read or is not JSON (names the file).
    """
    path = Path(out) / DATASET_RECORD
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None
    except (OSError, ValueError) as e:
        raise IoError(f"cannot read '{path}': {e}") from e
    if not isinstance(doc, dict):
        raise IoError(f"cannot read '{path}': expected a JSON object, got {type(doc).__name__}")
    return doc


def removed_objects(out: Path) -> dict[str, Any]:
    """The record's ``removed_objects``: the objects that left the tote during the drops of the
    scenes present (read from each ``scene*/scene.json``, so resumed runs count every scene)."""
    by_scene: dict[str, list[str]] = {}
    dropped = 0
    for sj in sorted(Path(out).glob("scene*/scene.json")):
        try:
            doc = json.loads(sj.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        dropped += int(doc.get("stats", {}).get("num_dropped", len(doc.get("instances", []))))
        names = [str(r.get("name")) for r in doc.get("removed", [])]
        if names:
            by_scene[sj.parent.name.removeprefix("scene")] = names
    return {
        "count": sum(len(v) for v in by_scene.values()),
        "dropped": dropped,
        "by_scene": dict(sorted(by_scene.items(), key=lambda kv: int(kv[0]))),
    }
