"""Closed-loop picking (mgn.eval.pick) and re-settling (mgn.scene.settle).

Truth: hand-built scenes whose outcome is known without the code under test: a lone box on the
floor, a box stacked on a larger one (taking the lower one away drops the upper one by the lower
one's height; taking the upper one leaves the lower one where it is), a policy that only
chooses grasps the label model marks as colliding.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from mgn.errors import InvalidArgumentError
from mgn.io.scene_json import read_scene_json, write_scene_json

LOWER, UPPER = "box_shoe", "box_tea"  # 240 x 150 x 90 mm and 125 x 75 x 65 mm


@pytest.fixture(scope="module")
def pick_config(tmp_path_factory: pytest.TempPathFactory):
    """A config with tiny object labels (suction only is computed for suction runs), and a
    private label cache for this module."""
    from mgn.pipeline.config import load_config

    cache = tmp_path_factory.mktemp("pick_cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MGN_CACHE_DIR", str(cache))
        yield load_config(
            {
                "object_labels": {"suction_points": 150, "pj_points": 40, "seed": 1},
                "labels": {"pj_physics": False},
                "camera": {"resolution_scale": 0.1},
            }
        )


def _instance(k: int, name: str, x: float, y: float, z_bottom: float, yaw: float = 0.0):
    from mgn.objects import get_object
    from mgn.scene import SceneInstance

    spec = get_object(name)
    lo = np.asarray(spec.vertices).min(axis=0)
    c, s = np.cos(yaw), np.sin(yaw)
    X = np.eye(4)
    X[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    X[:3, 3] = [x, y, z_bottom - lo[2]]
    return SceneInstance(k, name, spec.category_id, "builtin", X)


def _height(name: str) -> float:
    from mgn.objects import get_object

    v = np.asarray(get_object(name).vertices)
    return float(v[:, 2].max() - v[:, 2].min())


def _scene(*instances):
    from mgn.objects import ToteSpec
    from mgn.scene import Scene

    return Scene(tuple(instances), ToteSpec(), seed=5)


@pytest.fixture(scope="module")
def single_box():
    return _scene(_instance(1, UPPER, 0.02, -0.01, 0.0, 0.2))


@pytest.fixture(scope="module")
def stack():
    """box_tea resting on box_shoe, both on the floor in the middle of the tote."""
    return _scene(
        _instance(1, LOWER, 0.0, 0.0, 0.0), _instance(2, UPPER, 0.04, 0.0, _height(LOWER), 0.3)
    )


def _best_visible_grasp_of(target_name: str):
    """A callable policy: the best collision-free visible grasp of the object named so."""

    def policy(state):
        names = [inst.name for inst in state.scene.instances]
        k = names.index(target_name)
        obj = np.asarray(state.grasps.object_id)
        ok = (obj == k) & state.visible & ~np.asarray(state.grasps.colliding)
        rows = np.flatnonzero(ok)
        assert len(rows), f"no visible collision-free grasp on {target_name}"
        return k + 1, int(rows[np.argmax(state.score[rows])])

    return policy


# ---------------------------------------------------------------------------- settle


def test_settle_keeps_a_resting_stack_and_drops_the_upper_box_when_the_lower_is_removed(stack):
    from mgn.scene import settle, settle_tracked

    same = settle(stack)
    assert len(same) == 2
    for a, b in zip(same.instances, stack.instances, strict=True):
        assert np.linalg.norm(a.X_WO[:3, 3] - b.X_WO[:3, 3]) < 0.001
    assert "floor" in same.instances[0].contacts
    assert "floor" not in same.instances[1].contacts

    fallen, old = settle_tracked(stack, remove=(1,))
    assert old == (2,)
    assert len(fallen) == 1
    assert fallen.instances[0].instance_id == 1
    drop = stack.instances[1].X_WO[2, 3] - fallen.instances[0].X_WO[2, 3]
    assert drop == pytest.approx(_height(LOWER), abs=0.003)
    assert "floor" in fallen.instances[0].contacts
    # Only the lower box removed and nothing else changed in the scene record.
    assert fallen.tote == stack.tote
    assert fallen.seed == stack.seed

    empty = settle(stack, remove=(1, 2))
    assert len(empty) == 0


def test_settle_lets_a_box_above_the_floor_fall_onto_it():
    from mgn.scene import settle

    floating = _scene(_instance(1, UPPER, 0.0, 0.0, 0.05))
    down = settle(floating)
    assert down.instances[0].X_WO[2, 3] == pytest.approx(
        floating.instances[0].X_WO[2, 3] - 0.05, abs=0.002
    )


def test_settle_rejects_unknown_ids(stack):
    from mgn.scene import settle

    with pytest.raises(InvalidArgumentError, match="instance ids of the scene"):
        settle(stack, remove=(3,))
    with pytest.raises(InvalidArgumentError, match="instance ids of the scene"):
        settle(stack, remove=(0,))


# ---------------------------------------------------------------------------- picking


def test_single_box_is_cleared_at_the_first_attempt(single_box, pick_config, tmp_path):
    from mgn.eval.pick import run_picking

    r = run_picking(single_box, policy="label", config=pick_config, out=tmp_path)
    assert r.R_object == 1.0
    assert r.R_mixture == 1.0
    assert r.R_grasp == 1.0
    assert len(r.attempts) == 1
    assert r.stop_reason == "empty"
    a = r.attempts[0]
    assert a.success
    assert a.reason == "ok"
    assert a.score >= 0.5
    assert a.instance_id == 1
    # The chosen suction grasp approaches from above (tool z points down into the box top).
    assert np.asarray(a.X_W_tool)[2, 2] < -0.9
    assert a.disturbance_max_translation == 0.0
    assert a.remaining == 0
    for f in ("step_000.png", "final.png", "picking.gif", "results.json"):
        assert (tmp_path / f).is_file(), f
    doc = json.loads((tmp_path / "results.json").read_text())
    assert doc["R_object"] == 1.0
    assert doc["attempts"][0]["success"] is True
    assert "R_grasp 1.000" in r.table()


def test_picking_the_lower_box_first_disturbs_the_upper_one_and_not_the_reverse(stack, pick_config):
    from mgn.eval.pick import run_picking

    fall = _height(LOWER)
    bottom = run_picking(
        stack, policy=_best_visible_grasp_of(LOWER), config=pick_config, max_attempts=1
    )
    a = bottom.attempts[0]
    assert a.success
    assert a.instance_id == 1
    assert a.disturbance_max_translation > 0.5 * fall  # the tea box fell onto the floor
    assert a.disturbance_max_translation > 0.02

    top = run_picking(
        stack, policy=_best_visible_grasp_of(UPPER), config=pick_config, max_attempts=1
    )
    a = top.attempts[0]
    assert a.success
    assert a.instance_id == 2
    assert a.disturbance_max_translation < 0.002
    assert a.disturbance_max_rotation < 0.02


def test_label_policy_clears_the_stack_top_first(stack, pick_config):
    from mgn.eval.pick import run_picking

    r = run_picking(stack, policy="label", config=pick_config)
    assert r.cleared == (2, 1)  # the top layer first: no object was disturbed
    assert r.R_object == 1.0
    assert r.R_mixture == 1.0
    assert all(a.disturbance_max_translation < 0.002 for a in r.attempts)


def test_colliding_grasps_fail_twice_per_object_and_the_run_stops(stack, pick_config):
    from mgn.eval.pick import run_picking

    def colliding(state):
        g = state.grasps
        obj = np.asarray(g.object_id)
        rows = np.flatnonzero(np.asarray(g.colliding) & state.eligible[obj] & ~state.tried)
        return int(obj[rows[0]]) + 1, int(rows[0])

    r = run_picking(stack, policy=colliding, config=pick_config)
    assert len(r.attempts) == 4
    assert r.stop_reason == "failures"
    assert all(not a.success and a.reason == "collision" for a in r.attempts)
    assert sorted(a.instance_id for a in r.attempts) == [1, 1, 2, 2]
    assert r.R_grasp == 0.0
    assert r.R_object == 0.0
    assert r.R_mixture == 0.0


def test_same_seed_same_records(stack, pick_config):
    from mgn.eval.pick import run_picking

    kw = {"policy": "random", "config": pick_config, "stochastic": True, "max_attempts": 3}
    a = run_picking(stack, seed=4, **kw)
    b = run_picking(stack, seed=4, **kw)
    assert a == b
    assert len(a.attempts) >= 1
    assert a.to_dict() == b.to_dict()
    assert run_picking(stack, seed=4, num_threads=1, **kw) == a  # whatever the thread count


def test_bad_input_is_rejected_clearly(stack, pick_config):
    from mgn.eval.pick import run_picking

    with pytest.raises(InvalidArgumentError, match="unknown policy"):
        run_picking(stack, policy="greedy", config=pick_config)
    with pytest.raises(InvalidArgumentError, match="gripper"):
        run_picking(stack, gripper="magnet", config=pick_config)
    with pytest.raises(InvalidArgumentError, match=r"instances 1..2"):
        run_picking(stack, policy=lambda s: (7, 0), config=pick_config)
    with pytest.raises(InvalidArgumentError, match="must return"):
        run_picking(stack, policy=lambda s: "box", config=pick_config)
    with pytest.raises(InvalidArgumentError, match="no objects"):
        run_picking(_scene(), config=pick_config)
    with pytest.raises(InvalidArgumentError, match="cannot load policy"):
        run_picking(stack, policy="no_such_module_xyz:f", config=pick_config)


def test_cli_picks_a_dataset_scene_with_the_dataset_config(small_dataset, tmp_path, capsys):
    import mgn
    from mgn.cli.main import main

    scene = mgn.Dataset(small_dataset).scenes()[0]
    n = len(json.loads((scene.folder / "scene.json").read_text())["instances"])
    out = tmp_path / "run"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MGN_CACHE_DIR", str(tmp_path / "cache"))
        code = main(
            [
                "pick",
                str(scene.folder),
                "--policy",
                "label",
                "--out",
                str(out),
                "--max-attempts",
                "2",
                "--resolution",
                "96",
            ]
        )
    assert code == 0
    printed = capsys.readouterr().out
    assert "R_grasp" in printed
    assert "R_object" in printed
    doc = json.loads((out / "results.json").read_text())
    assert doc["num_objects"] == n
    assert 1 <= doc["num_attempts"] <= 2
    assert doc["policy"] == "label"
    assert doc["gripper"] == "suction"
    assert (out / "picking.gif").is_file()
    assert (out / "step_000.png").is_file()
    # The dataset's config was used: the labels cached are those of its object-label settings.
    from mgn.pipeline.config import load_config
    from mgn.pipeline.label_cache import label_keys

    config = load_config(mgn.Dataset(small_dataset).info["config"])
    sc = read_scene_json(scene.folder / "scene.json")
    for i in range(len(sc)):
        key = label_keys(sc.object_spec(i), config)["suction"]
        assert (tmp_path / "cache" / "labels" / f"suction-{key}.npz").is_file()


def test_cli_reports_an_unknown_policy(single_box, tmp_path, capsys):
    from mgn.cli.main import main

    path = write_scene_json(single_box, tmp_path / "scene.json")
    code = main(["pick", str(path), "--policy", "nonsense", "--out", str(tmp_path / "o")])
    assert code == 1
    assert "unknown policy 'nonsense'" in capsys.readouterr().err
