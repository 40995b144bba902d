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
from collections.abc import Collection, Mapping, Sequence
from typing import Any

import deflate
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
    "zip_bytes",
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
    entries = []
    for name, value in arrays.items():
        array = np.asanyarray(value)
        if array.dtype.hasobject:
            raise InvalidArgumentError(
                f"npz_bytes: array '{name}' has dtype object; expected numbers"
            )
        lvl = (levels or {}).get(name, level)
        compressor: Any = None
        method = zipfile.ZIP_STORED
        if name in lzma_entries:
            compressor, method = _NpzLzma(), zipfile.ZIP_LZMA
        elif compress and name in (zlib_levels or {}):
            compressor, method = ZipRunDeflate((zlib_levels or {})[name]), zipfile.ZIP_DEFLATED
        elif compress:
            compressor, method = ZipDeflate(lvl), zipfile.ZIP_DEFLATED
        # The .npy bytes (what np.lib.format.write_array writes for a C-order array): the
        # header and the array's own buffer, not copied.
        # (np.ascontiguousarray would make a 0-d array 1-d.)
        array = array if array.flags.c_contiguous else np.ascontiguousarray(array)
        head = io.BytesIO()
        np.lib.format.write_array_header_1_0(head, np.lib.format.header_data_from_array_1_0(array))
        parts: list[bytes | memoryview] = [head.getvalue()]
        if array.size:
            parts.append(array.reshape(-1).view(np.uint8).data)
        entries.append((f"{name}.npy", method, compressor, parts))
    return zip_bytes(entries)


#: Signatures and layouts of the zip records :func:`zip_bytes` writes (APPNOTE 4.3.7, 4.3.12,
#: 4.3.16, 4.5.3).
_LOCAL_HEADER = struct.Struct("<4s2B4HL2L2H")
_CENTRAL_HEADER = struct.Struct("<4s4B4HL2L5H2L")
_END_RECORD = struct.Struct("<4s4H2LH")
_ZIP64_EXTRA = struct.Struct("<HHQQ")
#: Version needed to extract: 4.5 (zip64 sizes in every local header), 6.3 for LZMA entries.
_ZIP64_VERSION, _LZMA_VERSION = 45, 63
#: General-purpose flag bit 1 of an LZMA entry: the stream ends with an end marker.
_LZMA_EOS_FLAG = 0x02


def zip_bytes(entries: Sequence[tuple[str, int, Any, Sequence[bytes | memoryview]]]) -> bytes:
    """The bytes of a zip archive of ``entries`` (name, method, compressor, parts): each entry
    the concatenated ``parts``, stored (``zipfile.ZIP_STORED``, compressor None) or compressed
    by ``compressor`` (``compress(part)`` per part, then ``flush()``; method ``ZIP_DEFLATED``
    or ``ZIP_LZMA``). The same bytes ``zipfile.ZipFile`` writes into a seekable file with
    ``force_zip64=True`` for entries dated :data:`NPZ_DATE_TIME` with permissions rw-r--r--
    (every zip reader, ``np.load`` included, reads them; tests compare the two byte for byte),
    with the CRC-32 by libdeflate (~10x faster than zlib's, which ``zipfile`` uses)."""
    out: list[bytes | memoryview] = []
    central: list[bytes] = []
    offset = 0
    dt = NPZ_DATE_TIME
    dosdate = (dt[0] - 1980) << 9 | dt[1] << 5 | dt[2]
    dostime = dt[3] << 11 | dt[4] << 5 | (dt[5] // 2)
    for name, method, compressor, parts in entries:
        crc, size = 0, 0
        body: list[bytes | memoryview] = []
        for part in parts:
            crc = deflate.crc32(part, crc)
            size += len(part) if isinstance(part, bytes) else part.nbytes
            body.append(compressor.compress(part) if compressor is not None else part)
        if compressor is not None:
            body.append(compressor.flush())
        packed = sum(len(b) if isinstance(b, bytes) else b.nbytes for b in body)
        version = _LZMA_VERSION if method == zipfile.ZIP_LZMA else _ZIP64_VERSION
        flags = _LZMA_EOS_FLAG if method == zipfile.ZIP_LZMA else 0
        fname = name.encode("ascii")
        extra = _ZIP64_EXTRA.pack(1, _ZIP64_EXTRA.size - 4, size, packed)
        if size > _ZIP64_LIMIT or packed > _ZIP64_LIMIT or offset > _ZIP64_LIMIT:
            raise InvalidArgumentError(f"zip_bytes: entry '{name}' beyond 2 GiB")
        out.append(
            _LOCAL_HEADER.pack(
                b"PK\x03\x04",
                version,
                0,
                flags,
                method,
                dostime,
                dosdate,
                crc,
                0xFFFFFFFF,
                0xFFFFFFFF,
                len(fname),
                len(extra),
            )
            + fname
            + extra
        )
        central.append(
            _CENTRAL_HEADER.pack(
                b"PK\x01\x02",
                version,
                _CREATE_SYSTEM,
                version,
                0,
                flags,
                method,
                dostime,
                dosdate,
                crc,
                packed,
                size,
                len(fname),
                0,
                0,
                0,
                0,
                _EXTERNAL_ATTR,
                offset,
            )
            + fname
        )
        out.extend(body)
        offset += len(out[-len(body) - 1]) + packed
    directory = b"".join(central)
    end = _END_RECORD.pack(
        b"PK\x05\x06", 0, 0, len(entries), len(entries), len(directory), offset, 0
    )
    return b"".join([*out, directory, end])


#: Largest size and offset of a zip entry without the zip64 end records (which the npz of one
#: view never needs).
_ZIP64_LIMIT = (1 << 31) - 1
#: "Version made by" host of the entries: 3 (Unix), as ``zipfile`` writes off Windows.
_CREATE_SYSTEM = 3
#: External attributes: rw-r--r-- (numpy's own writer's).
_EXTERNAL_ATTR = 0o644 << 16


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
