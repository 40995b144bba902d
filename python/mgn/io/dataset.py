"""Read a dataset back: ``mgn.Dataset(DIR)`` (lazy; SI units; also original MetaGraspNet folders,
synthetic and real: the real scenes' ``{v}_amodal.npz`` and ``{v}_grasps.npz`` are read by
:attr:`View.real_amodal`, :attr:`View.suction_bitmap` and :attr:`View.parallel_jaw_2d`).

Layout (docs/format.md): ``DIR/dataset.json`` (mgn only), ``DIR/models/<id>/`` object folders and
``DIR/scene<N>/`` scene folders with the files of :mod:`mgn.io.scene_folder`. Nothing is read
before it is asked for, and what is read is kept (a :class:`View` caches its arrays).

Units: the files store centimetres; everything returned here is in metres (the conversion table
is :data:`mgn.io.scene_schema.CM_RULES`), except the ``{v}_order.json`` content, which is
returned as stored (its ``depth_diff`` in cm).

Example::

    ds = mgn.Dataset("out")
    for scene in ds.scenes():
        view = scene.view(0)
        rgb, depth_m = view.rgb, view.depth
        pj = view.grasps("paralleljaw")          # non-colliding, camera frame, metres
"""

from __future__ import annotations

import io
import json
import lzma
import os
import re
import zipfile
import zlib
from functools import cached_property
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import numpy.typing as npt
from PIL import Image

from mgn.base.units import M_TO_CM
from mgn.errors import IoError
from mgn.hardware import MGN_FOLDER, normalize_grasp_kind
from mgn.io.image_codecs import (
    COM_RESIDUAL_ENCODING,
    FLOAT_DELTA_ENCODING,
    FLOAT_GRADIENT_ENCODING,
    UNORM16_ENCODING,
    com_heatmap_prediction,
    decode_com_residual,
    decode_float_gradient,
    decode_float_image,
)
from mgn.io.model_folder import object_folders
from mgn.io.order_files import read_order_csv, read_order_json
from mgn.io.scene_hdf5 import POSE_COLUMNS_GROUP, read_scene_dataset
from mgn.io.scene_schema import UNITS_ATTR, from_cm, ideal_metres
from mgn.scene.cameras import MGN_APERTURE_MM, MGN_FOCAL_LENGTH_MM, Intrinsics

#: What reading a damaged npz raises (zipfile's checks, a bad CRC-32 or header, zlib's or LZMA's
#: inflater on a damaged stream, a cut file).
_NPZ_ERRORS = (OSError, ValueError, zipfile.BadZipFile, EOFError, zlib.error, lzma.LZMAError)

__all__ = ["Dataset", "SceneFolder", "View"]

_SCENE_RE = re.compile(r"^scene(\d+)$")
_VIEW_RE = re.compile(r"^(\d+)_rgb\.png$")


def _read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise IoError(f"'{path}' does not exist") from None
    except (OSError, ValueError) as e:
        raise IoError(f"'{path}' is not readable JSON: {e}") from e


def intrinsics_from_params(p: dict[str, Any]) -> Intrinsics:
    """Intrinsics from a ``{v}_camera_params.json`` (mgn's px keys with the OpenCV
    ``distortion`` when the images are distorted, or MetaGraspNet's focal length and apertures
    in mm with the principal point at the image centre)."""
    if all(k in p for k in ("fx", "fy", "cx", "cy", "width", "height")):
        return Intrinsics(
            int(p["width"]),
            int(p["height"]),
            float(p["fx"]),
            float(p["fy"]),
            float(p["cx"]),
            float(p["cy"]),
            tuple(float(c) for c in p.get("distortion", ())),
        )
    try:
        w = int(p["resolution"]["width"])
        h = int(p["resolution"]["height"])
        f = float(p["focal_length"])
        fx = f * w / float(p["horizontal_aperture"])
        fy = f * h / float(p["vertical_aperture"])
    except (KeyError, TypeError, ValueError, ZeroDivisionError) as e:
        raise IoError(f"camera params lack fx/fy/cx/cy and the MetaGraspNet keys: {e}") from e
    return Intrinsics(w, h, fx, fy, w / 2.0, h / 2.0)


