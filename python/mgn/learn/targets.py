"""Training targets of the baselines, as numpy arrays (no PyTorch here).

Per view of a dataset the network learns four maps, all at the network's resolution:

- **foreground**: the union of the visible object masks (``instances > 0``);
- **core**: on each object's pixels, the Euclidean distance to the nearest pixel that is not
  the object's (px), divided by the largest such distance on the object: 1 on the object's
  medial axis, small at its outline, 0 on the background. The parts of ``core > 0.5`` are well
  apart even where objects touch, and seed the instances (:mod:`mgn.learn.instances`);
- **hidden** (amodal models only): pixels where some object lies behind the visible surface,
  the union over objects of ``amodal mask and not visible mask``;
- **suction**: per-pixel suction quality in [0, 1] from the scene's suction grasps. Each grasp's
  contact point (camera frame) is projected into the image with the view's intrinsics (lens
  distortion included); the pixels within ``radius_m`` of it (a disc of ``fx * radius_m / z``
  px, ``z`` the contact's depth) that show the grasp's object get the grasp's score (the largest
  score where discs overlap). A weight map says which pixels are known: 1 on the discs and on
  the background (quality 0), 0 on object pixels no grasp label covers.

The same input normalisation is used for training and prediction (:func:`network_input`):
RGB as [0, 1] floats, depth as ``(depth - median) / DEPTH_SCALE_M`` clipped to
[-DEPTH_CLIP, DEPTH_CLIP], 0 where the sensor has no value; the height above the fitted floor
plane (:mod:`mgn.learn.floor`) as ``height / HEIGHT_SCALE_M`` with the height clipped to
:data:`HEIGHT_RANGE_M`, 0 (the floor) where the sensor has no value. Models with
``ModelConfig.rgb_norm="image"`` then see each RGB channel standardised over its image
(:func:`normalize_rgb`, after the training's augmentation), so that a photograph several times
darker or of another white balance than the training views gives the same network input.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from PIL import Image

from mgn.errors import InvalidArgumentError
from mgn.learn.floor import FloorPlane, fit_floor, floor_footprint, height_above_floor
from mgn.scene.cameras import Intrinsics
from mgn.scene.lens import distort_normalized

__all__ = [
    "DEPTH_CLIP",
    "DEPTH_SCALE_M",
    "HEIGHT_RANGE_M",
    "HEIGHT_SCALE_M",
    "MODALITIES",
    "RGB_NORMS",
    "RGB_NORM_MIN_STD",
    "core_target",
    "depth_channel",
    "height_channel",
    "hidden_target",
    "input_channels",
    "model_input",
    "network_input",
    "network_shape",
    "normalize_rgb",
    "project_points",
    "resize_nearest",
    "resize_rgb",
    "suction_target",
    "uses_depth",
    "uses_rgb",
]

#: Input settings: RGB (3 channels), depth (1), both (4), the height above the fitted floor
#: plane (1) or RGB and that height (4).
MODALITIES = ("rgb", "depth", "rgbd", "height", "rgb-height")
_CHANNELS = {"rgb": 3, "depth": 1, "rgbd": 4, "height": 1, "rgb-height": 4}
#: Depth normalisation: metres per unit of the depth channel.
DEPTH_SCALE_M = 0.1
#: Depth channel range after normalisation (units of DEPTH_SCALE_M).
DEPTH_CLIP = 5.0
#: Heights above the floor the height channel distinguishes, m (lower and higher are clipped:
#: the floor's noise below, the bin's walls and rim above).
HEIGHT_RANGE_M = (-0.05, 0.3)
#: Height normalisation: metres per unit of the height channel.
HEIGHT_SCALE_M = 0.1
#: Per-image normalisations of the RGB channels (:func:`normalize_rgb`): ``none`` (RGB in
#: [0, 1] as read) or ``image`` (each channel standardised over its image).
RGB_NORMS = ("none", "image")
#: Smallest standard deviation (of RGB in [0, 1]) the ``image`` normalisation divides by, so
#: that a nearly uniform channel is not blown up into noise.
RGB_NORM_MIN_STD = 0.02


def input_channels(modality: str) -> int:
    """Number of input channels of a modality (``rgb`` 3, ``depth`` 1, ``rgbd`` 4, ``height``
    1, ``rgb-height`` 4)."""
    if modality not in MODALITIES:
        raise InvalidArgumentError(f"modality must be one of {MODALITIES}, got {modality!r}")
    return _CHANNELS[modality]


def uses_rgb(modality: str) -> bool:
    """Whether a modality's input has the RGB channels (first)."""
    input_channels(modality)
    return modality in ("rgb", "rgbd", "rgb-height")


