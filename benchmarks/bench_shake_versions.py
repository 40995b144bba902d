"""Shake trial rate of this checkout beside an older build of mgn, measured in the same run.

Trials per second depend on the machine as much as on the code (the issue's baseline, 169
trials/s on 2 cores, and session 13's 286/s were measured on other machines than the next
session's), so a speed-up of the trial itself is only meaningful against the older code timed
on the same machine in the same run. This runs bench_shake's MetaGraspNet-grid rows (box, ball,
steel block; 5 grasps x 10 x 10 settings, each build's default ShakeOptions) in a child
process of each interpreter, alternating previous / current for every repeat so that a drift
of the machine hurts both alike, and prints trials/s on 1 and 2 threads (CPU and wall), steps
per trial, the current/previous ratio and the share of identical trial outcomes.

The older build is any virtual environment with mgn installed, e.g. the last commit of v0.1
(f45adcb, the code the issue's baseline was measured with):

    git worktree add /tmp/mgn-v01 f45adcb && cd /tmp/mgn-v01 && python3 -m venv .venv \\
        && .venv/bin/pip install .
    python -m benchmarks.bench_shake_versions --previous /tmp/mgn-v01/.venv/bin/python

Both children import the trial set from this checkout's benchmarks/bench_shake.py (objects and
grasps), so they run the same trials; only mgn differs.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from .common import load_average

REPO = Path(__file__).resolve().parents[1]

# Runs in the child interpreter (either build): one JSON line per (object, threads).
CHILD = r"""
import hashlib, json, sys, time
import numpy as np
import mgn
from mgn.hardware import default_gripper
from mgn.pj.physics import ShakeOptions, shake_scores
sys.path.insert(0, sys.argv[1])
from benchmarks.bench_shake import grasps_for, objects

gripper = default_gripper()
for name, mesh, mass, inertia in objects(mgn):
    width = float(np.ptp(np.asarray(mesh.vertices)[:, 0]))
    grasps = grasps_for(width, int(sys.argv[2]))
    for t in map(int, sys.argv[3].split(",")):
        w0, c0 = time.perf_counter(), time.process_time()
        r = shake_scores(mesh, mass, np.zeros(3), inertia, grasps, gripper,
                         ShakeOptions(num_threads=t))
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        ok = np.asarray(r.trial_success, np.uint8)
        print(json.dumps({"object": name, "threads": t, "trials": int(r.num_trials),
                          "wall": wall, "cpu": cpu, "steps": int(r.total_steps),
                          "success": ok.tolist(), "mgn": mgn.__file__}), flush=True)
"""


def run_child(python: str, grasps: int, threads: str) -> list[dict]:
    """One pass of the child under `python`: its JSON records (raises with its stderr)."""
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)  # each interpreter imports its own mgn
    proc = subprocess.run(
        [python, "-c", CHILD, str(REPO), str(grasps), threads],
        capture_output=True,
        text=True,
        env=env,
        cwd="/",
        check=False,
    )
    if proc.returncode != 0:
        raise SystemExit(f"{python} failed (exit {proc.returncode}):\n{proc.stderr[-2000:]}")
    return [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--previous", required=True, help="python of a venv with the older mgn")
    ap.add_argument("--current", default=sys.executable, help="python of this checkout's mgn")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--grasps", type=int, default=5)
    ap.add_argument("--threads", default="1,2")
    args = ap.parse_args(argv)
    if not Path(args.previous).is_file():
        raise SystemExit(f"--previous {args.previous}: no such interpreter")
    sides = {"previous": args.previous, "current": args.current}
    runs: dict[str, list[list[dict]]] = {k: [] for k in sides}
    print(f"load average at start: {load_average()}")
    for rep in range(args.repeats):
        order = list(sides) if rep % 2 == 0 else list(sides)[::-1]
        for side in order:
            runs[side].append(run_child(sides[side], args.grasps, args.threads))
            print(f"  repeat {rep + 1}/{args.repeats}: {side} done", flush=True)
    for side, python in sides.items():
        print(f"{side}: {python} -> {runs[side][0][0]['mgn']}")
    print(
        "| object | threads | previous trials/s (wall) | current trials/s (wall) | current / "
        "previous | per CPU-s previous / current | steps/trial previous / current | identical "
        "outcomes |"
    )
    print("|---|---:|---:|---:|---:|---|---|---:|")
    for k, rec in enumerate(runs["current"][0]):
        stats = {}
        for side in sides:
            recs = [r[k] for r in runs[side]]
            stats[side] = (
                float(np.median([r["trials"] / r["wall"] for r in recs])),
                float(np.median([r["trials"] / r["cpu"] for r in recs])),
                recs[0]["steps"] / recs[0]["trials"],
                np.asarray(recs[0]["success"]),
            )
        p, c = stats["previous"], stats["current"]
        same = float(np.mean(p[3] == c[3])) if p[3].shape == c[3].shape else float("nan")
        print(
            f"| {rec['object']} | {rec['threads']} | {p[0]:.0f} | {c[0]:.0f} | "
            f"{c[0] / p[0]:.2f}x | {p[1]:.0f} / {c[1]:.0f} | {p[2]:.0f} / {c[2]:.0f} | "
            f"{same:.1%} |",
            flush=True,
        )
    print(f"load average at end: {load_average()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
