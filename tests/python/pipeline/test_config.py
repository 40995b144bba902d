"""The dataset configuration: defaults, YAML round trip, validation messages naming the key."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pytest
import yaml

from mgn import _core
from mgn.errors import InvalidArgumentError, IoError
from mgn.hardware import ParallelJawGripper, SuctionCup
from mgn.objects import ToteSpec
from mgn.pipeline.config import (
    Config,
    ConfigError,
    default_config,
    dump_config,
    load_config,
)
from mgn.scene import DropOptions


def test_defaults_are_the_mgn_values() -> None:
    c = default_config()
    assert c.gripper == ParallelJawGripper()
    assert c.cup == SuctionCup()
    assert c.tote == ToteSpec()
    assert c.drop == DropOptions()
    assert c.object_labels.suction_points == 5000
    assert c.object_labels.pj_points == 5000
    assert c.object_labels.physics_grid == 10
    # Every stored parallel-jaw grasp gets a physics score by default, with the staircase search.
    assert c.object_labels.physics_grasps is None
    assert c.object_labels.physics_search == "staircase"
    assert c.object_labels.physics_calibration == 32
    # Checks: null = 0 with the object-level calibration, the search's own default without.
    assert c.object_labels.physics_checks is None
    assert c.object_labels.staircase_checks == 0
    uncalibrated = load_config({"object_labels": {"physics_calibration": 0}}).object_labels
    assert uncalibrated.staircase_checks == _core.grasp.ShakeOptions().staircase_checks == 6
    given = load_config({"object_labels": {"physics_checks": 4}}).object_labels
    assert given.physics_checks == given.staircase_checks == 4
    assert c.objects.copies == (2, 5)
    assert c.objects.compose_kwargs() == {"categories": None, "count": 20, "copies": (2, 5)}
    assert c.camera.rig == "mgn"
    assert c.camera.view_indices == tuple(range(37))
    assert c.camera.intrinsics == "mgn_synthetic"
    assert c.camera.resolution_scale == 1.0
    assert all(dataclasses.asdict(c.labels).values())


def test_dump_then_load_gives_the_same_config(tmp_path: Path) -> None:
    text = dump_config()
    assert "unknown" not in text
    assert text.startswith("#")
    path = tmp_path / "cfg.yaml"
    path.write_text(text)
    assert load_config(path) == Config()
    custom = load_config(
        {
            "objects": {"categories": ["mug", 3], "count": 7, "copies": [1, 3]},
            "tote": {"inner_length": 0.5, "color": [0.1, 0.2, 0.3, 1.0]},
            "gripper": {"max_opening": 0.1, "finger_size": [0.01, 0.02, 0.06]},
            "cup": {"radius": 0.01, "outer_radius": 0.012},
            "camera": {
                "rig": "hemisphere",
                "hemisphere": {"radii": [0.9], "tilts": [0.0, 0.4], "azimuths": [0, math.pi]},
                "views": [3, 0],
                "intrinsics": "zivid_two_like",
                "resolution_scale": 0.25,
                "sensor": "tof",
                "randomize": False,
            },
            "labels": {"pj_physics": False, "layout": False},
            "object_labels": {"suction_points": 100, "suction_model": "strain", "seed": 4},
            "drop": {"max_time": 3.0, "window_min": [-0.05, -0.02, 0.3]},
        }
    )
    path.write_text(dump_config(custom))
    again = load_config(path)
    assert again == custom
    assert again != Config()
    assert again.camera.view_indices == (3, 0)
    assert again.tote.inner_length == 0.5


def test_cli_dump_prints_the_defaults(capsys: pytest.CaptureFixture, tmp_path: Path) -> None:
    from mgn.cli.main import main

    assert main(["config", "dump"]) == 0
    assert load_config(yaml.safe_load(capsys.readouterr().out)) == Config()
    path = tmp_path / "c.yaml"
    path.write_text("camera: {views: [0, 5, 17]}\n")
    assert main(["config", "check", str(path)]) == 0
    assert "3 views" in capsys.readouterr().out
    path.write_text("camera: {viewz: [0]}\n")
    assert main(["config", "check", str(path)]) == 1
    assert "camera.viewz" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("data", "key", "detail"),
    [
        ({"objectz": {}}, "'objectz'", "valid keys"),
        ({"camera": {"resolutin_scale": 0.5}}, "'camera.resolutin_scale'", "resolution_scale"),
        ({"camera": {"resolution_scale": -1}}, "'camera.resolution_scale'", "> 0, got -1"),
        ({"camera": {"resolution_scale": "big"}}, "'camera.resolution_scale'", "'big'"),
        ({"camera": {"views": [0, 37]}}, "'camera.views'", "0..36"),
        ({"camera": {"views": [1, 1]}}, "'camera.views'", "distinct"),
        ({"camera": {"views": [0.5]}}, "'camera.views[0]'", "integer"),
        ({"camera": {"rig": "dome"}}, "'camera.rig'", "'mgn', 'hemisphere'"),
        ({"camera": {"sensor": "lidar"}}, "'camera.sensor'", "structured-light"),
        ({"camera": {"hemisphere": {"radii": []}}}, "'camera.hemisphere.radii'", "non-empty"),
        ({"labels": {"suction": "yes"}}, "'labels.suction'", "true or false"),
        ({"object_labels": {"pj_points": 0}}, "'object_labels.pj_points'", ">= 1"),
        ({"object_labels": {"physics_grasps": 0}}, "'object_labels.physics_grasps'", ">= 1"),
        ({"object_labels": {"physics_search": "grid"}}, "'object_labels.physics_search'", "full"),
        ({"object_labels": {"physics_checks": -1}}, "'object_labels.physics_checks'", ">= 0"),
        (
            {"object_labels": {"physics_calibration": -2}},
            "'object_labels.physics_calibration'",
            ">= 0",
        ),
        ({"objects": {"count": True}}, "'objects.count'", "integer"),
        ({"objects": {"copies": [3, 2]}}, "'objects.copies'", "min <= max"),
        ({"objects": {"copies": [2]}}, "'objects.copies'", "2 values"),
        ({"objects": {"names": ["mug"], "count": 3}}, "'objects'", "not both"),
        ({"objects": {"names": [None]}}, "'objects.names[0]'", "object name"),
        ({"tote": {"inner_length": -0.1}}, "'tote.inner_length'", "> 0"),
        ({"tote": {"depth": 1}}, "'tote.depth'", "inner_length"),
        ({"gripper": {"max_opening": "wide"}}, "'gripper", "max_opening"),
        ({"cup": {"num_points": 3}}, "'cup.num_points'", ">= 6"),
        ({"drop": {"tote_collision": "sphere"}}, "'drop", "tote_collision"),
        ({"drop": {"steps": 5}}, "'drop.steps'", "max_time"),
        ({"camera": 3}, "'camera'", "mapping"),
    ],
)
def test_errors_name_the_key(data: dict, key: str, detail: str) -> None:
    with pytest.raises(ConfigError) as info:
        load_config(data)
    message = str(info.value)
    assert key in message, message
    assert detail in message, message
    assert isinstance(info.value, ValueError)
    assert isinstance(info.value, InvalidArgumentError)


def test_files_invalid_yaml_missing_file_and_relative_paths(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("camera: [unclosed\n")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_config(bad)
    with pytest.raises(IoError, match="not found"):
        load_config(tmp_path / "missing.yaml")
    sub = tmp_path / "cfg"
    sub.mkdir()
    path = sub / "c.yaml"
    path.write_text("objects: {user_objects: [objs/mine.yaml, /abs/other.yaml]}\n")
    c = load_config(path)
    assert c.objects.user_objects == (str(sub.resolve() / "objs/mine.yaml"), "/abs/other.yaml")
    path.write_text("tote: {inner_width: 0}\n")
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert str(path) in str(info.value)
    assert "'tote.inner_width'" in str(info.value)


def test_hemisphere_view_count() -> None:
    c = load_config(
        {"camera": {"rig": "hemisphere", "hemisphere": {"radii": [1, 2], "tilts": [0.1]}}}
    )
    assert c.camera.num_rig_views == 2 * 1 * 4
    with pytest.raises(ConfigError, match=r"0\.\.15"):  # default: 2 radii x 2 tilts x 4
        load_config({"camera": {"rig": "hemisphere", "views": [16]}})


def test_io_archival_switch() -> None:
    assert default_config().io.archival is False
    c = load_config({"io": {"archival": True}})
    assert c.io.archival is True
    assert Config.from_dict(c.to_dict()).io.archival is True  # round trip (dataset.json)
    with pytest.raises(ConfigError, match=r"io.archival"):
        load_config({"io": {"archival": "yes"}})
    with pytest.raises(ConfigError, match="io"):
        load_config({"io": {"compact": True}})
