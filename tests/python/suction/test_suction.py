"""Suction façade: seal models through Python, wrench score, object labels and their file."""

import h5py
import numpy as np
import pytest

import mgn
from mgn.cli.main import main
from mgn.hardware import SuctionCup
from mgn.objects import get_object
from mgn.suction import (
    FAILURE_REASONS,
    SealModel,
    label_object,
    suction_wrench_scores,
)


def block():
    """20 x 20 x 5 cm block with its top face at z = 0."""
    X = np.eye(4)
    X[2, 3] = -0.025
    return mgn.make_box([0.2, 0.2, 0.05]).transformed(X)


@pytest.mark.parametrize("model", ["spring", "strain", "smoothness"])
def test_every_model_seals_a_plane_and_misses_off_the_edge(model):
    seal = SealModel(block(), model=model)
    r = seal.evaluate([[0.0, 0.0, 0.0], [0.1, 0.1, 0.0]], [[0, 0, 1], [0, 0, 1]])
    assert r.score[0] == pytest.approx(1.0)
    assert r.score[1] == pytest.approx(0.0)
    assert r.reason_names()[1] == "miss"
    assert r.trial_sealed.shape == (2, 10)


def test_chunked_evaluation_equals_one_call():
    sphere = mgn.make_sphere(0.01, 96, 48)  # borderline radius: trials differ
    s = mgn.sample_surface(sphere, 60, seed=1)
    seal = SealModel(sphere)
    whole = seal.evaluate(s.points, s.normals, seed=3)
    parts = [
        seal.evaluate(s.points[a : a + 20], s.normals[a : a + 20], seed=3, first_index=a)
        for a in (0, 20, 40)
    ]
    np.testing.assert_array_equal(whole.score, np.concatenate([p.score for p in parts]))
    assert 0.0 < whole.score.mean() < 1.0


def test_reasons_name_the_failed_check():
    assert FAILURE_REASONS[:6] == ("none", "miss", "obstruction", "hill", "hole", "force")
    roof = mgn.make_box([0.05, 0.05, 0.005]).transformed(
        np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.05], [0, 0, 0, 1.0]])
    )
    r = SealModel(mgn.Mesh.merge([block(), roof])).evaluate([[0, 0, 0]], [[0, 0, 1]], perturb=False)
    assert r.reason_names() == ["obstruction"]


def test_bad_candidates_and_cups_are_rejected():
    seal = SealModel(block())
    with pytest.raises(mgn.InvalidArgumentError, match="not on the mesh"):
        seal.evaluate([[0, 0, 0.05]], [[0, 0, 1]])
    with pytest.raises(mgn.InvalidArgumentError, match="normal"):
        seal.evaluate([[0, 0, 0]], [[np.nan, 0, 1]])
    with pytest.raises(mgn.InvalidArgumentError, match="radius"):
        SuctionCup(radius=0.0)


def test_wrench_score_matches_the_torque_formula():
    s = suction_wrench_scores(
        [[0, 0, 0.1], [0.05, 0, 0.1]],
        [[0, 0, -1], [0, 0, -1]],
        mass=0.5,
        com=[0.05, 0, 0.1],
        cup_radius=0.01,
    )
    tau_max = 15.6 * 0.01 * np.pi * np.sqrt(2)
    assert s[0] == pytest.approx(1 - 0.5 * 9.81 * 0.05 / tau_max, rel=1e-6)
    assert s[1] == pytest.approx(1.0)


def test_object_labels_are_deterministic_and_sensible():
    spec = get_object("box_tea")
    mesh = spec.to_mesh()
    p = mgn.mass_properties(mesh, spec.density)
    a = label_object(mesh, mass=p.mass, com=p.center_of_mass, num_points=300, seed=2)
    b = label_object(mesh, mass=p.mass, com=p.center_of_mass, num_points=300, seed=2, chunk=37)
    np.testing.assert_array_equal(a.score, b.score)
    np.testing.assert_array_equal(a.points, b.points)
    assert a.num_colliding == 0  # a box has nothing to hit the cup body
    assert (a.score > 0.9).mean() > 0.5  # most of a box's faces seal
    # approach points into the surface: the contact frame's z opposes the outward normal
    ray = mgn.RayScene(mesh).intersect(a.points - 0.01 * a.approach, a.approach)
    assert ray.hit.all()
    assert np.all((a.wrench >= 0) & (a.wrench <= 1))


def test_mug_interior_is_obstructed_or_colliding():
    spec = get_object("mug")
    mesh = spec.to_mesh()
    p = mgn.mass_properties(mesh, spec.density)
    labels = label_object(mesh, mass=p.mass, com=p.center_of_mass, num_points=400, seed=0)
    assert labels.num_colliding > 0
    assert (labels.reason == FAILURE_REASONS.index("obstruction")).sum() > 0


def test_cli_writes_suction_labels_in_the_metagraspnet_layout(tmp_path):
    assert main(["objects", "export", str(tmp_path), "--only", "can_soda", "--quiet"]) == 0
    assert main(["suction", "label", str(tmp_path), "--num-points", "200", "--quiet"]) == 0
    with h5py.File(tmp_path / "models" / "006" / "textured.obj.hdf5") as h5:
        pre = h5["grasps/suctioncup/pregrasp_transform"][:]
        score = h5["grasps/suctioncup/quality_score"][:]
        assert pre.dtype == np.float32
        assert pre.shape[1] == 6
        assert len(pre) == len(score) > 0
        np.testing.assert_allclose(np.linalg.norm(pre[:, :3], axis=1), 1.0, atol=1e-5)
        assert np.abs(pre[:, 3:]).max() > 1.0  # centimetres: a soda can is ~12 cm tall
        assert h5["grasps/paralleljaw/pregrasp_transform"].shape == (0, 10)
        assert h5["metadata"].attrs["suction_model"] == "spring"
        assert "keypts/com" in h5  # the rest of the file is kept


def test_cli_board_then_calibrate_recovers_the_model(tmp_path):
    import csv

    from mgn.calibration import make_calibration_board

    assert main(["suction", "board", str(tmp_path)]) == 0
    with (tmp_path / "poses.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    v, f, _ = make_calibration_board()
    pts = np.array([[float(r[k]) for k in ("x_m", "y_m", "z_m")] for r in rows], np.float32)
    nrm = np.array([[float(r[k]) for k in ("nx", "ny", "nz")] for r in rows], np.float32)
    truth = SealModel(mgn.Mesh(v.astype(np.float32), f)).evaluate(pts, nrm, perturb=False)
    with (tmp_path / "filled.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["pose_id", "sealed", "tear_off_force_N"])
        for r, s in zip(rows, truth.score, strict=True):
            w.writerow([r["pose_id"], int(s > 0.5), ""])
    out = tmp_path / "fitted.yaml"
    assert main(["suction", "calibrate", str(tmp_path / "filled.csv"), "--out", str(out)]) == 0
    fitted = SuctionCup.from_yaml(out)
    again = SealModel(mgn.Mesh(v.astype(np.float32), f), fitted).evaluate(pts, nrm, perturb=False)
    assert ((again.score > 0.5) == (truth.score > 0.5)).mean() >= 0.95
