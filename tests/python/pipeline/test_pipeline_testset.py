"""Test-set builders: the unseen-object split and the difficulty-balanced view selection."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mgn.errors import InvalidArgumentError
from mgn.objects import builtin_objects
from mgn.pipeline import generate, scene_seed
from mgn.pipeline.config import Config, ConfigError, load_config
from mgn.pipeline.testset import (
    NOVEL_TAG,
    RECIPES,
    compose_scene,
    parse_quota,
    plan_batch,
    resolve_split,
    select_views,
)

# Tiny scenes: 3 views at 120 x 120 px, no grasp labels (object labels are not needed for the
# layout), short drops.
TINY = {
    "objects": {"categories": ["box_tea", "can_soda", "box_cube"], "copies": [1, 2]},
    "camera": {"views": [0, 5, 17], "resolution_scale": 0.1},
    "labels": {"suction": False, "paralleljaw": False, "pj_physics": False, "scene_grasps": False},
    "drop": {"max_time": 1.5},
}
# Small quotas over levels that tiny scenes of three box/can categories reach with this seed
# (levels 1, 2 and 4/5 with few objects). The run is deterministic, so the quotas are met the
# same way on every machine; max_scenes bounds the run if a change made a level unreachable
# (the test then fails on report.unmet, never hangs).
QUOTA = {"1": 2, "2": 1, "4": 1}
SEED = 3


def tiny(**sections: dict) -> Config:
    d = json.loads(json.dumps(TINY))
    for k, v in sections.items():
        d[k] = {**d.get(k, {}), **v}
    return load_config(d)


def selection_config(**more: object) -> Config:
    return tiny(selection={"quota": QUOTA, "batch_scenes": 2, "max_scenes": 12, **more})


def novel_names() -> set[str]:
    return {o.name for o in builtin_objects() if NOVEL_TAG in o.tags}


@pytest.fixture(autouse=True)
def _cache(tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MGN_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "testset_cache"))


# ----------------------------------------------------------------------------- unit checks


def test_novel_objects_cover_the_papers_kinds() -> None:
    novel = [o for o in builtin_objects() if NOVEL_TAG in o.tags]
    assert 5 <= len(novel) <= 8
    kinds = {"nonconvex", "black", "deformable", "transparent"}
    for o in novel:
        assert o.tags & kinds, o.name
    assert kinds <= set().union(*(o.tags for o in novel))  # every kind of the paper's novel set


def test_config_round_trip_and_errors_name_the_key() -> None:
    cfg = load_config(
        {"split": {"name": "test", "unseen": ["wine_glass", 7]}, "selection": {"quota": {2: 3}}}
    )
    assert cfg.selection.quota == (0, 3, 0, 0, 0)
    assert Config.from_dict(json.loads(json.dumps(cfg.to_dict()))) == cfg
    assert load_config(None).split.name == "all"
    assert load_config(None).selection.quota is None
    bad = [
        ({"selection": {"quota": {3: -1}}}, "selection.quota.3"),
        ({"selection": {"quota": {6: 1}}}, "selection.quota.6"),
        ({"selection": {"quota": {1: 0}}}, "selection.quota"),
        ({"selection": {"batch_scenes": 0}}, "selection.batch_scenes"),
        ({"split": {"name": "val"}}, "split.name"),
        ({"split": {"unseen": "black"}}, "split.unseen"),
    ]
    for data, key in bad:
        with pytest.raises(ConfigError, match=f"'{key}'"):
            load_config(data)
    catalogue = list(builtin_objects())
    with pytest.raises(ConfigError, match=r"'split.unseen\[1\]'.*'no_such_thing'"):
        resolve_split(
            load_config({"split": {"name": "test", "unseen": ["sack", "no_such_thing"]}}),
            catalogue,
        )
    train_names = {"split": {"name": "train"}, "objects": {"names": ["can_soda", "wine_glass"]}}
    with pytest.raises(ConfigError, match=r"'objects.names\[1\]'.*wine_glass"):
        resolve_split(load_config(train_names), catalogue)
    train_cats = {"split": {"name": "train", "unseen": ["mug"]}, "objects": {"categories": ["mug"]}}
    with pytest.raises(ConfigError, match=r"'objects.categories\[0\]'.*mug"):
        resolve_split(load_config(train_cats), catalogue)
    assert parse_quota("1=20,2=20,3=20,4=20,5=20") == (20,) * 5
    assert parse_quota("5=1") == (0, 0, 0, 0, 1)
    for text in ("1=2,x", "1=-2", "1=1,1=2", "9=1", "1=a"):
        with pytest.raises(ConfigError, match="--difficulty-quota"):
            parse_quota(text)


def test_plan_batch_steers_towards_the_missing_levels() -> None:
    assert plan_batch([0, 0, 0, 0, 0], 4) == []
    assert plan_batch([5, 0, 0, 0, 0], 3) == [1, 1, 1]
    assert plan_batch([1, 0, 0, 0, 9], 4) == [1, 5, 5, 5]
    assert plan_batch([2, 2, 2, 2, 2], 3) == [1, 2, 3]  # lowest levels first
    for remaining in ([3, 0, 7, 1, 0], [20] * 5, [0, 1, 0, 0, 50]):
        for b in (1, 2, 5, 8):
            plan = plan_batch(remaining, b)
            assert len(plan) == b
            assert plan == sorted(plan)
            assert all(remaining[lv - 1] > 0 for lv in plan)
            missing = [lv for lv in range(1, 6) if remaining[lv - 1] > 0]
            assert set(missing[:b]) <= set(plan)
    # Selection: first come first served in the given order, exactly the quota.
    views = [(0, v, d) for v, d in enumerate([1, 1, 4, 1, 5, 4])]
    chosen, rejected, left = select_views(views, [2, 0, 0, 1, 0])
    assert [e["view"] for e in chosen] == [0, 1, 2]
    assert left == [0, 0, 0, 0, 0]
    assert [e["view"] for e in rejected] == [3, 4, 5]


def test_split_compositions() -> None:
    catalogue = list(builtin_objects())
    novel = novel_names()
    train = load_config({"split": {"name": "train"}})
    test = load_config({"split": {"name": "test"}})
    s_train, s_test = resolve_split(train, catalogue), resolve_split(test, catalogue)
    assert set(s_train.unseen_names) == novel
    ids = {o.name: o.category_id for o in catalogue}
    assert s_test.to_json()["unseen_categories"] == sorted(ids[n] for n in novel)
    seen_any = 0
    for i in range(40):
        seed = scene_seed(1, i)
        names = [s.name for s in compose_scene(train, catalogue, seed, s_train)]
        assert len(names) == 20
        assert not set(names) & novel
        t = [s.name for s in compose_scene(test, catalogue, seed, s_test)]
        assert len(t) == 20
        assert set(t) & novel
        # Without the split the same seed gives the plain composition (MGN: 20 objects).
        plain = compose_scene(
            load_config(None), catalogue, seed, resolve_split(Config(), catalogue)
        )
        seen_any += bool({s.name for s in plain} & novel)
        for level in (1, 2, 3):
            lo, hi, _ = RECIPES[level]  # type: ignore[misc]
            objs = [s.name for s in compose_scene(test, catalogue, seed, s_test, level)]
            assert lo <= len(objs) <= hi
            assert len(set(objs)) == len(objs)
            assert set(objs) & novel
        objs = [s.name for s in compose_scene(train, catalogue, seed, s_train, 4)]
        assert len(set(objs)) < len(objs)
        assert not set(objs) & novel
    assert 0 < seen_any < 40  # the plain composition does not always hold a novel object


# ------------------------------------------------------------------------- generated scenes


def scene_names(root: Path, i: int) -> tuple[set[str], set[str]]:
    d = json.loads((root / f"scene{i}" / "scene.json").read_text())
    return {o["name"] for o in d["instances"]}, {o["name"] for o in d["removed"]}


def test_train_and_test_split_datasets(tmp_path: Path) -> None:
    """Generated scenes (scene.json): unseen categories never lie in a train scene and are
    composed into every test scene. Cheap objects keep it fast (the default 'novel' set is
    checked on compositions above): the train split holds out every object but three, drawn
    from the whole catalogue; the test split draws from three categories, box_cube unseen."""
    cheap = ["box_tea", "can_soda", "box_cube"]
    held_out = sorted(o.name for o in builtin_objects() if o.name not in cheap)
    cfg_train = tiny(
        objects={"categories": None, "count": 2, "copies": [1, 1]},
        split={"name": "train", "unseen": held_out},
        camera={"views": [0]},
    )
    cfg_test = tiny(
        objects={"count": 2, "copies": [1, 1]},
        split={"name": "test", "unseen": ["box_cube"]},
        camera={"views": [0]},
    )
    ids = {o.name: o.category_id for o in builtin_objects()}
    for cfg, name, unseen in ((cfg_train, "train", held_out), (cfg_test, "test", ["box_cube"])):
        out = tmp_path / name
        report = generate(out, 3, config=cfg, seed=SEED, progress=False)
        assert report.complete, report.format_summary()
        recorded = json.loads((out / "dataset.json").read_text())["split"]
        assert recorded["name"] == name
        assert set(recorded["unseen_names"]) == set(unseen)
        assert recorded["unseen_categories"] == sorted(ids[n] for n in unseen)
        for i in range(3):
            inside, removed = scene_names(out, i)
            if name == "train":
                assert not (inside | removed) & set(unseen)
                assert inside <= set(cheap)
            else:
                assert "box_cube" in inside | removed
    unseen = {"box_cube"}
    inside_test = set().union(*(scene_names(tmp_path / "test", i)[0] for i in range(3)))
    assert inside_test & unseen  # the unseen object does lie in the test scenes
    with pytest.raises(InvalidArgumentError, match="split"):
        generate(tmp_path / "train", 3, config=cfg_test, seed=SEED, resume=True, progress=False)


@pytest.fixture(scope="module")
def balanced(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    """A difficulty-balanced run with two worker processes."""
    out = tmp_path_factory.mktemp("balanced") / "ds"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MGN_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "testset_cache"))
        report = generate(out, config=selection_config(), seed=SEED, workers=2, progress=False)
    assert report.complete, report.format_summary()
    return out, json.loads((out / "dataset.json").read_text())


def test_quotas_met_exactly_and_recorded(balanced: tuple[Path, dict]) -> None:
    from conftest import check_difficulty

    out, doc = balanced
    sel = doc["selection"]
    assert sel["quota"] == {"1": 2, "2": 1, "3": 0, "4": 1, "5": 0}
    assert sel["complete"]
    views = sel["views"]
    assert views == sorted(views, key=lambda e: (e["scene"], e["view"]))
    counts = {lv: sum(e["difficulty"] == lv for e in views) for lv in range(1, 6)}
    assert counts == {1: 2, 2: 1, 3: 0, 4: 1, 5: 0}
    assert doc["num_scenes"] == sel["scenes_generated"] == 2 * sel["batches_done"]
    # Every view of every generated scene is either selected or rejected, once.
    listed = {(e["scene"], e["view"]) for e in views + sel["rejected"]}
    assert len(listed) == len(views) + len(sel["rejected"])
    for i in range(doc["num_scenes"]):
        for v in (0, 5, 17):
            if (out / f"scene{i}" / f"{v}_layout.json").exists():
                assert (i, v) in listed
    for e in views + sel["rejected"]:
        layout = json.loads((out / f"scene{e['scene']}" / f"{e['view']}_layout.json").read_text())
        assert check_difficulty(layout) == e["difficulty"]
    # Exactness: no level was over-filled, and a view was only rejected once its level was full.
    taken = dict.fromkeys(range(1, 6), 0)
    for e in sorted(views + sel["rejected"], key=lambda e: (e["scene"], e["view"])):
        full = taken[e["difficulty"]] >= int(sel["quota"][str(e["difficulty"])])
        assert (e in sel["rejected"]) == full
        taken[e["difficulty"]] += not full


def test_same_selection_in_process_and_resumed_past_max_scenes(
    balanced: tuple[Path, dict], tmp_path: Path
) -> None:
    """One worker, first stopped by max_scenes after one batch (unmet levels reported), then
    resumed with the default limit: the same selection as the two-worker run."""
    _, ref = balanced
    out = tmp_path / "ds"
    report = generate(
        out, config=selection_config(max_scenes=1), seed=SEED, workers=1, progress=False
    )
    doc = json.loads((out / "dataset.json").read_text())
    if ref["selection"]["batches_done"] > 1:
        assert not report.complete
        assert report.unmet
        assert "QUOTA NOT MET" in report.format_summary()
        assert doc["status"] == "incomplete"
        assert doc["selection"]["unmet"] == {str(k): v for k, v in report.unmet.items()}
    report = generate(out, config=selection_config(), seed=SEED, resume=True, progress=False)
    assert report.complete, report.format_summary()
    doc = json.loads((out / "dataset.json").read_text())
    assert doc["selection"] == ref["selection"]
    assert doc["status"] == "complete"


def test_pruned_balanced_dataset_validates(balanced: tuple[Path, dict], tmp_path: Path) -> None:
    from mgn.cli.main import main
    from mgn.io.dataset import Dataset
    from mgn.io.validate import validate_dataset

    _, ref = balanced
    out = tmp_path / "ds"
    args = ["generate", "--out", str(out), "--seed", str(SEED), "--quiet", "--prune-rejected"]
    cfg_path = tmp_path / "cfg.yaml"
    cfg_path.write_text(json.dumps(json.loads(json.dumps(TINY))))
    quota = ",".join(f"{k}={v}" for k, v in QUOTA.items())
    args += ["--config", str(cfg_path), "--difficulty-quota", quota, "--batch-scenes", "2"]
    assert main([*args, "--max-scenes", "12"]) == 0
    doc = json.loads((out / "dataset.json").read_text())
    sel = doc["selection"]
    assert sel["views"] == ref["selection"]["views"]
    assert sel["pruned"]
    assert validate_dataset(out) == []
    ds = Dataset(out)
    kept = {(s, v) for s in ds.scene_ids for v in ds.scene(s).view_ids}
    assert kept == {(e["scene"], e["view"]) for e in sel["views"]}
    for s in ds.scene_ids:
        gt = json.loads((out / f"scene{s}" / "scene_gt.json").read_text())
        assert sorted(int(k) for k in gt) == sorted(ds.scene(s).view_ids)
    # Running the pruning again (as --resume does) changes nothing.
    before = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    assert main([*args, "--max-scenes", "12", "--resume"]) == 0
    after = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    assert before == after
    assert validate_dataset(out) == []
    with pytest.raises(InvalidArgumentError, match="--scenes"):
        generate(out, 3, config=selection_config(), seed=SEED, progress=False)
    with pytest.raises(ConfigError, match=r"'labels.layout'"):
        generate(
            tmp_path / "x",
            config=selection_config().__class__.from_dict(
                {
                    **json.loads(json.dumps(selection_config().to_dict())),
                    "labels": {"layout": False},
                }
            ),
            progress=False,
        )
