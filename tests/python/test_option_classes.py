"""Options and per-object labels cross the boundary as bound classes (docs/architecture.md, "The
typed boundary"): the Python façades take their keyword defaults from the bound C++ structs, the
ranges are checked by each struct's C++ ``validate()`` naming the field, and the per-object
labels of the scene grasp model are a typed ``ObjectGraspLabels``."""

from __future__ import annotations

import dataclasses
import inspect
import math

import numpy as np
import pytest

import mgn
from mgn import _core
from mgn.geometry import make_box
from mgn.pj import AntipodalSampler, pj_wrench_scores
from mgn.render import Renderer
from mgn.render.path import FilmOptions, PathTraceOptions
from mgn.render.renderer import LightSample
from mgn.scene.cameras import CameraView, Intrinsics
from mgn.suction import SealModel, suction_wrench_scores
from mgn.view_labels import grasps

BOX = make_box((0.04, 0.06, 0.05))


def _keyword_defaults(fn) -> dict[str, object]:
    return {
        name: p.default
        for name, p in inspect.signature(fn).parameters.items()
        if p.default is not inspect.Parameter.empty
    }


def test_facade_defaults_are_the_bound_structs():
    """Each keyword default of a façade equals the field of a default-constructed C++ struct
    (MetaGraspNet's values, written here independently as a second source)."""
    seal, anti = _core.grasp.SealOptions(), _core.grasp.AntipodalOptions()
    assert (seal.num_trials, seal.angle_sigma, seal.position_sigma) == (10, 0.1, -1.0)
    assert (anti.probes, anti.approaches_tried, anti.approaches_kept) == (5, 50, 20)
    assert anti.tilt == math.pi / 16
    assert anti.friction_coef == pytest.approx(math.tan(math.pi / 8))
    d = _keyword_defaults(SealModel.evaluate)
    for name in ("num_trials", "angle_sigma", "perturb", "seed", "first_index", "num_threads"):
        assert d[name] == getattr(seal, name), name
    d = _keyword_defaults(AntipodalSampler.sample)
    for name in ("probes", "tilt", "offset", "start_offset", "friction_coef", "approaches_tried"):
        assert d[name] == getattr(anti, name), name
    wrench = _core.grasp.PjWrenchOptions()
    assert (wrench.friction, wrench.grip_force, wrench.contact_radius) == (0.5, 70.0, 0.005)
    d = _keyword_defaults(pj_wrench_scores)
    assert (d["friction"], d["grip_force"], d["contact_radius"]) == (0.5, 70.0, 0.005)
    assert (
        _keyword_defaults(suction_wrench_scores)["k"]
        == _core.grasp.SuctionWrenchOptions().k
        == 15.6
    )
    light = _core.render.LightSample()
    assert (LightSample().intensity, LightSample().color_temperature, LightSample().ambient) == (
        light.intensity,
        light.color_temperature,
        light.ambient,
    )
    scene = _core.scene.SceneGraspOptions()
    assert list(scene.offsets) == [0.0, 0.1]
    assert scene.gravity_world == (0.0, 0.0, -1.0)
    assert grasps.DEFAULT_SHAFT_RADIUS == scene.tool.shaft_radius == 0.015
    assert grasps.DEFAULT_APPROACH_STEP == scene.approach_step == 0.005
    assert scene.suction_wrench.k == 15.6
    assert scene.pj_wrench.grip_force == 70.0


