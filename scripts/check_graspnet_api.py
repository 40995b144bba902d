"""Load a GraspNet export (``mgn export graspnet DS OUT``) with graspnetAPI and suctionnetAPI and
compare what they read with the grasps of the dataset.

Run it in an environment where ``graspnetAPI`` and ``suctionnetAPI`` import (they need open3d,
opencv, transforms3d, autolab_core, cvxopt, scikit-learn, scikit-image and h5py; mgn itself is
not needed):

    python scripts/check_graspnet_api.py OUT DS [--camera mgn]

Per view it checks, against ``{v}_scene.hdf5`` of the dataset read with h5py: graspnetAPI's
``GraspGroup().from_npy`` (scores, widths = the jaws' opening, approach = the first rotation
column, the grasp point plus depth along the approach at the fingertips, object ids),
``RectGraspGroup`` (one row per line of the Jacquard file, the same centres), suctionnetAPI's
``SuctionGroup().from_npy`` (scores, directions = minus the approach, points). It then runs
graspnetAPI's own collision and emptiness test (``collision_detection``, its gripper model) on
the parallel-jaw grasps against the view's depth points, once as exported and once with the
approach and closing columns swapped, and prints both counts (grasps holding scene points
between the jaws; of those, grasps whose fingers and palm meet no scene point). Exit status 1
on a mismatch.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import h5py
import numpy as np
from graspnetAPI import GraspGroup, RectGraspGroup
from graspnetAPI.utils.eval_utils import collision_detection
from suctionnetAPI import SuctionGroup

CM = 0.01


def _scene_points(ds_view: Path, K: np.ndarray) -> np.ndarray:
    """Camera-frame points (m) of the view's sensor depth (``{v}.npz``, cm)."""
    with np.load(ds_view) as z:
        d = z["depth"].astype(np.float64) * CM
    v, u = np.nonzero(np.isfinite(d) & (d > 0))
    z = d[v, u]
    x = (u - K[0, 2]) * z / K[0, 0]
    y = (v - K[1, 2]) * z / K[1, 1]
    return np.stack([x, y, z], axis=1)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path, help="the export folder")
    ap.add_argument("dataset", type=Path, help="the mgn dataset it was exported from")
    ap.add_argument("--camera", default="mgn")
    args = ap.parse_args()
    config = json.loads((args.dataset / "dataset.json").read_text()).get("config", {})
    g = config.get("gripper") or {}
    tip = float(g.get("contact_from_tip", 0.008))  # pad centre above the tip, m
    margin = float(g.get("collision_margin", 0.03))
    max_opening = float(g.get("max_opening", 0.08))
    bad: list[str] = []
    totals = {"views": 0, "grasps": 0, "suction": 0, "rects": 0}
    # per frame convention: [grasps with points between the jaws, of those free of the scene, all]
    empty = {"exported": [0, 0, 0], "swapped": [0, 0, 0]}
    for folder in sorted((args.out / "scenes").glob("scene_*")):
        n = int(folder.name.split("_")[1])
        cam = folder / args.camera
        K = np.load(cam / "camK.npy")
        for gfile in sorted((cam / "grasp").glob("*.npy")):
            v = int(gfile.stem)
            where = f"scene {n} view {v}"
            totals["views"] += 1
            with h5py.File(args.dataset / f"scene{n}" / f"{v}_scene.hdf5", "r") as f:
                cats = f["objects/categories"][()].astype(int)
                pj = {k: f["non_colliding_grasps/paralleljaw/" + k][()] for k in
                      ("contact_poses_relative_to_camera", "contact_width", "score_analytical",
                       "object_id")}  # fmt: skip
                su = {k: f["non_colliding_grasps/suctioncup/" + k][()] for k in
                      ("contact_poses_relative_to_camera", "score_analytical", "score_wrench",
                       "object_id")}  # fmt: skip
            gg = GraspGroup().from_npy(str(gfile))
            T = pj["contact_poses_relative_to_camera"].astype(np.float64)
            order = np.argsort(-pj["score_analytical"].astype(np.float64), kind="stable")
            T = T[order]
            w = pj["contact_width"][order] * CM
            tips = T[:, :3, 3] * CM + 0.5 * w[:, None] * T[:, :3, 0] + tip * T[:, :3, 2]
            opening = np.minimum(w + margin, max_opening)
            approach = gg.rotation_matrices[:, :, 0]
            checks = {
                "count": len(gg) == len(T),
                "scores": np.allclose(gg.scores, pj["score_analytical"][order], atol=1e-6),
                "widths": np.allclose(gg.widths, opening, atol=1e-7),
                "approach": np.allclose(gg.rotation_matrices[:, :, 0], T[:, :3, 2], atol=1e-5),
                "closing": np.allclose(gg.rotation_matrices[:, :, 1], T[:, :3, 0], atol=1e-5),
                "tips": np.allclose(
                    gg.translations + gg.depths[:, None] * approach, tips, atol=2e-6
                ),
                "object_id": (gg.object_ids.astype(int) == cats[pj["object_id"][order]]).all(),
            }
            sg = SuctionGroup().from_npy(str(cam / "suction" / f"{v:04d}.npz"))
            S = su["contact_poses_relative_to_camera"].astype(np.float64)
            ss = su["score_analytical"].astype(np.float64) * su["score_wrench"]
            so = np.argsort(-ss, kind="stable")
            checks |= {
                "suction count": len(sg) == len(S),
                "suction scores": np.allclose(sg.scores(), ss[so], atol=1e-6),
                "suction directions": np.allclose(sg.directions(), -S[so, :3, 2], atol=1e-6),
                "suction points": np.allclose(sg.translations(), S[so, :3, 3] * CM, atol=1e-7),
                "suction object_id": (sg.object_ids() == cats[su["object_id"][so]]).all(),
            }
            rg = RectGraspGroup(str(cam / "rect" / f"{v:04d}.npy"))
            lines = (cam / "jacquard" / f"{v:04d}_grasps.txt").read_text().splitlines()
            checks |= {
                "rect count": len(rg) == len(lines),
                "rect centres": len(rg) == 0
                or np.allclose(
                    rg.center_points,
                    [[float(x) for x in ln.split(";")[:2]] for ln in lines],
                    atol=0.006,
                ),
            }
            bad += [f"{where}: {k}" for k, ok in checks.items() if not ok]
            totals["grasps"] += len(gg)
            totals["suction"] += len(sg)
            totals["rects"] += len(rg)
            if len(gg):
                pts = _scene_points(args.dataset / f"scene{n}" / f"{v}.npz", K)
                for name, arr in (("exported", gg.grasp_group_array),
                                  ("swapped", _swapped(gg.grasp_group_array))):  # fmt: skip
                    col, emp = collision_detection([arr], [arr[:, 13:16]], [None], [None], pts)
                    empty[name][0] += int((~emp[0]).sum())
                    empty[name][1] += int((~col[0]).sum())
                    empty[name][2] += len(arr)
    print(
        f"{totals['views']} views: {totals['grasps']} parallel-jaw grasps (GraspGroup), "
        f"{totals['suction']} suction grasps (SuctionGroup), {totals['rects']} rectangles "
        "(RectGraspGroup) read"
    )
    for name, (held, free, total) in empty.items():
        print(f"graspnetAPI collision_detection, {name} frames: of {total} grasps {held} hold "
              f"at least 10 scene points between the jaws, {free} of them with no scene point "
              "in the fingers or the palm")  # fmt: skip
    for line in bad:
        print("MISMATCH", line)
    print("ok" if not bad else f"{len(bad)} mismatches")
    return 1 if bad else 0


def _swapped(rows: np.ndarray) -> np.ndarray:
    """The rows with the first two rotation columns exchanged (and the third negated, to keep a
    rotation): the approach and the closing direction confused."""
    out = rows.copy()
    R = rows[:, 4:13].reshape(-1, 3, 3)
    out[:, 4:13] = np.stack([R[:, :, 1], R[:, :, 0], -R[:, :, 2]], axis=2).reshape(-1, 9)
    return out


if __name__ == "__main__":
    sys.exit(main())
