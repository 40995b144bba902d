"""Standard deflate streams made by libdeflate: zip entries, HDF5 gzip chunks and PNG images.

Every stream here is plain deflate (RFC 1951), in the zlib wrapper (RFC 1950) where the format
asks for it, so every reader decodes it unchanged: ``np.load`` (Python's ``zipfile``), the HDF5
library's gzip filter (h5py), libpng (Pillow, OpenCV). Only the encoder differs from zlib's:
libdeflate (through the PyPI package ``deflate``; third_party_notes/deflate.md) compresses whole
buffers, with better block splitting than zlib, and releases the GIL while it works. On a
1200 x 1200 view (docs/format.md) its level 6 takes about the time of zlib's level 1 and gives
10-20 % fewer bytes for the sensor depth and the images, 3x fewer for the masks.

The same bytes in give the same stream out (for one libdeflate version): nothing depends on the
number of threads or on the machine.

- :func:`deflate_raw` / :func:`zlib_stream`: one buffer, one stream;
- :class:`ZipDeflate`: the compressor of one ``zipfile`` entry (raw deflate, wbits -15);
- :func:`h5_write_deflated`: an HDF5 dataset written chunk by chunk, each chunk shuffled and
  deflated here and stored with ``write_direct_chunk`` (the file is an ordinary shuffle + gzip
  dataset);
- :func:`png_encode`: a PNG of a grey, RGB, 16-bit grey or palette image (filter type 0, one
  IDAT chunk).
"""

from __future__ import annotations

import functools
import struct
import zlib
from typing import Any

import deflate
import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError

__all__ = [
    "RUN_BLOCK",
    "MAX_LEVEL",
    "ZipDeflate",
    "ZipRunDeflate",
    "deflate_runs",
    "zlib_runs_stream",
    "deflate_raw",
    "h5_write_deflated",
    "png_encode",
    "shuffled_chunks",
    "zlib_stream",
]

#: Highest libdeflate level (10-12 search for the optimal parse: several times slower).
MAX_LEVEL = 12


def _check_level(level: int) -> int:
    if not 1 <= int(level) <= MAX_LEVEL:
        raise InvalidArgumentError(f"deflate level {level}: expected 1..{MAX_LEVEL}")
    return int(level)


def deflate_raw(data: bytes | memoryview, level: int) -> bytes:
    """Raw deflate stream (RFC 1951, what zip entries hold) of ``data`` at libdeflate ``level``
    (1..12)."""
    return bytes(deflate.deflate_compress(data, _check_level(level)))


def zlib_stream(data: bytes | memoryview, level: int) -> bytes:
    """zlib stream (RFC 1950: header, deflate, Adler-32; what PNG IDAT and HDF5 gzip chunks hold)
    of ``data`` at libdeflate ``level`` (1..12)."""
    return bytes(deflate.zlib_compress(data, _check_level(level)))


#: Largest stored deflate block (RFC 1951 3.2.4: LEN is 16 bits).
_STORED_MAX = 0xFFFF


def _stored_blocks(data: bytes) -> bytes:
    """``data`` as non-final stored deflate blocks (byte-aligned: header byte 0, LEN, NLEN, the
    bytes), which a following deflate stream continues."""
    out = []
    for s in range(0, len(data), _STORED_MAX):
        part = data[s : s + _STORED_MAX]
        out.append(struct.pack("<BHH", 0, len(part), len(part) ^ 0xFFFF) + part)
    return b"".join(out)


