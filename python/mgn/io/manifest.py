"""The manifest of a scene folder: every file with its size and SHA-256, written last.

A scene folder is complete exactly when its ``manifest.json`` exists and every file it lists
has the listed size and checksum. ``mgn generate --resume`` keeps complete scenes and redoes the
others.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from mgn.base.atomic import atomic_write_text
from mgn.io.scene_schema import view_file_names

__all__ = [
    "MANIFEST",
    "check_manifest",
    "file_sha256",
    "prune_scene",
    "scene_view_ids",
    "write_manifest",
]

MANIFEST = "manifest.json"
_CHUNK = 1 << 20


def file_sha256(path: str | os.PathLike[str]) -> str:
    """Hex SHA-256 of a file's bytes."""
    h = hashlib.sha256()
    with Path(path).open("rb") as fh:
        while block := fh.read(_CHUNK):
            h.update(block)
    return h.hexdigest()


def write_manifest(folder: str | os.PathLike[str], **info: Any) -> dict[str, Any]:
    """Write ``folder/manifest.json`` listing every other file below ``folder`` (relative POSIX
    paths, sorted) with ``size`` (bytes) and ``sha256``; ``info`` is stored alongside (e.g. the
    scene index and seed). Returns the manifest."""
    root = Path(folder)
    files = {}
    for p in sorted(root.rglob("*")):
        if p.is_file() and p.name != MANIFEST:
            files[p.relative_to(root).as_posix()] = {
                "size": p.stat().st_size,
                "sha256": file_sha256(p),
            }
    manifest = {**info, "files": files}
    atomic_write_text(root / MANIFEST, json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    return manifest


def check_manifest(folder: str | os.PathLike[str], *, checksums: bool = True) -> str | None:
    """None when ``folder`` is complete and consistent with its manifest, else the reason.

    Args:
        checksums: also compare the SHA-256 of every file (else only presence and sizes).
    """
    root = Path(folder)
    try:
        manifest = json.loads((root / MANIFEST).read_text(encoding="utf-8"))
        files = manifest["files"]
    except FileNotFoundError:
        return "no manifest"
    except (OSError, ValueError, KeyError, TypeError) as e:
        return f"unreadable manifest ({e})"
    if not isinstance(files, dict):
        return "malformed manifest"
    for rel, entry in files.items():
        p = root / rel
        try:
            size = p.stat().st_size
        except OSError:
            return f"missing file '{rel}'"
        if size != entry.get("size"):
            return f"'{rel}' has {size} bytes, the manifest says {entry.get('size')}"
        if checksums and file_sha256(p) != entry.get("sha256"):
            return f"'{rel}' does not match its checksum"
    return None


def scene_view_ids(folder: str | os.PathLike[str]) -> list[int]:
    """The view indices of a written scene folder, ascending (from ``{v}_layout.json``)."""
    ids = []
    for p in Path(folder).glob("*_layout.json"):
        head = p.name.split("_", 1)[0]
        if head.isdigit():
            ids.append(int(head))
    return sorted(ids)


def prune_scene(folder: str | os.PathLike[str], views: Sequence[int]) -> bool:
    """Delete the files of ``views`` from a complete scene folder, keeping it consistent.

    ``scene_gt.json`` loses the views' entries and ``manifest.json`` their files (the other
    entries are kept as they are; the ``scene_gt.json`` entry is recomputed), then the files
    are deleted: a kill at any point leaves a manifest whose files all exist, and running it
    again finishes the job. A scene left without views is removed as a whole (renamed to a
    ``.tmp-`` name first). Returns True if the scene folder was removed.
    """

    root = Path(folder)
    if not root.is_dir():
        return True
    drop = {int(v) for v in views}
    left = [v for v in scene_view_ids(root) if v not in drop]
    if not left:
        tmp = root.parent / f".tmp-pruned-{root.name}-{os.getpid()}"
        root.rename(tmp)
        shutil.rmtree(tmp, ignore_errors=True)
        return True
    gt_path = root / "scene_gt.json"
    if gt_path.exists():
        gt = json.loads(gt_path.read_text(encoding="utf-8"))
        gt = {k: val for k, val in gt.items() if int(k) not in drop}
        atomic_write_text(gt_path, json.dumps(gt, indent=1, allow_nan=True) + "\n")
    mpath = root / MANIFEST
    manifest = json.loads(mpath.read_text(encoding="utf-8"))
    gone = {name for v in drop for name in view_file_names(v)}
    files = {k: e for k, e in manifest["files"].items() if k not in gone}
    if "scene_gt.json" in files:
        files["scene_gt.json"] = {"size": gt_path.stat().st_size, "sha256": file_sha256(gt_path)}
    manifest["files"] = files
    manifest["pruned_views"] = sorted(set(manifest.get("pruned_views", [])) | drop)
    atomic_write_text(mpath, json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    for name in sorted(gone):
        (root / name).unlink(missing_ok=True)
    return False
