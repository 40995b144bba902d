"""``mgn validate DIR`` and ``mgn coco DIR -o annotations.json``: check and export a dataset."""

from __future__ import annotations

import argparse
import sys

__all__ = ["register"]


def _cmd_validate(args: argparse.Namespace) -> int:
    from mgn.io.validate import validate_dataset

    problems = validate_dataset(args.dir)
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
    from mgn.io.coco import export_coco

    scenes = None
    if args.scenes:
        scenes = [int(s) for s in args.scenes.split(",") if s.strip()]
    path = export_coco(args.dir, args.out, scenes=scenes, class_agnostic=args.class_agnostic)
    print(f"wrote {path}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``validate`` and ``coco`` to the ``mgn`` subcommands."""
    p = sub.add_parser("validate", help="check every file of a dataset against FORMAT.md")
    p.add_argument("dir", help="dataset folder")
    p.add_argument("--max-problems", type=int, default=50, help="problems printed (default 50)")
    p.set_defaults(func=_cmd_validate)

    p = sub.add_parser("coco", help="export a dataset's annotations in COCO format")
    p.add_argument("dir", help="dataset folder")
    p.add_argument("-o", "--out", required=True, help="output annotations.json")
    p.add_argument("--scenes", help="comma-separated scene ids (default: all)")
    p.add_argument("--class-agnostic", action="store_true", help="one category 'object'")
    p.set_defaults(func=_cmd_coco)
