"""The GraspNet export (``mgn export graspnet``) and the 2-D grasp rectangles, checked against
the array layouts graspnetAPI and suctionnetAPI document (GraspGroup: [score, width, height,
depth, rotation (9, row-major), translation (3), object_id], gripper x = approach, y = closing;
SuctionGroup: [score, direction (3), translation (3), object_id], the cup along +direction;
RectGraspGroup: [center_x, center_y, open_x, open_y, height, score, object_id]; Jacquard
``x;y;theta;w;h``), read here with numpy alone, and against mgn's own files read with h5py."""

from __future__ import annotations

import json
import math
from pathlib import Path

import h5py
import numpy as np
import pytest
from PIL import Image

import mgn
from mgn.cli.main import main
from mgn.errors import InvalidArgumentError, IoError
from mgn.hardware import ParallelJawGripper
from mgn.io.graspnet import (
    export_graspnet,
    grasp_rectangles,
    graspnet_gripper,
    graspnet_rows,
    jacquard_text,
    rect_rows,
    suctionnet_rows,
)
from mgn.scene.cameras import Intrinsics

CM = 0.01


def _frame(approach: np.ndarray, closing: np.ndarray, p1: np.ndarray) -> np.ndarray:
    """mgn's grasp frame: x = closing, y = approach x closing, z = approach, origin p1."""
    a = approach / np.linalg.norm(approach)
    v = closing - a * (closing @ a)
    v /= np.linalg.norm(v)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = v, np.cross(a, v), a, p1
    return T


def _tilted(deg: float, z: float = 0.6) -> np.ndarray:
    """A grasp whose approach leans ``deg`` degrees from +z towards +y, closing along x."""
    t = math.radians(deg)
    return _frame(
        np.array([0.0, math.sin(t), math.cos(t)]), np.array([1.0, 0, 0]), np.array([0.01, -0.02, z])
    )


# --- rectangles of constructed grasps -------------------------------------------------------------


def test_rectangle_of_a_grasp_along_the_optical_axis() -> None:
    K = Intrinsics(640, 480, 600.0, 600.0, 320.0, 240.0)
    w, z, h = 0.05, 0.75, 0.02
    p1 = np.array([0.03, -0.04, z])
    T = _frame(np.array([0.0, 0, 1]), np.array([1.0, 0, 0]), p1)
    r = grasp_rectangles(T[None], [w], [0.7], [3], K, jaw_height=h)
    assert len(r) == 1
    # pinhole by hand, OpenCV pixel centres (cx - 0.5)
    centre = p1 + [w / 2, 0, 0]
    u = 600.0 * centre[0] / z + 320.0 - 0.5
    v = 600.0 * centre[1] / z + 240.0 - 0.5
    assert r.center[0] == pytest.approx([u, v], abs=1e-9)
    assert r.width[0] == pytest.approx(w * 600.0 / z, rel=1e-12)
    assert r.height[0] == pytest.approx(h * 600.0 / z, rel=1e-12)
    assert r.angle[0] == pytest.approx(0.0, abs=1e-12)
    assert r.score[0] == 0.7
    assert r.object_id[0] == 3
    # the jaws open wider than the contacts: the same centre, width opening * fx / z
    r = grasp_rectangles(T[None], [w], [0.7], [3], K, jaw_height=h, opening=[0.08])
    assert r.center[0] == pytest.approx([u, v], abs=1e-9)
    assert r.width[0] == pytest.approx(0.08 * 600.0 / z, rel=1e-12)


