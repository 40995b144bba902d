"""``output.formats`` of ``mgn generate``: the BOP and GraspNet exports written per scene while
generating. The independent truth is ``mgn export bop`` / ``mgn export graspnet`` run on the
finished dataset afterwards (the exported trees must be the same bytes), the mgn scene files of
a run without exports (unchanged), and the files themselves for the object ids (read with json,
numpy and h5py here)."""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml
from conftest import SMALL_DATASET_CONFIG

from mgn.errors import IoError
from mgn.io.bop import export_bop, validate_bop
from mgn.io.graspnet import export_graspnet
from mgn.io.validate import validate_dataset
from mgn.pipeline import generate
from mgn.pipeline.config import ConfigError, dump_config, load_config

SEED = 5
ALL = ["mgn", "bop", "graspnet"]


def _config(formats: list[str] | None = None) -> dict:
    # The shared small config, fewer objects: 2 scenes x 3 views at 120 x 120 px.
    cfg = json.loads(json.dumps(SMALL_DATASET_CONFIG))
    cfg["objects"] = {"categories": ["box_tea", "can_soda"], "copies": [1, 1], "refill": False}
    if formats is not None:
        cfg["output"] = {"formats": formats}
    return cfg


def _tree(root: Path) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in root.rglob("*") if p.is_file()}


