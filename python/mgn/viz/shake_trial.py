"""Pictures of one shake trial: an animated GIF and a PNG strip of the gripper shaking an object.

The trial comes from :func:`mgn.pj.physics.shake_trajectory`; frames are drawn by a small
orthographic renderer (flat-shaded triangles, painter's order, Pillow polygons), so no OpenGL
is needed. The fingers are drawn orange while they touch the object and red when they do not.

:func:`show_trial` runs one trial of a built-in object or a mesh file and writes its pictures
(the ``mgn pj show-trial`` action, :mod:`mgn.cli.pj`).
"""

from __future__ import annotations

import io
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from PIL import Image, ImageDraw

from mgn import _core
from mgn.base.atomic import atomic_write_bytes
from mgn.errors import InvalidArgumentError
from mgn.geometry.mesh import load_mesh, mass_properties
from mgn.geometry.raytrace import RayScene
from mgn.hardware import ParallelJawGripper, default_gripper
from mgn.objects import get_object
from mgn.pj.physics import PHASE_NAMES, ShakeOptions, ShakeTrajectory, shake_trajectory

Mesh = _core.geometry.Mesh

_BACKGROUND = (248, 248, 245)
_OBJECT = np.array([90.0, 130.0, 190.0])
_PALM = np.array([110.0, 110.0, 115.0])
_TOUCH = np.array([235.0, 150.0, 40.0])
_LOST = np.array([215.0, 50.0, 45.0])
# View: orthographic, looking mostly along +y of the world with a little yaw and pitch.
_YAW, _PITCH = np.deg2rad(25.0), np.deg2rad(18.0)


def _view_rotation() -> npt.NDArray[np.float64]:
    """Rows = camera right, up, forward (into the screen), in world coordinates."""
    forward = np.array(
        [np.sin(_YAW) * np.cos(_PITCH), np.cos(_YAW) * np.cos(_PITCH), -np.sin(_PITCH)]
    )
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    return np.stack([right, up, forward])


