"""Cup calibration: the printable board, its files, the CSV reader and the fit of c1, c2."""

import csv
import math
import struct
from pathlib import Path

import numpy as np
import pytest

import mgn
from mgn.calibration import calibrate_from_csv, make_calibration_board, write_calibration_board
from mgn.calibration.board import PLATE_SIZE, TOP_Z, board_poses
from mgn.calibration.fit import (
    calibrate,
    classification_metrics,
    predict_seals,
    read_results_csv,
)
from mgn.hardware import SuctionCup


@pytest.fixture(scope="module")
def board():
    v, f, feats = make_calibration_board()
    ids, names, _params, pts, nrm = board_poses(feats)
    return {
        "mesh": mgn.Mesh(v, f),
        "features": feats,
        "ids": np.asarray(ids),
        "names": names,
        "points": pts,
        "normals": nrm,
    }


@pytest.fixture(scope="module")
def board_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("board")
    write_calibration_board(out)
    return out


# ----------------------------------------------------------------------------------------------
# The board
# ----------------------------------------------------------------------------------------------


def test_board_is_one_watertight_outward_solid(board):
    report = board["mesh"].validate()
    assert report.is_watertight
    assert report.is_winding_consistent
    assert report.is_outward
    assert report.num_boundary_edges == 0
    assert report.num_components == 1
    lo, hi = np.asarray(board["mesh"].bounds)
    np.testing.assert_allclose(lo, 0.0, atol=1e-9)
    np.testing.assert_allclose(hi[:2], PLATE_SIZE[:2], atol=1e-9)
    assert hi[2] == pytest.approx(TOP_Z + 0.012)  # the 12 mm step is the tallest feature
    trimesh = pytest.importorskip("trimesh")
    tm = trimesh.Trimesh(board["mesh"].vertices, board["mesh"].faces, process=True)
    assert tm.is_watertight
    assert tm.is_winding_consistent
    assert tm.volume > 0
    assert tm.euler_number == 2 - 2 * 6  # six through-holes: genus 6


def test_board_has_the_graded_features(board):
    feats = board["features"]

    def params(kind):
        return sorted(round(f["parameter_m"] * 1000, 3) for f in feats if f["kind"] == kind)

    assert params("step") == [1, 2, 4, 6, 8, 10, 12]
    assert params("hole") == [2, 4, 6, 8, 10, 12]
    for kind in ("convex_cylinder", "concave_cylinder", "dome"):
        radii = params(kind)
        assert radii[0] == 5
        assert radii[-1] == 40
        assert len(radii) >= 6
    assert {"ridge", "groove", "flat", "edge", "corner", "tilt"} <= {f["kind"] for f in feats}
    for f in feats:
        assert {"name", "kind", "parameter", "parameter_m", "poses"} <= set(f)
        assert f["poses"], f["name"]
    ids = board["ids"]
    np.testing.assert_array_equal(ids, np.arange(len(ids)))
    np.testing.assert_allclose(np.linalg.norm(board["normals"], axis=1), 1.0, atol=1e-12)
    assert len(set(board["names"])) == len(feats)


def test_every_pose_lies_on_the_board_surface(board):
    pts, nrm = board["points"], board["normals"]
    vertical = np.abs(nrm[:, 2]) < 0.1  # on a side face: cast along -normal instead
    direction = np.where(vertical[:, None], -nrm, [0.0, 0.0, -1.0])
    start = pts - 0.05 * direction
    hits = mgn.RayScene(board["mesh"]).intersect(start, direction)
    assert hits.hit.all()
    miss = np.linalg.norm(hits.points - pts, axis=1)
    assert miss.max() < 1e-4, np.asarray(board["names"])[miss >= 1e-4]


def test_flat_controls_seal_and_hole_rims_do_not(board):
    pred = predict_seals(board["mesh"], board["points"], board["normals"], SuctionCup())
    names = np.asarray(board["names"])
    assert pred[np.isin(names, ["flat", "side_face"])].all()
    first_hole_pose = [f["poses"][0]["pose_id"] for f in board["features"] if f["kind"] == "hole"]
    assert not pred[first_hole_pose].any()  # 1 mm beyond the rim: the hole is under the cup


