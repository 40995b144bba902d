"""The machine's limits that mgn's stages depend on, the share of them each stage reaches, and the
floors of the regression gate.

Measured in the same run as the suites, with every core the process may use:

- ``embree_coherent``: Embree first-hit rays/s for a pinhole camera's rays (1000 x 1000, quick
  447 x 447) on a fixed icosphere of 81,920 triangles (``RayScene.intersect(coherent=True)``).
- ``embree_random``: the same for 1,000,000 (quick 200,000) random rays through the icosphere.
- ``llvmpipe_triangles``: triangles/s of Mesa's software rasteriser (OSMesa) drawing a depth-only
  frame of 12 such icospheres (983,040 triangles) at 1200 x 1200 with mgn's Renderer.

A result row names the limit it is bound by and the work of one of its items in the limit's unit
(``Row.limit_work``): its share = mgn's rate at all threads x work per item / limit.

The gate (``python -m benchmarks --gate``): :data:`FLOORS` states, for the rows that time mgn
beside a peer, the lowest mgn / peer speed ratio accepted. Each floor is about 60 % of the ratio
of the reference run (2-core AMD EPYC, 2026-11-25; benchmarks/PERFORMANCE.md's first version):
low enough that another machine, another load or run-to-run noise stays above it (ratios move by
10-30 % between machines, much less than absolute rates), high enough that losing a fast path
(a packet path, a pre-test, a thread pool) falls below it. The floors apply to the 1-thread
ratio (mgn on one core against the peer as it comes) where mgn was timed on one thread, else to
the ratio at the most threads measured. The Mitsuba 3 floor is the exception: that peer compiles
itself for the machine's vector unit, its ratio moved 2.3x between two such machines, and its floor
is about 60 % of the ratio of the current page's machine (docs/decisions/0063).
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .common import Row, fmt_rate, measure_alternating, thread_counts

#: What each limit is, in words, for the report.
LIMIT_NAMES = {
    "embree_coherent": "Embree first-hit, coherent camera rays (rays/s)",
    "embree_random": "Embree first-hit, random rays (rays/s)",
    "llvmpipe_triangles": "llvmpipe depth-only rasterisation, 1200×1200 (triangles/s)",
}


def _icosphere(mgn: Any) -> Any:
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=6, radius=0.1)
    return mgn.Mesh(
        np.ascontiguousarray(s.vertices, np.float32), np.ascontiguousarray(s.faces, np.int32)
    )


def measure_limits(
    mgn: Any, *, quick: bool, repeats: int, log: Callable[[str], None]
) -> dict[str, float]:
    """Rates of the machine limits (see the module docstring); {} without mgn."""
    if mgn is None:
        return {}
    from .bench_raycast import camera_rays, random_rays

    t = thread_counts()[-1]
    mesh = _icosphere(mgn)
    scene = mgn.RayScene(mesh)
    bounds = np.asarray(scene.bounds)
    side = 447 if quick else 1000
    cam_o, cam_d = camera_rays(bounds, side, side)
    rnd_o, rnd_d = random_rays(np.random.default_rng(7), bounds, 200_000 if quick else 1_000_000)
    cases = {
        "embree_coherent": lambda: scene.intersect(cam_o, cam_d, coherent=True, num_threads=t),
        "embree_random": lambda: scene.intersect(rnd_o, rnd_d, coherent=False, num_threads=t),
    }
    n = {"embree_coherent": len(cam_o), "embree_random": len(rnd_o)}
    renderer = None
    try:
        from mgn.render import Renderer
        from mgn.render.renderer import Instance
        from mgn.scene.cameras import CameraView, Intrinsics, look_at

        renderer = Renderer(1200, 1200)
        mid = renderer.add_mesh(mesh)
        instances = []
        for k in range(12):
            X = np.eye(4)
            X[:3, 3] = [0.22 * (k % 4) - 0.33, 0.22 * (k // 4) - 0.22, 0.0]
            instances.append(Instance(mid, X, k + 1))
        renderer.set_instances(instances)
        X_WC = look_at([0.0, 0.0, 1.0], [0.0, 0.0, 0.0], up=[0.0, 1.0, 0.0])
        view = CameraView(Intrinsics.mgn_synthetic(), X_WC)
        tris = 12 * 81_920

        def frame() -> None:
            renderer.render(view, rgb=False, depth=True, instances=False, shadows=False)

        cases["llvmpipe_triangles"] = frame
        n["llvmpipe_triangles"] = tris
    except Exception as e:  # the limit is reported missing, not faked
        log(f"  limits: renderer unavailable ({type(e).__name__}: {e})")
    for fn in cases.values():
        fn()  # warm-up
    timings = measure_alternating(cases, repeats)
    out = {k: timings[k].rate(n[k]) for k in cases}
    log("  limits: " + ", ".join(f"{k} {fmt_rate(v)}" for k, v in out.items()))
    return out


def limits_markdown(limits: dict[str, float]) -> str:
    """The "Machine limits" table."""
    if not limits:
        return "Not measured (mgn not built)."
    lines = ["| limit | rate |", "|---|---|"]
    lines += [f"| {LIMIT_NAMES[k]} | {fmt_rate(v)} |" for k, v in limits.items()]
    return "\n".join(lines)


def shares(rows: list[Row], limits: dict[str, float]) -> list[dict[str, Any]]:
    """Per row bound by a measured limit: its rate in the limit's unit and its share."""
    t = thread_counts()[-1]
    out = []
    for r in rows:
        if r.limit_work is None or t not in r.mgn:
            continue
        key, work = r.limit_work
        if key not in limits:
            continue
        rate = r.mgn[t].rate(r.n) * work
        out.append(
            {
                "row": f"{r.group}: {r.case}",
                "limit": key,
                "rate": rate,
                "share": rate / limits[key],
            }
        )
    return out


