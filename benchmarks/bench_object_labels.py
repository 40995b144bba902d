"""Object labels without physics: time to first results for every built-in object.

What `mgn generate` computes once per object before its first scene when the label cache is cold
(mgn.pipeline.label_cache.compute_object_labels with ``labels.pj_physics`` off): the even surface
samples (drawn once, shared), the suction labels (cup-body collision filter, robust seal score,
wrench score) and the parallel-jaw labels (antipodal probes, up to 50 collision-checked approaches
per accepted probe, wrench score), at the MetaGraspNet sizes (5000 suction and 5000 parallel-jaw
points). Target: <= 3 s per object on 2 idle cores.

Each object is labelled once per thread count (the labels take seconds; the warm-up would double
the run); wall and process CPU seconds are reported per object, with the load average, since on
a shared machine the wall time is pessimistic and the CPU time is the better measure. The labels
with 1 and N threads are compared (they must be identical). There is no peer: MetaGraspNet's own
label scripts take minutes per object.

    python -m benchmarks --only object_labels [--quick]   (quick: 6 objects, 1000 points)
    python -m benchmarks.bench_object_labels [--objects mug,box_cereal] [--points 5000] [--stages]

``--stages`` also times the three stages of the same computation one by one (wall / CPU s): the
shared even surface samples, the suction labels (cup-body collision filter, seal trials, wrench)
and the parallel-jaw labels (antipodal probes, gripper collision filter, wrench), and checks that
the staged labels equal compute_object_labels'.
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import os
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from .common import Row, Timing, thread_counts

QUICK_OBJECTS = ("mug", "box_cereal", "can_food", "wine_glass", "l_bracket", "sack")
TARGET_S = 3.0


def _config(points: int) -> Any:
    from mgn.pipeline.config import Config

    return Config.from_dict(
        {
            "object_labels": {"suction_points": points, "pj_points": points},
            "labels": {"pj_physics": False},
        }
    )


def _same(a: Any, b: Any) -> bool:
    for kind in ("suction", "paralleljaw"):
        x, y = getattr(a, kind), getattr(b, kind)
        for f in dataclasses.fields(x):
            u, v = getattr(x, f.name), getattr(y, f.name)
            if isinstance(u, np.ndarray) and not np.array_equal(u, v, equal_nan=True):
                return False
    return True


def time_object(spec: Any, config: Any, threads: int) -> tuple[Timing, Any]:
    """One timed compute_object_labels call: (Timing with one wall/CPU sample, labels)."""
    from mgn.pipeline.label_cache import compute_object_labels

    gc.collect()
    w0, c0 = time.perf_counter(), time.process_time()
    labels = compute_object_labels(spec, config, num_threads=threads)
    return Timing([time.perf_counter() - w0], [time.process_time() - c0]), labels


def time_stages(spec: Any, config: Any, threads: int) -> tuple[dict[str, Timing], Any]:
    """The stages of compute_object_labels (no physics) timed one by one: ({stage: Timing},
    (suction labels, parallel-jaw labels))."""
    from mgn.geometry.mesh import mass_properties, sample_surface
    from mgn.pj.labels import label_object as pj_label_object
    from mgn.suction.labels import label_object as suction_label_object

    mesh = spec.to_mesh()
    props = mass_properties(mesh, spec.density)
    ol = config.object_labels
    out: dict[str, Timing] = {}

    def timed(name: str, fn: Callable[[], Any]) -> Any:
        gc.collect()
        w0, c0 = time.perf_counter(), time.process_time()
        value = fn()
        out[name] = Timing([time.perf_counter() - w0], [time.process_time() - c0])
        return value

    shared = timed(
        "samples", lambda: sample_surface(mesh, ol.suction_points, method="even", seed=ol.seed)
    )
    common = {
        "mass": props.mass,
        "com": props.center_of_mass,
        "seed": ol.seed,
        "num_threads": threads,
        "samples": shared,
    }
    suction = timed(
        "suction",
        lambda: suction_label_object(
            mesh, cup=config.cup, model=ol.suction_model, num_points=ol.suction_points, **common
        ),
    )
    pj = timed(
        "paralleljaw",
        lambda: pj_label_object(mesh, gripper=config.gripper, num_points=ol.pj_points, **common),
    )
    return out, (suction, pj)


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any | None,
    mgn_status: str,
    log: Callable[[str], None],
) -> list[Row]:
    del repeats  # one call per object and thread count (see the module docstring)
    threads = thread_counts()
    points = 1000 if quick else 5000
    rows: list[Row] = []
    if mgn is None:
        return [
            Row(
                group="object labels",
                case="every built-in object, labels without physics",
                n=1,
                unit="objects/s",
                peer_name="—",
                mgn_status=mgn_status,
                peer_status="no peer",
            )
        ]
    from mgn.objects import builtin_objects

    config = _config(points)
    specs = [s for s in builtin_objects() if not quick or s.name in QUICK_OBJECTS]
    for spec in specs:
        row = Row(
            group="object labels",
            case=f"{spec.name} ({len(spec.faces):,} tri), labels without physics, "
            f"{points} + {points} points",
            n=1,
            unit="objects/s",
            peer_name="—",
            peer_status="no drop-in peer (MetaGraspNet's scripts take minutes per object)",
        )
        results = {}
        for t in threads:
            load = os.getloadavg()[0]
            timing, labels = time_object(spec, config, t)
            row.mgn[t] = timing
            results[t] = labels
            row.notes.append(
                f"{t} thread(s): wall {timing.wall[0]:.2f} s, CPU {timing.cpu[0]:.2f} s "
                f"(load {load:.1f})"
            )
        best = row.mgn[threads[-1]].wall[0]
        n_suction = len(results[threads[-1]].suction.score)
        n_pj = len(results[threads[-1]].paralleljaw.width)
        verdict = (
            f"; target {TARGET_S:.0f} s with {threads[-1]} threads: "
            f"{'met' if best <= TARGET_S else 'not met'} ({best:.2f} s wall)"
            if points == 5000
            else " (the 3 s target is for 5000 + 5000 points)"
        )
        row.notes.append(f"{n_suction:,} suction and {n_pj:,} parallel-jaw labels{verdict}")
        if len(threads) > 1:
            same = _same(results[threads[0]], results[threads[-1]])
            row.notes.append(
                f"labels with {threads[0]} and {threads[-1]} threads "
                + ("identical" if same else "DIFFER")
            )
        log(f"  object labels: {spec.name}: " + "; ".join(row.notes))
        rows.append(row)
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", default="", help="comma-separated names (default: all)")
    ap.add_argument("--points", type=int, default=5000)
    ap.add_argument("--threads", type=int, default=max(thread_counts()))
    ap.add_argument("--stages", action="store_true", help="also time each stage")
    args = ap.parse_args(argv)
    from mgn.objects import builtin_objects

    config = _config(args.points)
    names = set(filter(None, args.objects.split(",")))
    total_wall = total_cpu = 0.0
    for spec in builtin_objects():
        if names and spec.name not in names:
            continue
        load = os.getloadavg()[0]
        timing, labels = time_object(spec, config, args.threads)
        total_wall += timing.wall[0]
        total_cpu += timing.cpu[0]
        print(
            f"{spec.name:18s} wall {timing.wall[0]:6.2f} s  CPU {timing.cpu[0]:6.2f} s  "
            f"load {load:5.1f}  suction {len(labels.suction.score):5d}  "
            f"pj {len(labels.paralleljaw.width):6d}",
            flush=True,
        )
        if args.stages:
            stages, (suction, pj) = time_stages(spec, config, args.threads)
            staged = dataclasses.replace(labels, suction=suction, paralleljaw=pj)
            print(
                "    stages (wall / CPU s): "
                + ", ".join(f"{k} {t.wall[0]:.2f} / {t.cpu[0]:.2f}" for k, t in stages.items())
                + ("; labels identical" if _same(labels, staged) else "; labels DIFFER"),
                flush=True,
            )
    print(f"total wall {total_wall:.1f} s, CPU {total_cpu:.1f} s, {args.threads} threads")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
