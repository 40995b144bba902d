"""The ``mgn`` command line. Errors print one line and exit non-zero; ``--debug`` shows tracebacks.

Subcommands::

    mgn objects list [--json]          the built-in objects (id, name, size, tags)
    mgn objects export DIR [--only N]  write them in the MetaGraspNet model folder layout
    mgn info MESH [--scale S]          validation and mass properties of a mesh file
    mgn suction label ROOT             suction labels of exported objects (textured.obj.hdf5)
    mgn suction board OUT              calibration board STL + poses to try + results template
    mgn suction calibrate RESULTS.csv  fit the cup constants c1, c2 (NLopt) and report metrics
    mgn demo [--out DIR]               export + ray-cast/collision smoke + a picture
"""

from __future__ import annotations

import argparse
import io
import json
import math
import os
import re
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import yaml
from PIL import Image
from tqdm import tqdm

from mgn._core import __version__
from mgn.base.atomic import atomic_write_bytes, atomic_write_text
from mgn.base.yaml_file import read_yaml
from mgn.calibration import calibrate_from_csv, write_calibration_board
from mgn.cli.args import split_list
from mgn.cli.demo import run_demo
from mgn.errors import InvalidArgumentError, MgnError
from mgn.geometry.mesh import Mesh, load_mesh, mass_properties
from mgn.geometry.repair import repair_mesh, split_note
from mgn.hardware import SuctionCup, default_cup, default_gripper
from mgn.io.grasp_file import write_suction_labels
from mgn.io.model_folder import object_folders, read_model_folder, write_model_folder, write_tote
from mgn.objects import (
    ObjectSpec,
    builtin_objects,
    default_tote,
    get_object,
    load_objects_yaml,
    object_names,
)
from mgn.objects.user import (
    UserObjectWarning,
    check_object_name,
    describe_material,
    warn_implausible_size,
    warn_missing_material_files,
)
from mgn.suction import label_object
from mgn.viz.suction_compare import compare_models, comparison_picture


def _catalogue(extra_yaml: Sequence[str] | None) -> list[ObjectSpec]:
    """Built-in objects followed by the user objects of each ``--add`` YAML file."""

    specs = list(builtin_objects())
    for path in extra_yaml or ():
        specs.extend(load_objects_yaml(path))
    return specs


def _cmd_objects_list(args: argparse.Namespace) -> int:

    rows: list[dict[str, Any]] = []
    for spec in _catalogue(args.add):
        size = np.ptp(np.asarray(spec.vertices), axis=0) * 1000
        mass = mass_properties(spec.to_mesh(), spec.density).mass
        rows.append(
            {
                "id": spec.category_id,
                "name": spec.name,
                "size_mm": [round(float(s), 1) for s in size],
                "mass_g": round(mass * 1000, 1),
                "faces": int(len(spec.faces)),
                "tags": sorted(spec.tags),
                "description": spec.description,
            }
        )
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    print(f"{'id':>3}  {'name':<24}{'size (mm)':<22}{'mass (g)':>9}  tags")
    for r in rows:
        size = "x".join(f"{s:.0f}" for s in r["size_mm"])
        print(f"{r['id']:>3}  {r['name']:<24}{size:<22}{r['mass_g']:>9.1f}  {', '.join(r['tags'])}")
    print(f"{len(rows)} objects; plus the tote, the default gripper and the default suction cup")
    return 0


def _cmd_objects_export(args: argparse.Namespace) -> int:

    specs = _catalogue(args.add)
    args.only = split_list(args.only)
    if args.only:
        by_key = {s.name: s for s in specs} | {str(s.category_id): s for s in specs}
        missing = [n for n in args.only if n not in by_key]
        if missing:
            raise KeyError(f"unknown object(s) {missing}; known: {sorted(s.name for s in specs)}")
        specs = list({id(by_key[n]): by_key[n] for n in args.only}.values())  # once each
    written = set()
    for spec in tqdm(specs, desc="exporting objects", unit="obj", disable=args.quiet):
        written.add(write_model_folder(spec, args.dir, overwrite=True))

    root = Path(args.dir)
    default_gripper().to_yaml(root / "gripper.yaml")
    default_cup().to_yaml(root / "suction_cup.yaml")
    write_tote(default_tote(), root)
    print(f"wrote {len(written)} object folders to {root / 'models'} (+ tote, gripper, cup)")
    return 0


