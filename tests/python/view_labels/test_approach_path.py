"""The whole approach path is checked and every colliding grasp says why (issue 16, item 6).

Truth: the same collision model evaluated at poses 1 mm apart along the approach (brute force),
against the default model (the listed offsets 0 and 100 mm plus the path between them)."""

from __future__ import annotations

import numpy as np
from conftest import translation

from mgn.geometry import make_box, mass_properties
from mgn.objects import ToteSpec
from mgn.pj import label_object as pj_label_object
from mgn.scene.drop import tote_mesh
from mgn.suction.labels import label_object as suction_label_object
from mgn.view_labels.grasps import (
    COLLISION_OBSTACLES,
    COLLISION_PARTS,
    SceneGraspModel,
)

TOTE = tote_mesh(ToteSpec())  # inner 400 x 300 x 150 mm, floor top at z = 0 (tote frame = W)
BOX = (0.04, 0.06, 0.05)


def _model(objects, pj, su, **kw) -> SceneGraspModel:
    kw.setdefault("num_threads", 1)
    return SceneGraspModel.from_meshes(
        [m for m, _ in objects],
        np.array([X for _, X in objects]).reshape(-1, 4, 4),
        [0.2] * len(objects),
        np.zeros((len(objects), 3)),
        pj,
        su,
        TOTE,
        np.eye(4),
        **kw,
    )


def _longest_run(b: np.ndarray) -> np.ndarray:
    """(M,) longest run of True along each row of (M, K) bool."""
    run = np.zeros(len(b), int)
    best = np.zeros(len(b), int)
    for k in range(b.shape[1]):
        run = np.where(b[:, k], run + 1, 0)
        best = np.maximum(best, run)
    return best


def test_default_check_matches_a_dense_brute_force_and_catches_path_collisions() -> None:
    box = make_box(BOX)
    props = mass_properties(box, 500.0)
    pj = pj_label_object(box, mass=props.mass, com=props.center_of_mass, num_points=120, seed=1)
    su = suction_label_object(box, mass=props.mass, com=props.center_of_mass, num_points=120)
    # The box stands 1 cm from the +x wall of the tote (inner wall at x = 0.2 m).
    objects = [(box, translation(0.17, 0.0, 0.025))]
    dense = _model(
        objects, [pj], [su], offsets=tuple(np.linspace(0.0, 0.1, 101)), approach_step=1.0
    )
    ends = _model(objects, [pj], [su], offsets=(0.0, 0.1), approach_step=1.0)
    default = _model(objects, [pj], [su])
    for kind in ("pj", "suction"):
        d, _e, m = (getattr(x, kind) for x in (dense, ends, default))
        # The default poses are a subset of the dense ones: nothing extra.
        assert not np.any(m.colliding & ~d.colliding), kind
        # Every collision that lasts 3 mm or more along the path is found (shorter ones are
        # grazing contacts of a part's side with an edge: zero penetration depth).
        solid = _longest_run(d.hit >= 0) >= 3
        np.testing.assert_array_equal(m.colliding[solid], True, err_msg=kind)
        assert np.mean(m.colliding != d.colliding) < 1e-3, kind
        assert np.all(m.collision_part[~m.colliding] == 0)
        assert np.all(m.collision_part[m.colliding] > 0)
        assert np.all(m.collision_obstacle[m.colliding] > 0)
    # The scene has grasps that are free at the grasp and 100 mm back but not in between
    # (the palm sweeping through the wall on a tilted approach).
    path_only = dense.pj.colliding & ~ends.pj.colliding & (_longest_run(dense.pj.hit >= 0) >= 3)
    assert path_only.any()
    what = [COLLISION_OBSTACLES[int(w)] for w in default.pj.collision_obstacle[path_only]]
    assert set(what) <= {"floor", "wall"}, what
    assert "wall" in what, what


def test_collision_reasons_on_analytic_cases() -> None:
    box = make_box(BOX)
    other = make_box((0.04, 0.04, 0.12))
    # Suction on the box's bottom face (approach +z into it): the cup goes through the floor.
    # Suction on its top face: free. Parallel-jaw from the top across x, with a tall box right
    # next to it on the +x side: the finger hits the other object.
    from test_scene_grasps import pj_labels, suction_labels

    su = suction_labels([[0, 0, -0.025], [0, 0, 0.025]], [[0, 0, 1], [0, 0, -1]])
    pj = pj_labels([[-0.02, 0, 0]], [[1, 0, 0]], [[0, 0, -1]], [0.04])
    objects = [(box, translation(0.0, 0.0, 0.025)), (other, translation(0.045, 0.0, 0.06))]
    m = _model(objects, [pj, None], [su, None])
    assert m.suction.colliding.tolist() == [True, False]
    assert COLLISION_PARTS[int(m.suction.collision_part[0])] == "cup"
    assert COLLISION_OBSTACLES[int(m.suction.collision_obstacle[0])] == "floor"
    assert m.pj.colliding.tolist() == [True]
    assert COLLISION_PARTS[int(m.pj.collision_part[0])] == "finger"
    assert COLLISION_OBSTACLES[int(m.pj.collision_obstacle[0])] == "other object"


def test_report_shows_why_grasps_collide(small_dataset, tmp_path) -> None:
    from mgn.io.dataset import Dataset
    from mgn.viz.report import collect_stats, write_report

    stats = collect_stats(Dataset(small_dataset))
    for kind in ("paralleljaw", "suctioncup"):
        split = stats["collision_reasons"][kind]
        assert sum(split.values()) == stats["grasp_counts"]["colliding"].get(kind, 0) > 0
        assert all(" / " in k and "?" not in k for k in split)
    page = write_report(small_dataset, tmp_path / "r.html").read_text()
    assert "why paralleljaw grasps collide (part / obstacle)" in page