def test_write_calibration_board_files(board, board_dir, tmp_path):
    n_faces = board["mesh"].num_faces
    data = (board_dir / "board.stl").read_bytes()
    assert not data.startswith(b"solid")  # binary, not ASCII
    (count,) = struct.unpack("<I", data[80:84])
    assert count == n_faces
    assert len(data) == 84 + 50 * count
    loaded = mgn.load_mesh(board_dir / "board.stl", scale=1e-3)  # the STL is in millimetres
    np.testing.assert_allclose(np.asarray(loaded.bounds)[1, :2], PLATE_SIZE[:2], atol=1e-6)
    assert loaded.validate().is_watertight
    assert "MILLIMETRES" in (board_dir / "README.txt").read_text()

    with (board_dir / "poses.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0])[:9] == [
        "pose_id",
        "feature",
        "parameter_m",
        "x_m",
        "y_m",
        "z_m",
        "nx",
        "ny",
        "nz",
    ]
    assert len(rows) == len(board["ids"])
    xyz = np.array([[float(r[k]) for k in ("x_m", "y_m", "z_m")] for r in rows])
    np.testing.assert_allclose(xyz, board["points"], atol=1e-6)  # metres
    with (board_dir / "results_template.csv").open(newline="") as fh:
        tmpl = list(csv.DictReader(fh))
    assert list(tmpl[0]) == ["pose_id", "sealed", "tear_off_force_N"]
    assert [int(r["pose_id"]) for r in tmpl] == board["ids"].tolist()
    assert all(r["sealed"] == "" and r["tear_off_force_N"] == "" for r in tmpl)

    with pytest.raises(mgn.IoError, match="overwrite"):
        write_calibration_board(board_dir)
    fresh = write_calibration_board(tmp_path / "again")
    assert fresh["stl"].read_bytes() == data  # deterministic
    write_calibration_board(tmp_path / "again", overwrite=True)


# ----------------------------------------------------------------------------------------------
# Fitting c1, c2
# ----------------------------------------------------------------------------------------------


def test_recovers_known_cup_constants_from_noisy_simulated_outcomes(board):
    """Simulate outcomes with known constants (two attempts per pose) plus 5 % label noise; the
    fit from the defaults must predict like the true model. c1 and c2 are only weakly
    identifiable (whole regions of the plane predict the same outcomes), so predictions are
    tested, not the values."""
    mesh, pts, nrm = board["mesh"], board["points"], board["normals"]
    default = SuctionCup()
    true = SuctionCup(c1=4 * default.c1, c2=0.25 * default.c2)
    y_true = predict_seals(mesh, pts, nrm, true)
    y_default = predict_seals(mesh, pts, nrm, default)
    # The board discriminates: the default constants disagree with the truth on > 5 % of poses.
    assert np.mean(y_default != y_true) > 0.05
    attempts = 2
    y_sim = np.tile(y_true, attempts)
    flip = np.random.default_rng(20240607).random(len(y_sim)) < 0.05
    measured = y_sim ^ flip

    report = calibrate(
        mesh,
        np.tile(pts, (attempts, 1)),
        np.tile(nrm, (attempts, 1)),
        measured,
        default,
        seed=0,
        features=board["names"] * attempts,
    )
    fitted = predict_seals(mesh, pts, nrm, report.cup)
    np.testing.assert_array_equal(np.tile(fitted, attempts), report.predicted)
    agreement = float(np.mean(fitted == y_true))
    print(
        f"\ntrue c1={true.c1:.5g} c2={true.c2:.5g}; fitted c1={report.cup.c1:.5g} "
        f"c2={report.cup.c2:.5g}; held-out accuracy {report.test['accuracy']:.3f}; agreement "
        f"with the true model {agreement:.3f} (default: {np.mean(y_default == y_true):.3f}); "
        f"{report.evaluations} evaluations"
    )
    assert report.test["accuracy"] >= 0.9
    assert agreement >= 0.95
    assert report.objective == pytest.approx(report.train["accuracy"])
    # The fit is at least as good on the training split as the true constants.
    tr = report.train_indices
    assert report.train["accuracy"] >= np.mean(y_sim[tr] == measured[tr]) - 1e-12
    # Every other cup field is kept.
    assert report.cup.radius == default.radius
    assert report.cup.num_points == default.num_points
    text = report.format_report()
    assert "c1" in text
    assert "held-out" in text
    assert "specificity" in text
    assert "tilt" in text


