"""Read the arrays of an ``.npz`` one by one, fast: :class:`NpzReader`.

``numpy.load`` inflates each zip entry with zlib; the scene writer's entries are raw deflate
streams (docs/format.md, "Deflate streams"), which libdeflate (PyPI ``deflate``) inflates 2-3x
faster in one call. The reader reads the file once, inflates an entry with libdeflate when it
is deflated (method 8; checked against the entry's CRC-32), with Python's ``zipfile``
otherwise (stored, LZMA), and gives an entry's shape and dtype from its ``.npy`` header, or the
first bytes of its data, without inflating the rest.
"""

from __future__ import annotations

import io
import os
import struct
import zipfile
import zlib
from pathlib import Path
from typing import Any

import deflate
import numpy as np

from mgn.errors import IoError

__all__ = ["NpzReader"]

_LOCAL_HEADER = struct.Struct("<4s2B4HL2L2H")  # zip local file header, 30 bytes
_READ_ERRORS = (OSError, ValueError, zipfile.BadZipFile, EOFError, zlib.error, KeyError)


class NpzReader:
    """The arrays of one ``.npz`` file (``{key}.npy`` entries), read on demand.

    Raises :class:`~mgn.errors.IoError` naming the file when it is missing, is not a zip file,
    or an entry is damaged (bad CRC-32, cut stream, bad ``.npy`` header).
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = os.fspath(path)
        try:
            with Path(self.path).open("rb") as f:
                self._data = f.read()
            self._zip = zipfile.ZipFile(io.BytesIO(self._data))
        except FileNotFoundError:
            raise IoError(f"'{self.path}' does not exist") from None
        except _READ_ERRORS as e:
            raise IoError(f"'{self.path}' is not a readable npz: {e}") from e
        self._info = {
            i.filename[:-4]: i for i in self._zip.infolist() if i.filename.endswith(".npy")
        }

    @property
    def files(self) -> list[str]:
        """The array names, in the file's order."""
        return list(self._info)

    def __contains__(self, key: str) -> bool:
        return key in self._info

    def _entry(self, key: str) -> zipfile.ZipInfo:
        try:
            return self._info[key]
        except KeyError:
            raise IoError(f"'{self.path}' has no array '{key}' (it has {self.files})") from None

    def _raw(self, info: zipfile.ZipInfo) -> memoryview:
        """The compressed bytes of an entry."""
        fields = _LOCAL_HEADER.unpack_from(self._data, info.header_offset)
        if fields[0] != b"PK\x03\x04":
            raise IoError(f"'{self.path}': bad local header of '{info.filename}'")
        start = info.header_offset + _LOCAL_HEADER.size + fields[-2] + fields[-1]
        return memoryview(self._data)[start : start + info.compress_size]

    def _bytes(self, key: str) -> bytes | bytearray:
        info = self._entry(key)
        try:
            if info.compress_type == zipfile.ZIP_DEFLATED:
                out = deflate.deflate_decompress(self._raw(info), info.file_size)
                if deflate.crc32(out) != info.CRC:
                    raise IoError(f"'{self.path}': '{info.filename}' fails its CRC-32")
                return out
            return self._zip.read(info)
        except IoError:
            raise
        except (*_READ_ERRORS, deflate.DeflateError) as e:
            raise IoError(f"'{self.path}': '{info.filename}' is damaged: {e}") from e

    def header(self, key: str) -> tuple[tuple[int, ...], np.dtype[Any], int]:
        """(shape, dtype, offset of the data) of an entry, from the first bytes of its
        ``.npy`` data (a few hundred bytes are inflated)."""
        return _npy_header(self.prefix_bytes(key, 512), f"'{self.path}': '{key}.npy'")

    def prefix_bytes(self, key: str, size: int) -> bytes:
        """The first ``size`` bytes (at most) of an entry's ``.npy`` data, inflating only them."""
        info = self._entry(key)
        try:
            if info.compress_type == zipfile.ZIP_DEFLATED:
                return zlib.decompressobj(-15).decompress(self._raw(info), size)
            with self._zip.open(info) as f:
                return f.read(size)
        except (*_READ_ERRORS, deflate.DeflateError) as e:
            raise IoError(f"'{self.path}': '{info.filename}' is damaged: {e}") from e

    def rows(self, key: str, count: int) -> np.ndarray:
        """The first ``count`` rows (along axis 0) of a C-ordered entry, inflating only them."""
        shape, dtype, offset = self.header(key)
        per_row = int(np.prod(shape[1:], dtype=np.int64)) * dtype.itemsize
        count = max(0, min(count, shape[0] if shape else 0))
        data = self.prefix_bytes(key, offset + count * per_row)
        if len(data) < offset + count * per_row:
            raise IoError(f"'{self.path}': '{key}.npy' is cut short")
        return np.frombuffer(
            data, dtype, count * per_row // max(dtype.itemsize, 1), offset
        ).reshape((count, *shape[1:]))

    def __getitem__(self, key: str) -> np.ndarray:
        """The whole array of an entry."""
        data = self._bytes(key)
        shape, dtype, offset = _npy_header(data, f"'{self.path}': '{key}.npy'")
        n = int(np.prod(shape, dtype=np.int64))
        if len(data) - offset < n * dtype.itemsize:
            raise IoError(f"'{self.path}': '{key}.npy' is cut short")
        return np.frombuffer(data, dtype, n, offset).reshape(shape)


def _npy_header(data: bytes | bytearray, what: str) -> tuple[tuple[int, ...], np.dtype[Any], int]:
    """(shape, dtype, data offset) of ``.npy`` bytes; C order required."""
    f = io.BytesIO(bytes(data[:1024]) if len(data) > 1024 else bytes(data))
    try:
        major, _ = np.lib.format.read_magic(f)
        if major == 1:
            shape, fortran, dtype = np.lib.format.read_array_header_1_0(f)
        else:
            shape, fortran, dtype = np.lib.format.read_array_header_2_0(f)
    except ValueError as e:
        raise IoError(f"{what} has no valid .npy header: {e}") from e
    if fortran or dtype.hasobject:
        raise IoError(f"{what}: expected a C-ordered array of plain values")
    return tuple(int(x) for x in shape), dtype, f.tell()