def _uniform_scale(text: str) -> float:
    """The ``--scale`` of a mesh: one number > 0 (several numbers: only uniform is supported)."""
    parts = [t for t in re.split(r"[,x\s]+", text.strip()) if t]
    if len(parts) > 1:
        raise argparse.ArgumentTypeError(
            f"only a uniform scale is supported (one number that multiplies every coordinate), "
            f"got {text!r}; scale the mesh file itself for different factors per axis"
        )
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def _snake(stem: str) -> str:

    name = re.sub(r"[^a-z0-9]+", "_", stem.lower()).strip("_")
    return name if name and not name[0].isdigit() else f"part_{name}"


def _closed_entry(
    mesh: Any, report: Any, entry: dict[str, Any], density: float
) -> tuple[str, str, Any]:
    """Set ``repair`` / ``allow_open`` of a new user-object entry as its mesh needs: a mesh
    that is not closed is repaired (:func:`mgn.geometry.repair.repair_mesh`): ``repair: true``
    when that closes it, else ``allow_open: true`` (the mesh as it is). Closed solids that touch
    along an edge or at a vertex are closed as read; the note says what was split. Returns (the
    note of the "added" line, the warning of a mesh that stays open or "", the mesh as it is
    read)."""
    if report.is_watertight and report.is_winding_consistent:
        split = split_note(report)  # closed solids that touch: closed as read
        if not split:
            return "", "", mesh
        mass_g = mass_properties(mesh, density).mass * 1e3
        return f"; {split}: closed, solid mass {mass_g:.4g} g", "", mesh
    fixed = repair_mesh(mesh)
    if fixed.closed:
        entry["repair"] = True
        mass_g = mass_properties(fixed.mesh, density).mass * 1e3
        changes = "; ".join(c for c in (*fixed.changes, split_note(fixed.after)) if c)
        note = f"; repaired as it is read ({changes}): closed, solid mass "
        return f"{note}{mass_g:.4g} g", "", fixed.mesh
    entry["allow_open"] = True
    mass_g = mass_properties(mesh, density).mass * 1e3
    r = fixed.after  # what the repair cannot fix
    why = []
    if r.num_boundary_edges:
        holes = f" ({fixed.holes_left} hole(s) larger than 1 % of the surface)"
        why.append(f"{r.num_boundary_edges} free edges" + (holes if fixed.holes_left else ""))
    if r.num_nonmanifold_edges:
        why.append(f"{r.num_nonmanifold_edges} edge(s) shared by more than two faces")
    if r.num_misoriented_edges:
        why.append(f"{r.num_misoriented_edges} misoriented edge(s)")
    note = f"; OPEN: shell mass {mass_g:.4g} g, no parallel-jaw labels"
    warn = (
        f" stays open: {', '.join(why)}, which the repair (winding, duplicate and stray faces, "
        f"small holes) cannot fix. It is marked allow_open: its mass {mass_g:.4g} g is a shell "
        "mass (2 mm walls, not a solid), and it gets suction labels only, no parallel-jaw "
        "labels. Close the mesh (e.g. in MeshLab or Blender) for a solid mass and parallel-jaw "
        "labels."
    )
    return note, warn, mesh