def test_split_is_stratified_and_reproducible(board):
    mesh, pts, nrm = board["mesh"], board["points"], board["normals"]
    sub = np.arange(0, len(pts), 3)
    y = predict_seals(mesh, pts[sub], nrm[sub])
    a = calibrate(mesh, pts[sub], nrm[sub], y, seed=7, global_evaluations=20, local_evaluations=5)
    b = calibrate(
        mesh,
        pts[sub],
        nrm[sub],
        y,
        seed=7,
        global_evaluations=20,
        local_evaluations=5,
        num_threads=1,
    )
    np.testing.assert_array_equal(a.test_indices, b.test_indices)
    assert (a.cup.c1, a.cup.c2, a.evaluations) == (b.cup.c1, b.cup.c2, b.evaluations)
    both = np.sort(np.concatenate([a.train_indices, a.test_indices]))
    np.testing.assert_array_equal(both, np.arange(len(sub)))
    for cls in (True, False):
        n_cls = int(np.sum(y == cls))
        assert int(np.sum(y[a.test_indices] == cls)) == math.floor(0.3 * n_cls + 0.5)
    c = calibrate(mesh, pts[sub], nrm[sub], y, seed=8, global_evaluations=20, local_evaluations=5)
    assert not np.array_equal(a.test_indices, c.test_indices)


def test_ties_keep_the_initial_constants(board):
    """Flat controls seal for every (c1, c2): all points tie, the initial constants win."""
    mesh, pts, nrm = board["mesh"], board["points"], board["normals"]
    flat = np.asarray(board["names"]) == "flat"
    cup = SuctionCup(c1=0.2, c2=0.005)
    report = calibrate(mesh, pts[flat], nrm[flat], np.ones(flat.sum(), bool), cup)
    assert (report.cup.c1, report.cup.c2) == (0.2, 0.005)
    assert report.train["accuracy"] == 1.0
    assert math.isnan(report.train["specificity"])  # no measured failure: zero denominator


def test_classification_metrics_counts_and_nan():
    m = classification_metrics([1, 1, 0, 0, 1], [1, 0, 0, 1, 1])
    assert (m["tp"], m["fp"], m["tn"], m["fn"]) == (2, 1, 1, 1)
    assert m["ppv"] == pytest.approx(2 / 3)
    assert m["npv"] == pytest.approx(0.5)
    assert m["sensitivity"] == pytest.approx(2 / 3)
    assert m["specificity"] == pytest.approx(0.5)
    assert m["accuracy"] == pytest.approx(0.6)
    none_predicted = classification_metrics([0, 0], [1, 0])
    assert math.isnan(none_predicted["ppv"])
    assert none_predicted["npv"] == 0.5
    with pytest.raises(mgn.InvalidArgumentError, match="equal lengths"):
        classification_metrics([1], [1, 0])


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"c1_range": (0.0, 1.0)}, "c1_min"),
        ({"c1_range": (0.5, 0.1)}, "c1_max"),
        ({"c2_range": (-1.0, 1.0)}, "c2_min"),
        ({"c2_range": (0.1, 0.1)}, "c2_max"),
        ({"holdout_fraction": 0.95}, "holdout_fraction"),
        ({"holdout_fraction": -0.1}, "holdout_fraction"),
        ({"global_evaluations": 0}, "global_evaluations"),
        ({"surface_index": [0, 0, 1]}, r"experiments\[2\]\.surface"),
    ],
)
def test_calibrate_rejects_bad_options(board, kwargs, field):
    pts, nrm = board["points"][:3], board["normals"][:3]
    with pytest.raises(mgn.InvalidArgumentError, match=field):
        calibrate(board["mesh"], pts, nrm, [1, 0, 1], **kwargs)


