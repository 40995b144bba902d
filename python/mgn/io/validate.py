"""``mgn validate DIR``: check every file of a dataset against the schema of docs/format.md.

Reports, per file, what is missing or corrupt (unreadable, wrong keys, shapes, dtypes, values out
of range, inconsistent with the other files of the view, checksum different from the manifest).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mgn.io.dataset import Dataset, SceneFolder, View
from mgn.io.manifest import MANIFEST, check_manifest
from mgn.io.scene_folder import HDF5_FLOAT_KEYS, view_file_names

__all__ = ["Problem", "validate_dataset"]

#: npz key -> the dtypes allowed (mgn writes the first; MetaGraspNet's files have float32).
_NPZ_KEYS: dict[str, tuple[type, ...]] = {
    "depth": (np.float32,),
    "instances_objects": (np.uint8, np.float32),
    "instances_semantic": (np.uint16, np.uint8, np.float32),
    "occlusion": (np.float32,),
}


@dataclass(frozen=True)
class Problem:
    """One finding: the file (relative to the dataset root) and what is wrong with it."""

    path: str
    message: str

    def __str__(self) -> str:
        return f"{self.path}: {self.message}"


Report = Callable[[str, str], None]  # bad(file suffix, message)


def _check_camera_and_rgb(view: View, bad: Report) -> tuple[int, int] | None:
    """Checks ``_camera_params.json`` and ``_rgb.png``; returns the image (height, width)."""
    try:
        K = view.intrinsics
        hw: tuple[int, int] | None = (K.height, K.width)
    except Exception as e:  # noqa: BLE001 (report any failure as a finding)
        bad("_camera_params.json", str(e))
        hw = None
    try:
        rgb = view.rgb
        if hw is not None and rgb.shape != (*hw, 3):
            bad("_rgb.png", f"shape {rgb.shape}, camera params say {(*hw, 3)}")
    except Exception as e:  # noqa: BLE001
        bad("_rgb.png", str(e))
    return hw


def _check_masks(z: Any, hw: tuple[int, int] | None, bad: Report) -> int:
    """Checks the amodal and visible masks of a view's ``.npz``; returns the instance count."""
    am = z["occlusion_objects"]
    n = int(am.shape[0])
    if am.ndim != 3 or (hw is not None and am.shape[1:] != hw):
        bad(".npz", f"'occlusion_objects' has shape {am.shape}, expected (N, *{hw})")
    if "instances_objects" in z:
        ids = z["instances_objects"]
        if np.any(ids != np.round(ids)) or ids.min(initial=0) < 0 or ids.max(initial=0) > n:
            bad(".npz", f"'instances_objects' must hold whole ids 0..{n}")
        elif ids.max(initial=0) < 1:
            bad(".npz", "no visible object in this view (the camera sees only the tote)")
        elif am.ndim == 3 and am.shape[1:] == ids.shape:
            for i in range(n):
                vis = ids == i + 1
                if vis.any() and np.any(vis & ~am[i]):
                    bad(".npz", f"visible mask of instance {i + 1} not inside its amodal mask")
                    break
    return n


def _check_npz(view: View, hw: tuple[int, int] | None, bad: Report) -> int | None:
    """Checks a view's ``.npz``; returns the instance count (None: unknown)."""
    n = None
    try:
        z = view.npz
        for key, dtypes in _NPZ_KEYS.items():
            if key not in z:
                bad(".npz", f"lacks '{key}'")
            elif z[key].dtype not in dtypes or (hw is not None and z[key].shape != hw):
                names = " or ".join(str(np.dtype(d)) for d in dtypes)
                bad(".npz", f"'{key}' is {z[key].dtype} {z[key].shape}, expected {names} {hw}")
        if "occlusion_objects" not in z:
            bad(".npz", "lacks 'occlusion_objects'")
        else:
            n = _check_masks(z, hw, bad)
        if "occlusion" in z:
            occ = z["occlusion"]
            if np.any(~np.isfinite(occ)) or occ.min(initial=0) < 0 or occ.max(initial=0) > 1:
                bad(".npz", "'occlusion' must lie in [0, 1]")
    except Exception as e:  # noqa: BLE001
        bad(".npz", str(e))
    return n


def _check_groups(h5: Any, n: int | None, bad: Report) -> None:
    """Checks the grasp and keypoint groups of a view's ``_scene.hdf5``."""
    groups: dict[str, dict[str, Any]] = {}
    for key, value in h5.items():
        if "grasps/" in key or key.startswith("keypts/"):
            g, _, leaf = key.rpartition("/")
            groups.setdefault(g, {})[leaf] = value
    for g, leaves in groups.items():
        lengths = {leaf: len(a) for leaf, a in leaves.items()}
        if len(set(lengths.values())) > 1 and "occluded_object_id" not in leaves:
            bad("_scene.hdf5", f"group '{g}' has datasets of different lengths {lengths}")
        for leaf, a in leaves.items():
            if leaf.endswith("object_id") and n is not None and len(a):
                if a.min() < 0 or a.max() >= n:
                    bad("_scene.hdf5", f"'{g}/{leaf}' must lie in 0..{n - 1}")
            if leaf.startswith("score") and len(a):
                finite = a[np.isfinite(a)]
                if len(finite) and (finite.min() < 0 or finite.max() > 1):
                    bad("_scene.hdf5", f"'{g}/{leaf}' must lie in [0, 1]")