def _mtimes(root: Path) -> dict[str, int]:
    return {p.relative_to(root).as_posix(): p.stat().st_mtime_ns for p in root.rglob("*")}


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Two runs of the same seed: ``plain`` (default formats) and ``exported`` ([mgn, bop,
    graspnet]), sharing one label cache."""
    base = tmp_path_factory.mktemp("generate_exports")
    out = {"plain": base / "plain", "exported": base / "exported"}
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MGN_CACHE_DIR", str(base / "cache"))
        for name, formats in (("plain", None), ("exported", ALL)):
            report = generate(
                out[name], 2, config=load_config(_config(formats)), seed=SEED, progress=False
            )
            assert report.complete, report.format_summary()
    return out


def test_exports_equal_mgn_export(runs: dict[str, Path], tmp_path: Path) -> None:
    ds = runs["exported"]
    assert sorted(p.name for p in (ds / "bop" / "train_pbr").iterdir()) == ["000000", "000001"]
    export_bop(ds, tmp_path / "bop")
    export_graspnet(ds, tmp_path / "graspnet")
    for name in ("bop", "graspnet"):
        made, again = _tree(ds / name), _tree(tmp_path / name)
        assert sorted(made) == sorted(again), name
        assert all(made[k] == again[k] for k in made), name
    assert validate_bop(ds / "bop") == []
    assert validate_dataset(ds) == []  # the export folders do not disturb the mgn check
    assert not list(ds.rglob(".*"))  # no temporary leftovers


def test_exports_leave_the_mgn_files_unchanged(runs: dict[str, Path]) -> None:
    for n in (0, 1):
        assert _tree(runs["plain"] / f"scene{n}") == _tree(runs["exported"] / f"scene{n}")
    assert _tree(runs["plain"] / "models") == _tree(runs["exported"] / "models")
    docs = {k: json.loads((v / "dataset.json").read_text()) for k, v in runs.items()}
    assert docs["plain"]["config"]["output"] == {"formats": ["mgn"]}
    assert docs["exported"]["config"]["output"] == {"formats": ALL}
    assert not (runs["plain"] / "bop").exists()
    assert not (runs["plain"] / "graspnet").exists()


def test_object_ids_are_category_ids_in_every_format(runs: dict[str, Path]) -> None:
    ds = runs["exported"]
    folders = {int(p.name) for p in (ds / "models").iterdir() if p.is_dir()}
    info = json.loads((ds / "bop" / "models" / "models_info.json").read_text())
    assert {int(k) for k in info} == folders
    plys = {int(p.stem[4:]) for p in (ds / "bop" / "models").glob("obj_*.ply")}
    assert plys == folders
    checked = 0
    for n in (0, 1):
        gt = json.loads((ds / "bop" / "train_pbr" / f"{n:06d}" / "scene_gt.json").read_text())
        cam = ds / "graspnet" / "scenes" / f"scene_{n:04d}" / "mgn"
        for key, entries in gt.items():
            v = int(key)
            with h5py.File(ds / f"scene{n}" / f"{v}_scene.hdf5", "r") as h:
                cats = np.asarray(h["objects/categories"]).astype(int).tolist()
            assert [e["obj_id"] for e in entries] == cats
            grasp = np.load(cam / "grasp" / f"{v:04d}.npy")
            suction = np.load(cam / "suction" / f"{v:04d}.npz")["arr_0"]
            rect = np.load(cam / "rect" / f"{v:04d}.npy")
            for rows, col in ((grasp, 16), (suction, 7), (rect, 6)):
                ids = set(rows[:, col].astype(int).tolist())
                assert ids <= set(cats) <= folders
                checked += len(rows)
    assert checked > 0


def test_resume_redoes_missing_and_half_written_exports(
    runs: dict[str, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    ds = tmp_path / "ds"
    shutil.copytree(runs["exported"], ds)
    before = {name: _tree(ds / name) for name in ("bop", "graspnet")}
    # Scene 1: its BOP export gone, a half-written one left under atomic_dir's temporary name,
    # its GraspNet export gone too (a stop between the scene and its exports).
    shutil.rmtree(ds / "bop" / "train_pbr" / "000001")
    half = ds / "bop" / "train_pbr" / ".000001.abc123.tmp"
    (half / "rgb").mkdir(parents=True)
    (half / "rgb" / "000000.png").write_bytes(b"partial")
    shutil.rmtree(ds / "graspnet" / "scenes" / "scene_0001")
    (ds / "bop" / "models" / ".models_info.json.xyz.tmp").write_text("{")
    kept = {
        "bop": _mtimes(ds / "bop" / "train_pbr" / "000000"),
        "graspnet": _mtimes(ds / "graspnet" / "scenes" / "scene_0000"),
        "models": _mtimes(ds / "bop" / "models" / "obj_000003.ply"),
    }
    monkeypatch.setenv("MGN_CACHE_DIR", str(runs["exported"].parent / "cache"))
    report = generate(
        ds, 2, config=load_config(_config(ALL)), seed=SEED, resume=True, progress=False
    )
    assert report.complete
    assert report.skipped == [0, 1]
    assert not report.failed
    for name in ("bop", "graspnet"):
        assert _tree(ds / name) == before[name], name
    assert not half.exists()
    assert kept["bop"] == _mtimes(ds / "bop" / "train_pbr" / "000000")  # not redone
    assert kept["graspnet"] == _mtimes(ds / "graspnet" / "scenes" / "scene_0000")
    assert kept["models"] == _mtimes(ds / "bop" / "models" / "obj_000003.ply")


def test_resume_adds_formats_to_a_finished_dataset(
    runs: dict[str, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    ds = tmp_path / "ds"
    shutil.copytree(runs["plain"], ds)
    monkeypatch.setenv("MGN_CACHE_DIR", str(runs["exported"].parent / "cache"))
    report = generate(
        ds, 2, config=load_config(_config(["mgn", "bop"])), seed=SEED, resume=True, progress=False
    )
    assert report.complete
    assert report.skipped == [0, 1]
    assert _tree(ds / "bop") == _tree(runs["exported"] / "bop")
    assert not (ds / "graspnet").exists()
    assert _tree(ds / "scene0") == _tree(runs["plain"] / "scene0")


def test_failed_export_fails_the_scene_and_resume_redoes_it(
    runs: dict[str, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from mgn.pipeline import exports

    ds = tmp_path / "ds"
    shutil.copytree(runs["plain"], ds)
    shutil.rmtree(ds / "scene1")  # scene 1 is generated again, then its export fails
    real = exports.export_graspnet_scene

    def broken(*args: object, **kwargs: object) -> bool:
        raise IoError("simulated: cannot write the grasp files")

    monkeypatch.setenv("MGN_CACHE_DIR", str(runs["exported"].parent / "cache"))
    monkeypatch.setattr(exports, "export_graspnet_scene", broken)
    report = generate(
        ds, 2, config=load_config(_config(ALL)), seed=SEED, resume=True, progress=False
    )
    assert not report.complete
    assert [r.index for r in report.failed] == [0, 1]
    assert all("simulated" in (r.error or "") for r in report.failed)
    assert (ds / "scene1").is_dir()  # the scene itself is complete
    monkeypatch.setattr(exports, "export_graspnet_scene", real)
    report = generate(
        ds, 2, config=load_config(_config(ALL)), seed=SEED, resume=True, progress=False
    )
    assert report.complete
    assert report.skipped == [0, 1]
    for name in ("bop", "graspnet"):
        assert _tree(ds / name) == _tree(runs["exported"] / name), name


@pytest.mark.parametrize(
    ("formats", "names"),
    [
        (["mgn", "coco"], ["output.formats[1]", "'coco'", "'mgn', 'bop', 'graspnet'"]),
        (["bop"], ["output.formats", "includes 'mgn'"]),
        (["mgn", "bop", "bop"], ["output.formats", "distinct"]),
        ("bop", ["output.formats", "a list"]),
        ([], ["output.formats"]),
    ],
)
def test_bad_formats_name_the_key(formats: object, names: list[str]) -> None:
    with pytest.raises(ConfigError) as err:
        load_config({"output": {"formats": formats}})
    for name in names:
        assert name in str(err.value)


def test_bop_with_lens_distortion_is_refused_up_front() -> None:
    intr = {
        "width": 64,
        "height": 48,
        "fx": 60.0,
        "fy": 60.0,
        "cx": 32.0,
        "cy": 24.0,
        "distortion": [0.01, 0.0, 0.0, 0.0],
    }
    cfg = {"camera": {"intrinsics": intr}}
    load_config(cfg)  # fine without the BOP export
    with pytest.raises(ConfigError, match=r"output.formats.*distortion"):
        load_config({**cfg, "output": {"formats": ["mgn", "bop"]}})
    load_config({**cfg, "output": {"formats": ["mgn", "graspnet"]}})


def test_config_dump_lists_the_formats() -> None:
    text = dump_config()
    assert "output:\n  formats: [mgn]\n" in text
    assert load_config(None).output.formats == ("mgn",)
    cfg = load_config({"output": {"formats": ALL}})
    assert dataclasses.asdict(cfg.output) == {"formats": tuple(ALL)}
    assert cfg.output.exports == ("bop", "graspnet")
    assert load_config(yaml.safe_load(dump_config(cfg))) == cfg  # the dump round-trips


def test_collected_scenes_are_exported_by_the_main_process(
    runs: dict[str, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With ``collect`` the workers return the scene files and this process writes them and the
    exports: the same bytes as the workers' own exports."""
    monkeypatch.setenv("MGN_CACHE_DIR", str(runs["exported"].parent / "cache"))
    ds = tmp_path / "ds"
    report = generate(
        ds, 1, config=load_config(_config(ALL)), seed=SEED, collect=True, progress=False
    )
    assert report.complete
    assert set(report.results[0].times) >= {"export: bop", "export: graspnet"}
    ref = runs["exported"]
    for sub in ("bop/train_pbr/000000", "graspnet/scenes/scene_0000"):
        assert _tree(ds / sub) == _tree(ref / sub), sub
