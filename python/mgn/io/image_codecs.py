"""How the scene writer encodes images into bytes, and how readers decode them.

- PNG (:func:`png_bytes`, :func:`depth_picture_png`): libdeflate at :data:`DEFLATE_LEVEL`, no
  time chunk, so the bytes are reproducible.
- float32 images of ``{v}_mgn.hdf5`` stored as int32 codes that shuffle + deflate compress
  (lossless, every bit restored, NaN included): the differences of the bit patterns along rows
  (:func:`encode_float_image`, :data:`FLOAT_DELTA_ENCODING`) or the zigzag-mapped gradient
  residual (:func:`encode_float_gradient`, :data:`FLOAT_GRADIENT_ENCODING`); [0, 1] images as
  16-bit integers in the archival mode (:data:`UNORM16_ENCODING`, lossy).
- the CoM heat map stored as its bit difference from :func:`com_heatmap_prediction`
  (:func:`com_residual`, :func:`decode_com_residual`, :data:`COM_RESIDUAL_ENCODING`).

The encoding of an image is named by its ``mgn_encoding`` attribute in ``{v}_mgn.hdf5``.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.base.compress import png_encode
from mgn.errors import InvalidArgumentError
from mgn.render.views import depth_picture_indexed

__all__ = [
    "COM_RESIDUAL_ENCODING",
    "DEFLATE_LEVEL",
    "FLOAT_DELTA_ENCODING",
    "FLOAT_GRADIENT_ENCODING",
    "UNORM16_ENCODING",
    "com_heatmap_prediction",
    "com_residual",
    "decode_com_residual",
    "decode_float_gradient",
    "decode_float_image",
    "depth_picture_png",
    "encode_float_gradient",
    "encode_float_image",
    "png_bytes",
]

#: libdeflate level of the deflate streams of the scene writer's images (PNG, HDF5 chunks): on a
#: 1200 x 1200 view of 20 objects it costs less than zlib's level 1 did, for 0.88x the bytes of
#: ``depth_ideal`` and 0.86x the RGB PNG's (docs/decisions/0020-format-libdeflate.md).
DEFLATE_LEVEL = 6

#: Value of the ``mgn_encoding`` attribute of a ``{v}_mgn.hdf5`` float32 image stored as the int32
#: differences of its bit patterns along each row (lossless; smooth images shrink ~30 %).
FLOAT_DELTA_ENCODING = "float32-bits-delta-rows"

#: Archival mode: ``mgn_encoding`` of a [0, 1] image stored as uint16 k, read as float32 k / 65535.
UNORM16_ENCODING = "unorm16"


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


#: ``mgn_encoding`` of a ``com_heatmap`` stored as the int32 differences (modulo 2^32) of its
#: float32 bit patterns from :func:`com_heatmap_prediction`, whose inputs the dataset's
#: attributes hold (``com_parameters``, ``X_WC``, ``K``) with ``depth_ideal`` (m) of the same
#: file and ``instances_objects`` of ``{v}.npz``.
COM_RESIDUAL_ENCODING = "float32-bits-minus-com-prediction"


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


def com_residual(com: npt.ArrayLike, prediction: npt.NDArray[np.float32]) -> npt.NDArray[np.int32]:
    bits = np.ascontiguousarray(com, np.float32).view(np.int32)
    with np.errstate(over="ignore"):
        return bits - prediction.view(np.int32)


def decode_com_residual(
    residual: npt.ArrayLike, prediction: npt.NDArray[np.float32]
) -> npt.NDArray[np.float32]:
    """The heat map of a ``com_heatmap`` stored with :data:`COM_RESIDUAL_ENCODING`."""
    with np.errstate(over="ignore"):
        return (np.asarray(residual, np.int32) + prediction.view(np.int32)).view(np.float32)


def png_bytes(image: npt.ArrayLike, *, level: int = DEFLATE_LEVEL) -> bytes:
    """PNG of an (H, W) or (H, W, 3) uint8 / (H, W) uint16 image (no time chunk: reproducible),
    deflated by libdeflate at ``level`` (1..12; :func:`mgn.base.compress.png_encode`: no row
    filter, which on rendered pictures gives fewer bytes than zlib level 6 with libpng's
    filters, at ~1/4 of its time)."""
    return png_encode(np.asarray(image), level=level)


def depth_picture_png(depth: npt.ArrayLike, *, level: int = DEFLATE_LEVEL) -> bytes:
    """``{v}_depth.png`` of a depth image (m): :func:`mgn.render.views.depth_picture` as a palette
    PNG (every reader converts it to the same RGB; ~half the bytes and faster to write than the
    RGB PNG), deflated by libdeflate at ``level`` (:func:`mgn.base.compress.png_encode`)."""
    index, palette = depth_picture_indexed(depth)
    return png_encode(index, level=level, palette=palette)