def uses_depth(modality: str) -> bool:
    """Whether a modality's input is computed from a depth image (depth or height channel)."""
    input_channels(modality)
    return modality != "rgb"


def network_shape(height: int, width: int, image_size: int) -> tuple[int, int]:
    """(H', W') the network sees for an image of (height, width): the longer side scaled to
    ``image_size`` px, each side rounded to a multiple of 16 (at least 16)."""
    if image_size < 16:
        raise InvalidArgumentError(f"image_size must be >= 16 px, got {image_size}")
    scale = image_size / max(height, width)
    return (max(16, round(height * scale / 16) * 16), max(16, round(width * scale / 16) * 16))


def resize_nearest(a: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Nearest-neighbour resize of the first two axes of ``a`` to ``shape`` (pixel centres
    mapped onto pixel centres)."""
    h, w = a.shape[:2]
    rows = np.minimum(((np.arange(shape[0]) + 0.5) * h / shape[0]).astype(np.int64), h - 1)
    cols = np.minimum(((np.arange(shape[1]) + 0.5) * w / shape[1]).astype(np.int64), w - 1)
    return np.asarray(a[rows][:, cols])


def resize_rgb(rgb: npt.NDArray[np.uint8], shape: tuple[int, int]) -> npt.NDArray[np.uint8]:
    """Bilinear (area-filtered when shrinking) resize of an (H, W, 3) uint8 image (Pillow)."""
    if rgb.shape[:2] == shape:
        return rgb
    im = Image.fromarray(np.ascontiguousarray(rgb))
    return np.asarray(im.resize((shape[1], shape[0]), Image.Resampling.BILINEAR))


def depth_channel(depth_m: np.ndarray) -> npt.NDArray[np.float32]:
    """The normalised depth channel of an (H, W) depth in metres (NaN or <= 0: no value)."""
    d = np.asarray(depth_m, np.float64)
    valid = np.isfinite(d) & (d > 0)
    out = np.zeros(d.shape, np.float32)
    if valid.any():
        med = float(np.median(d[valid]))
        out[valid] = np.clip((d[valid] - med) / DEPTH_SCALE_M, -DEPTH_CLIP, DEPTH_CLIP)
    return out


def height_channel(
    depth_m: np.ndarray,
    intrinsics: Intrinsics | None = None,
    *,
    footprint: bool = False,
    floor: FloorPlane | None = None,
    inside: np.ndarray | None = None,
    name: str = "image",
) -> npt.NDArray[np.float32]:
    """The normalised height channel of an (H, W) depth in metres (NaN or <= 0: no value) at
    its own resolution: the height above the floor plane -- ``floor`` when given (a synthetic
    view's own, :func:`mgn.learn.floor.scene_floor`), else the one fitted to the depth
    (:func:`mgn.learn.floor.fit_floor`); ``intrinsics`` of the depth image, or a nominal
    pinhole when None -- clipped to :data:`HEIGHT_RANGE_M`, divided by
    :data:`HEIGHT_SCALE_M`; 0 where there is no value and, with ``footprint``, outside the
    floor's footprint: ``inside`` ((H, W) bool) when given (a synthetic view's bin interior,
    :func:`mgn.learn.floor.bin_interior`), else :func:`mgn.learn.floor.floor_footprint`."""
    plane = floor if floor is not None else fit_floor(depth_m, intrinsics, name=name)
    h = np.nan_to_num(height_above_floor(depth_m, intrinsics, floor=plane, name=name), nan=0.0)
    if footprint:
        if inside is None:
            inside = floor_footprint(depth_m, intrinsics, floor=plane, name=name)
        elif inside.shape != h.shape:
            raise InvalidArgumentError(
                f"{name}: the footprint is {inside.shape} but the depth is {h.shape}"
            )
        h[~np.asarray(inside, bool)] = 0.0
    lo, hi = HEIGHT_RANGE_M
    return np.asarray((np.clip(h, lo, hi) / np.float32(HEIGHT_SCALE_M)).astype(np.float32))


def network_input(
    rgb: npt.NDArray[np.uint8] | None,
    depth_m: np.ndarray | None,
    modality: str,
    shape: tuple[int, int],
    *,
    name: str = "image",
    intrinsics: Intrinsics | None = None,
    floor_footprint: bool = False,
    floor: FloorPlane | None = None,
    inside: np.ndarray | None = None,
) -> npt.NDArray[np.float32]:
    """(C, H', W') float32 network input of one image at ``shape``. ``name`` (a file or view)
    is named in the error when the modality needs an array that is missing or mis-sized.
    ``intrinsics`` (of the depth image) serve the height modalities' floor fit; without them a
    nominal pinhole is assumed (:func:`mgn.learn.floor.nominal_intrinsics`); with
    ``floor_footprint`` the height is 0 outside the floor's footprint; ``floor`` and ``inside``
    replace the fitted plane and footprint where the scene's own are known
    (:func:`height_channel`)."""
    input_channels(modality)
    planes: list[np.ndarray] = []
    if uses_rgb(modality):
        if rgb is None:
            raise InvalidArgumentError(f"{name}: the model's input is {modality}, but no RGB")
        rgb = np.asarray(rgb)
        if rgb.ndim != 3 or rgb.shape[2] != 3:
            raise InvalidArgumentError(f"{name}: RGB must be (H, W, 3), got {rgb.shape}")
        small = resize_rgb(rgb.astype(np.uint8), shape).astype(np.float32) / np.float32(255.0)
        planes.extend(np.moveaxis(small, 2, 0))
    if uses_depth(modality):
        if depth_m is None:
            raise InvalidArgumentError(
                f"{name}: the model's input is {modality}, but no depth was given"
            )
        depth_m = np.asarray(depth_m)
        if rgb is not None and depth_m.shape != rgb.shape[:2]:
            raise InvalidArgumentError(
                f"{name}: depth is {depth_m.shape[1]} x {depth_m.shape[0]} px but the image is "
                f"{rgb.shape[1]} x {rgb.shape[0]} px; they must match"
            )
        if modality in ("height", "rgb-height"):
            hc = height_channel(
                depth_m,
                intrinsics,
                footprint=floor_footprint,
                floor=floor,
                inside=inside,
                name=name,
            )
            planes.append(resize_nearest(hc, shape))
        else:
            planes.append(depth_channel(resize_nearest(depth_m, shape)))
    return np.stack(planes).astype(np.float32)


def normalize_rgb(x: np.ndarray, mode: str) -> npt.NDArray[np.float32]:
    """The RGB channels ``x`` (3, H, W) or (N, 3, H, W), values in [0, 1], normalised by
    ``mode`` (:data:`RGB_NORMS`): ``none`` returns them unchanged; ``image`` maps each channel
    of each image to ``(x - mean) / max(std, RGB_NORM_MIN_STD)``, mean and standard deviation
    over the image's pixels, so that an image times any gain ``a`` (with ``a * std >=
    RGB_NORM_MIN_STD``) plus any offset per channel, unclipped, gives the same result."""
    if mode not in RGB_NORMS:
        raise InvalidArgumentError(f"rgb_norm must be one of {RGB_NORMS}, got {mode!r}")
    a = np.asarray(x, np.float32)
    if a.ndim not in (3, 4) or a.shape[-3] != 3 or a.shape[-1] < 1 or a.shape[-2] < 1:
        raise InvalidArgumentError(
            f"normalize_rgb: expected RGB channels (3, H, W) or (N, 3, H, W), got {a.shape}"
        )
    if mode == "none":
        return a
    d = a.astype(np.float64)
    mean = d.mean(axis=(-2, -1), keepdims=True)
    std = np.maximum(d.std(axis=(-2, -1), keepdims=True), RGB_NORM_MIN_STD)
    return np.asarray(((d - mean) / std).astype(np.float32))


def model_input(x: np.ndarray, modality: str, rgb_norm: str) -> npt.NDArray[np.float32]:
    """What the network is given for inputs ``x`` (C, H, W) or (N, C, H, W) of
    :func:`network_input` (after any augmentation): the RGB channels of ``rgb``, ``rgbd`` and
    ``rgb-height`` inputs normalised by ``rgb_norm`` (:func:`normalize_rgb`), the depth or
    height channel unchanged."""
    a = np.asarray(x, np.float32)
    c = input_channels(modality)
    if a.ndim not in (3, 4) or a.shape[-3] != c:
        raise InvalidArgumentError(
            f"model input: a {modality} input has {c} channel(s), (C, H, W) or (N, C, H, W); "
            f"got {a.shape}"
        )
    if not uses_rgb(modality) or rgb_norm == "none":
        if rgb_norm not in RGB_NORMS:
            raise InvalidArgumentError(f"rgb_norm must be one of {RGB_NORMS}, got {rgb_norm!r}")
        return a
    rgb = normalize_rgb(a[..., :3, :, :], rgb_norm)
    return np.ascontiguousarray(np.concatenate([rgb, a[..., 3:, :, :]], axis=-3))


def core_target(instances: np.ndarray) -> npt.NDArray[np.float32]:
    """(H, W) float32 normalised inner distance of every object pixel (module docstring); the
    image border counts as the object's (an object cut by the border is not thinned there)."""
    from scipy import ndimage

    ids = np.asarray(instances)
    out = np.zeros(ids.shape, np.float32)
    for k, box in enumerate(ndimage.find_objects(ids.astype(np.int64)), start=1):
        if box is None:
            continue
        rows, cols = box
        r0, r1 = max(rows.start - 1, 0), min(rows.stop + 1, ids.shape[0])
        c0, c1 = max(cols.start - 1, 0), min(cols.stop + 1, ids.shape[1])
        mask = ids[r0:r1, c0:c1] == k
        d = ndimage.distance_transform_edt(mask)
        top = float(d.max())
        if top > 0:
            block = out[r0:r1, c0:c1]
            block[mask] = (d[mask] / top).astype(np.float32)
    return out


