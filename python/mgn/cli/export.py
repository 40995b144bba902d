"""``mgn export``: a dataset in another layout (``mgn export bop DS OUT``: the BOP layout;
``mgn export graspnet DS OUT``: grasp files for graspnetAPI, suctionnetAPI and planar grasp
detectors)."""

from __future__ import annotations

import argparse

from mgn.errors import InvalidArgumentError
from mgn.io.bop import DEFAULT_DEPTH_SCALE_MM, DEFAULT_SPLIT, export_bop
from mgn.io.graspnet import (
    DEFAULT_CAMERA,
    DEFAULT_MAX_TILT_DEG,
    DEFAULT_PJ_SCORE,
    DEFAULT_SUCTION_SCORE,
    PJ_SCORES,
    SUCTION_SCORES,
    export_graspnet,
)

__all__ = ["register"]


def _scene_ids(text: str | None) -> list[int] | None:
    if not text:
        return None
    try:
        return [int(s) for s in text.split(",") if s.strip()]
    except ValueError:
        raise InvalidArgumentError(
            f"--scenes {text!r}: expected comma-separated scene ids, e.g. 0,2,5"
        ) from None


def _cmd_bop(args: argparse.Namespace) -> int:
    result = export_bop(
        args.dir,
        args.out,
        scenes=_scene_ids(args.scenes),
        split=args.split,
        depth_scale=args.depth_scale,
    )
    print(
        f"wrote {result.root}: {len(result.written)} scene(s) written, "
        f"{len(result.skipped)} already there"
    )
    return 0


def _cmd_graspnet(args: argparse.Namespace) -> int:
    result = export_graspnet(
        args.dir,
        args.out,
        scenes=_scene_ids(args.scenes),
        camera=args.camera,
        pj_score=args.pj_score,
        suction_score=args.suction_score,
        max_tilt_deg=args.max_tilt,
    )
    c = result.counts
    print(
        f"wrote {result.root}: {len(result.written)} scene(s) written, "
        f"{len(result.skipped)} already there; {c['grasp']} parallel-jaw grasps, "
        f"{c['suction']} suction grasps, {c['rect']} rectangles"
        + (
            f"; left out for a NaN score: {c['grasp_unscored']} parallel-jaw, "
            f"{c['suction_unscored']} suction"
            if c["grasp_unscored"] or c["suction_unscored"]
            else ""
        )
    )
    return 0


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``export`` (with ``export bop`` and ``export graspnet``) to the ``mgn`` subcommands."""
    export = sub.add_parser("export", help="write a dataset in another layout (BOP, GraspNet)")
    esub = export.add_subparsers(dest="export_cmd", required=True)
    p = esub.add_parser(
        "bop",
        help="the BOP layout: models in mm, per scene rgb, depth, masks, scene_gt*.json "
        "(docs/format.md, 'BOP export'); scenes already in OUT are skipped",
    )
    p.add_argument("dir", help="mgn dataset folder")
    p.add_argument("out", help="BOP output folder (created)")
    p.add_argument("--scenes", help="comma-separated scene ids (default: all)")
    p.add_argument("--split", default=DEFAULT_SPLIT, help="split folder name")
    p.add_argument(
        "--depth-scale",
        type=float,
        default=DEFAULT_DEPTH_SCALE_MM,
        help="mm per unit of the 16-bit depth PNGs",
    )
    p.set_defaults(func=_cmd_bop)

    p = esub.add_parser(
        "graspnet",
        help="grasp files per view, camera frame: graspnetAPI GraspGroup and RectGraspGroup "
        "arrays, suctionnetAPI SuctionGroup arrays, Jacquard grasp rectangles "
        "(docs/format.md, 'GraspNet export'); scenes already in OUT are skipped",
    )
    p.add_argument("dir", help="mgn dataset folder")
    p.add_argument("out", help="output folder (created)")
    p.add_argument("--scenes", help="comma-separated scene ids (default: all)")
    p.add_argument(
        "--camera", default=DEFAULT_CAMERA, help=f"camera folder name (default {DEFAULT_CAMERA})"
    )
    p.add_argument(
        "--pj-score",
        choices=PJ_SCORES,
        default=DEFAULT_PJ_SCORE,
        help="parallel-jaw score written (default %(default)s)",
    )
    p.add_argument(
        "--suction-score",
        choices=SUCTION_SCORES,
        default=DEFAULT_SUCTION_SCORE,
        help="suction score written: seal, wrench or their product (default %(default)s)",
    )
    p.add_argument(
        "--max-tilt",
        type=float,
        default=DEFAULT_MAX_TILT_DEG,
        help="largest angle between a grasp's approach and the optical axis for a "
        "2-D rectangle, degrees (default %(default)s)",
    )
    p.set_defaults(func=_cmd_graspnet)