class ZipDeflate:
    """Drop-in for the raw-deflate compressor ``zipfile`` makes for a ``ZIP_DEFLATED`` entry
    (``compress`` / ``flush``; ``zipfile`` computes the CRC and sizes of the uncompressed bytes
    itself). Keeps the parts written (a memoryview is kept, not copied) and deflates them at
    flush in one libdeflate call; leading parts of less than 64 KiB together (e.g. a ``.npy``
    header before the array's own buffer) go first as stored blocks, so the large last part
    is deflated without being copied next to them.

    On images made of long runs of equal bytes (masks, id images, a heat map's zero residual)
    libdeflate's compact streams (~3x smaller than zlib's level 1) take zlib's inflater 2-3x
    longer to read back (+70 ms per 1200 x 1200 view of 20 objects): where reading speed
    matters, deflate those with zlib's level 1 (``npz_bytes(zlib_levels=...)``)."""

    def __init__(self, level: int) -> None:
        self._level = _check_level(level)
        self._parts: list[bytes | memoryview] = []

    def _deflate(self, data: bytes | memoryview) -> bytes:
        """The final part of the entry's raw deflate stream (ends with a final block)."""
        return deflate_raw(data, self._level)

    def compress(self, data: bytes | memoryview) -> bytes:
        self._parts.append(data)
        return b""

    def flush(self) -> bytes:
        parts, self._parts = self._parts, []
        if not parts:
            return self._deflate(b"")
        head = b"".join(bytes(p) for p in parts[:-1])
        if len(head) < 1 << 16:
            return _stored_blocks(head) + self._deflate(parts[-1])
        return self._deflate(head + bytes(parts[-1]))


#: Bytes per block of :func:`deflate_runs` (all-zero blocks come from cached streams).
RUN_BLOCK = 1 << 14


@functools.lru_cache(maxsize=64)
def _zero_blocks(count: int, level: int) -> bytes:
    """Non-final raw deflate blocks, ending byte-aligned (zlib's sync flush), made by zlib at
    ``level`` from ``count`` * :data:`RUN_BLOCK` zero bytes: they inflate to those zeros after
    any preceding blocks (their matches reach back into their own zeros only)."""
    c = zlib.compressobj(level, zlib.DEFLATED, -15)
    return c.compress(bytes(count * RUN_BLOCK)) + c.flush(zlib.Z_SYNC_FLUSH)


#: The final empty block that ends a raw deflate stream after a sync flush (fixed Huffman,
#: BFINAL 1, end-of-block code only).
_FINAL_EMPTY_BLOCK = b"\x03\x00"


