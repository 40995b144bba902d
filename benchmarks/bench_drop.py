"""Scene drop: mgn.scene (Bullet in C++) against pybullet running the same drop.

Both sides drop the same 20 built-in objects (the same convex parts: mgn's cached decomposition
with the drop's part merging, `mgn.geometry.convex.DROP_DECOMPOSITION`; the same masses and centres
of mass, the same friction and restitution), from the same release poses (the ones mgn draws for the
seed), into the same tote (five static boxes), with the same time step, solver iterations and rest
thresholds, and stop when every object has been at rest for the same time or at 7 s. pybullet is
driven as a user writes it: a Python loop of `stepSimulation` and `getBaseVelocity`. Differences
that remain: pybullet computes the inertia from the shapes (mgn uses the exact mesh inertia), and
pybullet keeps its own contact settings.

Peak memory of each side is measured in a fresh subprocess (ru_maxrss), minus the same
process's footprint after the imports.

Two rows: the C++ simulation alone (release, settle, re-settle) against pybullet's loop, the same
work on both sides; and `drop_scene` as `mgn generate` runs it (the simulation, the final
separation of the render meshes, the scene statistics), which has no peer (pybullet leaves the
render meshes as the hulls put them): docs/decisions/0049-drop-benchmark-rows.md.

The number of steps to settle is chaotic (a bit-level change of a hull moves it by hundreds of
steps): the single-seed row is one sample; compare settings over several seeds.

The second row drops the scenes of `bench_pipeline` (scene i of seed 2024: 20 objects of the
pipeline's catalogue) and reports the CPU seconds of each drop (one thread; the C++ drop only,
decompositions cached). Why the drop is set up as it is (two friction directions, the vectorised
hull support search): docs/decisions/0014-drop-two-friction-directions.md and
0015-drop-hull-support-search.md.

Run alone: `python -m benchmarks.bench_drop [--quick]`.
"""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from .common import PEER_NOT_INSTALLED, Row, Timing, measure_alternating

NUM_OBJECTS = 20
SEED = 2024


def load_peer() -> tuple[Any | None, str]:
    try:
        import pybullet
    except ImportError as exc:
        return None, f"{PEER_NOT_INSTALLED} (pybullet: {exc})"
    return pybullet, ""


def scene_objects() -> list:
    from mgn.scene import compose_objects

    return compose_objects(count=NUM_OBJECTS, seed=SEED)


def mgn_drop(objects: list) -> Any:
    from mgn.scene import drop_scene

    return drop_scene(objects, seed=SEED)


def mgn_simulation(objects: list) -> Any:
    """The C++ drop only (release, settle, re-settle): the work pybullet's loop does; without
    the final separation pass of the render meshes and the scene statistics."""
    from mgn.objects import ToteSpec
    from mgn.scene import DropOptions
    from mgn.scene.drop import _simulate

    out, *_ = _simulate(objects, SEED, ToteSpec(), DropOptions(), None, None, True)
    return out


def _prepared(objects: list) -> tuple[Any, list, list]:
    """mgn's release poses and, per object, its convex parts and mass properties."""
    from mgn.geometry.convex import DROP_DECOMPOSITION, cached_convex_decomposition
    from mgn.geometry.mesh import mass_properties
    from mgn.objects import ToteSpec
    from mgn.scene import DropOptions
    from mgn.scene.drop import _simulate

    out, *_ = _simulate(objects, SEED, ToteSpec(), DropOptions(), None, None, True)
    parts, props = [], []
    for s in objects:
        mesh = s.to_mesh()
        parts.append(cached_convex_decomposition(mesh, DROP_DECOMPOSITION))
        props.append(mass_properties(mesh, s.density))
    return out, parts, props