def hidden_target(instances: np.ndarray, amodal: np.ndarray) -> npt.NDArray[np.bool_]:
    """(H, W) bool: pixels where an object's amodal mask (``amodal[i]`` is instance ``i + 1``)
    extends behind something else."""
    ids = np.asarray(instances)
    am = np.asarray(amodal, bool)
    if am.ndim != 3 or am.shape[1:] != ids.shape:
        raise InvalidArgumentError(
            f"amodal masks must be (N, {ids.shape[0]}, {ids.shape[1]}), got {am.shape}"
        )
    out = np.zeros(ids.shape, bool)
    for i in range(am.shape[0]):
        out |= am[i] & (ids != i + 1)
    return out


def project_points(
    points_c: np.ndarray, intrinsics: Intrinsics
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.bool_]]:
    """Continuous pixel coordinates (u, v) of camera-frame points (m, OpenCV axes; pixel ``(r,
    c)`` covers ``c <= u < c + 1``, ``r <= v < r + 1``), with the lens distortion of
    ``intrinsics``, and which points lie in front of the camera and inside the image."""
    p = np.asarray(points_c, np.float64).reshape(-1, 3)
    z = p[:, 2]
    front = z > 1e-9
    zs = np.where(front, z, 1.0)
    x, y = p[:, 0] / zs, p[:, 1] / zs
    if intrinsics.distortion:
        x, y = distort_normalized(x, y, intrinsics.distortion)
    u = intrinsics.fx * x + intrinsics.cx
    v = intrinsics.fy * y + intrinsics.cy
    inside = front & (u >= 0) & (u < intrinsics.width) & (v >= 0) & (v < intrinsics.height)
    return u, v, inside


