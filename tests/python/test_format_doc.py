"""docs/format.md names what the files hold: every dataset of ``{v}_scene.hdf5``, every key of
``{v}.npz``, ``{v}_order.json``, ``{v}_layout.json``, ``{v}_camera_params.json`` and
``scene.json`` of a generated dataset is documented in its section."""

from __future__ import annotations

import json
import re
from pathlib import Path

import h5py
import numpy as np

DOC = Path(__file__).resolve().parents[2] / "docs" / "format.md"


def _section(title: str) -> str:
    """The text of docs/format.md from the heading ``### title`` to the next heading."""
    text = DOC.read_text(encoding="utf-8")
    start = text.index(f"### {title}\n")
    end = text.find("\n#", start + 1)
    return text[start : end if end > 0 else len(text)]


def _ticked(text: str) -> set[str]:
    return set(re.findall(r"`([^`]+)`", text))


def _documented_paths(section: str) -> list[tuple[tuple[str, ...], tuple[str, ...]]]:
    """(head, tail) of every path named in the first cell of the section's table rows: a path
    matches when it starts with head and ends with tail. ``a/b`` is the whole path, ``…/b/c``
    a tail, ``a/…/c`` both; a bare name after a path in the same cell replaces its last part."""
    out: list[tuple[tuple[str, ...], tuple[str, ...]]] = []
    for line in section.splitlines():
        if not line.startswith("| `"):
            continue
        cell = line.split("|")[1]
        head: tuple[str, ...] = ()
        tail: tuple[str, ...] = ()
        for token in re.findall(r"`([^`]+)`", cell):
            if "/" in token:
                parts = token.split("/")
                if "…" in parts:
                    k = parts.index("…")
                    head, tail = tuple(parts[:k]), tuple(parts[k + 1 :])
                else:
                    head, tail = tuple(parts), tuple(parts)
            else:
                full = head == tail
                tail = (*tail[:-1], token)
                head = tail if full else head
            out.append((head, tail))
    return out


def _matches(path: tuple[str, ...], head: tuple[str, ...], tail: tuple[str, ...]) -> bool:
    return path[: len(head)] == head and len(tail) > 0 and path[-len(tail) :] == tail


def test_every_scene_hdf5_dataset_is_in_the_table(small_dataset):
    documented = _documented_paths(_section("`{v}_scene.hdf5`"))
    paths: list[str] = []
    with h5py.File(small_dataset / "scene0" / "0_scene.hdf5", "r") as h5:
        h5.visititems(lambda n, o: paths.append(n) if isinstance(o, h5py.Dataset) else None)
    assert "keypts/com/keypts_relative_to_camera" in paths
    missing = []
    for path in paths:
        if path.startswith("mgn_pose_columns/"):
            continue  # storage of the virtual tool poses, described below the table
        parts = tuple(path.split("/"))
        # colliding_grasps/… has the layout of non_colliding_grasps (one row says so).
        alias = ("non_colliding_grasps", *parts[1:]) if parts[0] == "colliding_grasps" else parts
        if not any(_matches(p, h, t) for p in (parts, alias) for h, t in documented):
            missing.append(path)
    assert not missing, f"{{v}}_scene.hdf5 datasets missing from docs/format.md: {missing}"


def test_every_key_of_the_json_files_and_the_npz_is_documented(small_dataset):
    scene = small_dataset / "scene0"
    order = json.loads((scene / "0_order.json").read_text())
    keys = {k for entry in order.values() for k in entry}
    assert "bin_rel" in keys
    assert keys <= _ticked(_section("`{v}_order.json`")), keys - _ticked(
        _section("`{v}_order.json`")
    )
    layout = json.loads((scene / "0_layout.json").read_text())
    keys = set(layout) | {k for entry in layout["objects"].values() for k in entry}
    assert keys <= _ticked(_section("`{v}_layout.json` (mgn)"))
    params = json.loads((scene / "0_camera_params.json").read_text())
    assert set(params) <= _ticked(_section("`{v}_camera_params.json`"))
    with np.load(scene / "0.npz") as z:
        assert set(z.files) <= _ticked(_section("`{v}.npz`"))
    # scene.json: its keys and those of its objects are named, and no camera (it has none).
    doc = DOC.read_text(encoding="utf-8")
    row = next(line for line in doc.splitlines() if line.startswith("| `scene.json` |"))
    data = json.loads((scene / "scene.json").read_text())
    named = _ticked(row)
    assert set(data) <= named
    assert set(data["instances"][0]) <= named

    def keys(x: object) -> set[str]:
        if isinstance(x, dict):
            return set(x) | {k for v in x.values() for k in keys(v)}
        return {k for v in x for k in keys(v)} if isinstance(x, list) else set()

    claimed = {k for k in named if re.fullmatch(r"[a-z_]+", k)} - {"mgn"}
    if not data["removed"]:
        claimed -= {"reason"}  # the key of a removed object's entry
    if "drop_attempts" not in data["stats"]:
        claimed -= {"drop_attempts"}  # written with objects.refill, which the fixture turns off
    assert claimed <= keys(data), f"scene.json lacks {claimed - keys(data)}"
