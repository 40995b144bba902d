"""Scene files: bytes per scene, write and read time per view, against the previous layout.

One scene of the pipeline benchmark's size (20 objects, 37 views at 1200 x 1200, all labels; the
object labels come from the label cache, or are computed once) is generated, then every view's
arrays are written again three times in the same loop: with the current writer
(`mgn.io.scene_folder.write_view`), with its archival mode (`io.archival: true`) and with the
layout mgn wrote first (all arrays in `{v}.npz`, float32 ids, `depth_ideal`, `valid_depth` and
`com_heatmap` in the npz, RGB depth picture; reproduced here as the "peer"). Reading is timed on
the current files: every array of a view through `mgn.Dataset`. Bytes per scene are the sum over
the scene folder (views, `scene_gt.json`, `scene.json`), also split by file kind. The records
carry the scene's CoM parameters and the camera pose the pipeline had, so `com_heatmap` is
stored as when the scene was generated (its residual from the prediction).

The BOP and GraspNet exports of the scene (``mgn.io.bop.export_bop_scene``,
``mgn.io.graspnet.export_graspnet_scene``: what ``output.formats`` adds per scene) are timed
with their peak traced memory and checked against ``mgn export`` of the same scene, beside
BlenderProc's published BOP-writer figure (not measured: no Blender here).

Run alone: `python -m benchmarks.bench_format [--quick] [--dataset DIR] [--only-exports]`
(quick: 10 objects, 5 views at 600 px; `--dataset`: measure scene 0 of an existing dataset
instead of generating).
"""

from __future__ import annotations

import json
import shutil
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .common import Row, Timing, bench_tempdir, load_average

SEED = 2024


def _legacy_files(rec: Any) -> dict[str, bytes]:
    """The files of one view in the layout mgn wrote before (for the comparison)."""
    from mgn.base.deterministic import npz_bytes
    from mgn.base.units import M_TO_CM
    from mgn.io.image_codecs import png_bytes
    from mgn.io.scene_hdf5 import hdf5_bytes
    from mgn.io.scene_schema import to_cm
    from mgn.render.views import depth_picture

    f4 = np.float32
    v = rec.index
    npz = {
        "depth": (np.asarray(rec.depth, np.float64) * M_TO_CM).astype(f4),
        "instances_objects": np.asarray(rec.instances).astype(f4),
        "instances_semantic": np.asarray(rec.semantic).astype(f4),
        "occlusion": np.asarray(rec.occlusion_map, f4),
        "occlusion_objects": np.asarray(rec.amodal, bool),
        "depth_ideal": (np.asarray(rec.depth_ideal, np.float64) * M_TO_CM).astype(f4),
        "valid_depth": np.asarray(rec.valid_depth, bool),
        **{k: np.asarray(a) for k, a in rec.extra_npz.items()},
    }
    h5 = {p: to_cm(p, a).astype(f4) for p, a in rec.scene_hdf5.items()}
    dump = lambda d: (json.dumps(d, indent=1) + "\n").encode()  # noqa: E731
    return {
        f"{v}_rgb.png": png_bytes(np.asarray(rec.rgb, np.uint8)),
        f"{v}.npz": npz_bytes(**npz),
        f"{v}_depth.png": png_bytes(depth_picture(rec.depth)),
        f"{v}_scene.hdf5": hdf5_bytes(h5),
        f"{v}_order.csv": rec.order_csv.encode(),
        f"{v}_order.json": dump(rec.order_json),
        f"{v}_layout.json": dump(rec.layout_json),
        f"{v}_camera_params.json": dump(rec.intrinsics.camera_params()),
    }


def _write_legacy(folder: Path, rec: Any) -> int:
    from mgn.base.atomic import atomic_write_bytes

    total = 0
    for name, data in _legacy_files(rec).items():
        atomic_write_bytes(folder / name, data)
        total += len(data)
    return total


def _com_parameters(folder: Path) -> Any:
    """(N, 5) CoM parameters of the scene in ``folder`` (as the pipeline passes them)."""
    from mgn.io.scene_json import read_scene_json
    from mgn.view_labels.objects import SceneRayModel

    return SceneRayModel.from_scene(read_scene_json(folder / "scene.json")).com_parameters()


