"""What a MetaGraspNet scene folder holds (docs/format.md): the files of a view
(:func:`view_file_names`), the datasets every ``{v}_scene.hdf5`` has and their dtypes, the
content of one view as the writer takes it (:class:`ViewRecord`), and the units.

Lengths are **centimetres** in these files (MetaGraspNet's convention) and SI everywhere else in
mgn: :class:`ViewRecord` holds metres, the writer (:mod:`mgn.io.scene_folder`) converts with
:func:`to_cm`, and :mod:`mgn.io.dataset` converts back with :func:`from_cm`, one table for both
(:data:`CM_RULES`). The sensor depth is stored on the :data:`DEPTH_GRID_CM` grid the sensor presets
report (:func:`depth_to_cm`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn.base.units import M_TO_CM
from mgn.errors import InvalidArgumentError
from mgn.scene.cameras import Intrinsics

__all__ = [
    "CM_RULES",
    "DEPTH_GRID_CM",
    "HDF5_FLOAT_KEYS",
    "HDF5_INT_LEAVES",
    "MGN_HDF5_CM",
    "UNITS_ATTR",
    "ViewRecord",
    "depth_to_cm",
    "from_cm",
    "id_image_dtype",
    "ideal_metres",
    "to_cm",
    "view_file_names",
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
        for name in (
            "depth",
            "depth_ideal",
            "valid_depth",
            "instances",
            "semantic",
            "occlusion_map",
        ):
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

#: Attribute of a ``{v}_mgn.hdf5`` depth image giving its unit (absent: cm).
UNITS_ATTR = "mgn_units"


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


def ideal_metres(depth_ideal_cm: npt.ArrayLike) -> npt.NDArray[np.float32]:
    """float32 metres of a ``depth_ideal`` stored in cm (archival mode, earlier files), as
    :class:`mgn.io.dataset.View` gives them."""
    out: npt.NDArray[np.float32] = (
        np.asarray(depth_ideal_cm, np.float32) / np.float32(M_TO_CM)
    ).astype(np.float32)
    return out
