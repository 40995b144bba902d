"""The MetaGraspNet scene folder (docs/format.md): the one writer of a labelled view, its schema.

A scene folder ``<root>/scene<N>/`` holds, per view ``v``: ``{v}_rgb.png``, ``{v}.npz``,
``{v}_depth.png``, ``{v}_scene.hdf5``, ``{v}_order.csv``, ``{v}_order.json``,
``{v}_layout.json`` (mgn: bin relations and the difficulty level), ``{v}_mgn.hdf5`` (mgn: the
images MetaGraspNet does not have) and ``{v}_camera_params.json``; and once per scene
``scene_gt.json``.

Bytes (docs/format.md): the npz holds MetaGraspNet's keys only, with the dtypes its own scripts
work with unchanged: ``depth`` and ``occlusion`` float32, ``instances_objects`` uint8 (at most 255
instances), ``instances_semantic`` uint16 (float32 if a category id exceeds 65535),
``occlusion_objects`` bool; zip deflate. Every deflate stream (zip entries, HDF5 gzip chunks,
PNG) is made by libdeflate at :data:`DEFLATE_LEVEL` (:mod:`mgn.base.compress`): standard
streams that zlib and every reader decode. The sensor depth is stored on the
:data:`DEPTH_GRID_CM` grid the sensor presets report (:func:`depth_to_cm`): exact, and half the
bytes. mgn's own images go to ``{v}_mgn.hdf5`` with HDF5's shuffle filter (standard in every HDF5
library), float32 images delta-coded along rows (:func:`encode_float_image`): ``depth_ideal``
(metres, the renderer's values, when the heat map is a residual; else cm), ``com_heatmap``
(given the scene's CoM parameters, as its residual from :func:`com_heatmap_prediction`: zeros for
the pipeline's heat maps), and ``valid_depth`` only when it is not exactly ``isfinite(depth)``
(the sensors mark invalid pixels NaN, so normally it is derived on reading). In
``{v}_scene.hdf5`` the tool poses that share their contact poses' rotation are HDF5 virtual
datasets over them (:func:`hdf5_bytes`). The depth picture is a palette PNG of the noise-free
depth where the sensor has a value. Every array reads back bit-identical;
``write_view(..., archival=True)`` is the lossy compact archival mode (sensor depth on
:data:`ARCHIVAL_DEPTH_STEP_CM` in an LZMA zip entry, grasp poses rounded, RGB at libdeflate
level 9).

Lengths are **centimetres** in these files (MetaGraspNet's convention) and SI everywhere else in
mgn: :class:`ViewRecord` holds metres, the writer converts, and :mod:`mgn.io.dataset` converts
back with the same table (:data:`CM_RULES`).

Every file is written atomically, and byte-for-byte reproducibly (no timestamps in the zip entries
of the npz nor in the HDF5 objects), so the same seed gives files with the same checksums.
"""

from __future__ import annotations

import io
import json
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.base.atomic import atomic_write_bytes, atomic_write_text
from mgn.base.compress import h5_write_deflated, png_encode
from mgn.base.deterministic import (
    H5_DATASET_KWARGS,
    h5_create_dataset,
    h5_create_group,
    npz_bytes,
)
from mgn.base.units import M_TO_CM
from mgn.errors import InvalidArgumentError
from mgn.render.views import depth_picture_indexed
from mgn.scene.cameras import Intrinsics
from mgn.view_labels.grasps import COLLISION_OBSTACLES, COLLISION_PARTS

__all__ = [
    "ARCHIVAL_DEPTH_STEP_CM",
    "ARCHIVAL_POSE_STEP_CM",
    "ARCHIVAL_ROTATION_STEP",
    "CM_RULES",
    "COLLISION_OBSTACLES",
    "COLLISION_PARTS",
    "COM_RESIDUAL_ENCODING",
    "DEFLATE_LEVEL",
    "DEPTH_GRID_CM",
    "DEPTH_PICTURE_LEVEL",
    "FLOAT_DELTA_ENCODING",
    "FLOAT_GRADIENT_ENCODING",
    "H5_LIBVER",
    "HDF5_FLOAT_KEYS",
    "HDF5_INT_LEAVES",
    "MGN_HDF5_CM",
    "MGN_IMAGE_LEVEL",
    "M_TO_CM",
    "NPZ_LEVEL",
    "POSE_COLUMNS_GROUP",
    "RGB_LEVEL",
    "ROTATION_BLOCK_POSES",
    "RUN_IMAGES",
    "RUN_LEVEL",
    "SCENE_HDF5_LEVEL",
    "SHARED_ROTATION_ENCODING",
    "TOOL_POSE_LEAVES",
    "UNITS_ATTR",
    "UNORM16_ENCODING",
    "UNSHUFFLED_LEAVES",
    "ViewRecord",
    "com_heatmap_prediction",
    "decode_com_residual",
    "decode_float_gradient",
    "decode_float_image",
    "depth_picture_png",
    "depth_to_cm",
    "encode_float_gradient",
    "encode_float_image",
    "from_cm",
    "hdf5_bytes",
    "id_image_dtype",
    "ideal_metres",
    "mgn_hdf5_bytes",
    "png_bytes",
    "read_scene_dataset",
    "scene_gt_entries",
    "to_cm",
    "view_file_names",
    "write_scene_gt",
    "write_view",
]


