"""Render the camera views of a scene as arrays (RGB, sensor and ideal depth, instance ids).

:func:`iter_views` is the one rendering loop a scene pipeline calls: objects as (mesh, X_WO,
instance id) triples, the tote mesh and its pose, which views of the MetaGraspNet rig (or any
list of :class:`~mgn.scene.cameras.CameraView`). It yields one :class:`ViewImages` per view;
:func:`mgn.io.view_images.render_views` renders and writes the image files.
:func:`depth_picture` makes the picture of a depth image for people.
"""

from __future__ import annotations

import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError, InvalidTypeError
from mgn.geometry.mesh import Mesh, make_box
from mgn.render.photo import PhotoRenderer
from mgn.render.renderer import Instance, LightSample, Renderer
from mgn.render.sensor import SensorName, apply_depth_sensor
from mgn.render.settings import RenderSettings
from mgn.scene.cameras import CameraView, Intrinsics, mgn_rig
from mgn.scene.lens import Lens, lens_for

__all__ = ["ViewImages", "depth_picture", "depth_picture_indexed", "iter_views"]

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
            "denoised", "max_bounces"}`` (:meth:`mgn.render.settings.RenderSettings.describe`).
        pinhole: for a camera with lens distortion, the pinhole render (camera
            ``lens.render_K``, same pose) these images were resampled from; None otherwise.
        lens: the camera's :class:`~mgn.scene.lens.Lens` (None for a pinhole camera).
        seconds: wall seconds of this view's parts: ``raster`` (the OpenGL pass: depth and
            ids, and the RGB with the raster engine), ``trace``, ``denoise`` and ``develop``
            (path engine), ``sensor`` (the depth sensor model).
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
    pinhole: ViewImages | None = field(default=None, repr=False)
    lens: Lens | None = field(default=None, repr=False)
    seconds: dict[str, float] = field(default_factory=dict, repr=False, compare=False)


def _distorted(images: ViewImages, view: CameraView, lens: Lens) -> ViewImages:
    """The images of the distorted camera ``view`` resampled from the pinhole render ``images``
    (docs/cameras.md): ids nearest, RGB bilinear, the ideal depth bilinear in 1/z inside one
    surface (the nearest pixel at edges). The sensor depth is that same interpolated surface plus
    the sensor's deviation at the nearest pinhole pixel (its noise keeps its statistics), invalid
    where the sensor gave nothing and at depth discontinuities."""
    ids = images.instance_ids
    ideal = images.depth_ideal
    deviation = np.where(images.valid, images.depth - ideal, np.float32(np.nan))
    surface = lens.warp_depth(ideal, at_edges="invalid")
    depth = (surface + lens.warp_nearest(deviation)).astype(np.float32)
    valid = np.isfinite(depth)
    return ViewImages(
        images.index,
        view,
        lens.warp_rgb(images.rgb),
        depth,
        lens.warp_depth(ideal, ids, at_edges="nearest"),
        valid,
        lens.warp_nearest(ids),
        images.light,
        images.engine,
        pinhole=images,
        lens=lens,
        seconds=images.seconds,
    )


_CMAP = np.array(
    [[48, 18, 59], [50, 110, 230], [40, 200, 160], [160, 230, 50], [250, 180, 40], [200, 30, 10]],
    dtype=np.float64,
)


def _depth_lut() -> npt.NDArray[np.uint8]:
    t = np.linspace(0.0, len(_CMAP) - 1, 256)
    i0 = np.minimum(t.astype(np.int64), len(_CMAP) - 2)
    f = (t - i0)[:, None]
    out: npt.NDArray[np.uint8] = np.round(_CMAP[i0] * (1 - f) + _CMAP[i0 + 1] * f).astype(np.uint8)
    return out


_DEPTH_LUT = _depth_lut()