def test_rectangle_width_uses_fx_and_angle_is_clockwise_on_screen() -> None:
    K = Intrinsics(640, 480, 500.0, 700.0, 320.0, 240.0)
    w, z = 0.04, 0.5
    # opening along the image's x axis: fx counts
    T = _frame(np.array([0.0, 0, 1]), np.array([1.0, 0, 0]), np.array([0.0, 0, z]))
    r = grasp_rectangles(T[None], [w], [1.0], [1], K, jaw_height=0.02)
    assert r.width[0] == pytest.approx(w * 500.0 / z)
    # opening 30 deg from x towards +y (down in the image): +30 deg
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    K2 = Intrinsics(640, 480, 600.0, 600.0, 320.0, 240.0)
    T = _frame(np.array([0.0, 0, 1]), np.array([c, s, 0]), np.array([0.0, 0, z]))
    r = grasp_rectangles(T[None], [w], [1.0], [1], K2, jaw_height=0.02)
    assert math.degrees(r.angle[0]) == pytest.approx(30.0)
    assert r.width[0] == pytest.approx(w * 600.0 / z)
    # the same opening the other way round (closing -v) is the same rectangle: angle in (-90, 90]
    T = _frame(np.array([0.0, 0, 1]), np.array([-c, -s, 0]), np.array([w * c, w * s, z]))
    r2 = grasp_rectangles(T[None], [w], [1.0], [1], K2, jaw_height=0.02)
    assert math.degrees(r2.angle[0]) == pytest.approx(30.0)
    assert r2.center[0] == pytest.approx(r.center[0])


def test_tilt_threshold() -> None:
    K = Intrinsics(640, 480, 600.0, 600.0, 320.0, 240.0)
    poses = np.stack([_tilted(d) for d in (0.0, 15.0, 19.9, 20.0, 20.1, 25.0, 60.0)])
    r = grasp_rectangles(poses, np.full(7, 0.03), np.arange(7.0), np.zeros(7), K, jaw_height=0.02)
    assert r.index.tolist() == [0, 1, 2, 3]
    r = grasp_rectangles(
        poses, np.full(7, 0.03), np.arange(7.0), np.zeros(7), K, jaw_height=0.02, max_tilt_deg=30.0
    )
    assert r.index.tolist() == [0, 1, 2, 3, 4, 5]
    # a grasp approaching away from the camera (-z) is never a rectangle
    flipped = _frame(np.array([0.0, 0, -1]), np.array([1.0, 0, 0]), np.array([0.0, 0, 0.5]))
    assert len(grasp_rectangles(flipped[None], [0.03], [1], [0], K, jaw_height=0.02)) == 0
    with pytest.raises(InvalidArgumentError, match="max_tilt_deg"):
        grasp_rectangles(
            poses, np.full(7, 0.03), np.ones(7), np.zeros(7), K, jaw_height=0.02, max_tilt_deg=90.0
        )


def _jacquard_jaw_ends(line: str) -> np.ndarray:
    """The two ends of the opening of a Jacquard line, read as planar grasp detectors read it:
    the centre, then half the width along theta (degrees, from x towards y, y down)."""
    x, y, theta, w, _ = (float(f) for f in line.split(";"))
    d = np.array([math.cos(math.radians(theta)), math.sin(math.radians(theta))])
    return np.array([[x, y] - w / 2 * d, [x, y] + w / 2 * d])


def test_jacquard_and_rect_rows_round_trip() -> None:
    K = Intrinsics(640, 480, 600.0, 600.0, 320.0, 240.0)
    rng = np.random.default_rng(5)
    poses, widths = [], []
    for _ in range(20):
        ang = rng.uniform(-math.pi, math.pi)
        poses.append(
            _frame(
                np.array([0.0, 0, 1]),
                np.array([math.cos(ang), math.sin(ang), 0]),
                np.array([*rng.uniform(-0.1, 0.1, 2), rng.uniform(0.4, 0.9)]),
            )
        )
        widths.append(rng.uniform(0.01, 0.08))
    P = np.stack(poses)
    W = np.array(widths)
    r = grasp_rectangles(P, W, rng.uniform(size=20), np.arange(20), K, jaw_height=0.02)
    lines = jacquard_text(r).splitlines()
    assert len(lines) == 20
    for k, line in enumerate(lines):
        ends = _jacquard_jaw_ends(line)
        # the projected contacts, by hand (pinhole, OpenCV pixel centres)
        p1 = P[k, :3, 3]
        p2 = p1 + W[k] * P[k, :3, 0]
        proj = [[600 * q[0] / q[2] + 319.5, 600 * q[1] / q[2] + 239.5] for q in (p1, p2)]
        err = min(np.abs(ends - proj).max(), np.abs(ends[::-1] - proj).max())
        assert err < 0.01  # 2 decimals in the file
        assert -90 < float(line.split(";")[2]) <= 90
    rows = rect_rows(r)
    assert rows.shape == (20, 7)
    assert rows.dtype == np.float32
    half = np.linalg.norm(rows[:, 2:4] - rows[:, 0:2], axis=1)
    assert half == pytest.approx(r.width / 2, rel=1e-5)
    assert rows[:, 4] == pytest.approx(r.height, rel=1e-6)
    assert rows[:, 6].tolist() == list(range(20))


