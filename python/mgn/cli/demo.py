"""The README's demo: export the built-in objects and run a ray-cast / collision smoke on them.

It writes ``<out>/models/`` (the MetaGraspNet object folders), ``<out>/gallery.png`` (the objects
laid out on a floor, ray-cast from above: shaded colour beside a depth picture) and
``<out>/smoke.json`` (what was checked and measured). Later issues grow it into dataset
generation.
"""

from __future__ import annotations

import io
import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from mgn.base.atomic import atomic_write_bytes, atomic_write_text
from mgn.geometry.collision import CollisionModel, collide
from mgn.geometry.mesh import Mesh, load_mesh, make_box, mass_properties
from mgn.geometry.raytrace import RayScene, camera_rays
from mgn.io.model_folder import write_model_folder
from mgn.objects import ObjectSpec, builtin_objects


@dataclass(frozen=True)
class SmokeResult:
    """Summary of a demo run (see :func:`run_demo`)."""

    out_dir: Path
    num_objects: int
    reloaded_ok: int
    rays_per_second: float
    collision_checks: int
    collision_errors: int
    picture: Path


def _translation(x: float, y: float, z: float) -> np.ndarray:
    X = np.eye(4)
    X[:3, 3] = (x, y, z)
    return X


def _grid_poses(meshes: list[Mesh], spacing: float) -> np.ndarray:
    """Poses X_WO placing each object on the floor z = 0, in a square grid centred at 0."""
    cols = int(np.ceil(np.sqrt(len(meshes))))
    poses = []
    for i, m in enumerate(meshes):
        r, c = divmod(i, cols)
        b = m.bounds
        x = (c - (cols - 1) / 2) * spacing
        y = ((cols - 1) / 2 - r) * spacing
        poses.append(_translation(x, y, -float(b[0, 2])))
    return np.stack(poses)


def _picture(
    scene: RayScene, colors: np.ndarray, extent: float, size: int, num_threads: int
) -> tuple[np.ndarray, float]:
    """Top-down orthographic-like view (a pinhole far above): shaded RGB | depth, and rays/s."""
    height = 4.0 * extent
    f = size / 2 / (0.55 * extent / height)
    K = np.array([[f, 0, size / 2], [0, f, size / 2], [0, 0, 1.0]])
    X_WC = np.eye(4)
    X_WC[:3, :3] = np.diag([1.0, -1.0, -1.0])  # camera z looks down -z(world), image y = -y(world)
    X_WC[:3, 3] = (0, 0, height)
    origins, dirs = camera_rays(K, size, size, X_WC)
    t0 = time.perf_counter()
    hits = scene.intersect(origins, dirs, coherent=True, num_threads=num_threads)
    rate = len(dirs) / max(time.perf_counter() - t0, 1e-9)
    ids = hits.instance_ids.reshape(size, size)
    light = np.array([0.3, -0.4, 0.87])
    light /= np.linalg.norm(light)
    lambert = np.clip(hits.normals @ light, 0.0, 1.0).reshape(size, size)
    rgb = colors[np.clip(ids, 0, None)] * (0.35 + 0.65 * lambert)[..., None]
    rgb[ids < 0] = (0.1, 0.1, 0.12)
    depth = hits.distance.reshape(size, size)
    valid = np.isfinite(depth)
    d = np.zeros_like(depth)
    if valid.any():
        lo, hi = depth[valid].min(), depth[valid].max()
        d[valid] = 1.0 - (depth[valid] - lo) / max(hi - lo, 1e-9)  # near = bright
    grey = np.repeat((0.15 + 0.85 * d)[..., None] * valid[..., None], 3, axis=2)
    image = np.concatenate([rgb, grey], axis=1)
    return (np.clip(image, 0, 1) * 255).astype(np.uint8), rate


def _display_color(spec: ObjectSpec) -> np.ndarray:
    if spec.material.texture is not None:
        out: np.ndarray = (
            np.asarray(spec.material.texture, np.float64).reshape(-1, 3).mean(0) / 255.0
        )
        return out
    return np.asarray(spec.material.base_color[:3], np.float64)


