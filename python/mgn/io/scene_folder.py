"""The MetaGraspNet scene folder (docs/format.md): the one writer of a labelled view.

A scene folder ``<root>/scene<N>/`` holds, per view ``v``: ``{v}_rgb.png``, ``{v}.npz``,
``{v}_depth.png``, ``{v}_scene.hdf5``, ``{v}_order.csv``, ``{v}_order.json``,
``{v}_layout.json`` (mgn: bin relations and the difficulty level), ``{v}_mgn.hdf5`` (mgn: the
images MetaGraspNet does not have) and ``{v}_camera_params.json``; and once per scene
``scene_gt.json``.

Bytes (docs/format.md): the npz holds MetaGraspNet's keys only, with the dtypes its own scripts work
with unchanged: ``depth`` and ``occlusion`` float32, ``instances_objects`` uint8 (at most 255
instances), ``instances_semantic`` uint16 (float32 if a category id exceeds 65535),
``occlusion_objects`` bool; zip deflate. Every deflate stream (zip entries, HDF5 gzip chunks, PNG)
is made by libdeflate at :data:`DEFLATE_LEVEL` (:mod:`mgn.base.compress`): standard streams that
zlib and every reader decode. The sensor depth is stored on the
:data:`mgn.io.scene_schema.DEPTH_GRID_CM` grid the sensor presets report (:func:`depth_to_cm`):
exact, and half the bytes. mgn's own images go to ``{v}_mgn.hdf5`` with HDF5's shuffle filter
(standard in every HDF5 library), float32 images delta-coded along rows
(:mod:`mgn.io.image_codecs`): ``depth_ideal`` (metres, the renderer's values, when the heat map is a
residual; else cm), ``com_heatmap`` (given the scene's CoM parameters, as its residual from
:func:`com_heatmap_prediction`: zeros for the pipeline's heat maps), and ``valid_depth`` only when
it is not exactly ``isfinite(depth)`` (the sensors mark invalid pixels NaN, so normally it is
derived on reading). In ``{v}_scene.hdf5`` the tool poses that share their contact poses' rotation
are HDF5 virtual datasets over them (:func:`mgn.io.scene_hdf5.hdf5_bytes`). The depth picture is a
palette PNG of the noise-free depth where the sensor has a value. Every array reads back
bit-identical; ``write_view(..., archival=True)`` is the lossy compact archival mode (sensor depth
on :data:`ARCHIVAL_DEPTH_STEP_CM` in an LZMA zip entry, grasp poses rounded, RGB at libdeflate level
9).

Lengths are **centimetres** in these files (MetaGraspNet's convention) and SI everywhere else in
mgn: :class:`mgn.io.scene_schema.ViewRecord` holds metres, the writer converts, and
:mod:`mgn.io.dataset` converts back with the same table (:data:`mgn.io.scene_schema.CM_RULES`).

Every file is written atomically, and byte-for-byte reproducibly (no timestamps in the zip entries
of the npz nor in the HDF5 objects), so the same seed gives files with the same checksums.

This module writes the files (:func:`write_view`, :func:`write_scene_gt`) and chooses their
compression levels and the archival mode; what the folder holds and its units are
:mod:`mgn.io.scene_schema`, the image encodings :mod:`mgn.io.image_codecs`, the HDF5 files
:mod:`mgn.io.scene_hdf5`.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn.base.atomic import atomic_write_bytes, atomic_write_text
from mgn.base.deterministic import npz_bytes
from mgn.base.units import M_TO_CM
from mgn.errors import InvalidArgumentError
from mgn.io.image_codecs import (
    COM_RESIDUAL_ENCODING,
    DEFLATE_LEVEL,
    com_heatmap_prediction,
    com_residual,
    depth_picture_png,
    png_bytes,
)
from mgn.io.scene_hdf5 import hdf5_bytes, mgn_hdf5_bytes, unscored_marks
from mgn.io.scene_schema import (
    HDF5_INT_LEAVES,
    UNITS_ATTR,
    ViewRecord,
    depth_to_cm,
    id_image_dtype,
    to_cm,
)

__all__ = [
    "ARCHIVAL_DEPTH_STEP_CM",
    "ARCHIVAL_POSE_STEP_CM",
    "ARCHIVAL_ROTATION_STEP",
    "DEPTH_PICTURE_LEVEL",
    "MGN_IMAGE_LEVEL",
    "NPZ_LEVEL",
    "RGB_LEVEL",
    "RUN_IMAGES",
    "RUN_LEVEL",
    "SCENE_HDF5_LEVEL",
    "scene_gt_entries",
    "write_scene_gt",
    "write_view",
]


#: Archival mode (``io.archival``): grid (cm) of the stored sensor and ideal depth, 1/64 cm =
#: 0.15625 mm (values at most 0.078 mm from the model's; half the structured-light noise at 0.3 m).
ARCHIVAL_DEPTH_STEP_CM = 2.0**-6

#: Archival mode: grid of the rotation entries and of the translations (cm) of the grasp poses
#: (2^-16: at most 0.0004 degrees; 1/1024 cm = 0.01 mm).
ARCHIVAL_ROTATION_STEP = 2.0**-16
ARCHIVAL_POSE_STEP_CM = 2.0**-10
_GRASP_GROUPS = ("colliding_grasps/", "non_colliding_grasps/")


def _archival_poses(poses_cm: npt.ArrayLike) -> npt.NDArray[np.float32]:
    """(…, 4, 4) float32 poses (cm) with rotation entries and translations on the archival
    grids (the last row stays [0, 0, 0, 1])."""
    out = np.array(poses_cm, np.float32)
    if out.size:
        out[..., :3, :3] = _snap(out[..., :3, :3], ARCHIVAL_ROTATION_STEP)
        out[..., :3, 3] = _snap(out[..., :3, 3], ARCHIVAL_POSE_STEP_CM)
    return out


def _snap(a: npt.NDArray[np.float32], step: float) -> npt.NDArray[np.float32]:
    """float32 ``a`` rounded to multiples of ``step`` (a power of two; NaN stays NaN)."""
    out: npt.NDArray[np.float32] = (np.round(a / np.float32(step)) * np.float32(step)).astype(
        np.float32
    )
    return out


#: libdeflate level of the images of ``{v}_mgn.hdf5`` (``depth_ideal``'s gradient residual) in
#: the default mode: level 6 (the archival mode's) gives 0.99x the bytes in 1.2x the time.
MGN_IMAGE_LEVEL = 5
#: libdeflate level of the chunks of ``{v}_scene.hdf5`` (grasps, keypoints) in the default mode:
#: level 6 (the archival mode's) gives 0.998x the bytes (float32 rotations are at their entropy)
#: in 1.07x the time.
SCENE_HDF5_LEVEL = 5
#: libdeflate level of the zip entries of ``{v}.npz``: the sensor depth in 0.84x the bytes of
#: zlib's level 1 in the same time (level 6: another -0.7 %, +30 % time), the masks in 0.3x.
NPZ_LEVEL = 5


#: libdeflate level of the scene writer's ``{v}_depth.png``, a picture of the noise-free depth at
#: the pixels where the sensor gives a value (black elsewhere): bands of equal colour
#: (docs/format.md).
DEPTH_PICTURE_LEVEL = DEFLATE_LEVEL
#: libdeflate level of ``{v}_rgb.png`` in the default mode: 0.97x the bytes of level 6 for +3 ms
#: per 1200 x 1200 view (-0.4 MB per scene; level 8: 0.95x for +17 ms).
RGB_LEVEL = 7


def _json(data: Any) -> str:
    return json.dumps(data, indent=1, sort_keys=False, allow_nan=True) + "\n"


#: Images of long runs of equal bytes (the amodal masks, the CoM heat map's residual and
#: ``valid_depth``) that the default mode deflates with zlib's level :data:`RUN_LEVEL`, the runs
#: of all-zero blocks as cached hand-made deflate blocks (:func:`mgn.base.compress.deflate_runs`:
#: the amodal masks in ~11 ms instead of ~45 per 1200 x 1200 view of 20 objects, in 101 kB
#: instead of zlib's 159): libdeflate's streams of them are 2x smaller still (-1.9 MB per scene
#: for the masks) but zlib inflates them 3x slower (+50 ms per view for the masks); the archival
#: mode takes the bytes. The ids and ``occlusion`` are
#: libdeflate's (0.5x the bytes of zlib's level 1, -2.3 MB per scene, for +15 ms per view to
#: read them).
RUN_IMAGES: tuple[str, ...] = (
    "occlusion_objects",
    "com_heatmap",
    "valid_depth",
)

#: zlib level of :data:`RUN_IMAGES`: zlib's fast levels 1-3 keep long-distance matches, which zlib
#: inflates fast; level 3 gives 0.94x the bytes of level 1 in the same time (level 4 on: 0.4x
#: the bytes, but 2.5x the time and 10x slower to inflate).
RUN_LEVEL = 3
#: Archival mode's npz: the sensor depth an LZMA entry (:data:`NPZ_LZMA_FILTER`).
_NPZ_ARCHIVAL: dict[str, Any] = {"lzma_entries": ("depth",)}
#: Archival mode's libdeflate level of ``{v}_rgb.png``: 0.97x the bytes of :data:`DEFLATE_LEVEL`
#: for ~2x its time (+25 ms per 1200 x 1200 view; the ``{v}_mgn.hdf5`` images gain 1 % at level
#: 9 for +80 ms, so they stay at :data:`DEFLATE_LEVEL`).
_RGB_ARCHIVAL_LEVEL = 9


def write_view(
    folder: str | os.PathLike[str],
    rec: ViewRecord,
    *,
    archival: bool = False,
    times: dict[str, float] | None = None,
) -> list[Path]:
    """Write the files of one view into ``folder`` (created); returns the paths written.

    Units: the npz depth and every HDF5 length are converted to centimetres; ``depth_ideal``
    is stored in metres (the renderer's float32) when the heat map is stored as its residual.
    Dtypes and layout: see the module doc. ``archival``: the compact archival mode (lossy: the
    sensor depth rounded to :data:`ARCHIVAL_DEPTH_STEP_CM`, grasp poses to
    :data:`ARCHIVAL_ROTATION_STEP` / :data:`ARCHIVAL_POSE_STEP_CM`, the depth an LZMA zip entry
    that ``np.load`` reads; without
    ``rec.com_parameters`` also ``depth_ideal`` rounded and ``com_heatmap`` in 16 bits; same keys
    and dtypes in the files MetaGraspNet reads).
    ``times``: when given, the CPU seconds of the calling thread (``time.thread_time``) spent on
    each part are added to it: ``arrays`` (unit and dtype conversions, the CoM prediction), one
    key per encoded file kind (``rgb.png``, ``npz``, ``depth.png``, ``scene.hdf5``,
    ``mgn.hdf5``, ``json and csv``) and ``files`` (writing them to disk).
    """

    t_last = time.thread_time()

    def lap(part: str) -> None:
        nonlocal t_last
        if times is not None:
            now = time.thread_time()
            times[part] = times.get(part, 0.0) + now - t_last
            t_last = now

    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    v = rec.index
    f4 = np.float32
    depth_cm = depth_to_cm(rec.depth)
    com = rec.extra_npz.get("com_heatmap")
    # With the CoM parameters the heat map costs ~nothing (its residual from the prediction,
    # which needs the exact depth_ideal): exact in both modes, and smaller than rounding both.
    residual = com is not None and rec.com_parameters is not None
    # depth_ideal in cm only when it is not stored in metres (see below).
    ideal_cm = None if residual else (np.asarray(rec.depth_ideal, np.float64) * M_TO_CM).astype(f4)
    if archival:
        depth_cm = _snap(depth_cm, ARCHIVAL_DEPTH_STEP_CM)
        if ideal_cm is not None:
            ideal_cm = _snap(ideal_cm, ARCHIVAL_DEPTH_STEP_CM)
    npz: dict[str, Any] = {
        "depth": depth_cm,
        "instances_objects": np.asarray(rec.instances).astype(id_image_dtype(0, instances=True)),
        "instances_semantic": np.asarray(rec.semantic).astype(
            id_image_dtype(rec.semantic, instances=False)
        ),
        "occlusion": np.asarray(rec.occlusion_map, f4),
        "occlusion_objects": np.asarray(rec.amodal, bool),
    }
    image_attrs: dict[str, dict[str, Any]] = {}
    ideal_m = np.asarray(rec.depth_ideal, f4)
    images: dict[str, np.ndarray] = {"depth_ideal": ideal_m if ideal_cm is None else ideal_cm}
    if residual:
        # The renderer's own float32 metres (cm in float32 would round some away); the heat map
        # prediction below needs them exactly.
        images["depth_ideal"] = ideal_m
        image_attrs["depth_ideal"] = {UNITS_ATTR: "m"}
    valid = np.asarray(rec.valid_depth, bool)
    if not np.array_equal(valid, np.isfinite(depth_cm)):
        images["valid_depth"] = valid  # not derivable from the depth: stored
    for key, value in rec.extra_npz.items():
        if key in npz or key in images or key == "valid_depth":
            raise InvalidArgumentError(
                f"write_view: extra image '{key}' would replace a format key"
            )
        images[key] = np.asarray(value)
    unorm16: tuple[str, ...] = ("com_heatmap",) if archival and not residual else ()
    if residual:
        X_WC = np.asarray(rec.scene_hdf5["camera/pose_relative_to_world"], np.float64)
        K = rec.intrinsics
        K4 = np.array([K.fx, K.fy, K.cx, K.cy], np.float64)
        params = np.asarray(rec.com_parameters, np.float64).reshape(-1, 5)
        pred = com_heatmap_prediction(ideal_m, rec.instances, X_WC.reshape(4, 4), K4, params)
        images["com_heatmap"] = com_residual(images["com_heatmap"], pred)
        image_attrs["com_heatmap"] = {
            "mgn_encoding": COM_RESIDUAL_ENCODING,
            "com_parameters": params,
            "X_WC": X_WC.reshape(4, 4),
            "K": K4,
        }
    h5 = {
        path: np.asarray(value).astype(np.int32)
        if path.rpartition("/")[2] in HDF5_INT_LEAVES
        else to_cm(path, value).astype(f4)
        for path, value in rec.scene_hdf5.items()
    }
    if archival:
        for path, value in h5.items():
            if path.startswith(_GRASP_GROUPS) and path.endswith("poses_relative_to_camera"):
                h5[path] = _archival_poses(value)
    lap("arrays")
    files: dict[str, bytes] = {}
    files[f"{v}_rgb.png"] = png_bytes(
        np.asarray(rec.rgb, np.uint8), level=_RGB_ARCHIVAL_LEVEL if archival else RGB_LEVEL
    )
    lap("rgb.png")
    runs = {} if archival else dict.fromkeys(RUN_IMAGES, RUN_LEVEL)
    files[f"{v}.npz"] = npz_bytes(
        **npz, level=NPZ_LEVEL, zlib_levels=runs, **(_NPZ_ARCHIVAL if archival else {})
    )
    lap("npz")
    files[f"{v}_depth.png"] = depth_picture_png(
        np.where(valid, ideal_m, np.float32(np.nan)), level=DEPTH_PICTURE_LEVEL
    )
    lap("depth.png")
    files[f"{v}_scene.hdf5"] = hdf5_bytes(
        h5,
        unscored_marks(h5),
        share_rotations=True,
        level=DEFLATE_LEVEL if archival else SCENE_HDF5_LEVEL,
    )
    lap("scene.hdf5")
    files[f"{v}_mgn.hdf5"] = mgn_hdf5_bytes(
        images,
        unorm16=unorm16,
        attrs=image_attrs,
        level=DEFLATE_LEVEL if archival else MGN_IMAGE_LEVEL,
        zlib_levels=runs,
    )
    lap("mgn.hdf5")
    files[f"{v}_order.csv"] = rec.order_csv.encode()
    files[f"{v}_order.json"] = _json(rec.order_json).encode()
    files[f"{v}_layout.json"] = _json(rec.layout_json).encode()
    files[f"{v}_camera_params.json"] = _json(rec.intrinsics.camera_params()).encode()
    lap("json and csv")
    paths = []
    for name, data in files.items():
        atomic_write_bytes(out / name, data)
        paths.append(out / name)
    lap("files")
    return paths


def scene_gt_entries(
    X_CO: npt.ArrayLike, obj_ids: npt.ArrayLike, seen: npt.ArrayLike | None = None
) -> list[dict[str, Any]]:
    """``scene_gt.json`` entries of one view: per instance ``cam_R_m2c`` (a nested 3x3 list, one
    list per row of R_CO, as MetaGraspNet writes it), ``cam_t_m2c`` (cm) and ``obj_id`` (int);
    instances with ``seen`` False are left out."""
    X = np.asarray(X_CO, np.float64)
    ids = np.asarray(obj_ids).reshape(-1)
    keep = np.ones(len(ids), bool) if seen is None else np.asarray(seen, bool).reshape(-1)
    out = []
    for i, oid in enumerate(ids):
        if not keep[i]:
            continue
        out.append(
            {
                "cam_R_m2c": [[float(x) for x in row] for row in X[i, :3, :3]],
                "cam_t_m2c": [float(x) for x in X[i, :3, 3] * M_TO_CM],
                "obj_id": int(oid),
            }
        )
    return out


def write_scene_gt(
    folder: str | os.PathLike[str], per_view: Mapping[int, list[dict[str, Any]]]
) -> Path:
    """Write ``scene_gt.json`` (keys: view indices as strings)."""
    path = Path(folder) / "scene_gt.json"
    atomic_write_text(path, _json({str(v): per_view[v] for v in sorted(per_view)}))
    return path
