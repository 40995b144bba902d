"""The manifest of a scene folder: every file with its size and SHA-256, written last.

A scene folder is complete exactly when its ``manifest.json`` exists and every file it lists
has the listed size and checksum. ``mgn generate --resume`` keeps complete scenes and redoes the
others.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

from mgn.base.atomic import atomic_write_text

__all__ = ["MANIFEST", "check_manifest", "file_sha256", "write_manifest"]

MANIFEST = "manifest.json"
_CHUNK = 1 << 20


def file_sha256(path: str | os.PathLike[str]) -> str:
    """Hex SHA-256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
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
