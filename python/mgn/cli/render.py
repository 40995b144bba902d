"""``mgn render`` subcommands: the camera rig and a demo render of built-in objects.

Wired into :func:`mgn.cli.main.build_parser` by one call to :func:`register`.
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np

from mgn.cli.args import add_engine_arguments, engine_settings
from mgn.errors import InvalidArgumentError
from mgn.io.view_images import render_views
from mgn.objects import builtin_objects, tote_mesh
from mgn.render.settings import RenderSettings
from mgn.scene.cameras import Intrinsics, mgn_rig

__all__ = ["register"]


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``render`` command group to the ``mgn`` subparsers."""
    render = sub.add_parser("render", help="camera rigs and off-screen rendering")
    rsub = render.add_subparsers(dest="render_command", metavar="ACTION", required=True)
    p = rsub.add_parser("rig", help="print the 37 MetaGraspNet camera poses (JSON)")
    p.add_argument("--seed", type=int, default=0, help="rig seed (default: %(default)s)")
    p.add_argument("--target", type=float, nargs=3, default=(0.0, 0.0, 0.0), metavar="M")
    p.set_defaults(func=_cmd_rig)
    p = rsub.add_parser("demo", help="render built-in objects in the tote (RGB, depth, ids)")
    p.add_argument("out", help="output folder")
    p.add_argument("--views", type=int, nargs="+", default=[0], metavar="V", help="rig views")
    p.add_argument("--objects", type=int, default=12, help="number of built-in objects")
    p.add_argument("--seed", type=int, default=0, help="rig, lighting and noise seed")
    p.add_argument(
        "--sensor", choices=["ideal", "structured-light", "tof"], default="structured-light"
    )
    p.add_argument("--scale", type=float, default=1.0, help="image size factor (1 = 1200 px)")
    p.add_argument("--no-randomize", action="store_true", help="fixed light and colours")

    add_engine_arguments(p)
    p.set_defaults(func=_cmd_demo)


def _cmd_rig(args: argparse.Namespace) -> int:

    poses, params = mgn_rig(args.seed, args.target)
    print(json.dumps({"params": vars(params), "X_WC": poses.tolist()}, indent=1))
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:

    if not 1 <= args.objects <= len(builtin_objects()):
        raise InvalidArgumentError(
            f"--objects must be in 1..{len(builtin_objects())}, got {args.objects}"
        )
    if not 0.05 <= args.scale <= 2.0:
        raise InvalidArgumentError(f"--scale must be in [0.05, 2], got {args.scale}")
    items = []
    cols = math.ceil(math.sqrt(args.objects * 4 / 3))
    rows = math.ceil(args.objects / cols)
    for k, spec in enumerate(builtin_objects()[: args.objects]):
        mesh = spec.to_mesh()
        X = np.eye(4)
        yaw = 0.7 * k
        X[:2, :2] = [[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]
        x = -0.16 + 0.32 * ((k % cols) + 0.5) / cols
        y = -0.11 + 0.22 * ((k // cols) + 0.5) / rows
        X[:3, 3] = (x, y, -float(np.asarray(mesh.bounds)[0, 2]))
        items.append((mesh, X, k + 1))
    K = Intrinsics.mgn_synthetic().scaled(args.scale)
    res = render_views(
        items,
        tote_mesh(),
        args.views,
        args.out,
        rig_seed=args.seed,
        K=K,
        sensor=args.sensor,
        randomize=not args.no_randomize,
        seed=args.seed,
        render=engine_settings(RenderSettings(), args),
    )
    for r in res:
        print(f"view {r.index}: {r.valid.mean():.1%} valid depth -> {args.out}/{r.index}_*.png")
    return 0
