"""The one function that writes a scene folder: :func:`write_scene`.

``mgn generate`` calls :func:`write_scene` once per scene, on a temporary folder that is renamed
to ``scene<N>`` (with its manifest) only when the function returns. Whatever it writes must be
byte-reproducible (see :mod:`mgn.base.deterministic`): the same scene and config give the same
bytes whatever the executor.

It renders and labels every kept view with :func:`mgn.pipeline.label_scene.label_scene`, which
writes the docs/format.md files of each view, ``scene_gt.json`` and ``scene.json``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from mgn.io.scene_json import write_scene_json
from mgn.pipeline.config import CameraConfig, Config
from mgn.pipeline.label_cache import ObjectLabels
from mgn.pipeline.label_scene import LabelOptions, label_scene
from mgn.scene.cameras import CameraView, Intrinsics, hemisphere_rig, mgn_rig
from mgn.scene.scene import Scene

__all__ = ["label_options", "scene_intrinsics", "scene_views", "write_scene"]


def scene_intrinsics(camera: CameraConfig) -> Intrinsics:
    """The intrinsics of ``camera`` (a preset or the user's, with its lens distortion) at its
    resolution scale."""
    k = camera.intrinsics
    if isinstance(k, str):
        preset = Intrinsics.preset(k)
    else:
        preset = Intrinsics(k.width, k.height, k.fx, k.fy, k.cx, k.cy, k.distortion)
    return preset if camera.resolution_scale == 1.0 else preset.scaled(camera.resolution_scale)


def scene_views(
    scene: Scene, camera: CameraConfig, *, rig_seed: int | None = None
) -> list[tuple[int, CameraView]]:
    """(view index, camera) of every view kept by ``camera.views``, in order.

    The ``mgn`` rig is drawn from ``rig_seed`` (default: the scene seed;
    :func:`mgn.scene.cameras.mgn_rig`), looking at the tote centre (the world origin); the
    ``hemisphere`` rig and the user ``poses`` are fixed. View indices are those of the full rig,
    so ``views: [0, 5, 17]`` gives files ``0_*``, ``5_*`` and ``17_*``.
    """
    K = scene_intrinsics(camera)
    if camera.rig == "mgn":
        poses, _ = mgn_rig(scene.seed if rig_seed is None else rig_seed)
    elif camera.rig == "poses":
        poses = np.asarray(camera.poses, np.float64)
    else:
        h = camera.hemisphere
        poses = hemisphere_rig(h.radii, h.tilts, h.azimuths)
    return [(v, CameraView(K, poses[v])) for v in camera.view_indices]


def label_options(
    config: Config, seed: int, *, num_threads: int = 0, scene_grasps: bool | None = None
) -> LabelOptions:
    """The :class:`~mgn.pipeline.label_scene.LabelOptions` of a scene of ``config``: the camera
    section's sensor and randomisation, the labels switched on (``scene_grasps``: False turns
    the scene grasps off, None keeps ``labels.scene_grasps``), the render settings and the io
    section's archival mode; ``seed``: the scene seed."""
    return LabelOptions(
        sensor=config.camera.sensor,  # type: ignore[arg-type]
        randomize=config.camera.randomize,
        seed=seed,
        layout=config.labels.layout,
        scene_grasps=config.labels.scene_grasps if scene_grasps is None else scene_grasps,
        num_threads=num_threads,
        render=config.render,
        archival=config.io.archival,
    )


def write_scene(
    scene: Scene,
    folder: str | os.PathLike[str],
    config: Config,
    object_labels: Mapping[str, ObjectLabels],
    *,
    num_threads: int = 0,
) -> dict[str, float]:
    """Write the files of one scene into ``folder`` (an existing, empty temporary folder).

    Args:
        scene: the settled scene (instances 1..N, poses in the tote frame, seed).
        folder: where to write; the caller renames it to ``scene<N>`` afterwards.
        config: the dataset configuration (cameras, sensor, labels switched on).
        object_labels: name -> the cached labels of every object of the scene (object frame).
        num_threads: C++ threads per scene (0 = all cores).

    Returns:
        Seconds per labelling stage (render, object labels, layout, scene grasps, write, ...).

    Raises:
        OSError: a file cannot be written (``errno.ENOSPC`` when the disk is full).
    """

    out = Path(folder)
    if len(scene) == 0:
        write_scene_json(scene, out / "scene.json")
        return {}  # every object left the tote: nothing to render but the scene file says so
    labels = config.labels
    pj = su = None
    if labels.scene_grasps:
        got = [object_labels.get(inst.name) for inst in scene.instances]
        if labels.paralleljaw:
            pj = [g.paralleljaw if g is not None else None for g in got]
        if labels.suction:
            su = [g.suction if g is not None else None for g in got]
    options = label_options(config, scene.seed, num_threads=num_threads)
    views = scene_views(scene, config.camera)
    timings = label_scene(
        scene,
        out,
        views,
        pj_labels=pj,
        suction_labels=su,
        gripper=config.gripper,
        cup=config.cup,
        options=options,
    )
    return timings.seconds