def _box(size: npt.ArrayLike, centre: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    m = _core.geometry.make_box(np.asarray(size, dtype=np.float64))
    return np.asarray(m.vertices, dtype=np.float64) + np.asarray(centre), np.asarray(m.faces)


def _hand_parts(
    gripper: ParallelJawGripper, left: float, right: float
) -> list[tuple[np.ndarray, np.ndarray, str]]:
    """Palm and finger boxes in the hand frame: (vertices, faces, kind)."""
    f = np.asarray(gripper.finger_size, dtype=np.float64)
    palm = np.asarray(gripper.palm_size, dtype=np.float64)
    fz = gripper.flange_to_tip - 0.5 * f[2]
    pz = gripper.flange_to_tip - f[2] - 0.5 * palm[2]
    return [
        (*_box(palm, (0.0, 0.0, pz)), "palm"),
        (*_box(f, (-(left + 0.5 * f[0]), 0.0, fz)), "left"),
        (*_box(f, (right + 0.5 * f[0], 0.0, fz)), "right"),
    ]


def _transform(X: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.asarray(v @ X[:3, :3].T + X[:3, 3])


def render_frames(
    traj: ShakeTrajectory,
    object_meshes: Sequence[Mesh],
    gripper: ParallelJawGripper | None = None,
    *,
    size: int = 320,
    supersample: int = 2,
) -> list[Image.Image]:
    """One RGB image per recorded step of ``traj`` (square, ``size`` pixels)."""
    if size < 16:
        raise InvalidArgumentError(f"render_frames: size must be >= 16 px, got {size}")
    g = gripper if gripper is not None else default_gripper()
    R = _view_rotation()
    light = -R[2] + 0.6 * R[1] + 0.3 * R[0]
    light /= np.linalg.norm(light)
    obj = [
        (np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces, dtype=np.int64))
        for m in object_meshes
    ]
    # A fixed window around the hand's path (the object may leave it when dropped).
    pts = []
    for k in range(len(traj.time)):
        for v, _, _ in _hand_parts(g, traj.finger_left[k], traj.finger_right[k]):
            pts.append(_transform(traj.X_WH[k], v) @ R[:2].T)
    for v, _ in obj:
        pts.append(_transform(traj.X_WO[0], v) @ R[:2].T)
    allp = np.concatenate(pts)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    centre, half = 0.5 * (lo + hi), 0.5 * float(np.max(hi - lo)) * 1.1 + 1e-6
    n = size * supersample
    scale = n / (2.0 * half)

    frames = []
    for k in range(len(traj.time)):
        pieces = [(v, f, _OBJECT, traj.X_WO[k]) for v, f in obj]
        touch = {"left": traj.contact_left[k], "right": traj.contact_right[k]}
        for v, f, kind in _hand_parts(g, traj.finger_left[k], traj.finger_right[k]):
            base = _PALM if kind == "palm" else (_TOUCH if touch[kind] else _LOST)
            pieces.append((v, f, base, traj.X_WH[k]))
        tris, colours, depth = [], [], []
        for v, f, base, X in pieces:
            t = _transform(X, v)[f]  # (F, 3, 3) world-frame triangles
            nrm = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
            nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-12)
            facing = nrm @ R[2] < 0.0  # towards the camera (back faces are hidden)
            shade = 0.35 + 0.65 * np.clip(nrm @ light, 0.0, 1.0)
            cam_t = t @ R.T
            tris.append(cam_t[facing])
            colours.append(shade[facing, None] * base)
            depth.append(cam_t[facing, :, 2].mean(axis=1))
        cam = np.concatenate(tris)
        col = np.clip(np.concatenate(colours), 0, 255).astype(np.uint8)
        order = np.argsort(-np.concatenate(depth))  # far first
        img = Image.new("RGB", (n, n), _BACKGROUND)
        draw = ImageDraw.Draw(img)
        xy = (cam[:, :, :2] - centre) * scale
        xy[:, :, 0] += 0.5 * n
        xy[:, :, 1] = 0.5 * n - xy[:, :, 1]
        for i in order:
            draw.polygon([tuple(p) for p in xy[i]], fill=tuple(int(c) for c in col[i]))
        img = img.resize((size, size), Image.Resampling.LANCZOS)
        label = f"{PHASE_NAMES[int(traj.phase[k])]}  t={traj.time[k]:.2f}s"
        ImageDraw.Draw(img).text((6, 4), label, fill=(30, 30, 30))
        frames.append(img)
    return frames


def gif_bytes(frames: Sequence[Image.Image], frame_ms: int = 50) -> bytes:
    """An endlessly looping animated GIF of ``frames``."""
    if not frames:
        raise InvalidArgumentError("gif_bytes: expected at least one frame")
    buf = io.BytesIO()
    frames[0].save(
        buf, format="GIF", save_all=True, append_images=list(frames[1:]), duration=frame_ms, loop=0
    )
    return buf.getvalue()


def strip_image(frames: Sequence[Image.Image], count: int = 8) -> Image.Image:
    """``count`` frames evenly spread over the trial, side by side (first and last included)."""
    if not frames:
        raise InvalidArgumentError("strip_image: expected at least one frame")
    count = max(1, min(count, len(frames)))
    idx = np.unique(np.linspace(0, len(frames) - 1, count).round().astype(int))
    w, h = frames[0].size
    strip = Image.new("RGB", (w * len(idx), h), _BACKGROUND)
    for j, i in enumerate(idx):
        strip.paste(frames[i], (j * w, 0))
    return strip


def write_trial_pictures(
    traj: ShakeTrajectory,
    object_meshes: Sequence[Mesh],
    out_prefix: str | os.PathLike[str],
    gripper: ParallelJawGripper | None = None,
    *,
    size: int = 320,
    strip_frames: int = 8,
    frame_ms: int = 50,
) -> tuple[Path, Path]:
    """Write ``PREFIX.gif`` and ``PREFIX_strip.png`` (atomically); returns both paths."""
    frames = render_frames(traj, object_meshes, gripper, size=size)
    prefix = Path(out_prefix)
    gif, png = prefix.with_name(prefix.name + ".gif"), prefix.with_name(prefix.name + "_strip.png")
    atomic_write_bytes(gif, gif_bytes(frames, frame_ms))
    buf = io.BytesIO()
    strip_image(frames, strip_frames).save(buf, format="PNG")
    atomic_write_bytes(png, buf.getvalue())
    return gif, png


