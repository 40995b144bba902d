"""Parallel-jaw labels (MODELS.md §5): sampler, collision, wrench score, HDF5 writer, CLIs."""

import dataclasses
import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import fcl
import h5py
import numpy as np
import pytest
import trimesh

import mgn
from mgn.cli.main import main
from mgn.geometry.mesh import make_box, make_sphere, mass_properties
from mgn.hardware import ParallelJawGripper
from mgn.io.grasp_file import read_pj_labels, write_pj_labels
from mgn.io.model_folder import write_model_folder
from mgn.objects import builtin_objects
from mgn.pj import (
    AntipodalSampler,
    core_gripper,
    gripper_meshes,
    hand_poses,
    label_object,
    pj_wrench_scores,
)

BOX = (0.04, 0.06, 0.12)  # x and y graspable (< 80 mm), z not


def _box_labels(**kw):
    box = make_box(BOX)
    props = mass_properties(box, 500.0)
    return box, label_object(box, mass=props.mass, com=props.center_of_mass, **kw)


def _trimesh(m: mgn.Mesh) -> trimesh.Trimesh:
    return trimesh.Trimesh(np.asarray(m.vertices), np.asarray(m.faces), process=False)


def _fcl_bvh(m: mgn.Mesh) -> fcl.BVHModel:
    bvh = fcl.BVHModel()
    bvh.beginModel(len(m.vertices), len(m.faces))
    bvh.addSubModel(np.asarray(m.vertices, np.float64), np.asarray(m.faces, np.int32))
    bvh.endModel()
    return bvh


def test_two_cubes_sharing_an_edge_are_a_closed_solid_with_grasps_on_each_cube():
    """Two 4 cm cubes touching along one edge: validate splits the edge, the mass is that of
    two solid cubes and the sampler grasps each cube across its own faces."""
    cube = make_box((0.04, 0.04, 0.04))
    X = np.eye(4)
    X[:3, 3] = (0.04, 0.04, 0.0)
    pair = mgn.Mesh.merge([cube, cube.transformed(X)])
    r = pair.validate()
    assert r.is_watertight
    assert r.is_outward
    assert (r.num_split_edges, r.num_split_vertices) == (1, 2)
    props = mass_properties(pair, 500.0)
    assert props.is_exact
    assert props.volume == pytest.approx(2 * 0.04**3, rel=1e-6)
    labels = label_object(pair, mass=props.mass, com=props.center_of_mass, num_points=100, seed=1)
    assert len(labels) > 0
    p1 = labels.p1.astype(np.float64)
    mid = p1 + 0.5 * labels.width[:, None] * labels.closing.astype(np.float64)
    # Every grasp closes on one cube: its centre inside the first or the second cube.
    in_first = np.all(np.abs(mid) <= 0.02 + 1e-6, axis=1)
    in_second = np.all(np.abs(mid - X[:3, 3]) <= 0.02 + 1e-6, axis=1)
    assert np.all(in_first | in_second)
    assert in_first.any()
    assert in_second.any()


def test_box_grasps_across_narrow_faces_score_one_and_none_across_the_long_side():
    _, labels = _box_labels(num_points=300, seed=1, sampler_options={"approaches_kept": 4})
    assert len(labels) > 0
    v = labels.closing.astype(np.float64)
    # No grasp closes along z (the 120 mm side); widths stay below the maximum opening.
    assert np.all(np.abs(v[:, 2]) < np.cos(np.pi / 8))
    assert labels.width.max() < 0.08
    # Points on an x face (40 mm across) at least 20 mm from its edges score 1.0 (5 of 5 probes):
    # a probe tilts by < 0.28 rad and starts up to 5 mm off, so it leaves within ~20 mm.
    samples = mgn.sample_surface(make_box(BOX), 300, method="even", seed=1)
    p = np.asarray(samples.points)
    n = np.asarray(samples.normals)
    half = np.asarray(BOX) / 2
    interior = (np.abs(n[:, 0]) > 0.5) & (np.abs(p[:, 1]) < half[1] - 0.02)
    interior &= np.abs(p[:, 2]) < half[2] - 0.02
    assert interior.sum() > 10
    assert np.all(labels.point_score[interior] == 1.0)
    # Points on the z faces (the long side is 120 mm) never score.
    assert np.all(labels.point_score[np.abs(n[:, 2]) > 0.5] == 0.0)
    # Every grasp carries its point's score.
    np.testing.assert_array_equal(labels.quality_score, labels.point_score[labels.point_index])


