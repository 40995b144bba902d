"""Configurations that would give degenerate datasets are named (issue 16, item 9): ``mgn config
check`` and ``mgn generate`` warn with the setting; ``mgn validate`` flags views without any
visible object."""

from __future__ import annotations

import io
import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest
import trimesh
import yaml

from mgn.cli import main
from mgn.io.validate import validate_dataset
from mgn.pipeline.config import load_config
from mgn.pipeline.sanity import config_errors, config_warnings


def test_default_config_has_no_warning() -> None:
    assert config_warnings(load_config(None)) == []
    assert config_errors(load_config(None)) == []


def test_too_many_objects_are_named() -> None:
    # ~24 of the built-in objects fill the default tote's volume: 200 warn, 1000 (40x) refuse
    (w,) = config_warnings(load_config({"objects": {"count": 200}}))
    assert w.startswith("objects.count: 200 objects")
    errors = config_errors(load_config({"objects": {"count": 1000}}))
    assert any(
        e.startswith("objects.count: 1000 objects") and "more than 10x" in e for e in errors
    ), errors


def test_tiny_images_are_named() -> None:
    (w,) = config_warnings(load_config({"camera": {"resolution_scale": 0.0005}}))
    assert w.startswith("camera.resolution_scale = 0.0005")
    assert "1x1 px" in w


def test_cameras_that_cannot_see_into_the_tote_are_named() -> None:
    cfg = {"camera": {"rig": "hemisphere", "hemisphere": {"radii": [0.1, 0.8], "tilts": [1.5]}}}
    w = config_warnings(load_config(cfg))
    assert any(x.startswith("camera.hemisphere.tilts[0] = 1.5 rad") for x in w), w
    assert any(x.startswith("camera.hemisphere.radii[0] = 0.1 m") for x in w), w


def test_fifty_micrometre_object_is_named(tmp_path: Path) -> None:
    trimesh.creation.box((5.0, 5.0, 5.0)).export(tmp_path / "cube.stl")  # 5 units
    (tmp_path / "objs.yaml").write_text(
        yaml.safe_dump(
            {
                "objects": [
                    {
                        "name": "speck",
                        "mesh": "cube.stl",
                        "scale": 1e-5,
                        "density": 1000,
                        "friction": 0.5,
                    }
                ]
            }
        )
    )
    cfg = load_config({"objects": {"user_objects": [str(tmp_path / "objs.yaml")]}})
    w = config_warnings(cfg)  # the loader's warning, once, as text (no Python warning)
    speck = [x for x in w if "speck" in x]
    assert len(speck) == 1, w
    assert "objs.yaml: objects[0] ('speck')" in speck[0], w
    assert "is 0.05 mm across, too small" in speck[0], w
    # A part of 1-5 mm passes the loader but gets the setting's warning.
    (tmp_path / "objs.yaml").write_text(
        yaml.safe_dump(
            {
                "objects": [
                    {
                        "name": "grain",
                        "mesh": "cube.stl",
                        "scale": 4e-4,
                        "density": 1000,
                        "friction": 0.5,
                    }
                ]
            }
        )
    )
    w = config_warnings(cfg)
    assert any(
        x.startswith("objects.user_objects ('") and "object 'grain' is 2 mm across" in x for x in w
    ), w
    # The command line prints it and still accepts the file.
    (tmp_path / "cfg.yaml").write_text(
        yaml.safe_dump({"objects": {"user_objects": [str(tmp_path / "objs.yaml")]}})
    )
    assert main(["config", "check", str(tmp_path / "cfg.yaml")]) == 0


def test_config_check_prints_the_warning(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    (tmp_path / "cfg.yaml").write_text(yaml.safe_dump({"objects": {"count": 200}}))
    assert main(["config", "check", str(tmp_path / "cfg.yaml")]) == 0
    err = capsys.readouterr().err
    assert "warning: objects.count: 200 objects" in err


def test_validate_flags_a_view_without_visible_objects(small_dataset: Path, tmp_path: Path):
    ds = tmp_path / "ds"
    shutil.copytree(small_dataset, ds)
    assert validate_dataset(ds) == []
    npz = min((ds / "scene0").glob("*.npz"))
    with np.load(npz) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["instances_objects"] = np.zeros_like(arrays["instances_objects"])
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    npz.write_bytes(buf.getvalue())
    assert zipfile.is_zipfile(npz)
    problems = validate_dataset(ds)
    assert any("no visible object" in p.message and npz.name in p.path for p in problems), problems


def test_generate_prints_the_warning(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    cfg = {
        "objects": {"names": ["box_tea", "can_soda"]},
        "camera": {"views": [0], "resolution_scale": 0.02},  # 24 x 24 px
        "labels": dict.fromkeys(
            ("suction", "paralleljaw", "pj_physics", "layout", "scene_grasps"), False
        ),
        "drop": {"max_time": 1.0},
    }
    (tmp_path / "cfg.yaml").write_text(yaml.safe_dump(cfg))
    args = ["generate", "--out", str(tmp_path / "ds"), "--scenes", "1"]
    assert main([*args, "--config", str(tmp_path / "cfg.yaml"), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "warning: camera.resolution_scale = 0.02: images of 24x24 px" in err
