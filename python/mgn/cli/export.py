"""``mgn export``: a dataset in another layout (``mgn export bop DS OUT``: the BOP layout)."""

from __future__ import annotations

import argparse

from mgn.errors import InvalidArgumentError
from mgn.io.bop import DEFAULT_DEPTH_SCALE_MM, DEFAULT_SPLIT, export_bop

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


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``export`` (with ``export bop``) to the ``mgn`` subcommands."""
    export = sub.add_parser("export", help="write a dataset in another layout (BOP)")
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
    p.add_argument("--depth-scale", type=float, default=DEFAULT_DEPTH_SCALE_MM,
                   help="mm per unit of the 16-bit depth PNGs")  # fmt: skip
    p.set_defaults(func=_cmd_bop)
