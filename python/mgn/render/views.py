"""Render the camera views of a scene and write the images (RGB, depth, instances).

:func:`render_views` is the one entry point a scene pipeline calls: objects as (mesh, X_WO,
instance id) triples, the tote mesh and its pose, which views of the MetaGraspNet rig (or any
list of :class:`~mgn.render.camera.CameraView`), and an output folder. Per view ``v`` it writes
(atomically):

- ``{v}_rgb.png``: 8-bit RGB.
- ``{v}_depth.png``: a picture of depth for people: colour-mapped normalised inverse depth of the
  sensor depth (8-bit RGB, invalid pixels black).
- ``{v}_depth.npz``: ``depth`` (sensor z-depth, **cm**, NaN invalid), ``depth_ideal`` (noise-free,
  cm, NaN where nothing is seen) and ``valid_depth`` (bool), float32, named as the keys
  (docs/format.md) of ``{v}.npz`` so the scene writer can merge them.
- ``{v}_instances.png``: 16-bit instance ids (0 = background, tote and floor).
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.geometry import Mesh, make_box
from mgn.io.atomic import atomic_write_bytes
from mgn.objects import ToteSpec, make_tote
from mgn.render.camera import CameraView, Intrinsics, mgn_rig
from mgn.render.photo import PhotoRenderer, RenderSettings
from mgn.render.renderer import Instance, LightSample, Renderer
from mgn.render.sensor import SensorName, apply_depth_sensor

__all__ = ["ViewImages", "depth_picture", "iter_views", "render_views", "tote_mesh"]

M_TO_CM = 100.0
#: Side of the square floor slab drawn under the tote, m.
FLOOR_SIZE = 3.0


@dataclass(frozen=True)
class ViewImages:
    """Everything rendered for one view (lengths in metres).

    Attributes:
        index: view index (in the rig, or in the given list).
        view: the camera.
        rgb: (H, W, 3) uint8.
        depth: (H, W) float32 sensor z-depth, m, NaN invalid.
        depth_ideal: (H, W) float32 noise-free z-depth, m, 0 where nothing is seen.
        valid: (H, W) bool.
        instance_ids: (H, W) int32, 0 = background.
        light: the light used (raster engine; the path engine's lights are in ``engine``).
        engine: what made ``rgb``: ``{"engine": "raster"}`` or ``{"engine": "path", "spp",
            "denoised", "max_bounces"}`` (:meth:`mgn.render.photo.RenderSettings.describe`).
    """

    index: int
    view: CameraView
    rgb: npt.NDArray[np.uint8]
    depth: npt.NDArray[np.float32]
    depth_ideal: npt.NDArray[np.float32]
    valid: npt.NDArray[np.bool_]
    instance_ids: npt.NDArray[np.int32]
    light: LightSample
    engine: dict[str, Any] = field(default_factory=lambda: {"engine": "raster"})


def tote_mesh(spec: ToteSpec | None = None) -> Mesh:
    """The tote (:func:`mgn.objects.make_tote`) as a Mesh with its colour as material."""
    s = ToteSpec() if spec is None else spec
    vertices, faces = make_tote(s)
    mat = _core.Material()
    mat.name = "tote"
    mat.base_color = np.asarray(s.color, np.float32)
    mat.specular = np.full(3, 0.1, np.float32)
    return Mesh(np.asarray(vertices, np.float32), faces, None, [mat], [], "tote")


_CMAP = np.array(
    [[48, 18, 59], [50, 110, 230], [40, 200, 160], [160, 230, 50], [250, 180, 40], [200, 30, 10]],
    dtype=np.float64,
)


def _depth_lut() -> npt.NDArray[np.uint8]:
    t = np.linspace(0.0, len(_CMAP) - 1, 256)
    i0 = np.minimum(t.astype(np.int64), len(_CMAP) - 2)
    f = (t - i0)[:, None]
    return np.round(_CMAP[i0] * (1 - f) + _CMAP[i0 + 1] * f).astype(np.uint8)


_DEPTH_LUT = _depth_lut()


def depth_picture(depth: npt.ArrayLike) -> npt.NDArray[np.uint8]:
    """(H, W, 3) uint8 picture of a depth image (m; NaN or <= 0 invalid): inverse depth
    normalised over the valid pixels, colour-mapped (256 levels) from dark blue (far) to red
    (near); invalid pixels black."""
    d = np.asarray(depth, np.float32)
    valid = np.isfinite(d) & (d > 0)
    out = np.zeros((*d.shape, 3), np.uint8)
    if not valid.any():
        return out
    inv = 1.0 / d[valid]
    lo, hi = float(inv.min()), float(inv.max())
    level = np.round((inv - lo) * (255.0 / max(hi - lo, 1e-12))).astype(np.uint8)
    out[valid] = _DEPTH_LUT[level]
    return out


def iter_views(
    objects: Sequence[tuple[Mesh, npt.ArrayLike, int]],
    tote: Mesh | None,
    views: Sequence[int] | Sequence[CameraView] | Sequence[tuple[int, CameraView]] | None = None,
    *,
    X_W_tote: npt.ArrayLike | None = None,
    rig_seed: int = 0,
    K: Intrinsics | None = None,
    sensor: SensorName = "structured-light",
    randomize: bool = True,
    seed: int = 0,
    floor: bool = True,
    shadows: bool = True,
    renderer: Renderer | None = None,
    render: RenderSettings | None = None,
    num_threads: int = 0,
) -> Iterator[ViewImages]:
    """Render the views of a scene one at a time (the arguments of :func:`render_views`, without
    ``out_dir``): the scene is uploaded once and each view's images are yielded before the next
    view is rendered, so memory does not grow with the number of views. ``views`` may also be
    (view index, camera) pairs: the index names the files and seeds the view's randomisation.

    With ``render.engine == "path"`` the RGB image is path-traced (:mod:`mgn.render.photo`);
    depth and instance ids still come from the raster's geometry passes, which the tracer
    matches pixel for pixel.
    """
    settings = render if render is not None else RenderSettings()
    X_tote = np.eye(4) if X_W_tote is None else np.asarray(X_W_tote, np.float64)
    if X_tote.shape != (4, 4) or not np.all(np.isfinite(X_tote)):
        raise ValueError(f"X_W_tote must be a finite (4, 4) pose, got shape {X_tote.shape}")
    for k, item in enumerate(objects):
        if len(item) != 3:
            raise ValueError(f"objects[{k}] must be (mesh, X_WO, instance_id), got {item!r}")
        if int(item[2]) < 1:
            raise ValueError(f"objects[{k}]: instance id must be >= 1 (0 is the background)")
    if not objects and tote is None:
        raise ValueError("render_views: empty scene (no objects and no tote)")

    # Cameras.
    intr = Intrinsics.mgn_synthetic() if K is None else K
    cams: list[tuple[int, CameraView]]
    if views is None or all(isinstance(v, (int, np.integer)) for v in views):
        poses, _ = mgn_rig(rig_seed, X_tote[:3, 3])
        idx = range(len(poses)) if views is None else [int(v) for v in views]  # type: ignore[union-attr]
        for v in idx:
            if not 0 <= v < len(poses):
                raise ValueError(f"view index must be in 0..{len(poses) - 1}, got {v}")
        cams = [(v, CameraView(intr, poses[v])) for v in idx]
    else:
        cams = []
        for k, v in enumerate(views):
            if isinstance(v, tuple) and len(v) == 2 and isinstance(v[1], CameraView):
                cams.append((int(v[0]), v[1]))
            elif isinstance(v, CameraView):
                cams.append((k, v))
            else:
                raise TypeError(
                    f"views[{k}] must be a view index, a CameraView or (index, CameraView), "
                    f"got {v!r}"
                )
    max_w = max(c.K.width for _, c in cams)
    max_h = max(c.K.height for _, c in cams)

    # Scene.
    r = renderer
    if r is None or r.max_size[0] < max_w or r.max_size[1] < max_h:
        r = Renderer(max_w, max_h)
    mesh_ids: dict[int, int] = {}
    instances: list[Instance] = []

    def upload(mesh: Mesh) -> int:
        key = id(mesh)
        if key not in mesh_ids:
            mesh_ids[key] = r.add_mesh(mesh)
        return mesh_ids[key]

    for mesh, X_WO, inst in objects:
        instances.append(Instance(upload(mesh), np.asarray(X_WO, np.float64), int(inst)))
    if tote is not None:
        instances.append(Instance(upload(tote), X_tote, 0, randomize_color=True))
    if floor:
        slab = make_box((FLOOR_SIZE, FLOOR_SIZE, 0.01))
        z_floor = 0.0
        if tote is not None:
            corners = np.asarray(tote.bounds)
            z_floor = float(
                min((X_tote[:3, :3] @ np.array([x, y, z]) + X_tote[:3, 3])[2]
                    for x in corners[:, 0] for y in corners[:, 1] for z in corners[:, 2])
            )  # fmt: skip
        X_floor = np.eye(4)
        X_floor[:2, 3] = X_tote[:2, 3]
        X_floor[2, 3] = z_floor - 0.005
        instances.append(Instance(upload(slab), X_floor, 0, randomize_color=True))
    r.set_instances(instances)
    flags = r.surface_flags_by_id()
    photo = None
    if settings.engine == "path":
        tote_color = (0.2, 0.35, 0.6)
        if tote is not None and tote.materials:
            tote_color = tuple(float(c) for c in np.asarray(tote.materials[0].base_color)[:3])
        photo = PhotoRenderer(
            objects, tote, X_tote, (slab, X_floor) if floor else None, settings,
            tote_color=tote_color, randomize=randomize, seed=seed, num_threads=num_threads,
        )  # fmt: skip

    for v, cam in cams:
        img = r.render(cam, rgb=photo is None, randomize=randomize, seed=seed, view_index=v,
                       shadows=shadows)  # fmt: skip
        assert img.depth is not None and img.instance_ids is not None
        if photo is not None:
            rgb, _ = photo.render(cam, v)
            engine = photo.describe()
        else:
            assert img.rgb is not None
            rgb, engine = img.rgb, {"engine": "raster"}
        sens = apply_depth_sensor(
            img.depth, img.instance_ids, cam.K, sensor, flags_by_id=flags, seed=seed + v
        )
        res = ViewImages(
            v, cam, rgb, sens.depth, img.depth, sens.valid, img.instance_ids, img.light, engine
        )
        yield res


def render_views(
    objects: Sequence[tuple[Mesh, npt.ArrayLike, int]],
    tote: Mesh | None,
    views: Sequence[int] | Sequence[CameraView] | Sequence[tuple[int, CameraView]] | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    **kwargs: Any,
) -> list[ViewImages]:
    """Render views of a scene; write the images when ``out_dir`` is given.

    Args:
        objects: (mesh, X_WO (4, 4), instance id >= 1) per object; meshes shared by several
            instances are uploaded once (by identity).
        tote: the tote mesh (e.g. :func:`tote_mesh`) or None; drawn with instance id 0.
        views: view indices of the MetaGraspNet rig (default: all 37), explicit cameras, or
            (view index, camera) pairs.
        out_dir: folder for the files (created); None writes nothing.
        X_W_tote: pose of the tote in the world (default identity). The rig looks at its origin
            (the centre of the inner floor).
        rig_seed: seed of the rig (:func:`mgn.render.mgn_rig`).
        K: intrinsics for rig views (default MGN synthetic, 1200 x 1200).
        sensor: depth sensor preset for ``depth``.
        randomize: per-view light and tote / floor colour randomisation from (seed, view).
        seed: seed of lighting randomisation and sensor noise (the noise of view v uses
            seed + v).
        floor: draw a floor slab under the tote (instance id 0).
        renderer: reuse a Renderer large enough for the views (the meshes are added to it, its
            instances replaced); default or too small: a new one.
        render: how the RGB images are made (:class:`mgn.render.photo.RenderSettings`; default
            the raster engine).
        num_threads: path tracer threads (0 = all cores); images do not depend on it.

        **kwargs: the keyword arguments of :func:`iter_views` (``X_W_tote``, ``rig_seed``,
            ``K``, ``sensor``, ``randomize``, ``seed``, ``floor``, ``shadows``, ``renderer``,
            ``render``, ``num_threads``).

    Returns:
        One :class:`ViewImages` per view, in order.
    """
    out_path = None if out_dir is None else Path(out_dir)
    if out_path is not None:
        out_path.mkdir(parents=True, exist_ok=True)
    results: list[ViewImages] = []
    for res in iter_views(objects, tote, views, **kwargs):
        results.append(res)
        if out_path is not None:
            _write_view(out_path, res)
    return results


def _write_view(folder: Path, res: ViewImages) -> None:
    from mgn.io.scene_format import png_bytes as _png

    v = res.index
    atomic_write_bytes(folder / f"{v}_rgb.png", _png(res.rgb))
    atomic_write_bytes(folder / f"{v}_depth.png", _png(depth_picture(res.depth)))
    ideal = np.where(res.depth_ideal > 0, res.depth_ideal, np.nan).astype(np.float32)
    from mgn.io.deterministic import npz_bytes  # reproducible bytes (no zip timestamps)

    data = npz_bytes(
        depth=(res.depth * M_TO_CM).astype(np.float32),
        depth_ideal=(ideal * M_TO_CM).astype(np.float32),
        valid_depth=res.valid,
    )
    atomic_write_bytes(folder / f"{v}_depth.npz", data)
    if res.instance_ids.max(initial=0) > 65535:
        raise ValueError("instance ids above 65535 do not fit the 16-bit instance PNG")
    atomic_write_bytes(folder / f"{v}_instances.png", _png(res.instance_ids.astype(np.uint16)))
