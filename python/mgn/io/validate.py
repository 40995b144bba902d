"""``mgn validate DIR``: check every file of a dataset against docs/format.md.

Reports, per file, what is missing or corrupt (unreadable, wrong keys, shapes, dtypes, units,
values out of range, checksum different from the manifest) and every broken invariant between
the files of a view (docs/format.md):

- the objects of a view: ids 1..N, each in ``instances_objects``; N the same in every file
  (amodal masks, ``objects/*``, ``{v}_order.*``, ``{v}_layout.json``, ``scene_gt.json``);
  every visible mask inside its amodal mask; ``objects/scene_instance_id`` names objects of
  ``scene.json``;
- occlusion: the 4-decimal rate 1 - visible / amodal pixels, the same in ``{v}_order.json``,
  ``objects/occlusion`` and the ``occlusion`` image;
- the relation graph: parents and children lists that mirror each other, ``{v}_order.csv``
  holding -1 exactly at the relations, depth differences > 0 (0.0 only with ``edge_size`` 0),
  each relation backed by its masks (the parent seen on at least 10 px and 10 % of the two
  objects' decided overlap), ``total_covered_edge`` the sum of the children's edges, the layers
  those the definition derives from the graph (a parentless object is in layer 0), and
  ``{v}_layout.json``'s layers, picking order and difficulty consistent with them;
- grasps: every stored grasp scored (analytical and wrench scores in [0, 1]; a parallel-jaw
  ``score_simulation`` NaN only where ``dataset.json`` records unscored grasps or physics off;
  suction ``score_simulation`` in [0, 1] for every grasp, or NaN for all of them in datasets
  whose object labels have no suction physics score), object ids and contact widths in range,
  groups complete;
- units: camera fields of view in radians (2 atan(W / 2 fx)), apertures in mm, clipping range
  in cm; depth, object poses and ``scene_gt.json`` translations in cm and consistent with each
  other.

Each view's large arrays are read once (the npz entries with libdeflate,
:class:`mgn.io.npz_reader.NpzReader`; the grasp poses and the ideal-depth image are not read) and
released before the next view: about 1 s and 150 MB per 37-view scene of 1200 x 1200 px.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np
from PIL import Image

from mgn.io.dataset import Dataset, SceneFolder
from mgn.io.manifest import MANIFEST, check_manifest
from mgn.io.npz_reader import NpzReader
from mgn.io.order_files import derive_layers, strongly_connected
from mgn.io.scene_hdf5 import UNSCORED_ATTR, unscored_marks
from mgn.io.scene_schema import HDF5_INT_LEAVES, view_file_names
from mgn.scene.cameras import MGN_CLIPPING_RANGE_CM, MGN_FOCAL_LENGTH_MM

__all__ = ["Problem", "validate_dataset"]

#: npz key -> the dtypes allowed (mgn writes the first; MetaGraspNet's files have float32).
_NPZ_KEYS: dict[str, tuple[type, ...]] = {
    "depth": (np.float32,),
    "instances_objects": (np.uint8, np.float32),
    "instances_semantic": (np.uint16, np.uint8, np.float32),
    "occlusion": (np.float32,),
    "occlusion_objects": (np.bool_,),
}
#: Datasets every ``{v}_scene.hdf5`` has: path -> shape with N the objects of the view.
_OBJECT_KEYS: dict[str, tuple[int | str, ...]] = {
    "camera/pose_relative_to_world": (1, 4, 4),
    "objects/poses_relative_to_camera": ("N", 4, 4),
    "objects/categories": ("N",),
    "objects/bbox_loose": ("N", 4),
    "objects/bbox_tight": ("N", 4),
    "objects/occlusion": ("N",),
    "objects/scene_instance_id": ("N",),
}
_SCORES = ("score_analytical", "score_simulation", "score_wrench")
#: The datasets of each group of ``{v}_scene.hdf5``: leaf -> trailing shape.
_GROUP_LEAVES: dict[str, dict[str, tuple[int, ...]]] = {
    "paralleljaw": {
        "franka_poses_relative_to_camera": (4, 4),
        "contact_poses_relative_to_camera": (4, 4),
        "contact_width": (),
        **dict.fromkeys(_SCORES, ()),
        "object_id": (),
    },
    "suctioncup": {
        "suction_poses_relative_to_camera": (4, 4),
        "contact_poses_relative_to_camera": (4, 4),
        **dict.fromkeys(_SCORES, ()),
        "object_id": (),
    },
    "keypts": {
        "keypts_relative_to_camera": (4,),
        "object_id": (),
        "occluded_keypts_relative_to_camera": (4,),
        "occluded_object_id": (),
    },
}
_COLLISION_LEAVES = ("collision_part", "collision_obstacle")
#: ``{v}_camera_params.json`` keys (docs/format.md).
_CAMERA_KEYS = (
    "fx",
    "fy",
    "cx",
    "cy",
    "width",
    "height",
    "focal_length",
    "horizontal_aperture",
    "vertical_aperture",
    "horizontal_fov",
    "vertical_fov",
    "resolution",
    "clipping_range",
)
_ORDER_KEYS = ("id", "occlusion", "layer", "parents", "children", "total_covered_edge", "bin_rel")
_LAYOUT_KEYS = (
    "difficulty",
    "num_layers",
    "max_occlusion",
    "classes_unique",
    "all_complete",
    "order",
    "objects",
)
_LAYOUT_OBJECT_KEYS = (
    "visible",
    "visible_px",
    "complete",
    "num_regions",
    "layer",
    "category_id",
    "bin_rel",
)
#: The relation thresholds of the dataset pipeline (``compute_layout``'s defaults).
_MIN_OVERLAP_PX, _MIN_OVERLAP_FRACTION = 10, 0.1
#: Difficulty level 1 allows occlusion rates up to this (``compute_layout``'s default).
_MAX_OCCLUSION_LEVEL1 = 0.05
#: An object's mean depth over its visible pixels lies within this of its pose's z, cm (its
#: origin lies inside its bounding box; objects are smaller than this).
_DEPTH_POSE_CM = 50.0


@dataclass(frozen=True)
class Problem:
    """One finding: the file (relative to the dataset root) and what is wrong with it."""

    path: str
    message: str

    def __str__(self) -> str:
        return f"{self.path}: {self.message}"


class _Stop(Exception):
    """A file of the view cannot be checked further (already reported)."""


@dataclass
class _Marks:
    """What ``dataset.json`` says about grasps left without a physics score (a scene folder
    without one, e.g. of ``mgn scene label``, records nothing: its NaN scores are not checked)."""

    recorded: bool = False
    pj_physics: bool = True
    unscored: int = 0
    max_opening_cm: float | None = None


@dataclass
class _ViewFacts:
    """What the scene checks need of a view."""

    n: int
    categories: np.ndarray
    X_CO: np.ndarray  # (N, 4, 4) cm
    scene_instance_id: np.ndarray


Report = Callable[[str, str], None]  # bad(file suffix, message)


def _json(path: Path, suffix: str, bad: Report) -> Any:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError) as e:
        bad(suffix, f"not readable JSON: {e}")
        raise _Stop from None


class _ViewCheck:
    """The checks of one view (module doc); problems go to ``bad``."""

    def __init__(self, folder: Path, v: int, marks: _Marks, bad: Report) -> None:
        self.folder, self.v, self.marks, self.bad = folder, v, marks, bad

    def path(self, suffix: str) -> Path:
        return self.folder / f"{self.v}{suffix}"

    def run(self) -> _ViewFacts | None:
        hw = self.camera()
        try:
            npz = NpzReader(self.path(".npz"))
        except Exception as e:  # report any failure as a finding
            self.bad(".npz", str(e))
            return None
        ids, amodal = self.masks(npz, hw)
        if ids is None or amodal is None:
            return None
        n = amodal.shape[0]
        try:
            h5 = self.hdf5(n, ids.shape)
        except _Stop:
            return None
        vis_px = self.visible(ids, amodal, h5["objects/bbox_tight"])
        am_px = np.array(
            [
                np.count_nonzero(m[_crop(b)])
                for m, b in zip(amodal, h5["objects/bbox_loose"], strict=True)
            ],
            np.int64,
        )
        if not np.array_equal(am_px, [np.count_nonzero(m) for m in amodal]):
            self.bad("_scene.hdf5", "'objects/bbox_loose' does not hold the amodal masks")
            am_px = np.array([np.count_nonzero(m) for m in amodal], np.int64)
        occ = np.round(1.0 - vis_px / np.maximum(am_px, 1), 4)
        try:
            order = _json(self.path("_order.json"), "_order.json", self.bad)
            layout = _json(self.path("_layout.json"), "_layout.json", self.bad)
        except _Stop:
            return None
        # Without layout labels ({v}_layout.json is {}), _order.json holds no rates.
        self.occlusion(npz, ids, occ, vis_px, h5, order if layout != {} else None)
        self.depth_units(npz, ids, vis_px, h5)
        if layout == {}:  # written without layout labels (labels.layout: false)
            self.no_layout(order, n)
        else:
            self.order(order, n, ids, amodal, h5, vis_px)
            self.layout(layout, order, n, h5, vis_px)
        return _ViewFacts(
            n,
            h5["objects/categories"],
            h5["objects/poses_relative_to_camera"],
            h5["objects/scene_instance_id"],
        )

    # -- files of the view -----------------------------------------------------------------

    def camera(self) -> tuple[int, int] | None:
        """``_camera_params.json`` (keys, units) and the size of ``_rgb.png``."""
        try:
            p = _json(self.path("_camera_params.json"), "_camera_params.json", self.bad)
        except _Stop:
            return None
        missing = [k for k in _CAMERA_KEYS if k not in p]
        if missing:
            self.bad("_camera_params.json", f"lacks {missing} (docs/format.md)")
            return None
        try:
            w, h, fx, fy = int(p["width"]), int(p["height"]), float(p["fx"]), float(p["fy"])
            fov = (float(p["horizontal_fov"]), float(p["vertical_fov"]))
            ap = (float(p["horizontal_aperture"]), float(p["vertical_aperture"]))
        except (TypeError, ValueError) as e:
            self.bad("_camera_params.json", f"not numbers: {e}")
            return None
        want = (2 * math.atan(0.5 * w / fx), 2 * math.atan(0.5 * h / fy))
        if not np.allclose(fov, want, rtol=1e-6):
            self.bad(
                "_camera_params.json",
                f"horizontal_fov, vertical_fov {list(fov)}: expected "
                f"radians 2 atan(W / 2 fx), 2 atan(H / 2 fy) = {[round(x, 6) for x in want]}",
            )
        focal = float(p["focal_length"])
        if not np.allclose(ap, (focal * w / fx, focal * h / fy), rtol=1e-6) or not math.isclose(
            focal, MGN_FOCAL_LENGTH_MM
        ):
            self.bad(
                "_camera_params.json",
                f"focal_length {focal}, apertures {list(ap)}: "
                f"expected {MGN_FOCAL_LENGTH_MM} mm and focal_length * W / fx, * H / fy mm",
            )
        if p["resolution"] != {"height": h, "width": w}:
            self.bad("_camera_params.json", f"resolution {p['resolution']} is not width, height")
        if list(p["clipping_range"]) != list(MGN_CLIPPING_RANGE_CM):
            self.bad(
                "_camera_params.json",
                f"clipping_range {p['clipping_range']}: expected "
                f"{list(MGN_CLIPPING_RANGE_CM)} (cm)",
            )
        try:
            with Image.open(self.path("_rgb.png")) as im:  # the header only
                if im.size != (w, h) or im.mode != "RGB":
                    self.bad(
                        "_rgb.png",
                        f"{im.mode} {im.size[0]} x {im.size[1]}, expected RGB "
                        f"{w} x {h} (camera params)",
                    )
        except OSError as e:
            self.bad("_rgb.png", f"not a readable PNG: {e}")
        return h, w

    def masks(
        self, npz: NpzReader, hw: tuple[int, int] | None
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """The npz's keys, dtypes and shapes; the instance ids and amodal masks."""
        try:
            for key, dtypes in _NPZ_KEYS.items():
                if key not in npz:
                    self.bad(".npz", f"lacks '{key}'")
                    continue
                shape, dtype, _ = npz.header(key)
                want = hw if key != "occlusion_objects" else None
                if dtype not in dtypes or (want is not None and shape != want):
                    names = " or ".join(str(np.dtype(d)) for d in dtypes)
                    self.bad(".npz", f"'{key}' is {dtype} {shape}, expected {names} {want}")
                    return None, None
            if "instances_objects" not in npz or "occlusion_objects" not in npz:
                return None, None
            ids, amodal = npz["instances_objects"], npz["occlusion_objects"]
        except Exception as e:
            self.bad(".npz", str(e))
            return None, None
        n = amodal.shape[0]
        if amodal.ndim != 3 or amodal.shape[1:] != ids.shape:
            self.bad(
                ".npz", f"'occlusion_objects' has shape {amodal.shape}, expected (N, *{ids.shape})"
            )
            return None, None
        if ids.dtype.kind == "f":
            if not np.array_equal(ids, np.round(ids)):
                self.bad(".npz", "'instances_objects' holds ids that are not whole numbers")
                return None, None
            ids = ids.astype(np.int64)
        top = int(ids.max(initial=0))
        if top > n:
            self.bad(".npz", f"'instances_objects' has id {top}; the view has {n} objects")
            return None, None
        if top == 0:
            self.bad(".npz", "no visible object in this view (the camera sees only the tote)")
        return ids, amodal

    def visible(self, ids: np.ndarray, amodal: np.ndarray, tight: np.ndarray) -> np.ndarray:
        """Visible pixels per object (every id present; each visible mask inside its amodal
        mask and its ``objects/bbox_tight``)."""
        n = amodal.shape[0]
        vis_px = np.zeros(n, np.int64)
        inside = True
        for i in range(n):
            crop = _crop(tight[i])
            mine = ids[crop] == i + 1
            vis_px[i] = np.count_nonzero(mine)
            if inside and np.any(mine & ~amodal[i][crop]):
                self.bad(".npz", f"visible mask of instance {i + 1} not inside its amodal mask")
                inside = False
        if vis_px.sum() != np.count_nonzero(ids):  # some pixels lie outside their box
            self.bad("_scene.hdf5", "'objects/bbox_tight' does not hold the visible masks")
            vis_px = np.bincount(ids.reshape(-1), minlength=n + 1)[1 : n + 1].astype(np.int64)
        if not (vis_px > 0).all():
            self.bad(
                ".npz",
                f"instances {(np.flatnonzero(vis_px == 0) + 1).tolist()} have no "
                f"visible pixel: a view holds the objects it sees, ids 1..N without gaps "
                f"(MetaGraspNet's visualize_layout.py counts the ids it finds)",
            )
        return vis_px

    def hdf5(self, n: int, hw: tuple[int, ...]) -> dict[str, np.ndarray]:
        """``_scene.hdf5``: keys, shapes, dtypes; the grasp and keypoint groups. Returns the
        small datasets (objects, camera, ids and scores); poses are not read. A missing mgn
        addition of the objects group is reported and stood in for (the whole image as the
        visible box, NaN occlusion, 1..N), so that the other checks still run."""
        out: dict[str, np.ndarray] = {}
        try:
            with h5py.File(self.path("_scene.hdf5"), "r") as h5:
                for key, shape in _OBJECT_KEYS.items():
                    want = tuple(n if s == "N" else s for s in shape)
                    ds = h5.get(key)
                    if ds is None:
                        self.bad("_scene.hdf5", f"lacks '{key}'")
                    elif ds.shape != want:
                        self.bad("_scene.hdf5", f"'{key}' has shape {ds.shape}, expected {want}")
                    else:
                        out[key] = ds[()]
                stand_in = {
                    "objects/bbox_tight": np.tile([0, 0, hw[1], hw[0]], (n, 1)),
                    "objects/occlusion": np.full(n, np.nan, np.float32),
                    "objects/scene_instance_id": np.arange(1, n + 1, dtype=np.int32),
                }
                for key, value in stand_in.items():
                    out.setdefault(key, value)
                if len(out) < len(_OBJECT_KEYS):
                    raise _Stop
                for key in ("objects/categories", "objects/scene_instance_id"):
                    if out[key].dtype.kind not in "iu":
                        self.bad("_scene.hdf5", f"'{key}' is {out[key].dtype}, expected int32")
                self.groups(h5, n, out)
                self.unscored_marks(h5.attrs.get(UNSCORED_ATTR), out)
        except OSError as e:
            self.bad("_scene.hdf5", f"not a readable HDF5 file: {e}")
            raise _Stop from None
        t = out["objects/poses_relative_to_camera"][:, :3, 3]
        if n and not np.all(t[:, 2] > 0):
            self.bad(
                "_scene.hdf5", "'objects/poses_relative_to_camera': an object behind the camera"
            )
        return out

    def groups(self, h5: Any, n: int, out: dict[str, np.ndarray]) -> None:
        for top in ("non_colliding_grasps", "colliding_grasps", "keypts"):
            if top not in h5:
                continue
            for kind in h5[top]:
                g = h5[f"{top}/{kind}"]
                spec = (
                    _GROUP_LEAVES["keypts" if top == "keypts" else kind]
                    if (top == "keypts" or kind in _GROUP_LEAVES)
                    else None
                )
                name = f"{top}/{kind}"
                if spec is None:
                    self.bad("_scene.hdf5", f"unknown group '{name}'")
                    continue
                leaves = dict(spec)
                if top == "colliding_grasps":
                    leaves.update(dict.fromkeys(_COLLISION_LEAVES, ()))
                members = set(g)
                missing = sorted(set(leaves) - members)
                if missing:
                    self.bad("_scene.hdf5", f"group '{name}' lacks {missing}")
                    continue
                rows: dict[str, int] = {}
                for leaf, trailing in leaves.items():
                    # h5py's low-level dataset handle: its wrapper objects cost ~0.1 ms each.
                    ds = h5py.h5d.open(g.id, leaf.encode())
                    shape, dtype = ds.shape, ds.dtype
                    if shape[1:] != trailing:
                        self.bad(
                            "_scene.hdf5",
                            f"'{name}/{leaf}' has shape {shape}, expected (M, *{trailing})",
                        )
                    want_int = leaf in HDF5_INT_LEAVES
                    if (dtype.kind in "iu") != want_int or (not want_int and dtype != np.float32):
                        self.bad(
                            "_scene.hdf5",
                            f"'{name}/{leaf}' is {dtype}, expected "
                            f"{'int32' if want_int else 'float32'}",
                        )
                    rows[leaf] = shape[0]
                    if leaf.endswith("object_id") or leaf in _SCORES or leaf == "contact_width":
                        a = np.empty(shape, dtype)
                        if a.size:
                            ds.read(h5py.h5s.ALL, h5py.h5s.ALL, a)
                        out[f"{name}/{leaf}"] = a
                self.group_values(top, kind, name, rows, out, n)

    def group_values(
        self,
        top: str,
        kind: str,
        name: str,
        rows: dict[str, int],
        out: Mapping[str, np.ndarray],
        n: int,
    ) -> None:
        if top == "keypts":
            pairs = (
                ("keypts_relative_to_camera", "object_id"),
                ("occluded_keypts_relative_to_camera", "occluded_object_id"),
            )
            for a, b in pairs:
                if rows[a] != rows[b]:
                    self.bad("_scene.hdf5", f"'{name}/{a}' has {rows[a]} rows, '{b}' {rows[b]}")
        elif len(set(rows.values())) > 1:
            self.bad("_scene.hdf5", f"group '{name}' has datasets of different lengths {rows}")
            return
        for leaf in ("object_id", "occluded_object_id"):
            ids = out.get(f"{name}/{leaf}")
            if ids is not None and ids.size and (ids.min() < 0 or ids.max() >= n):
                self.bad("_scene.hdf5", f"'{name}/{leaf}' must lie in 0..{n - 1} (instance id - 1)")
        if top != "keypts":
            self.scores(kind, name, out)

    def unscored_marks(self, mark: Any, out: Mapping[str, np.ndarray]) -> None:
        """The root attribute ``mgn_unscored_grasps`` (when present: files of earlier builds
        lack it) counts exactly the NaN parallel-jaw physics scores of the file."""
        if mark is None:
            return
        want = unscored_marks(out).get(UNSCORED_ATTR, {})
        try:
            got = json.loads(mark)
        except (TypeError, ValueError):
            got = None
        if got != want:
            self.bad(
                "_scene.hdf5",
                f"root attribute '{UNSCORED_ATTR}' is {mark!r}; the parallel-jaw physics scores "
                f"hold NaN as {want}",
            )

    def scores(self, kind: str, name: str, out: Mapping[str, np.ndarray]) -> None:
        """Every stored grasp scored (or its missing physics score recorded) and its width."""
        for s in _SCORES:
            a = out[f"{name}/{s}"]
            nan = np.isnan(a)
            finite = a[~nan]
            if finite.size and (finite.min() < 0 or finite.max() > 1):
                self.bad("_scene.hdf5", f"'{name}/{s}' must lie in [0, 1]")
            if not nan.any():
                continue
            if s != "score_simulation":
                self.bad(
                    "_scene.hdf5",
                    f"'{name}/{s}': {int(nan.sum())} stored grasps have no score (NaN)",
                )
            elif (
                kind == "paralleljaw"
                and self.marks.recorded
                and self.marks.pj_physics
                and (self.marks.unscored == 0)
            ):
                self.bad(
                    "_scene.hdf5",
                    f"'{name}/score_simulation': {int(nan.sum())} grasps "
                    "without a physics score, but dataset.json records no unscored grasps "
                    "(physics_scores) and labels.pj_physics is on",
                )
        if kind == "suctioncup":
            nan = np.isnan(out[f"{name}/score_simulation"])
            if nan.any() and not nan.all():
                self.bad(
                    "_scene.hdf5",
                    f"'{name}/score_simulation': {int(nan.sum())} of {nan.size} grasps NaN; "
                    "expected a physics score for every grasp or (labels without one) for none",
                )
        width = out.get(f"{name}/contact_width")
        cap = self.marks.max_opening_cm
        if (
            width is not None
            and width.size
            and (width.min() < 0 or (cap is not None and width.max() > cap * (1 + 1e-6)))
        ):
            self.bad(
                "_scene.hdf5",
                f"'{name}/contact_width' must lie in [0, {cap}] cm (the gripper's opening)",
            )

    # -- invariants between files ----------------------------------------------------------

    def occlusion(
        self,
        npz: NpzReader,
        ids: np.ndarray,
        occ: np.ndarray,
        vis_px: np.ndarray,
        h5: Mapping[str, np.ndarray],
        order: Mapping[str, Any] | None,
    ) -> None:
        """The 4-decimal occlusion rates: masks, ``objects/occlusion``, order.json (None: a
        view without layout labels, whose order.json holds no rates), the image."""
        if order is not None:
            stored = np.array(
                [_num(order.get(str(i + 1), {}).get("occlusion")) for i in range(len(occ))]
            )
            off = np.flatnonzero(~(np.abs(stored - occ) <= 1e-12))
            if off.size:
                i = int(off[0])
                self.bad(
                    "_order.json",
                    f"occlusion of {i + 1} is {stored[i]}, its masks give "
                    f"{occ[i]} (1 - visible / amodal px, 4 decimals)",
                )
        if not np.array_equal(h5["objects/occlusion"], occ.astype(np.float32)):
            self.bad(
                "_scene.hdf5", "'objects/occlusion' differs from the 4-decimal rates of the masks"
            )
        try:
            image = npz["occlusion"]
        except Exception as e:
            self.bad(".npz", str(e))
            return
        # Each object's pixels hold its rate, and nothing else is non-zero.
        tight, rates = h5["objects/bbox_tight"], occ.astype(np.float32)
        ok = all(
            np.all(image[_crop(tight[i])][ids[_crop(tight[i])] == i + 1] == rates[i])
            for i in range(len(occ))
        )
        if not ok or np.count_nonzero(image) != int(vis_px[rates != 0].sum()):
            self.bad(
                ".npz",
                "'occlusion' is not each visible pixel's 4-decimal object occlusion "
                "rate (0 elsewhere)",
            )

    def depth_units(
        self, npz: NpzReader, ids: np.ndarray, vis_px: np.ndarray, h5: Mapping[str, np.ndarray]
    ) -> None:
        """Depth (cm) against the objects' poses (cm): each object's mean depth over its
        visible pixels lies within :data:`_DEPTH_POSE_CM` of its origin's z."""
        try:
            depth = npz["depth"]
        except Exception as e:
            self.bad(".npz", str(e))
            return
        # Every 4th pixel of every 4th row: 1/16 of the image.
        d = depth[::4, ::4].reshape(-1)
        ok = np.isfinite(d)
        flat = ids[::4, ::4].reshape(-1)[ok]
        n = len(vis_px)
        count = np.bincount(flat, minlength=n + 1)[1 : n + 1]
        total = np.bincount(flat, weights=d[ok], minlength=n + 1)[1 : n + 1]
        z = h5["objects/poses_relative_to_camera"][:, 2, 3]
        seen = count >= 4
        gap = np.abs(total[seen] / count[seen] - z[seen])
        if gap.size and np.median(gap) > _DEPTH_POSE_CM:
            self.bad(
                ".npz",
                f"'depth' and the object poses disagree by {np.median(gap):.1f} "
                "(median over objects): both must be in cm",
            )

    def graph(
        self, order: Mapping[str, Any], n: int
    ) -> (
        tuple[
            dict[tuple[int, int], tuple[float, float]],
            dict[tuple[int, int], tuple[float, float]],
            list[list[int]],
        ]
        | None
    ):
        """The relations of ``_order.json`` as listed under the children's ``parents`` and
        under the parents' ``children`` ((parent, child) -> (depth_diff, edge_size)), and each
        object's 0-based parents; None when an entry lacks keys."""
        bad = self.bad
        rel: dict[tuple[int, int], tuple[float, float]] = {}  # (parent, child) -> (dd, edge)
        mirrored: dict[tuple[int, int], tuple[float, float]] = {}
        parents: list[list[int]] = [[] for _ in range(n)]
        for i in range(1, n + 1):
            e = order[str(i)]
            missing = [k for k in _ORDER_KEYS if k not in e]
            if missing:
                bad("_order.json", f"object {i} lacks {missing}")
                return None
            if e["id"] != i:
                bad("_order.json", f"object {i} has id {e['id']}")
            ps = e["parents"]
            if [p.get("id") for p in ps] == [0]:
                if ps != [{"id": 0, "depth_diff": 0.0, "edge_size": 0.0}]:
                    bad(
                        "_order.json",
                        f"object {i}: a parentless entry is {{id 0, depth_diff 0.0, "
                        f"edge_size 0.0}}, got {ps[0]}",
                    )
                ps = []
            for p in ps:
                rel[(p["id"], i)] = (_num(p.get("depth_diff")), _num(p.get("edge_size")))
            for c in e["children"]:
                mirrored[(i, c["id"])] = (_num(c.get("depth_diff")), _num(c.get("edge_size")))
            parents[i - 1] = [int(p["id"]) - 1 for p in ps if isinstance(p.get("id"), int)]
            covered = sum(_num(c.get("edge_size")) for c in e["children"])
            if _num(e["total_covered_edge"]) != covered:
                bad(
                    "_order.json",
                    f"object {i}: total_covered_edge {e['total_covered_edge']} is "
                    f"not the sum of its children's edge_size ({covered})",
                )
        return rel, mirrored, parents

    def order(
        self,
        order: Mapping[str, Any],
        n: int,
        ids: np.ndarray,
        amodal: np.ndarray,
        h5: Mapping[str, np.ndarray],
        vis_px: np.ndarray,
    ) -> None:
        """``_order.json`` and ``_order.csv``: the relation graph as docs/format.md defines it."""
        bad = self.bad
        if sorted(order, key=lambda k: int(k) if str(k).isdigit() else -1) != [
            str(i) for i in range(1, n + 1)
        ]:
            bad("_order.json", f'keys {list(order)[:10]}: expected "1".."{n}" (the objects)')
            return
        parsed = self.graph(order, n)
        if parsed is None:
            return
        rel, mirrored, parents = parsed
        if rel != mirrored:
            diff = sorted(set(rel.items()) ^ set(mirrored.items()))[:3]
            bad("_order.json", f"parents and children lists do not mirror each other: {diff}")
        for (a, b), (dd, edge) in sorted(rel.items()):
            if not (1 <= a <= n) or a == b:
                bad("_order.json", f"object {b} has parent {a}: expected another object 1..{n}")
                return
            if not (dd >= 0 and edge >= 0 and float(edge).is_integer()):
                bad(
                    "_order.json",
                    f"{a} over {b}: depth_diff {dd} cm, edge_size {edge}: expected "
                    "depth_diff >= 0 (the parent above its child) and a pixel count",
                )
            elif (dd == 0) != (edge == 0):
                bad(
                    "_order.json",
                    f"{a} over {b}: depth_diff {dd} cm with edge_size {edge}: a "
                    "measured stretch has depth_diff > 0, an unmeasured one 0.0 and edge 0",
                )
            elif edge > vis_px[b - 1]:
                bad(
                    "_order.json",
                    f"{a} over {b}: edge_size {edge} exceeds {b}'s {vis_px[b - 1]} visible px",
                )
        self.mask_evidence(rel, n, ids, amodal, h5)
        self.csv(rel, n)
        layers = derive_layers(parents)
        stored = [order[str(i + 1)]["layer"] for i in range(n)]
        if stored != layers:
            i = next(k for k in range(n) if stored[k] != layers[k])
            bad(
                "_order.json",
                f"object {i + 1} has layer {stored[i]}; its parents "
                f"{[p + 1 for p in parents[i]]} give layer {layers[i]} (0 no parent, 1 one parent "
                "in layer 0, 2 interlock, 3 others)",
            )

    def no_layout(self, order: Mapping[str, Any], n: int) -> None:
        """``_order.json`` of a view without layout labels: one parentless entry per object."""
        want = {
            str(i): {
                "id": i,
                "parents": [{"id": 0, "depth_diff": 0.0, "edge_size": 0.0}],
                "children": [],
            }
            for i in range(1, n + 1)
        }
        if order != want:
            self.bad(
                "_order.json",
                "without layout labels ({v}_layout.json {}) every object has "
                "the single parentless entry and no children",
            )

    def mask_evidence(
        self,
        rel: Mapping[tuple[int, int], tuple[float, float]],
        n: int,
        ids: np.ndarray,
        amodal: np.ndarray,
        h5: Mapping[str, np.ndarray],
    ) -> None:
        """Each relation's parent is seen on enough of its child's amodal mask."""
        boxes = h5["objects/bbox_loose"]
        seen: dict[int, np.ndarray] = {}

        def seen_over(b: int) -> np.ndarray:  # S[:, b]: pixels of each id inside b's mask
            if b not in seen:
                crop = _crop(boxes[b - 1])  # holds the mask (checked with the occlusion)
                seen[b] = np.bincount(ids[crop][amodal[b - 1][crop]], minlength=n + 1)
            return seen[b]

        for a, b in rel:
            if not (1 <= a <= n and 1 <= b <= n):
                continue
            ab, ba = int(seen_over(b)[a]), int(seen_over(a)[b])
            if ab < _MIN_OVERLAP_PX or ab < _MIN_OVERLAP_FRACTION * (ab + ba):
                self.bad(
                    "_order.json",
                    f"{a} over {b}: {a} is seen on {ab} px of {b}'s amodal mask "
                    f"({b} on {ba} of {a}'s): a parent is seen on at least "
                    f"{_MIN_OVERLAP_PX} px and {_MIN_OVERLAP_FRACTION:.0%} of them",
                )

    def csv(self, rel: Mapping[tuple[int, int], Any], n: int) -> None:
        try:
            rows = [r for r in self.path("_order.csv").read_text().splitlines() if r.strip()]
            m = np.array([[int(float(x)) for x in r.split(",")] for r in rows], np.int64)
        except (OSError, ValueError) as e:
            self.bad("_order.csv", f"not readable: {e}")
            return
        if m.shape != (n, n) and not (n == 0 and m.size == 0):
            self.bad("_order.csv", f"shape {m.shape}, expected ({n}, {n})")
            return
        want = np.zeros((n, n), np.int64)
        for a, b in rel:
            if 1 <= a <= n and 1 <= b <= n:
                want[b - 1, a - 1] = -1
        if not np.array_equal(m, want):
            r, c = np.argwhere(m != want)[0]
            self.bad(
                "_order.csv",
                f"M[{r}][{c}] = {m[r, c]}: expected -1 exactly where instance "
                f"{c + 1} is a parent of {r + 1} in _order.json, else 0",
            )

    def layout(
        self,
        layout: Mapping[str, Any],
        order: Mapping[str, Any],
        n: int,
        h5: Mapping[str, np.ndarray],
        vis_px: np.ndarray,
    ) -> None:
        """``_layout.json`` against the order files and the masks; its difficulty by Table IV."""
        bad = self.bad
        missing = [k for k in _LAYOUT_KEYS if k not in layout]
        if missing:
            bad("_layout.json", f"lacks {missing}")
            return
        objs = layout["objects"]
        if list(objs) != [str(i) for i in range(1, n + 1)]:
            bad("_layout.json", f'objects {list(objs)[:10]}: expected "1".."{n}"')
            return
        cats = h5["objects/categories"]
        for i in range(1, n + 1):
            o, e = objs[str(i)], order.get(str(i), {})
            if any(k not in o for k in _LAYOUT_OBJECT_KEYS):
                bad(
                    "_layout.json",
                    f"object {i} lacks {[k for k in _LAYOUT_OBJECT_KEYS if k not in o]}",
                )
                return
            if o["layer"] != e.get("layer") or o["bin_rel"] != e.get("bin_rel"):
                bad("_layout.json", f"object {i}: layer / bin_rel differ from _order.json")
            if o["category_id"] != int(cats[i - 1]) or o["visible_px"] != int(vis_px[i - 1]):
                bad("_layout.json", f"object {i}: category_id / visible_px differ from the files")
            if o["visible"] is not True:
                bad("_layout.json", f"object {i}: every object of a view is visible")
        layers = {objs[str(i)]["layer"] for i in range(1, n + 1)}
        complete = all(objs[str(i)]["complete"] for i in range(1, n + 1))
        unique = len(set(cats.tolist())) == n
        occ = max((_num(order[str(i)]["occlusion"]) for i in range(1, n + 1)), default=0.0)
        if (layout["num_layers"], layout["classes_unique"], layout["all_complete"]) != (
            len(layers),
            unique,
            complete,
        ) or not math.isclose(_num(layout["max_occlusion"]), occ, abs_tol=1e-12):
            bad(
                "_layout.json",
                "num_layers / classes_unique / all_complete / max_occlusion "
                "differ from the objects",
            )
        if complete and unique:
            level = 1 if len(layers) <= 2 and occ <= _MAX_OCCLUSION_LEVEL1 else 2
        else:
            level = 3 if unique else (4 if complete else 5)
        if layout["difficulty"] != level:
            bad(
                "_layout.json", f"difficulty {layout['difficulty']}: its objects give level {level}"
            )
        picks = layout["order"]
        if sorted(picks) != list(range(1, n + 1)):
            bad("_layout.json", f"order {picks[:10]} is not a permutation of 1..{n}")
            return
        pos = {k: j for j, k in enumerate(picks)}
        parents = [
            [p["id"] - 1 for p in order[str(i)]["parents"] if p["id"]] for i in range(1, n + 1)
        ]
        comp = strongly_connected(parents)
        for i in range(n):
            late = [a + 1 for a in parents[i] if a not in comp[i] and pos[a + 1] > pos[i + 1]]
            if late:
                bad("_layout.json", f"order picks {i + 1} before its parents {late}")
                return


