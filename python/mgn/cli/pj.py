"""``mgn pj``: parallel-jaw labels from the command line.

    mgn pj label PATH [PATH ...] [--gripper G.yaml] [--points N] [--seed S] [--no-physics]

PATH is an object folder (``textured.obj`` + ``textured.obj.hdf5``), an export root (its
``models/NNN`` folders are all labelled) or a mesh file (then ``--out`` names the HDF5 file to
write and ``--density`` gives the mass).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mgn.errors import InvalidArgumentError
from mgn.geometry.mesh import load_mesh, mass_properties
from mgn.hardware import ParallelJawGripper
from mgn.io.grasp_file import create_labels_file, write_pj_labels
from mgn.io.model_folder import object_folders, read_model_folder
from mgn.pj.labels import DEFAULT_STORED_GRASPS, label_object
from mgn.pj.physics import (
    CALIBRATED_STAIRCASE_CHECKS,
    CALIBRATION_TOLERANCE,
    ShakeOptions,
    ShakeScorer,
    search_options,
)
from mgn.viz.shake_trial import show_trial


def _physics_scorer(args: argparse.Namespace, gripper: ParallelJawGripper) -> ShakeScorer:
    """The Bullet shake-test scorer (every grasp, or at most ``--physics-grasps`` per object)."""

    return ShakeScorer(
        density=args.density,
        gripper=gripper,
        options=search_options(
            args.physics_grid,
            args.physics_search == "staircase",
            args.physics_calibration,
            args.physics_checks,
            args.num_threads,
        ),
        max_grasps=args.physics_grasps,
        calibration_grasps=args.physics_calibration,
        calibration_min_grasps=args.physics_calibration_min,
        calibration_tolerance=args.physics_tolerance,
    )


def _targets(paths: list[str], out: str | None) -> list[tuple[Path, Path, Path | None]]:
    """(mesh file, hdf5 file, model folder or None) for each PATH."""

    targets: list[tuple[Path, Path, Path | None]] = []
    for raw in paths:
        p = Path(raw)
        if p.is_dir() and (p / "textured.obj").is_file():
            targets.append((p / "textured.obj", p / "textured.obj.hdf5", p))
        elif p.is_dir() and (p / "models").is_dir():
            folders = object_folders(p)
            if not folders:
                raise InvalidArgumentError(f"no object folders under '{p / 'models'}'")
            targets.extend((f / "textured.obj", f / "textured.obj.hdf5", f) for f in folders)
        elif p.is_file():
            if out is None and len(paths) == 1:
                raise InvalidArgumentError(f"'{p}' is a mesh file: give --out LABELS.hdf5")
            if len(paths) != 1:
                raise InvalidArgumentError("--out works with a single mesh file")
            assert out is not None  # checked above
            targets.append((p, Path(out), None))
        else:
            raise FileNotFoundError(f"'{p}' is neither an object folder, an export root nor a mesh")
    return targets


def _cmd_label(args: argparse.Namespace) -> int:

    if args.grasps < 0:
        raise InvalidArgumentError(f"--grasps must be >= 0 (0 = all), got {args.grasps}")
    gripper = ParallelJawGripper.from_yaml(args.gripper) if args.gripper else ParallelJawGripper()
    physics = _physics_scorer(args, gripper) if args.physics else None
    for mesh_path, h5_path, folder in _targets(args.paths, args.out):
        mesh = load_mesh(mesh_path)
        density = args.density
        name = mesh_path.stem
        if folder is not None:
            meta = read_model_folder(folder).metadata
            density = float(meta.get("density_kg_m3", density))
            name = f"{folder.name} {meta.get('name', '')}"
        props = mass_properties(mesh, density)
        if physics is not None:
            physics.density = density
        labels = label_object(
            mesh,
            mass=props.mass,
            com=props.center_of_mass,
            gripper=gripper,
            num_points=args.points,
            seed=args.seed,
            num_threads=args.num_threads,
            progress=not args.quiet,
            physics=physics,
            max_grasps=args.grasps or None,
        )
        if folder is None and not h5_path.exists():
            create_labels_file(h5_path)
        write_pj_labels(h5_path, labels)
        good = int((labels.point_score >= 1.0).sum())
        print(
            f"{name}: {len(labels)} parallel-jaw grasps from {labels.num_points} points "
            f"({good} points with analytic score 1.0, {labels.num_colliding} colliding "
            f"approaches dropped) -> {h5_path}"
        )
    return 0


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``pj`` command group to the ``mgn`` subparsers."""
    pj = sub.add_parser("pj", help="parallel-jaw grasp labels")
    psub = pj.add_subparsers(dest="pj_command", metavar="ACTION", required=True)
    p = psub.add_parser(
        "label",
        help="label objects (writes grasps/paralleljaw/* of textured.obj.hdf5)",
        description=__doc__.replace("``", "").replace("::", ":"),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("paths", nargs="+", metavar="PATH", help="object folder, export root or mesh")
    p.add_argument("--gripper", metavar="YAML", help="gripper YAML (default: MetaGraspNet hand)")
    p.add_argument("--points", type=int, default=5000, help="contact points per object")
    p.add_argument(
        "--grasps",
        type=int,
        default=DEFAULT_STORED_GRASPS,
        metavar="N",
        help="grasps stored per object: an evenly strided subset of what the sampler finds "
        f"(default {DEFAULT_STORED_GRASPS}; 0 = all of them)",
    )
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--num-threads", type=int, default=0, help="0 = all cores")
    p.add_argument("--density", type=float, default=1000.0, help="kg/m^3 for a bare mesh file")
    p.add_argument("--out", metavar="HDF5", help="output file when PATH is a mesh file")
    p.add_argument(
        "--physics",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="run the physics (shake) score; --no-physics for the fast analytic path",
    )
    p.add_argument(
        "--physics-grasps",
        type=int,
        default=None,
        metavar="N",
        help="cap: at most N grasps per object get a physics score (evenly strided; the others "
        "keep NaN, counted in the metadata); default: every grasp",
    )
    p.add_argument(
        "--physics-search",
        choices=("staircase", "full"),
        default="staircase",
        help="staircase: walk the monotone success boundary, falling back to the full grid where "
        "a check fails (default); full: simulate every grid cell",
    )
    p.add_argument(
        "--physics-checks",
        type=int,
        default=None,
        metavar="N",
        help="staircase only: N extra inferred cells simulated to catch non-monotone grids "
        f"(default {CALIBRATED_STAIRCASE_CHECKS} with --physics-calibration > 0, which catches "
        f"such objects as a whole, else {ShakeOptions.staircase_checks}; more checks, closer to "
        "the full grid)",
    )
    p.add_argument(
        "--physics-calibration",
        type=int,
        default=ShakeScorer.calibration_grasps,
        metavar="N",
        help="staircase only: the first N grasps of each object are simulated on the full grid; "
        "the staircase searches replayed on them choose the cheapest one within "
        "--physics-tolerance for the object's other grasps, else the full grid (default "
        f"{ShakeScorer.calibration_grasps}; 0 = off)",
    )
    p.add_argument(
        "--physics-calibration-min",
        type=int,
        default=ShakeScorer.calibration_min_grasps,
        metavar="N",
        help="the calibration stops after N grasps when the plain staircase is within "
        "--physics-tolerance on them, else it goes on to --physics-calibration (default "
        f"{ShakeScorer.calibration_min_grasps}; 0 = one stage)",
    )
    p.add_argument(
        "--physics-tolerance",
        type=float,
        default=CALIBRATION_TOLERANCE,
        metavar="E",
        help="mean absolute score error a search may have on the calibration grasps (its 95 %% "
        f"bound; default {CALIBRATION_TOLERANCE}, the simulation's own noise band; 0 = exact)",
    )
    p.add_argument(
        "--physics-grid", type=int, default=5, help="S of the S x S friction x density grid"
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_label)

    register_show_trial(psub)


def _cmd_show_trial(args: argparse.Namespace) -> int:
    summary = show_trial(
        args.object,
        args.grasp,
        friction=args.friction,
        density_factor=args.density_factor,
        grip_force=args.grip_force,
        seed=args.seed,
        out=args.out,
        every=args.every,
        strip_frames=args.strip_frames,
        size=args.size,
    )
    print(json.dumps(summary))
    return 0


def register_show_trial(psub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``show-trial`` action (:func:`mgn.viz.shake_trial.show_trial`) to the ``mgn pj``
    subparsers ``psub``::

        mgn pj show-trial OBJECT [--grasp a a a v v v p p p w] [--friction F]
                                 [--density-factor D] [--out PREFIX] [--every N]
                                 [--strip-frames K] [--size PX]
    """
    p = psub.add_parser(
        "show-trial", help="render one physics shake trial to a GIF and a PNG strip"
    )
    p.add_argument("object", help="built-in object name or id, or a mesh file (metres)")
    p.add_argument(
        "--grasp",
        nargs=10,
        type=float,
        metavar="X",
        help="grasp row a(3) v(3) p1(3) w in metres (default: across the CoM from above)",
    )
    p.add_argument("--friction", type=float, default=1.0, help="friction coefficient")
    p.add_argument("--density-factor", type=float, default=1.0, help="mass factor")
    p.add_argument("--grip-force", type=float, default=20.0, help="N per finger")
    p.add_argument("--seed", type=int, default=0, help="seed of the rotation axis/angle")
    p.add_argument("--out", default="shake_trial", help="output prefix (PREFIX.gif, ...)")
    p.add_argument("--every", type=int, default=10, help="record every N simulation steps")
    p.add_argument("--strip-frames", type=int, default=8, help="frames in the PNG strip")
    p.add_argument("--size", type=int, default=320, help="frame size in pixels")
    p.set_defaults(func=_cmd_show_trial)
