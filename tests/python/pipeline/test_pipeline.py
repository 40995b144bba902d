"""``mgn generate``: determinism across executors, resume after a kill, failures, full disk."""

from __future__ import annotations

import errno
import hashlib
import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import check_difficulty, coco_ground_truth_ap

from mgn.base.deterministic import NPZ_DATE_TIME, h5_create_dataset, h5_create_group, npz_bytes
from mgn.errors import InvalidArgumentError, IoError
from mgn.io.manifest import check_manifest, write_manifest
from mgn.io.scene_schema import view_file_names
from mgn.pipeline import generate, scene_seed, scene_views
from mgn.pipeline.config import Config, load_config

# 2 scenes x 3 views at 120 x 120 px, few objects, tiny label sizes.
SMALL = {
    "objects": {"categories": ["box_tea", "can_soda"], "copies": [1, 2]},
    "camera": {"views": [0, 5, 17], "resolution_scale": 0.1},
    "object_labels": {
        "suction_points": 30,
        "pj_points": 30,
        "physics_grasps": 3,
        "physics_grid": 2,
    },
    "drop": {"max_time": 2.0},
}
SEED = 7


def checksums(root: Path) -> dict[str, str]:
    """sha256 of every file below root (relative POSIX paths)."""
    return {
        p.relative_to(root).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("mgn_cache")


@pytest.fixture
def env(cache_dir: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("MGN_CACHE_DIR", str(cache_dir))
    return cache_dir


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory, cache_dir: Path) -> tuple[Path, dict]:
    """An uninterrupted in-process run (labels computed and cached)."""
    out = tmp_path_factory.mktemp("ref") / "ds"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MGN_CACHE_DIR", str(cache_dir))
        report = generate(out, 2, config=load_config(SMALL), seed=SEED, progress=False)
    assert report.complete, report.format_summary()
    assert report.labels_computed == 2
    assert report.labels_cached == 0
    return out, checksums(out)


def test_reference_dataset_layout(reference: tuple[Path, dict]) -> None:
    out, sums = reference
    doc = json.loads((out / "dataset.json").read_text())
    assert doc["schema_version"] == 1
    assert doc["seed"] == SEED
    assert doc["num_scenes"] == 2
    assert doc["status"] == "complete"
    assert set(doc["splits"]) == {"train", "val", "test"}
    assert Config.from_dict(doc["config"]) == load_config(SMALL)
    for i in range(2):
        folder = out / f"scene{i}"
        assert check_manifest(folder) is None
        scene = json.loads((folder / "scene.json").read_text())
        # Independent re-statement of the documented seed rule.
        expected = int(np.random.SeedSequence([SEED, i]).generate_state(1, np.uint32)[0]) >> 1
        assert scene["seed"] == expected
        assert 2 <= len(scene["instances"]) <= 4
        assert f"scene{i}/scene_gt.json" in sums
        for v in (0, 5, 17):
            for name in view_file_names(v):
                assert f"scene{i}/{name}" in sums
        assert not any(k.startswith(f"scene{i}/1_") for k in sums)  # only the kept views
    assert not list(out.glob(".tmp-*"))
    # The scene suction grasps carry the physics score (MetaGraspNet's colored_pcl.py colours
    # them by it): a number in [0, 1] for every grasp.
    n_suction = 0
    with h5py.File(out / "scene0" / "0_scene.hdf5", "r") as h5:
        for group in ("non_colliding_grasps", "colliding_grasps"):
            name = f"{group}/suctioncup/score_simulation"
            if name in h5:
                sim = np.asarray(h5[name][()], float).reshape(-1)
                n_suction += sim.size
                assert np.isfinite(sim).all(), name
                assert sim.min() >= 0, name
                assert sim.max() <= 1, name
    assert n_suction > 0
    # Object folders carry the labels (rows = labels, no padding).
    for cid in ("003", "006"):
        with h5py.File(out / "models" / cid / "textured.obj.hdf5", "r") as h5:
            pj = h5["grasps/paralleljaw/pregrasp_transform"]
            sc = h5["grasps/suctioncup/pregrasp_transform"]
            assert pj.shape[1] == 10
            assert pj.shape[0] > 0
            assert sc.shape[1] == 6
            assert 0 < sc.shape[0] <= 30
            # Suction physics: seal score x share of the 2 x 2 grid held, for every grasp.
            seal = np.asarray(h5["grasps/suctioncup/quality_score"])
            ssim = np.asarray(h5["grasps/suctioncup/quality_score_simulation"])
            assert ssim.shape == seal.shape
            assert np.isfinite(ssim).all()
            assert ((ssim >= 0) & (ssim <= seal)).all()
            held = ssim[seal > 0] / seal[seal > 0]
            assert np.isin(np.round(held * 4), [0, 1, 2, 3, 4]).all()
            sim = np.asarray(h5["grasps/paralleljaw/quality_score_simulation"])
            assert np.isfinite(sim).sum() == 3  # physics_grasps
            meta = h5["metadata"].attrs
            assert int(meta["pj_physics_scored"]) == 3
            assert int(meta["pj_physics_unscored"]) == sim.shape[0] - 3
    # The cap is recorded in dataset.json: every object's stored and scored grasps.
    rec = doc["physics_scores"]
    assert rec["cap"] == 3
    assert rec["search"] == "staircase"
    assert rec["grid"] == 2
    assert rec["checks"] == load_config({}).object_labels.staircase_checks == 0
    assert rec["calibration"] == load_config({}).object_labels.physics_calibration == 32
    assert set(rec["objects"]) == {"box_tea", "can_soda"}
    assert rec["capped_objects"] == ["box_tea", "can_soda"]
    assert all(o["scored"] == 3 for o in rec["objects"].values())
    assert rec["unscored"] == rec["grasps"] - 6 > 0


def test_every_stored_pj_grasp_gets_a_physics_score_by_default(tmp_path: Path, env: Path) -> None:
    """No cap (the default): no stored parallel-jaw grasp, in the object files or in the scene
    grasp files, is left without a physics score, and dataset.json says so."""
    cfg = {
        "objects": {"names": ["box_tea"]},
        "camera": {"views": [0], "resolution_scale": 0.1},
        "object_labels": {"suction_points": 30, "pj_points": 8, "physics_grid": 2},
        "labels": {"suction": False, "layout": False},
        "drop": {"max_time": 2.0},
    }
    assert load_config(cfg).object_labels.physics_grasps is None
    report = generate(tmp_path / "ds", 1, config=load_config(cfg), seed=3, progress=False)
    assert report.complete, report.format_summary()
    doc = json.loads((tmp_path / "ds" / "dataset.json").read_text())
    rec = doc["physics_scores"]
    assert rec["cap"] is None
    assert rec["unscored"] == 0
    assert rec["capped_objects"] == []
    assert rec["grasps"] == rec["scored"] == rec["objects"]["box_tea"]["grasps"] > 0
    (model,) = (tmp_path / "ds" / "models").iterdir()
    with h5py.File(model / "textured.obj.hdf5", "r") as h5:
        sim = np.asarray(h5["grasps/paralleljaw/quality_score_simulation"])
    assert sim.shape == (rec["grasps"],)
    assert np.isfinite(sim).all()
    n_scene = 0
    with h5py.File(tmp_path / "ds" / "scene0" / "0_scene.hdf5", "r") as h5:
        for group in ("non_colliding_grasps", "colliding_grasps"):
            name = f"{group}/paralleljaw/score_simulation"
            if name in h5:
                scene_sim = np.asarray(h5[name][()], float).reshape(-1)
                n_scene += scene_sim.size
                assert np.isfinite(scene_sim).all(), name
    assert n_scene > 0
    assert "physics scores" not in report.format_summary()  # nothing capped to report
    # Written without layout labels: _order.json holds no occlusion rates, and the dataset is
    # still valid (the rates are checked in the masks, the HDF5 file and the image).
    from mgn.io.validate import validate_dataset

    assert json.loads((tmp_path / "ds" / "scene0" / "0_layout.json").read_text()) == {}
    assert validate_dataset(tmp_path / "ds") == []


def test_generate_says_where_the_time_went(
    tmp_path: Path, env: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``mgn generate`` estimates the object labels before it starts, ends with where the
    time went (per object; drop, render parts, labels, write) and ``--profile`` writes it as
    JSON; the path engine's parts (trace, denoise, develop) are timed separately."""
    from mgn.cli.main import main

    cfg = {
        "objects": {"names": ["box_tea"]},
        "camera": {"views": [0], "resolution_scale": 0.1},
        "object_labels": {"suction_points": 30, "pj_points": 8, "physics_grid": 2},
        "labels": {"layout": False},
        "drop": {"max_time": 2.0},
        "render": {"engine": "path"},
    }
    (tmp_path / "cfg.yaml").write_text(json.dumps(cfg))
    prof = tmp_path / "profile.json"
    code = main(
        [
            "generate",
            "--out",
            str(tmp_path / "ds"),
            "--scenes",
            "1",
            "--config",
            str(tmp_path / "cfg.yaml"),
            "--no-cache",
            "--profile",
            str(prof),
        ]
    )
    out = capsys.readouterr()
    assert code == 0, out.out + out.err
    assert "object labels: 1 to compute, 0 from the cache; roughly" in out.err
    assert "per object: box_tea" in out.out
    assert "where the scene time went" in out.out
    p = json.loads(prof.read_text())
    assert p["object_labels"]["computed"] == 1
    assert p["object_labels"]["cached"] == 0
    (seconds,) = p["object_labels"]["objects_s"].values()
    assert 0 < seconds <= p["object_labels"]["wall_s"] <= p["wall_s"]
    parts = p["scenes"]["parts_s"]
    for part in (
        "drop",
        "render: trace",
        "render: denoise",
        "render: develop",
        "render: raster",
        "render: sensor",
        "object labels",
        "scene grasps",
        "finalize",
    ):
        assert part in parts, part
        assert parts[part] >= 0.0, part
    assert parts["render: trace"] > 0
    assert p["scenes"]["written"] == 1
    # The render thread's parts add up to no more than its busy time.
    render_parts = sum(v for k, v in parts.items() if k.startswith("render: "))
    assert render_parts <= parts["render"] + 1e-3


def test_label_time_estimate_brackets_the_cost_model() -> None:
    from mgn.pipeline.label_cache import (
        COMPOUND_TRIAL_FACTOR,
        TRIAL_CPU_S,
        estimate_label_seconds,
    )

    cfg = load_config({"object_labels": {"pj_grasps": 100, "physics_grid": 10}})
    low, high = estimate_label_seconds(cfg, 2, 2)
    assert 0 < low < high
    # At least the first stage's 12 calibration grids of 100 trials each per object, on 2
    # cores, and the plain staircase's 6 trials for each of the other 88 grasps; the high end
    # all 32 calibration grids at a compound's cost per trial (40 solver iterations).
    assert low >= 2 * (12 * 100 + 88 * 6) * TRIAL_CPU_S / 2
    assert low < 2 * 32 * 100 * TRIAL_CPU_S / 2
    assert high >= 2 * 32 * 100 * COMPOUND_TRIAL_FACTOR * TRIAL_CPU_S / 2
    one_stage = load_config(
        {"object_labels": {"pj_grasps": 100, "physics_grid": 10, "physics_calibration_min": 0}}
    )
    assert estimate_label_seconds(one_stage, 2, 2)[0] >= 2 * 32 * 100 * TRIAL_CPU_S / 2
    # Without physics only the sampling is left; more cores, less time.
    off = load_config({"labels": {"pj_physics": False}})
    assert estimate_label_seconds(off, 2, 2)[1] < low
    assert estimate_label_seconds(cfg, 2, 4)[0] == pytest.approx(low / 2)


def test_reference_dataset_validates_reads_and_exports(
    reference: tuple[Path, dict], tmp_path: Path
) -> None:
    """The issue's end-to-end check: validate, read back, COCO (AP = 1 for the ground truth
    against itself), and `mgn show` writes a PNG of the view's size."""
    from PIL import Image
    from pycocotools.coco import COCO

    from mgn.cli.main import main
    from mgn.io import coco
    from mgn.io.dataset import Dataset
    from mgn.io.validate import validate_dataset

    out, _ = reference
    assert validate_dataset(out) == []
    ds = Dataset(out)
    assert ds.scene_ids == [0, 1]
    assert ds.info["seed"] == SEED
    view = ds.scene(1).view(5)
    n = len(ds.scene(1).scene_json["instances"])
    assert view.amodal.shape[0] == n
    assert view.instances.max() <= n
    assert view.rgb.shape == (*view.depth.shape, 3)
    assert np.nanmax(view.depth) < 2.0
    check_difficulty(view.layout)  # asserts the stored level is Table IV of its entries
    ann = coco.export_coco(ds, tmp_path / "annotations.json")
    gt = COCO(str(ann))
    anns = gt.loadAnns(gt.getAnnIds())
    assert len(gt.getImgIds()) == 6
    assert anns
    assert coco_ground_truth_ap(gt) == (pytest.approx(1.0), pytest.approx(1.0))
    png = tmp_path / "show.png"
    args = ["show", str(out), "--scene", "0", "--view", "17", "--grasps", "pj", "--layout"]
    assert main([*args, "-o", str(png)]) == 0
    with Image.open(png) as im:
        # The view with its legend below (what the colours and labels mean).
        assert im.size[0] == view.intrinsics.width
        assert im.size[1] > view.intrinsics.height + 20
        assert np.asarray(im).std() > 0


def test_two_workers_give_the_same_bytes(
    reference: tuple[Path, dict], tmp_path: Path, env: Path
) -> None:
    out = tmp_path / "ds"
    report = generate(out, 2, config=load_config(SMALL), seed=SEED, workers=2, progress=False)
    assert report.complete
    assert report.labels_cached == 2
    assert checksums(out) == reference[1]


def test_four_workers_collecting_give_the_same_bytes(
    reference: tuple[Path, dict], tmp_path: Path, env: Path
) -> None:
    """Workers that write into folders of their own and send the files back (--collect, for
    cluster workers without a shared disk) give the same dataset, byte for byte."""
    out = tmp_path / "ds"
    report = generate(
        out, 2, config=load_config(SMALL), seed=SEED, workers=4, collect=True, progress=False
    )
    assert report.complete
    assert all(r.files is None for r in report.results.values())
    assert checksums(out) == reference[1]
    assert not list(out.glob(".tmp-*"))


def test_dask_local_cluster_gives_the_same_bytes(
    reference: tuple[Path, dict], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import distributed  # the optional 'cluster' extra

    # A fresh cache: the object labels are computed on the Dask workers too.
    monkeypatch.setenv("MGN_CACHE_DIR", str(tmp_path / "cache"))
    out = tmp_path / "ds"
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        report = generate(
            out,
            2,
            config=load_config(SMALL),
            seed=SEED,
            scheduler=cluster.scheduler_address,
            progress=False,
        )
    assert report.complete
    assert report.labels_computed == 2
    assert checksums(out) == reference[1]


KILL_SCRIPT = """
import os, signal, sys
from pathlib import Path
import mgn.pipeline.scene_writer as sw
real = sw.write_scene
def dying(scene, folder, config, labels):
    stages = real(scene, folder, config, labels)
    if Path(folder).name.startswith(".tmp-scene1-"):
        (Path(folder) / "half.bin").write_bytes(b"x" * 10)
        os.kill(os.getpid(), signal.SIGKILL)  # killed mid-scene
    return stages
sw.write_scene = dying
from mgn.pipeline.config import load_config
from mgn.pipeline import generate
generate(sys.argv[1], 2, config=load_config({config!r}), seed={seed}, progress=False)
"""


def test_killed_run_resumes_to_the_same_dataset(
    reference: tuple[Path, dict], tmp_path: Path, env: Path
) -> None:
    out = tmp_path / "ds"
    script = tmp_path / "kill.py"
    script.write_text(KILL_SCRIPT.format(config=SMALL, seed=SEED))
    proc = subprocess.run(
        [sys.executable, str(script), str(out)], check=False, capture_output=True, timeout=120
    )
    assert proc.returncode == -9, proc.stderr.decode()[-2000:]
    assert check_manifest(out / "scene0") is None
    assert not (out / "scene1").exists()
    assert len(list(out.glob(".tmp-scene1-*"))) == 1  # the half scene, under its temporary name
    assert json.loads((out / "dataset.json").read_text())["status"] == "running"
    with pytest.raises(IoError, match="--resume"):
        generate(out, 2, config=load_config(SMALL), seed=SEED, progress=False)
    report = generate(out, 2, config=load_config(SMALL), seed=SEED, resume=True, progress=False)
    assert report.skipped == [0]
    assert [r.index for r in report.ok] == [1]
    assert checksums(out) == reference[1]


def test_interrupt_leaves_no_half_scene_and_resume_redoes_bad_scenes(
    reference: tuple[Path, dict], tmp_path: Path, env: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import mgn.pipeline.scene_writer as sw

    real = sw.write_scene

    def interrupted(scene, folder, config, labels):
        stages = real(scene, folder, config, labels)
        if Path(folder).name.startswith(".tmp-scene1-"):
            raise KeyboardInterrupt
        return stages

    out = tmp_path / "ds"
    monkeypatch.setattr(sw, "write_scene", interrupted)
    with pytest.raises(KeyboardInterrupt):
        generate(out, 2, config=load_config(SMALL), seed=SEED, progress=False)
    assert not list(out.glob(".tmp-*"))
    assert not (out / "scene1").exists()
    monkeypatch.setattr(sw, "write_scene", real)
    # A complete-looking scene whose file no longer matches its manifest is redone.
    shutil.copytree(reference[0] / "scene1", out / "scene1")
    (out / "scene1" / "0_rgb.png").write_bytes(b"corrupt")
    report = generate(out, 2, config=load_config(SMALL), seed=SEED, resume=True, progress=False)
    assert report.skipped == [0]
    assert [r.index for r in report.ok] == [1]
    assert checksums(out) == reference[1]


def test_resume_refuses_another_seed_or_config(reference: tuple[Path, dict], env: Path) -> None:
    out = reference[0]
    with pytest.raises(InvalidArgumentError, match="seed"):
        generate(out, 2, config=load_config(SMALL), seed=SEED + 1, resume=True, progress=False)
    other = load_config({**SMALL, "drop": {"max_time": 3.0}})
    with pytest.raises(InvalidArgumentError, match="config differs"):
        generate(out, 2, config=other, seed=SEED, resume=True, progress=False)
    assert checksums(out) == reference[1]  # nothing was touched


CUBE_OBJ = """mtllib cube.mtl
usemtl grey
v -0.5 -0.5 -0.5
v 0.5 -0.5 -0.5
v 0.5 0.5 -0.5
v -0.5 0.5 -0.5
v -0.5 -0.5 0.5
v 0.5 -0.5 0.5
v 0.5 0.5 0.5
v -0.5 0.5 0.5
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
"""


def test_failing_scene_is_reported_and_the_others_finish(tmp_path: Path, env: Path) -> None:
    """A 1 m cube cannot be dropped into the 0.4 m tote: the scenes that draw it fail."""
    (tmp_path / "cube.obj").write_text(CUBE_OBJ)
    (tmp_path / "cube.mtl").write_text("newmtl grey\nKd 0.6 0.6 0.6\nKs 0.1 0.1 0.1\nNs 20\n")
    (tmp_path / "objects.yaml").write_text(
        "objects:\n  - {name: huge_cube, mesh: cube.obj, density: 100, friction: 0.5}\n"
    )
    cfg = dict(SMALL)
    cfg["objects"] = {
        "categories": ["box_tea", "huge_cube"],
        "count": 1,
        "copies": [1, 1],
        "user_objects": [str(tmp_path / "objects.yaml")],
    }
    config = load_config(cfg)
    from mgn.objects import builtin_objects, load_objects_yaml
    from mgn.scene import compose_objects

    catalogue = [*builtin_objects(), *load_objects_yaml(tmp_path / "objects.yaml")]
    n = 6
    drawn = [
        compose_objects(
            **config.objects.compose_kwargs(), seed=scene_seed(SEED, i), catalogue=catalogue
        )[0].name
        for i in range(n)
    ]
    bad = [i for i, name in enumerate(drawn) if name == "huge_cube"]
    assert 0 < len(bad) < n  # the seed draws both kinds of scene
    out = tmp_path / "ds"
    report = generate(out, n, config=config, seed=SEED, progress=False)
    assert [r.index for r in report.failed] == bad
    assert sorted(r.index for r in report.ok) == sorted(set(range(n)) - set(bad))
    for r in report.failed:
        assert r.seed == scene_seed(SEED, r.index)
        assert "huge_cube" in r.error
        assert f"scene{r.index} (seed {r.seed})" in report.format_summary()
        assert not (out / f"scene{r.index}").exists()
    doc = json.loads((out / "dataset.json").read_text())
    assert doc["status"] == "incomplete"
    assert [f["scene"] for f in doc["failed_scenes"]] == bad
    assert not list(out.glob(".tmp-*"))


def test_disk_full_is_reported_with_the_path(
    tmp_path: Path, env: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    import mgn.pipeline.scene_writer as sw
    from mgn.cli.main import main

    def full(scene, folder, config, labels):
        path = Path(folder) / "0_rgb.png"
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    monkeypatch.setattr(sw, "write_scene", full)
    cfg = tmp_path / "small.yaml"
    cfg.write_text(json.dumps(SMALL))  # JSON is YAML
    out = tmp_path / "ds"
    argv = ["generate", "--scenes", "3", "--out", str(out), "--config", str(cfg), "--quiet"]
    assert main(argv) == 1
    text = capsys.readouterr().out
    assert "disk full while writing scene0" in text
    assert "0_rgb.png" in text
    assert "not run: scene1, scene2" in text  # no new scene is started on a full disk
    assert not list(out.glob("scene*"))
    assert not list(out.glob(".tmp-*"))


def test_scene_seed_rule() -> None:
    seeds = [scene_seed(3, i) for i in range(100)]
    assert len(set(seeds)) == 100
    assert all(0 <= s < 2**31 for s in seeds)
    assert scene_seed(3, 5) != scene_seed(5, 3)
    with pytest.raises(InvalidArgumentError, match="seed"):
        scene_seed(-1, 0)
    with pytest.raises(InvalidArgumentError, match="index"):
        scene_seed(0, -2)


def test_bad_arguments_are_refused_before_writing(tmp_path: Path, env: Path) -> None:
    out = tmp_path / "ds"
    with pytest.raises(InvalidArgumentError, match="--scenes"):
        generate(out, 0, config=load_config(SMALL), progress=False)
    with pytest.raises(InvalidArgumentError, match="--workers"):
        generate(out, 1, config=load_config(SMALL), workers=0, progress=False)
    with pytest.raises(InvalidArgumentError, match="objects"):
        generate(out, 1, config=load_config(SMALL), objects=["no_such_object"], progress=False)
    assert not out.exists()


def test_scene_views_follow_the_rig() -> None:
    from mgn.objects import ToteSpec
    from mgn.scene import Scene
    from mgn.scene.cameras import hemisphere_rig, mgn_rig

    scene = Scene((), ToteSpec(), 11)
    cfg = load_config({"camera": {"views": [0, 5, 17], "resolution_scale": 0.5}})
    views = scene_views(scene, cfg.camera)
    poses, _ = mgn_rig(11)
    assert [v for v, _ in views] == [0, 5, 17]
    for v, cam in views:
        np.testing.assert_array_equal(cam.X_WC, poses[v])
        assert (cam.K.width, cam.K.height) == (600, 600)
    hemi = {"radii": [0.8], "tilts": [0.2, 0.5], "azimuths": [0.0, 1.0, 2.0]}
    cfg = load_config({"camera": {"rig": "hemisphere", "hemisphere": hemi, "views": [4, 1]}})
    poses = hemisphere_rig(hemi["radii"], hemi["tilts"], hemi["azimuths"])
    views = scene_views(scene, cfg.camera)
    assert [v for v, _ in views] == [4, 1]
    np.testing.assert_array_equal(views[0][1].X_WC, poses[4])


def test_manifest_detects_missing_resized_and_altered_files(tmp_path: Path) -> None:
    (tmp_path / "a.bin").write_bytes(b"abc")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "b.txt").write_text("hello")
    m = write_manifest(tmp_path, scene=3)
    assert m["scene"] == 3
    assert m["files"]["sub/b.txt"] == {
        "size": 5,
        "sha256": hashlib.sha256(b"hello").hexdigest(),
    }
    assert check_manifest(tmp_path) is None
    (tmp_path / "a.bin").write_bytes(b"abd")  # same size, other bytes
    assert "checksum" in check_manifest(tmp_path)
    assert check_manifest(tmp_path, checksums=False) is None
    (tmp_path / "a.bin").write_bytes(b"abcd")
    assert "4 bytes" in check_manifest(tmp_path)
    (tmp_path / "sub" / "b.txt").unlink()
    (tmp_path / "a.bin").write_bytes(b"abc")
    assert "missing file 'sub/b.txt'" in check_manifest(tmp_path)
    (tmp_path / "manifest.json").unlink()
    assert check_manifest(tmp_path) == "no manifest"


def test_npz_bytes_are_reproducible_and_readable() -> None:
    import io

    arrays = {
        "depth": np.linspace(0, 1, 12, dtype=np.float32).reshape(3, 4),
        "ok": np.eye(3, 4) > 0,
    }
    data = npz_bytes(**arrays)
    with np.load(io.BytesIO(data)) as z:
        assert z.files == ["depth", "ok"]
        for k, v in arrays.items():
            np.testing.assert_array_equal(z[k], v)
            assert z[k].dtype == v.dtype
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        assert all(i.date_time == NPZ_DATE_TIME for i in zf.infolist())
        assert all(i.compress_type == zipfile.ZIP_DEFLATED for i in zf.infolist())
    assert npz_bytes(**arrays) == data
    with pytest.raises(ValueError, match="object"):
        npz_bytes(bad=np.array([None, 1], dtype=object))


def test_npz_entries_are_plain_deflate_at_their_level_that_zlib_reads() -> None:
    """Deflated entries are raw deflate streams that zlib itself inflates to numpy's own .npy
    bytes; a higher level (``levels``) gives a smaller mask entry, and the bytes repeat."""
    import io
    import zlib

    rng = np.random.default_rng(5)
    mask = np.zeros((6, 200, 300), bool)
    for i in range(6):
        y, x = rng.integers(0, 150, 2)
        mask[i, y : y + 50, x : x + 120] = True
    occ = rng.random((200, 300)).astype(np.float32)
    data = npz_bytes(mask=mask, occ=occ, levels={"mask": 6})
    fast = npz_bytes(mask=mask, occ=occ)
    with np.load(io.BytesIO(data)) as z:
        assert z["mask"].dtype == bool
        assert np.array_equal(z["mask"], mask)
        assert np.array_equal(z["occ"].view(np.uint32), occ.view(np.uint32))
    with zipfile.ZipFile(io.BytesIO(data)) as zf, zipfile.ZipFile(io.BytesIO(fast)) as zp:
        for name, array in (("mask.npy", mask), ("occ.npy", occ)):
            info = zf.getinfo(name)
            assert info.compress_type == zipfile.ZIP_DEFLATED
            expected = io.BytesIO()
            np.lib.format.write_array(expected, array, allow_pickle=False)
            raw = data[info.header_offset :]  # the local header, then the raw stream
            name_len, extra_len = np.frombuffer(raw[26:30], "<u2")
            stream = raw[30 + name_len + extra_len :][: info.compress_size]
            assert zlib.decompress(stream, -15) == expected.getvalue()
            assert zlib.crc32(expected.getvalue()) == info.CRC
        assert zf.getinfo("mask.npy").compress_size < zp.getinfo("mask.npy").compress_size
    assert npz_bytes(mask=mask, occ=occ, levels={"mask": 6}) == data
    # zlib_levels: that entry is zlib's stream at that level (the .npy header a stored block
    # before it, a sync flush and an empty final block after it: < 200 bytes more; the other
    # entry stays libdeflate's).
    mixed = npz_bytes(mask=mask, occ=occ, levels={"mask": 6}, zlib_levels={"occ": 1})
    with zipfile.ZipFile(io.BytesIO(mixed)) as zm, zipfile.ZipFile(io.BytesIO(data)) as zf:
        c = zlib.compressobj(1, zlib.DEFLATED, -15)
        npy = zm.read("occ.npy")
        plain = len(c.compress(npy) + c.flush())
        assert plain <= zm.getinfo("occ.npy").compress_size <= plain + 200
        assert zm.getinfo("mask.npy").compress_size == zf.getinfo("mask.npy").compress_size
        assert np.load(io.BytesIO(mixed))["occ"].tobytes() == occ.tobytes()


def test_h5_helpers_write_without_timestamps(tmp_path: Path) -> None:
    path = tmp_path / "a.h5"
    with h5py.File(path, "w", libver="latest") as h5:  # v2 object headers can hold times
        g = h5_create_group(h5, "grasps/paralleljaw")
        d = h5_create_dataset(g, "quality_score", np.arange(4, dtype=np.float32))
        control = h5.create_dataset("stamped", data=np.zeros(2), track_times=True)
        assert h5py.h5g.get_objinfo(control.id).mtime > 0  # the check can see a timestamp
        assert h5py.h5g.get_objinfo(g.id).mtime == 0
        assert h5py.h5g.get_objinfo(d.id).mtime == 0
    with h5py.File(path, "r") as h5:
        np.testing.assert_array_equal(h5["grasps/paralleljaw/quality_score"], np.arange(4))


def test_label_cache_key_is_bumped_for_compound_solver_iterations(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Parallel-jaw physics scores of compounds changed when the shake test's grip controller
    started reading the net pad force (object-labels-10), when compounds got 40 solver
    iterations (object-labels-11) and when a compound touched at many points got fewer
    (object-labels-12): entries written under a previous version's keys must not be found."""
    from mgn.objects import get_object
    from mgn.pipeline import label_cache

    assert label_cache.CACHE_VERSION == "object-labels-12"
    spec, config = get_object("pipe_elbow"), Config()
    keys = label_cache.label_keys(spec, config)
    assert set(keys) == {"suction", "paralleljaw"}
    for previous in ("object-labels-9", "object-labels-10", "object-labels-11"):
        monkeypatch.setattr(label_cache, "CACHE_VERSION", previous)
        old = label_cache.label_keys(spec, config)
        assert all(old[kind] != keys[kind] for kind in keys)


def test_label_cache_round_trip_and_keys(tmp_path: Path, env: Path) -> None:
    import dataclasses

    from mgn.objects import get_object
    from mgn.pipeline.label_cache import (
        compute_object_labels,
        label_keys,
        load_cached_labels,
        object_labels,
        shake_options,
    )

    spec = get_object("box_tea")
    config = load_config(SMALL)
    computed = compute_object_labels(spec, config, num_threads=1)
    got = object_labels(spec, config)  # cached by the reference run, or computed now
    cached = load_cached_labels(spec, config)
    assert cached is not None
    for kind in ("suction", "paralleljaw"):
        a, b, c = (getattr(x, kind) for x in (computed, got, cached))
        for f in dataclasses.fields(a):
            va, vb, vc = (getattr(x, f.name) for x in (a, b, c))
            if isinstance(va, np.ndarray):
                np.testing.assert_array_equal(va, vb)
                np.testing.assert_array_equal(va, vc)
                assert va.dtype == vc.dtype
            else:
                assert va == vb == vc
    keys = label_keys(spec, config)
    other_cup = dataclasses.replace(config, cup=dataclasses.replace(config.cup, radius=0.01))
    assert label_keys(spec, other_cup)["suction"] != keys["suction"]
    assert label_keys(spec, other_cup)["paralleljaw"] == keys["paralleljaw"]
    heavier = dataclasses.replace(spec, density=spec.density * 2)
    assert label_keys(heavier, config) != keys
    no_physics = load_config({**SMALL, "labels": {"pj_physics": False, "suction": False}})
    assert set(label_keys(spec, no_physics)) == {"paralleljaw"}
    assert label_keys(spec, no_physics)["paralleljaw"] != keys["paralleljaw"]
    more_checks = dataclasses.replace(
        config,
        object_labels=dataclasses.replace(
            config.object_labels, physics_checks=config.object_labels.staircase_checks + 1
        ),
    )
    assert label_keys(spec, more_checks)["paralleljaw"] != keys["paralleljaw"]
    calibrated = dataclasses.replace(
        config,
        object_labels=dataclasses.replace(config.object_labels, physics_calibration=3),
    )
    assert label_keys(spec, calibrated)["paralleljaw"] != keys["paralleljaw"]
    assert label_keys(spec, more_checks)["suction"] == keys["suction"]
    # The suction physics score depends on the grid and the cup's bending limit.
    grid3 = dataclasses.replace(
        config, object_labels=dataclasses.replace(config.object_labels, physics_grid=3)
    )
    assert label_keys(spec, grid3)["suction"] != keys["suction"]
    stiff = dataclasses.replace(config, cup=dataclasses.replace(config.cup, bending_k=20.0))
    assert label_keys(spec, stiff)["suction"] != keys["suction"]
    assert label_keys(spec, stiff)["paralleljaw"] == keys["paralleljaw"]
    o = shake_options(more_checks).to_core()
    assert o.staircase
    assert o.staircase_checks == config.object_labels.staircase_checks + 1
    assert o.grid == config.object_labels.physics_grid