def _crop(box: np.ndarray) -> tuple[slice, slice]:
    """The rows and columns of a COCO box [x, y, w, h] (px)."""
    x, y, w, h = (max(int(v), 0) for v in box)
    return slice(y, y + h), slice(x, x + w)


def _num(x: Any) -> float:
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def _check_scene_gt(
    scene: SceneFolder, facts: Mapping[int, _ViewFacts], found: list[tuple[str, str]]
) -> None:
    """``scene_gt.json``: per view, entry k = instance k + 1 (pose in cm, category)."""
    try:
        gt = json.loads((scene.folder / "scene_gt.json").read_text())
    except FileNotFoundError:
        found.append(("scene_gt.json", "missing"))
        return
    except (OSError, ValueError) as e:
        found.append(("scene_gt.json", f"not readable JSON: {e}"))
        return
    if sorted(gt, key=lambda k: int(k) if str(k).isdigit() else -1) != [
        str(v) for v in scene.view_ids
    ]:
        found.append(("scene_gt.json", f"views {sorted(gt)[:10]} are not the scene's views"))
    for v, f in facts.items():
        entries = gt.get(str(v))
        if not isinstance(entries, list) or len(entries) != f.n:
            found.append(
                ("scene_gt.json", f"view {v}: expected {f.n} entries (the view's objects)")
            )
            continue
        try:
            ids = [int(e["obj_id"]) for e in entries]
            t = np.array([e["cam_t_m2c"] for e in entries], np.float64).reshape(f.n, 3)
            R = np.array([e["cam_R_m2c"] for e in entries], np.float64).reshape(f.n, 3, 3)
        except (KeyError, TypeError, ValueError) as e:
            found.append(("scene_gt.json", f"view {v}: bad entry: {e}"))
            continue
        if ids != [int(c) for c in f.categories]:
            found.append(
                ("scene_gt.json", f"view {v}: obj_id {ids} differ from objects/categories")
            )
        if not (
            np.allclose(t, f.X_CO[:, :3, 3], atol=1e-3, rtol=1e-5)
            and np.allclose(R, f.X_CO[:, :3, :3], atol=1e-5)
        ):
            found.append(
                (
                    "scene_gt.json",
                    f"view {v}: cam_R_m2c / cam_t_m2c (cm) differ from "
                    "objects/poses_relative_to_camera",
                )
            )


