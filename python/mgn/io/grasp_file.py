"""Atomic updates of the grasp groups of an object's ``textured.obj.hdf5`` (docs/format.md)."""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from mgn.errors import IoError

#: Empty datasets written for a grasp group that has no labels yet (readers open both groups).
EMPTY_GROUPS: dict[str, dict[str, tuple[int, ...]]] = {
    "grasps/paralleljaw": {"pregrasp_transform": (0, 10), "quality_score": (0,)},
    "grasps/suctioncup": {"pregrasp_transform": (0, 6), "quality_score": (0,)},
}


def replace_grasp_group(
    hdf5_path: str | os.PathLike[str],
    group: str,
    datasets: Mapping[str, np.ndarray],
    metadata: Mapping[str, Any],
    *,
    who: str,
) -> None:
    """Replace ``group`` (e.g. ``"grasps/suctioncup"``) of an existing HDF5 file with
    ``datasets`` (written as float32; integer arrays, e.g. ``failure_reason``, keep their integer
    type) and merge ``metadata`` into the ``metadata`` group's
    attributes (dicts and lists as JSON). The other groups are kept; an absent grasp group of
    :data:`EMPTY_GROUPS` is created empty. The update is made on a temporary copy that replaces
    the file only when complete, keeping its permissions.

    Raises:
        IoError: naming ``who`` and the file, if it does not exist or cannot be updated.
    """
    path = Path(hdf5_path)
    if not path.is_file():
        raise IoError(f"{who}: '{path}' does not exist (export the object first)")
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        shutil.copyfile(path, tmp)
        with h5py.File(tmp, "a") as h5:
            if group in h5:
                del h5[group]
            g = h5.require_group(group)
            for name, data in datasets.items():
                a = np.asarray(data)
                if not np.issubdtype(a.dtype, np.integer):
                    a = a.astype(np.float32)
                g.create_dataset(name, data=a)
            for other, shapes in EMPTY_GROUPS.items():
                if other not in h5:
                    e = h5.require_group(other)
                    for name, shape in shapes.items():
                        e.create_dataset(name, data=np.zeros(shape, np.float32))
            meta = h5.require_group("metadata")
            for key, value in metadata.items():
                meta.attrs[key] = json.dumps(value) if isinstance(value, (dict, list)) else value
        shutil.copymode(path, tmp)
        os.replace(tmp, path)
    except OSError as e:
        raise IoError(f"{who}: cannot update '{path}': {e}") from e
    finally:
        if tmp.exists():
            tmp.unlink()
