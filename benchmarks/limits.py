"""The machine's limits that mgn's stages depend on, and what share of them each stage reaches.

Measured in the same run as the suites, with every core the process may use:

- ``embree_coherent``: Embree first-hit rays/s for a pinhole camera's rays (1000 x 1000, quick
  447 x 447) on a fixed icosphere of 81,920 triangles (``RayScene.intersect(coherent=True)``).
- ``embree_random``: the same for 1,000,000 (quick 200,000) random rays through the icosphere.
- ``llvmpipe_triangles``: triangles/s of Mesa's software rasteriser (OSMesa) drawing a depth-only
  frame of 12 such icospheres (983,040 triangles) at 1200 x 1200 with mgn's Renderer.

A result row names the limit it is bound by and the work of one of its items in the limit's unit
(``Row.limit_work``): its share = mgn's rate at all threads x work per item / limit.
"""

from __future__ import annotations

import math
from collections.abc import Callable
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
    return mgn.Mesh(np.ascontiguousarray(s.vertices, np.float32),
                    np.ascontiguousarray(s.faces, np.int32))  # fmt: skip


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
    except Exception as e:  # noqa: BLE001 (the limit is reported missing, not faked)
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
        out.append({
            "row": f"{r.group}: {r.case}",
            "limit": key,
            "rate": rate,
            "share": rate / limits[key],
        })  # fmt: skip
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
    lo = min(0.5, min(r for _, r in items))
    hi = max(20.0, max(r for _, r in items))

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