def deflate_runs(data: bytes | memoryview | npt.NDArray[Any], level: int) -> bytes:
    """Raw deflate stream (RFC 1951) of ``data`` made by zlib at ``level`` (1..9), for images
    that are mostly zeros (masks, ids, the CoM residual): the data is cut into blocks of
    :data:`RUN_BLOCK` bytes; each run of at least two all-zero blocks is a cached stream of zeros
    (:func:`_zero_blocks`, powers of two of blocks), the bytes between them are deflated by a
    fresh zlib compressor each (so no match reaches across a run). zlib's fast levels (1-3) keep
    its matches long-distance, which zlib inflates several times faster than libdeflate's
    compact streams of runs (:class:`ZipDeflate`); skipping the zeros makes it ~3x faster
    than deflating them. The same bytes in give the same stream out (for one zlib version)."""
    if not 1 <= int(level) <= 9:
        raise InvalidArgumentError(f"zlib level {level}: expected 1..9")
    a = np.frombuffer(data, np.uint8) if not isinstance(data, np.ndarray) else data.reshape(-1)
    a = a.view(np.uint8)
    n = len(a) // RUN_BLOCK
    zero = np.zeros(n + 2, bool)  # padded with a non-zero block at both ends
    if n:
        words = a[: n * RUN_BLOCK].view(np.uint64).reshape(n, RUN_BLOCK // 8)
        zero[1:-1] = ~words.any(axis=1)
    edges = np.flatnonzero(np.diff(zero.view(np.int8)))  # starts (+1) and ends (-1) of runs
    out: list[bytes] = []

    def deflate_part(start: int, stop: int) -> None:
        if stop > start:
            c = zlib.compressobj(level, zlib.DEFLATED, -15)
            out.append(c.compress(a[start:stop].data) + c.flush(zlib.Z_SYNC_FLUSH))

    done = 0  # bytes of ``a`` in ``out``
    for first, last in zip(edges[0::2], edges[1::2], strict=True):
        count = int(last - first)  # all-zero blocks first .. last - 1
        if count < 2:
            continue
        deflate_part(done, int(first) * RUN_BLOCK)
        for bit in range(count.bit_length()):
            if count >> bit & 1:
                out.append(_zero_blocks(1 << bit, level))
        done = int(last) * RUN_BLOCK
    deflate_part(done, len(a))
    out.append(_FINAL_EMPTY_BLOCK)
    return b"".join(out)


def zlib_runs_stream(data: bytes | memoryview | npt.NDArray[Any], level: int) -> bytes:
    """zlib stream (RFC 1950) of :func:`deflate_runs` of ``data`` at zlib ``level``."""
    adler = deflate.adler32(data if not isinstance(data, np.ndarray) else data.reshape(-1).data)
    return b"\x78\x5e" + deflate_runs(data, level) + struct.pack(">I", adler)


class ZipRunDeflate(ZipDeflate):
    """The compressor of a ``zipfile`` entry (as :class:`ZipDeflate`) whose stream is
    :func:`deflate_runs` of the entry at zlib ``level`` (1..9): images of long runs of zeros
    that must stay fast to inflate with zlib."""

    def __init__(self, level: int) -> None:
        if not 1 <= int(level) <= 9:
            raise InvalidArgumentError(f"zlib level {level}: expected 1..9")
        self._level = int(level)
        self._parts: list[bytes | memoryview] = []

    def _deflate(self, data: bytes | memoryview) -> bytes:
        return deflate_runs(data, self._level)


def shuffled_chunks(
    data: npt.ArrayLike, chunks: tuple[int, ...], *, shuffle: bool = True
) -> list[tuple[tuple[int, ...], bytes]]:
    """The chunks of ``data`` for an HDF5 chunked layout of shape ``chunks``, in row-major chunk
    order, each as (offset, bytes after HDF5's shuffle filter): a full chunk's C-order values (the
    parts beyond the dataset's edge zero) with byte k of every value grouped together (all bytes
    0, then all bytes 1, ...), as the HDF5 shuffle filter arranges them. ``shuffle=False``: the
    chunk's C-order values as they are (a dataset without the shuffle filter)."""
    a = np.ascontiguousarray(data)
    if a.ndim != len(chunks) or a.ndim == 0 or any(c < 1 for c in chunks):
        raise InvalidArgumentError(
            f"shuffled_chunks: chunk shape {chunks} does not fit an array of shape {a.shape}"
        )
    counts = [-(-n // c) for n, c in zip(a.shape, chunks, strict=True)]
    padded_shape = tuple(n * c for n, c in zip(counts, chunks, strict=True))
    if padded_shape != a.shape:
        padded = np.zeros(padded_shape, a.dtype)
        padded[tuple(slice(0, n) for n in a.shape)] = a
        a = padded
    size = a.dtype.itemsize
    # (n0, c0, n1, c1, ..., size) -> (n0, n1, ..., size, c0, c1, ...): per chunk, byte planes
    # (without the shuffle: (n0, n1, ..., c0, c1, ..., size)).
    split = a.view(np.uint8).reshape(
        [x for n, c in zip(counts, chunks, strict=True) for x in (n, c)] + [size]
    )
    nd = a.ndim
    inner = [2 * i + 1 for i in range(nd)]
    order = [2 * i for i in range(nd)] + ([2 * nd] + inner if shuffle else inner + [2 * nd])
    planes = np.ascontiguousarray(split.transpose(order)).reshape(int(np.prod(counts)), -1)
    out = []
    for k, index in enumerate(np.ndindex(*counts)):
        offset = tuple(i * c for i, c in zip(index, chunks, strict=True))
        out.append((offset, planes[k].tobytes()))
    return out


def h5_write_deflated(
    group: Any,
    name: str,
    data: npt.ArrayLike,
    chunks: tuple[int, ...],
    level: int,
    *,
    zlib_level: int | None = None,
    shuffle: bool = True,
    **kwargs: Any,
) -> Any:
    """Create dataset ``name`` in h5py ``group`` holding ``data`` with chunk shape ``chunks`` and
    the filters shuffle + gzip, the chunks compressed here (:func:`shuffled_chunks`, then
    :func:`zlib_stream` at libdeflate ``level``) and stored with ``write_direct_chunk``: every
    HDF5 reader decodes them with its own gzip filter. ``zlib_level``: deflate with zlib at that
    level instead, zero blocks skipped (:func:`zlib_runs_stream`; images of long runs).
    ``shuffle=False``: gzip only, no shuffle filter (values of a few repeated 4-byte patterns
    compress better unshuffled). ``kwargs`` go to ``create_dataset`` (e.g.
    ``track_times=False``). Returns the dataset."""
    a = np.ascontiguousarray(data)
    ds = group.create_dataset(
        name, shape=a.shape, dtype=a.dtype, chunks=chunks, compression="gzip",
        compression_opts=min(_check_level(level), 9), shuffle=shuffle, **kwargs,
    )  # fmt: skip
    for offset, raw in shuffled_chunks(a, chunks, shuffle=shuffle):
        stream = (
            zlib_stream(raw, level) if zlib_level is None else zlib_runs_stream(raw, zlib_level)
        )
        ds.id.write_direct_chunk(offset, stream, 0)
    return ds


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _png_chunk(kind: bytes, body: bytes) -> bytes:
    return (
        struct.pack(">I", len(body))
        + kind
        + body
        + struct.pack(">I", zlib.crc32(body, zlib.crc32(kind)))
    )


def png_encode(image: npt.ArrayLike, *, level: int, palette: npt.ArrayLike | None = None) -> bytes:
    """A PNG (ISO/IEC 15948) of ``image``: (H, W) uint8 grey, (H, W, 3) uint8 RGB, (H, W) uint16
    grey, or (H, W) uint8 indices into ``palette`` ((K, 3) uint8, K <= 256). Every row has filter
    type 0 (none: on rendered pictures with flat regions libdeflate's matches do better than the
    Sub/Up/Paeth predictors at the same level), one IDAT chunk at libdeflate ``level``, no time
    or text chunk (reproducible)."""
    a = np.asarray(image)
    if palette is not None:
        pal = np.asarray(palette)
        if a.ndim != 2 or a.dtype != np.uint8 or pal.ndim != 2 or pal.shape[1] != 3:
            raise InvalidArgumentError(
                f"png_encode: palette image must be (H, W) uint8 with a (K, 3) palette, got "
                f"{a.shape} {a.dtype} and {pal.shape}"
            )
        if not 1 <= len(pal) <= 256 or int(a.max(initial=0)) >= len(pal):
            raise InvalidArgumentError(
                f"png_encode: palette of {len(pal)} colours for indices up to {int(a.max())}"
            )
        depth, colour, rows = 8, 3, a
    elif a.ndim == 3 and a.shape[2] == 3 and a.dtype == np.uint8:
        depth, colour, rows = 8, 2, a.reshape(a.shape[0], -1)
    elif a.ndim == 2 and a.dtype == np.uint8:
        depth, colour, rows = 8, 0, a
    elif a.ndim == 2 and a.dtype == np.uint16:
        depth, colour, rows = 16, 0, a.astype(">u2").view(np.uint8)
    else:
        raise InvalidArgumentError(
            f"png_encode: image of shape {a.shape} and dtype {a.dtype}; expected (H, W) uint8, "
            "(H, W, 3) uint8 or (H, W) uint16"
        )
    h, w = a.shape[:2]
    if h < 1 or w < 1:
        raise InvalidArgumentError(f"png_encode: empty image of shape {a.shape}")
    raw = np.empty((h, rows.shape[1] + 1), np.uint8)
    raw[:, 0] = 0  # filter type none
    raw[:, 1:] = rows
    parts = [
        _PNG_SIGNATURE,
        _png_chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, colour, 0, 0, 0)),
    ]
    if palette is not None:
        parts.append(_png_chunk(b"PLTE", np.ascontiguousarray(pal, np.uint8).tobytes()))
    parts.append(_png_chunk(b"IDAT", zlib_stream(raw.data, level)))
    parts.append(_png_chunk(b"IEND", b""))
    return b"".join(parts)