#: How lengths are stored in the scene HDF5 (path suffix -> what is in centimetres):
#: ``"pose"``: the translation column of (…, 4, 4) matrices; ``"xyz"``: columns 1..3 of (…, 4)
#: rows [id or score, x, y, z]; ``"all"``: every value.
CM_RULES: tuple[tuple[str, str], ...] = (
    ("poses_relative_to_camera", "pose"),
    ("pose_relative_to_world", "pose"),
    ("contact_width", "all"),
    ("keypts_relative_to_camera", "xyz"),
)

#: Leaf names of ``{v}_scene.hdf5`` datasets stored as int32 (integer-valued labels; MetaGraspNet's
#: readers only index with them). Everything else is float32, as in MetaGraspNet's files.
HDF5_INT_LEAVES: tuple[str, ...] = (
    "object_id",
    "occluded_object_id",
    "categories",
    "collision_part",
    "collision_obstacle",
    "scene_instance_id",
)

#: Datasets every view's ``{v}_scene.hdf5`` has (empty groups have zero-length datasets).
HDF5_FLOAT_KEYS: tuple[str, ...] = (
    "camera/pose_relative_to_world",
    "objects/poses_relative_to_camera",
    "objects/categories",
    "objects/bbox_loose",
)


def _rule(path: str) -> str | None:
    for suffix, rule in CM_RULES:
        if path.endswith(suffix):
            return rule
    return None


def _scale(path: str, a: np.ndarray, factor: float) -> np.ndarray:
    rule = _rule(path)
    out = np.array(a, dtype=np.float64)
    if rule is None or out.size == 0:
        return out
    if rule == "pose":
        out[..., :3, 3] *= factor
    elif rule == "xyz":
        out[..., 1:4] *= factor
    else:
        out *= factor
    return out


def to_cm(path: str, a: npt.ArrayLike) -> np.ndarray:
    """The array stored at HDF5 ``path`` converted from metres to the file's centimetres."""
    return _scale(path, np.asarray(a), M_TO_CM)


def from_cm(path: str, a: npt.ArrayLike) -> np.ndarray:
    """The inverse of :func:`to_cm` (file centimetres -> metres)."""
    return _scale(path, np.asarray(a), 1.0 / M_TO_CM)


