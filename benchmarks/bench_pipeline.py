"""Dataset generation: complete scenes per hour of `mgn generate`, time per stage, peak memory.

Target: scenes of 20 objects, 37 views at 1200 x 1200, all labels, at least 60 scenes per hour
on 2 cores. The run happens in a fresh subprocess (`generate(..., workers=K)`) after a
warm-up scene there (imports, convex decompositions); object labels missing from the cache are
computed before any scene starts and their time (`GenerateReport.label_seconds`) is subtracted,
so the rate counts the scene tasks only: drop, render, per-view object labels, layout, scene
grasps, writing, and finalising (manifest + rename). Object labels are computed once per object
and cached, never per scene. Their size is the README demo's (2000 suction and parallel-jaw
candidates, 30 shaken grasps per object): a scene places at most 2000 grasps of each kind per
object either way (LabelOptions.max_grasps_per_object), so it costs what it costs with the MGN
label sizes. One timed run per worker count (4 scenes each; ~5 min in all when idle), then one
scene with the path engine at the demo's setting (1 sample per pixel + OIDN's fast filter; target:
<= 150 s for a 37-view scene with every label on 2 cores; ~5 min with its warm-up).

CPU per scene is each worker process's CPU over its scene (all its threads: OSMesa, parallel
loops, the writer threads), recorded by `run_scene`; the label cache is filled before the timed
run. A last row runs the stages of scene 0 one after the other (`--child --stages`) and gives the
CPU and wall seconds of each: drop, ray model, scene grasp collisions, render, object labels,
layout, scene grasps, write.

With one worker (in-process) the drop of scene k + 1 runs in a thread alongside the labelling
of scene k, so the "drop" seconds of that row are the time spent waiting for the drop and a
scene's CPU includes the next scene's drop (the sum over the scenes is the run's CPU). The
stage-by-stage row is the one to read for the CPU of each stage.

Peak memory per worker is ru_maxrss of the largest worker process (RUSAGE_CHILDREN for a pool,
RUSAGE_SELF in-process). There is no peer program that makes MetaGraspNet scenes on the CPU, so
the rows have no peer column.

Run alone: `python -m benchmarks.bench_pipeline [--quick]`.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .common import Row, Timing, load_average

HERE = Path(__file__).resolve().parent
SEED = 2024


def bench_config(quick: bool, engine: str = "raster") -> dict[str, Any]:
    """20 objects, 37 views at 1200 x 1200, all labels (quick: 10 objects, 5 views at 600 x 600);
    engine "path": the README demo's photographs (1 sample per pixel + OIDN's fast filter)."""
    render = {"engine": "path", "spp": 1} if engine == "path" else {"engine": "raster"}
    return {
        "render": render,
        "objects": {"count": 10 if quick else 20},
        "camera": {
            "views": [0, 5, 14, 27, 36] if quick else None,
            "resolution_scale": 0.5 if quick else 1.0,
        },
        "object_labels": {
            "suction_points": 2000,
            "pj_points": 2000,
            "physics_grasps": 30,
            "physics_grid": 5,
        },
    }


def _substages(report: Any) -> dict[str, float]:
    out: dict[str, float] = {}
    for r in report.results.values():
        for k, v in r.times.items():
            if k.startswith("write: "):
                out[k[len("write: ") :]] = out.get(k[len("write: ") :], 0.0) + v
    return out


def _cpu_seconds() -> float:
    """User + system CPU seconds of this process (all threads) and of its waited-for children."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def _cache_labels(config: Any, scenes: int) -> None:
    """Puts the object labels of scenes 0..scenes-1 (seed SEED) in the cache, so the timed run
    spends its CPU on scenes only."""
    from mgn.pipeline.label_cache import object_labels
    from mgn.pipeline.sanity import load_catalogue
    from mgn.pipeline.seeds import scene_seed
    from mgn.pipeline.testset import compose_scene, resolve_split

    catalogue = list(load_catalogue(config).specs)
    split = resolve_split(config, catalogue)
    for i in range(scenes):
        for spec in compose_scene(config, catalogue, scene_seed(SEED, i), split):
            object_labels(spec, config)