def _check_hdf5(view: View, n: int | None, bad: Report) -> None:
    """Checks a view's ``_scene.hdf5``."""
    try:
        h5 = view.hdf5
        for key in HDF5_FLOAT_KEYS:
            if key not in h5:
                bad("_scene.hdf5", f"lacks '{key}'")
        if n is not None:
            expect = {
                "camera/pose_relative_to_world": (1, 4, 4),
                "objects/poses_relative_to_camera": (n, 4, 4),
                "objects/categories": (n,),
                "objects/bbox_loose": (n, 4),
            }
            for key, shape in expect.items():
                if key in h5 and h5[key].shape != shape:
                    bad("_scene.hdf5", f"'{key}' has shape {h5[key].shape}, expected {shape}")
        _check_groups(h5, n, bad)
    except Exception as e:  # noqa: BLE001
        bad("_scene.hdf5", str(e))


def _check_order(view: View, n: int | None, bad: Report) -> None:
    """Checks a view's ``_order.csv`` and ``_order.json`` against each other."""
    v = view.index
    try:
        m = view.relation_matrix
        if n is not None and m.shape != (n, n) and m.size:
            bad("_order.csv", f"shape {m.shape}, expected ({n}, {n})")
        order = view.order
        if n is not None:
            missing = [str(i) for i in range(1, n + 1) if str(i) not in order]
            if missing:
                bad("_order.json", f"lacks instances {missing[:10]}")
        for key, entry in order.items():
            if not isinstance(entry, dict):
                continue
            for p in entry.get("parents", []):
                pid = int(p["id"])
                if pid > 0 and m.size and m[int(key) - 1, pid - 1] != -1:
                    bad("_order.json", f"parent {pid} of {key} is not -1 in {v}_order.csv")
    except Exception as e:  # noqa: BLE001
        bad("_order.json", str(e))


def _check_view(view: View, problems: list[tuple[str, str]]) -> None:
    v = view.index

    def bad(suffix: str, msg: str) -> None:
        problems.append((f"{v}{suffix}", msg))

    for name in view_file_names(v):
        if not (view.folder / name).exists():
            problems.append((name, "missing"))
    hw = _check_camera_and_rgb(view, bad)
    n = _check_npz(view, hw, bad)
    _check_hdf5(view, n, bad)
    _check_order(view, n, bad)


def _check_scene(scene: SceneFolder, problems: list[Problem], root: Path) -> None:

    found: list[tuple[str, str]] = []
    if (scene.folder / MANIFEST).exists():
        reason = check_manifest(scene.folder)
        if reason is not None:
            found.append((MANIFEST, reason))
    if not scene.view_ids:
        found.append((".", "no views"))
    for view in scene.views():
        _check_view(view, found)
    rel = scene.folder.relative_to(root)
    problems.extend(Problem(str(rel / name), msg) for name, msg in found)


def _check_completeness(ds: Dataset, info: dict[str, Any], problems: list[Problem]) -> None:
    """An mgn dataset (one with ``dataset.json``) holds exactly the scenes it announces.

    ``num_scenes`` fixes the scene folders ``scene0 .. scene<num_scenes - 1>``; a folder may be
    absent only when a difficulty-balanced run pruned it (``selection.pruned`` and none of its
    views selected). ``status`` must be ``complete``: ``running`` means the process was killed,
    ``interrupted`` stopped by Ctrl-C, ``failed`` stopped by an error (``error`` says which, e.g.
    a full disk), ``incomplete`` that scenes failed. Every scene folder needs its manifest (it is
    written last, so a folder without one was never finished).
    """
    status = info.get("status")
    if status != "complete":
        failed = info.get("failed_scenes")
        more = f" (failed scenes: {failed})" if failed else ""
        if info.get("error"):
            more += f" ({info['error']})"
        problems.append(
            Problem(
                "dataset.json",
                f"status is {status!r}, expected 'complete': the run did not finish{more}; "
                "complete it with 'mgn generate --resume'",
            )
        )
    num = info.get("num_scenes")
    if isinstance(num, bool) or not isinstance(num, int) or num < 0:
        problems.append(Problem("dataset.json", f"num_scenes must be an integer >= 0, got {num!r}"))
        return
    present = set(ds.scene_ids)
    raw_sel = info.get("selection")
    sel: dict[str, Any] = raw_sel if isinstance(raw_sel, dict) else {}
    selected = {int(e["scene"]) for e in sel.get("views", []) if isinstance(e, dict)}
    prunable = bool(sel.get("pruned")) if sel else False
    missing = [i for i in range(num) if i not in present and not (prunable and i not in selected)]
    if missing:
        shown = ", ".join(f"scene{i}" for i in missing[:10]) + (" ..." if len(missing) > 10 else "")
        problems.append(
            Problem(
                ".",
                f"{len(missing)} of num_scenes={num} scene folders missing: {shown}",
            )
        )
    extra = sorted(i for i in present if i >= num)
    if extra:
        problems.append(
            Problem(".", f"scene folders beyond num_scenes={num}: " + ", ".join(map(str, extra)))
        )
    for i in sorted(present):
        if not (ds.root / f"scene{i}" / MANIFEST).exists():
            problems.append(Problem(f"scene{i}/{MANIFEST}", "missing: the scene was not finished"))


def validate_dataset(root: str | os.PathLike[str]) -> list[Problem]:
    """Every problem found in the dataset at ``root`` (an empty list: valid).

    Besides every file of every scene, an mgn dataset (with ``dataset.json``) must be complete:
    its status ``complete`` and the scene folders the ones ``num_scenes`` announces.
    """
    ds = Dataset(root)
    problems: list[Problem] = []
    info: dict[str, Any] | None = None
    try:
        info = ds.info
    except Exception as e:  # noqa: BLE001
        problems.append(Problem("dataset.json", str(e)))
    if not ds.scene_ids:
        problems.append(Problem(".", "no scene<N> folders"))
    if isinstance(info, dict):
        _check_completeness(ds, info, problems)
    for scene in ds.scenes():
        _check_scene(scene, problems, ds.root)
    return problems
