"""Dataset generation: complete scenes per hour of `mgn generate`, time per stage, peak memory.

The issue's target: scenes of 20 objects, 37 views at 1200 x 1200, all labels, at least 60 scenes
per hour on 2 cores. The run happens in a fresh subprocess (`generate(..., workers=K)`) after a
warm-up scene there (imports, convex decompositions); object labels missing from the cache are
computed before any scene starts and their time (`GenerateReport.label_seconds`) is subtracted,
so the rate counts the scene tasks only: drop, render, per-view object labels, layout, scene
grasps, writing, and finalising (manifest + rename). Object labels are computed once per object
and cached, never per scene. Their size is the README demo's (2000 suction and parallel-jaw
candidates, 30 shaken grasps per object): a scene places at most 2000 grasps of each kind per
object either way (LabelOptions.max_grasps_per_object), so it costs what it costs with the MGN
label sizes. One timed run per worker count (4 scenes each; ~5 min in all when idle).

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


def bench_config(quick: bool) -> dict[str, Any]:
    """20 objects, 37 views at 1200 x 1200, all labels (quick: 10 objects, 5 views at 600 x 600)."""
    return {
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


def child_main(argv: list[str]) -> int:
    """Generate in this process tree and print one JSON line of measurements."""
    p = argparse.ArgumentParser()
    p.add_argument("--scenes", type=int, required=True)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--quick", action="store_true")
    a = p.parse_args(argv)
    from mgn.pipeline import generate
    from mgn.pipeline.config import load_config

    config = load_config(bench_config(a.quick))
    with tempfile.TemporaryDirectory() as tmp:
        generate(Path(tmp) / "warm", 1, config=config, seed=SEED + 1, progress=False)
        t0 = time.perf_counter()
        report = generate(
            Path(tmp) / "ds", a.scenes, config=config, seed=SEED, workers=a.workers, progress=False
        )
        # Object labels missing from the cache are computed before any scene starts: their
        # time (report.label_seconds) is not scene time.
        wall = time.perf_counter() - t0 - report.label_seconds
        rss_self = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        rss_children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
        out = {
            "scenes": a.scenes,
            "ok": len(report.ok),
            "workers": a.workers,
            "wall_s": wall,
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


def _run_child(scenes: int, workers: int, quick: bool) -> tuple[dict | None, str]:
    cmd = [sys.executable, "-m", "benchmarks.bench_pipeline", "--child"]
    cmd += ["--scenes", str(scenes), "--workers", str(workers)] + (["--quick"] if quick else [])
    proc = subprocess.run(cmd, cwd=HERE.parent, capture_output=True, text=True, env=os.environ)
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
    for workers in (1, 2):
        row = Row(
            group="dataset generation",
            case=(
                f"mgn generate, {cfg['objects']['count']} objects, {views} views at "
                f"{size}x{size}, {workers} worker(s)"
            ),
            n=scenes,
            unit="scenes/s",
            peer_name="—",
            peer_status="no peer (no other CPU MetaGraspNet generator)",
        )
        if mgn is None:
            row.mgn_status = mgn_status
            rows.append(row)
            continue
        log(f"  pipeline: {scenes} scenes, {workers} worker(s)")
        walls, notes = [], []
        for _ in range(1):  # one run of `scenes` scenes: minutes each
            result, status = _run_child(scenes, workers, quick)
            if result is None:
                row.mgn_status = status
                break
            walls.append(result["wall_s"])
            st = result["stage_s"]
            per = {k: v / max(result["ok"], 1) for k, v in st.items()}
            notes = [
                f"{3600 * result['ok'] / result['wall_s']:.0f} scenes/hour",
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
            row.mgn[workers] = Timing(wall=walls, cpu=walls)
            row.notes = notes
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