def stage_cpu(config: Any) -> dict[str, Any]:
    """CPU and wall seconds per stage of one scene (seed SEED, scene 0), the stages run one
    after the other in this process (C++ stages with their default threads): drop, the two
    per-scene preparations, then per view render (raster + depth sensor), object labels,
    layout, scene grasps and write (encode + files). The CPU of a stage is this process's
    getrusage difference around it, so it counts every thread the stage uses (OSMesa's
    llvmpipe threads, parallel loops)."""
    import numpy as np

    from mgn.io.scene_folder import scene_gt_entries, write_view
    from mgn.objects import tote_mesh
    from mgn.pipeline.label_cache import object_labels
    from mgn.pipeline.label_scene import strided_subset, view_grasps, view_record
    from mgn.pipeline.sanity import load_catalogue
    from mgn.pipeline.scene_writer import scene_views
    from mgn.pipeline.seeds import scene_seed
    from mgn.pipeline.testset import compose_scene, resolve_split
    from mgn.render.views import iter_views
    from mgn.scene.drop import drop_scene
    from mgn.view_labels.grasps import SceneGraspModel
    from mgn.view_labels.layout import OCCLUSION_DECIMALS, compute_layout
    from mgn.view_labels.objects import (
        SceneRayModel,
        round_occlusion,
        seen_objects,
        view_object_labels,
    )

    stages: dict[str, list[float]] = {}
    write_parts: dict[str, float] = {}  # CPU-s of the writer per part (write_view's ``times``)

    def timed(stage: str, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
        t0, c0 = time.perf_counter(), _cpu_seconds()
        out = fn(*args, **kwargs)
        acc = stages.setdefault(stage, [0.0, 0.0])
        acc[0] += time.perf_counter() - t0
        acc[1] += _cpu_seconds() - c0
        return out

    with tempfile.TemporaryDirectory() as tmp:
        # The objects of scene 0 of `generate(..., seed=SEED)`.
        catalogue = list(load_catalogue(config).specs)
        seed = scene_seed(SEED, 0)
        picked = compose_scene(config, catalogue, seed, resolve_split(config, catalogue))
        labels = {s.name: object_labels(s, config) for s in picked}
        scene = timed("drop", drop_scene, picked, seed=seed, tote=config.tote, options=config.drop)
        got = [labels[inst.name] for inst in scene.instances]
        rays = timed("prepare: ray model", SceneRayModel.from_scene, scene)
        pj = [strided_subset(g.paralleljaw, 2000) for g in got]
        su = [strided_subset(g.suction, 2000) for g in got]
        # As label_scene: the files need each grasp's first colliding pose only.
        sgm = timed(
            "prepare: scene grasp collisions",
            SceneGraspModel,
            scene,
            pj,
            su,
            config.gripper,
            config.cup,
            first_collision_only=True,
        )
        views = scene_views(scene, config.camera)
        cats = np.array([i.category_id for i in scene.instances], np.int64)
        bins = [i.bin_relation for i in scene.instances]
        frames = iter_views(
            scene.render_items(),
            tote_mesh(scene.tote),
            views,
            sensor=config.camera.sensor,
            seed=seed,
        )
        out = Path(tmp)
        for v, view in views:
            images = timed("render", next, frames)
            lab = timed(
                "object labels",
                view_object_labels,
                rays,
                view,
                images.instance_ids,
                depth=images.depth_ideal,
            )
            lab, index = seen_objects(round_occlusion(lab, OCCLUSION_DECIMALS))
            lay = timed(
                "layout",
                compute_layout,
                lab.visible,
                lab.amodal,
                images.depth_ideal,
                cats[index],
                [bins[i] for i in index],
                occlusion=lab.occlusion,
            )
            gr = timed("scene grasps", view_grasps, sgm, view, index, len(scene.instances))
            scene_gt_entries(lab.X_CO, cats[index])
            record = view_record(
                v, view, images, lab, lay, gr, rays.com_parameters()[index], instance_ids=index + 1
            )
            timed("write", write_view, out, record, times=write_parts)
    return {
        "objects": len(scene.instances),
        "views": len(views),
        "stages": {k: {"wall_s": w, "cpu_s": c} for k, (w, c) in stages.items()},
        "write_parts_cpu_s": write_parts,
    }


def child_main(argv: list[str]) -> int:
    """Generate in this process tree and print one JSON line of measurements."""
    p = argparse.ArgumentParser()
    p.add_argument("--scenes", type=int, required=True)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--quick", action="store_true")
    p.add_argument("--stages", action="store_true")
    p.add_argument("--engine", choices=["raster", "path"], default="raster")
    a = p.parse_args(argv)
    from mgn.pipeline import generate
    from mgn.pipeline.config import load_config

    config = load_config(bench_config(a.quick, a.engine))
    if a.stages:
        print(json.dumps(stage_cpu(config)))
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        generate(Path(tmp) / "warm", 1, config=config, seed=SEED + 1, progress=False)
        _cache_labels(config, a.scenes)
        t0 = time.perf_counter()
        report = generate(
            Path(tmp) / "ds", a.scenes, config=config, seed=SEED, workers=a.workers, progress=False
        )
        # Object labels missing from the cache are computed before any scene starts: their
        # time (report.label_seconds) is not scene time.
        wall = time.perf_counter() - t0 - report.label_seconds
        # CPU of the scene tasks: each worker process's CPU over its scene (all its threads).
        cpu = sum(r.times.get("cpu", 0.0) for r in report.results.values())
        rss_self = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        rss_children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
        out = {
            "scenes": a.scenes,
            "ok": len(report.ok),
            "workers": a.workers,
            "wall_s": wall,
            "cpu_s": cpu,
            "label_s": report.label_seconds,
            "stage_s": report.stage_seconds(),
            # The labelling stages inside "write" (render, object labels, layout, scene grasps,
            # waiting for the file writers, ...), summed over the scenes.
            "substage_s": _substages(report),
            "objects_per_scene": [r.num_objects for r in report.ok],
            "bytes_per_scene": report.output_bytes / max(a.scenes, 1),
            "peak_rss_worker_mib": rss_children if a.workers > 1 else rss_self,
            "failed": [r.error for r in report.failed],
        }
    print(json.dumps(out))
    return 0


def _run_child(
    scenes: int, workers: int, quick: bool, stages: bool = False, engine: str = "raster"
) -> tuple[dict | None, str]:
    cmd = [sys.executable, "-m", "benchmarks.bench_pipeline", "--child"]
    cmd += ["--scenes", str(scenes), "--workers", str(workers)] + (["--quick"] if quick else [])
    cmd += (["--stages"] if stages else []) + ["--engine", engine]
    proc = subprocess.run(
        cmd, cwd=HERE.parent, check=False, capture_output=True, text=True, env=os.environ
    )
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or ["?"])[-1]
        return None, f"failed ({last})"
    return json.loads(proc.stdout.strip().splitlines()[-1]), ""


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any,
    mgn_status: str,
    log: Callable[[str], None],
) -> list[Row]:
    """One row per worker count: scenes per hour (n = scenes per timed run)."""
    scenes = 4  # a full-mode run takes ~3 + 2 min (1 and 2 workers) on an idle machine
    cfg = bench_config(quick)
    views = len(cfg["camera"]["views"] or range(37))
    size = int(1200 * cfg["camera"]["resolution_scale"])
    rows = []
    # The raster engine at 1 and 2 workers, then one scene with the path engine (target: a
    # 37-view scene with path-traced pictures and every label in <= 150 s on 2 cores).
    for workers, engine, n_scenes in ((1, "raster", scenes), (2, "raster", scenes), (1, "path", 1)):
        what = "" if engine == "raster" else ", path engine (1 spp + OIDN fast)"
        row = Row(
            group="dataset generation",
            case=(
                f"mgn generate, {cfg['objects']['count']} objects, {views} views at "
                f"{size}x{size}, {workers} worker(s){what}"
            ),
            n=n_scenes,
            unit="scenes/s",
            peer_name="—",
            peer_status="no peer (no other CPU MetaGraspNet generator)",
        )
        if mgn is None:
            row.mgn_status = mgn_status
            rows.append(row)
            continue
        log(f"  pipeline: {n_scenes} scene(s), {workers} worker(s), {engine} engine")
        walls, cpus, notes = [], [], []
        for _ in range(1):  # one run of `n_scenes` scenes: minutes each
            result, status = _run_child(n_scenes, workers, quick, engine=engine)
            if result is None:
                row.mgn_status = status
                break
            walls.append(result["wall_s"])
            cpus.append(result.get("cpu_s", result["wall_s"]))
            st = result["stage_s"]
            per = {k: v / max(result["ok"], 1) for k, v in st.items()}
            notes = [
                f"{3600 * result['ok'] / result['wall_s']:.0f} scenes/hour",
                f"{result['wall_s'] / max(result['ok'], 1):.1f} s wall and "
                f"{result.get('cpu_s', 0.0) / max(result['ok'], 1):.1f} CPU-s per scene",
                "per scene " + ", ".join(f"{k} {v:.1f} s" for k, v in per.items()),
                "inside write, per scene: "
                + ", ".join(
                    f"{k} {v / max(result['ok'], 1):.1f} s"
                    for k, v in result.get("substage_s", {}).items()
                ),
                f"load average {load_average()}",
                f"peak RSS per worker {result['peak_rss_worker_mib']:.0f} MiB",
                f"{result['bytes_per_scene'] / 1e6:.1f} MB per scene",
            ]
        if walls:
            row.mgn[workers] = Timing(wall=walls, cpu=cpus)
            row.notes = notes
        rows.append(row)
    if mgn is not None:
        log("  pipeline: stages of one scene, one after the other")
        result, status = _run_child(1, 1, quick, stages=True)
        row = Row(
            group="dataset generation",
            case=f"stages of one scene ({cfg['objects']['count']} objects, {views} views at "
            f"{size}x{size}), run one after the other",
            n=1,
            unit="scenes/s",
            peer_name="—",
            peer_status="no peer (no other CPU MetaGraspNet generator)",
        )
        if result is None:
            row.mgn_status = status
        else:
            st = result["stages"]
            wall = sum(v["wall_s"] for v in st.values())
            cpu = sum(v["cpu_s"] for v in st.values())
            row.mgn[1] = Timing(wall=[wall], cpu=[cpu])
            row.notes = [
                "CPU-s (wall s) per stage: "
                + ", ".join(f"{k} {v['cpu_s']:.1f} ({v['wall_s']:.1f})" for k, v in st.items()),
                "inside write, CPU-s: "
                + ", ".join(f"{k} {v:.1f}" for k, v in result.get("write_parts_cpu_s", {}).items()),
                f"total {cpu:.1f} CPU-s ({wall:.1f} s wall) for {result['objects']} objects",
                f"load average {load_average()}",
            ]
        rows.append(row)
    return rows


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if args and args[0] == "--child":
        return child_main(args[1:])
    p = argparse.ArgumentParser(prog="python -m benchmarks.bench_pipeline")
    p.add_argument("--quick", action="store_true")
    a = p.parse_args(args)
    from .common import import_mgn

    mgn, status = import_mgn()
    for row in run(quick=a.quick, repeats=1, mgn=mgn, mgn_status=status, log=print):
        print(row.case, "|", "; ".join(row.notes) or row.mgn_status)
    return 0


if __name__ == "__main__":
    sys.exit(main())
