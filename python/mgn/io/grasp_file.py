"""The grasp groups of an object's ``textured.obj.hdf5`` (docs/format.md): atomic updates, the
parallel-jaw and suction label writers, the parallel-jaw reader."""

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
import numpy.typing as npt

from mgn.base.atomic import disk_full_error, disk_full_message
from mgn.base.units import M_TO_CM
from mgn.errors import IoError
from mgn.pj.labels import PjLabels
from mgn.suction.labels import SuctionLabels

#: Empty datasets written for a grasp group that has no labels yet (readers open both groups).
EMPTY_GROUPS: dict[str, dict[str, tuple[int, ...]]] = {
    "grasps/paralleljaw": {"pregrasp_transform": (0, 10), "quality_score": (0,)},
    "grasps/suctioncup": {"pregrasp_transform": (0, 6), "quality_score": (0,)},
}


def create_labels_file(hdf5_path: str | os.PathLike[str]) -> None:
    """Create the labels file of a bare mesh file: an HDF5 file with an empty
    ``grasps/paralleljaw`` group (its parent folder is created)."""
    path = Path(hdf5_path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with h5py.File(path, "w") as h5:
        h5.create_group("grasps/paralleljaw")


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
        tmp.replace(path)
    except (OSError, RuntimeError) as e:  # h5py reports some write failures as RuntimeError
        if disk_full_error(e) is not None:
            raise IoError(f"{who}: {disk_full_message(path)}") from e
        if not isinstance(e, OSError):
            raise
        raise IoError(f"{who}: cannot update '{path}': {e}") from e
    finally:
        if tmp.exists():
            tmp.unlink()


def write_pj_labels(hdf5_path: str | os.PathLike[str], labels: PjLabels) -> None:
    """Replace ``grasps/paralleljaw/*`` of an object's ``textured.obj.hdf5`` (docs/format.md).

    Writes ``pregrasp_transform`` (M, 10) [a (3), v (3), p1 (3, cm), w (cm)],
    ``quality_score`` (M,) (analytic), ``quality_score_simulation`` (M,) (NaN when physics was
    not run) and the mgn extension ``score_wrench`` (M,), all float32, plus the metadata
    attributes. Other groups (suction labels, keypoints) are kept. The file is updated on a
    temporary copy that replaces the original only when complete.
    """
    replace_grasp_group(
        hdf5_path,
        "grasps/paralleljaw",
        {
            "pregrasp_transform": labels.pregrasp_transform().reshape(-1, 10),
            "quality_score": labels.quality_score,
            "quality_score_simulation": labels.quality_score_simulation,
            "score_wrench": labels.score_wrench,
        },
        labels.metadata,
        who="write_pj_labels",
    )


def read_pj_labels(hdf5_path: str | os.PathLike[str]) -> dict[str, npt.NDArray[np.float64]]:
    """The ``grasps/paralleljaw`` datasets of a file in metres: approach, closing, p1 (M, 3),
    width, quality_score, quality_score_simulation, score_wrench (M,) (absent ones omitted)."""
    with h5py.File(hdf5_path, "r") as h5:
        g = h5["grasps/paralleljaw"]
        pre = np.asarray(g["pregrasp_transform"], np.float64).reshape(-1, 10)
        out = {
            "approach": pre[:, 0:3],
            "closing": pre[:, 3:6],
            "p1": pre[:, 6:9] / M_TO_CM,
            "width": pre[:, 9] / M_TO_CM,
        }
        for name in ("quality_score", "quality_score_simulation", "score_wrench"):
            if name in g:
                out[name] = np.asarray(g[name], np.float64)
    return out


def write_suction_labels(hdf5_path: str | os.PathLike[str], labels: SuctionLabels) -> None:
    """Replace ``grasps/suctioncup/*`` of an object's ``textured.obj.hdf5`` (docs/format.md).

    Writes ``pregrasp_transform`` (K, 6) [approach (3, into the surface), contact (3, cm)],
    ``quality_score`` (K,) (seal score) and the mgn extensions ``quality_score_simulation``
    (K,) (physics score: seal score x hold score, docs/models.md §3a; written when the labels
    have it), ``score_wrench`` (K,) and ``failure_reason`` (K,) (uint8 codes of
    ``mgn.suction.FAILURE_REASONS``; the others float32), plus the metadata attributes. The
    file is updated on a temporary copy that replaces the original only when complete.
    """
    datasets = {
        "pregrasp_transform": np.concatenate(
            [labels.approach, labels.points * M_TO_CM], axis=1
        ).reshape(-1, 6),
        "quality_score": labels.score,
    }
    if labels.simulation is not None:
        datasets["quality_score_simulation"] = labels.simulation
    datasets["score_wrench"] = labels.wrench
    datasets["failure_reason"] = labels.reason
    replace_grasp_group(
        hdf5_path,
        "grasps/suctioncup",
        datasets,
        labels.metadata,
        who="write_suction_labels",
    )
