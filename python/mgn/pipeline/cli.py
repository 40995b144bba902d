"""``mgn generate`` and ``mgn config``::

mgn generate --out DIR [--scenes N] [--config cfg.yaml] [--objects NAME ...] [--seed S]
             [--workers K] [--resume] [--scheduler tcp://host:8786] [--quiet] [--no-cache]
mgn config dump [--out cfg.yaml]     the default configuration (every key, MGN values)
mgn config check cfg.yaml            validate a configuration file
"""

from __future__ import annotations

import argparse
import sys

__all__ = ["register"]


def _cmd_generate(args: argparse.Namespace) -> int:
    from mgn.pipeline.runner import generate

    report = generate(
        args.out,
        args.scenes,
        config=args.config,
        seed=args.seed,
        objects=args.objects,
        workers=args.workers,
        resume=args.resume,
        scheduler=args.scheduler,
        progress=not args.quiet,
        use_cache=not args.no_cache,
    )
    print(report.format_summary())
    return 0 if report.complete else 1


def _cmd_config_dump(args: argparse.Namespace) -> int:
    from mgn.config import dump_config

    text = dump_config()
    if args.out:
        from mgn.io.atomic import atomic_write_text

        atomic_write_text(args.out, text)
        print(f"default configuration written to {args.out}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0


def _cmd_config_check(args: argparse.Namespace) -> int:
    from mgn.config import load_config

    config = load_config(args.file)
    views = len(config.camera.view_indices)
    print(f"{args.file}: valid ({config.camera.rig} rig, {views} views per scene)")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``generate`` and the ``config`` command group to the ``mgn`` subparsers."""
    p = sub.add_parser(
        "generate",
        help="generate a dataset (resumable; local processes or a Dask cluster)",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--scenes", type=int, default=3, metavar="N", help="scenes (default 3)")
    p.add_argument("--out", required=True, metavar="DIR", help="dataset folder")
    p.add_argument("--config", metavar="YAML", help="configuration (default: MGN defaults)")
    p.add_argument(
        "--objects", nargs="+", metavar="NAME", help="these objects in every scene (names or ids)"
    )
    p.add_argument("--seed", type=int, default=0, help="dataset seed (default 0)")
    p.add_argument("--workers", type=int, default=1, help="local worker processes (default 1)")
    p.add_argument("--resume", action="store_true", help="keep complete scenes, redo the others")
    p.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler, e.g. tcp://host:8786")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.add_argument("--no-cache", action="store_true", help="do not read/write the label cache")
    p.set_defaults(func=_cmd_generate)

    c = sub.add_parser("config", help="the dataset configuration (YAML)")
    csub = c.add_subparsers(dest="config_command", metavar="ACTION", required=True)
    p = csub.add_parser("dump", help="print the default configuration")
    p.add_argument("--out", metavar="YAML", help="write it to this file instead")
    p.set_defaults(func=_cmd_config_dump)
    p = csub.add_parser("check", help="validate a configuration file")
    p.add_argument("file", help="configuration YAML")
    p.set_defaults(func=_cmd_config_check)