@dataclass(frozen=True)
class ViewRecord:
    """Everything written for one view (SI units, camera frame OpenCV).

    Attributes:
        index: view index v.
        rgb: (H, W, 3) uint8.
        depth: (H, W) sensor z-depth, m, NaN invalid.
        depth_ideal: (H, W) noise-free z-depth, m, NaN where nothing is seen.
        valid_depth: (H, W) bool.
        instances: (H, W) contiguous instance ids 0..N (0 background).
        semantic: (H, W) category id of the visible object, 0 background.
        occlusion_map: (H, W) each visible pixel's object occlusion rate in [0, 1].
        amodal: (N, H, W) bool amodal masks (row i = instance i + 1).
        intrinsics: the camera intrinsics.
        scene_hdf5: ``{v}_scene.hdf5`` datasets by path (docs/format.md), lengths in metres.
        order_json: ``{v}_order.json`` content (its lengths already in cm, as docs/format.md says).
        order_csv: ``{v}_order.csv`` text.
        layout_json: ``{v}_layout.json`` content (mgn: bin relations, difficulty).
        extra_npz: further (H, W) images under mgn's own names (e.g. ``com_heatmap``), written
            to ``{v}_mgn.hdf5``.
        com_parameters: (N, 5) per instance [c_W (3), d_min, d_max], world frame, m
            (:meth:`mgn.view_labels.objects.SceneRayModel.com_parameters`), or None. Given (and
            a ``com_heatmap`` image), the heat map is stored as its difference from
            :func:`com_heatmap_prediction` (lossless, a tenth of the bytes).
    """

    index: int
    rgb: npt.NDArray[np.uint8]
    depth: npt.NDArray[np.float32]
    depth_ideal: npt.NDArray[np.float32]
    valid_depth: npt.NDArray[np.bool_]
    instances: npt.NDArray[np.integer]
    semantic: npt.NDArray[np.integer]
    occlusion_map: npt.NDArray[np.float32]
    amodal: npt.NDArray[np.bool_]
    intrinsics: Intrinsics
    scene_hdf5: Mapping[str, np.ndarray]
    order_json: Mapping[str, Any]
    order_csv: str
    layout_json: Mapping[str, Any]
    extra_npz: Mapping[str, np.ndarray] = field(default_factory=dict)
    com_parameters: npt.NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        h, w = self.intrinsics.height, self.intrinsics.width
        v = self.index
        for name in ("depth", "depth_ideal", "valid_depth", "instances", "semantic",
                     "occlusion_map"):  # fmt: skip
            shape = np.shape(getattr(self, name))
            if shape != (h, w):
                raise InvalidArgumentError(
                    f"ViewRecord {v}: {name} must be ({h}, {w}), got {shape}"
                )
        if np.shape(self.rgb) != (h, w, 3):
            raise InvalidArgumentError(
                f"ViewRecord {v}: rgb must be ({h}, {w}, 3), got {np.shape(self.rgb)}"
            )
        amodal = np.shape(self.amodal)
        if len(amodal) != 3 or amodal[1:] != (h, w):
            raise InvalidArgumentError(
                f"ViewRecord {v}: amodal must be (N, {h}, {w}), got {amodal}"
            )
        n = amodal[0]
        top = int(np.max(self.instances, initial=0))
        if top > n or int(np.min(self.instances, initial=0)) < 0:
            raise InvalidArgumentError(
                f"ViewRecord {v}: instance ids must be in 0..{n}, got max {top}"
            )
        if n > 255:
            raise InvalidArgumentError(f"ViewRecord {v}: at most 255 instances per view, got {n}")
        seen = np.bincount(np.asarray(self.instances, np.int64).reshape(-1), minlength=n + 1)
        hidden = np.flatnonzero(seen[1:] == 0) + 1
        if hidden.size:
            raise InvalidArgumentError(
                f"ViewRecord {v}: instances {hidden.tolist()} have no visible pixel; a view holds "
                f"the objects it sees, numbered 1..N without gaps (MetaGraspNet's readers count "
                f"the ids of the instance image: mgn.view_labels.objects.seen_objects)"
            )
        for key in HDF5_FLOAT_KEYS:
            if key not in self.scene_hdf5:
                raise InvalidArgumentError(f"ViewRecord {v}: scene_hdf5 lacks '{key}'")


def view_file_names(v: int) -> list[str]:
    """The files of view ``v`` in a scene folder."""
    return [
        f"{v}_rgb.png",
        f"{v}.npz",
        f"{v}_depth.png",
        f"{v}_scene.hdf5",
        f"{v}_mgn.hdf5",
        f"{v}_order.csv",
        f"{v}_order.json",
        f"{v}_layout.json",
        f"{v}_camera_params.json",
    ]


#: ``{v}_mgn.hdf5`` datasets that hold lengths in centimetres.
MGN_HDF5_CM: tuple[str, ...] = ("depth_ideal",)
#: Rows per HDF5 chunk of an (H, W) image in ``{v}_mgn.hdf5`` (shuffle + deflate per chunk): at
#: libdeflate level :data:`MGN_IMAGE_LEVEL` chunks of 600 rows store ``depth_ideal`` of a 1200 x
#: 1200 view in the bytes of 128-row chunks at level 6, in 0.8x the time.
_IMAGE_CHUNK_ROWS = 600


def id_image_dtype(values: npt.ArrayLike, *, instances: bool) -> np.dtype:
    """The npz dtype of an id image: uint8 for instance ids (at most 255 instances per view);
    uint16 for category ids, float32 (MetaGraspNet's own dtype) if one exceeds 65535."""
    if instances:
        return np.dtype(np.uint8)
    top = int(np.max(values, initial=0))
    return np.dtype(np.uint16) if top <= np.iinfo(np.uint16).max else np.dtype(np.float32)


#: Grid (cm) on which the writer stores the sensor depth exactly: the sensor presets report z on
#: multiples of it (``DepthSensorParams.depth_step``: 1/256 cm structured light, 1/64 cm ToF,
#: times a power of two that grows with the noise: ``depth_step_noise_fraction``), and float32
#: values on a power-of-two grid end in zero bits, which deflate compresses (docs/format.md).
DEPTH_GRID_CM = 2.0**-8

#: Value of the ``mgn_encoding`` attribute of a ``{v}_mgn.hdf5`` float32 image stored as the int32
#: differences of its bit patterns along each row (lossless; smooth images shrink ~30 %).
FLOAT_DELTA_ENCODING = "float32-bits-delta-rows"


#: Archival mode (``io.archival``): grid (cm) of the stored sensor and ideal depth, 1/64 cm =
#: 0.15625 mm (values at most 0.078 mm from the model's; half the structured-light noise at 0.3 m).
ARCHIVAL_DEPTH_STEP_CM = 2.0**-6

#: Archival mode: ``mgn_encoding`` of a [0, 1] image stored as uint16 k, read as float32 k / 65535.
UNORM16_ENCODING = "unorm16"