def test_ranges_are_checked_by_the_structs_validate():
    seal = SealModel(BOX)
    with pytest.raises(mgn.InvalidArgumentError, match=r"SealOptions\.num_trials must be >= 1"):
        seal.evaluate([[0.02, 0, 0]], [[1, 0, 0]], num_trials=0)
    with pytest.raises(mgn.InvalidArgumentError, match=r"SealOptions\.angle_sigma must be"):
        seal.evaluate([[0.02, 0, 0]], [[1, 0, 0]], angle_sigma=float("nan"))
    with pytest.raises(mgn.InvalidArgumentError, match=r"AntipodalOptions\.probes must be"):
        AntipodalSampler(BOX).sample([[0.02, 0, 0]], [[1, 0, 0]], probes=0)
    with pytest.raises(mgn.InvalidArgumentError, match=r"PjWrenchOptions\.grip_force must be"):
        pj_wrench_scores([[0, 0, 0]], [[1, 0, 0]], [0.04], mass=1.0, com=(0, 0, 0), grip_force=0)
    with pytest.raises(mgn.InvalidArgumentError, match=r"SuctionWrenchOptions\.k must be"):
        suction_wrench_scores([[0, 0, 0]], [[0, 0, -1]], mass=1.0, com=(0, 0, 0), k=-1.0)
    opts = _core.render.RenderOptions()
    opts.light.ambient = -0.5  # the nested struct is the options' own (reference semantics)
    with pytest.raises(mgn.InvalidArgumentError, match=r"RenderOptions\.light\.ambient must be"):
        opts.validate()
    opts.randomize = True  # a drawn light: the given one is not used, nor checked
    opts.validate()
    r = Renderer(64, 48)
    r.add_mesh(BOX)
    X_WC = np.eye(4)
    X_WC[2, 3] = -0.5  # half a metre before the box, looking along +z at it
    view = CameraView(Intrinsics(64, 48, 60.0, 60.0, 32.0, 24.0), X_WC)
    with pytest.raises(mgn.InvalidArgumentError, match=r"RenderOptions\.rgb/depth/instances"):
        r.render(view, rgb=False, depth=False, instances=False)
    with pytest.raises(mgn.InvalidArgumentError, match=r"RenderOptions\.light\.intensity must"):
        r.render(view, light=LightSample(intensity=-1.0))
    bad = _core.scene.SceneGraspOptions()
    bad.tool.shaft_radius = 0.0
    with pytest.raises(mgn.InvalidArgumentError, match=r"SuctionTool\.shaft_radius"):
        bad.validate()


def test_object_grasp_labels_are_typed_and_checked():
    rng = np.random.default_rng(3)
    p1, v, a = (rng.normal(size=(4, 3)) for _ in range(3))
    w = rng.uniform(0.01, 0.05, 4).astype(np.float32)
    pts = rng.normal(size=(2, 3)).astype(np.float32)
    labels = _core.scene.ObjectGraspLabels(
        pj_p1=p1,
        pj_closing=v,
        pj_approach=a,
        pj_width=w,
        pj_score_analytical=np.float32([0.1, 0.2, 0.3, 0.4]),
        suction_points=pts,
        suction_approach=-pts,
    )
    assert labels.pj_p1.dtype == np.float64
    assert np.array_equal(labels.pj_p1, p1)
    assert np.array_equal(labels.pj_closing, v)
    assert np.array_equal(labels.pj_approach, a)
    assert labels.pj_width.dtype == np.float32
    assert np.array_equal(labels.pj_width, w)
    assert labels.pj_score_simulation.shape == (0,)  # not given: NaN in the model
    assert np.array_equal(labels.suction_points, pts)
    assert np.array_equal(labels.suction_approach, -pts)
    empty = _core.scene.ObjectGraspLabels()
    assert empty.pj_p1.shape == (0, 3)
    assert empty.suction_points.shape == (0, 3)
    with pytest.raises(mgn.InvalidArgumentError, match=r"ObjectGraspLabels\.pj_closing"):
        _core.scene.ObjectGraspLabels(pj_p1=p1, pj_closing=v[:3], pj_approach=a, pj_width=w)
    with pytest.raises(mgn.InvalidArgumentError, match=r"ObjectGraspLabels\.pj_approach"):
        _core.scene.ObjectGraspLabels(pj_p1=p1, pj_closing=v, pj_approach=a[:, :2], pj_width=w)
    with pytest.raises(mgn.InvalidArgumentError, match=r"ObjectGraspLabels\.suction_approach"):
        _core.scene.ObjectGraspLabels(suction_points=pts, suction_approach=pts[:1])
    with pytest.raises(mgn.InvalidArgumentError, match=r"ObjectGraspLabels\.pj_width"):
        _core.scene.ObjectGraspLabels(pj_p1=p1, pj_closing=v, pj_approach=a, pj_width=w[:, None])


def test_path_tracer_dataclasses_default_to_the_bound_structs():
    trace, film = PathTraceOptions(), FilmOptions()
    core_trace, core_film = _core.render.PathTraceOptions(), _core.render.FilmOptions()
    for f in dataclasses.fields(trace):
        assert getattr(trace, f.name) == getattr(core_trace, f.name), f.name
    for f in dataclasses.fields(film):
        assert getattr(film, f.name) == getattr(core_film, f.name), f.name
    # The values mgn/render/path_tracer.hpp documents, written here again as a second source.
    assert (trace.spp, trace.max_bounces, trace.rr_depth, trace.clamp_indirect) == (16, 6, 2, 10.0)
    assert (film.exposure, film.tone) == (0.0, "filmic")
