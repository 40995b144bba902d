"""``mgn validate`` rejects incomplete datasets (issue 16, item 8): a killed run, a failed run, a
deleted scene folder, a scene that was never finished."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from mgn.cli import main
from mgn.io.validate import validate_dataset


@pytest.fixture
def copy(small_dataset: Path, tmp_path: Path) -> Path:
    out = tmp_path / "ds"
    shutil.copytree(small_dataset, out)
    return out


def _edit_info(root: Path, **changes: object) -> None:
    p = root / "dataset.json"
    doc = json.loads(p.read_text())
    doc.update(changes)
    p.write_text(json.dumps(doc))


def test_complete_dataset_is_valid(copy: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert validate_dataset(copy) == []
    assert main(["validate", str(copy)]) == 0


def test_deleted_scene_folder_is_reported(copy: Path) -> None:
    shutil.rmtree(copy / "scene1")
    problems = validate_dataset(copy)
    assert any("scene1" in p.message and "num_scenes=2" in p.message for p in problems), problems
    assert main(["validate", str(copy)]) == 1


@pytest.mark.parametrize("status", ["running", "incomplete"])
def test_unfinished_run_is_reported(copy: Path, status: str) -> None:
    _edit_info(copy, status=status)
    problems = validate_dataset(copy)
    assert [p.path for p in problems] == ["dataset.json"]
    assert repr(status) in problems[0].message
    assert main(["validate", str(copy)]) == 1


def test_more_scenes_announced_than_present_is_reported(copy: Path) -> None:
    _edit_info(copy, num_scenes=5)  # e.g. killed after two of five scenes
    problems = validate_dataset(copy)
    assert any("3 of num_scenes=5" in p.message for p in problems), problems


def test_scene_without_manifest_is_reported(copy: Path) -> None:
    (copy / "scene0" / "manifest.json").unlink()
    problems = validate_dataset(copy)
    assert any(p.path == "scene0/manifest.json" for p in problems), problems