def depth_to_cm(depth_m: npt.ArrayLike) -> npt.NDArray[np.float32]:
    """float32 centimetres of a depth image in metres, such that ``cm / float32(100)`` (what
    :class:`mgn.io.dataset.View` does) gives back the metres bit for bit wherever that is possible
    on the :data:`DEPTH_GRID_CM` grid (the sensor presets' output); other pixels (ideal sensor,
    user grids) hold ``float32(m * 100)``. NaN stays NaN."""
    m = np.asarray(depth_m, np.float32)
    plain = (m.astype(np.float64) * M_TO_CM).astype(np.float32)
    with np.errstate(invalid="ignore"):
        snapped = (np.round(plain / DEPTH_GRID_CM) * DEPTH_GRID_CM).astype(np.float32)
        exact = snapped / np.float32(M_TO_CM) == m
    return np.where(exact, snapped, plain)


def encode_float_image(image: npt.ArrayLike) -> npt.NDArray[np.int32]:
    """(H, W) float32 -> int32 differences of the bit patterns along each row (first column
    kept); wraps modulo 2^32, so :func:`decode_float_image` restores every bit (NaN included)."""
    bits = np.ascontiguousarray(image, np.float32).view(np.int32)
    out: npt.NDArray[np.int32] = bits.copy()
    with np.errstate(over="ignore"):
        out[:, 1:] = bits[:, 1:] - bits[:, :-1]
    return out


def decode_float_image(coded: npt.ArrayLike) -> npt.NDArray[np.float32]:
    """The inverse of :func:`encode_float_image`."""
    a = np.asarray(coded, np.int32)
    return np.cumsum(a, axis=1, dtype=np.int32).view(np.float32)


#: Value of the ``mgn_encoding`` attribute of a ``{v}_mgn.hdf5`` float32 image stored by
#: :func:`encode_float_gradient` (lossless): ``depth_ideal`` in 0.73x the bytes of
#: :data:`FLOAT_DELTA_ENCODING` (-7 MB per 37-view scene of 1200 x 1200 views).
FLOAT_GRADIENT_ENCODING = "float32-bits-gradient-zigzag"


def encode_float_gradient(image: npt.ArrayLike) -> npt.NDArray[np.int32]:
    """(H, W) float32 -> int32: each pixel's bit pattern minus the gradient prediction left + up -
    upper-left (missing neighbours count as 0; modulo 2^32), zigzag-mapped (0, -1, 1, -2, ... ->
    0, 1, 2, 3, ...) so that small residuals of either sign have zero high bytes, which HDF5's
    shuffle filter groups for deflate. On a rendered depth image the residual is ~0 inside every
    plane. :func:`decode_float_gradient` restores every bit (NaN included)."""
    d = encode_float_image(image)  # differences along rows
    with np.errstate(over="ignore"):
        d[1:] -= d[:-1].copy()  # and along columns: the gradient residual
        return (d << 1) ^ (d >> 31)


def decode_float_gradient(coded: npt.ArrayLike) -> npt.NDArray[np.float32]:
    """The inverse of :func:`encode_float_gradient`."""
    z = np.asarray(coded, np.int32)
    d = (z.view(np.uint32) >> 1).view(np.int32) ^ -(z & 1)
    np.cumsum(d, axis=0, dtype=np.int32, out=d)
    return np.cumsum(d, axis=1, dtype=np.int32).view(np.float32)


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


#: ``mgn_encoding`` of a ``com_heatmap`` stored as the int32 differences (modulo 2^32) of its
#: float32 bit patterns from :func:`com_heatmap_prediction`, whose inputs the dataset's
#: attributes hold (``com_parameters``, ``X_WC``, ``K``) with ``depth_ideal`` (m) of the same
#: file and ``instances_objects`` of ``{v}.npz``.
COM_RESIDUAL_ENCODING = "float32-bits-minus-com-prediction"
#: Attribute of a ``{v}_mgn.hdf5`` depth image giving its unit (absent: cm).
UNITS_ATTR = "mgn_units"


