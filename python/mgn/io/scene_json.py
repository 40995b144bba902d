"""``scene.json``: a dropped :class:`mgn.scene.Scene` as JSON (layout in :mod:`mgn.scene.scene`).

The scene turns itself into plain data (``Scene.to_dict`` / ``Scene.from_dict``); this module
owns the file: JSON text, atomic write, read errors naming the file.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from mgn.base.atomic import atomic_write_text
from mgn.errors import InvalidArgumentError, IoError
from mgn.scene.scene import Scene

__all__ = ["read_scene_json", "write_scene_json"]


def write_scene_json(scene: Scene, path: str | os.PathLike[str]) -> Path:
    """Write ``scene`` as JSON (atomically). Returns the path."""
    text = json.dumps(scene.to_dict(), indent=1, allow_nan=False)
    atomic_write_text(path, text + "\n")
    return Path(path)


def read_scene_json(path: str | os.PathLike[str]) -> Scene:
    """Read a scene written by :func:`write_scene_json`.

    Raises:
        IoError: the file does not exist.
        InvalidArgumentError: the file is not valid JSON or not a scene (names the problem).
    """
    p = Path(path)
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError as e:
        raise IoError(f"read_scene_json: file not found: '{p}'") from e
    except json.JSONDecodeError as e:
        raise InvalidArgumentError(f"read_scene_json: '{p}' is not valid JSON: {e}") from e
    return Scene.from_dict(data)
