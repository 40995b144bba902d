"""The HDF5 files of a scene folder, as bytes: ``{v}_scene.hdf5`` (:func:`hdf5_bytes`: grasp
sets, poses, keypoints; chunked, shuffled and deflated, the tool poses that share their contact
poses' rotation stored as HDF5 virtual datasets over them) and ``{v}_mgn.hdf5``
(:func:`mgn_hdf5_bytes`: mgn's own images, encoded by :mod:`mgn.io.image_codecs`), and the
reader of a ``{v}_scene.hdf5`` dataset that assembles those virtual datasets
(:func:`read_scene_dataset`).

The files hold no timestamps (:mod:`mgn.base.deterministic`), so the same arrays give the same
bytes; deflate streams are libdeflate's (:func:`mgn.base.compress.h5_write_deflated`). Every HDF5
>= 1.10 reader opens them (:data:`H5_LIBVER`).
"""

from __future__ import annotations

import io
import json
from collections.abc import Mapping
from typing import Any

import h5py
import numpy as np
import numpy.typing as npt

from mgn.base.compress import h5_write_deflated
from mgn.base.deterministic import H5_DATASET_KWARGS, h5_create_dataset, h5_create_group
from mgn.io.image_codecs import (
    FLOAT_GRADIENT_ENCODING,
    UNORM16_ENCODING,
    encode_float_gradient,
)

__all__ = [
    "H5_LIBVER",
    "POSE_COLUMNS_GROUP",
    "ROTATION_BLOCK_POSES",
    "SHARED_ROTATION_ENCODING",
    "TOOL_POSE_LEAVES",
    "UNSCORED_ATTR",
    "UNSCORED_REASON_ATTR",
    "UNSHUFFLED_LEAVES",
    "hdf5_bytes",
    "mgn_hdf5_bytes",
    "read_scene_dataset",
    "unscored_marks",
]

#: Rows per HDF5 chunk of an (H, W) image in ``{v}_mgn.hdf5`` (shuffle + deflate per chunk): at
#: libdeflate level :data:`mgn.io.scene_folder.MGN_IMAGE_LEVEL` chunks of 600 rows store
#: ``depth_ideal`` of a 1200 x 1200 view in the bytes of 128-row chunks at level 6, in 0.8x the
#: time.
_IMAGE_CHUNK_ROWS = 600


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
                ds = h5_write_deflated(
                    h5,
                    name,
                    data,
                    chunks,
                    level,
                    zlib_level=(zlib_levels or {}).get(name),
                    **H5_DATASET_KWARGS,
                )
            else:
                ds = h5_create_dataset(h5, name, data)
            if coded:
                ds.attrs["mgn_encoding"] = coded
            for key, value in (attrs or {}).get(name, {}).items():
                ds.attrs[key] = value
    return buf.getvalue()


#: Datasets with at least this many values are stored chunked with gzip and the shuffle filter
#: (deflated by libdeflate at :data:`mgn.io.image_codecs.DEFLATE_LEVEL`): grasp sets shrink ~3x;
#: every HDF5 reader (h5py, the C library) has gzip.
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