def com_heatmap_prediction(
    depth_ideal_m: npt.ArrayLike,
    instances: npt.ArrayLike,
    X_WC: npt.ArrayLike,
    K: npt.ArrayLike,
    com_parameters: npt.ArrayLike,
) -> npt.NDArray[np.float32]:
    """The CoM heat map (docs/models.md §7) of a view from its noise-free depth, as the C++ label
    model computes it: at each pixel (u, v) of instance i with a depth z (m), the point
    p_C = (z (u + 0.5 - cx) / fx, z (v + 0.5 - cy) / fy, z) moved to the world by ``X_WC``
    (4, 4, m) scores clip((d_max - |p_W - c_W|) / max(d_max - d_min, 1e-12), 0, 1) with
    [c_W, d_min, d_max] = ``com_parameters[i - 1]`` (N, 5); 0 elsewhere. ``K`` = (fx, fy, cx, cy)
    px. Computed by the C++ core (``mgn::com_heatmap_prediction``, mgn/scene/view_labels.hpp):
    only IEEE-exact operations in the order written here, without fused multiply-adds
    (x = ((u + 0.5) - cx) * z / fx; each world coordinate ((X_r0 x + X_r1 y) + X_r2 z) + X_r3,
    minus c_r, squared and summed in the order r = 0, 1, 2), so every machine predicts the same
    bits (the stored residual makes the heat map exact whatever the prediction's error)."""
    inst = np.asarray(instances)
    params = np.ascontiguousarray(np.asarray(com_parameters, np.float64).reshape(-1, 5))
    ids = inst.reshape(inst.shape[0], -1) if inst.ndim == 2 else inst.reshape(-1, 1)
    top = int(np.max(ids, initial=0))
    if top > len(params):
        raise InvalidArgumentError(
            f"com_heatmap_prediction: instance id {top} but only {len(params)} rows "
            "of com_parameters; expected one row per instance"
        )
    depth = np.asarray(depth_ideal_m, np.float32).reshape(ids.shape)
    fx, fy, cx, cy = (float(k) for k in np.asarray(K, np.float64).reshape(4))
    X = np.asarray(X_WC, np.float64).reshape(4, 4)
    out = _core.scene.com_heatmap_prediction(
        depth, ids.astype(np.int32, copy=False), X, fx, fy, cx, cy, params
    )
    return np.asarray(out).reshape(inst.shape)


def _com_residual(com: npt.ArrayLike, prediction: npt.NDArray[np.float32]) -> npt.NDArray[np.int32]:
    bits = np.ascontiguousarray(com, np.float32).view(np.int32)
    with np.errstate(over="ignore"):
        return bits - prediction.view(np.int32)


def decode_com_residual(
    residual: npt.ArrayLike, prediction: npt.NDArray[np.float32]
) -> npt.NDArray[np.float32]:
    """The heat map of a ``com_heatmap`` stored with :data:`COM_RESIDUAL_ENCODING`."""
    with np.errstate(over="ignore"):
        return (np.asarray(residual, np.int32) + prediction.view(np.int32)).view(np.float32)


def ideal_metres(depth_ideal_cm: npt.ArrayLike) -> npt.NDArray[np.float32]:
    """float32 metres of a ``depth_ideal`` stored in cm (archival mode, earlier files), as
    :class:`mgn.io.dataset.View` gives them."""
    out: npt.NDArray[np.float32] = (
        np.asarray(depth_ideal_cm, np.float32) / np.float32(M_TO_CM)
    ).astype(np.float32)
    return out


def mgn_hdf5_bytes(
    images: Mapping[str, np.ndarray],
    *,
    unorm16: tuple[str, ...] = (),
    attrs: Mapping[str, Mapping[str, Any]] | None = None,
    level: int = 6,
    zlib_levels: Mapping[str, int] | None = None,
) -> bytes:
    """``{v}_mgn.hdf5``: (H, W) images by name, chunked by rows, shuffle + deflate (libdeflate
    ``level``, :func:`mgn.base.compress.h5_write_deflated`), without timestamps; float32 images
    stored with :func:`encode_float_image` (attribute ``mgn_encoding`` =
    :data:`FLOAT_DELTA_ENCODING`), those named in ``unorm16`` (values in
    [0, 1]) as uint16 ``round(x * 65535)`` (:data:`UNORM16_ENCODING`, lossy: archival mode);
    ``attrs``: further attributes by image name; ``zlib_levels``: images deflated by zlib at the
    given level instead (fast to inflate where they are long runs). Integer images are stored as
    given."""
    buf = io.BytesIO()
    with h5py.File(buf, "w", libver=H5_LIBVER) as h5:
        for name, value in images.items():
            data = np.ascontiguousarray(value)
            coded: str | None = None
            if name in unorm16:
                data = np.round(np.clip(data, 0.0, 1.0) * 65535.0).astype(np.uint16)
                coded = UNORM16_ENCODING
            elif data.dtype == np.float32 and data.ndim == 2 and data.size > 0:
                data = encode_float_gradient(data)
                coded = FLOAT_GRADIENT_ENCODING
            if data.size:
                chunks = (min(_IMAGE_CHUNK_ROWS, data.shape[0]), *data.shape[1:])
                ds = h5_write_deflated(h5, name, data, chunks, level,
                                       zlib_level=(zlib_levels or {}).get(name),
                                       **H5_DATASET_KWARGS)  # fmt: skip
            else:
                ds = h5_create_dataset(h5, name, data)
            if coded:
                ds.attrs["mgn_encoding"] = coded
            for key, value in (attrs or {}).get(name, {}).items():
                ds.attrs[key] = value
    return buf.getvalue()