def pybullet_drop(p: Any, objects: list, prepared: tuple) -> dict[str, Any]:
    """The same drop in pybullet (DIRECT mode); returns the final poses and step count."""
    from mgn.objects import ToteSpec
    from mgn.scene import DropOptions
    from mgn.scene.drop import RESTITUTION

    out, parts, props = prepared
    o, tote = DropOptions(), ToteSpec()
    cid = p.connect(p.DIRECT)
    try:
        p.setGravity(0, 0, -o.gravity, physicsClientId=cid)
        p.setPhysicsEngineParameter(
            fixedTimeStep=o.dt, numSolverIterations=o.solver_iterations, physicsClientId=cid
        )
        hx, hy, H = tote.inner_length / 2, tote.inner_width / 2, tote.inner_height
        T = max(tote.wall_thickness, 0.02)
        F = max(tote.floor_thickness, 0.02)
        boxes = [
            ((-hx - T, -hy - T, -F), (hx + T, hy + T, 0.0)),
            ((-hx - T, -hy - T, -F), (-hx, hy + T, H)),
            ((hx, -hy - T, -F), (hx + T, hy + T, H)),
            ((-hx, -hy - T, -F), (hx, -hy, H)),
            ((-hx, hy, -F), (hx, hy + T, H)),
        ]
        for lo, hi in boxes:
            lo_, hi_ = np.array(lo), np.array(hi)
            shape = p.createCollisionShape(
                p.GEOM_BOX, halfExtents=list((hi_ - lo_) / 2), physicsClientId=cid
            )
            b = p.createMultiBody(0, shape, basePosition=list((hi_ + lo_) / 2), physicsClientId=cid)
            p.changeDynamics(
                b,
                -1,
                lateralFriction=o.tote_friction,
                restitution=o.tote_restitution,
                physicsClientId=cid,
            )
        bodies = []
        for k, spec in enumerate(objects):
            com = np.asarray(props[k].center_of_mass)
            files = _part_files(spec.name, parts[k])
            shape = p.createCollisionShapeArray(
                [p.GEOM_MESH] * len(files),
                fileNames=files,
                meshScales=[[1.0, 1.0, 1.0]] * len(files),
                collisionFramePositions=[list(-com)] * len(files),
                physicsClientId=cid,
            )
            X = np.asarray(out.X_WO_release)[k]
            q = _quat_xyzw(X[:3, :3])
            pos = X[:3, :3] @ com + X[:3, 3]  # pybullet's base frame sits at the CoM
            b = p.createMultiBody(
                props[k].mass,
                shape,
                basePosition=list(pos),
                baseOrientation=q,
                physicsClientId=cid,
            )
            p.changeDynamics(
                b,
                -1,
                lateralFriction=spec.friction,
                restitution=RESTITUTION,
                rollingFriction=o.rolling_friction,
                spinningFriction=o.rolling_friction,
                angularDamping=o.angular_damping,
                linearDamping=0.0,
                physicsClientId=cid,
            )
            bodies.append(b)
        rest_steps = int(np.ceil(o.rest_time / o.dt - 1e-9))
        max_steps = int(np.ceil(o.max_time / o.dt - 1e-9))
        at_rest = np.zeros(len(bodies), int)
        active = np.ones(len(bodies), bool)
        steps = 0
        while steps < max_steps:
            p.stepSimulation(physicsClientId=cid)
            steps += 1
            for k, b in enumerate(bodies):
                if not active[k]:
                    continue
                pos, _ = p.getBasePositionAndOrientation(b, physicsClientId=cid)
                if pos[2] < -tote.floor_thickness - 0.02:
                    active[k] = False
                    continue
                v, w = p.getBaseVelocity(b, physicsClientId=cid)
                rest = np.linalg.norm(v) < o.linear_rest and np.linalg.norm(w) < o.angular_rest
                at_rest[k] = at_rest[k] + 1 if rest else 0
            if np.all(at_rest[active] >= rest_steps):
                break
        return {"steps": steps, "settled": bool(np.all(at_rest[active] >= rest_steps))}
    finally:
        p.disconnect(physicsClientId=cid)


_PART_DIR: dict[str, list[str]] = {}