def _exact_camera(view: Any, hdf5: dict[str, Any]) -> dict[str, Any]:
    """The view's datasets with the camera pose the pipeline had (float64, kept with the heat
    map's prediction inputs in ``{v}_mgn.hdf5``), so that the heat map predicts as when the
    scene was written; the float32 cm pose in ``{v}_scene.hdf5`` is the same."""
    import h5py

    out = dict(hdf5)
    p = view.path("_mgn.hdf5")
    if p.exists():
        with h5py.File(p, "r") as h5:
            if "com_heatmap" in h5 and "X_WC" in h5["com_heatmap"].attrs:
                out["camera/pose_relative_to_world"] = h5["com_heatmap"].attrs["X_WC"][None]
    return out


def _record(view: Any, com_parameters: Any = None) -> Any:
    """A ViewRecord holding the arrays of a written view (SI units)."""
    from mgn.io.scene_schema import ViewRecord

    return ViewRecord(
        index=view.index,
        rgb=view.rgb,
        depth=view.depth,
        depth_ideal=view.depth_ideal,
        valid_depth=view.valid_depth,
        instances=view.instances,
        semantic=view.semantic,
        occlusion_map=view.occlusion_map,
        amodal=view.amodal,
        intrinsics=view.intrinsics,
        scene_hdf5=_exact_camera(view, view.hdf5),
        order_json=view.order,
        order_csv=view.path("_order.csv").read_text(),
        layout_json=view.layout or {},
        extra_npz={"com_heatmap": view.com_heatmap},
        com_parameters=com_parameters,
    )


