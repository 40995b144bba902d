"""objects.count as a per-scene [min, max] range: validation, the counts drawn, the int path."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from mgn.errors import InvalidArgumentError
from mgn.objects import builtin_objects
from mgn.pipeline import generate, scene_seed
from mgn.pipeline.config import ConfigError, ObjectsConfig, dump_config, load_config
from mgn.pipeline.testset import compose_scene, resolve_split
from mgn.scene import compose_objects

SEED = 11
CATALOGUE = list(builtin_objects())


def _scene(config: dict, seed: int) -> list[str]:
    cfg = load_config(config)
    split = resolve_split(cfg, CATALOGUE)
    return [s.name for s in compose_scene(cfg, CATALOGUE, seed, split)]


def test_range_counts_lie_in_the_range_and_reach_both_ends() -> None:
    cfg = {"objects": {"count": [2, 4]}}
    objects = ObjectsConfig(count=(2, 4))
    seeds = [scene_seed(SEED, i) for i in range(40)]
    counts = [len(_scene(cfg, s)) for s in seeds]
    assert all(2 <= n <= 4 for n in counts), counts
    assert set(counts) == {2, 3, 4}, counts
    assert counts == [objects.scene_count(s) for s in seeds]
    # Not one count for the whole dataset: no value takes (nearly) every scene.
    assert max(counts.count(n) for n in (2, 3, 4)) < 30, counts


def test_a_range_scene_holds_the_objects_of_its_drawn_whole_count() -> None:
    """The range only picks the count: with it, the composition is the int path's."""
    for cfg in (
        {"count": [3, 9]},
        {"count": [3, 9], "copies": [1, 2]},
        {"categories": ["mug", 3, "box_tea"], "count": [2, 7], "copies": [1, 3]},
    ):
        for i in range(12):
            s = scene_seed(SEED, i)
            ranged = _scene({"objects": cfg}, s)
            whole = _scene({"objects": {**cfg, "count": len(ranged)}}, s)
            assert ranged == whole, (cfg, i)
            assert cfg["count"][0] <= len(ranged) <= cfg["count"][1]


def test_the_int_path_is_the_composition_of_that_count() -> None:
    for i in range(8):
        s = scene_seed(SEED, i)
        expected = [x.name for x in compose_objects(count=7, seed=s, catalogue=CATALOGUE)]
        assert _scene({"objects": {"count": 7}}, s) == expected
        default = [x.name for x in compose_objects(count=20, seed=s, catalogue=CATALOGUE)]
        assert _scene({}, s) == default
    # A whole count (or none) does not depend on the seed given to compose_kwargs.
    for objects in (ObjectsConfig(), ObjectsConfig(count=7), ObjectsConfig(categories=("mug",))):
        assert objects.compose_kwargs() == objects.compose_kwargs(12345)
    assert ObjectsConfig(count=7).scene_count(5) == 7
    assert ObjectsConfig().scene_count(5) == ObjectsConfig.DEFAULT_COUNT
    assert ObjectsConfig(categories=("mug",)).scene_count(5) is None
    assert ObjectsConfig(names=("mug",)).scene_count(5) is None


def test_counts_do_not_depend_on_the_order_scenes_are_composed() -> None:
    cfg = {"objects": {"count": [1, 20]}}
    seeds = [scene_seed(SEED, i) for i in range(10)]
    forward = [_scene(cfg, s) for s in seeds]
    backward = [_scene(cfg, s) for s in reversed(seeds)]
    assert forward == backward[::-1]
    assert len({len(x) for x in forward}) > 1


def test_count_range_and_copies_with_categories() -> None:
    cfg = {"objects": {"categories": ["mug", "box_tea"], "count": [3, 6], "copies": [1, 2]}}
    for i in range(10):
        names = _scene(cfg, scene_seed(SEED, i))
        assert 3 <= len(names) <= 6
        assert set(names) <= {"mug", "box_tea"}


@pytest.mark.parametrize(
    "value",
    [[0, 5], [5, 3], [1.5, 3], [1, 2, 3], [4], [], "a", "3", 0, -2, 2.0, True, [True, 2], [1, "2"]],
)
def test_bad_counts_name_the_key_and_what_is_expected(value: object) -> None:
    with pytest.raises(ConfigError) as info:
        load_config({"objects": {"count": value}})
    message = str(info.value)
    assert "'objects.count'" in message, message
    assert "[min, max]" in message, message
    assert "1 <= min <= max" in message, message
    assert repr(value) in message, message
    with pytest.raises(ConfigError, match=r"'objects\.count'"):
        ObjectsConfig(count=value)  # type: ignore[arg-type]


def test_a_range_needs_the_scene_seed() -> None:
    with pytest.raises(InvalidArgumentError, match="scene seed"):
        ObjectsConfig(count=(2, 4)).compose_kwargs()
    assert ObjectsConfig(count=[2, 4]).count == (2, 4)  # type: ignore[arg-type]
    assert ObjectsConfig(count=(3, 3)).scene_count(1) == 3


def test_range_round_trip_dump_and_check(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    from mgn.cli.main import main

    cfg = load_config({"objects": {"count": [5, 20]}})
    assert cfg.objects.count == (5, 20)
    text = dump_config(cfg)
    assert "count: [5, 20]" in text
    assert "[min, max]" in dump_config()  # the section comment says int or [min, max]
    assert load_config(yaml.safe_load(text)) == cfg
    path = tmp_path / "c.yaml"
    path.write_text("objects: {count: [5, 20]}\ncamera: {views: [0]}\n")
    assert main(["config", "check", str(path)]) == 0
    assert "5-20 objects per scene" in capsys.readouterr().out
    path.write_text("objects: {count: 7}\n")
    assert main(["config", "check", str(path)]) == 0
    assert "7 objects per scene" in capsys.readouterr().out
    path.write_text("objects: {count: [5, 3]}\n")
    assert main(["config", "check", str(path)]) == 1
    assert "objects.count" in capsys.readouterr().err


def test_scenes_record_their_drawn_count(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A tiny generated dataset: scene.json stats.num_dropped is the scene's drawn count and
    dataset.json keeps the configured range."""
    monkeypatch.setenv("MGN_CACHE_DIR", str(tmp_path / "cache"))
    config = {
        "objects": {"categories": ["box_tea", "can_soda"], "count": [1, 3], "copies": [1, 2]},
        "camera": {"views": [0], "resolution_scale": 0.1},
        "labels": {"suction": False, "paralleljaw": False, "pj_physics": False},
        "drop": {"max_time": 2.0},
    }
    out = tmp_path / "ds"
    n = 3
    report = generate(out, n, config=load_config(config), seed=SEED, progress=False)
    assert report.complete, report.format_summary()
    doc = json.loads((out / "dataset.json").read_text())
    assert doc["config"]["objects"]["count"] == [1, 3]
    for i in range(n):
        scene = json.loads((out / f"scene{i}" / "scene.json").read_text())
        drawn = _scene(config, scene_seed(SEED, i))
        assert scene["stats"]["num_dropped"] == len(drawn)
        kept = [x["name"] for x in scene["instances"]] + [x["name"] for x in scene["removed"]]
        assert sorted(kept) == sorted(drawn)
