"""Labelled real photographs for evaluation: two layouts, read into :class:`RealImage` records.

**MetaGraspNet's real layout** (``dataset_real/scene<N>/``, read through :class:`mgn.Dataset`):
per view ``{v}_rgb.png``; ``{v}.npz`` with ``depth`` (cm, NaN no value) and, where labelled,
``instances_objects``; the annotated view's ``{v}_amodal.npz``
(``amodal_bitmaps_full_size_instances`` (N, 2, H, W): visible and hidden part of each object)
and ``{v}_grasps.npz`` (``suction_bitmap`` (H, W), non-zero = good suction point;
``parallel_jaw_2d`` (M, 2, 2) image point pairs). A view is an evaluation image when it has
masks (``{v}_amodal.npz`` or ``instances_objects``). ``PATH`` is the folder holding the
``scene<N>`` folders or one scene folder.

**A COCO folder**: images (PNG/JPEG) and one COCO instances JSON (``images`` with ``id``,
``file_name`` relative to the JSON's folder, ``width``, ``height``; ``annotations`` with
``image_id`` and ``segmentation`` as polygons or RLE; categories are ignored: the evaluation is
class-agnostic). An annotation with ``iscrowd: 1`` marks object pixels whose objects are not
outlined one by one (a foreground label): it counts for the foreground IoU and is an ignored
region for the mask AP (COCO's crowd rule). Optional depth per image: ``<stem>_depth.npy`` (m)
or ``<stem>_depth.png`` (16-bit, mm) beside the image. ``PATH`` is the JSON file, or the folder
when it holds exactly one ``.json`` file.

Depth files elsewhere (``mgn predict --depth``): :func:`read_depth`.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from PIL import Image
from pycocotools import mask as mask_utils

from mgn.errors import IoError
from mgn.io.dataset import Dataset, SceneFolder, View

__all__ = [
    "IMAGE_SUFFIXES",
    "REAL_FORMATS",
    "RealImage",
    "detect_real_format",
    "read_coco_folder",
    "read_depth",
    "read_image",
    "read_mgn_real",
    "read_real_set",
]

#: Image files read as photographs.
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg")
#: The layouts :func:`read_real_set` reads.
REAL_FORMATS = ("metagraspnet", "coco")


def read_image(path: str | os.PathLike[str]) -> npt.NDArray[np.uint8]:
    """(H, W, 3) uint8 RGB of a PNG or JPEG file; IoError naming the file otherwise."""
    p = Path(path)
    if p.suffix.lower() not in IMAGE_SUFFIXES:
        raise IoError(f"'{p}': expected a PNG or JPEG image ({', '.join(IMAGE_SUFFIXES)})")
    try:
        with Image.open(p) as im:
            return np.asarray(im.convert("RGB"))
    except FileNotFoundError:
        raise IoError(f"'{p}' does not exist") from None
    except OSError as e:
        raise IoError(f"'{p}' is not a readable image: {e}") from e


def read_depth(path: str | os.PathLike[str]) -> npt.NDArray[np.float32]:
    """(H, W) float32 depth in metres, NaN where there is no value (0, negative or NaN in the
    file), from ``.npy`` (float, m), ``.npz`` with a ``depth`` array in cm (MetaGraspNet's
    ``{v}.npz``) or a 16-bit single-channel PNG in mm."""
    p = Path(path)
    suffix = p.suffix.lower()
    try:
        if suffix == ".npy":
            d: npt.NDArray[np.float32] = np.load(p, allow_pickle=False).astype(np.float32)
        elif suffix == ".npz":
            with np.load(p, allow_pickle=False) as z:
                if "depth" not in z.files:
                    raise IoError(f"'{p}' has no 'depth' array (it has {z.files})")
                d = z["depth"].astype(np.float32) / np.float32(100.0)
        elif suffix == ".png":
            with Image.open(p) as im:
                raw = np.asarray(im)
            if raw.ndim != 2 or raw.dtype != np.uint16:
                raise IoError(
                    f"'{p}': a depth PNG must be 16-bit single-channel (mm), got "
                    f"{raw.dtype} {raw.shape}"
                )
            d = raw.astype(np.float32) / np.float32(1000.0)
        else:
            raise IoError(f"'{p}': depth must be .npy (m), .npz 'depth' (cm) or 16-bit .png (mm)")
    except FileNotFoundError:
        raise IoError(f"'{p}' does not exist") from None
    except (OSError, ValueError) as e:
        if isinstance(e, IoError):
            raise
        raise IoError(f"'{p}' is not a readable depth file: {e}") from e
    if d.ndim != 2:
        raise IoError(f"'{p}': depth must be a 2-D array, got shape {d.shape}")
    d[~np.isfinite(d) | (d <= 0)] = np.nan
    return d


@dataclass
class RealImage:
    """One labelled photograph.

    Attributes:
        name: where it came from ("scene46/3", or the image's file name).
        rgb: (H, W, 3) uint8.
        depth: (H, W) float32 m (NaN no value), or None.
        masks: (N, H, W) bool visible object masks.
        amodal: (N, H, W) bool amodal masks, or None when the labels have none.
        suction_bitmap: (H, W) float32 (non-zero = good suction point), or None.
        parallel_jaw_2d: (M, 2, 2) image point pairs px, or None.
        crowd: (H, W) bool object pixels labelled without separating the objects (COCO
            ``iscrowd: 1``), or None. The labelled foreground is ``masks`` and ``crowd``.
    """

    name: str
    rgb: npt.NDArray[np.uint8]
    depth: npt.NDArray[np.float32] | None
    masks: npt.NDArray[np.bool_]
    amodal: npt.NDArray[np.bool_] | None = None
    suction_bitmap: npt.NDArray[np.float32] | None = None
    parallel_jaw_2d: npt.NDArray[np.float64] | None = None
    crowd: npt.NDArray[np.bool_] | None = None

    @property
    def foreground(self) -> npt.NDArray[np.bool_]:
        """(H, W) bool: every labelled object pixel (the visible masks and ``crowd``)."""
        fg = np.zeros(self.rgb.shape[:2], bool)
        for m in self.masks:
            fg |= m
        if self.crowd is not None:
            fg |= self.crowd
        return fg

    def check(self, source: str) -> None:
        """IoError naming ``source`` when an array's size differs from the image's."""
        h, w = self.rgb.shape[:2]
        arrays: dict[str, Any] = {
            "masks": self.masks,
            "amodal": self.amodal,
            "depth": self.depth,
            "suction_bitmap": self.suction_bitmap,
            "crowd": self.crowd,
        }
        for key, a in arrays.items():
            if a is not None and tuple(a.shape[-2:]) != (h, w):
                raise IoError(
                    f"{source}: {key} is {a.shape[-1]} x {a.shape[-2]} px but the image is "
                    f"{w} x {h} px"
                )


def _is_mgn_scene(folder: Path) -> bool:
    return folder.is_dir() and any(folder.glob("*_rgb.png"))


def detect_real_format(path: str | os.PathLike[str]) -> str:
    """``"metagraspnet"`` or ``"coco"`` for a path of either layout (module docstring);
    IoError naming the path and both layouts otherwise."""
    p = Path(path)
    if p.is_file() and p.suffix.lower() == ".json":
        return "coco"
    if p.is_dir():
        if _is_mgn_scene(p) or any(
            _is_mgn_scene(s) for s in p.iterdir() if s.name.startswith("scene")
        ):
            return "metagraspnet"
        if len(list(p.glob("*.json"))) == 1:
            return "coco"
    if not p.exists():
        raise IoError(f"'{p}' does not exist")
    raise IoError(
        f"'{p}' is in no known annotation format: expected MetaGraspNet's real layout (scene<N>/ "
        "folders with {v}_rgb.png and {v}_amodal.npz or {v}.npz masks) or a folder of images "
        "with one COCO instances JSON (or the JSON file itself)"
    )


def _view_image(view: View) -> RealImage | None:
    has_masks = view.path("_amodal.npz").exists() or view._npz_has("instances_objects")
    if not has_masks:
        return None
    name = f"{view.folder.name}/{view.index}"
    ids = view.instances
    real = view.real_amodal
    amodal: np.ndarray | None
    if real is not None:
        masks, amodal = real[:, 0], real[:, 0] | real[:, 1]
    else:
        masks = ids[None] == np.arange(1, int(ids.max()) + 1)[:, None, None]
        amodal = view.amodal if view._npz_has("occlusion_objects") else None
    depth = view.depth if view._npz_has("depth") else None
    img = RealImage(name, view.rgb, depth, masks, amodal, view.suction_bitmap, view.parallel_jaw_2d)
    img.check(f"'{view.folder}' view {view.index}")
    return img


def read_mgn_real(path: str | os.PathLike[str]) -> list[RealImage]:
    """The labelled views of MetaGraspNet's real layout (module docstring), by scene, view."""
    p = Path(path)
    if _is_mgn_scene(p) and not any(_is_mgn_scene(s) for s in p.glob("scene*")):
        m = p.name.removeprefix("scene")
        scenes = [SceneFolder(p, int(m) if m.isdigit() else 0)]
    else:
        scenes = Dataset(p).scenes()
    images = [img for s in scenes for v in s.views() if (img := _view_image(v)) is not None]
    if not images:
        raise IoError(f"'{p}': no labelled view ({{v}}_amodal.npz or {{v}}.npz masks) found")
    return images


def _coco_json(p: Path) -> Path:
    if p.is_file():
        return p
    found = sorted(p.glob("*.json"))
    if len(found) != 1:
        raise IoError(
            f"'{p}': expected exactly one COCO annotations .json, found "
            f"{[f.name for f in found]}; name the file"
        )
    return found[0]


def _ann_mask(ann: dict[str, Any], h: int, w: int, source: str) -> np.ndarray:
    seg = ann.get("segmentation")
    try:
        if isinstance(seg, list):
            rle = mask_utils.merge(mask_utils.frPyObjects(seg, h, w))
        elif isinstance(seg, dict) and isinstance(seg.get("counts"), list):
            rle = mask_utils.frPyObjects(seg, h, w)
        elif isinstance(seg, dict):
            counts = seg["counts"]
            rle = {
                "size": seg["size"],
                "counts": counts.encode() if isinstance(counts, str) else counts,
            }
        else:
            raise IoError(
                f"{source}: annotation {ann.get('id')} has no polygon or RLE 'segmentation'"
            )
        m = mask_utils.decode(rle).astype(bool)
    except (KeyError, TypeError, ValueError) as e:
        raise IoError(
            f"{source}: annotation {ann.get('id')} has an unreadable 'segmentation': {e}"
        ) from e
    if m.ndim == 3:
        m = m.any(axis=2)
    if m.shape != (h, w):
        raise IoError(
            f"{source}: annotation {ann.get('id')} mask is {m.shape[1]} x {m.shape[0]} "
            f"px but its image is {w} x {h} px"
        )
    mask: npt.NDArray[np.bool_] = m
    return mask


def _sibling_depth(image: Path) -> np.ndarray | None:
    for suffix in ("_depth.npy", "_depth.png"):
        d = image.with_name(image.stem + suffix)
        if d.exists():
            return read_depth(d)
    return None


def read_coco_folder(path: str | os.PathLike[str]) -> list[RealImage]:
    """The images of a COCO instances JSON (module docstring), in the JSON's image order."""
    js = _coco_json(Path(path))
    try:
        doc = json.loads(js.read_text())
    except (OSError, ValueError) as e:
        raise IoError(f"'{js}' is not readable JSON: {e}") from e
    if (
        not isinstance(doc, dict)
        or not isinstance(doc.get("images"), list)
        or not isinstance(doc.get("annotations"), list)
    ):
        raise IoError(
            f"'{js}' is in no known annotation format: a COCO instances file has "
            "'images' and 'annotations' lists"
        )
    by_image: dict[Any, list[dict[str, Any]]] = {}
    for ann in doc["annotations"]:
        by_image.setdefault(ann.get("image_id"), []).append(ann)
    images = []
    for entry in doc["images"]:
        try:
            file = js.parent / entry["file_name"]
            image_id = entry["id"]
        except (KeyError, TypeError) as e:
            raise IoError(f"'{js}': an image entry lacks 'id' or 'file_name': {e}") from e
        rgb = read_image(file)
        h, w = rgb.shape[:2]
        if (entry.get("height", h), entry.get("width", w)) != (h, w):
            raise IoError(
                f"'{js}': image {image_id} is {entry.get('width')} x "
                f"{entry.get('height')} px in the JSON, '{file}' is {w} x {h} px"
            )
        source = f"'{js}' image {image_id} ('{entry['file_name']}')"
        anns = by_image.get(image_id, [])
        masks = [_ann_mask(a, h, w, source) for a in anns if not a.get("iscrowd")]
        crowds = [_ann_mask(a, h, w, source) for a in anns if a.get("iscrowd")]
        stack = np.stack(masks) if masks else np.zeros((0, h, w), bool)
        crowd = np.logical_or.reduce(crowds) if crowds else None
        img = RealImage(str(entry["file_name"]), rgb, _sibling_depth(file), stack, crowd=crowd)
        img.check(source)
        images.append(img)
    if not images:
        raise IoError(f"'{js}' lists no images")
    return images


def read_real_set(path: str | os.PathLike[str], fmt: str = "auto") -> list[RealImage]:
    """The labelled photographs at ``path``: ``fmt`` one of :data:`REAL_FORMATS` or ``"auto"``
    (:func:`detect_real_format`)."""
    if fmt == "auto":
        fmt = detect_real_format(path)
    if fmt == "metagraspnet":
        return read_mgn_real(path)
    if fmt == "coco":
        return read_coco_folder(path)
    raise IoError(f"unknown real-set format {fmt!r}; known: auto, {', '.join(REAL_FORMATS)}")