def _cmd_objects_add(args: argparse.Namespace) -> int:
    """Append one user-object entry per mesh to a YAML file, validating each one."""

    target = Path(args.to)
    data = read_yaml(target, "user-object YAML") if target.exists() else None
    if data is None:
        data = {"objects": []}
    if not isinstance(data, dict) or not isinstance(data.get("objects"), list):
        raise InvalidArgumentError(
            f"user-object YAML '{target}': expected a top-level 'objects:' list"
        )
    if args.name and len(args.name) != len(args.meshes):
        raise InvalidArgumentError(
            f"mgn objects add: --name gives {len(args.name)} name(s) for {len(args.meshes)} "
            "mesh(es); expected one per mesh"
        )
    taken = {s.name for s in builtin_objects()} | {
        str(e.get("name")) for e in data["objects"] if isinstance(e, dict)
    }
    base = target.resolve().parent
    added: list[str] = []
    open_notes: list[str] = []
    new_names: set[str] = set()
    materials: dict[str, tuple[Any, dict[str, Any]]] = {}
    for i, mesh_arg in enumerate(args.meshes):
        path = Path(mesh_arg)
        mesh = load_mesh(path, scale=args.scale)  # IoError / InvalidArgumentError name the file
        report = mesh.validate()
        name = args.name[i] if args.name else _snake(path.stem)
        if args.name:
            check_object_name(name, "mgn objects add: --name")
        stem, k = name, 2
        while name in taken:
            name, k = f"{stem}_{k}", k + 1
        taken.add(name)
        entry: dict[str, Any] = {"name": name}
        full = path.resolve()  # relative to the YAML file when below it, else absolute
        entry["mesh"] = (
            full.relative_to(base).as_posix() if full.is_relative_to(base) else os.fspath(full)
        )
        entry.update(scale=args.scale, density=args.density, friction=args.friction)
        note, open_note, mesh = _closed_entry(mesh, report, entry, args.density)
        if open_note:
            open_notes.append(f"{name} ('{path}'){open_note}")
        if args.tags:
            entry["tags"] = list(args.tags)
        data["objects"].append(entry)
        size = np.ptp(np.asarray(mesh.vertices), axis=0) * 1000
        added.append(f"  {name}: {path} {'x'.join(f'{v:.0f}' for v in size)} mm{note}")
        new_names.add(name)
        materials[name] = (mesh.materials[0] if mesh.materials else None, entry)
    text = yaml.safe_dump(data, sort_keys=False)
    tmp = target.with_name(f".{target.name}.check.yaml")
    tmp.write_text(text, encoding="utf-8")
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            specs = load_objects_yaml(tmp)  # the whole file, as generate will read it
    except MgnError as e:
        raise type(e)(str(e).replace(os.fspath(tmp), os.fspath(target))) from None
    finally:
        tmp.unlink(missing_ok=True)
    for w in caught:  # about the objects added now (the others were said when they were)
        if isinstance(w.message, UserObjectWarning) and w.message.object_name not in new_names:
            continue
        print(
            f"mgn: warning: {w.message}".replace(os.fspath(tmp), os.fspath(target)), file=sys.stderr
        )
    for note in open_notes:
        print(f"mgn: warning: {note}", file=sys.stderr)
    atomic_write_text(target, text)
    print(f"{target}: {len(specs)} object(s); added:")
    by_name = {s.name: s for s in specs}
    for line, name in zip(added, materials, strict=True):
        mat, entry = materials[name]
        print(f"{line}\n    material: {describe_material(mat, by_name[name].material, entry)}")
    names = " ".join(s.name for s in specs)
    print(f"next: mgn generate --out DS --scenes 10 --add {target} --categories {names}")
    return 0


def mesh_info(path: str, scale: float = 1.0, density: float = 1000.0) -> dict[str, Any]:
    """The ``mgn info`` / ``mgn-cli info`` JSON document of a mesh file (same keys and values,
    numbers to 10 significant digits): counts, bounds (m), validation, mass properties (kg, m,
    kg m^2 about the centre of mass; open meshes as a 2 mm shell)."""

    mesh = load_mesh(path, scale=scale)
    warn_implausible_size(mesh.vertices, f"'{path}' (scale {scale:g})")
    warn_missing_material_files(path, mesh, f"'{path}'")
    r = mesh.validate()
    p = mass_properties(mesh, density)

    def num(v: float) -> float | None:
        return float(f"{float(v):.10g}") if math.isfinite(float(v)) else None

    def vec(v: npt.ArrayLike) -> list[float | None]:
        return [num(x) for x in np.asarray(v, np.float64).ravel()]

    lo, hi = np.asarray(mesh.bounds, np.float64)
    uvs = mesh.uvs
    return {
        "path": path,
        "name": mesh.name,
        "num_vertices": r.num_vertices,
        "num_faces": r.num_faces,
        "num_materials": len(mesh.materials),
        "has_uvs": uvs is not None and len(uvs) > 0,
        "bounds_min": vec(lo),
        "bounds_max": vec(hi),
        "validation": {
            "is_watertight": r.is_watertight,
            "is_winding_consistent": r.is_winding_consistent,
            "is_outward": r.is_outward,
            "num_boundary_edges": r.num_boundary_edges,
            "num_nonmanifold_edges": r.num_nonmanifold_edges,
            "num_misoriented_edges": r.num_misoriented_edges,
            "num_components": r.num_components,
            "num_split_edges": r.num_split_edges,
            "num_split_vertices": r.num_split_vertices,
            "area": num(r.area),
            "signed_volume": num(r.signed_volume),
        },
        "mass_properties": {
            "density": num(density),
            "volume": num(p.volume),
            "mass": num(p.mass),
            "center_of_mass": vec(p.center_of_mass),
            "inertia": [vec(row) for row in np.asarray(p.inertia)],
            "is_exact": bool(p.is_exact),
        },
    }


