"""``mgn predict``: instance masks and suction maps of a trained model on any images.

:class:`Predictor` loads a ``model.pt`` (:mod:`mgn.learn.checkpoint`) and runs it on one image
at a time: the image (and depth, for the depth, RGB-D and height models; the height models fit
the floor plane at the depth's own resolution, :mod:`mgn.learn.floor`) is resized to the network's
resolution (:func:`mgn.learn.targets.network_input`), the output maps are turned into
instances there (:func:`mgn.learn.instances.instances_from_maps`) and brought back to the
image's size (instance ids nearest-neighbour, probabilities bilinear).

Test-time augmentation (``tta``, :data:`TTA_MODES`): the network also sees mirrored and turned
copies of the image, each output is turned back, and the probability maps (after the sigmoid)
are averaged before the instances are formed. It costs one forward pass per copy:

- ``none`` (the default): the image as it is, 1 pass;
- ``flips``: the image, its left-right mirror and its upside-down mirror, 3 passes;
- ``flips+rot180``: those and the 180-degree rotation, 4 passes;
- ``dihedral``: the four 90-degree rotations, each also mirrored left-right, 8 passes.

:func:`predict_files` does this for image files and writes, per image ``<stem>``:
``<stem>_instances.png`` (16-bit, 0 background, instance ``i`` has id ``i + 1``),
``<stem>_suction.png`` (8-bit, suction quality x 255), ``<stem>_overlay.png`` (the picture
of :func:`mgn.learn.pictures.overlay`), plus one ``predictions.json`` for all images (the
model file, its config and the test-time augmentation ``tta``; per image: size, instances
with score, box [x, y, w, h] px, area px and COCO RLE of the visible mask, and of the amodal
mask for amodal models; the suction peaks [u, v, quality], u, v pixel centres).

Depth files (:func:`mgn.io.real.read_depth`): ``.npy`` (float, metres), ``.npz`` with a
``depth`` array in centimetres (MetaGraspNet's ``{v}.npz``), or a 16-bit PNG in millimetres; 0
or NaN is no value.
"""

from __future__ import annotations

import copy
import io
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from PIL import Image
from pycocotools import mask as mask_utils
from tqdm import tqdm

from mgn.base.atomic import atomic_write_bytes, atomic_write_text
from mgn.errors import InvalidArgumentError
from mgn.io.real import IMAGE_SUFFIXES, read_depth, read_image
from mgn.learn.backend import choose_device, require_torch
from mgn.learn.checkpoint import MODEL_FORMAT, read_torch_file
from mgn.learn.config import ModelConfig
from mgn.learn.instances import InstanceMaps, instances_from_maps
from mgn.learn.model import build_model
from mgn.learn.pictures import overlay
from mgn.learn.targets import (
    model_input,
    network_input,
    network_shape,
    resize_nearest,
    uses_depth,
    uses_rgb,
)
from mgn.scene.cameras import Intrinsics

__all__ = [
    "DEFAULT_TTA",
    "IMAGE_SUFFIXES",
    "TTA_MODES",
    "Prediction",
    "Predictor",
    "as_predictor",
    "check_tta",
    "predict_files",
    "read_depth",
    "read_image",
    "suction_peaks",
]


#: Test-time augmentations (module docstring): for each mode, its copies of the image as
#: (quarter turns counter-clockwise, then a left-right mirror); ``len`` is the forward passes.
TTA_MODES: dict[str, tuple[tuple[int, bool], ...]] = {
    "none": ((0, False),),
    "flips": ((0, False), (0, True), (2, True)),
    "flips+rot180": ((0, False), (0, True), (2, True), (2, False)),
    "dihedral": tuple((k, m) for k in range(4) for m in (False, True)),
}
#: The test-time augmentation of :class:`Predictor`, ``mgn predict`` and ``mgn eval real``.
DEFAULT_TTA = "none"


def check_tta(tta: str) -> str:
    """``tta`` if it is one of :data:`TTA_MODES`; else InvalidArgumentError naming ``tta``."""
    if not isinstance(tta, str) or tta not in TTA_MODES:
        raise InvalidArgumentError(
            f"tta (test-time augmentation) must be one of {tuple(TTA_MODES)}, got {tta!r}"
        )
    return tta