def depth_picture(depth: npt.ArrayLike) -> npt.NDArray[np.uint8]:
    """(H, W, 3) uint8 picture of a depth image (m; NaN or <= 0 invalid): inverse depth
    normalised over the valid pixels, colour-mapped (255 levels, so that with black the picture
    fits a 256-colour palette) from dark blue (far) to red (near); invalid pixels black."""
    index, palette = depth_picture_indexed(depth)
    return palette[index]


def depth_picture_indexed(
    depth: npt.ArrayLike,
) -> tuple[npt.NDArray[np.uint8], npt.NDArray[np.uint8]]:
    """The picture of :func:`depth_picture` as (H, W) uint8 indices into a (K, 3) uint8 palette of
    the colours it uses (K <= 256: black and 255 levels): ``palette[index]`` is the picture (a
    palette PNG: about half the bytes of the RGB picture)."""
    d = np.asarray(depth, np.float32)
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(d)
        valid &= d > 0
    key = np.zeros(d.shape, np.uint8)  # 0 invalid (black), 1 + level otherwise
    if valid.any():
        inv = 1.0 / d[valid]
        lo, hi = float(inv.min()), float(inv.max())
        level = np.round((inv - lo) * (254.0 / max(hi - lo, 1e-12))).astype(np.uint8)
        level += 1
        key[valid] = level
    # Level l of 0..254 takes the colour map's entry round(l * 255 / 254) (both ends kept).
    lut = _DEPTH_LUT[np.round(np.arange(255) * (255.0 / 254.0)).astype(np.int64)]
    colours = np.concatenate([np.zeros((1, 3), np.uint8), lut])
    used = np.flatnonzero(np.bincount(key.ravel(), minlength=256))
    remap = np.zeros(256, np.uint8)
    remap[used] = np.arange(len(used))
    return remap[key], colours[used]


def _checked_scene(
    objects: Sequence[tuple[Mesh, npt.ArrayLike, int]],
    tote: Mesh | None,
    X_W_tote: npt.ArrayLike | None,
) -> np.ndarray:
    """Checks the scene arguments of :func:`iter_views`; returns the tote pose (4, 4)."""
    X_tote = np.eye(4) if X_W_tote is None else np.asarray(X_W_tote, np.float64)
    if X_tote.shape != (4, 4) or not np.all(np.isfinite(X_tote)):
        raise InvalidArgumentError(
            f"X_W_tote must be a finite (4, 4) pose, got shape {X_tote.shape}"
        )
    for k, item in enumerate(objects):
        if len(item) != 3:
            raise InvalidArgumentError(
                f"objects[{k}] must be (mesh, X_WO, instance_id), got {item!r}"
            )
        if int(item[2]) < 1:
            raise InvalidArgumentError(
                f"objects[{k}]: instance id must be >= 1 (0 is the background)"
            )
    if not objects and tote is None:
        raise InvalidArgumentError("render_views: empty scene (no objects and no tote)")

    return X_tote