#: Datasets with at least this many values are stored chunked with gzip and the shuffle filter
#: (deflated by libdeflate at :data:`DEFLATE_LEVEL`): grasp sets shrink ~3x; every HDF5 reader
#: (h5py, the C library) has gzip.
_COMPRESS_FROM = 256
#: Rows per chunk of a compressed (M, ...) dataset of ``{v}_scene.hdf5``; a chunk holds one
#: entry (e.g. row 0, column 3 of every pose) of up to this many rows, which shuffle + deflate
#: compress better than whole rows; the chunks a row spans (16 of 32 KiB for poses) fit HDF5's
#: 1 MiB chunk cache, so reading row by row (``list(dataset)``) stays fast.
_CHUNK_ROWS = 8192
#: (M, 4, 4) poses of ``{v}_scene.hdf5`` chunked by the first three rows of each pose (rotation
#: and translation, 48 contiguous bytes per pose; the last row in a second chunk), unshuffled,
#: instead of by entry: suction contact rotations repeat (the points of a flat face share its
#: normal; ~40 % of the rows of a view), which deflate finds as three 12-byte matches: 0.85x the
#: bytes of the shuffled entry chunks in the same time (-2 MB per 37-view scene;
#: docs/decisions/0021-format-writer-encodings.md). Parallel-jaw rotations are all distinct:
#: shuffled entry chunks are smaller there (0.93x).
ROTATION_BLOCK_POSES: tuple[str, ...] = ("suctioncup/contact_poses_relative_to_camera",)
#: Leaf names of ``{v}_scene.hdf5`` datasets deflated without the shuffle filter: per-grasp values
#: taken from a few levels or repeated along the rows (scores, the widths of the grasps sharing a
#: contact point), which deflate matches as whole 4-byte values: 0.5-0.9x the bytes of
#: the shuffled chunks (-0.5 MB per scene). The wrench scores and the integer labels stay
#: shuffled (1.2x / 1.3x larger without).
UNSHUFFLED_LEAVES: tuple[str, ...] = (
    "contact_width",
    "score_analytical",
    "score_simulation",
)
#: HDF5 file-format bounds of the scene writer's files: the HDF5 1.10 formats (the virtual
#: datasets need them anyway), whose chunk indexes and object headers take ~25 kB per
#: ``{v}_scene.hdf5`` instead of ~107 kB with the 1.8-compatible ones (-3 MB per scene).
#: Every HDF5 >= 1.10 reader (h5py since 2.7) opens them.
H5_LIBVER: tuple[str, str] = ("v110", "v110")

#: Tool-pose datasets of ``{v}_scene.hdf5`` whose rotation block equals the one of the group's
#: ``contact_poses_relative_to_camera`` (same axes, moved along them): stored as HDF5 virtual
#: datasets that take columns 0..2 from the contact poses.
TOOL_POSE_LEAVES: tuple[str, ...] = (
    "franka_poses_relative_to_camera",
    "suction_poses_relative_to_camera",
)
#: Group of ``{v}_scene.hdf5`` holding the last column (translation, 1) of the tool poses stored
#: as virtual datasets, under the tool dataset's own path.
POSE_COLUMNS_GROUP = "mgn_pose_columns"
#: ``mgn_encoding`` of a tool-pose virtual dataset (columns 0..2 from the contact poses, column 3
#: from :data:`POSE_COLUMNS_GROUP`).
SHARED_ROTATION_ENCODING = "rotation-of-contact-poses"
_CONTACT_LEAF = "contact_poses_relative_to_camera"


def _write_dataset(group: Any, name: str, data: np.ndarray, level: int, path: str = "") -> None:
    """A dataset of ``{v}_scene.hdf5`` (at ``path``) without timestamps: chunked with gzip at
    libdeflate ``level`` from ``_COMPRESS_FROM`` values on, contiguous below. A chunk holds one
    entry of up to ``_CHUNK_ROWS`` rows, shuffled (except :data:`UNSHUFFLED_LEAVES`); the poses
    of :data:`ROTATION_BLOCK_POSES` rows 0..2 of each pose, unshuffled."""
    if data.size < _COMPRESS_FROM or data.ndim == 0:
        h5_create_dataset(group, name, data)
        return
    rows = min(len(data), _CHUNK_ROWS)
    chunks: tuple[int, ...] = (rows, *([1] * (data.ndim - 1)))
    shuffle = name not in UNSHUFFLED_LEAVES
    if data.shape[1:] == (4, 4) and path.endswith(ROTATION_BLOCK_POSES):
        chunks, shuffle = (rows, 3, 4), False
    h5_write_deflated(group, name, data, chunks, level, shuffle=shuffle, **H5_DATASET_KWARGS)


