"""Scaling on a Dask cluster: scenes per hour of `mgn generate --scheduler` on a local Dask
cluster of 1, 2 and 4 worker processes, and the scaling efficiency against 1 worker.

Each worker count gets a fresh `distributed.LocalCluster` (one thread per worker process, a
memory limit per worker) started inside the timed run, because starting the cluster is part of
what a user pays. The object labels are computed (and cached) by a warm-up run first, so the
timed runs measure the scene tasks. The same seed is used for every worker count and the
per-file SHA-256 of every scene (its manifest) must be identical across the runs: the
"deterministic bytes" check.

Affordability: the scenes are small (``SCENE_CONFIG``: 6-9 objects of three categories, 3 views at
240 x 240 px, tiny object labels), 40 per worker count. They measure the scheduling overhead
and the scaling of the scene tasks, not the speed of full-size scenes (`bench_pipeline` does
that). On a machine with C
cores, K > C workers cannot scale beyond C: the efficiency is reported against K and against
min(K, C).

Run alone: `python -m benchmarks.bench_cluster [--scenes 40] [--workers 1 2 4]`.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .common import Row, Timing, bench_tempdir, load_average

HERE = Path(__file__).resolve().parent
SEED = 7
SCENES = 40
WORKERS = (1, 2, 4)
MEMORY_LIMIT = "1.5GiB"
SCENE_CONFIG: dict[str, Any] = {
    # Three categories, 2-3 copies each: the warm-up run computes every object label and convex
    # decomposition the timed runs need (none of them pays for a cache miss).
    "objects": {"categories": ["box_tea", "can_soda", "box_cereal"], "copies": [2, 3]},
    "camera": {"views": [0, 5, 17], "resolution_scale": 0.2},
    "object_labels": {
        "suction_points": 200,
        "pj_points": 200,
        "physics_grasps": 4,
        "physics_grid": 2,
    },
    "drop": {"max_time": 2.0},
}


def _digests(out: Path) -> dict[str, dict[str, str]]:
    """scene folder -> {file: sha256} from the manifests."""
    res = {}
    for m in sorted(out.glob("scene*/manifest.json")):
        files = json.loads(m.read_text())["files"]
        res[m.parent.name] = {k: v["sha256"] for k, v in files.items()}
    return res


def child_main(argv: list[str]) -> int:
    """One timed run on a fresh LocalCluster of K workers; prints one JSON line."""
    p = argparse.ArgumentParser()
    p.add_argument("--scenes", type=int, required=True)
    p.add_argument("--workers", type=int, required=True)
    p.add_argument("--out", type=Path, required=True)
    a = p.parse_args(argv)
    from distributed import LocalCluster

    from mgn.pipeline import generate
    from mgn.pipeline.config import load_config

    config = load_config(SCENE_CONFIG)
    t0 = time.perf_counter()
    with LocalCluster(
        n_workers=a.workers,
        threads_per_worker=1,
        processes=True,
        memory_limit=MEMORY_LIMIT,
        dashboard_address=None,
    ) as cluster:
        t_up = time.perf_counter() - t0
        report = generate(
            a.out,
            a.scenes,
            config=config,
            seed=SEED,
            scheduler=cluster.scheduler_address,
            progress=False,
        )
        wall = time.perf_counter() - t0 - report.label_seconds
        peak = 0.0
        try:
            from distributed import Client

            with Client(cluster.scheduler_address) as client:
                info = client.scheduler_info()["workers"]
                peak = max(w.get("metrics", {}).get("memory", 0) for w in info.values()) / 2**20
        except Exception:  # the memory figure is informative only
            pass
    print(
        json.dumps(
            {
                "scenes": a.scenes,
                "ok": len(report.ok),
                "workers": a.workers,
                "wall_s": wall,
                "cluster_start_s": t_up,
                "label_s": report.label_seconds,
                "worker_memory_mib_at_end": peak,
                "load": os.getloadavg(),
                "failed": [r.error for r in report.failed],
            }
        )
    )
    return 0


def _run_child(scenes: int, workers: int, out: Path) -> tuple[dict | None, str]:
    cmd = [
        sys.executable,
        "-m",
        "benchmarks.bench_cluster",
        "--child",
        "--scenes",
        str(scenes),
        "--workers",
        str(workers),
        "--out",
        str(out),
    ]
    env = dict(os.environ)
    proc = subprocess.run(
        cmd, cwd=HERE.parent, check=False, capture_output=True, text=True, env=env
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
    scenes: int = SCENES,
    workers: tuple[int, ...] = WORKERS,
) -> list[Row]:
    """One row per worker count: scenes per second (n = scenes per run)."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        mgn, mgn_status = None, "needs dask distributed (pip install 'mgn[cluster]')"
    if quick:
        scenes = min(scenes, 12)
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:
        cores = os.cpu_count() or 1
    root = bench_tempdir("mgn_bench_cluster_")
    os.environ.setdefault("MGN_CACHE_DIR", str(root / "cache"))
    rows: list[Row] = []
    if mgn is not None:
        log("  cluster: warm-up (object labels into the cache)")
        _run_child(2, 1, root / "warm")
    base_rate = None
    reference: dict[str, dict[str, str]] | None = None
    for k in workers:
        row = Row(
            group="dataset generation",
            case=f"mgn generate on a local Dask cluster, {k} worker process(es), small scenes",
            n=scenes,
            unit="scenes/s",
            peer_name="—",
            peer_status="no peer: its own 1-worker run is the reference",
        )
        rows.append(row)
        if mgn is None:
            row.mgn_status = mgn_status
            continue
        out = root / f"ds{k}"
        log(f"  cluster: {scenes} scenes on {k} worker(s), load {load_average()}")
        result, status = _run_child(scenes, k, out)
        if result is None:
            row.mgn_status = status
            continue
        rate = result["ok"] / result["wall_s"]
        base_rate = rate if k == 1 else base_rate
        row.mgn[k] = Timing(wall=[result["wall_s"]], cpu=[result["wall_s"]])
        digests = _digests(out)
        if reference is None:
            reference = digests
            same = "reference"
        else:
            same = "identical" if digests == reference else "DIFFERENT"
        row.agreement = f"scene bytes {same} to the first run"
        row.agreement_ok = same != "DIFFERENT"
        row.notes = [
            f"{3600 * rate:.0f} scenes/hour",
            f"cluster start {result['cluster_start_s']:.1f} s (included)",
            f"load {', '.join(f'{x:.1f}' for x in result['load'])} at the end",
            f"worker memory limit {MEMORY_LIMIT}",
        ]
        if result["failed"]:
            row.notes.append(f"{len(result['failed'])} failed: {result['failed'][0]}")
        if base_rate and k > 1:
            eff = rate / (k * base_rate)
            eff_c = rate / (min(k, cores) * base_rate)
            row.notes.append(
                f"scaling efficiency {100 * eff:.0f} % of {k}x "
                f"({100 * eff_c:.0f} % of the {min(k, cores)}x this {cores}-core machine allows)"
            )
        shutil.rmtree(out, ignore_errors=True)
    return rows


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if args and args[0] == "--child":
        return child_main(args[1:])
    p = argparse.ArgumentParser(prog="python -m benchmarks.bench_cluster")
    p.add_argument("--scenes", type=int, default=SCENES)
    p.add_argument("--workers", type=int, nargs="+", default=list(WORKERS))
    a = p.parse_args(args)
    from .common import import_mgn

    mgn, status = import_mgn()
    rows = run(
        quick=False,
        repeats=1,
        mgn=mgn,
        mgn_status=status,
        log=print,
        scenes=a.scenes,
        workers=tuple(a.workers),
    )
    for row in rows:
        print(row.case, "|", row.agreement, "|", "; ".join(row.notes) or row.mgn_status)
    return 0


if __name__ == "__main__":
    sys.exit(main())