class View:
    """One view of a scene folder (lazy; arrays are read on first access and kept)."""

    def __init__(self, folder: Path, index: int) -> None:
        self.folder = folder
        self.index = index

    def __repr__(self) -> str:
        return f"View({str(self.folder)!r}, {self.index})"

    def path(self, suffix: str) -> Path:
        """``folder / f"{index}{suffix}"``, e.g. ``path("_rgb.png")``."""
        return self.folder / f"{self.index}{suffix}"

    @cached_property
    def rgb(self) -> npt.NDArray[np.uint8]:
        """(H, W, 3) uint8."""

        try:
            with Image.open(self.path("_rgb.png")) as im:
                return np.asarray(im.convert("RGB"))
        except OSError as e:
            raise IoError(f"'{self.path('_rgb.png')}' is not a readable PNG: {e}") from e

    @cached_property
    def npz(self) -> dict[str, np.ndarray]:
        """All arrays of ``{v}.npz`` as stored (depth in cm)."""
        p = self.path(".npz")
        try:
            data = p.read_bytes()
        except FileNotFoundError:
            raise IoError(f"'{p}' does not exist") from None
        except OSError as e:
            raise IoError(f"'{p}' is not readable: {e}") from e
        try:
            with np.load(io.BytesIO(data), allow_pickle=False) as z:
                return {k: z[k] for k in z.files}
        except _NPZ_ERRORS as e:
            raise IoError(f"'{p}' is not a readable npz: {e}") from e

    def npz_array(self, key: str) -> np.ndarray:
        """One array of ``{v}.npz`` as stored, reading (decompressing) only that array; kept.
        IoError if the file or the key is missing."""
        if "npz" in self.__dict__:
            try:
                npz: dict[str, np.ndarray] = self.__dict__["npz"]
                return npz[key]
            except KeyError:
                raise IoError(f"'{self.path('.npz')}' has no array '{key}'") from None
        cache: dict[str, np.ndarray] = self.__dict__.setdefault("_npz_arrays", {})
        if key not in cache:
            p = self.path(".npz")
            try:
                with np.load(p, allow_pickle=False) as z:
                    if key not in z.files:
                        raise IoError(f"'{p}' has no array '{key}' (it has {z.files})")
                    cache[key] = z[key]
            except FileNotFoundError:
                raise IoError(f"'{p}' does not exist") from None
            except _NPZ_ERRORS as e:
                if isinstance(e, IoError):
                    raise
                raise IoError(f"'{p}' is not a readable npz: {e}") from e
        return cache[key]

    def hdf5_dataset(self, name: str) -> np.ndarray:
        """One dataset of ``{v}_scene.hdf5`` (lengths in metres), reading only that dataset.
        IoError if the file or the dataset is missing."""
        if "hdf5" in self.__dict__:
            try:
                hdf5: dict[str, np.ndarray] = self.__dict__["hdf5"]
                return hdf5[name]
            except KeyError:
                raise IoError(f"'{self.path('_scene.hdf5')}' has no dataset '{name}'") from None
        p = self.path("_scene.hdf5")
        try:
            with h5py.File(p, "r") as h5:
                if name not in h5:
                    raise IoError(f"'{p}' has no dataset '{name}'")
                return from_cm(name, read_scene_dataset(h5, name))
        except FileNotFoundError:
            raise IoError(f"'{p}' does not exist") from None
        except OSError as e:
            if isinstance(e, IoError):
                raise
            raise IoError(f"'{p}' is not a readable HDF5 file: {e}") from e

    @property
    def depth(self) -> npt.NDArray[np.float32]:
        """(H, W) sensor z-depth, m, NaN invalid."""
        depth: npt.NDArray[np.float32] = (self.npz["depth"] / np.float32(M_TO_CM)).astype(
            np.float32
        )
        return depth

    def mgn_image(self, name: str) -> np.ndarray | None:
        """An image of ``{v}_mgn.hdf5`` as stored (``depth_ideal`` in cm), reading only it; kept.
        Datasets written before that file existed had these images in ``{v}.npz``: read from
        there. None if the view has no such image (original MetaGraspNet folders)."""
        cache: dict[str, np.ndarray | None] = self.__dict__.setdefault("_mgn_images", {})
        if name in cache:
            return cache[name]
        p = self.path("_mgn.hdf5")
        value = None
        if p.exists():
            try:
                with h5py.File(p, "r") as h5:
                    if name in h5:
                        ds = h5[name]
                        value = ds[()]
                        coding = ds.attrs.get("mgn_encoding")
                        if coding == FLOAT_GRADIENT_ENCODING:
                            value = decode_float_gradient(value)
                        elif coding == FLOAT_DELTA_ENCODING:
                            value = decode_float_image(value)
                        elif coding == UNORM16_ENCODING:
                            value = value.astype(np.float32) / np.float32(65535.0)
                        elif coding == COM_RESIDUAL_ENCODING:
                            ideal = self._depth_ideal_m()
                            if ideal is None:
                                raise IoError(f"'{p}': com_heatmap needs depth_ideal, absent")
                            pred = com_heatmap_prediction(
                                ideal,
                                self.npz_array("instances_objects"),
                                ds.attrs["X_WC"],
                                ds.attrs["K"],
                                ds.attrs["com_parameters"],
                            )
                            value = decode_com_residual(value, pred)
                        if ds.attrs.get(UNITS_ATTR) == "m":
                            # Stored in metres (the renderer's float32): kept, and given in cm
                            # as the writer converts them (float32 of the float64 product).
                            cache[f"{name} (m)"] = value
                            value = (value.astype(np.float64) * M_TO_CM).astype(np.float32)
            except OSError as e:
                raise IoError(f"'{p}' is not a readable HDF5 file: {e}") from e
        elif self.path(".npz").exists():
            with np.load(self.path(".npz"), allow_pickle=False) as z:
                value = z[name] if name in z.files else None
        cache[name] = value
        return value

    def _depth_ideal_m(self) -> npt.NDArray[np.float32] | None:
        """``depth_ideal`` in metres: as stored when the file holds metres (the renderer's
        values), else the stored cm / 100."""
        d = self.mgn_image("depth_ideal")
        cache: dict[str, np.ndarray | None] = self.__dict__["_mgn_images"]
        if "depth_ideal (m)" in cache:
            return cache["depth_ideal (m)"]
        return None if d is None else ideal_metres(d)

    @property
    def depth_ideal(self) -> npt.NDArray[np.float32] | None:
        """(H, W) noise-free z-depth, m (mgn files only; None otherwise)."""
        return self._depth_ideal_m()

    @property
    def valid_depth(self) -> npt.NDArray[np.bool_]:
        """(H, W) bool: pixels where the sensor measured a depth (stored only when it is not
        exactly the finite pixels of ``depth``)."""
        v = self.mgn_image("valid_depth")
        return np.isfinite(self.npz_array("depth")) if v is None else v.astype(bool)

    @property
    def com_heatmap(self) -> npt.NDArray[np.float32] | None:
        """(H, W) CoM score of the surface seen at each pixel in [0, 1] (mgn files only)."""
        c = self.mgn_image("com_heatmap")
        return None if c is None else c.astype(np.float32)

    def _npz_has(self, key: str) -> bool:
        """Whether ``{v}.npz`` exists and holds ``key`` (reads only the file's index)."""
        p = self.path(".npz")
        if "npz" in self.__dict__:
            return key in self.__dict__["npz"]
        if not p.exists():
            return False
        try:
            with np.load(p, allow_pickle=False) as z:
                return key in z.files
        except _NPZ_ERRORS as e:
            raise IoError(f"'{p}' is not a readable npz: {e}") from e

    @property
    def instances(self) -> npt.NDArray[np.int32]:
        """(H, W) contiguous instance ids, 0 background. MetaGraspNet's real scenes: from
        ``{v}.npz`` when it holds ``instances_objects``, else from the visible masks of
        ``{v}_amodal.npz`` (instance i + 1 where ``[i, 0]`` is set)."""
        if not self._npz_has("instances_objects"):
            real = self.real_amodal
            if real is not None:
                ids = np.zeros(real.shape[2:], np.int32)
                for i in range(real.shape[0]):
                    ids[real[i, 0] & (ids == 0)] = i + 1
                return ids
            raise IoError(
                f"{self}: no instance masks ('{self.path('.npz')}' has no 'instances_objects' "
                f"and there is no '{self.path('_amodal.npz')}')"
            )
        return self.npz["instances_objects"].astype(np.int32)

    @property
    def semantic(self) -> npt.NDArray[np.int32]:
        """(H, W) category ids, 0 background."""
        return self.npz["instances_semantic"].astype(np.int32)

    @property
    def occlusion_map(self) -> npt.NDArray[np.float32]:
        """(H, W) occlusion rate of each visible pixel's object."""
        return self.npz["occlusion"].astype(np.float32)

    @property
    def amodal(self) -> npt.NDArray[np.bool_]:
        """(N, H, W) amodal masks (row i = instance i + 1). MetaGraspNet's real scenes: the
        visible and hidden parts of ``{v}_amodal.npz`` together."""
        if not self._npz_has("occlusion_objects"):
            real = self.real_amodal
            if real is not None:
                return real[:, 0] | real[:, 1]
        return self.npz["occlusion_objects"].astype(bool)

    @property
    def num_instances(self) -> int:
        """N, the number of instances of the view's scene."""
        if not self._npz_has("occlusion_objects") and self.real_amodal is not None:
            return int(self.real_amodal.shape[0])
        return int(self.npz["occlusion_objects"].shape[0])

    def _extra_npz(self, suffix: str) -> dict[str, np.ndarray]:
        p = self.path(suffix)
        if not p.exists():
            return {}
        try:
            with np.load(p, allow_pickle=False) as z:
                return {k: z[k] for k in z.files}
        except _NPZ_ERRORS as e:
            raise IoError(f"'{p}' is not a readable npz: {e}") from e

    @cached_property
    def real_amodal(self) -> npt.NDArray[np.bool_] | None:
        """(N, 2, H, W) bool ``amodal_bitmaps_full_size_instances`` of ``{v}_amodal.npz``
        (MetaGraspNet's real scenes, the annotated view: ``[:, 0]`` the visible part of each
        object, ``[:, 1]`` its hidden part); None when the view has no such file."""
        arrays = self._extra_npz("_amodal.npz")
        if not arrays:
            return None
        key = "amodal_bitmaps_full_size_instances"
        if key not in arrays:
            raise IoError(f"'{self.path('_amodal.npz')}' has no '{key}' (it has {sorted(arrays)})")
        a = np.asarray(arrays[key])
        if a.ndim != 4 or a.shape[1] != 2:
            raise IoError(
                f"'{self.path('_amodal.npz')}': '{key}' must be (N, 2, H, W), got {a.shape}"
            )
        return a.astype(bool)

    @cached_property
    def real_grasps(self) -> dict[str, np.ndarray]:
        """The arrays of ``{v}_grasps.npz`` (MetaGraspNet's real scenes: ``suction_bitmap``
        and ``parallel_jaw_2d``); empty when the view has no such file."""
        return self._extra_npz("_grasps.npz")

    @property
    def suction_bitmap(self) -> npt.NDArray[np.float32] | None:
        """(H, W) float32 hand-labelled suction map of a real view (``suction_bitmap`` of
        ``{v}_grasps.npz``; non-zero = a good suction point), None if absent."""
        b = self.real_grasps.get("suction_bitmap")
        return None if b is None else np.asarray(b, np.float32)

    @property
    def parallel_jaw_2d(self) -> npt.NDArray[np.float64] | None:
        """(M, 2, 2) hand-labelled parallel-jaw grasps of a real view as image point pairs
        [[x1, y1], [x2, y2]] px (``parallel_jaw_2d`` of ``{v}_grasps.npz``), None if absent."""
        g = self.real_grasps.get("parallel_jaw_2d")
        return None if g is None else np.asarray(g, np.float64).reshape(-1, 2, 2)

    @cached_property
    def hdf5(self) -> dict[str, np.ndarray]:
        """Every dataset of ``{v}_scene.hdf5`` by path, lengths converted to metres."""
        p = self.path("_scene.hdf5")
        out: dict[str, np.ndarray] = {}
        try:
            with h5py.File(p, "r") as h5:

                def visit(name: str, obj: Any) -> None:
                    if isinstance(obj, h5py.Dataset) and not name.startswith(POSE_COLUMNS_GROUP):
                        out[name] = from_cm(name, read_scene_dataset(h5, name))

                h5.visititems(visit)
        except FileNotFoundError:
            raise IoError(f"'{p}' does not exist") from None
        except OSError as e:
            raise IoError(f"'{p}' is not a readable HDF5 file: {e}") from e
        return out

    @property
    def X_WC(self) -> npt.NDArray[np.float64]:
        """(4, 4) camera pose in the world (tote frame), m."""
        return self.hdf5["camera/pose_relative_to_world"].reshape(4, 4)

    @property
    def X_CO(self) -> npt.NDArray[np.float64]:
        """(N, 4, 4) object poses in the camera frame, m."""
        return self.hdf5["objects/poses_relative_to_camera"]

    def grasps(self, kind: str, *, colliding: bool = False) -> dict[str, np.ndarray]:
        """The scene grasps of ``kind`` (``"suction"`` or ``"paralleljaw"``; the MetaGraspNet
        folder names ``"suctioncup"`` and aliases such as ``"pj"`` work too), camera frame,
        metres: the datasets of ``(non_)colliding_grasps/<folder>/`` by name (empty dict if
        absent)."""

        kind = MGN_FOLDER[normalize_grasp_kind(kind)]
        prefix = f"{'colliding' if colliding else 'non_colliding'}_grasps/{kind}/"
        return {k[len(prefix) :]: v for k, v in self.hdf5.items() if k.startswith(prefix)}

    @cached_property
    def order(self) -> dict[str, Any]:
        """``{v}_order.json`` as stored (keys "1".."N"; depth_diff in cm)."""
        order: dict[str, Any] = _read_json(self.path("_order.json"))
        return order

    @cached_property
    def layout(self) -> dict[str, Any] | None:
        """``{v}_layout.json`` (mgn: bin relations, difficulty), None if absent."""
        p = self.path("_layout.json")
        return _read_json(p) if p.exists() else None

    @cached_property
    def relation_matrix(self) -> npt.NDArray[np.int8]:
        """(N, N) int8 relation matrix from ``{v}_order.csv``: M[i][j] = -1 if instance j+1
        lies on / occludes instance i+1, +1 for the reverse (the file stores the -1 entries;
        :func:`mgn.io.order_files.read_order_csv`)."""

        csv = self.path("_order.csv")
        if csv.exists():
            return read_order_csv(csv)
        # Original MetaGraspNet downloads lack the CSV of some views: the JSON's parents say it.
        return np.array(read_order_json(self.path("_order.json")).relation, np.int8)

    @cached_property
    def intrinsics(self) -> Intrinsics:
        """The camera intrinsics of the view. Original MetaGraspNet synthetic scenes have no
        ``{v}_camera_params.json``: their camera is the MGN one (35 mm focal length on a 20.955 mm
        aperture, square pixels, principal point at the image centre) at the RGB image's size."""
        p = self.path("_camera_params.json")
        if p.exists():
            return intrinsics_from_params(_read_json(p))
        h, w = self.rgb.shape[:2]
        f = MGN_FOCAL_LENGTH_MM * w / MGN_APERTURE_MM
        return Intrinsics(int(w), int(h), f, f, w / 2.0, h / 2.0)


