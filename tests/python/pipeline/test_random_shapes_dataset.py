"""A dataset with random procedural objects (``objects.random_shapes``): the scene names them so
that they are rebuilt, their masks, amodal masks and depth match the rebuilt meshes ray-cast
at their poses, their parallel-jaw labels are marked as skipped, and the bytes do not depend
on the worker count."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from mgn.geometry.raytrace import RayScene, camera_rays
from mgn.io.dataset import Dataset
from mgn.io.validate import validate_dataset
from mgn.objects.random_shapes import RANDOM_SOURCE_PREFIX, random_shape_source, random_shapes
from mgn.pipeline import generate
from mgn.pipeline.config import load_config
from mgn.scene.scene import resolve_object

RANDOM = ["random_shape_0000", "random_shape_0003", "random_shape_0005"]
CONFIG = {
    "objects": {
        "names": [*RANDOM, "random_shape_0000", "box_tea"],
        "random_shapes": 6,
        "random_shape_size": [0.04, 0.12],
        "random_shape_seed": 11,
    },
    "camera": {"views": [0, 5], "resolution_scale": 0.1},
    "labels": {"paralleljaw": True, "pj_physics": False},
    "object_labels": {"suction_points": 30, "pj_points": 30},
    "drop": {"max_time": 2.0},
}


def checksums(root: Path) -> dict[str, str]:
    return {
        p.relative_to(root).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    cache = tmp_path_factory.mktemp("cache")
    out = tmp_path_factory.mktemp("rs") / "ds"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MGN_CACHE_DIR", str(cache))
        report = generate(out, 1, config=load_config(CONFIG), seed=2, progress=False)
    assert report.complete, report.format_summary()
    # The random shapes get no parallel-jaw grasps, and the run says so.
    assert set(report.no_paralleljaw) == set(RANDOM)
    assert all("random shape" in why for why in report.no_paralleljaw.values())
    return out


def test_scene_names_the_random_shapes_so_they_are_rebuilt(dataset: Path) -> None:
    scene = json.loads((dataset / "scene0" / "scene.json").read_text())
    pool = {s.name: s for s in random_shapes(6, (0.04, 0.12), 11, 31)}
    placed = [i for i in scene["instances"] if i["name"].startswith("random_shape_")]
    assert {i["name"] for i in placed} <= set(RANDOM)
    assert len(placed) >= 3, scene["removed"]
    for inst in placed:
        assert inst["source"].startswith(RANDOM_SOURCE_PREFIX)
        spec = resolve_object(inst["name"], inst["source"])
        assert spec == pool[inst["name"]]
        assert inst["category_id"] == spec.category_id


def test_dataset_validates_and_labels_say_what_was_skipped(dataset: Path) -> None:
    assert validate_dataset(dataset) == []
    info = json.loads((dataset / "dataset.json").read_text())
    assert info["config"]["objects"]["random_shapes"] == 6
    assert set(info["no_paralleljaw_labels"]) == set(RANDOM)
    for name in RANDOM:
        spec = resolve_object(name, random_shape_source(6, (0.04, 0.12), 11, 31))
        with h5py.File(dataset / "models" / f"{spec.category_id:03d}" / "textured.obj.hdf5") as h5:
            names: list[str] = []
            h5.visit(names.append)
            text = (
                " ".join(names)
                + " "
                + " ".join(str(v) for n in names for v in h5[n].attrs.values())
            )
        assert "suction" in text  # suction labels are computed for random shapes
        assert "random shape" in text  # the parallel-jaw labels say why they are empty


def test_masks_amodal_and_depth_match_the_rebuilt_meshes(dataset: Path) -> None:
    ds = Dataset(dataset)
    scene = ds.scene(0)
    insts = scene.scene_json["instances"]
    checked = depth_checked = 0
    for v in (0, 5):
        view = scene.view(v)
        K = view.intrinsics
        Km = np.array([[K.fx, 0.0, K.cx], [0.0, K.fy, K.cy], [0.0, 0.0, 1.0]])
        o, d = camera_rays(Km, K.width, K.height, np.eye(4))
        ids = view.instances
        depth = view.depth_ideal
        scene_ids = view.hdf5["objects/scene_instance_id"]
        for k, sid in enumerate(scene_ids):  # view instance k + 1 is scene instance sid
            inst = insts[int(sid) - 1]
            if not inst["name"].startswith("random_shape_"):
                continue
            mesh = resolve_object(inst["name"], inst["source"]).to_mesh()
            hits = RayScene(mesh, view.X_CO[k][None]).intersect(o, d, coherent=True)
            sil = hits.hit.reshape(K.height, K.width)
            amodal = view.amodal[k]
            if sil.sum() < 20:
                continue
            iou = (sil & amodal).sum() / (sil | amodal).sum()
            assert iou >= 0.97, (inst["name"], v, iou)
            visible = ids == k + 1
            assert not (visible & ~amodal).any()  # visible part inside the amodal mask
            if visible.sum() >= 10 and depth is not None:
                z = (hits.distance * d[:, 2]).reshape(K.height, K.width)
                inner = visible & sil
                err = np.abs(depth[inner] - z[inner])
                assert np.median(err) < 1e-3, (inst["name"], v, np.median(err))
                depth_checked += 1
            checked += 1
    assert checked >= 2
    assert depth_checked >= 1


def test_two_workers_give_the_same_bytes(dataset: Path, tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("MGN_CACHE_DIR", str(tmp_path / "cache"))
    out = tmp_path / "ds"
    report = generate(out, 1, config=load_config(CONFIG), seed=2, workers=2, progress=False)
    assert report.complete
    assert checksums(out) == checksums(dataset)
