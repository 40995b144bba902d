"""Study of decision 0060 (not a maintained benchmark): shake-score step convergence of
multi-hull objects.

capture OBJ: the calibration inputs of ``compute_object_labels`` (the convex parts, mass
properties and the 32 calibration grasps of ShakeScorer's first shake_scores call), saved to
DATA/inputs_OBJ.npz without running the physics.
run OBJ SETTING [--grasps N] [--every K]: full 10 x 10 grids of N calibration grasps (every
K-th of the 32) at one setting, 1 thread; saves outcomes, steps and CPU-s to
DATA/grid_OBJ_SETTING_N.json.
compare OBJ REF SETTING...: mean |score - ref| per grasp and differing cells.
phase OBJ SETTING REF: for cells that fail at SETTING and hold at REF, the phase in which the
object falls out (recorded trajectories) and the object's motion in the hand.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

DATA = Path(os.environ.get("MHCONV_DATA", "/work/wt/mhconv-data"))


class _Captured(Exception):
    pass


def capture(name: str) -> None:
    import mgn.pj.physics as phys
    from mgn.pipeline.config import Config
    from mgn.pipeline.label_cache import compute_object_labels

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    from benchmarks.bench_object_physics import _spec

    got: dict[str, Any] = {}

    def fake(parts: Any, mass: float, com: Any, inertia: Any, rows: Any, *a: Any) -> Any:
        got.update(parts=parts, mass=mass, com=np.asarray(com), inertia=np.asarray(inertia),
                   rows=np.asarray(rows))  # fmt: skip
        raise _Captured

    phys.shake_scores = fake  # type: ignore[assignment]
    spec = _spec(name, DATA)
    c0 = time.process_time()
    try:
        compute_object_labels(spec, Config(), 1)
    except _Captured:
        pass
    parts = got["parts"]
    arrays: dict[str, Any] = {
        "mass": got["mass"], "com": got["com"], "inertia": got["inertia"], "rows": got["rows"],
        "nparts": len(parts),
    }  # fmt: skip
    for k, p in enumerate(parts):
        arrays[f"v{k}"] = np.asarray(p.vertices)
        arrays[f"f{k}"] = np.asarray(p.faces)
    np.savez(DATA / f"inputs_{name}.npz", **arrays)
    print(f"{name}: {len(parts)} parts, mass {got['mass']:.4f} kg, {len(got['rows'])} grasps, "
          f"capture CPU-s {time.process_time() - c0:.1f}")  # fmt: skip


def load(name: str) -> dict[str, Any]:
    from mgn.geometry.mesh import Mesh

    z = np.load(DATA / f"inputs_{name}.npz")
    parts = [Mesh(z[f"v{k}"], z[f"f{k}"]) for k in range(int(z["nparts"]))]
    return {"parts": parts, "mass": float(z["mass"]), "com": z["com"], "inertia": z["inertia"],
            "rows": z["rows"]}  # fmt: skip


def options(setting: str) -> Any:
    """Setting names: s400 / s800 / s1600 (step 1/400 s ...), then +it20 (solver iterations),
    +h5 (iterations_per_hull_contact), +m2 (margin 2e-4 m ...), +cd (contact_distance)."""
    from mgn.pj.physics import ShakeOptions

    parts = setting.split("+")
    f = {"s400": 1, "s800": 2, "s1600": 4, "s200": 0.5}[parts[0]]
    kw: dict[str, Any] = dict(
        dt=1.0 / (400 * f), close_steps=int(800 * f), shake_steps=int(800 * f),
        rotate_steps=int(600 * f), settle_steps=int(20 * f), lost_contact_steps=int(20 * f),
        num_threads=1, staircase=False,
    )  # fmt: skip
    for p in parts[1:]:
        if p.startswith("it"):
            kw["solver_iterations"] = int(p[2:])
        elif p.startswith("hv"):
            kw["max_hull_vertices"] = int(p[2:])
        elif p.startswith("h"):
            kw["iterations_per_hull_contact"] = float(p[1:])
        elif p.startswith("m"):
            kw["margin"] = float(p[1:]) * 1e-4
        else:
            raise ValueError(p)
    return ShakeOptions(**kw)


def pick(n: int, every: int, offset: int = 0) -> np.ndarray:
    return np.arange(offset, 32, every)[:n]


def run(name: str, setting: str, n: int, every: int, offset: int, div: int, tag: str) -> None:
    """Grasp k of the 32 draws the random streams of grasp k // div (div = every: its position
    in the list), so a subset (offset) repeats the trials of the full list."""
    from dataclasses import replace

    from mgn.pj.physics import shake_scores

    inp = load(name)
    idx = pick(n, every, offset)
    o = options(setting)
    c0 = time.process_time()
    res = [
        shake_scores(inp["parts"], inp["mass"], inp["com"], inp["inertia"], inp["rows"][[k]],
                     None, replace(o, first_grasp_index=int(k) // div))  # fmt: skip
        for k in idx
    ]
    cpu = time.process_time() - c0
    succ = np.concatenate([np.asarray(r.trial_success) for r in res])
    steps = np.concatenate([np.asarray(r.trial_steps) for r in res])
    score = np.concatenate([np.asarray(r.score) for r in res])
    out = {
        "object": name, "setting": setting, "grasps": idx.tolist(), "cpu_s": cpu,
        "success": succ.astype(int).tolist(), "steps": steps.astype(int).tolist(),
        "score": score.tolist(), "load": os.getloadavg()[0],
    }  # fmt: skip
    (DATA / f"grid_{name}_{setting}_{tag}.json").write_text(json.dumps(out))
    print(f"{name} {setting} {len(idx)} grasps: mean score {np.mean(score):.3f} CPU-s {cpu:.1f} "
          f"({cpu / steps.size:.4f}/trial, {steps.mean():.0f} steps/trial) load {out['load']:.1f}")  # fmt: skip


def _grid(name: str, setting: str, tag: str) -> dict[str, Any]:
    return json.loads((DATA / f"grid_{name}_{setting}_{tag}.json").read_text())


def compare(name: str, ref: str, settings: list[str], tag: str) -> None:
    R = _grid(name, ref, tag)
    rs = np.asarray(R["success"], bool).reshape(-1, 100)
    for s in settings:
        G = _grid(name, s, tag)
        gs = np.asarray(G["success"], bool).reshape(-1, 100)
        k = min(len(gs), len(rs))
        d = np.abs(gs[:k].mean(1) - rs[:k].mean(1))
        lost = int(np.sum(~gs[:k] & rs[:k]))
        won = int(np.sum(gs[:k] & ~rs[:k]))
        print(f"{name} {s:<16} vs {ref}: {k} grasps, mean {gs[:k].mean():.3f} vs {rs[:k].mean():.3f}"
              f" |d| {d.mean():.4f} (max {d.max():.2f}) cells {lost + won} of {gs[:k].size} "
              f"(fail-only-here {lost}, hold-only-here {won}) CPU-s {G['cpu_s']:.1f} "
              f"({G['cpu_s'] / gs[:k].size:.4f}/trial) vs ref {R['cpu_s']:.1f}")  # fmt: skip


def phase(name: str, setting: str, ref: str, tag: str, limit: int) -> None:
    from mgn.pj.physics import shake_trajectory

    inp = load(name)
    G, R = _grid(name, setting, tag), _grid(name, ref, tag)
    gs = np.asarray(G["success"], bool).reshape(-1, 10, 10)
    rs = np.asarray(R["success"], bool).reshape(-1, 10, 10)
    cells = np.argwhere(~gs & rs)[:limit]
    o = options(setting)
    fr = np.linspace(0.5, 2.0, 10)
    de = np.linspace(0.25, 1.0, 10)
    names = {0: "close", 1: "translate", 2: "rotate"}
    counts: dict[str, int] = {}
    print(f"{name}: {len(np.argwhere(~gs & rs))} cells fail at {setting} and hold at {ref}")
    for g, i, j in cells:
        grasp = inp["rows"][G["grasps"][g]]
        t = shake_trajectory(inp["parts"], inp["mass"], inp["com"], inp["inertia"], grasp[None],
                             fr[i], de[j], None, o, record_every=1,
                             trial_index=int(g * 100 + i * 10 + j))  # fmt: skip
        ph = np.asarray(t.phase)
        cl, cr = np.asarray(t.contact_left, bool), np.asarray(t.contact_right, bool)
        both = cl & cr
        # first step of the final streak without both fingers touching
        k = len(both) - 1
        while k > 0 and not both[k - 1]:
            k -= 1
        p = names[int(ph[k])]
        counts[p] = counts.get(p, 0) + 1
        # object motion in the hand frame per step during the closing's last 50 steps and the
        # first 50 shake steps (jitter)
        XWO = np.asarray(t.X_WO)
        XWH = np.asarray(t.X_WH)
        rel = np.einsum("nji,njk->nik", XWH[:, :3, :3], XWO[:, :3, 3:] - XWH[:, :3, 3:])[..., 0]
        closing = np.flatnonzero(ph == 0)
        jit = np.linalg.norm(np.diff(rel[closing[-50:]], axis=0), axis=1).mean() if len(
            closing) > 50 else float("nan")  # fmt: skip
        print(f"  grasp {G['grasps'][g]} f {fr[i]:.2f} d {de[j]:.2f}: falls out in {p} at "
              f"t {t.time[k]:.3f} s (steps {t.steps}, closing {len(closing)}), closing jitter "
              f"{jit * 1e6:.1f} um/step, opening {t.finger_left[-1] * 2e3:.1f} mm")  # fmt: skip
    print("  phases:", counts)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser()
    p.add_argument("cmd")
    p.add_argument("object")
    p.add_argument("settings", nargs="*")
    p.add_argument("--grasps", type=int, default=16)
    p.add_argument("--every", type=int, default=2)
    p.add_argument("--limit", type=int, default=12)
    p.add_argument("--offset", type=int, default=0)
    p.add_argument("--div", type=int, default=0)
    a = p.parse_args(argv)
    tag = f"{a.grasps}x{a.every}" + (f"o{a.offset}" if a.offset else "")
    if a.cmd == "capture":
        capture(a.object)
    elif a.cmd == "run":
        for s in a.settings:
            run(a.object, s, a.grasps, a.every, a.offset, a.div or a.every, tag)
    elif a.cmd == "compare":
        compare(a.object, a.settings[0], a.settings[1:], tag)
    elif a.cmd == "phase":
        phase(a.object, a.settings[0], a.settings[1], tag, a.limit)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