def _turned(a: np.ndarray, k: int, mirror: bool) -> np.ndarray:
    """(C, H, W) ``a`` turned ``k`` quarter turns counter-clockwise, then mirrored left-right."""
    b = np.rot90(a, k, axes=(1, 2))
    return np.ascontiguousarray(b[:, :, ::-1] if mirror else b)


def _unturned(a: np.ndarray, k: int, mirror: bool) -> np.ndarray:
    """The inverse of :func:`_turned`."""
    b = a[:, :, ::-1] if mirror else a
    return np.rot90(b, -k, axes=(1, 2))


def suction_peaks(
    quality: np.ndarray, k: int, *, radius: float, min_quality: float = 0.0
) -> npt.NDArray[np.float64]:
    """(<= k, 3) [u, v, quality] of the k best pixels of a quality map, each at least ``radius``
    px from the ones before (greedy non-maximum suppression; ties go to the first pixel in row
    order); u, v are pixel centres (column + 0.5, row + 0.5). Stops below ``min_quality``."""
    q = np.array(quality, np.float64)
    if q.ndim != 2:
        raise InvalidArgumentError(f"quality map must be (H, W), got {q.shape}")
    q[~np.isfinite(q)] = -np.inf
    h, w = q.shape
    rows, cols = np.arange(h)[:, None], np.arange(w)[None, :]
    out = []
    for _ in range(max(0, k)):
        i = int(np.argmax(q))
        r, c = divmod(i, w)
        if not q[r, c] > -np.inf or q[r, c] < min_quality:
            break
        out.append((c + 0.5, r + 0.5, float(quality[r, c])))
        q[(rows - r) ** 2 + (cols - c) ** 2 < radius * radius] = -np.inf
    return np.array(out, np.float64).reshape(-1, 3)


def _resize_float(a: np.ndarray, shape: tuple[int, int]) -> npt.NDArray[np.float32]:
    if a.shape == shape:
        return a.astype(np.float32)
    im = Image.fromarray(a.astype(np.float32), mode="F")
    return np.asarray(im.resize((shape[1], shape[0]), Image.Resampling.BILINEAR), np.float32)


@dataclass(frozen=True)
class Prediction:
    """A model's output for one image, at the image's size.

    Attributes:
        instances: the instances (:class:`~mgn.learn.instances.InstanceMaps`).
        foreground: (H, W) float32 object probability.
        suction: (H, W) float32 suction quality in [0, 1].
    """

    instances: InstanceMaps
    foreground: npt.NDArray[np.float32]
    suction: npt.NDArray[np.float32]

    def suction_points(self, k: int = 10, radius: float | None = None) -> np.ndarray:
        """The k best suction points [u, v, quality] (:func:`suction_peaks`; default radius
        2 % of the image diagonal), on predicted objects only."""
        h, w = self.suction.shape
        r = 0.02 * float(np.hypot(h, w)) if radius is None else radius
        q = np.where(self.instances.labels > 0, self.suction, -np.inf)
        return suction_peaks(q, k, radius=r)