def test_sphere_grasps_pass_near_the_centre_within_the_friction_cone():
    R = 0.03
    sphere = make_sphere(R, 96, 48)
    sampler = AntipodalSampler(sphere)
    samples = mgn.sample_surface(sphere, 60, method="even", seed=2)
    p = np.asarray(samples.points, np.float64)
    exact = sampler.sample(p, p / np.linalg.norm(p, axis=1, keepdims=True), tilt=0, offset=0)
    assert len(exact.width) > 0
    assert np.all(exact.point_score == 1.0)
    centres = exact.p1 + 0.5 * exact.width[:, None] * exact.closing
    np.testing.assert_allclose(centres, 0.0, atol=1e-4)
    res = sampler.sample(p, np.asarray(samples.normals), seed=5)
    # Distance of each closing line from the centre: below R sin(atan mu) (+ facets).
    d = np.linalg.norm(np.cross(res.p1, res.closing), axis=1)
    assert np.all(d < R * math.sin(math.pi / 8) + 1e-3)
    np.testing.assert_allclose(res.width, 2 * np.sqrt(R**2 - d**2), atol=1e-3)


def test_directions_are_unit_and_perpendicular():
    _, labels = _box_labels(num_points=100, seed=3)
    a = labels.approach.astype(np.float64)
    v = labels.closing.astype(np.float64)
    np.testing.assert_allclose(np.linalg.norm(a, axis=1), 1.0, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1.0, atol=1e-6)
    np.testing.assert_allclose(np.einsum("ij,ij->i", a, v), 0.0, atol=1e-6)


def test_no_reported_grasp_collides_by_an_independent_fcl_query():
    spec = next(s for s in builtin_objects() if s.name == "mug")
    mesh = mgn.Mesh(np.asarray(spec.vertices, np.float32), np.asarray(spec.faces, np.int32))
    g = ParallelJawGripper()
    sampler = AntipodalSampler(mesh, g)
    s = mgn.sample_surface(mesh, 150, method="even", seed=4)
    kw = {"seed": 4, "approaches_kept": 3}
    free = sampler.sample(s.points, s.normals, **kw)
    unchecked = sampler.sample(s.points, s.normals, check_collision=False, **kw)
    obj = fcl.CollisionObject(_fcl_bvh(mesh), fcl.Transform())
    obj_tm = _trimesh(mesh)

    def collides(p1, v, a, w):
        X = hand_poses(p1[None], v[None], a[None], [w], g)[0]
        opening = g.collision_opening(float(w))
        palm, left, right = gripper_meshes(g, opening)
        hand = mgn.Mesh.merge([palm, left, right])
        tf = fcl.Transform(X[:3, :3], X[:3, 3])
        req, res = fcl.CollisionRequest(), fcl.CollisionResult()
        if fcl.collide(fcl.CollisionObject(_fcl_bvh(hand), tf), obj, req, res) > 0:
            return True
        # A part entirely inside the mug wall: one vertex of each part inside the mesh.
        verts = [np.asarray(m.vertices, np.float64)[0] for m in (palm, left, right)]
        pts = np.asarray(verts) @ X[:3, :3].T + X[:3, 3]
        return bool(obj_tm.contains(pts).any())

    assert len(free.width) > 30
    for i in range(len(free.width)):
        assert not collides(free.p1[i], free.closing[i], free.approach[i], free.width[i]), i
    hits = [
        collides(unchecked.p1[i], unchecked.closing[i], unchecked.approach[i], unchecked.width[i])
        for i in range(len(unchecked.width))
    ]
    assert free.num_colliding > 0
    assert any(hits)


