"""``mgn pick``: closed-loop picking in simulation (:func:`mgn.eval.pick.run_picking`)."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from mgn.cli.args import add_engine_arguments, engine_settings, grasp_kind_arg
from mgn.eval.pick import run_picking
from mgn.io.dataset_record import read_dataset_record
from mgn.io.scene_json import read_scene_json
from mgn.pipeline.config import Config, default_config, load_config
from mgn.scene.scene import Scene

__all__ = ["register"]


def _load_scene(path: Path) -> tuple[Scene, Config | None]:
    """The scene of a scene folder (its scene.json; the dataset's config from the parent's
    dataset.json when there is one) or of a scene.json file."""

    file = path / "scene.json" if path.is_dir() else path
    scene = read_scene_json(file)
    doc = read_dataset_record(file.parent.parent)
    config = None
    if doc is not None and isinstance(doc.get("config"), dict):
        config = load_config(doc["config"])
    return scene, config


def _cmd_pick(args: argparse.Namespace) -> int:

    scene, config = _load_scene(Path(args.scene))
    if args.config is not None:
        config = load_config(args.config)
    if args.engine is not None or args.spp is not None:
        config = config or default_config()
        config = dataclasses.replace(config, render=engine_settings(config.render, args))
    results = run_picking(
        scene,
        policy=args.policy,
        gripper=args.gripper,
        config=config,
        max_failures_per_object=args.max_failures,
        max_attempts=args.max_attempts,
        seed=args.seed,
        stochastic=args.stochastic,
        resolution=args.resolution,
        out=args.out,
        num_threads=args.threads,
    )
    print(results.table())
    print(f"results, step images and picking.gif in {args.out}")
    return 0


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``mgn pick`` to the ``mgn`` subparsers."""
    p = sub.add_parser(
        "pick",
        help="closed-loop picking in simulation (R_grasp, R_object, R_mixture, disturbance)",
    )
    p.add_argument("scene", help="a scene folder of a dataset (scene<N>/) or a scene.json")
    p.add_argument(
        "--policy",
        default="label",
        help="'label', 'random' or 'module:function' (policy(state) -> "
        "(instance_id, grasp index or X_W_tool) or None)",
    )

    p.add_argument(
        "--gripper",
        type=grasp_kind_arg,
        default="suction",
        help="suction or paralleljaw (default suction; aliases suctioncup, pj)",
    )
    p.add_argument(
        "--config",
        default=None,
        help="config YAML (object labels, gripper, cup, camera); default: the "
        "dataset's config, else the defaults",
    )
    p.add_argument("--max-attempts", type=int, default=None)
    p.add_argument("--max-failures", type=int, default=2, help="failed attempts per object")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--stochastic",
        action="store_true",
        help="success with probability = score (else score >= 0.5)",
    )
    p.add_argument("--resolution", type=int, default=160, help="top-view image size, px")
    p.add_argument(
        "--num-threads",
        "--threads",
        dest="threads",
        type=int,
        default=0,
        help="C++ threads (0 = all cores)",
    )
    p.add_argument("--out", required=True, help="output folder")

    add_engine_arguments(p, what="the step pictures")
    p.set_defaults(func=_cmd_pick)