def _check_scene(
    scene: SceneFolder, problems: list[Problem], root: Path, marks: _Marks, checksums: bool
) -> None:
    found: list[tuple[str, str]] = []
    if (scene.folder / MANIFEST).exists():
        reason = check_manifest(scene.folder, checksums=checksums)
        if reason is not None:
            found.append((MANIFEST, reason))
    if not scene.view_ids:
        found.append((".", "no views"))
    instance_ids: set[int] | None = None
    try:
        doc = json.loads((scene.folder / "scene.json").read_text())
        instance_ids = {int(i["instance_id"]) for i in doc["instances"]}
    except FileNotFoundError:
        found.append(("scene.json", "missing"))
    except (OSError, ValueError, KeyError, TypeError) as e:
        found.append(("scene.json", f"not a scene description (instances with instance_id): {e}"))
    facts: dict[int, _ViewFacts] = {}
    for v in scene.view_ids:

        def bad(suffix: str, msg: str, v: int = v) -> None:
            found.append((f"{v}{suffix}", msg))

        for name in view_file_names(v):
            if not (scene.folder / name).exists():
                found.append((name, "missing"))
        f = _ViewCheck(scene.folder, v, marks, bad).run()
        if f is None:
            continue
        facts[v] = f
        _check_mgn_hdf5(scene.folder / f"{v}_mgn.hdf5", bad)
        if instance_ids is not None:
            sid = f.scene_instance_id.tolist()
            if not set(sid) <= instance_ids or sorted(set(sid)) != sid:
                bad(
                    "_scene.hdf5",
                    f"'objects/scene_instance_id' {sid[:10]}: expected distinct "
                    "instance ids of scene.json in scene order",
                )
    _check_scene_gt(scene, facts, found)
    rel = scene.folder.relative_to(root)
    problems.extend(Problem(str(rel / name), msg) for name, msg in found)


