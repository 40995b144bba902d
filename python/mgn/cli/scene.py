"""``mgn scene ...``: the scene command group.

    mgn scene drop (--objects NAME[,NAME..] | --categories NAME[,NAME..] [--count N] | --count N)
                   [--seed S] [--out scene.json] [--add YAML] [--copies MIN-MAX] ...

Further actions (e.g. ``render``) register themselves by adding a function to :data:`ACTIONS`;
each takes the ``scene`` subparsers object and adds its parser with ``set_defaults(func=...)``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from collections.abc import Callable
from pathlib import Path

from tqdm import tqdm

from mgn.base.atomic import atomic_dir
from mgn.cli.args import add_engine_arguments, engine_settings, split_list
from mgn.errors import InvalidArgumentError, MgnError
from mgn.io.dataset_record import DATASET_RECORD, read_dataset_record
from mgn.io.scene_json import read_scene_json, write_scene_json
from mgn.io.view_images import render_views
from mgn.objects import builtin_objects, load_objects_yaml, tote_mesh
from mgn.pipeline.config import Config, load_config
from mgn.pipeline.label_cache import object_labels
from mgn.pipeline.label_scene import label_scene
from mgn.pipeline.scene_writer import label_options, scene_views
from mgn.pj.labels import PjLabels
from mgn.scene.compose import compose_objects
from mgn.scene.drop import drop_scene
from mgn.scene.scene import DropOptions
from mgn.suction.labels import SuctionLabels
from mgn.viz.scene_export import export_scene_glb

__all__ = ["ACTIONS", "register"]


def _copies(text: str) -> tuple[int, int]:
    try:
        lo, _, hi = text.partition("-")
        return (int(lo), int(hi or lo))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected MIN-MAX (e.g. 2-5), got {text!r}") from None


def _cmd_drop(args: argparse.Namespace) -> int:

    catalogue = list(builtin_objects())
    sources: dict[str, str] = {}
    for path in args.add or ():
        for spec in load_objects_yaml(path):
            catalogue.append(spec)
            sources[spec.name] = str(Path(path).resolve())
    names = split_list(args.objects)
    categories = split_list(args.categories)
    if names is None and categories is None and args.count is None:
        raise InvalidArgumentError("mgn scene drop: give --objects, --categories or --count")
    objects = compose_objects(
        names=names,
        categories=categories,
        count=args.count,
        copies=args.copies,
        seed=args.seed,
        catalogue=catalogue,
    )
    options = DropOptions(max_time=args.max_time, tote_collision=args.tote_collision)
    used = {s.name for s in objects}
    scene = drop_scene(
        objects,
        seed=args.seed,
        options=options,
        sources={k: v for k, v in sources.items() if k in used},
    )
    write_scene_json(scene, args.out)
    st = scene.stats
    print(
        f"dropped {st['num_dropped']} objects (seed {args.seed}): {len(scene)} in the tote, "
        f"{len(scene.removed)} removed; {'settled' if st['settled'] else 'NOT settled'} after "
        f"{st['simulated_time']:.2f} s simulated ({st['steps']} steps)"
    )
    for inst in scene.instances:
        z = inst.X_WO[2, 3] * 1000
        rel = inst.bin_relation
        touches = ",".join(inst.contacts)
        print(f"  {inst.instance_id:>3} {inst.name:<22} z={z:6.1f} mm  {rel:<7} {touches}")
    for r in scene.removed:
        print(f"  removed {r.name}: {r.reason}")
    print(f"scene written to {args.out}")
    return 0


def _register_drop(ssub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = ssub.add_parser("drop", help="drop objects into the tote and write the settled scene")
    p.add_argument(
        "--objects",
        nargs="+",
        metavar="NAME",
        help="these objects (names or ids; repeat a name for copies)",
    )
    p.add_argument(
        "--categories",
        nargs="+",
        metavar="NAME",
        help="these categories, each with --copies copies (MetaGraspNet: 2-5)",
    )
    p.add_argument("--count", type=int, help="total number of objects")
    p.add_argument("--copies", type=_copies, default=(2, 5), metavar="MIN-MAX")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default="scene.json", help="scene JSON (default: scene.json)")
    p.add_argument("--add", action="append", metavar="YAML", help="user objects YAML file")
    p.add_argument("--max-time", type=float, default=7.0, help="simulated seconds at most")
    p.add_argument("--tote-collision", choices=["boxes", "mesh"], default="boxes")
    p.set_defaults(func=_cmd_drop)


def _cmd_render(args: argparse.Namespace) -> int:

    config = load_config(args.config)
    render = engine_settings(config.render, args)
    scene = read_scene_json(args.scene)
    if len(scene) == 0:
        raise InvalidArgumentError(f"'{args.scene}': the scene has no objects to render")
    # The camera section gives the rig, the intrinsics (resolution scale, lens), the sensor and
    # the randomisation, as for `mgn scene label`; the flags given override it.
    camera = config.camera
    rig = scene_views(scene, dataclasses.replace(camera, views=None), rig_seed=args.rig_seed)
    wanted = args.view or (list(camera.views) if camera.views is not None else [0])
    bad = sorted(set(wanted) - {v for v, _ in rig})
    if bad:
        raise InvalidArgumentError(
            f"--view {bad}: the {camera.rig} rig has views 0..{len(rig) - 1}"
        )
    views = render_views(
        scene.render_items(),
        tote_mesh(scene.tote),
        views=[rig[v] for v in wanted],
        out_dir=args.out,
        sensor=args.sensor or camera.sensor,
        randomize=camera.randomize and not args.no_randomize,
        seed=scene.seed,
        render=render,
        num_threads=args.num_threads,
    )
    for v in views:
        print(f"view {v.index}: {args.out}/{v.index}_rgb.png, _depth.png, _instances.png")
    return 0


def _register_render(ssub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = ssub.add_parser("render", help="render views of a dropped scene (RGB, depth, instances)")
    p.add_argument("scene", help="scene JSON written by `mgn scene drop`")
    p.add_argument(
        "--view",
        type=int,
        nargs="+",
        help="views of the rig (default: the config's camera.views, else view 0)",
    )
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--rig-seed", type=int, help="camera rig seed (default: the scene seed)")
    p.add_argument(
        "--sensor",
        choices=["ideal", "structured-light", "tof"],
        help="depth sensor (default: the config's camera.sensor, structured-light)",
    )
    p.add_argument("--no-randomize", action="store_true", help="fixed light and colours")
    p.add_argument(
        "--config",
        help="dataset config YAML: its camera section (rig, intrinsics, resolution scale, lens, "
        "sensor, randomisation) and render section",
    )
    p.add_argument("--num-threads", type=int, default=0, help="0 = all cores")
    add_engine_arguments(p)
    p.set_defaults(func=_cmd_render)


def _cmd_label(args: argparse.Namespace) -> int:

    config = load_config(args.config)
    render = engine_settings(config.render, args)
    scene = read_scene_json(args.scene)
    if len(scene) == 0:
        raise InvalidArgumentError(f"'{args.scene}': the scene has no objects to label")
    views = scene_views(scene, config.camera)
    if args.view is not None:
        known = {v for v, _ in views}
        missing = sorted(set(args.view) - known)
        if missing:
            raise InvalidArgumentError(
                f"--view {missing}: not among the configured views {sorted(known)}"
            )
        views = [(v, c) for v, c in views if v in set(args.view)]
    grasps = config.labels.scene_grasps and not args.no_grasps
    pj: list[PjLabels | None] | None = None
    su: list[SuctionLabels | None] | None = None
    if grasps:
        t0 = time.perf_counter()
        by_name = {}
        names = sorted({(inst.name, inst.source) for inst in scene.instances})
        for name, source in tqdm(names, desc="object labels", unit="object", disable=None):
            idx = next(
                i
                for i, inst in enumerate(scene.instances)
                if (inst.name, inst.source) == (name, source)
            )
            by_name[name] = object_labels(
                scene.object_spec(idx), config, num_threads=args.num_threads
            )
        got = [by_name[inst.name] for inst in scene.instances]
        pj = [g.paralleljaw for g in got] if config.labels.paralleljaw else None
        su = [g.suction for g in got] if config.labels.suction else None
        print(f"object labels of {len(names)} objects in {time.perf_counter() - t0:.1f} s")
    options = dataclasses.replace(
        label_options(config, scene.seed, num_threads=args.num_threads, scene_grasps=grasps),
        render=render,
    )
    with (
        tqdm(total=len(views), desc="views", unit="view", disable=None) as bar,
        atomic_dir(args.out, overwrite=args.overwrite) as tmp,
    ):
        timings = label_scene(
            scene,
            tmp,
            views,
            pj_labels=pj,
            suction_labels=su,
            gripper=config.gripper,
            cup=config.cup,
            options=options,
            progress=lambda *_: bar.update(1),
        )
    split = ", ".join(f"{k} {v:.0f}" for k, v in timings.per_view_ms().items())
    print(f"{len(views)} views of {len(scene)} objects in {args.out} (ms per view: {split})")
    return 0


def _register_label(ssub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = ssub.add_parser(
        "label", help="render and label a dropped scene: one MetaGraspNet scene folder"
    )
    p.add_argument("scene", help="scene JSON written by `mgn scene drop`")
    p.add_argument("--out", required=True, help="the scene folder to write (created)")
    p.add_argument("--config", help="dataset config YAML (cameras, sensor, labels, gripper, cup)")
    p.add_argument("--view", type=int, nargs="+", help="only these views of the configured rig")
    p.add_argument("--no-grasps", action="store_true", help="skip the scene grasp labels")
    p.add_argument("--overwrite", action="store_true", help="replace an existing folder")
    p.add_argument("--num-threads", type=int, default=0, help="0 = all cores")
    add_engine_arguments(p)
    p.set_defaults(func=_cmd_label)


def _scene_path(arg: str) -> str:
    """A scene JSON, or a scene folder (``mgn scene label`` / ``mgn generate``) holding one."""

    folder = Path(arg)
    if arg and folder.is_dir():  # Path("") is the working folder
        p = folder / "scene.json"
        if not p.exists():
            raise FileNotFoundError(
                f"'{arg}' is a folder without scene.json; expected a scene "
                "JSON (mgn scene drop) or a scene folder"
            )
        return os.fspath(p)
    return arg


def _dataset_config(scene_path: str) -> tuple[Config | None, Path | None]:
    """The config recorded in the ``dataset.json`` of the dataset a scene folder belongs to
    (``DS/scene<N>/scene.json`` -> ``DS/dataset.json``), and that file; (None, None) when the
    scene is not part of a dataset."""
    record = Path(scene_path).resolve().parent.parent / DATASET_RECORD
    doc = read_dataset_record(record.parent)
    if doc is None or not isinstance(doc.get("config"), dict):
        return None, None
    try:
        return Config.from_dict(doc["config"]), record
    except MgnError as e:
        raise InvalidArgumentError(
            f"'{record}': its config cannot be read ({e}); give --config"
        ) from e


def _cmd_export(args: argparse.Namespace) -> int:

    path = _scene_path(args.scene)
    config = load_config(args.config)
    if args.config is None:  # a dataset's scene: its own cameras, gripper and cup
        recorded, record = _dataset_config(path)
        if recorded is not None:
            config = recorded
            print(f"config (cameras, gripper, cup) from {record}; --config replaces it")
    scene = read_scene_json(path)
    views = [] if args.no_cameras else scene_views(scene, config.camera)
    counts = export_scene_glb(
        scene,
        args.out,
        views=views,
        grasps=args.grasps,
        top_k=args.top_k,
        config=config,
        num_threads=args.num_threads,
    )
    print(
        f"{args.out}: {counts['objects']} objects, tote, {counts['cameras']} cameras, "
        f"{counts['grasps']} collision-free grasps ({counts['nodes']} nodes, metres; node "
        "tote_frame turns the tote's z up into glTF's y up)"
    )
    return 0


def _register_export(ssub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = ssub.add_parser(
        "export",
        help="write the scene as glTF binary (.glb): objects, tote, cameras, optional grasps",
        description="Write a scene as .glb for any glTF viewer: one node per object (matrix = "
        "X_WO), the tote, a frustum per camera (matrix = X_WC) and, with --grasps, the best "
        "--top-k collision-free grasps of every object (cup or hand meshes, red = score 0, "
        "green = 1).",
    )
    p.add_argument("scene", help="scene JSON (mgn scene drop) or a scene folder")
    p.add_argument("out", help="output .glb file")
    p.add_argument(
        "--config",
        help="config YAML: cameras, gripper, cup (default: the dataset.json "
        "config of the scene's dataset, else the MGN defaults)",
    )
    p.add_argument(
        "--grasps", metavar="KIND", help="also draw grasps: suction or paralleljaw (default: none)"
    )
    p.add_argument("--top-k", type=int, default=5, help="grasps per object (default 5)")
    p.add_argument("--no-cameras", action="store_true", help="leave the camera frustums out")
    p.add_argument("--num-threads", type=int, default=0, help="0 = all cores (default)")
    p.set_defaults(func=_cmd_export)


#: Functions adding one action each to the ``scene`` subparsers.
ACTIONS: list[Callable[[argparse._SubParsersAction[argparse.ArgumentParser]], None]] = [
    _register_drop,
    _register_render,
    _register_label,
    _register_export,
]


def register(
    sub: argparse._SubParsersAction[argparse.ArgumentParser],
) -> argparse._SubParsersAction[argparse.ArgumentParser]:
    """Add the ``scene`` command group to the top-level subparsers; returns its subparsers."""
    scene = sub.add_parser("scene", help="compose, drop and render scenes")
    ssub = scene.add_subparsers(dest="scene_command", metavar="ACTION", required=True)
    for add in ACTIONS:
        add(ssub)
    return ssub