def suction_target(
    contacts_c: np.ndarray,
    scores: np.ndarray,
    instance_ids: np.ndarray,
    instances: np.ndarray,
    intrinsics: Intrinsics,
    *,
    radius_m: float = 0.01,
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
    """(quality, weight), both (H, W) float32, of the suction grasps with contact points
    ``contacts_c`` (K, 3) m in the camera frame, scores in [0, 1] and the instance id (1..N) of
    each grasp's object, on the view's ``instances`` image (module docstring)."""
    ids = np.asarray(instances)
    h, w = ids.shape
    if (intrinsics.width, intrinsics.height) != (w, h):
        raise InvalidArgumentError(
            f"intrinsics are {intrinsics.width} x {intrinsics.height} px, instances {w} x {h} px"
        )
    if radius_m <= 0:
        raise InvalidArgumentError(f"suction radius must be > 0 m, got {radius_m}")
    pts = np.asarray(contacts_c, np.float64).reshape(-1, 3)
    sc = np.asarray(scores, np.float64).reshape(-1)
    oid = np.asarray(instance_ids).reshape(-1).astype(np.int64)
    if not len(pts) == len(sc) == len(oid):
        raise InvalidArgumentError(
            f"suction target: {len(pts)} contacts, {len(sc)} scores, {len(oid)} instance ids"
        )
    quality = np.zeros((h, w), np.float32)
    covered = np.zeros((h, w), bool)
    u, v, inside = project_points(pts, intrinsics)
    for k in np.flatnonzero(inside & np.isfinite(sc)):
        r = intrinsics.fx * radius_m / pts[k, 2]
        c0, c1 = max(0, int(np.floor(u[k] - r))), min(w, int(np.ceil(u[k] + r)) + 1)
        r0, r1 = max(0, int(np.floor(v[k] - r))), min(h, int(np.ceil(v[k] + r)) + 1)
        cy = np.arange(r0, r1)[:, None] + 0.5
        cx = np.arange(c0, c1)[None, :] + 0.5
        disc = ((cx - u[k]) ** 2 + (cy - v[k]) ** 2 <= r * r) & (ids[r0:r1, c0:c1] == oid[k])
        block = quality[r0:r1, c0:c1]
        np.maximum(block, np.where(disc, np.float32(np.clip(sc[k], 0.0, 1.0)), 0), out=block)
        covered[r0:r1, c0:c1] |= disc
    weight = (covered | (ids == 0)).astype(np.float32)
    return quality, weight