def _check_mgn_hdf5(path: Path, bad: Report) -> None:
    """``{v}_mgn.hdf5``: its images exist (metadata only; the data is not read)."""
    try:
        with h5py.File(path, "r") as h5:
            for key in ("depth_ideal", "com_heatmap"):
                if key not in h5 or h5[key].ndim != 2:
                    bad("_mgn.hdf5", f"lacks the (H, W) image '{key}'")
    except OSError as e:
        bad("_mgn.hdf5", f"not a readable HDF5 file: {e}")


def _check_completeness(ds: Dataset, info: dict[str, Any], problems: list[Problem]) -> None:
    """An mgn dataset (one with ``dataset.json``) holds exactly the scenes it announces.

    ``num_scenes`` fixes the scene folders ``scene0 .. scene<num_scenes - 1>``; a folder may be
    absent only when a difficulty-balanced run pruned it (``selection.pruned`` and none of its
    views selected). ``status`` must be ``complete``: ``running`` means the process was killed,
    ``interrupted`` stopped by Ctrl-C, ``failed`` stopped by an error (``error`` says which, e.g.
    a full disk), ``incomplete`` that scenes failed. Every scene folder needs its manifest (it is
    written last, so a folder without one was never finished).
    """
    status = info.get("status")
    if status != "complete":
        failed = info.get("failed_scenes")
        more = f" (failed scenes: {failed})" if failed else ""
        if info.get("error"):
            more += f" ({info['error']})"
        problems.append(
            Problem(
                "dataset.json",
                f"status is {status!r}, expected 'complete': the run did not finish{more}; "
                "complete it with 'mgn generate --resume'",
            )
        )
    num = info.get("num_scenes")
    if isinstance(num, bool) or not isinstance(num, int) or num < 0:
        problems.append(Problem("dataset.json", f"num_scenes must be an integer >= 0, got {num!r}"))
        return
    present = set(ds.scene_ids)
    raw_sel = info.get("selection")
    sel: dict[str, Any] = raw_sel if isinstance(raw_sel, dict) else {}
    selected = {int(e["scene"]) for e in sel.get("views", []) if isinstance(e, dict)}
    prunable = bool(sel.get("pruned")) if sel else False
    missing = [i for i in range(num) if i not in present and not (prunable and i not in selected)]
    if missing:
        shown = ", ".join(f"scene{i}" for i in missing[:10]) + (" ..." if len(missing) > 10 else "")
        problems.append(
            Problem(
                ".",
                f"{len(missing)} of num_scenes={num} scene folders missing: {shown}",
            )
        )
    extra = sorted(i for i in present if i >= num)
    if extra:
        problems.append(
            Problem(".", f"scene folders beyond num_scenes={num}: " + ", ".join(map(str, extra)))
        )
    for i in sorted(present):
        if not (ds.root / f"scene{i}" / MANIFEST).exists():
            problems.append(Problem(f"scene{i}/{MANIFEST}", "missing: the scene was not finished"))


