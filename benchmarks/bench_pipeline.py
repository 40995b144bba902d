"""Dataset generation: complete scenes per hour of `mgn generate`, time per stage, peak memory.

The issue's target: scenes of 20 objects, 37 views at 1200 x 1200, at least 60 scenes per hour on
2 cores. The run happens in a fresh subprocess (`generate(..., workers=K)`), after one warm-up
scene there (imports, convex decompositions and object labels cached), so the rate counts the
scene tasks only: drop, write (today: scene.json + rendered views; the full FORMAT.md writer of
the integrator will add the per-view labels) and finalise (manifest + rename). Object labels are
switched off here: they are computed once per object and cached, never per scene.

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

from .common import Row, Timing

HERE = Path(__file__).resolve().parent
SEED = 2024


def bench_config(quick: bool) -> dict[str, Any]:
    """20 objects, 37 views at 1200 x 1200 (quick: 10 objects, 5 views at 600 x 600)."""
    return {
        "objects": {"count": 10 if quick else 20},
        "camera": {
            "views": [0, 5, 14, 27, 36] if quick else None,
            "resolution_scale": 0.5 if quick else 1.0,
        },
        "labels": {"suction": False, "paralleljaw": False, "pj_physics": False},
    }


def child_main(argv: list[str]) -> int:
    """Generate in this process tree and print one JSON line of measurements."""
    p = argparse.ArgumentParser()
    p.add_argument("--scenes", type=int, required=True)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--quick", action="store_true")
    a = p.parse_args(argv)
    from mgn.config import load_config
    from mgn.pipeline import generate

    config = load_config(bench_config(a.quick))
    with tempfile.TemporaryDirectory() as tmp:
        generate(Path(tmp) / "warm", 1, config=config, seed=SEED + 1, progress=False)
        t0 = time.perf_counter()
        report = generate(
            Path(tmp) / "ds", a.scenes, config=config, seed=SEED, workers=a.workers, progress=False
        )
        wall = time.perf_counter() - t0
        rss_self = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        rss_children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
        out = {
            "scenes": a.scenes,
            "ok": len(report.ok),
            "workers": a.workers,
            "wall_s": wall,
            "stage_s": report.stage_seconds(),
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
    scenes = 4 if quick else 10
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
        for _ in range(max(1, min(repeats, 2))):
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