def _shares_rotation(datasets: Mapping[str, np.ndarray], path: str) -> bool:
    """Whether the (M, 4, 4) tool poses at ``path`` equal the group's contact poses bit for bit in
    columns 0..2 (rotation and the bottom row's zeros), so they can be a virtual dataset."""
    parent, _, leaf = path.rpartition("/")
    contact = datasets.get(f"{parent}/{_CONTACT_LEAF}")
    tool = datasets[path]
    if leaf not in TOOL_POSE_LEAVES or contact is None or tool.size == 0:
        return False
    if tool.dtype != contact.dtype or tool.shape != contact.shape or tool.shape[1:] != (4, 4):
        return False
    return bool(
        np.array_equal(
            np.ascontiguousarray(tool[:, :, :3]).view(np.uint8),
            np.ascontiguousarray(contact[:, :, :3]).view(np.uint8),
        )
    )


def _group(h5: Any, path: str, groups: dict[str, Any]) -> Any:
    """The group at ``path`` of file ``h5`` (created without timestamps if missing), looked up
    once per file through ``groups`` (h5py's own lookups cost ~0.1 ms each)."""
    if path not in groups:
        groups[path] = h5[path] if path in h5 else h5_create_group(h5, path)
    return groups[path]


def _virtual_tool_poses(
    h5: Any, path: str, tool: np.ndarray, level: int, groups: dict[str, Any]
) -> None:
    """Write ``tool`` (M, 4, 4) at ``path`` as a virtual dataset: columns 0..2 from the group's
    contact poses (same file), column 3 from ``POSE_COLUMNS_GROUP/path`` (written here); no
    timestamps."""
    parent = path.rpartition("/")[0]
    contact = f"{parent}/{_CONTACT_LEAF}"
    column_path = f"{POSE_COLUMNS_GROUP}/{path}"
    column = np.ascontiguousarray(tool[:, :, 3])
    group_path, _, name = column_path.rpartition("/")
    _write_dataset(_group(h5, group_path, groups), name, column, level, column_path)
    m = tool.shape[0]
    dcpl = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
    dcpl.set_layout(h5py.h5d.VIRTUAL)
    dcpl.set_obj_track_times(False)
    dcpl.set_fill_value(np.zeros(1, tool.dtype))
    for src_path, src_shape, v_start, v_count in (
        (contact, (m, 4, 4), (0, 0, 0), (m, 4, 3)),
        (column_path, (m, 4), (0, 0, 3), (m, 4, 1)),
    ):
        vspace = h5py.h5s.create_simple(tool.shape)
        vspace.select_hyperslab(v_start, v_count)
        sspace = h5py.h5s.create_simple(src_shape)
        if len(src_shape) == 3:
            sspace.select_hyperslab((0, 0, 0), v_count)
        else:
            sspace.select_all()
        dcpl.set_virtual(vspace, b".", src_path.encode(), sspace)
    tid = h5py.h5t.py_create(tool.dtype, logical=True)
    space = h5py.h5s.create_simple(tool.shape)
    leaf = path.rpartition("/")[2].encode()
    dsid = h5py.h5d.create(_group(h5, parent, groups).id, leaf, tid, space, dcpl=dcpl)
    h5py.Dataset(dsid).attrs["mgn_encoding"] = SHARED_ROTATION_ENCODING


def read_scene_dataset(h5: Any, path: str) -> np.ndarray:
    """The array of ``{v}_scene.hdf5`` dataset ``path`` as stored (cm): what ``h5[path][()]``
    gives, assembling the tool poses stored as virtual datasets (:data:`TOOL_POSE_LEAVES`) from
    their sources directly (a few times faster than HDF5's virtual-dataset read)."""
    ds = h5[path]
    if not ds.is_virtual or ds.attrs.get("mgn_encoding") != SHARED_ROTATION_ENCODING:
        return np.asarray(ds[()])
    out: np.ndarray = np.asarray(h5[f"{path.rpartition('/')[0]}/{_CONTACT_LEAF}"][()]).copy()
    out[:, :, 3] = h5[f"{POSE_COLUMNS_GROUP}/{path}"][()]
    return out


#: Root attribute of ``{v}_scene.hdf5``: per parallel-jaw ``score_simulation`` dataset that
#: holds NaN, how many of its grasps have no physics score (JSON ``{path: count}``). Absent when
#: every stored grasp is scored.
UNSCORED_ATTR = "mgn_unscored_grasps"
#: Root attribute of ``{v}_scene.hdf5`` beside :data:`UNSCORED_ATTR`: what a NaN physics score
#: means.
UNSCORED_REASON_ATTR = "mgn_unscored_reason"
UNSCORED_REASON = (
    "NaN score_simulation: the grasp has no physics score (object_labels.physics_grasps caps "
    "the scored grasps per object, or labels.pj_physics is off); dataset.json physics_scores "
    "counts them"
)


