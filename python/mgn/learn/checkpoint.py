"""Model and checkpoint files of :mod:`mgn.learn` (``torch.save`` dicts of tensors and plain
values, written atomically, read with ``weights_only=True``).

- ``model.pt``: ``{"format": "mgn-learn-model", "model_config", "state_dict", "training"}`` --
  what ``mgn predict`` and ``mgn eval real`` load;
- ``checkpoint.pt``: the whole training state after the last finished epoch
  (``"format": "mgn-learn-checkpoint"``, the configs, the views, the epoch, the model and
  optimizer state, the loss history) -- what ``mgn train --resume`` continues from.
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any

from mgn.base.atomic import atomic_write_bytes
from mgn.errors import IoError
from mgn.learn.backend import require_torch

__all__ = ["CHECKPOINT_FORMAT", "MODEL_FORMAT", "read_torch_file", "write_torch_file"]

MODEL_FORMAT = "mgn-learn-model"
CHECKPOINT_FORMAT = "mgn-learn-checkpoint"


def write_torch_file(path: str | os.PathLike[str], obj: dict[str, Any]) -> None:
    """``torch.save(obj)`` to ``path``, atomically."""
    torch = require_torch()
    buf = io.BytesIO()
    torch.save(obj, buf)
    atomic_write_bytes(path, buf.getvalue())


def read_torch_file(path: str | os.PathLike[str], expected_format: str) -> dict[str, Any]:
    """A file written by :func:`write_torch_file` whose ``"format"`` is ``expected_format``
    (tensors on the CPU). IoError naming the file when it is missing, unreadable or of
    another kind."""
    torch = require_torch()
    p = Path(path)
    try:
        data = p.read_bytes()
    except FileNotFoundError:
        raise IoError(f"'{p}' does not exist") from None
    except OSError as e:
        raise IoError(f"'{p}' is not readable: {e}") from e
    try:
        obj = torch.load(io.BytesIO(data), map_location="cpu", weights_only=True)
    except Exception as e:  # torch raises pickle, zip and runtime errors of many kinds
        raise IoError(f"'{p}' is not a readable mgn model file: {e}") from e
    if not isinstance(obj, dict) or obj.get("format") != expected_format:
        found = obj.get("format") if isinstance(obj, dict) else type(obj).__name__
        raise IoError(f"'{p}' is not an {expected_format} file (found {found!r})")
    return obj