def _part_files(name: str, parts: list) -> list[str]:
    """One OBJ per convex part (pybullet builds a convex hull from each mesh file)."""
    from .common import bench_tempdir

    if name not in _PART_DIR:
        root = bench_tempdir("mgn_bench_drop_")
        files = []
        for i, m in enumerate(parts):
            path = root / f"{name}_{i}.obj"
            v, f = np.asarray(m.vertices), np.asarray(m.faces) + 1
            lines = [f"v {a:.7g} {b:.7g} {c:.7g}" for a, b, c in v]
            lines += [f"f {a} {b} {c}" for a, b, c in f]
            path.write_text("\n".join(lines) + "\n")
            files.append(str(path))
        _PART_DIR[name] = files
    return _PART_DIR[name]


def _quat_xyzw(R: np.ndarray) -> list[float]:
    w = np.sqrt(max(0.0, 1.0 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    x = np.copysign(np.sqrt(max(0.0, 1.0 + R[0, 0] - R[1, 1] - R[2, 2])) / 2, R[2, 1] - R[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1.0 - R[0, 0] + R[1, 1] - R[2, 2])) / 2, R[0, 2] - R[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1.0 - R[0, 0] - R[1, 1] + R[2, 2])) / 2, R[1, 0] - R[0, 1])
    q = np.array([x, y, z, w])
    return list(q / np.linalg.norm(q))


def pipeline_scene_drops(seeds: list[int], log: Callable[[str], None]) -> list[dict[str, Any]]:
    """Drops scene i of `bench_pipeline` (seed SEED) for each i in `seeds`; per scene the CPU
    seconds of the C++ drop (time.process_time), the steps and the kept objects."""
    from mgn.pipeline.config import load_config
    from mgn.pipeline.sanity import load_catalogue
    from mgn.pipeline.seeds import scene_seed
    from mgn.pipeline.testset import compose_scene, resolve_split
    from mgn.scene.drop import _simulate

    from .bench_pipeline import SEED as PIPELINE_SEED
    from .bench_pipeline import bench_config

    config = load_config(bench_config(False))
    catalogue = list(load_catalogue(config).specs)
    split = resolve_split(config, catalogue)
    out = []
    for i in seeds:
        seed = scene_seed(PIPELINE_SEED, i)
        picked = compose_scene(config, catalogue, seed, split)
        # Warm-up: the decompositions of every object (cached on disk) outside the timing.
        for spec in picked:
            _simulate([spec], seed, config.tote, config.drop, None, None, True)
        c0 = time.process_time()
        r, *_ = _simulate(picked, seed, config.tote, config.drop, None, None, True)
        cpu = time.process_time() - c0
        kept = int((np.asarray(r.status) == 0).sum())
        out.append({"scene": i, "cpu_s": cpu, "steps": int(r.steps), "kept": kept})
        log(f"bench_drop: pipeline scene {i}: {cpu:.2f} CPU-s, {r.steps} steps, {kept} kept")
    return out