def run_demo(out: str | Path, *, num_threads: int = 0, image_size: int = 900) -> SmokeResult:
    """Export the built-in objects to ``out`` and check them with the ray caster and FCL.

    Checks made (each counted in ``smoke.json``): every exported ``textured.obj`` reloads
    watertight with the volume of the object it came from; no two objects of the gallery layout
    collide; every object collides with a copy of itself shifted by 30 % of its width and not
    with one shifted clear of its bounding box.
    """

    out_dir = Path(out)
    specs = builtin_objects()
    print(f"mgn demo: exporting {len(specs)} built-in objects to {out_dir / 'models'}")
    reloaded_ok = 0
    rows = []
    for spec in specs:
        folder = write_model_folder(spec, out_dir, overwrite=True)
        original = spec.to_mesh()
        reloaded = load_mesh(folder / "textured.obj")
        report = reloaded.validate()
        v0 = mass_properties(original, spec.density).volume
        v1 = mass_properties(reloaded, spec.density).volume
        ok = report.is_watertight and report.is_outward and abs(v1 - v0) <= 1e-4 * v0
        reloaded_ok += ok
        rows.append((spec.category_id, spec.name, reloaded.num_faces, v1 * 1e6, ok))

    meshes = [s.to_mesh() for s in specs]
    spacing = 0.27
    poses = _grid_poses(meshes, spacing)
    extent = spacing * int(np.ceil(np.sqrt(len(meshes))))
    floor = make_box([extent, extent, 0.01])
    scene = RayScene(
        [*meshes, floor],
        poses=np.concatenate([poses, _translation(0, 0, -0.005)[None]]),
        instance_ids=[*range(len(meshes)), len(meshes)],
    )
    colors = np.array([_display_color(s) for s in specs] + [(0.55, 0.55, 0.5)])
    image, rate = _picture(scene, colors, extent, image_size, num_threads)
    picture = out_dir / "gallery.png"

    buf = io.BytesIO()
    Image.fromarray(image).save(buf, format="PNG")
    atomic_write_bytes(picture, buf.getvalue())

    models = [CollisionModel(m) for m in meshes]
    checks = errors = 0
    for i in range(len(models)):
        others = [j for j in range(len(models)) if j != i]
        for j in others:
            checks += 1
            errors += bool(collide(models[i], poses[i], models[j], poses[j]))
        width = float(np.ptp(meshes[i].bounds[:, 0]))
        near = _translation(0.3 * width, 0, 0)
        far = _translation(width + 0.001, 0, 0)
        hits = np.asarray(
            collide(models[i], np.eye(4), models[i], np.stack([near, far]), num_threads=num_threads)
        )
        checks += 2
        errors += int(not hits[0]) + int(hits[1])

    print(f"{'id':>3}  {'name':<24}{'faces':>7}{'volume cm3':>12}  reload")
    for cid, name, faces, vol, ok in rows:
        print(f"{cid:>3}  {name:<24}{faces:>7}{vol:>12.1f}  {'ok' if ok else 'FAILED'}")
    print(
        f"ray casting: {len(meshes) + 1} meshes, {image_size * image_size} camera rays at "
        f"{rate / 1e6:.1f} M rays/s; collision checks: {checks}, unexpected results: {errors}"
    )
    print(f"picture: {picture}")
    summary: dict[str, Any] = {
        "num_objects": len(specs),
        "reloaded_ok": reloaded_ok,
        "camera_rays_per_second": rate,
        "collision_checks": checks,
        "collision_errors": errors,
        "objects": [
            {"id": c, "name": n, "faces": f, "volume_cm3": v, "reload_ok": bool(k)}
            for c, n, f, v, k in rows
        ],
    }
    atomic_write_text(out_dir / "smoke.json", json.dumps(summary, indent=2))
    return SmokeResult(out_dir, len(specs), reloaded_ok, rate, checks, errors, picture)