def test_one_or_two_threads_and_any_chunking_give_identical_labels():
    _, a = _box_labels(num_points=120, seed=9, num_threads=1, chunk=250)
    _, b = _box_labels(num_points=120, seed=9, num_threads=2, chunk=37)
    for f in ("approach", "closing", "p1", "width", "quality_score", "score_wrench"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)
    np.testing.assert_array_equal(a.point_index, b.point_index)
    _, c = _box_labels(num_points=120, seed=10)
    assert not np.array_equal(a.approach[:10], c.approach[:10])


def test_wrench_score_matches_a_numpy_soft_finger_model():
    rng = np.random.default_rng(0)
    p1 = rng.normal(scale=0.03, size=(50, 3))
    v = rng.normal(size=(50, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    w = rng.uniform(0.01, 0.07, 50)
    m, com, mu, f, r = 1.5, np.array([0.01, -0.02, 0.005]), 0.4, 20.0, 0.006
    got = pj_wrench_scores(p1, v, w, mass=m, com=com, friction=mu, grip_force=f, contact_radius=r)
    F = m * 9.81 * np.array([0, 0, -1.0])
    centre = p1 + 0.5 * w[:, None] * v
    tau = np.cross(com - centre, F)
    ft = 0.5 * np.linalg.norm(F - (v @ F)[:, None] * v, axis=1)
    tn = 0.5 * np.abs(np.einsum("ij,ij->i", tau, v))
    u = np.hypot(ft / (mu * f), tn / (2 / 3 * mu * r * f))
    np.testing.assert_allclose(got, np.minimum(1.0, 1.0 / u), rtol=1e-5)
    assert 0 < got.min() < 1
    assert got.max() == 1.0


def test_bad_input_is_rejected_with_a_clear_error():
    box = make_box((0.04, 0.04, 0.04))
    with pytest.raises(ValueError, match="max_opening"):
        ParallelJawGripper(max_opening=-0.01)
    core = core_gripper(ParallelJawGripper())
    core.max_opening = -0.01  # the C++ check too (e.g. a gripper built without the dataclass)
    with pytest.raises(mgn.InvalidArgumentError, match="max_opening"):
        core.validate()
    with pytest.raises(mgn.InvalidArgumentError, match="mass"):
        label_object(box, mass=0.0, com=(0, 0, 0))
    open_box = mgn.Mesh(np.asarray(box.vertices), np.asarray(box.faces)[:-2])
    with pytest.raises(mgn.InvalidArgumentError, match="no closed volume"):
        label_object(open_box, mass=0.1, com=(0, 0, 0), num_points=10)
    with pytest.raises(mgn.InvalidArgumentError, match="all be"):
        ParallelJawGripper(palm_mesh="palm.stl")
    with pytest.raises(mgn.InvalidArgumentError, match="probes"):
        AntipodalSampler(box).sample([[0.02, 0, 0]], [[1, 0, 0]], probes=0)


def test_mesh_gripper_from_yaml_matches_the_box_gripper(tmp_path):
    g = ParallelJawGripper()
    names = ("palm.stl", "left.stl", "right.stl")
    for name, m in zip(names, gripper_meshes(g, 0.0), strict=True):
        _trimesh(m).export(tmp_path / name)
    mesh_g = dataclasses.replace(
        g, palm_mesh=names[0], finger_left_mesh=names[1], finger_right_mesh=names[2]
    )
    mesh_g.to_yaml(tmp_path / "hand.yaml")
    back = ParallelJawGripper.from_yaml(tmp_path / "hand.yaml")
    assert back.has_meshes
    assert Path(back.palm_mesh) == tmp_path / "palm.stl"
    for a, b in zip(gripper_meshes(g, 0.05), gripper_meshes(back, 0.05), strict=True):
        va = np.unique(np.round(np.asarray(a.vertices, np.float64), 6), axis=0)
        vb = np.unique(np.round(np.asarray(b.vertices, np.float64), 6), axis=0)  # STL: unwelded
        np.testing.assert_allclose(va, vb, atol=1e-6)
    box = make_box(BOX)
    s = mgn.sample_surface(box, 40, method="even", seed=0)
    r1 = AntipodalSampler(box, g).sample(s.points, s.normals, seed=1)
    r2 = AntipodalSampler(box, back).sample(s.points, s.normals, seed=1)
    np.testing.assert_array_equal(r1.approach, r2.approach)


def test_labels_round_trip_through_hdf5_in_centimetres(tmp_path):
    spec = next(s for s in builtin_objects() if s.name == "mug")
    folder = write_model_folder(spec, tmp_path)
    h5_path = folder / "textured.obj.hdf5"
    mesh = mgn.load_mesh(folder / "textured.obj")
    props = mass_properties(mesh, spec.density)

    def fake_physics(_mesh, labels):
        return np.clip(labels.width / 0.08, 0, 1)

    labels = label_object(
        mesh, mass=props.mass, com=props.center_of_mass, num_points=60, physics=fake_physics
    )
    write_pj_labels(h5_path, labels)
    with h5py.File(h5_path) as h5:
        pre = h5["grasps/paralleljaw/pregrasp_transform"]
        assert pre.dtype == np.float32
        assert pre.shape == (len(labels), 10)
        np.testing.assert_allclose(pre[:, 6:9], labels.p1 * 100, rtol=1e-6)
        np.testing.assert_allclose(pre[:, 9], labels.width * 100, rtol=1e-6)
        assert "grasps/suctioncup/pregrasp_transform" in h5  # other groups kept
        assert "pj_gripper" in h5["metadata"].attrs
        assert h5["metadata"].attrs["pj_seed"] == 0
        assert "fake_physics" in h5["metadata"].attrs["pj_physics"]
    back = read_pj_labels(h5_path)
    np.testing.assert_allclose(back["p1"], labels.p1, atol=1e-7)
    np.testing.assert_allclose(back["width"], labels.width, atol=1e-7)
    np.testing.assert_allclose(back["quality_score_simulation"], labels.width / 0.08, rtol=1e-6)
    np.testing.assert_array_equal(back["score_wrench"], labels.score_wrench)
    assert np.all((labels.score_wrench >= 0) & (labels.score_wrench <= 1))


def test_cli_labels_an_object_folder_without_physics(tmp_path, capsys):
    spec = next(s for s in builtin_objects() if s.name == "mug")
    folder = write_model_folder(spec, tmp_path)
    args = ["pj", "label", str(folder), "--no-physics", "--points", "40", "--quiet"]
    assert main(args) == 0
    assert "parallel-jaw grasps from 40 points" in capsys.readouterr().out
    back = read_pj_labels(folder / "textured.obj.hdf5")
    assert len(back["width"]) > 0
    assert np.isnan(back["quality_score_simulation"]).all()


def test_cli_physics_scores_a_strided_subset(tmp_path):
    spec = next(s for s in builtin_objects() if s.name == "box_tea")
    folder = write_model_folder(spec, tmp_path)
    args = ["pj", "label", str(folder), "--points", "30", "--quiet"]
    assert main([*args, "--physics-grasps", "3", "--physics-grid", "2"]) == 0
    back = read_pj_labels(folder / "textured.obj.hdf5")
    sim = back["quality_score_simulation"]
    done = ~np.isnan(sim)
    assert done.sum() == 3
    assert done[0]
    assert done[-1]
    assert np.all((sim[done] >= 0) & (sim[done] <= 1))
    # A light tea box held across its faces with friction 0.5-2: the shake test holds it.
    assert sim[done].mean() > 0.5


def test_cpp_cli_reads_the_python_gripper_yaml(tmp_path):
    exe = shutil.which("mgn-cli") or str(Path(sys.executable).parent / "mgn-cli")
    assert Path(exe).is_file(), "mgn-cli is installed with the wheel"
    ParallelJawGripper(name="yaml_hand", max_opening=0.05).to_yaml(tmp_path / "g.yaml")
    _trimesh(make_box(BOX)).export(tmp_path / "box.stl")
    out = tmp_path / "labels.json"
    cmd = [exe, "pj", "--mesh", str(tmp_path / "box.stl"), "--gripper", str(tmp_path / "g.yaml")]
    r = subprocess.run(
        [*cmd, "--out", str(out), "--points", "30", "--seed", "2"],
        check=False,
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr
    data = json.loads(out.read_text())
    rows = np.asarray(data["pregrasp_transform"])
    assert data["gripper"] == "yaml_hand"
    assert rows.shape[1] == 10
    assert len(rows) > 0
    assert rows[:, 9].max() < 0.05  # the YAML's max_opening was applied: only the 40 mm side
    np.testing.assert_allclose(rows[:, 9].min(), 0.04, atol=1e-3)
    # The same labels as the Python API (same sampling, sampler and wrench score).
    mesh = mgn.load_mesh(tmp_path / "box.stl")
    props = mass_properties(mesh, 1000.0)
    gripper = ParallelJawGripper.from_yaml(tmp_path / "g.yaml")
    py = label_object(
        mesh, mass=props.mass, com=props.center_of_mass, gripper=gripper, num_points=30, seed=2
    )
    py_rows = np.concatenate([py.approach, py.closing, py.p1, py.width[:, None]], axis=1)
    assert rows.shape == py_rows.shape
    np.testing.assert_allclose(rows, py_rows, rtol=0, atol=1e-6)
    np.testing.assert_allclose(data["quality_score"], py.quality_score, atol=1e-7)
    np.testing.assert_allclose(data["score_wrench"], py.score_wrench, atol=1e-6)


@pytest.mark.parametrize("name", ["can_food", "mug", "wine_glass", "l_bracket", "box_cereal"])
def test_collision_filter_keeps_exactly_the_approaches_fcl_finds_free(name):
    # The sampler skips FCL where its own tests decide (an object point inside a box: collision;
    # every triangle > 1 um from every box: free). Truth: the plain FCL-per-part plus inside test
    # of AntipodalSampler.collides on every approach tried.
    spec = next(s for s in builtin_objects() if s.name == name)
    mesh = mgn.Mesh(np.asarray(spec.vertices, np.float32), np.asarray(spec.faces, np.int32))
    g = ParallelJawGripper()
    sampler = AntipodalSampler(mesh, g)
    s = mgn.sample_surface(mesh, 60, method="even", seed=11)
    kw = {"seed": 11, "approaches_tried": 30, "approaches_kept": 30, "num_threads": 1}
    every = sampler.sample(s.points, s.normals, check_collision=False, **kw)
    kept = sampler.sample(s.points, s.normals, **kw)
    X = hand_poses(every.p1, every.closing, every.approach, every.width, g)
    free = [
        not sampler.collides(X[i], g.collision_opening(float(every.width[i])))
        for i in range(len(every.width))
    ]

    def rows(r, mask=None):
        idx = range(len(r.width)) if mask is None else np.flatnonzero(mask)
        return [(int(r.point_index[i]), *r.approach[i].tolist(), *r.p1[i].tolist()) for i in idx]

    assert rows(kept) == rows(every, free)
    assert kept.num_colliding == len(free) - sum(free)
    assert 0 < sum(free) < len(free)  # both outcomes occur
