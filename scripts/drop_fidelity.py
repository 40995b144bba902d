"""Fidelity of settled piles: the demo's 12-object scenes dropped once each (no refill).

Per scene: objects lost (left the tote), `max_penetration` and `max_float_gap` of the render
meshes (m, from `scene.json` stats), the rounds of the final separation pass and the drop's
wall-clock seconds. Scene i uses the demo's composition: `compose_objects(count=12)` of the
built-in objects with the seed `scene_seed(0, i)`.

Run: `python scripts/drop_fidelity.py [--scenes 10] [--json out.json]`.
"""

from __future__ import annotations

import argparse
import json
import time

from mgn.objects import builtin_objects
from mgn.pipeline.seeds import scene_seed
from mgn.scene import compose_objects, drop_scene
from mgn.scene.penetration import render_penetration


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=10, help="scenes 0..N-1 (default 10)")
    ap.add_argument("--first", type=int, default=0, help="first scene index (default 0)")
    ap.add_argument("--json", help="write the rows here")
    args = ap.parse_args()
    rows = []
    for i in range(args.first, args.first + args.scenes):
        seed = scene_seed(0, i)
        objects = compose_objects(count=12, seed=seed, catalogue=builtin_objects())
        t = time.perf_counter()
        scene = drop_scene(objects, seed=seed)
        seconds = time.perf_counter() - t
        meshes = [scene.mesh(k) for k in range(len(scene))]
        check = render_penetration(meshes, list(scene.poses), scene.tote)
        row = {
            "scene": i,
            "lost": len(scene.removed),
            "max_penetration_mm": 1e3 * scene.stats["max_penetration"],
            "check_penetration_mm": 1e3 * check,
            "max_float_gap_mm": 1e3 * scene.stats["max_float_gap"],
            "separation_rounds": scene.stats.get("separation_rounds", 0),
            "max_move_mm": 1e3 * scene.stats.get("separation_max_move", 0.0),
            "steps": scene.stats["steps"],
            "seconds": seconds,
        }
        rows.append(row)
        print(json.dumps(row), flush=True)
    summary = {
        "scenes": len(rows),
        "lost": sum(r["lost"] for r in rows),
        "max_penetration_mm": max(r["max_penetration_mm"] for r in rows),
        "scenes_over_1mm": sum(r["max_penetration_mm"] > 1.0 for r in rows),
        "max_float_gap_mm": max(r["max_float_gap_mm"] for r in rows),
        "max_move_mm": max(r["max_move_mm"] for r in rows),
        "mean_seconds": sum(r["seconds"] for r in rows) / len(rows),
    }
    print(json.dumps(summary), flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"rows": rows, "summary": summary}, f, indent=1)


if __name__ == "__main__":
    main()