def _peak_rss_mib(side: str) -> tuple[float, float]:
    """(peak RSS after the imports, peak RSS after one drop) of a fresh process, MiB."""
    code = (
        "import json, resource, benchmarks.bench_drop as b\n"
        f"side = {side!r}\n"
        "objs = b.scene_objects()\n"
        "prep = b._prepared(objs) if side == 'peer' else None\n"
        "p, _ = b.load_peer()\n"
        "base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss\n"
        "b.mgn_drop(objs) if side == 'mgn' else b.pybullet_drop(p, objs, prep)\n"
        "peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss\n"
        "print(json.dumps([base / 1024, peak / 1024]))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=600, check=True
    )
    base, peak = json.loads(out.stdout.strip().splitlines()[-1])
    return base, peak


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any | None,
    mgn_status: str,
    log: Callable[[str], None],
) -> list[Row]:
    p, peer_status = load_peer()
    case = f"{NUM_OBJECTS} built-in objects into the tote, settle (dt 1/240 s, max 7 s)"
    row = Row(
        group="scene drop",
        case=f"{case}: the simulation",
        n=1,
        unit="drops/s",
        peer_name="pybullet stepSimulation loop",
        mgn_status=mgn_status,
        peer_status=peer_status,
    )
    whole = Row(
        group="scene drop",
        case=f"{case}: drop_scene (simulation, separation of the render meshes, statistics)",
        n=1,
        unit="drops/s",
        peer_name="-",
        mgn_status=mgn_status,
        peer_status="no peer (pybullet has no separation pass)",
    )
    if mgn is None:
        return [row, whole]
    objects = scene_objects()
    t0 = time.perf_counter()
    scene = mgn_drop(objects)  # warm-up: fills the decomposition cache
    log(f"bench_drop: first drop (with decompositions) {time.perf_counter() - t0:.2f} s")
    sim = mgn_simulation(objects)
    cases: dict[str, Callable[[], object]] = {
        "mgn": lambda: mgn_simulation(objects),
        "whole": lambda: mgn_drop(objects),
    }
    peer_result = None
    if p is not None:
        prepared = _prepared(objects)
        peer_result = pybullet_drop(p, objects, prepared)
        cases["peer"] = lambda: pybullet_drop(p, objects, prepared)
    timings = measure_alternating(cases, repeats)
    row.mgn[1] = timings["mgn"]  # one drop runs on one thread (Bullet's discrete world)
    whole.mgn[1] = timings["whole"]
    row.peer = timings.get("peer")
    st = scene.stats
    row.notes.append(
        f"mgn: {int(sim.steps)} steps, {st['simulated_time']:.2f} s simulated, "
        f"{len(scene)} kept / {len(scene.removed)} removed, median wall "
        f"{timings['mgn'].median:.2f} s ({int(sim.steps) / timings['mgn'].median:,.0f} steps/s)"
    )
    whole.notes.append(
        f"median wall {timings['whole'].median:.2f} s: the simulation "
        f"{timings['mgn'].median:.2f} s, the rest (separation pass, statistics) "
        f"{timings['whole'].median - timings['mgn'].median:.2f} s"
    )
    if peer_result is not None and row.peer is not None:
        row.notes.append(
            f"pybullet: {peer_result['steps']} steps, settled={peer_result['settled']}, median "
            f"wall {row.peer.median:.2f} s "
            f"({peer_result['steps'] / row.peer.median:,.0f} steps/s)"
        )
    for side in ["mgn"] + (["peer"] if p is not None else []):
        try:
            base, peak = _peak_rss_mib(side)
            row.notes.append(
                f"{side} peak RSS {peak:.0f} MiB ({peak - base:+.0f} MiB for the drop)"
            )
        except (subprocess.SubprocessError, ValueError, IndexError) as exc:
            row.notes.append(f"{side} peak RSS not measured ({type(exc).__name__})")
    row.agreement = "not compared (chaotic dynamics)"
    scenes = pipeline_scene_drops(list(range(2 if quick else 8)), log)
    total = sum(d["cpu_s"] for d in scenes)
    pipe = Row(
        group="scene drop",
        case=f"bench_pipeline scenes 0-{len(scenes) - 1} (20 objects each): CPU-s of the drops",
        n=len(scenes),
        unit="drops/s",
        peer_name="-",
        mgn_status=mgn_status,
        peer_status="no peer (mgn's own scenes)",
    )
    pipe.mgn[1] = Timing(wall=[total], cpu=[total])  # CPU seconds (one thread per drop)
    pipe.notes.append(
        f"total {total:.2f} CPU-s, mean {total / len(scenes):.2f} CPU-s per drop; per scene "
        + ", ".join(f"{d['scene']}: {d['cpu_s']:.2f} s/{d['steps']} steps" for d in scenes)
    )
    return [row, whole, pipe]


if __name__ == "__main__":
    from .common import import_mgn

    mgn_mod, status = import_mgn()
    rows = run(
        quick="--quick" in sys.argv,
        repeats=3,
        mgn=mgn_mod,
        mgn_status=status,
        log=lambda m: print(m, file=sys.stderr),
    )
    for r in rows:
        print(json.dumps(r.to_json(), indent=1))
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak RSS of this process: {rss:.0f} MiB")