# --- graspnetAPI / suctionnetAPI rows -----------------------------------------------------------


def test_graspnet_rows_layout() -> None:
    a = np.array([0.2, -0.1, 1.0])
    T = _frame(a, np.array([1.0, 0.3, 0]), np.array([0.05, 0.02, 0.6]))
    # the default gripper: fingers 5 cm long, 2 cm wide, pads 8 mm above the tips, margin 3 cm
    gripper = graspnet_gripper(ParallelJawGripper())
    rows = graspnet_rows(T[None].repeat(2, 0), [0.04, 0.06], [0.8, 0.5], [7, 7], gripper)
    assert rows.shape == (2, 17)
    assert rows.dtype == np.float32
    score, width, height, depth = rows[0, :4]
    R = rows[0, 4:13].reshape(3, 3).astype(np.float64)  # row-major
    t = rows[0, 13:16].astype(np.float64)
    assert (score, width, height, depth) == pytest.approx((0.8, 0.07, 0.02, 0.03))
    assert rows[1, 1] == pytest.approx(0.08)  # the opening stops at max_opening
    a = a / np.linalg.norm(a)
    assert R[:, 0] == pytest.approx(a, abs=1e-6)  # x = approach
    assert R[:, 1] == pytest.approx(T[:3, 0], abs=1e-6)  # y = closing
    assert R.T @ R == pytest.approx(np.eye(3), abs=1e-6)
    assert np.linalg.det(R) == pytest.approx(1)
    # graspnetAPI's fingers run from 2 cm behind t (its palm) to depth beyond t: mgn's fingers
    centre = T[:3, 3] + 0.02 * T[:3, 0]  # between the contacts
    tips = centre + 0.008 * a
    assert t + 0.03 * a == pytest.approx(tips, abs=1e-7)
    assert t - 0.02 * a == pytest.approx(tips - 0.05 * a, abs=1e-7)
    assert rows[0, 16] == 7


def test_suctionnet_rows_layout() -> None:
    a = np.array([0.0, 0.6, 0.8])
    T = _frame(a, np.array([1.0, 0, 0]), np.array([0.01, 0.02, 0.7]))
    rows = suctionnet_rows(T[None], [0.9], [4])
    assert rows.shape == (1, 8)
    assert rows.dtype == np.float32
    assert rows[0, 0] == pytest.approx(0.9)
    assert rows[0, 1:4] == pytest.approx(-a, abs=1e-7)  # outward normal: the cup lies along it
    assert rows[0, 4:7] == pytest.approx(T[:3, 3])
    assert rows[0, 7] == 4


# --- the export of a generated dataset ------------------------------------------------------------