def test_calibrate_rejects_bad_experiments(board):
    mesh, pts, nrm = board["mesh"], board["points"][:3].copy(), board["normals"][:3].copy()
    with pytest.raises(mgn.InvalidArgumentError, match="at least one"):
        calibrate(mesh, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, bool))
    bad = pts.copy()
    bad[1, 2] = np.nan
    with pytest.raises(mgn.InvalidArgumentError, match=r"experiments\[1\]\.point"):
        calibrate(mesh, bad, nrm, [1, 0, 1])
    bad = nrm.copy()
    bad[2] = 0.0
    with pytest.raises(mgn.InvalidArgumentError, match=r"experiments\[2\]\.normal"):
        calibrate(mesh, pts, bad, [1, 0, 1])
    bad = pts.copy()
    bad[0, 2] += 0.01  # 1 cm above the surface
    with pytest.raises(mgn.InvalidArgumentError, match=r"experiments\[0\].*not on the mesh"):
        calibrate(mesh, bad, nrm, [1, 0, 1])
    with pytest.raises(mgn.InvalidArgumentError, match="sealed"):
        calibrate(mesh, pts, nrm, [1, 0, 2])


# ----------------------------------------------------------------------------------------------
# CSV workflow
# ----------------------------------------------------------------------------------------------


def _write_results(path, rows, header=("pose_id", "sealed", "tear_off_force_N")):
    with Path(path).open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows(rows)
    return path


def test_calibrate_from_csv_round_trip(board, board_dir, tmp_path):
    y = predict_seals(board["mesh"], board["points"], board["normals"], SuctionCup())
    rows = [[pid, int(s), "12.5" if s else ""] for pid, s in zip(board["ids"], y, strict=True)]
    rows.append([3, int(y[3]), ""])  # a repeated attempt
    rows.append([4, "", ""])  # not tried: skipped
    results = _write_results(tmp_path / "results.csv", rows)
    budget = {"global_evaluations": 30, "local_evaluations": 10}
    report = calibrate_from_csv(results, board_dir, **budget)
    assert len(report.measured) == len(board["ids"]) + 1
    assert report.train["accuracy"] == 1.0
    assert report.test["accuracy"] == 1.0
    assert report.pose_ids is not None
    assert report.pose_ids[-1] == 3
    assert "accuracy" in report.format_report()
    # Without board_dir: the results' own folder if it holds the board, else the built-in board.
    inside = _write_results(board_dir / "results.csv", rows)
    assert calibrate_from_csv(inside, **budget).test == report.test
    assert calibrate_from_csv(results, **budget).test == report.test


def test_read_results_csv_forces_and_blanks(tmp_path):
    path = _write_results(
        tmp_path / "r.csv", [[0, 1, "3.5"], [1, "", ""], [2, 0, ""], ["", "", ""]]
    )
    r = read_results_csv(path, [0, 1, 2])
    np.testing.assert_array_equal(r.pose_ids, [0, 2])
    np.testing.assert_array_equal(r.sealed, [True, False])
    assert r.tear_off_force[0] == 3.5
    assert math.isnan(r.tear_off_force[1])
    np.testing.assert_array_equal(r.rows, [2, 4])


@pytest.mark.parametrize(
    ("rows", "header", "match"),
    [
        ([[0, 1]], ("pose_id", "outcome"), r"missing column.*sealed"),
        ([[0, 1], [99999, 0]], None, r"row 3: pose_id 99999 is not in poses.csv"),
        ([[0, 1], [1, "yes"]], None, r"row 3: sealed must be 0 or 1"),
        ([[0, 2]], None, r"row 2: sealed must be 0 or 1"),
        ([[0, 0.5]], None, r"row 2: sealed must be 0 or 1"),
        ([["x", 1]], None, r"row 2: pose_id must be an integer"),
        ([[0, 1, "-3"]], None, r"row 2: tear_off_force_N"),
        ([[0, ""]], None, r"no measured outcomes"),
    ],
)
def test_bad_results_csv_names_the_row(board_dir, tmp_path, rows, header, match):
    kw = {} if header is None else {"header": header}
    path = _write_results(tmp_path / "bad.csv", rows, **kw)
    with pytest.raises(mgn.InvalidArgumentError, match=match):
        calibrate_from_csv(path, board_dir)


def test_missing_results_file_is_an_io_error(board_dir, tmp_path):
    with pytest.raises(mgn.IoError, match="not found"):
        calibrate_from_csv(tmp_path / "nope.csv", board_dir)
