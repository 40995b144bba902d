"""Commands on a written dataset: ``mgn validate``, ``mgn coco``, ``mgn show``, ``mgn report``."""

from __future__ import annotations

import argparse
import sys

from mgn.io.bop import validate_bop
from mgn.io.coco import export_coco
from mgn.io.graspnet import DEFAULT_MAX_TILT_DEG
from mgn.io.validate import validate_dataset
from mgn.viz.overlay import show
from mgn.viz.report import write_report

__all__ = ["register"]


def _cmd_validate(args: argparse.Namespace) -> int:

    problems = validate_bop(args.dir) if args.format == "bop" else validate_dataset(args.dir)
    for p in problems[: args.max_problems]:
        print(p)
    if len(problems) > args.max_problems:
        print(f"... and {len(problems) - args.max_problems} more")
    if problems:
        print(f"{args.dir}: {len(problems)} problem(s)", file=sys.stderr)
        return 1
    print(f"{args.dir}: valid")
    return 0


def _cmd_coco(args: argparse.Namespace) -> int:

    scenes = None
    if args.scenes:
        scenes = [int(s) for s in args.scenes.split(",") if s.strip()]
    path = export_coco(args.dir, args.out, scenes=scenes, class_agnostic=args.class_agnostic)
    print(f"wrote {path}")
    return 0


def _cmd_show(args: argparse.Namespace) -> int:
    path = show(
        args.dir,
        args.scene,
        args.view,
        args.out,
        grasps=args.grasps,
        layout=args.layout,
        keypoints=not args.no_keypoints,
        alpha=args.alpha,
        panels=args.panels,
        max_tilt_deg=args.max_tilt,
    )
    print(f"wrote {path}")
    return 0


def _cmd_report(args: argparse.Namespace) -> int:
    path = write_report(
        args.dir, args.out, samples=args.samples, max_views=args.max_views, progress=not args.quiet
    )
    print(f"wrote {path}")
    return 0


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``validate`` and ``coco`` to the ``mgn`` subcommands."""
    p = sub.add_parser("validate", help="check every file of a dataset against docs/format.md")
    p.add_argument("dir", help="dataset folder")
    p.add_argument(
        "--format",
        choices=("mgn", "bop"),
        default="mgn",
        help="mgn: an mgn dataset; bop: a BOP folder (mgn export bop)",
    )
    p.add_argument("--max-problems", type=int, default=50, help="problems printed (default 50)")
    p.set_defaults(func=_cmd_validate)

    p = sub.add_parser("coco", help="export a dataset's annotations in COCO format")
    p.add_argument("dir", help="dataset folder")
    p.add_argument("-o", "--out", required=True, help="output annotations.json")
    p.add_argument("--scenes", help="comma-separated scene ids (default: all)")
    p.add_argument("--class-agnostic", action="store_true", help="one category 'object'")
    p.set_defaults(func=_cmd_coco)

    p = sub.add_parser("show", help="draw one view's labels on its RGB image (PNG, with a legend)")
    p.add_argument("dir", help="dataset folder, or one scene folder (mgn scene label --out)")
    p.add_argument("--scene", type=int, help="scene id N of scene<N> (needed for a dataset)")
    p.add_argument("--view", type=int, default=0, help="view index (default 0)")
    p.add_argument(
        "--grasps",
        metavar="KIND",
        help="draw scene grasps: suction or paralleljaw (aliases: suctioncup, pj), or "
        "rectangles (2-D grasp rectangles of the parallel-jaw grasps seen along their approach)",
    )
    p.add_argument(
        "--max-tilt",
        type=float,
        default=DEFAULT_MAX_TILT_DEG,
        help="with --grasps rectangles: largest angle between a grasp's approach and "
        "the optical axis, degrees (default %(default)s)",
    )
    p.add_argument("--layout", action="store_true", help="draw the relation graph and layers")
    p.add_argument("--no-keypoints", action="store_true", help="do not draw keypoints")
    p.add_argument(
        "--alpha",
        type=float,
        default=0.45,
        help="mask tint over the RGB, 0..1 (default 0.45; 0 = outlines only)",
    )
    p.add_argument(
        "--panels", action="store_true", help="add amodal-mask and depth panels beside the overlay"
    )
    p.add_argument("-o", "--out", required=True, help="output PNG")
    p.set_defaults(func=_cmd_show)

    p = sub.add_parser("report", help="an HTML page of sample views and label statistics")
    p.add_argument("dir", help="dataset folder")
    p.add_argument("-o", "--out", required=True, help="output HTML file")
    p.add_argument("--samples", type=int, default=6, help="sample views shown (default 6)")
    p.add_argument(
        "--max-views", type=int, default=400, help="views used for the statistics (default 400)"
    )
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    p.set_defaults(func=_cmd_report)