class Predictor:
    """A loaded model (``model.pt``) ready to predict; ``device`` as in
    :func:`mgn.learn.backend.choose_device`, ``num_threads`` torch CPU threads (0 = default),
    ``tta`` the test-time augmentation (:data:`TTA_MODES`, default :data:`DEFAULT_TTA`; each
    image costs ``len(TTA_MODES[tta])`` forward passes)."""

    def __init__(
        self,
        model_path: str | os.PathLike[str],
        *,
        device: str = "auto",
        num_threads: int = 0,
        tta: str = DEFAULT_TTA,
    ) -> None:
        self.tta = check_tta(tta)
        torch = require_torch()
        if num_threads:
            torch.set_num_threads(num_threads)
        self.path = Path(model_path)
        data = read_torch_file(self.path, MODEL_FORMAT)
        self.config = ModelConfig.from_saved(data["model_config"])
        self.training: dict[str, Any] = data.get("training", {})
        self.device = choose_device(device)
        self.model = build_model(self.config)
        self.model.load_state_dict(data["state_dict"])
        self.model.to(self.device).eval()

    def with_tta(self, tta: str) -> Predictor:
        """This predictor (the same loaded network) with test-time augmentation ``tta``."""
        other = copy.copy(self)
        other.tta = check_tta(tta)
        return other

    def maps(
        self,
        rgb: np.ndarray | None,
        depth: np.ndarray | None,
        *,
        name: str = "image",
        intrinsics: Intrinsics | None = None,
    ) -> tuple[npt.NDArray[np.float32], tuple[int, int]]:
        """(T, H', W') output probabilities at the network's resolution, and the image size;
        with test-time augmentation (:attr:`tta`) the mean of the probabilities of the image's
        copies, each turned back. ``intrinsics`` of the depth image serve the height models'
        floor fit (a nominal pinhole when None)."""
        ref = rgb if rgb is not None else depth
        if ref is None:
            raise InvalidArgumentError(f"{name}: no image given")
        h, w = np.asarray(ref).shape[:2]
        shape = network_shape(h, w, self.config.image_size)
        x = model_input(
            network_input(
                rgb,
                depth,
                self.config.modality,
                shape,
                name=name,
                intrinsics=intrinsics,
                floor_footprint=self.config.floor_footprint,
            ),
            self.config.modality,
            self.config.rgb_norm,
        )
        if self.tta == "none":
            return self._probs(x), (h, w)
        total = np.zeros((len(self.config.outputs), *x.shape[1:]), np.float64)
        copies = TTA_MODES[self.tta]
        for k, mirror in copies:
            total += _unturned(self._probs(_turned(x, k, mirror)), k, mirror)
        return (total / len(copies)).astype(np.float32), (h, w)

    def _probs(self, x: np.ndarray) -> npt.NDArray[np.float32]:
        """(T, H', W') sigmoid of the network's logits for one (C, H', W') input."""
        torch = require_torch()
        with torch.no_grad():
            logits = self.model(torch.from_numpy(x[None]).to(self.device))
            probs: npt.NDArray[np.float32] = torch.sigmoid(logits)[0].cpu().numpy()
        return probs.astype(np.float32)

    def predict(
        self,
        rgb: np.ndarray | None,
        depth: np.ndarray | None = None,
        *,
        name: str = "image",
        threshold: float = 0.5,
        core_threshold: float = 0.4,
        min_area: int = 8,
        intrinsics: Intrinsics | None = None,
    ) -> Prediction:
        """Instances and suction map of one image (RGB (H, W, 3) uint8; depth (H, W) m;
        ``intrinsics`` of the depth image for the height models, else a nominal pinhole)."""
        modality = self.config.modality
        if not uses_rgb(modality):
            rgb_in = None
            if depth is None:
                raise InvalidArgumentError(
                    f"{name}: the model's input is {modality}; give a depth file"
                )
        else:
            rgb_in = rgb
        probs, (h, w) = self.maps(
            rgb_in, depth if uses_depth(modality) else None, name=name, intrinsics=intrinsics
        )
        if not uses_rgb(modality) and rgb is None:
            h, w = np.asarray(depth).shape[:2]
        hidden = probs[3] if self.config.amodal else None
        small = instances_from_maps(
            probs[0],
            probs[1],
            hidden=hidden,
            threshold=threshold,
            core_threshold=core_threshold,
            min_area=min_area,
        )
        labels = resize_nearest(small.labels, (h, w))
        amodal = None
        if small.amodal is not None:
            amodal = (
                np.stack([resize_nearest(m, (h, w)) for m in small.amodal])
                if len(small.amodal)
                else np.zeros((0, h, w), bool)
            )
        inst = InstanceMaps(labels.astype(np.int32), small.scores, amodal)
        return Prediction(inst, _resize_float(probs[0], (h, w)), _resize_float(probs[2], (h, w)))


def as_predictor(
    model: Predictor | str | os.PathLike[str],
    *,
    device: str = "auto",
    num_threads: int = 0,
    tta: str | None = None,
) -> Predictor:
    """``model`` if it is a :class:`Predictor` (with test-time augmentation ``tta`` unless
    None), else the model file loaded (``tta`` None: :data:`DEFAULT_TTA`)."""
    if isinstance(model, Predictor):
        return model if tta is None else model.with_tta(tta)
    return Predictor(
        model, device=device, num_threads=num_threads, tta=DEFAULT_TTA if tta is None else tta
    )


def _rle(mask: np.ndarray) -> dict[str, Any]:
    r = mask_utils.encode(np.asfortranarray(mask.astype(np.uint8)))
    return {"size": [int(s) for s in r["size"]], "counts": r["counts"].decode("ascii")}


