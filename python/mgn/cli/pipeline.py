"""``mgn generate`` and ``mgn config``::

mgn generate --out DIR [--scenes N] [--config cfg.yaml] [--objects NAME ...] [--seed S]
             [--add my_objects.yaml] [--categories NAME ...]
             [--workers K] [--resume] [--scheduler tcp://host:8786 [--collect]] [--quiet]
             [--no-cache]
             [--split all|train|test] [--difficulty-quota 1=20,2=20,3=20,4=20,5=20
             [--max-scenes M] [--batch-scenes B] [--prune-rejected]]

Test sets (docs/testsets.md): --split train leaves the unseen categories (config split.unseen,
default: the objects tagged 'novel') out of every scene; --split test puts at least one in every
scene. --difficulty-quota generates scenes in batches until exactly that many views of each
difficulty level are selected (recorded in dataset.json), at most --max-scenes scenes.
mgn config dump [--out cfg.yaml]     the default configuration (every key, MGN values)
mgn config check cfg.yaml [--add YAML]   validate a configuration file (exit 1 when it fails
                                     every scene: unknown objects, a camera facing away, ...)
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import warnings
from pathlib import Path
from typing import Any

from mgn.base.atomic import atomic_write_text
from mgn.cli.args import add_engine_arguments, engine_settings, split_list
from mgn.errors import InvalidArgumentError
from mgn.geometry.convex import cache_dir
from mgn.io.stats import dataset_stats, format_stats
from mgn.pipeline.config import Config, SelectionConfig, dump_config, load_config
from mgn.pipeline.label_cache import label_cache_dir
from mgn.pipeline.runner import generate
from mgn.pipeline.sanity import config_errors, config_warnings, load_catalogue
from mgn.pipeline.testset import parse_quota

__all__ = ["register"]


def _config_with_overrides(args: argparse.Namespace) -> Config:
    """The config of ``--config`` with the test-set options applied."""

    cfg = load_config(args.config)
    if args.objects:
        cfg = dataclasses.replace(
            cfg,
            objects=dataclasses.replace(
                cfg.objects, names=tuple(args.objects), count=None, categories=None
            ),
        )
    if args.add:
        added = tuple(os.path.abspath(a) for a in args.add)
        cfg = dataclasses.replace(
            cfg,
            objects=dataclasses.replace(cfg.objects, user_objects=cfg.objects.user_objects + added),
        )
    if args.categories:
        if args.objects:
            raise InvalidArgumentError("mgn generate: give --objects or --categories, not both")
        cfg = dataclasses.replace(
            cfg,
            objects=dataclasses.replace(cfg.objects, names=None, categories=tuple(args.categories)),
        )
    if args.split is not None:
        cfg = dataclasses.replace(cfg, split=dataclasses.replace(cfg.split, name=args.split))
    sel: dict[str, Any] = {}
    if args.difficulty_quota is not None:
        quota = parse_quota(args.difficulty_quota)
        sel["quota"] = {str(k + 1): n for k, n in enumerate(quota)}
    if args.max_scenes is not None:
        sel["max_scenes"] = args.max_scenes
    if args.batch_scenes is not None:
        sel["batch_scenes"] = args.batch_scenes
    if args.prune_rejected:
        sel["prune_rejected"] = True

    cfg = dataclasses.replace(cfg, render=engine_settings(cfg.render, args))
    if sel:
        merged = {**cfg.selection.to_dict(), **sel}
        cfg = dataclasses.replace(cfg, selection=SelectionConfig.from_dict(merged, "selection"))
    return cfg


def _warn(text: str, shown: set[str]) -> None:
    """Print ``mgn: warning: text`` on stderr unless it was printed already."""
    if text not in shown:
        shown.add(text)
        print(f"mgn: warning: {text}", file=sys.stderr)


def _cmd_generate(args: argparse.Namespace) -> int:

    args.objects, args.categories = split_list(args.objects), split_list(args.categories)
    cfg = _config_with_overrides(args)  # --objects, --add, --categories, ... applied
    shown: set[str] = set()
    for w in config_warnings(cfg, load_catalogue(cfg)):
        _warn(w, shown)
    scenes = args.scenes
    if scenes is None and cfg.selection.quota is None:
        scenes = 3
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        try:
            report = generate(
                args.out,
                scenes,
                config=cfg,
                seed=args.seed,
                workers=args.workers,
                resume=args.resume,
                scheduler=args.scheduler,
                progress=not args.quiet,
                use_cache=not args.no_cache,
                collect=args.collect,
            )
        finally:
            for caught_w in caught:
                _warn(str(caught_w.message), shown)
    print(report.format_summary())
    if args.profile:
        atomic_write_text(args.profile, json.dumps(report.profile(), indent=2) + "\n")
        print(f"time profile written to {args.profile}", file=sys.stderr)
    return 0 if report.complete else 1


def _cmd_config_dump(args: argparse.Namespace) -> int:

    text = dump_config()
    if args.out:
        atomic_write_text(args.out, text)
        print(f"default configuration written to {args.out}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0


def _cmd_config_check(args: argparse.Namespace) -> int:

    config = load_config(args.file)
    if args.add:  # as mgn generate --add: user objects join the catalogue
        added = tuple(os.path.abspath(a) for a in args.add)
        config = dataclasses.replace(
            config,
            objects=dataclasses.replace(
                config.objects, user_objects=config.objects.user_objects + added
            ),
        )
    views = len(config.camera.view_indices)
    catalogue = load_catalogue(config)
    errors = config_errors(config, catalogue)
    found = config_warnings(config, catalogue)
    for e in errors:
        print(f"mgn: error: {e}", file=sys.stderr)
    for w in found:
        print(f"mgn: warning: {w}", file=sys.stderr)
    extra = f"; {len(found)} warning(s)" if found else ""
    if errors:
        print(f"{args.file}: INVALID: {len(errors)} setting(s) fail every scene (above){extra}")
        return 1
    per_scene = config.objects.count_range
    objs = ""
    if per_scene is not None:
        lo, hi = per_scene
        objs = f", {lo} objects per scene" if lo == hi else f", {lo}-{hi} objects per scene"
    print(f"{args.file}: valid ({config.camera.rig} rig, {views} views per scene{objs}{extra})")
    return 0


def _cache_entries() -> dict[str, list[Path]]:
    """Cache files by kind: suction labels, parallel-jaw labels, convex decompositions."""

    labels, convex = label_cache_dir(), cache_dir()
    files = {
        "suction labels": sorted(labels.glob("suction-*")) if labels.is_dir() else [],
        "parallel-jaw labels": sorted(labels.glob("pj-*")) if labels.is_dir() else [],
        "convex decompositions": sorted(p for p in convex.rglob("*") if p.is_file())
        if convex.is_dir()
        else [],
    }
    return files


def _cmd_cache_list(args: argparse.Namespace) -> int:

    files = _cache_entries()
    rows = {
        k: {"entries": len(v), "bytes": sum(p.stat().st_size for p in v)} for k, v in files.items()
    }
    if args.json:
        doc = {"label_dir": str(label_cache_dir()), "convex_dir": str(cache_dir()), **rows}
        print(json.dumps(doc, indent=2))
        return 0
    print(f"object-label cache: {label_cache_dir()}  (MGN_CACHE_DIR moves it)")
    print(f"convex-decomposition cache: {cache_dir()}")
    for k, r in rows.items():
        print(f"  {k:<22} {r['entries']:>6} entries  {r['bytes'] / 2**20:8.1f} MiB")
    return 0


def _cmd_cache_clear(args: argparse.Namespace) -> int:
    files = _cache_entries()
    kinds = ["suction labels", "parallel-jaw labels"] if args.labels_only else list(files)
    n = size = 0
    for k in kinds:
        for p in files[k]:
            size += p.stat().st_size
            p.unlink(missing_ok=True)
            n += 1
    print(f"removed {n} cache entries ({size / 2**20:.1f} MiB): {', '.join(kinds)}")
    return 0


def _cmd_stats(args: argparse.Namespace) -> int:

    st = dataset_stats(args.dir, max_views=args.max_views)
    print(json.dumps(st, indent=2) if args.json else format_stats(st))
    return 0


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``generate`` and the ``config`` command group to the ``mgn`` subparsers."""
    p = sub.add_parser(
        "generate",
        help="generate a dataset (resumable; local processes or a Dask cluster)",
        description=__doc__.replace("``", "").replace("::", ":"),
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
    p.add_argument(
        "--categories",
        nargs="+",
        metavar="NAME",
        help="draw the scenes from these objects, 2-5 copies each (config objects.categories)",
    )
    p.add_argument(
        "--add",
        action="append",
        metavar="YAML",
        help="user objects of this YAML file join the catalogue (repeatable; config "
        "objects.user_objects; write one with `mgn objects add`)",
    )
    p.add_argument("--seed", type=int, default=0, help="dataset seed (default 0)")
    p.add_argument("--workers", type=int, default=1, help="local worker processes (default 1)")
    p.add_argument("--resume", action="store_true", help="keep complete scenes, redo the others")
    p.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler, e.g. tcp://host:8786")
    p.add_argument(
        "--collect",
        action="store_true",
        help="workers send each scene's files back and this process writes them (cluster "
        "workers without the output folder on a shared disk; docs/cluster.md)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.add_argument("--no-cache", action="store_true", help="do not read/write the label cache")
    p.add_argument(
        "--profile",
        metavar="JSON",
        help="also write where the time went (object labels per object, scene parts: drop, "
        "render, labels, layout, scene grasps, write) to this JSON file",
    )
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

    add_engine_arguments(p)
    p.set_defaults(func=_cmd_generate)

    c = sub.add_parser("config", help="the dataset configuration (YAML)")
    csub = c.add_subparsers(dest="config_command", metavar="ACTION", required=True)
    p = csub.add_parser("dump", help="print the default configuration")
    p.add_argument("--out", metavar="YAML", help="write it to this file instead")
    p.set_defaults(func=_cmd_config_dump)
    p = sub.add_parser("stats", help="what a dataset holds: objects, views, labels, histograms")
    p.add_argument("dir", help="dataset folder")
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.add_argument("--max-views", type=int, metavar="N", help="read at most N views (default all)")
    p.set_defaults(func=_cmd_stats)

    k = sub.add_parser("cache", help="the object-label and convex-decomposition caches")
    ksub = k.add_subparsers(dest="cache_command", metavar="ACTION", required=True)
    p = ksub.add_parser("list", help="where the caches are, entries and size")
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.set_defaults(func=_cmd_cache_list)
    p = ksub.add_parser("clear", help="delete the cached entries (recomputed when needed)")
    p.add_argument(
        "--labels-only",
        action="store_true",
        help="keep the convex decompositions (default: clear both)",
    )
    p.set_defaults(func=_cmd_cache_clear)

    p = csub.add_parser(
        "check",
        help="validate a configuration file: its keys and values, then what would fail or empty "
        "every scene (exit 1) and what would give a degenerate dataset (warnings)",
    )
    p.add_argument("file", help="configuration YAML")
    p.add_argument(
        "--add",
        action="append",
        metavar="YAML",
        help="user objects of this YAML file, as mgn generate --add (repeatable)",
    )
    p.set_defaults(func=_cmd_config_check)
