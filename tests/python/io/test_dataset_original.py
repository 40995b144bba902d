"""Reading original MetaGraspNet scene folders: the files an mgn dataset adds are absent, the
relation CSV is written by numpy.savetxt (floats) or missing for some views, and synthetic scenes
have no camera parameter files. The folder is made by stripping a generated dataset, so the
values read must equal what the full mgn dataset gives."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from mgn.io.coco import coco_dict
from mgn.io.dataset import Dataset

MGN_ONLY = ("dataset.json", "scene.json", "manifest.json")


@pytest.fixture
def original_like(small_dataset: Path, tmp_path: Path) -> Path:
    root = tmp_path / "metagraspnet"
    shutil.copytree(small_dataset, root)
    for p in sorted(root.rglob("*")):
        name = p.name
        if p.is_file() and (
            name in MGN_ONLY or name.endswith(("_layout.json", "_camera_params.json"))
        ):
            p.unlink()
    for scene in Dataset(root).scenes():
        views = scene.view_ids
        # First view: the CSV as numpy.savetxt writes it; second view: no CSV at all.
        m = np.loadtxt(scene.folder / f"{views[0]}_order.csv", delimiter=",", ndmin=2)
        np.savetxt(scene.folder / f"{views[0]}_order.csv", m, delimiter=",")
        (scene.folder / f"{views[1]}_order.csv").unlink()
    return root


def test_original_folder_reads_like_the_full_dataset(small_dataset: Path, original_like: Path):
    full, orig = Dataset(small_dataset), Dataset(original_like)
    assert orig.info is None
    assert full.info is not None
    assert orig.scene_ids == full.scene_ids
    relations = 0
    for sid in full.scene_ids:
        fs, os_ = full.scene(sid), orig.scene(sid)
        assert os_.scene_json is None
        assert os_.view_ids == fs.view_ids
        for v in fs.view_ids:
            a, b = fs.view(v), os_.view(v)
            assert b.layout is None
            # The camera of MGN's synthetic scenes (35 mm on 20.955 mm) at the image size.
            ka, kb = a.intrinsics, b.intrinsics
            assert (kb.width, kb.height) == (ka.width, ka.height)
            np.testing.assert_allclose([kb.fx, kb.fy, kb.cx, kb.cy], [ka.fx, ka.fy, ka.cx, ka.cy])
            np.testing.assert_array_equal(b.relation_matrix, a.relation_matrix)
            relations += int((b.relation_matrix == -1).sum())
            np.testing.assert_array_equal(b.instances, a.instances)
            np.testing.assert_array_equal(b.X_CO, a.X_CO)
            for kind in ("paralleljaw", "suctioncup"):
                ga, gb = a.grasps(kind), b.grasps(kind)
                assert ga.keys() == gb.keys()
    assert relations > 0  # the comparison covered real occlusion relations


def test_coco_export_of_an_original_folder(original_like: Path) -> None:
    doc = coco_dict(Dataset(original_like))
    assert doc["images"]
    assert doc["annotations"]
    # No layout files: no difficulty on the images, the rest of the export is there.
    assert all("difficulty" not in im for im in doc["images"])
    assert all(a["segmentation"]["counts"] for a in doc["annotations"])