def prediction_record(pred: Prediction, image: str, k: int = 10) -> dict[str, Any]:
    """The ``predictions.json`` entry of one image (module docstring)."""
    inst = pred.instances
    h, w = inst.labels.shape
    rows = []
    amodal = inst.masks(amodal=True) if inst.amodal is not None else None
    for i, mask in enumerate(inst.masks()):
        ys, xs = np.nonzero(mask)
        box = (
            [
                int(xs.min()),
                int(ys.min()),
                int(xs.max() - xs.min() + 1),
                int(ys.max() - ys.min() + 1),
            ]
            if len(xs)
            else [0, 0, 0, 0]
        )
        row: dict[str, Any] = {
            "id": i + 1,
            "score": round(float(inst.scores[i]), 6),
            "bbox": box,
            "area": int(mask.sum()),
            "segmentation": _rle(mask),
        }
        if amodal is not None:
            row["amodal_segmentation"] = _rle(amodal[i])
        rows.append(row)
    peaks = pred.suction_points(k)
    return {
        "image": image,
        "width": w,
        "height": h,
        "instances": rows,
        "suction_points": [[round(float(a), 3) for a in p] for p in peaks],
    }


def _png(a: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(a).save(buf, format="PNG")
    return buf.getvalue()


def write_prediction(pred: Prediction, rgb: np.ndarray | None, out: Path, stem: str) -> None:
    """``<stem>_instances.png``, ``<stem>_suction.png`` and ``<stem>_overlay.png`` in ``out``."""
    atomic_write_bytes(out / f"{stem}_instances.png", _png(pred.instances.labels.astype(np.uint16)))
    q = np.clip(np.round(pred.suction * 255.0), 0, 255).astype(np.uint8)
    atomic_write_bytes(out / f"{stem}_suction.png", _png(q))
    atomic_write_bytes(out / f"{stem}_overlay.png", _png(overlay(rgb, pred)))


def predict_files(
    model: Predictor | str | os.PathLike[str],
    images: Sequence[str | os.PathLike[str]],
    out: str | os.PathLike[str],
    *,
    depths: Sequence[str | os.PathLike[str]] | None = None,
    device: str = "auto",
    num_threads: int = 0,
    threshold: float = 0.5,
    core_threshold: float = 0.4,
    num_suction_points: int = 10,
    progress: bool = True,
    tta: str | None = None,
) -> Path:
    """Predict every image file (module docstring); ``depths`` gives one depth file per image
    (needed by the depth, RGB-D and height models); ``tta`` the test-time augmentation
    (:data:`TTA_MODES`; None: the ``Predictor``'s own, or :data:`DEFAULT_TTA` for a model file).
    Returns the path of ``predictions.json``."""
    if not images:
        raise InvalidArgumentError("mgn predict: no images given")
    if depths is not None and len(depths) != len(images):
        raise InvalidArgumentError(
            f"mgn predict: {len(depths)} depth file(s) for {len(images)} image(s); give one each"
        )
    pred_model = as_predictor(model, device=device, num_threads=num_threads, tta=tta)
    if uses_depth(pred_model.config.modality) and depths is None:
        raise InvalidArgumentError(
            f"mgn predict: the model's input is {pred_model.config.modality}"
            "; give --depth with one depth file per image"
        )
    out_dir = Path(out)
    out_dir.mkdir(parents=True, exist_ok=True)
    stems: set[str] = set()
    records = []
    for k, image in enumerate(tqdm(images, desc="predict", unit="img", disable=not progress)):
        p = Path(image)
        rgb = read_image(p)
        depth_file = depths[k] if depths is not None else None
        depth = read_depth(depth_file) if depth_file is not None else None
        if depth is not None and depth.shape != rgb.shape[:2]:
            raise InvalidArgumentError(
                f"'{depth_file}' is {depth.shape[1]} x {depth.shape[0]} px, "
                f"'{p}' {rgb.shape[1]} x {rgb.shape[0]} px; they must match"
            )
        stem = p.stem
        while stem in stems:
            stem = f"{stem}_{k}"
        stems.add(stem)
        pred = pred_model.predict(
            rgb, depth, name=str(p), threshold=threshold, core_threshold=core_threshold
        )
        write_prediction(pred, rgb, out_dir, stem)
        records.append(prediction_record(pred, str(p), num_suction_points) | {"stem": stem})
    doc = {
        "model": os.fspath(pred_model.path),
        "model_config": pred_model.config.to_dict(),
        "tta": pred_model.tta,
        "images": records,
    }
    path = out_dir / "predictions.json"
    atomic_write_text(path, json.dumps(doc, indent=1) + "\n")
    return path
