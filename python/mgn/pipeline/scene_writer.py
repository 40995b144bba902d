"""The one function that writes a scene folder: :func:`write_scene`.

``mgn generate`` calls :func:`write_scene` once per scene, on a temporary folder that is renamed
to ``scene<N>`` (with its manifest) only when the function returns. Whatever it writes must be
byte-reproducible (see :mod:`mgn.io.deterministic`): the same scene and config give the same
bytes whatever the executor.

For now it writes ``scene.json`` (:meth:`mgn.scene.Scene.to_json`) and the rendered views of
:func:`mgn.render.views.render_views` (``{v}_rgb.png``, ``{v}_depth.png``, ``{v}_depth.npz``,
``{v}_instances.png``); the full FORMAT.md writer (per-view labels, HDF5, layout) replaces its
body, keeping the signature.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping
from pathlib import Path

from mgn.config import CameraConfig, Config
from mgn.pipeline.label_cache import ObjectLabels
from mgn.render.camera import CameraView, Intrinsics, hemisphere_rig, mgn_rig
from mgn.scene.scene import Scene

__all__ = ["scene_intrinsics", "scene_views", "write_scene"]


def scene_intrinsics(camera: CameraConfig) -> Intrinsics:
    """The intrinsics preset of ``camera`` at its resolution scale."""
    preset = {
        "mgn_synthetic": Intrinsics.mgn_synthetic,
        "zivid_two_like": Intrinsics.zivid_two_like,
    }[camera.intrinsics]()
    return preset if camera.resolution_scale == 1.0 else preset.scaled(camera.resolution_scale)


def scene_views(scene: Scene, camera: CameraConfig) -> list[tuple[int, CameraView]]:
    """(view index, camera) of every view kept by ``camera.views``, in order.

    The ``mgn`` rig is drawn from the scene seed (:func:`mgn.render.mgn_rig`), looking at the
    tote centre (the world origin); the ``hemisphere`` rig is fixed. View indices are those of
    the full rig, so ``views: [0, 5, 17]`` gives files ``0_*``, ``5_*`` and ``17_*``.
    """
    K = scene_intrinsics(camera)
    if camera.rig == "mgn":
        poses, _ = mgn_rig(scene.seed)
    else:
        h = camera.hemisphere
        poses = hemisphere_rig(h.radii, h.tilts, h.azimuths)
    return [(v, CameraView(K, poses[v])) for v in camera.view_indices]


def write_scene(
    scene: Scene,
    folder: str | os.PathLike[str],
    config: Config,
    object_labels: Mapping[str, ObjectLabels],
) -> None:
    """Write the files of one scene into ``folder`` (an existing, empty temporary folder).

    Args:
        scene: the settled scene (instances 1..N, poses in the tote frame, seed).
        folder: where to write; the caller renames it to ``scene<N>`` afterwards.
        config: the dataset configuration (cameras, sensor, labels switched on).
        object_labels: name -> the cached labels of every object of the scene (object frame).

    Raises:
        OSError: a file cannot be written (``errno.ENOSPC`` when the disk is full).
    """
    from mgn.render.views import _write_view, render_views, tote_mesh

    out = Path(folder)
    scene.to_json(out / "scene.json")
    if len(scene) == 0:
        return  # every object left the tote: nothing to render but the scene file says so
    meshes: dict[tuple[str, str], object] = {}
    objects = []
    for k, inst in enumerate(scene.instances):
        key = (inst.name, inst.source)
        if key not in meshes:  # copies share one mesh (uploaded once)
            meshes[key] = scene.mesh(k)
        objects.append((meshes[key], inst.X_WO, inst.instance_id))
    cams = scene_views(scene, config.camera)
    common = {
        "sensor": config.camera.sensor,
        "randomize": config.camera.randomize,
        "seed": scene.seed,
    }
    if config.camera.rig == "mgn":
        render_views(
            objects,  # type: ignore[arg-type]
            tote_mesh(scene.tote),
            views=[v for v, _ in cams],
            out_dir=out,
            rig_seed=scene.seed,
            K=cams[0][1].K,
            **common,  # type: ignore[arg-type]
        )
        return
    # Explicit cameras: render_views numbers them by position; write them under the rig index.
    images = render_views(
        objects,  # type: ignore[arg-type]
        tote_mesh(scene.tote),
        views=[c for _, c in cams],
        out_dir=None,
        **common,  # type: ignore[arg-type]
    )
    for (v, _), res in zip(cams, images, strict=True):
        _write_view(out, dataclasses.replace(res, index=v))