def unscored_marks(datasets: Mapping[str, npt.ArrayLike]) -> dict[str, Any]:
    """The root attributes that mark unscored parallel-jaw grasps in ``{v}_scene.hdf5``
    (:data:`UNSCORED_ATTR`, :data:`UNSCORED_REASON_ATTR`): empty when no parallel-jaw
    ``score_simulation`` holds NaN."""
    counts = {}
    for path, value in datasets.items():
        if path.endswith("paralleljaw/score_simulation"):
            n = int(np.isnan(np.asarray(value, np.float32)).sum())
            if n:
                counts[path] = n
    if not counts:
        return {}
    return {UNSCORED_ATTR: counts, UNSCORED_REASON_ATTR: UNSCORED_REASON}


def hdf5_bytes(
    datasets: Mapping[str, np.ndarray],
    attrs: Mapping[str, Any] | None = None,
    *,
    share_rotations: bool = False,
    level: int = 6,
) -> bytes:
    """An HDF5 file holding ``datasets`` (path -> array, written as given) without timestamps;
    ``attrs`` go on the root group (dicts and lists as JSON). Datasets of at least
    ``_COMPRESS_FROM`` values are chunked by entry (``_CHUNK_ROWS`` rows) with shuffle + gzip
    (libdeflate ``level``, :func:`mgn.base.compress.h5_write_deflated`).
    ``share_rotations``: tool poses (:data:`TOOL_POSE_LEAVES`) whose columns 0..2 equal their
    group's contact poses bit for bit are stored as virtual datasets reading those columns from
    the contact poses (every HDF5 >= 1.10 reader, h5py included, sees the same array)."""
    buf = io.BytesIO()
    with h5py.File(buf, "w", libver=H5_LIBVER) as h5:
        shared = []
        groups: dict[str, Any] = {}
        for path, value in datasets.items():
            data = np.asarray(value)
            if share_rotations and _shares_rotation(datasets, path):
                shared.append(path)
                continue
            parent, _, name = path.rpartition("/")
            group = _group(h5, parent, groups) if parent else h5
            _write_dataset(group, name, data, level, path)
        for path in shared:
            _virtual_tool_poses(h5, path, np.asarray(datasets[path]), level, groups)
        for key, value in (attrs or {}).items():
            h5.attrs[key] = json.dumps(value) if isinstance(value, (dict, list)) else value
    return buf.getvalue()


#: libdeflate level of the deflate streams of the scene writer's images (PNG, HDF5 chunks): on a
#: 1200 x 1200 view of 20 objects it costs less than zlib's level 1 did, for 0.88x the bytes of
#: ``depth_ideal`` and 0.86x the RGB PNG's (docs/decisions/0020-format-libdeflate.md).
DEFLATE_LEVEL = 6
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


def png_bytes(image: npt.ArrayLike, *, level: int = DEFLATE_LEVEL) -> bytes:
    """PNG of an (H, W) or (H, W, 3) uint8 / (H, W) uint16 image (no time chunk: reproducible),
    deflated by libdeflate at ``level`` (1..12; :func:`mgn.base.compress.png_encode`: no row
    filter, which on rendered pictures gives fewer bytes than zlib level 6 with libpng's
    filters, at ~1/4 of its time)."""
    return png_encode(np.asarray(image), level=level)


#: libdeflate level of the scene writer's ``{v}_depth.png``, a picture of the noise-free depth at
#: the pixels where the sensor gives a value (black elsewhere): bands of equal colour
#: (docs/format.md).
DEPTH_PICTURE_LEVEL = DEFLATE_LEVEL
#: libdeflate level of ``{v}_rgb.png`` in the default mode: 0.97x the bytes of level 6 for +3 ms
#: per 1200 x 1200 view (-0.4 MB per scene; level 8: 0.95x for +17 ms).
RGB_LEVEL = 7


def depth_picture_png(depth: npt.ArrayLike, *, level: int = DEFLATE_LEVEL) -> bytes:
    """``{v}_depth.png`` of a depth image (m): :func:`mgn.render.views.depth_picture` as a palette
    PNG (every reader converts it to the same RGB; ~half the bytes and faster to write than the
    RGB PNG), deflated by libdeflate at ``level`` (:func:`mgn.base.compress.png_encode`)."""
    index, palette = depth_picture_indexed(depth)
    return png_encode(index, level=level, palette=palette)


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
        images["com_heatmap"] = _com_residual(images["com_heatmap"], pred)
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
        out.append({
            "cam_R_m2c": [[float(x) for x in row] for row in X[i, :3, :3]],
            "cam_t_m2c": [float(x) for x in X[i, :3, 3] * M_TO_CM],
            "obj_id": int(oid),
        })  # fmt: skip
    return out


def write_scene_gt(
    folder: str | os.PathLike[str], per_view: Mapping[int, list[dict[str, Any]]]
) -> Path:
    """Write ``scene_gt.json`` (keys: view indices as strings)."""
    path = Path(folder) / "scene_gt.json"
    atomic_write_text(path, _json({str(v): per_view[v] for v in sorted(per_view)}))
    return path