def shares_markdown(items: list[dict[str, Any]]) -> str:
    if not items:
        return "No row is bound by a measured limit."
    lines = ["| stage | bound by | rate in that unit | share of the limit |", "|---|---|---|---|"]
    for s in items:
        lines.append(
            f"| {s['row']} | {s['limit']} | {fmt_rate(s['rate'])} | {100 * s['share']:.1f} % |"
        )
    return "\n".join(lines)


def plot_ratios(rows: list[Row], path: Any) -> bool:
    """A PNG bar chart of mgn/peer speed ratios at all threads (log scale); False if no row has
    a ratio."""
    from PIL import Image, ImageDraw

    t = thread_counts()[-1]
    items = [(f"{r.group}: {r.case}", r.ratio(t)) for r in rows]
    items = [(name, ratio) for name, ratio in items if ratio is not None and ratio > 0]
    if not items:
        return False
    label_w, bar_w, row_h, top = 520, 420, 18, 40
    width, height = label_w + bar_w + 80, top + row_h * len(items) + 30
    img = Image.new("RGB", (width, height), "white")
    draw = ImageDraw.Draw(img)
    title = f"mgn speed / peer speed at {t} threads (log scale; right of 1x: mgn faster)"
    draw.text((10, 10), title, fill="black")
    lo = min(0.5, *(r for _, r in items))
    hi = max(20.0, *(r for _, r in items))

    def x_of(ratio: float) -> float:
        return label_w + bar_w * (math.log(ratio) - math.log(lo)) / (math.log(hi) - math.log(lo))

    x1 = x_of(1.0)
    for tick in (0.5, 1, 2, 5, 10, 20, 50, 100):
        if lo <= tick <= hi:
            x = x_of(tick)
            draw.line([(x, top - 4), (x, height - 28)], fill=(225, 225, 225))
            draw.text((x - 8, height - 24), f"{tick:g}x", fill=(90, 90, 90))
    for k, (name, ratio) in enumerate(items):
        y = top + k * row_h
        # Pillow's built-in font has no "×": 1000×1000 is drawn as 1000x1000.
        name = name.replace("×", "x")
        short = name if len(name) <= 84 else name[:81] + "..."
        draw.text((6, y + 3), short, fill="black")
        x = x_of(ratio)
        color = (59, 117, 175) if ratio >= 1 else (200, 80, 60)
        draw.rectangle([min(x, x1), y + 3, max(x, x1), y + row_h - 3], fill=color)
        draw.text((max(x, x1) + 4, y + 3), f"{ratio:.2f}x", fill="black")
    draw.line([(x1, top - 4), (x1, height - 28)], fill="black")
    img.save(path)
    return True


# ----------------------------------------------------------------------------------------------
# Regression gate


@dataclasses.dataclass(frozen=True)
class Floor:
    """The lowest mgn / peer speed ratio accepted for the rows of ``group`` whose case matches
    ``pattern`` (a regular expression searched in ``Row.case``)."""

    group: str
    pattern: str
    floor: float
    threads: int | None = 1  # 1 = the per-core ratio; None = the most threads measured


