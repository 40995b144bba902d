"""Byte-reproducible files: the same arrays always give the same bytes.

Two writers mgn uses store the wall-clock time by default:

- ``np.savez_compressed`` stamps every zip entry with the current date and time;
- HDF5 stamps every object header with its creation/modification times unless told not to
  (h5py: ``track_times=False`` for datasets; groups follow the file's object-creation policy).

A dataset is only checkable by checksums (and comparable between an interrupted and an
uninterrupted run, or a 1-worker and an N-worker run) if neither happens. Use :func:`npz_bytes`
for ``.npz`` files and :func:`h5_create_dataset` / :func:`h5_create_group` (or
:data:`H5_DATASET_KWARGS`) for HDF5 files.
"""

from __future__ import annotations

import io
import lzma
import struct
import zipfile
from collections.abc import Collection, Mapping
from typing import Any

import h5py
import numpy as np
import numpy.typing as npt

from mgn.base.compress import ZipDeflate, ZipRunDeflate
from mgn.errors import InvalidArgumentError

__all__ = [
    "H5_DATASET_KWARGS",
    "NPZ_DATE_TIME",
    "NPZ_LZMA_FILTER",
    "h5_create_dataset",
    "h5_create_group",
    "npz_bytes",
]

#: Date stamped on every npz zip entry (the earliest date the zip format can store).
NPZ_DATE_TIME: tuple[int, int, int, int, int, int] = (1980, 1, 1, 0, 0, 0)
#: Keyword arguments of ``h5py.Group.create_dataset`` that keep HDF5 files reproducible.
H5_DATASET_KWARGS: dict[str, Any] = {"track_times": False}


#: LZMA1 settings of the npz entries :func:`npz_bytes` writes with LZMA: the fastest preset (its
#: match finder costs least on noise), no literal context bits and two position bits (values of
#: 4 bytes), a 1 MiB dictionary. The entry's header holds the properties, so any LZMA zip reader
#: decodes it.
NPZ_LZMA_FILTER: dict[str, Any] = {
    "id": lzma.FILTER_LZMA1,
    "preset": 0,
    "lc": 0,
    "lp": 2,
    "pb": 2,
    "dict_size": 1 << 20,
}


class _NpzLzma:
    """The compressor of one LZMA zip entry (APPNOTE 5.8.8: version 9.4, the properties' size,
    the properties, then raw LZMA1 data with an end marker), with :data:`NPZ_LZMA_FILTER`."""

    def __init__(self) -> None:
        props = lzma._encode_filter_properties(NPZ_LZMA_FILTER)  # type: ignore[attr-defined]
        self._header: bytes | None = struct.pack("<BBH", 9, 4, len(props)) + props
        self._comp = lzma.LZMACompressor(lzma.FORMAT_RAW, filters=[NPZ_LZMA_FILTER])

    def _head(self) -> bytes:
        head, self._header = self._header or b"", None
        return head

    def compress(self, data: bytes) -> bytes:
        return self._head() + self._comp.compress(data)

    def flush(self) -> bytes:
        return self._head() + self._comp.flush()


