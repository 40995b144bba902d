"""``mgn generate`` and ``mgn config``::

mgn generate --out DIR [--scenes N] [--config cfg.yaml] [--objects NAME ...] [--seed S]
             [--workers K] [--resume] [--scheduler tcp://host:8786] [--quiet] [--no-cache]
             [--split all|train|test] [--difficulty-quota 1=20,2=20,3=20,4=20,5=20
             [--max-scenes M] [--batch-scenes B] [--prune-rejected]]

Test sets (docs/testsets.md): --split train leaves the unseen categories (config split.unseen,
default: the objects tagged 'novel') out of every scene; --split test puts at least one in every
scene. --difficulty-quota generates scenes in batches until exactly that many views of each
difficulty level are selected (recorded in dataset.json), at most --max-scenes scenes.
mgn config dump [--out cfg.yaml]     the default configuration (every key, MGN values)
mgn config check cfg.yaml            validate a configuration file
"""

from __future__ import annotations

import argparse
import sys

__all__ = ["register"]


def _config_with_overrides(args: argparse.Namespace):  # noqa: ANN202 (mgn.config.Config)
    """The config of ``--config`` with the test-set options applied."""
    import dataclasses

    from mgn.config import load_config
    from mgn.pipeline.testset import parse_quota

    cfg = load_config(args.config)
    if args.split is not None:
        cfg = dataclasses.replace(cfg, split=dataclasses.replace(cfg.split, name=args.split))
    sel = {}
    if args.difficulty_quota is not None:
        quota = parse_quota(args.difficulty_quota)
        sel["quota"] = {str(k + 1): n for k, n in enumerate(quota)}
    if args.max_scenes is not None:
        sel["max_scenes"] = args.max_scenes
    if args.batch_scenes is not None:
        sel["batch_scenes"] = args.batch_scenes
    if args.prune_rejected:
        sel["prune_rejected"] = True
    from mgn.render.photo import settings_from_args

    cfg = dataclasses.replace(cfg, render=settings_from_args(cfg.render, args))
    if sel:
        from mgn.config import SelectionConfig

        merged = {**cfg.selection.to_dict(), **sel}
        cfg = dataclasses.replace(cfg, selection=SelectionConfig.from_dict(merged, "selection"))
    return cfg


def _cmd_generate(args: argparse.Namespace) -> int:
    from mgn.pipeline.runner import generate

    cfg = _config_with_overrides(args)
    scenes = args.scenes
    if scenes is None and cfg.selection.quota is None:
        scenes = 3
    report = generate(
        args.out,
        scenes,
        config=cfg,
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
    p.add_argument(
        "--scenes", type=int, metavar="N", help="scenes (default 3; not with a difficulty quota)"
    )
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
    p.add_argument(
        "--split",
        choices=("all", "train", "test"),
        help="unseen-object split: train = without the unseen categories, test = with them "
        "(config key split; default all)",
    )
    p.add_argument(
        "--difficulty-quota",
        metavar="L=N,...",
        help="views per difficulty level, e.g. 1=20,2=20,3=20,4=20,5=20 (config selection.quota)",
    )
    p.add_argument(
        "--max-scenes", type=int, metavar="M", help="give up after M scenes (default 100)"
    )
    p.add_argument("--batch-scenes", type=int, metavar="B", help="scenes per batch (default 4)")
    p.add_argument(
        "--prune-rejected", action="store_true", help="delete the files of the views not selected"
    )
    from mgn.render.photo import add_engine_arguments

    add_engine_arguments(p)
    p.set_defaults(func=_cmd_generate)

    c = sub.add_parser("config", help="the dataset configuration (YAML)")
    csub = c.add_subparsers(dest="config_command", metavar="ACTION", required=True)
    p = csub.add_parser("dump", help="print the default configuration")
    p.add_argument("--out", metavar="YAML", help="write it to this file instead")
    p.set_defaults(func=_cmd_config_dump)
    p = csub.add_parser("check", help="validate a configuration file")
    p.add_argument("file", help="configuration YAML")
    p.set_defaults(func=_cmd_config_check)