def default_grasp(mesh: Mesh, com: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """A grasp across the object's narrower horizontal extent, approaching from +z: one row
    [a, v, p1, w] (m). The contacts are the ray hits through the centre of mass, raised if
    needed so that the top of the object stays 35 mm below the grasp line (clear of the palm)."""

    verts = np.asarray(mesh.vertices, dtype=np.float64)
    c = np.asarray(com, dtype=np.float64).copy()
    c[2] = max(c[2], float(verts[:, 2].max()) - 0.035)
    ext = np.ptp(verts, axis=0)
    v = np.array([1.0, 0.0, 0.0]) if ext[0] <= ext[1] else np.array([0.0, 1.0, 0.0])
    far = 2.0 * float(np.linalg.norm(ext)) + 1.0
    scene = RayScene(mesh)
    hits = scene.intersect(
        np.stack([c - far * v, c + far * v]), np.stack([v, -v]).astype(np.float32)
    )
    if not bool(hits.hit.all()):
        raise InvalidArgumentError("default_grasp: the object is not hit through its centre")
    p1, p2 = hits.points[0].astype(np.float64), hits.points[1].astype(np.float64)
    return np.concatenate([[0.0, 0.0, -1.0], v, p1, [float(np.linalg.norm(p2 - p1))]])


def _load_object(name: str) -> tuple[Mesh, float, np.ndarray, np.ndarray]:
    """A built-in object (name or id) or a mesh file: (mesh, mass, com, inertia)."""

    if Path(name).suffix and Path(name).exists():
        mesh = load_mesh(name)
        density = 500.0
    else:
        spec = get_object(name)
        mesh, density = spec.to_mesh(), spec.density
    mp = mass_properties(mesh, density)
    return mesh, float(mp.mass), np.asarray(mp.center_of_mass), np.asarray(mp.inertia)


def show_trial(
    name: str,
    grasp: npt.ArrayLike | None = None,
    *,
    friction: float = 1.0,
    density_factor: float = 1.0,
    grip_force: float = 20.0,
    seed: int = 0,
    out: str | os.PathLike[str] = "shake_trial",
    every: int = 10,
    strip_frames: int = 8,
    size: int = 320,
) -> dict[str, Any]:
    """Run one shake trial and write its pictures ``<out>.gif`` and ``<out>_strip.png``.

    Args:
        name: built-in object name or id, or a mesh file (metres; density 500 kg/m^3).
        grasp: grasp row a(3) v(3) p1(3) w in metres; None: across the CoM from above
            (:func:`default_grasp`).
        friction: friction coefficient; density_factor: mass factor.
        grip_force: N per finger; seed: seed of the rotation axis and angle.
        out: output prefix; every: record every N simulation steps; strip_frames: frames in
            the PNG strip; size: frame size in pixels.

    Returns:
        The summary: object, grasp, success, ended_early, steps, frames, gif and strip paths.
    """
    mesh, mass, com, inertia = _load_object(name)
    g = np.asarray(grasp, dtype=np.float64) if grasp is not None else default_grasp(mesh, com)
    options = ShakeOptions(grip_force=grip_force, seed=seed)
    traj = shake_trajectory(
        mesh,
        mass,
        com,
        inertia,
        g,
        friction,
        density_factor,
        options=options,
        record_every=every,
    )
    gif, png = write_trial_pictures(traj, [mesh], out, size=size, strip_frames=strip_frames)
    return {
        "object": name,
        "grasp": [round(float(x), 6) for x in g],
        "success": bool(traj.success),
        "ended_early": bool(traj.ended_early),
        "steps": int(traj.steps),
        "frames": len(traj.time),
        "gif": str(gif),
        "strip": str(png),
    }