@pytest.fixture(scope="module")
def exported(small_dataset: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("graspnet") / "out"
    result = export_graspnet(small_dataset, out, max_tilt_deg=80.0)
    assert result.written == [0, 1]
    assert result.skipped == []
    assert min(result.counts[k] for k in ("grasp", "suction", "rect")) > 0
    return out


def _views(ds: Path, n: int) -> list[int]:
    return sorted(int(p.name.split("_")[0]) for p in (ds / f"scene{n}").glob("*_rgb.png"))


def _h5(ds: Path, n: int, v: int) -> dict[str, np.ndarray]:
    with h5py.File(ds / f"scene{n}" / f"{v}_scene.hdf5", "r") as f:
        out: dict[str, np.ndarray] = {}
        f.visititems(
            lambda k, d: out.__setitem__(k, d[()]) if isinstance(d, h5py.Dataset) else None
        )
        return out


def test_export_files_match_the_scene_files(small_dataset: Path, exported: Path) -> None:
    gripper = ParallelJawGripper()
    for n in (0, 1):
        folder = exported / "scenes" / f"scene_{n:04d}" / "mgn"
        params = json.loads((small_dataset / f"scene{n}" / "0_camera_params.json").read_text())
        K = np.load(folder / "camK.npy")
        assert K == pytest.approx(
            np.array(
                [
                    [params["fx"], 0, params["cx"] - 0.5],
                    [0, params["fy"], params["cy"] - 0.5],
                    [0, 0, 1],
                ]
            )
        )
        for v in _views(small_dataset, n):
            h = _h5(small_dataset, n, v)
            cats = h["objects/categories"].astype(int)
            pre = "non_colliding_grasps/paralleljaw/"
            T = h[pre + "contact_poses_relative_to_camera"].astype(np.float64)
            T[:, :3, 3] *= CM
            w = h[pre + "contact_width"].astype(np.float64) * CM
            flange = h[pre + "franka_poses_relative_to_camera"].astype(np.float64)
            s = h[pre + "score_analytical"].astype(np.float64)
            g = np.load(folder / "grasp" / f"{v:04d}.npy")
            assert g.dtype == np.float32
            assert g.shape == (len(T), 17)
            assert (np.diff(g[:, 0]) <= 0).all()  # best first
            order = np.argsort(-s, kind="stable")
            assert g[:, 0] == pytest.approx(s[order])
            assert g[:, 16].astype(int).tolist() == cats[h[pre + "object_id"][order]].tolist()
            R = g[:, 4:13].reshape(-1, 3, 3).astype(np.float64)
            assert R[:, :, 0] == pytest.approx(T[order, :3, 2], abs=1e-5)
            # the fingertips: depth beyond t along the approach = the flange + flange_to_tip
            tips = g[:, 13:16] + g[:, 3:4] * R[:, :, 0]
            want = flange[order, :3, 3] * CM + gripper.flange_to_tip * T[order, :3, 2]
            assert tips == pytest.approx(want, abs=2e-6)
            # graspnetAPI's palm (2 cm behind t) is mgn's palm face, finger_size z behind the tips
            palm = g[:, 13:16] - 0.02 * R[:, :, 0]
            assert palm == pytest.approx(want - gripper.finger_size[2] * T[order, :3, 2], abs=2e-6)
            opening = np.minimum(w[order] + gripper.collision_margin, gripper.max_opening)
            assert g[:, 1] == pytest.approx(opening, abs=1e-7)
            assert (g[:, 2] == np.float32(gripper.finger_size[1])).all()

            spre = "non_colliding_grasps/suctioncup/"
            S = h[spre + "contact_poses_relative_to_camera"].astype(np.float64)
            ss = (h[spre + "score_analytical"] * h[spre + "score_wrench"]).astype(np.float64)
            with np.load(folder / "suction" / f"{v:04d}.npz") as z:
                assert list(z.keys()) == ["arr_0"]
                su = z["arr_0"]
            assert su.dtype == np.float32
            assert su.shape == (len(S), 8)
            order = np.argsort(-ss, kind="stable")
            assert su[:, 0] == pytest.approx(ss[order], abs=1e-6)
            assert su[:, 1:4] == pytest.approx(-S[order, :3, 2], abs=1e-6)
            assert su[:, 4:7] == pytest.approx(S[order, :3, 3] * CM, abs=1e-7)
            assert su[:, 7].astype(int).tolist() == cats[h[spre + "object_id"][order]].tolist()

            rect = np.load(folder / "rect" / f"{v:04d}.npy")
            lines = (folder / "jacquard" / f"{v:04d}_grasps.txt").read_text().splitlines()
            assert rect.shape == (len(lines), 7)
            tilt = np.degrees(np.arccos(np.clip(T[:, 2, 2], -1, 1)))
            assert len(lines) == int((tilt <= 80.0).sum())
            for row, line in zip(rect, lines, strict=True):
                x, y, theta, width, height = (float(f) for f in line.split(";"))
                assert (x, y) == pytest.approx((row[0], row[1]), abs=0.006)
                d = row[2:4] - row[0:2]
                assert theta == pytest.approx(math.degrees(math.atan2(d[1], d[0])), abs=0.01)
                assert width == pytest.approx(2 * np.linalg.norm(d), abs=0.01)
                assert height == pytest.approx(row[4], abs=0.006)


def test_export_skips_scenes_and_takes_options(
    small_dataset: Path, exported: Path, tmp_path: Path
) -> None:
    before = {p: p.read_bytes() for p in exported.rglob("*") if p.is_file()}
    again = export_graspnet(small_dataset, exported, max_tilt_deg=80.0)
    assert again.written == []
    assert again.skipped == [0, 1]
    assert {p: p.read_bytes() for p in exported.rglob("*") if p.is_file()} == before
    # the same scenes again: the same bytes
    out = tmp_path / "again"
    export_graspnet(small_dataset, out, scenes=[1], max_tilt_deg=80.0)
    for p in (out / "scenes" / "scene_0001").rglob("*"):
        if p.is_file():
            assert p.read_bytes() == (exported / p.relative_to(out)).read_bytes()
    # the simulation score: grasps without one (NaN) are left out
    sim = export_graspnet(
        small_dataset,
        tmp_path / "sim",
        scenes=[1],
        camera="realsense",
        pj_score="simulation",
        suction_score="seal",
        max_tilt_deg=45,
    )
    total = 0
    for v in _views(small_dataset, 1):
        h = _h5(small_dataset, 1, v)
        s = h["non_colliding_grasps/paralleljaw/score_simulation"]
        g = np.load(tmp_path / "sim/scenes/scene_0001/realsense/grasp" / f"{v:04d}.npy")
        with np.load(tmp_path / "sim/scenes/scene_0001/realsense/suction" / f"{v:04d}.npz") as z:
            seal = np.sort(h["non_colliding_grasps/suctioncup/score_analytical"])[::-1]
            assert z["arr_0"][:, 0] == pytest.approx(seal)
        assert len(g) == int(np.isfinite(s).sum())
        total += len(s) - len(g)
    assert sim.counts["grasp_unscored"] == total > 0


def test_export_bad_inputs(small_dataset: Path, tmp_path: Path) -> None:
    with pytest.raises(InvalidArgumentError, match="camera"):
        export_graspnet(small_dataset, tmp_path / "x", camera="a/b")
    with pytest.raises(InvalidArgumentError, match="pj_score"):
        export_graspnet(small_dataset, tmp_path / "x", pj_score="best")
    with pytest.raises(InvalidArgumentError, match="suction_score"):
        export_graspnet(small_dataset, tmp_path / "x", suction_score="best")
    with pytest.raises(InvalidArgumentError, match="max_tilt_deg"):
        export_graspnet(small_dataset, tmp_path / "x", max_tilt_deg=-1)
    with pytest.raises(IoError, match="scene ids"):
        export_graspnet(small_dataset, tmp_path / "x", scenes=[7])


def test_cli_export_and_show_rectangles(
    small_dataset: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert (
        main(
            [
                "export",
                "graspnet",
                str(small_dataset),
                str(tmp_path / "gn"),
                "--scenes",
                "1",
                "--max-tilt",
                "45",
            ]
        )
        == 0
    )
    assert "1 scene(s) written" in capsys.readouterr().out
    lines = (tmp_path / "gn/scenes/scene_0001/mgn/jacquard/0000_grasps.txt").read_text()
    # one line per collision-free grasp of the view whose approach leans at most 45 deg
    pj = mgn.Dataset(small_dataset).scene(1).view(0).grasps("paralleljaw")
    approach_z = np.asarray(pj["contact_poses_relative_to_camera"])[:, 2, 2]
    upright = int((approach_z >= np.cos(np.radians(45.0)) - 1e-12).sum())
    assert 0 < upright < len(approach_z)
    assert len(lines.splitlines()) == upright
    png = tmp_path / "rect.png"
    assert (
        main(
            [
                "show",
                str(small_dataset),
                "--scene",
                "1",
                "--view",
                "0",
                "--grasps",
                "rectangles",
                "--max-tilt",
                "45",
                "-o",
                str(png),
            ]
        )
        == 0
    )
    plain = tmp_path / "plain.png"
    assert main(["show", str(small_dataset), "--scene", "1", "--view", "0", "-o", str(plain)]) == 0
    with Image.open(png) as a, Image.open(plain) as b:
        img, ref = np.asarray(a.convert("RGB")), np.asarray(b.convert("RGB"))
    h = min(img.shape[0], ref.shape[0]) - 80  # the picture, above the legend
    assert (img[:h] != ref[:h]).any(axis=2).sum() > 0  # rectangles drawn
