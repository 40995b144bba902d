"""Bit-identity check of the Bullet physics (drop and shake test) across a code change.

Runs fixed-seed drops, a settle and shake tests with several option sets and stores every
output array; ``--compare`` reports which arrays differ (bytes) between two such files and by how
much. Used when the Bullet adapter moved into cpp/src/physics: write a file on the old build,
one on the new build, compare.

    python scripts/physics_identity.py write before.npz
    python scripts/physics_identity.py compare before.npz after.npz
"""

from __future__ import annotations

import argparse
import sys

import numpy as np


def _drop_cases(out: dict[str, np.ndarray]) -> None:
    from mgn.objects import ToteSpec, builtin_objects
    from mgn.scene import drop_scene
    from mgn.scene.drop import _simulate
    from mgn.scene.scene import DropOptions

    lib = builtin_objects()
    specs = [lib[k % len(lib)] for k in (0, 3, 5, 7, 9, 11, 2, 4)]
    options = {
        "default": DropOptions(),
        "gjk": DropOptions(polyhedral_contacts=False),
        "allverts": DropOptions(max_hull_vertices=0, max_time=3.0),
    }
    for name, opt in options.items():
        for seed in (0, 1):
            raw, *_ = _simulate(specs, seed, ToteSpec(), opt, None, None, True)
            for key in ("X_WO", "X_WO_release", "status", "settled", "contacts"):
                out[f"drop/{name}/{seed}/{key}"] = np.asarray(getattr(raw, key))
            for key in ("steps", "max_penetration"):
                out[f"drop/{name}/{seed}/{key}"] = np.asarray(getattr(raw, key))
    scene = drop_scene(specs[:5], seed=3)
    X = np.array([i.X_WO for i in scene.instances])
    raw, *_ = _simulate(
        [next(s for s in specs if s.name == i.name) for i in scene.instances],
        0,
        ToteSpec(),
        DropOptions(),
        None,
        None,
        True,
        X,
    )
    out["settle/X_WO"] = np.asarray(raw.X_WO)
    out["settle/steps"] = np.asarray(raw.steps)


def _shake_cases(out: dict[str, np.ndarray]) -> None:
    import mgn
    from mgn.pj.physics import ShakeOptions, shake_scores

    box = mgn.make_box([0.04, 0.05, 0.06])
    ball = mgn.make_sphere(0.03, 32, 16)
    rows = []
    for i in range(4):
        dz = 0.006 * (i - 1.5)
        rows.append([0, 0, -1, 1, 0, 0, -0.02, 0.0, dz, 0.04])
    box_grasps = np.asarray(rows)
    ball_grasps = box_grasps.copy()
    ball_grasps[:, 6] = -0.03
    ball_grasps[:, 9] = 0.06
    for poly in (False, True):
        for name, mesh, grasps, density in (
            ("box", box, box_grasps, 2000.0),
            ("ball", ball, ball_grasps, 600.0),
        ):
            mp = mgn.mass_properties(mesh, density)
            o = ShakeOptions(grid=4, polyhedral_contacts=poly, num_threads=2, seed=5)
            r = shake_scores(mesh, mp.mass, mp.center_of_mass, mp.inertia, grasps, None, o)
            for key in ("score", "trial_success", "trial_ended_early", "trial_steps"):
                out[f"shake/{name}/{poly}/{key}"] = np.asarray(getattr(r, key))
            t = mgn.pj.physics.shake_trajectory(
                mesh, mp.mass, mp.center_of_mass, mp.inertia, grasps[0], 1.0, 0.5, None, o
            )
            out[f"traj/{name}/{poly}/X_WO"] = t.X_WO
            out[f"traj/{name}/{poly}/finger_left"] = t.finger_left


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    w = sub.add_parser("write")
    w.add_argument("path")
    w.add_argument("--only", choices=("drop", "shake"), default=None)
    c = sub.add_parser("compare")
    c.add_argument("a")
    c.add_argument("b")
    args = ap.parse_args(argv)
    if args.cmd == "write":
        out: dict[str, np.ndarray] = {}
        if args.only in (None, "drop"):
            _drop_cases(out)
        if args.only in (None, "shake"):
            _shake_cases(out)
        np.savez(args.path, **out)
        print(f"wrote {len(out)} arrays to {args.path}")
        return 0
    a, b = np.load(args.a), np.load(args.b)
    bad = 0
    for key in sorted(set(a.files) | set(b.files)):
        if key not in a.files or key not in b.files:
            print(f"{key}: only in one file")
            bad += 1
            continue
        x, y = a[key], b[key]
        if x.shape == y.shape and x.dtype == y.dtype and x.tobytes() == y.tobytes():
            continue
        bad += 1
        diff = (
            float(np.max(np.abs(x.astype(np.float64) - y.astype(np.float64))))
            if x.shape == y.shape
            else float("nan")
        )
        print(f"{key}: differs (max abs difference {diff:.3g})")
    print(f"{len(a.files) - bad} of {len(a.files)} arrays bit-identical")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
