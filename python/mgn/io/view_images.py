"""Render the camera views of a scene and write the images (RGB, depth, instances).

:func:`render_views` renders with :func:`mgn.render.views.iter_views` and, given an output folder,
writes per view ``v`` (atomically):

- ``{v}_rgb.png``: 8-bit RGB.
- ``{v}_depth.png``: a picture of depth for people: colour-mapped normalised inverse depth of the
  sensor depth (8-bit palette PNG, read as RGB; invalid pixels black).
- ``{v}_depth.npz``: ``depth`` (sensor z-depth, **cm**, NaN invalid), ``depth_ideal`` (noise-free,
  cm, NaN where nothing is seen) and ``valid_depth`` (bool), float32, named as the docs/format.md
  keys of ``{v}.npz`` so the scene writer can merge them.
- ``{v}_instances.png``: 16-bit instance ids (0 = background, tote and floor).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn.base.atomic import atomic_write_bytes
from mgn.base.deterministic import npz_bytes
from mgn.base.units import M_TO_CM
from mgn.errors import InvalidArgumentError
from mgn.geometry.mesh import Mesh
from mgn.io.image_codecs import depth_picture_png, png_bytes
from mgn.render.views import ViewImages, iter_views
from mgn.scene.cameras import CameraView

__all__ = ["render_views", "write_view_images"]


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
        tote: the tote mesh (e.g. :func:`mgn.objects.tote_mesh`) or None; drawn with instance id 0.
        views: view indices of the MetaGraspNet rig (default: all 37), explicit cameras, or
            (view index, camera) pairs.
        out_dir: folder for the files (created); None writes nothing.
        X_W_tote: pose of the tote in the world (default identity). The rig looks at its origin
            (the centre of the inner floor).
        rig_seed: seed of the rig (:func:`mgn.scene.cameras.mgn_rig`).
        K: intrinsics for rig views (default MGN synthetic, 1200 x 1200).
        sensor: depth sensor preset for ``depth``.
        randomize: per-view light and tote / floor colour randomisation from (seed, view).
        seed: seed of lighting randomisation and sensor noise (the noise of view v uses
            seed + v).
        floor: draw a floor slab under the tote (instance id 0).
        renderer: reuse a Renderer large enough for the views (the meshes are added to it, its
            instances replaced); default or too small: a new one.

        **kwargs: the keyword arguments of :func:`mgn.render.views.iter_views` (``X_W_tote``,
            ``rig_seed``, ``K``, ``sensor``, ``randomize``, ``seed``, ``floor``, ``shadows``,
            ``renderer``).

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
            write_view_images(out_path, res)
    return results


def write_view_images(folder: Path, res: ViewImages) -> None:
    """Write the image files of one rendered view into ``folder`` (see the module doc)."""
    v = res.index
    atomic_write_bytes(folder / f"{v}_rgb.png", png_bytes(res.rgb))
    atomic_write_bytes(folder / f"{v}_depth.png", depth_picture_png(res.depth))
    ideal = np.where(res.depth_ideal > 0, res.depth_ideal, np.nan).astype(np.float32)
    data = npz_bytes(
        depth=(res.depth * M_TO_CM).astype(np.float32),
        depth_ideal=(ideal * M_TO_CM).astype(np.float32),
        valid_depth=res.valid,
    )
    atomic_write_bytes(folder / f"{v}_depth.npz", data)
    if res.instance_ids.max(initial=0) > 65535:
        raise InvalidArgumentError("instance ids above 65535 do not fit the 16-bit instance PNG")
    atomic_write_bytes(folder / f"{v}_instances.png", png_bytes(res.instance_ids.astype(np.uint16)))