def npz_bytes(
    *,
    compress: bool = True,
    level: int = 1,
    levels: Mapping[str, int] | None = None,
    lzma_entries: Collection[str] = (),
    zlib_levels: Mapping[str, int] | None = None,
    **arrays: npt.ArrayLike,
) -> bytes:
    """The bytes of an ``.npz`` file holding ``arrays`` (readable by ``np.load``), reproducible.

    Like ``np.savez_compressed`` (``compress=True``) or ``np.savez``, but every zip entry carries
    the fixed date :data:`NPZ_DATE_TIME` and fixed permissions, and entries are in the order the
    keywords are given. Object arrays are refused (no pickles). Compressed entries are plain
    deflate (zip method 8) made by libdeflate (:class:`mgn.base.compress.ZipDeflate`) at
    ``level`` (1..12; the scene writer's 6 takes about the time of zlib's level 1 and gives
    depth images ~16 % and masks ~3x smaller); ``levels`` overrides it per array name. Arrays
    named in ``lzma_entries`` are zip entries of method 14 (LZMA, zip format 6.3) with the
    literal and position bits set for 4-byte values (:data:`NPZ_LZMA_FILTER`): a noisy float32
    image in ~0.6x the bytes of deflate, ~4x the CPU. ``np.load`` (``zipfile``) reads every
    entry; the LZMA ones need a zip reader with LZMA (Python's has it). Arrays named in
    ``zlib_levels`` are deflated by zlib at the given level instead of libdeflate (images of long
    runs, which zlib's level 1 keeps fast to inflate: :class:`mgn.base.compress.ZipDeflate`).

    Raises:
        ValueError: an array of dtype object.
    """
    method = zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED
    out = io.BytesIO()
    with zipfile.ZipFile(out, mode="w", compression=method, allowZip64=True) as zf:
        for name, value in arrays.items():
            array = np.asanyarray(value)
            if array.dtype.hasobject:
                raise InvalidArgumentError(
                    f"npz_bytes: array '{name}' has dtype object; expected numbers"
                )
            info = zipfile.ZipInfo(f"{name}.npy", date_time=NPZ_DATE_TIME)
            info.compress_type = zipfile.ZIP_LZMA if name in lzma_entries else method
            lvl = (levels or {}).get(name, level)
            try:
                info.compress_level = min(lvl, 9)  # type: ignore[attr-defined]  # Python >= 3.13
            except AttributeError:
                info._compresslevel = min(lvl, 9)  # type: ignore[attr-defined]  # Python <= 3.12
            info.external_attr = 0o644 << 16  # rw-r--r--, as numpy's own writer
            with zf.open(info, mode="w", force_zip64=True) as fh:
                if name in lzma_entries and hasattr(fh, "_compressor"):
                    # zipfile's own LZMA compressor has fixed settings: ours, same stream layout.
                    fh._compressor = _NpzLzma()
                elif compress and name in (zlib_levels or {}) and hasattr(fh, "_compressor"):
                    fh._compressor = ZipRunDeflate((zlib_levels or {})[name])
                elif compress and hasattr(fh, "_compressor"):
                    # zipfile's raw-deflate compressor (zlib, wbits -15) -> libdeflate's.
                    fh._compressor = ZipDeflate(lvl)
                # The .npy bytes (what np.lib.format.write_array writes for a C-order array)
                # in two writes, the header and the array's own buffer, not copied.
                array = np.ascontiguousarray(array)
                head = io.BytesIO()
                np.lib.format.write_array_header_1_0(
                    head, np.lib.format.header_data_from_array_1_0(array)
                )
                fh.write(head.getvalue())
                if array.size:
                    fh.write(array.reshape(-1).view(np.uint8).data)
    return out.getvalue()


def h5_create_dataset(group: Any, name: str, data: npt.ArrayLike, **kwargs: Any) -> Any:
    """``group.create_dataset(name, data=data, **kwargs)`` without HDF5 timestamps."""
    return group.create_dataset(name, data=data, **(H5_DATASET_KWARGS | kwargs))


def h5_create_group(parent: Any, name: str) -> Any:
    """``parent.create_group(name)`` without HDF5 timestamps on the group's object header.

    h5py has no ``track_times`` argument for groups, so the group is created through the
    low-level API with a group-creation property list that disables them. Intermediate groups of
    a path ``a/b/c`` are created the same way.
    """

    gcpl = h5py.h5p.create(h5py.h5p.GROUP_CREATE)
    gcpl.set_obj_track_times(False)
    lcpl = h5py.h5p.create(h5py.h5p.LINK_CREATE)
    lcpl.set_create_intermediate_group(True)
    gid = h5py.h5g.create(parent.id, name.encode("utf-8"), lcpl=lcpl, gcpl=gcpl)
    return h5py.Group(gid)