#: Floors of the gate (reference ratio of the first PERFORMANCE.md in the comments).
FLOORS: tuple[Floor, ...] = (
    # Ray casting against trimesh + embreex (1 thread).
    Floor("ray casting", r"^icosphere.*random rays, first hit with distance", 1.0),  # 1.76
    Floor("ray casting", r"^icosphere.*random rays, first hit, triangle", 0.6),  # 1.05
    Floor("ray casting", r"^icosphere.*random rays, any hit", 0.7),  # 1.23
    Floor("ray casting", r"^icosphere.*camera rays, first hit with distance", 3.5),  # 5.97
    Floor("ray casting", r"^icosphere.*camera rays, first hit, triangle", 2.5),  # 4.15
    Floor("ray casting", r"^icosphere.*camera rays, any hit", 2.0),  # 3.50
    Floor("ray casting", r"^scene.*random rays, first hit with distance", 0.8),  # 1.37
    Floor("ray casting", r"^scene.*random rays, first hit, triangle", 0.6),  # 1.05
    Floor("ray casting", r"^scene.*random rays, any hit", 1.2),  # 2.10
    Floor("ray casting", r"^scene.*camera rays, first hit with distance", 3.0),  # 5.09
    Floor("ray casting", r"^scene.*camera rays, first hit, triangle", 2.1),  # 3.60
    Floor("ray casting", r"^scene.*camera rays, any hit", 6.0),  # 10.13
    # Collision against python-fcl in a Python loop (1 thread).
    Floor("collision", r"collide \(boolean\)$", 0.6),  # 0.98
    Floor("collision", r"distance with nearest points$", 0.7),  # 1.12
    # Suction seal against the same model in NumPy + trimesh (1 thread).
    Floor("suction seal", r"^mug .*robust score", 11.0),  # 19.3
    Floor("suction seal", r"^bottle_water .*robust score", 9.0),  # 15.8
    Floor("suction seal", r"^box_cereal .*robust score", 15.0),  # 26.0
    Floor("suction seal", r"^pear .*robust score", 10.0),  # 16.5
    # Parallel-jaw probes against NumPy + trimesh (1 thread).
    Floor("parallel-jaw", r"antipodal probe test", 2.5),  # 4.09
    # The shake trial against the same trial with pybullet (1 thread).
    Floor("physics", r"^box .*1 thread$", 2.5),  # 4.13
    Floor("physics", r"^ball .*1 thread$", 2.8),  # 4.69
    Floor("physics", r"^steel block .*1 thread$", 2.0),  # 3.38
    # The drop's simulation against pybullet's loop (1 thread); decision 0049.
    Floor("scene drop", r"built-in objects into the tote.*: the simulation$", 0.5),  # 0.66-0.88
    # Rendering against pyrender (both on all threads).
    Floor("rendering", r"RGB \+ z-depth \+ instance ids", 6.0, None),  # 9.98
    # Path tracing against Cycles + OIDN and Mitsuba 3 (both on 2 threads).
    Floor("path tracing", r"16 spp \+ OIDN$", 1.5, None),  # 2.66
    # Mitsuba 3 JIT-compiles for the machine's widest vector unit: its ratio moved 2.69 -> 1.18
    # between two 2-core EPYC machines with mgn unchanged; floor from the second (decision 0063).
    Floor("path tracing", r"16 spp$", 0.7, None),  # 1.18
    # Layout against NumPy / SciPy (1 thread).
    Floor("layout", r"relations \+ layers \+ difficulty", 10.0),  # 18.1
    # Lens against OpenCV (mgn is slower here; the floor guards against getting slower still).
    Floor("lens", r"^undistortion map", 0.4),  # 0.69
    Floor("lens", r"^resample RGB", 0.06),  # 0.10
    # View labels against one render per object (1 thread).
    Floor("view labels", r"^masks, ", 1.4),  # 2.29-2.30
    Floor("view labels", r"^masks \+ keypoints", 1.2),  # 1.96-1.97
    # Dataset files against the first file layout and COCO export (1 thread).
    Floor("dataset files", r"^write one view's files", 1.1),  # 1.78
    Floor("dataset files", r"^mgn coco of one scene", 4.0),  # 6.82
)


def gate(rows: Sequence[Row], floors: Sequence[Floor] = FLOORS) -> list[dict[str, Any]]:
    """One check per (floor, matching row): the row, the threads of the ratio, the ratio, the
    floor and the verdict: "pass", "FAIL" (ratio below the floor) or "not measured" (no row
    matches, e.g. its suite was not run, or a side is missing)."""
    checks: list[dict[str, Any]] = []
    for f in floors:
        matching = [r for r in rows if r.group == f.group and re.search(f.pattern, r.case)]
        if not matching:
            checks.append(
                {
                    "row": f"{f.group}: /{f.pattern}/",
                    "threads": f.threads,
                    "ratio": None,
                    "floor": f.floor,
                    "verdict": "not measured",
                }
            )
            continue
        for r in matching:
            t = f.threads if f.threads is not None else (max(r.mgn) if r.mgn else None)
            ratio = r.ratio(t) if t is not None else None
            verdict = "not measured" if ratio is None else "pass" if ratio >= f.floor else "FAIL"
            checks.append(
                {
                    "row": f"{r.group}: {r.case}",
                    "threads": t,
                    "ratio": ratio,
                    "floor": f.floor,
                    "verdict": verdict,
                }
            )
    return checks


def gate_failures(checks: Sequence[dict[str, Any]]) -> list[str]:
    """The failed checks, in words."""
    return [
        f"{c['row']}: mgn / peer {c['ratio']:.2f}x at {c['threads']} thread(s), floor "
        f"{c['floor']:.2f}x"
        for c in checks
        if c["verdict"] == "FAIL"
    ]


def gate_markdown(checks: Sequence[dict[str, Any]]) -> str:
    """The "Gate" table."""
    lines = ["| row | threads | mgn / peer | floor | verdict |", "|---|---|---|---|---|"]
    for c in checks:
        ratio = "—" if c["ratio"] is None else f"{c['ratio']:.2f}×"
        threads = "—" if c["threads"] is None else str(c["threads"])
        verdict = "**FAIL**" if c["verdict"] == "FAIL" else c["verdict"]
        lines.append(f"| {c['row']} | {threads} | {ratio} | {c['floor']:.2f}× | {verdict} |")
    return "\n".join(lines)
