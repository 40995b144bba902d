"""Rendering: mgn.render.Renderer (C++, OSMesa) against pyrender (PyOpenGL on OSMesa).

The frame: 20 built-in objects (textured where the library textures them, two transparent) in a
grid on the floor of the default tote, seen by views of the MetaGraspNet rig at 1200 x 1200
(quick: 600 x 600). One timed call = one view's RGB + metric z-depth + instance-id images:

- mgn: ``Renderer.render`` (one call: shadow map, depth pre-pass, shading, three read-backs).
- pyrender: ``OffscreenRenderer.render`` with spot-light shadows (colour + depth), then a
  second ``render`` with ``RenderFlags.SEG`` (instance ids as colours).

Each side runs in its own subprocess (both use OSMesa, and peak memory is then per side): it
builds the scene, renders once untimed (warm-up; that frame is compared), then times the views.
Peak memory is the child's maximum resident set size (includes Python and NumPy).
Agreement: z-depth within 1 mm on the object pixels and equal instance ids, pixel by pixel.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .common import PEER_NOT_INSTALLED, Row, Timing, fraction, percent, thread_counts

DEPTH_TOL = 1e-3  # m
AGREEMENT_MIN = 0.98  # pixel-centre conventions and rasterisation rules differ at edges
N_OBJECTS = 20
HERE = Path(__file__).resolve().parent


def scene_items() -> list[tuple[Any, np.ndarray, int]]:
    """(mgn.Mesh, X_WO, instance id) of 20 built-in objects in a 5 x 4 grid in the tote."""
    from mgn.objects import builtin_objects

    specs = builtin_objects()[:N_OBJECTS]
    items = []
    for k, spec in enumerate(specs):
        mesh = spec.to_mesh()
        lo = np.asarray(mesh.bounds)[0]
        X = np.eye(4)
        yaw = 0.7 * k
        X[:2, :2] = [[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]
        X[:3, 3] = (-0.15 + 0.075 * (k % 5), -0.105 + 0.07 * (k // 5), -lo[2])
        items.append((mesh, X, k + 1))
    return items


def scene_triangles() -> int:
    """Triangles of the benchmark scene: its objects plus the tote."""
    from mgn.objects import tote_mesh

    return sum(len(m.faces) for m, _, _ in scene_items()) + len(tote_mesh().faces)


def camera(width: int) -> tuple[Any, np.ndarray]:
    from mgn.scene.cameras import Intrinsics, mgn_rig

    K = Intrinsics.mgn_synthetic().scaled(width / 1200)
    poses, _ = mgn_rig(2024, (0.0, 0.0, 0.0))
    return K, poses


def _side_mgn(width: int, views: list[int]) -> tuple[Callable[[int], tuple], Any]:
    from mgn.objects import tote_mesh
    from mgn.render import Instance, Renderer
    from mgn.scene.cameras import CameraView

    K, poses = camera(width)
    r = Renderer(K.width, K.height)
    insts = [Instance(r.add_mesh(m), X, i) for m, X, i in scene_items()]
    insts.append(Instance(r.add_mesh(tote_mesh()), np.eye(4), 0))
    r.set_instances(insts)

    def render(v: int) -> tuple:
        out = r.render(CameraView(K, poses[v]), randomize=True, seed=1, view_index=v)
        return out.rgb, out.depth, out.instance_ids

    return render, r


def _side_pyrender(width: int, views: list[int]) -> tuple[Callable[[int], tuple], Any]:
    os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")
    if not hasattr(np, "infty"):  # pyrender 0.1.45 still uses the alias NumPy 2 removed
        setattr(np, "infty", np.inf)  # noqa: B010
    import pyrender
    import trimesh
    from PIL import Image

    from mgn.objects import tote_mesh

    K, poses = camera(width)
    scene = pyrender.Scene(ambient_light=(0.25, 0.25, 0.25), bg_color=(0, 0, 0, 0))
    seg: dict[Any, tuple[int, int, int]] = {}
    items = scene_items() + [(tote_mesh(), np.eye(4), 0)]
    for mesh, X, inst in items:
        mat = mesh.materials[0]
        tex = mat.texture_data
        base = list(np.asarray(mat.base_color, float))
        base[3] *= float(mat.opacity)
        kwargs: dict[str, Any] = {
            "baseColorFactor": base,
            "metallicFactor": 0.0,
            "roughnessFactor": 0.6,
            "alphaMode": "BLEND" if base[3] < 1 else "OPAQUE",
        }
        visual = None
        if tex and mesh.uvs is not None:
            import io

            kwargs["baseColorTexture"] = Image.open(io.BytesIO(tex)).convert("RGB")
            visual = trimesh.visual.TextureVisuals(uv=np.asarray(mesh.uvs))
        tm = trimesh.Trimesh(np.asarray(mesh.vertices), np.asarray(mesh.faces), process=False)
        if visual is not None:
            tm.visual = visual
        material = pyrender.MetallicRoughnessMaterial(**kwargs)
        node = scene.add(pyrender.Mesh.from_trimesh(tm, material=material), pose=X)
        seg[node] = (inst, 0, 0)
    light = pyrender.SpotLight(color=np.ones(3), intensity=15.0, outerConeAngle=0.6)
    light_pose = np.eye(4)
    light_pose[:3, 3] = (0.3, -0.2, 1.5)
    scene.add(light, pose=light_pose)
    cam = pyrender.IntrinsicsCamera(K.fx, K.fy, K.cx, K.cy, znear=0.05, zfar=5.0)
    cam_node = scene.add(cam, pose=np.eye(4))
    r = pyrender.OffscreenRenderer(K.width, K.height)
    cv_to_gl = np.diag([1.0, -1.0, -1.0, 1.0])
    flags = pyrender.RenderFlags

    def render(v: int) -> tuple:
        scene.set_pose(cam_node, poses[v] @ cv_to_gl)
        color, depth = r.render(scene, flags=flags.SHADOWS_SPOT)
        ids, _ = r.render(scene, flags=flags.SEG, seg_node_map=seg)
        return color, depth, ids[..., 0].astype(np.int32)

    return render, r


def child_main(argv: list[str]) -> int:
    """One side in this process: prints JSON with timings and peak memory, saves the warm-up
    frame to --out (npz)."""
    p = argparse.ArgumentParser()
    p.add_argument("--side", choices=["mgn", "pyrender"], required=True)
    p.add_argument("--width", type=int, default=1200)
    p.add_argument("--repeats", type=int, default=7)
    p.add_argument("--out", required=True)
    a = p.parse_args(argv)
    views = [0, 5, 14, 27, 36]
    t0 = time.perf_counter()
    render, keep = (_side_mgn if a.side == "mgn" else _side_pyrender)(a.width, views)
    setup = time.perf_counter() - t0
    rgb, depth, ids = render(views[0])
    np.savez_compressed(a.out, rgb=rgb, depth=depth, ids=ids)
    wall, cpu = [], []
    for k in range(a.repeats):
        v = views[k % len(views)]
        c0, w0 = time.process_time(), time.perf_counter()
        render(v)
        wall.append(time.perf_counter() - w0)
        cpu.append(time.process_time() - c0)
    peak_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(json.dumps({"wall": wall, "cpu": cpu, "peak_kib": peak_kib, "setup_s": setup}))
    del keep
    return 0


def _run_child(side: str, width: int, repeats: int, out: Path) -> tuple[dict | None, str]:
    env = dict(os.environ, PYOPENGL_PLATFORM="osmesa")
    cmd = [sys.executable, "-m", "benchmarks.bench_render", "--side", side]
    cmd += ["--width", str(width), "--repeats", str(repeats), "--out", str(out)]
    proc = subprocess.run(
        cmd, cwd=HERE.parent, env=env, check=False, capture_output=True, text=True
    )
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or ["?"])[-1]
        status = PEER_NOT_INSTALLED if "ModuleNotFoundError" in proc.stderr else "failed"
        if "OSMesaCreateContextAttribs" in proc.stderr:
            status = 'failed: PyOpenGL too old for OSMesa, pip install "PyOpenGL>=3.1.5"'
        return None, f"{status} ({last})"
    return json.loads(proc.stdout.strip().splitlines()[-1]), ""


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any | None,
    mgn_status: str,
    log: Callable[[str], None],
) -> list[Row]:
    width = 600 if quick else 1200
    threads = thread_counts()
    log(f"  rendering: {N_OBJECTS} built-in objects + tote, {width}x{width}")
    with tempfile.TemporaryDirectory() as tmp:
        frames: dict[str, Any] = {}
        results: dict[str, dict | None] = {}
        statuses: dict[str, str] = {}
        for side in ("mgn", "pyrender"):
            if side == "mgn" and mgn is None:
                results[side], statuses[side] = None, mgn_status
                continue
            out = Path(tmp) / f"{side}.npz"
            results[side], statuses[side] = _run_child(side, width, repeats, out)
            if results[side] is not None:
                with np.load(out) as z:
                    frames[side] = {k: z[k] for k in z.files}
    row = Row(
        group="rendering",
        case=f"{N_OBJECTS} objects + tote, {width}×{width}, RGB + z-depth + instance ids",
        n=1,
        unit="views/s",
        peer_name="pyrender OffscreenRenderer.render (colour+depth, then SEG)",
        mgn_status=statuses["mgn"],
        peer_status=statuses["pyrender"],
    )
    m, p = results["mgn"], results["pyrender"]
    if m is not None:
        # llvmpipe rasterises with its own threads (LP_NUM_THREADS, default: every core).
        row.mgn = {threads[-1]: Timing(m["wall"], m["cpu"])}
        # Bound by llvmpipe: every triangle is drawn in three passes per view (the light's shadow
        # map, the depth/id pre-pass, the shading pass), so a view's work is 3 x triangles.
        row.limit_work = ("llvmpipe_triangles", 3.0 * scene_triangles())
        row.notes.append(
            f"mgn {1000 * float(np.median(m['wall'])):.0f} ms/view, peak RSS "
            f"{m['peak_kib'] / 1024:.0f} MiB, setup {m['setup_s']:.1f} s"
        )
    if p is not None:
        row.peer = Timing(p["wall"], p["cpu"])
        row.notes.append(
            f"pyrender {1000 * float(np.median(p['wall'])):.0f} ms/view, peak RSS "
            f"{p['peak_kib'] / 1024:.0f} MiB, setup {p['setup_s']:.1f} s"
        )
    if m is not None and p is not None:
        a, b = frames["mgn"], frames["pyrender"]
        objects = a["ids"] > 0
        depth_ok = fraction(np.abs(a["depth"] - b["depth"])[objects] < DEPTH_TOL)
        ids_ok = fraction(a["ids"] == b["ids"])
        row.agreement = f"depth ±1 mm {percent(depth_ok)}, ids {percent(ids_ok)}"
        row.agreement_ok = depth_ok >= AGREEMENT_MIN and ids_ok >= AGREEMENT_MIN
        row.notes.append(
            f"ratio pyrender/mgn time {float(np.median(p['wall']) / np.median(m['wall'])):.2f}"
        )
    return [row]


if __name__ == "__main__":
    sys.exit(child_main(sys.argv[1:]))