def _cameras(
    views: Sequence[int] | Sequence[CameraView] | Sequence[tuple[int, CameraView]] | None,
    intr: Intrinsics,
    rig_seed: int,
    X_tote: np.ndarray,
) -> list[tuple[int, CameraView]]:
    """(view index, camera) per requested view of :func:`iter_views`."""
    cams: list[tuple[int, CameraView]]
    if views is None or all(isinstance(v, (int, np.integer)) for v in views):
        poses, _ = mgn_rig(rig_seed, X_tote[:3, 3])
        idx = range(len(poses)) if views is None else [int(cast(int, v)) for v in views]
        for v in idx:
            if not 0 <= v < len(poses):
                raise InvalidArgumentError(f"view index must be in 0..{len(poses) - 1}, got {v}")
        cams = [(v, CameraView(intr, poses[v])) for v in idx]
    else:
        cams = []
        for k, view_item in enumerate(views):
            if (
                isinstance(view_item, tuple)
                and len(view_item) == 2
                and isinstance(view_item[1], CameraView)
            ):
                cams.append((int(view_item[0]), view_item[1]))
            elif isinstance(view_item, CameraView):
                cams.append((k, view_item))
            else:
                raise InvalidTypeError(
                    f"views[{k}] must be a view index, a CameraView or (index, CameraView), "
                    f"got {view_item!r}"
                )
    return cams


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
    """Render the views of a scene one at a time (the arguments of :func:`mgn.render_views`, without
    ``out_dir``): the scene is uploaded once and each view's images are yielded before the next
    view is rendered, so memory does not grow with the number of views. ``views`` may also be
    (view index, camera) pairs: the index names the files and seeds the view's randomisation.

    With ``render.engine == "path"`` the RGB image is path-traced (:mod:`mgn.render.photo`);
    depth and instance ids still come from the raster's geometry passes, which the tracer
    matches pixel for pixel.

    A camera with lens distortion (``K.distortion``) is rendered by either engine as the pinhole
    ``lens_for(K).render_K`` and resampled through the OpenCV model (:mod:`mgn.scene.lens`,
    docs/cameras.md); the yielded images are the distorted ones, ``ViewImages.pinhole`` holds
    the render they came from (the per-view labels are computed on it and resampled).
    """
    settings = render if render is not None else RenderSettings()
    X_tote = _checked_scene(objects, tote, X_W_tote)
    cams = _cameras(views, Intrinsics.mgn_synthetic() if K is None else K, rig_seed, X_tote)
    # A camera with distortion is rendered as the pinhole that covers it, then resampled.
    lenses = [lens_for(c.K) for _, c in cams]
    shot = [
        c if ln is None else CameraView(ln.render_K, c.X_WC)
        for (_, c), ln in zip(cams, lenses, strict=True)
    ]
    max_w = max(c.K.width for c in shot)
    max_h = max(c.K.height for c in shot)

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
                min(
                    (X_tote[:3, :3] @ np.array([x, y, z]) + X_tote[:3, 3])[2]
                    for x in corners[:, 0]
                    for y in corners[:, 1]
                    for z in corners[:, 2]
                )
            )
        X_floor = np.eye(4)
        X_floor[:2, 3] = X_tote[:2, 3]
        X_floor[2, 3] = z_floor - 0.005
        instances.append(Instance(upload(slab), X_floor, 0, randomize_color=True))
    r.set_instances(instances)
    flags = r.surface_flags_by_id()
    photo = None
    if settings.engine == "path":
        tote_color: tuple[float, ...] = (0.2, 0.35, 0.6)
        if tote is not None and tote.materials:
            tote_color = tuple(float(c) for c in np.asarray(tote.materials[0].base_color)[:3])
        photo = PhotoRenderer(
            objects,
            tote,
            X_tote,
            (slab, X_floor) if floor else None,
            settings,
            tote_color=tote_color,
            randomize=randomize,
            seed=seed,
            num_threads=num_threads,
        )

    for (v, view), lens, cam in zip(cams, lenses, shot, strict=True):
        t0 = time.perf_counter()
        img = r.render(
            cam, rgb=photo is None, randomize=randomize, seed=seed, view_index=v, shadows=shadows
        )
        assert img.depth is not None
        assert img.instance_ids is not None
        seconds = {"raster": time.perf_counter() - t0}
        if photo is not None:
            rgb, _ = photo.render(cam, v)
            engine = photo.describe()
            seconds.update(photo.last_seconds)
        else:
            assert img.rgb is not None
            rgb, engine = img.rgb, {"engine": "raster"}
        t1 = time.perf_counter()
        sens = apply_depth_sensor(
            img.depth,
            img.instance_ids,
            cam.K,
            sensor,
            flags_by_id=flags,
            seed=seed + v,
            num_threads=num_threads,
        )
        seconds["sensor"] = time.perf_counter() - t1
        res = ViewImages(
            v,
            cam,
            rgb,
            sens.depth,
            img.depth,
            sens.valid,
            img.instance_ids,
            img.light,
            engine,
            seconds=seconds,
        )
        yield res if lens is None else _distorted(res, view, lens)