def _same_arrays(new_dir: Path, old_dir: Path, v: int, rec: Any) -> bool:
    from mgn.io.dataset import View

    new = View(new_dir, v)
    with np.load(old_dir / f"{v}.npz") as z:
        old = {k: z[k] for k in z.files}
    pairs = [(new.npz_array(k), old[k]) for k in ("occlusion", "occlusion_objects")]
    # The sensor depth: the metres read back are the sensor's own float32 (the previous layout
    # stored float32(m * 100), whose last bit may differ from the grid value the writer stores).
    pairs += [(new.depth, np.asarray(rec.depth, np.float32))]
    pairs += [
        (new.mgn_image("depth_ideal"), old["depth_ideal"]),
        (new.com_heatmap, old["com_heatmap"]),
        (new.valid_depth, old["valid_depth"]),
    ]

    def bits(a: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(a).view(np.uint8)

    same = all(np.array_equal(bits(a), bits(b)) for a, b in pairs)
    return same and all(
        np.array_equal(new.npz_array(k), old[k])
        for k in ("instances_objects", "instances_semantic")
    )


def _coco_previous(ds: Any) -> dict[str, Any]:
    """The COCO export as mgn made it before streaming: whole views in memory (every array of
    the npz), one pycocotools call per mask (for the comparison)."""
    from pycocotools import mask as mask_utils

    def rle(m: np.ndarray) -> dict[str, Any]:
        r = mask_utils.encode(np.asfortranarray(m.astype(np.uint8)))
        return {"size": [int(r["size"][0]), int(r["size"][1])], "counts": r["counts"].decode()}

    def bbox(m: np.ndarray) -> list[float]:
        ys, xs = np.nonzero(m)
        if len(xs) == 0:
            return [0.0] * 4
        return [
            float(xs.min()),
            float(ys.min()),
            float(xs.max() - xs.min() + 1),
            float(ys.max() - ys.min() + 1),
        ]

    images, anns = [], []
    for sid in ds.scene_ids:
        for view in ds.scene(sid).views():
            _ = view.npz
            inst, amodal = view.instances, view.amodal
            images.append({"id": sid * 1000 + view.index})
            cats = view.hdf5["objects/categories"]
            for i in range(amodal.shape[0]):
                vis = inst == i + 1
                if vis.any():
                    anns.append(
                        {
                            "category_id": int(cats[i]),
                            "segmentation": rle(vis),
                            "bbox": bbox(vis),
                            "amodal_segmentation": rle(amodal[i]),
                            "amodal_bbox": bbox(amodal[i]),
                        }
                    )
    return {"images": images, "annotations": anns}


def _coco_row(ds_root: Path, n_views: int, size: int, objects: int) -> Row:
    import tracemalloc

    from mgn.io.coco import export_coco
    from mgn.io.dataset import Dataset

    row = Row(
        group="dataset files",
        case=f"mgn coco of one scene ({n_views} views, {objects} objects at {size}x{size})",
        n=n_views,
        unit="views/s",
        peer_name="previous mgn export (whole views in memory, one pycocotools call per mask)",
    )
    out = ds_root.parent / "coco.json"
    res: dict[str, tuple[float, float, float]] = {}
    sides = [
        ("mgn", lambda: export_coco(ds_root, out)),
        ("peer", lambda: _coco_previous(Dataset(ds_root))),
    ]
    for name, fn in sides:
        tracemalloc.start()
        t, c = time.perf_counter(), time.process_time()
        fn()
        wall, cpu = time.perf_counter() - t, time.process_time() - c
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        res[name] = (wall, cpu, peak)
    row.mgn[1] = Timing(wall=[res["mgn"][0]], cpu=[res["mgn"][1]])
    row.peer = Timing(wall=[res["peer"][0]], cpu=[res["peer"][1]])
    doc = json.loads(out.read_text())
    prev = _coco_previous(Dataset(ds_root))
    same = [a["segmentation"] for a in doc["annotations"]] == [
        a["segmentation"] for a in prev["annotations"]
    ] and [a["amodal_bbox"] for a in doc["annotations"]] == [
        a["amodal_bbox"] for a in prev["annotations"]
    ]
    row.agreement = "same masks and boxes" if same else "DIFFERENT annotations"
    row.agreement_ok = same
    row.notes = [
        f"peak traced memory {res['mgn'][2] / 2**20:.0f} MiB (previous {res['peer'][2] / 2**20:.0f}"
        " MiB)",
        f"{1e3 * res['mgn'][0] / n_views:.0f} ms/view (previous "
        f"{1e3 * res['peer'][0] / n_views:.0f} ms/view)",
        f"load average {load_average()}",
    ]
    return row


#: BlenderProc's BOP writer, as its release notes publish it (not measured here).
BLENDERPROC_BOP_WRITER = (
    "published, not measured: BlenderProc 2.7 release notes, BOP writer for 300 objects 60 s "
    "-> 12 s on 8 cores (its masks and scene_gt_info rendered from the models; mgn reads its "
    "own masks)"
)


def _measure(fn: Callable[[], Any]) -> tuple[float, float, float]:
    """(wall s, CPU s, peak traced memory in bytes) of one call."""
    import tracemalloc

    tracemalloc.start()
    t, c = time.perf_counter(), time.process_time()
    fn()
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return wall, cpu, peak


def _export_rows(ds_root: Path, n_views: int, size: int, objects: int) -> list[Row]:
    """Seconds and peak memory of one scene's BOP and GraspNet exports (what ``mgn generate``
    with ``output.formats: [mgn, bop, graspnet]`` adds per scene), beside BlenderProc's
    published BOP-writer figure; the files checked against ``mgn export`` of the dataset."""
    from mgn.io.bop import export_bop, export_bop_scene, validate_bop, write_bop_models
    from mgn.io.dataset import Dataset
    from mgn.io.graspnet import (
        export_graspnet,
        export_graspnet_scene,
        graspnet_gripper,
        gripper_of,
    )

    ds = Dataset(ds_root)
    scene = ds.scene(0)
    gripper = graspnet_gripper(gripper_of(ds))
    out = ds_root.parent / "exports"
    shutil.rmtree(out, ignore_errors=True)
    what = f"one scene ({n_views} views, {objects} objects at {size}x{size})"
    models = _measure(lambda: write_bop_models(ds, out / "bop"))
    n_models = len(ds.model_folders())
    sides = {
        "bop": lambda: export_bop_scene(scene, out / "bop"),
        "graspnet": lambda: export_graspnet_scene(scene, out / "graspnet", gripper),
    }
    rows = []
    for kind, fn in sides.items():
        wall, cpu, peak = _measure(fn)
        again = ds_root.parent / f"again_{kind}"
        shutil.rmtree(again, ignore_errors=True)
        if kind == "bop":
            export_bop(ds_root, again, scenes=[0])
            ok = validate_bop(out / "bop") == []
        else:
            export_graspnet(ds_root, again, scenes=[0])
            ok = True
        files = sorted(p for p in (out / kind).rglob("*") if p.is_file())
        ok &= all(p.read_bytes() == (again / p.relative_to(out / kind)).read_bytes() for p in files)
        nbytes = sum(p.stat().st_size for p in files)
        row = Row(
            group="dataset files",
            case=f"{'BOP' if kind == 'bop' else 'GraspNet'} export of {what}",
            n=n_views,
            unit="views/s",
            peer_name="BlenderProc BOP writer" if kind == "bop" else "—",
            peer_status=BLENDERPROC_BOP_WRITER if kind == "bop" else "no peer",
        )
        row.mgn[1] = Timing(wall=[wall], cpu=[cpu])
        row.agreement = (
            ("valid BOP, " if kind == "bop" else "") + "same bytes as mgn export"
            if ok
            else "DIFFERENT files from mgn export"
        )
        row.agreement_ok = ok
        row.notes = [
            f"{wall:.1f} s wall, {cpu:.1f} s CPU per scene ({1e3 * wall / n_views:.0f} ms/view); "
            f"peak traced memory {peak / 2**20:.0f} MiB; {nbytes / 1e6:.1f} MB, "
            f"{len(files)} files",
            f"load average {load_average()}",
        ]
        if kind == "bop":
            row.notes.insert(
                1,
                f"models/ (once per dataset): {n_models} models in {models[0]:.1f} s wall, "
                f"peak {models[2] / 2**20:.0f} MiB",
            )
        rows.append(row)
        shutil.rmtree(again, ignore_errors=True)
    shutil.rmtree(out, ignore_errors=True)
    return rows


def _kinds(folder: Path) -> dict[str, int]:
    """Bytes per file kind (the file name without its view index) of a folder."""
    out: dict[str, int] = {}
    for p in folder.iterdir():
        kind = p.name.lstrip("0123456789")
        out[kind] = out.get(kind, 0) + p.stat().st_size
    return out


def _read_all(folder: Path, index: int) -> None:
    from mgn.io.dataset import View

    v = View(folder, index)
    _ = (v.rgb, v.npz, v.depth_ideal, v.com_heatmap, v.valid_depth, v.hdf5, v.order, v.layout)


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any,
    mgn_status: str,
    log: Callable[[str], None],
    dataset: Path | None = None,
    coco: bool = True,
    exports: bool = True,
) -> list[Row]:
    from .bench_pipeline import bench_config

    cfg = bench_config(quick)
    size = int(1200 * cfg["camera"]["resolution_scale"])
    n_views = len(cfg["camera"]["views"] or range(37))
    row = Row(
        group="dataset files",
        case=f"write one view's files, {cfg['objects']['count']} objects at {size}x{size}",
        n=1,
        unit="views/s",
        peer_name="previous mgn layout (all arrays in the npz, float32 ids)",
    )
    if mgn is None:
        row.mgn_status = row.peer_status = mgn_status
        return [row]
    from mgn.io.dataset import Dataset
    from mgn.io.scene_folder import write_view
    from mgn.pipeline import generate
    from mgn.pipeline.config import load_config

    root = bench_tempdir("mgn_bench_format_")
    if dataset is None:
        log(f"  format: generating one scene ({n_views} views at {size} px), load {load_average()}")
        report = generate(root / "ds", 1, config=load_config(cfg), seed=SEED, progress=False)
        if not report.complete:
            err = report.failed[0].error if report.failed else "?"
            row.mgn_status = f"generation failed: {err}"
            return [row]
        ds_root = root / "ds"
    else:
        ds_root = dataset
    scene = Dataset(ds_root).scene(0)
    n_views = len(scene.view_ids)
    dirs = {name: root / name for name in ("new", "archival", "old")}
    for d in dirs.values():
        d.mkdir()
    walls: dict[str, list[float]] = {"new": [], "archival": [], "old": [], "read": []}
    cpus: dict[str, list[float]] = {k: [] for k in walls}
    identical = True
    com_parameters = _com_parameters(scene.folder)
    for k, v in enumerate(scene.view_ids):
        rec = _record(scene.view(v), com_parameters)
        sides = [
            ("new", lambda r=rec: write_view(dirs["new"], r)),
            ("archival", lambda r=rec: write_view(dirs["archival"], r, archival=True)),
            ("old", lambda r=rec: _write_legacy(dirs["old"], r)),
        ]
        for name, fn in sides if k % 2 == 0 else sides[::-1]:
            t, c = time.perf_counter(), time.process_time()
            fn()
            walls[name].append(time.perf_counter() - t)
            cpus[name].append(time.process_time() - c)
        t, c = time.perf_counter(), time.process_time()
        _read_all(dirs["new"], v)
        walls["read"].append(time.perf_counter() - t)
        cpus["read"].append(time.process_time() - c)
        # Both layouts hold the same arrays, bit for bit.
        identical &= _same_arrays(dirs["new"], dirs["old"], v, rec)
    scene_files = sum((scene.folder / n).stat().st_size for n in ("scene_gt.json", "scene.json"))
    kinds = {name: _kinds(d) for name, d in dirs.items()}
    per_scene = {name: sum(kk.values()) + scene_files for name, kk in kinds.items()}
    row.mgn[1] = Timing(wall=walls["new"], cpu=cpus["new"])
    row.peer = Timing(wall=walls["old"], cpu=cpus["old"])
    row.agreement = "same arrays, bit for bit" if identical else "DIFFERENT arrays"
    row.agreement_ok = identical
    scale = 37 / n_views

    def mb(x: float) -> str:
        return f"{x * scale / 1e6:.1f}"

    order = sorted(kinds["new"], key=lambda kk: -kinds["old"].get(kk, kinds["new"][kk]))
    split = ", ".join(
        f"{kk} {mb(kinds['new'][kk])} (archival {mb(kinds['archival'].get(kk, 0))}, "
        f"previous {mb(kinds['old'].get(kk, 0))})"
        for kk in order
        if kinds["new"][kk] * scale > 1e5
    )
    med = {name: 1e3 * float(np.median(w)) for name, w in walls.items()}
    med_cpu = {name: 1e3 * float(np.median(c)) for name, c in cpus.items()}
    row.notes = [
        f"{mb(per_scene['new'])} MB per 37-view scene (archival {mb(per_scene['archival'])} MB, "
        f"previous layout {mb(per_scene['old'])} MB)",
        f"MB per scene by file kind: {split}",
        f"write {med['new']:.0f} ms/view wall, {med_cpu['new']:.0f} ms CPU (archival "
        f"{med['archival']:.0f} / {med_cpu['archival']:.0f}, previous {med['old']:.0f} / "
        f"{med_cpu['old']:.0f}); read every array {med['read']:.0f} ms/view wall, "
        f"{med_cpu['read']:.0f} ms CPU",
        f"load average {load_average()}",
    ]
    rows = [row]
    if coco:
        rows.append(_coco_row(ds_root, n_views, size, cfg["objects"]["count"]))
    if exports:
        rows += _export_rows(ds_root, n_views, size, cfg["objects"]["count"])
    shutil.rmtree(root, ignore_errors=True)
    return rows