class SceneFolder:
    """One ``scene<N>`` folder."""

    def __init__(self, folder: Path, scene_id: int) -> None:
        self.folder = folder
        self.scene_id = scene_id

    def __repr__(self) -> str:
        return f"SceneFolder({str(self.folder)!r})"

    @cached_property
    def view_ids(self) -> list[int]:
        """Indices of the views present (by their ``{v}_rgb.png``), ascending."""
        ids = [int(m.group(1)) for p in self.folder.iterdir() if (m := _VIEW_RE.match(p.name))]
        return sorted(ids)

    def view(self, v: int) -> View:
        """View ``v``; IoError if the scene has no such view."""
        if v not in self.view_ids:
            raise IoError(f"{self.folder}: no view {v} (views: {self.view_ids})")
        return View(self.folder, v)

    def views(self) -> list[View]:
        """All views, ascending."""
        return [View(self.folder, v) for v in self.view_ids]

    @cached_property
    def scene_json(self) -> dict[str, Any] | None:
        """mgn's ``scene.json`` (objects, poses, tote, seed), None for original MGN folders."""
        p = self.folder / "scene.json"
        return _read_json(p) if p.exists() else None

    @cached_property
    def scene_gt(self) -> dict[str, Any] | None:
        """``scene_gt.json`` (per view: cam_R_m2c, cam_t_m2c in cm, obj_id), None if absent."""
        p = self.folder / "scene_gt.json"
        return _read_json(p) if p.exists() else None


