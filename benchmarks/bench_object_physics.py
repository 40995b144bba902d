"""Object labels with physics at the defaults: seconds per object, built-in and foreign meshes.

What `mgn generate` computes once per object when the label cache is cold, with every setting at
its default (mgn.pipeline.label_cache.compute_object_labels): even surface samples, suction
labels, the antipodal parallel-jaw sampler, ``object_labels.pj_grasps`` grasps stored (an
evenly strided subset of what the sampler finds) and a physics score for every stored grasp
(the Bullet shake test on MetaGraspNet's 10 x 10 friction x density grid: the first
``physics_calibration`` grasps on the full grid, the others with the search the calibration
chose within ``physics_tolerance``). Target: <= 120 s per object on 2 cores.

Per object: grasps the sampler found and stored, hulls of the shake shape, the chosen search,
its error bound (95 %), shake trials, wall and process CPU seconds. ``--agreement N``
simulates the full grid of N stored grasps after the calibration grasps (evenly strided) and
reports the estimator's actual mean |score - full grid| and identical scores on them (the
calibration grasps are exact by construction). Foreign meshes: public meshes shipped with the
``pybullet`` package (its ``pybullet_data``), at the scales below.

    python -m benchmarks.bench_object_physics [--objects can_soda,duck] [--threads 2]
        [--agreement 20] [--json out.json] [--scores scores.npz] [--calibration-min N]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

#: Foreign meshes from pybullet_data: name -> (file, scale to metres, density kg/m^3).
FOREIGN = {
    "duck": ("duck.obj", 0.05, 300.0),
    "bunny": ("bunny.obj", 0.05, 500.0),
    "torus": ("torus/torus_textured.obj", 0.05, 1000.0),
    "domino": ("domino/domino.obj", 1.0, 700.0),
    "hip_motor": ("laikago/hip_motor.stl", 1.0, 2700.0),
    "teddy": ("teddy2_VHACD_CHs.obj", 0.1, 150.0),
}
TARGET_S = 120.0


def _spec(name: str, folder: Path) -> Any:
    from mgn.objects import get_object
    from mgn.objects.user import load_objects_yaml

    if name not in FOREIGN:
        return get_object(name)
    import pybullet_data

    file, scale, density = FOREIGN[name]
    yaml = folder / f"{name}.yaml"
    yaml.write_text(
        f"objects:\n  - name: {name}\n    mesh: {Path(pybullet_data.getDataPath()) / file}\n"
        f"    scale: {scale}\n    density: {density}\n    friction: 0.6\n"
    )
    return load_objects_yaml(yaml)[0]


def _agreement(
    spec: Any, pj: Any, config: Any, n: int, threads: int, calibrated: int
) -> dict[str, Any]:
    """Full grids of n stored grasps after the ``calibrated`` calibration grasps against their
    stored scores."""
    from mgn.geometry import mass_properties
    from mgn.pj.labels import strided_subset
    from mgn.pj.physics import ShakeOptions, grasp_rows, shake_parts, shake_scores

    rest = np.arange(calibrated, len(pj))
    if n <= 0 or len(rest) == 0:
        return {}
    idx = rest[strided_subset(len(rest), n)]
    mesh = spec.to_mesh()
    props = mass_properties(mesh, spec.density)
    rows = grasp_rows(np.column_stack([pj.approach, pj.closing, pj.p1, pj.width[:, None]])[idx])
    # Each grasp keeps its own random streams (first_grasp_index = its index in the list).
    full = np.empty(len(idx))
    parts = shake_parts(mesh)  # the shape ShakeScorer simulates
    for j, g in enumerate(idx):
        one = shake_scores(
            parts,
            props.mass,
            props.center_of_mass,
            props.inertia,
            rows[j : j + 1],
            None,
            ShakeOptions(
                grid=config.object_labels.physics_grid,
                num_threads=threads,
                first_grasp_index=int(g),
            ),
        )
        full[j] = one.score[0]
    got = np.asarray(pj.quality_score_simulation, np.float64)[idx]
    d = np.abs(got - full)
    return {
        "agreement_grasps": len(idx),
        "mean_abs_error": float(d.mean()),
        "max_abs_error": float(d.max()),
        "identical": float(np.mean(d < 1e-6)),
    }


def run(
    objects: list[str],
    threads: int,
    agreement: int,
    scores: dict[str, Any] | None = None,
    calibration_min: int | None = None,
) -> list[dict[str, Any]]:
    from mgn.pipeline.config import Config
    from mgn.pipeline.label_cache import compute_object_labels
    from mgn.pj.physics import shake_parts

    config = Config()
    if calibration_min is not None:  # the calibration's first stage (0 = one stage of 32)
        config = replace(
            config,
            object_labels=replace(config.object_labels, physics_calibration_min=calibration_min),
        )
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        os.environ.setdefault("MGN_CACHE_DIR", tmp)  # the convex decompositions, not the labels
        for name in objects:
            spec = _spec(name, Path(tmp))
            w0, c0 = time.perf_counter(), time.process_time()
            labels = compute_object_labels(spec, config, threads)
            wall, cpu = time.perf_counter() - w0, time.process_time() - c0
            pj = labels.paralleljaw
            meta = pj.metadata if pj is not None else {}
            est = meta.get("pj_physics_estimator") or {}
            row = {
                "object": name,
                "found": meta.get("pj_num_found", 0),
                "stored": len(pj) if pj is not None else 0,
                "hulls": len(shake_parts(spec.to_mesh())),
                "scored": meta.get("pj_physics_scored", 0),
                "search": est.get("search", meta.get("pj_skipped", "-")),
                "error_bound": est.get("error_bound_95"),
                "trials": meta.get("pj_physics_trials"),
                "calibration_grasps": est.get("calibration_grasps"),
                "wall_s": round(wall, 1),
                "cpu_s": round(cpu, 1),
            }
            if scores is not None and pj is not None:
                scores[name] = np.asarray(pj.quality_score_simulation, np.float32)
            if pj is not None and len(pj):
                calibrated = int(est.get("calibration_grasps") or 0)
                row.update(_agreement(spec, pj, config, agreement, threads, calibrated))
            rows.append(row)
            print(_line(row), flush=True)
    return rows


def _line(r: dict[str, Any]) -> str:
    agree = (
        f" | {r['agreement_grasps']} full grids: mean |d| {r['mean_abs_error']:.4f}, "
        f"identical {r['identical']:.0%}"
        if "agreement_grasps" in r
        else ""
    )
    bound = "-" if r["error_bound"] is None else f"{r['error_bound']:.4f}"
    ok = "ok" if r["wall_s"] <= TARGET_S else "OVER"
    return (
        f"{r['object']:18s} found {r['found']:7d} stored {r['stored']:4d} scored {r['scored']:4d} "
        f"| {r['hulls']:2d} hulls | {r['search']:18s} on {r['calibration_grasps']} "
        f"bound {bound} | trials {r['trials']} "
        f"| {r['wall_s']:6.1f} s wall "
        f"{r['cpu_s']:6.1f} CPU-s {ok}{agree}"
    )


def main(argv: list[str] | None = None) -> int:
    from mgn.objects import builtin_objects

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", help="comma list (default: every built-in and foreign mesh)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--agreement", type=int, default=0, metavar="N")
    ap.add_argument("--json", metavar="FILE")
    ap.add_argument("--scores", metavar="FILE.npz", help="save every object's physics scores")
    ap.add_argument(
        "--calibration-min",
        type=int,
        metavar="N",
        help="object_labels.physics_calibration_min (default: its default; 0 = one stage)",
    )
    args = ap.parse_args(argv)
    names = (
        args.objects.split(",")
        if args.objects
        else [o.name for o in builtin_objects()] + list(FOREIGN)
    )
    scores: dict[str, Any] = {}
    rows = run(names, args.threads, args.agreement, scores, args.calibration_min)
    if args.scores:
        np.savez(args.scores, **scores)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    over = [r["object"] for r in rows if r["wall_s"] > TARGET_S]
    print(
        f"{len(rows) - len(over)} of {len(rows)} objects <= {TARGET_S:.0f} s"
        + (f"; over: {', '.join(over)}" if over else "")
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