def _section(doc: Mapping[str, Any], key: str) -> Mapping[str, Any]:
    value = doc.get(key)
    return value if isinstance(value, Mapping) else {}


def _marks(info: Mapping[str, Any] | None) -> _Marks:
    """What ``dataset.json`` records about physics scores and the gripper (defaults: none)."""
    m = _Marks()
    if not isinstance(info, Mapping):
        return m
    m.recorded = True
    config = _section(info, "config")
    m.pj_physics = bool(_section(config, "labels").get("pj_physics", True))
    unscored = _num(_section(info, "physics_scores").get("unscored"))
    m.unscored = int(unscored) if math.isfinite(unscored) else 0
    opening = _num(_section(config, "gripper").get("max_opening"))
    m.max_opening_cm = opening * 100.0 if math.isfinite(opening) else None
    return m


def validate_dataset(root: str | os.PathLike[str], *, checksums: bool = True) -> list[Problem]:
    """Every problem found in the dataset at ``root`` (an empty list: valid; module doc).

    Besides every file of every scene, an mgn dataset (with ``dataset.json``) must be complete:
    its status ``complete`` and the scene folders the ones ``num_scenes`` announces.
    ``checksums``: compare every file's SHA-256 with its scene's manifest (else sizes only).
    """
    ds = Dataset(root)
    problems: list[Problem] = []
    info: dict[str, Any] | None = None
    try:
        info = ds.info
    except Exception as e:
        problems.append(Problem("dataset.json", str(e)))
    if not ds.scene_ids:
        problems.append(Problem(".", "no scene<N> folders"))
    if isinstance(info, dict):
        _check_completeness(ds, info, problems)
    marks = _marks(info)
    for scene in ds.scenes():
        _check_scene(scene, problems, ds.root, marks, checksums)
    return problems
