"""Per-object labels are the same whichever computation path produces them.

- compute_object_labels draws the even surface samples once and shares them between the suction
  and parallel-jaw labels; the labels equal those of the two label_object calls drawing their
  own samples.
- The antipodal sampler's box-gripper pre-filters (point lists built lazily, sphere lists on
  first use) decide exactly as the FCL-only path of the same gripper given as meshes.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import trimesh

import mgn
from mgn.errors import InvalidArgumentError
from mgn.geometry.mesh import mass_properties
from mgn.hardware import ParallelJawGripper
from mgn.objects import builtin_objects
from mgn.pipeline.config import Config
from mgn.pipeline.label_cache import compute_object_labels
from mgn.pj import AntipodalSampler, gripper_meshes
from mgn.pj import label_object as pj_label_object
from mgn.suction import label_object as suction_label_object


def _spec(name: str):
    return next(s for s in builtin_objects() if s.name == name)


def _assert_same(a, b) -> None:
    assert type(a) is type(b)
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype, f.name
            np.testing.assert_array_equal(x, y, err_msg=f.name)
        else:
            assert x == y, f.name


def test_shared_samples_give_the_labels_of_separate_label_object_calls():
    spec = _spec("mug")
    config = Config.from_dict(
        {
            "object_labels": {"suction_points": 300, "pj_points": 300, "seed": 7},
            "labels": {"pj_physics": False},
        }
    )
    shared = compute_object_labels(spec, config, num_threads=2)
    mesh = spec.to_mesh()
    props = mass_properties(mesh, spec.density)
    kw = {
        "mass": props.mass,
        "com": props.center_of_mass,
        "num_points": 300,
        "seed": 7,
        "num_threads": 1,
    }
    suction = suction_label_object(
        mesh, cup=config.cup, model="spring", inertia=props.inertia, **kw
    )
    pj = pj_label_object(
        mesh, gripper=config.gripper, max_grasps=config.object_labels.pj_grasps, **kw
    )
    assert len(suction.score) > 50
    assert len(pj.width) > 100
    _assert_same(shared.suction, suction)
    _assert_same(shared.paralleljaw, pj)


def test_samples_of_the_wrong_size_are_rejected():
    spec = _spec("box_cube")
    mesh = spec.to_mesh()
    samples = mgn.sample_surface(mesh, 20, method="even", seed=0)
    for label_object in (suction_label_object, pj_label_object):
        with pytest.raises(InvalidArgumentError, match="samples holds 20 points") as e:
            label_object(mesh, mass=0.1, com=(0, 0, 0), num_points=30, samples=samples)
        assert "30" in str(e.value)


def _mesh_gripper(g: ParallelJawGripper, folder) -> ParallelJawGripper:
    paths = [folder / n for n in ("palm.stl", "left.stl", "right.stl")]
    for path, m in zip(paths, gripper_meshes(g, 0.0), strict=True):
        tm = trimesh.Trimesh(np.asarray(m.vertices, np.float64), np.asarray(m.faces), process=False)
        tm.export(path)
    return dataclasses.replace(
        g, palm_mesh=str(paths[0]), finger_left_mesh=str(paths[1]), finger_right_mesh=str(paths[2])
    )


def test_box_gripper_prefilters_decide_as_the_fcl_only_mesh_gripper(tmp_path):
    g = ParallelJawGripper()
    mesh_g = _mesh_gripper(g, tmp_path)
    for name, n in (("mug", 200), ("box_cereal", 120), ("l_bracket", 120)):
        mesh = _spec(name).to_mesh()
        s = mgn.sample_surface(mesh, n, method="even", seed=3)
        fast = AntipodalSampler(mesh, g).sample(s.points, s.normals, seed=5, num_threads=2)
        fcl_only = AntipodalSampler(mesh, mesh_g).sample(s.points, s.normals, seed=5, num_threads=1)
        assert fast.num_colliding > 100, name
        assert len(fast.width) > 100, name
        _assert_same(fast, fcl_only)