def _cmd_info(args: argparse.Namespace) -> int:

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        info = mesh_info(args.mesh, args.scale, args.density)
    for w in caught:
        print(f"mgn info: warning: {w.message}", file=sys.stderr)
    print(json.dumps(info, indent=2))
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:

    result = run_demo(args.out, num_threads=args.num_threads)
    failed = (result.num_objects - result.reloaded_ok) + result.collision_errors
    if failed:
        print(f"mgn demo: {failed} check(s) FAILED (see {result.out_dir / 'smoke.json'})")
        return 1
    print("mgn demo: all checks passed")
    return 0


def _cmd_suction_label(args: argparse.Namespace) -> int:

    root = Path(args.root)
    folders = object_folders(root)
    if args.objects:
        wanted = set(split_list(args.objects) or ())
        folders = [
            f
            for f in folders
            if f.name in wanted
            or str(int(f.name)) in wanted
            or read_model_folder(f).metadata.get("name") in wanted
        ]
    if not folders:
        raise InvalidArgumentError(f"no object folders to label under '{root / 'models'}'")
    cup = SuctionCup.from_yaml(args.cup) if args.cup else SuctionCup()
    for folder in folders:
        mf = read_model_folder(folder)
        mesh = load_mesh(folder / "textured.obj")
        density = float(mf.metadata.get("density_kg_m3", args.density))
        props = mass_properties(mesh, density)
        labels = label_object(
            mesh,
            mass=props.mass,
            com=props.center_of_mass,
            inertia=props.inertia,
            cup=cup,
            model=args.model,
            num_points=args.num_points,
            seed=args.seed,
            num_threads=args.num_threads,
            progress=not args.quiet,
        )
        write_suction_labels(folder / "textured.obj.hdf5", labels)
        good = int((labels.score >= 0.5).sum())
        print(
            f"{folder.name} {mf.metadata.get('name', '')}: {len(labels.score)} suction labels "
            f"({good} with score >= 0.5, {labels.num_colliding} colliding dropped)"
        )
    return 0


def _cmd_suction_board(args: argparse.Namespace) -> int:

    paths = write_calibration_board(args.out, overwrite=args.overwrite)
    print(f"calibration board: {paths['stl']} (mm); poses to try: {paths['poses']}")
    print(f"fill in {paths['results_template']}, then run: mgn suction calibrate FILLED.csv")
    return 0


def _cmd_suction_calibrate(args: argparse.Namespace) -> int:

    cup = SuctionCup.from_yaml(args.cup) if args.cup else SuctionCup()
    report = calibrate_from_csv(
        args.results, board_dir=args.board, cup=cup, seed=args.seed, num_threads=args.num_threads
    )
    print(report.format_report())
    report.cup.to_yaml(args.out)
    print(f"fitted cup written to {args.out}")
    return 0


def _mesh_or_builtin(arg: str, scale: float) -> Mesh:
    """A mesh file, or the name/id of a built-in object."""

    if arg and Path(arg).exists():  # Path("") is the working folder
        return load_mesh(arg, scale=scale)

    try:
        return get_object(arg).to_mesh()
    except KeyError:
        raise FileNotFoundError(
            f"'{arg}' is neither a mesh file nor a built-in object ({', '.join(object_names())})"
        ) from None