def main(argv: list[str] | None = None) -> int:
    import argparse

    p = argparse.ArgumentParser(prog="python -m benchmarks.bench_format")
    p.add_argument("--quick", action="store_true")
    p.add_argument("--dataset", type=Path, default=None, help="measure scene 0 of this dataset")
    p.add_argument("--no-coco", action="store_true", help="skip the COCO export row")
    p.add_argument("--no-exports", action="store_true", help="skip the BOP / GraspNet rows")
    p.add_argument(
        "--only-exports",
        action="store_true",
        help="only the BOP / GraspNet rows (of --dataset's scene 0)",
    )
    a = p.parse_args(sys.argv[1:] if argv is None else argv)
    from .common import import_mgn

    mgn, status = import_mgn()
    if a.only_exports:
        if a.dataset is None or mgn is None:
            p.error("--only-exports needs --dataset and a built mgn")
        from mgn.io.dataset import Dataset

        scene = Dataset(a.dataset).scene(0)
        objects = len((scene.scene_json or {}).get("instances", []))
        size = int(scene.views()[0].intrinsics.width)
        rows = _export_rows(a.dataset, len(scene.view_ids), size, objects)
    else:
        rows = run(
            quick=a.quick,
            repeats=1,
            mgn=mgn,
            mgn_status=status,
            log=print,
            dataset=a.dataset,
            coco=not a.no_coco,
            exports=not a.no_exports,
        )
    for row in rows:
        print(row.case, "|", row.agreement, "|", "\n  ".join(row.notes) or row.mgn_status)
    return 0


if __name__ == "__main__":
    sys.exit(main())
