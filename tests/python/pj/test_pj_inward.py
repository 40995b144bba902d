"""Closed meshes wound inward get the same parallel-jaw labels as outward ones (issue 16, item 5):
``label_object``, ``mgn pj label`` and ``mgn-cli pj``."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import trimesh

from mgn.cli import main
from mgn.geometry import make_box, mass_properties
from mgn.pj import label_object

BOX = (0.04, 0.06, 0.12)  # x and y graspable (< 80 mm), z not


def _write_stl(mesh, path: Path, *, inward: bool) -> None:
    faces = np.asarray(mesh.faces)
    if inward:
        faces = faces[:, ::-1]
    trimesh.Trimesh(np.asarray(mesh.vertices), faces, process=False).export(path)


def _across_a_side(w) -> bool:
    # A chord across a side of width s inside the friction cone (half-angle pi/8) is s..s/cos.
    c = np.cos(np.pi / 8)
    w = np.asarray(w, np.float64)
    return bool(np.all(((w > 0.0399) & (w < 0.04 / c)) | ((w > 0.0599) & (w < 0.06 / c))))


def _labels(mesh):
    props = mass_properties(mesh, 1000.0)
    return label_object(mesh, mass=props.mass, com=props.center_of_mass, num_points=40, seed=3)


def test_inward_mesh_gives_the_labels_of_the_outward_mesh(tmp_path: Path) -> None:
    import mgn

    _write_stl(make_box(BOX), tmp_path / "out.stl", inward=False)
    _write_stl(make_box(BOX), tmp_path / "in.stl", inward=True)
    outward, inward = mgn.load_mesh(tmp_path / "out.stl"), mgn.load_mesh(tmp_path / "in.stl")
    assert inward.validate().signed_volume < 0 < outward.validate().signed_volume
    a, b = _labels(outward), _labels(inward)
    # The reversed winding changes where in each triangle the even sampler puts its points, so
    # the grasps are not the same rows; they are the same kind and about as many.
    assert len(a) > 0
    assert 0.8 * len(a) <= len(b) <= 1.25 * len(a)
    for labels in (a, b):  # the box is grasped across its 40 or 60 mm sides
        assert _across_a_side(labels.width)
    assert abs(b.quality_score.mean() - a.quality_score.mean()) < 0.1


def test_cli_labels_an_inward_mesh(tmp_path: Path) -> None:
    _write_stl(make_box(BOX), tmp_path / "in.stl", inward=True)
    out = tmp_path / "labels.hdf5"
    args = ["pj", "label", str(tmp_path / "in.stl"), "--out", str(out)]
    assert main([*args, "--no-physics", "--points", "40", "--quiet"]) == 0
    with h5py.File(out, "r") as h5:
        assert len(h5["grasps/paralleljaw/pregrasp_transform"]) > 0


def test_cpp_cli_labels_an_inward_mesh(tmp_path: Path) -> None:
    exe = shutil.which("mgn-cli") or str(Path(sys.executable).parent / "mgn-cli")
    _write_stl(make_box(BOX), tmp_path / "in.stl", inward=True)
    _write_stl(make_box(BOX), tmp_path / "out.stl", inward=False)
    rows = []
    for name in ("in", "out"):
        out = tmp_path / f"{name}.json"
        r = subprocess.run(
            [exe, "pj", "--mesh", str(tmp_path / f"{name}.stl"), "--out", str(out)]
            + ["--points", "30", "--seed", "2"],
            check=False,
            capture_output=True,
            text=True,
        )
        assert r.returncode == 0, r.stderr
        rows.append(np.asarray(json.loads(out.read_text())["pregrasp_transform"]))
    inward, outward = rows
    assert len(outward) > 0
    assert 0.8 * len(outward) <= len(inward) <= 1.25 * len(outward)
    assert _across_a_side(inward[:, 9])
