"""The other layouts ``mgn generate`` writes as it goes (config ``output.formats``).

After a scene's folder ``DIR/scene<N>`` is complete, :func:`export_scene` writes the scene in
each layout of ``output.formats`` besides ``mgn``, with the same functions and defaults as
``mgn export``:

- ``bop``: ``DIR/bop/`` (:func:`mgn.io.bop.export_bop_scene`: ``train_pbr/<N:06d>/``, depth
  scale 0.1 mm; the models by :func:`mgn.io.bop.write_bop_models` when the run's objects are
  labelled);
- ``graspnet``: ``DIR/graspnet/`` (:func:`mgn.io.graspnet.export_graspnet_scene`:
  ``scenes/scene_<N:04d>/mgn/``, the analytical parallel-jaw score, seal x wrench for suction,
  rectangles within 20 degrees of the optical axis).

Each scene's export is built under a temporary name and renamed when complete, so it is either
whole or absent; :func:`missing_exports` finds the layouts a complete scene still lacks (the
run was stopped between the scene and its export, or the export failed), which ``--resume``
writes, and :func:`clean_export_tmp` removes the temporary folders a killed run left. One view
is in memory at a time: the memory does not grow with the number of scenes. The exported files
are the bytes ``mgn export bop DIR DIR/bop`` and ``mgn export graspnet DIR DIR/graspnet`` write.
"""

from __future__ import annotations

import re
import shutil
import time
from collections.abc import Sequence
from pathlib import Path

from mgn.errors import InvalidArgumentError
from mgn.hardware import ParallelJawGripper
from mgn.io.bop import DEFAULT_SPLIT, export_bop_scene, write_bop_models
from mgn.io.dataset import SceneFolder
from mgn.io.graspnet import DEFAULT_CAMERA, export_graspnet_scene, graspnet_gripper

__all__ = [
    "EXPORT_FOLDERS",
    "clean_export_tmp",
    "export_models",
    "export_scene",
    "missing_exports",
]

#: The folder of ``DIR`` each export layout goes to.
EXPORT_FOLDERS = {"bop": "bop", "graspnet": "graspnet"}

# Temporary names of mgn.base.atomic: ".<name>.<random>.tmp" (atomic_dir, atomic files) and
# ".<name>.old-<pid>" (a folder being replaced).
_TMP_RE = re.compile(r"^\..+(\.tmp|\.old-\d+)$")


def _scene_target(out: Path, fmt: str, index: int) -> Path:
    if fmt == "bop":
        return out / EXPORT_FOLDERS["bop"] / DEFAULT_SPLIT / f"{index:06d}"
    if fmt == "graspnet":
        return out / EXPORT_FOLDERS["graspnet"] / "scenes" / f"scene_{index:04d}" / DEFAULT_CAMERA
    raise InvalidArgumentError(f"output.formats: no export layout {fmt!r}")


def missing_exports(out: Path, index: int, formats: Sequence[str]) -> list[str]:
    """The layouts of ``formats`` (``mgn`` ignored) whose export of scene ``index`` is not in
    ``out``."""
    return [f for f in formats if f != "mgn" and not _scene_target(out, f, index).is_dir()]


def export_models(out: Path, formats: Sequence[str]) -> None:
    """Bring the models of the exports (BOP's ``models/``) up to date with ``out/models/``."""
    if "bop" in formats:
        write_bop_models(out, out / EXPORT_FOLDERS["bop"])


def export_scene(
    out: Path, index: int, formats: Sequence[str], gripper: ParallelJawGripper
) -> dict[str, float]:
    """Write the exports of the complete scene folder ``out/scene<index>`` for the layouts of
    ``formats`` (``mgn`` ignored) that do not have it yet; ``gripper``: the dataset's
    (``config.gripper``). Returns the wall seconds per layout written (``"export: bop"``,
    ``"export: graspnet"``)."""
    scene = SceneFolder(out / f"scene{index}", index)
    times: dict[str, float] = {}
    for fmt in formats:
        if fmt == "mgn":
            continue
        t0 = time.perf_counter()
        root = out / EXPORT_FOLDERS[fmt]
        if fmt == "bop":
            done = export_bop_scene(scene, root)
        else:
            done = export_graspnet_scene(scene, root, graspnet_gripper(gripper))
        if done:
            times[f"export: {fmt}"] = time.perf_counter() - t0
    return times


def clean_export_tmp(out: Path) -> list[Path]:
    """Remove the temporary files and folders a stopped run left in the export folders of
    ``out`` (half-written scene exports, models, JSON files); returns what was removed."""
    # Where atomic_dir and the atomic files put them: the export folder, its models / split
    # folders (BOP), and the scene folders holding the camera folders (GraspNet).
    patterns = {"bop": (".*", "*/.*"), "graspnet": (".*", "scenes/.*", "scenes/*/.*")}
    removed: list[Path] = []
    for fmt, globs in patterns.items():
        root = out / EXPORT_FOLDERS[fmt]
        if not root.is_dir():
            continue
        for pattern in globs:
            for p in sorted(root.glob(pattern)):
                if not _TMP_RE.match(p.name):
                    continue
                if p.is_dir():
                    shutil.rmtree(p, ignore_errors=True)
                else:
                    p.unlink(missing_ok=True)
                removed.append(p)
    return removed