def _cmd_suction_compare(args: argparse.Namespace) -> int:

    mesh = _mesh_or_builtin(args.mesh, args.scale)
    cup = SuctionCup.from_yaml(args.cup) if args.cup else SuctionCup()
    comp = compare_models(
        mesh, cup=cup, num_points=args.num_points, seed=args.seed, num_threads=args.num_threads
    )
    print(comp.format_table())
    if args.png:
        buf = io.BytesIO()
        Image.fromarray(comparison_picture(mesh, comp)).save(buf, format="PNG")
        atomic_write_bytes(args.png, buf.getvalue())
        print(f"picture: {args.png}")
    if args.json:
        doc = {
            "points_m": comp.points.tolist(),
            "normals": comp.normals.tolist(),
            "scores": {m: s.tolist() for m, s in comp.scores.items()},
            "pairs": [
                {
                    "a": p.a,
                    "b": p.b,
                    "agreement": p.agreement,
                    "a_low_b_seal": p.low_vs_seal,
                    "a_high_b_no_seal": p.high_vs_no_seal,
                }
                for p in comp.pairs
            ],
            "seal_threshold": comp.seal_threshold,
            "cup": cup.to_dict(),
            "seed": args.seed,
        }
        atomic_write_text(args.json, json.dumps(doc))
        print(f"scores: {args.json}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mgn",
        description="Synthesise bin-picking datasets with ambidextrous grasp labels.",
    )
    parser.add_argument("--version", action="version", version=f"mgn {__version__}")
    parser.add_argument("--debug", action="store_true", help="show full tracebacks on errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    objects = sub.add_parser("objects", help="the built-in object library")
    osub = objects.add_subparsers(dest="objects_command", metavar="ACTION", required=True)
    add_help = "also include the user objects described in this YAML file (repeatable)"
    p = osub.add_parser("list", help="list the built-in objects")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--add", action="append", metavar="YAML", help=add_help)
    p.set_defaults(func=_cmd_objects_list)
    p = osub.add_parser("export", help="write the objects as MetaGraspNet model folders")
    p.add_argument("dir", help="output root; objects go to DIR/models/<id>/")
    p.add_argument(
        "--objects",
        "--only",
        dest="only",
        nargs="+",
        metavar="NAME",
        help="export only these (names or ids)",
    )
    p.add_argument("--add", action="append", metavar="YAML", help=add_help)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_objects_export)
    p = osub.add_parser(
        "add",
        help="describe your meshes as user objects (appends to a YAML file, validating each)",
        description="Append one entry per mesh to the user-object YAML file --to (created if "
        "missing; format: mgn.objects.user). A mesh that is not closed is repaired (repair: "
        "true: winding, duplicate and stray faces, small holes; the output says what changed); "
        "one that stays open gets allow_open: true (thin-shell mass, no parallel-jaw labels). "
        "Then: mgn generate --out DS --add FILE --categories NAME ...",
    )
    p.add_argument("meshes", nargs="+", metavar="MESH", help="mesh files (OBJ, STL, PLY, GLB...)")
    p.add_argument("--to", required=True, metavar="YAML", help="user-object YAML to append to")
    p.add_argument(
        "--name",
        nargs="+",
        metavar="NAME",
        help="object names, one per mesh (default: from the file names)",
    )
    p.add_argument(
        "--scale",
        type=_uniform_scale,
        default=1.0,
        help="uniform coordinate scale (default 1; 0.001 for a file in mm)",
    )
    p.add_argument("--density", type=float, default=1000.0, help="kg/m^3 (default 1000)")
    p.add_argument("--friction", type=float, default=0.5, help="Coulomb friction (default 0.5)")
    p.add_argument("--tags", nargs="+", metavar="TAG", help="tags (mgn.objects.ALLOWED_TAGS)")
    p.set_defaults(func=_cmd_objects_add)

    suction = sub.add_parser("suction", help="suction grasp labels")
    ssub = suction.add_subparsers(dest="suction_command", metavar="ACTION", required=True)
    p = ssub.add_parser(
        "label", help="label the objects of an export root (writes grasps/suctioncup/*)"
    )
    p.add_argument("root", help="folder with models/<id>/ (from `mgn objects export`)")
    p.add_argument("--objects", nargs="+", metavar="NAME", help="only these (names or ids)")
    p.add_argument("--cup", metavar="YAML", help="suction cup YAML (default: MetaGraspNet cup)")
    p.add_argument("--model", choices=["spring", "strain", "smoothness"], default="spring")
    p.add_argument("--num-points", type=int, default=5000, help="candidates per object")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--density", type=float, default=500.0, help="kg/m^3 if not in metadata")
    p.add_argument("--num-threads", type=int, default=0, help="0 = all cores")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=_cmd_suction_label)
    p = ssub.add_parser("board", help="write the calibration board (STL) and the poses to try")
    p.add_argument("out", help="output folder")
    p.add_argument("--overwrite", action="store_true", help="replace existing files")
    p.set_defaults(func=_cmd_suction_board)
    p = ssub.add_parser("calibrate", help="fit the cup constants c1, c2 to measured outcomes")
    p.add_argument("results", help="the filled-in results CSV (pose_id, sealed, ...)")
    p.add_argument("--board", help="folder with poses.csv (default: the CSV's folder)")
    p.add_argument("--cup", metavar="YAML", help="initial cup (default: MetaGraspNet cup)")
    p.add_argument("--out", default="fitted_cup.yaml", help="fitted cup YAML")
    p.add_argument("--seed", type=int, default=0, help="held-out split seed")
    p.add_argument("--num-threads", type=int, default=0)
    p.set_defaults(func=_cmd_suction_calibrate)
    p = ssub.add_parser(
        "compare", help="score the same points with the three seal models; table and picture"
    )
    p.add_argument("mesh", help="mesh file, or the name/id of a built-in object")
    p.add_argument(
        "--scale", type=_uniform_scale, default=1.0, help="uniform coordinate scale (0.001 for mm)"
    )
    p.add_argument("--cup", metavar="YAML", help="suction cup YAML (default: MetaGraspNet cup)")
    p.add_argument("--num-points", type=int, default=1000, help="candidates (default 1000)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--png", metavar="FILE", help="write the per-model picture (PNG)")
    p.add_argument("--json", metavar="FILE", help="write points and scores (JSON)")
    p.add_argument("--num-threads", type=int, default=0, help="0 = all cores")
    p.set_defaults(func=_cmd_suction_compare)
    __import__("mgn.cli.pj", fromlist=["register"]).register(
        sub
    )  # mgn pj label (python/mgn/cli/pj.py)

    __import__("mgn.cli.scene", fromlist=["register"]).register(sub)
    p = sub.add_parser(
        "info", help="validation and mass properties of a mesh file (JSON, as mgn-cli info)"
    )
    p.add_argument("mesh", help="mesh file (OBJ, STL, PLY, GLB/GLTF, DAE, ...)")
    p.add_argument(
        "--scale",
        type=_uniform_scale,
        default=1.0,
        help="uniform coordinate scale (default 1; 0.001 for mm)",
    )
    p.add_argument("--density", type=float, default=1000.0, help="kg/m^3 (default 1000)")
    p.set_defaults(func=_cmd_info)

    p = sub.add_parser("demo", help="export the built-in objects and run a smoke check")
    p.add_argument("--out", default="demo_out", help="output folder (default: demo_out)")
    p.add_argument("--num-threads", type=int, default=0, help="0 = all cores")
    p.set_defaults(func=_cmd_demo)
    __import__("mgn.cli.render", fromlist=["register"]).register(sub)
    __import__("mgn.cli.io", fromlist=["register"]).register(sub)
    __import__("mgn.cli.export", fromlist=["register"]).register(sub)  # mgn export bop
    __import__("mgn.cli.pipeline", fromlist=["register"]).register(sub)  # generate, config
    __import__("mgn.cli.eval", fromlist=["register"]).register(sub)  # eval detections|grasps|...
    __import__("mgn.cli.pick", fromlist=["register"]).register(sub)  # mgn pick
    __import__("mgn.cli.learn", fromlist=["register"]).register(sub)  # train, predict
    _use_formatter(parser)
    return parser


def _shows_default(action: argparse.Action) -> bool:
    d = action.default
    return not (d is None or d is False or d is True or d == argparse.SUPPRESS)


class _HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Descriptions as written; every option's default in its help unless the help names it."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if (
            action.option_strings
            and _shows_default(action)
            and "default" not in text
            and "%(default)" not in text
        ):
            text = f"{text} (default: %(default)s)"
        return text


def _use_formatter(parser: argparse.ArgumentParser) -> None:
    parser.formatter_class = _HelpFormatter
    for action in parser._actions:  # argparse has no public walk
        if action.help is None and action.option_strings and _shows_default(action):
            action.help = "default: %(default)s"
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                _use_formatter(sub)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mgn`` command. Returns the process exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except (MgnError, OSError, ValueError, KeyError) as e:
        if args.debug:
            raise
        message = e.args[0] if isinstance(e, KeyError) and e.args else e
        print(f"mgn: error: {message}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("mgn: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