class Dataset:
    """A dataset folder written by ``mgn generate`` (or an original MetaGraspNet download)."""

    def __init__(self, root: str | os.PathLike[str]) -> None:
        self.root = Path(root)
        if not self.root.is_dir():
            raise IoError(f"Dataset: '{self.root}' is not a folder")

    def __repr__(self) -> str:
        return f"Dataset({str(self.root)!r})"

    @cached_property
    def info(self) -> dict[str, Any] | None:
        """``dataset.json`` (schema version, config, versions, seed), None if absent."""
        p = self.root / "dataset.json"
        return _read_json(p) if p.exists() else None

    @cached_property
    def scene_ids(self) -> list[int]:
        """Ids N of the complete ``scene<N>`` folders, ascending."""
        ids = [
            int(m.group(1))
            for p in self.root.iterdir()
            if p.is_dir() and (m := _SCENE_RE.match(p.name))
        ]
        return sorted(ids)

    def scene(self, n: int) -> SceneFolder:
        """Scene ``n``; IoError if absent."""
        if n not in self.scene_ids:
            raise IoError(f"{self.root}: no scene{n} (scenes: {self.scene_ids[:20]}...)")
        return SceneFolder(self.root / f"scene{n}", n)

    def scenes(self) -> list[SceneFolder]:
        """All scenes, ascending."""
        return [SceneFolder(self.root / f"scene{n}", n) for n in self.scene_ids]

    def model_folders(self) -> list[Path]:
        """The object folders ``models/<id>/``."""

        return object_folders(self.root)

    def __len__(self) -> int:
        return len(self.scene_ids)
