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
    "MAX_LEVEL",
    "RUN_BLOCK",
    "ZERO_RUN_DISTANCE",
    "ZipDeflate",
    "ZipRunDeflate",
    "deflate_raw",
    "deflate_runs",
    "h5_write_deflated",
    "png_encode",
    "shuffled_chunks",
    "zlib_runs_stream",
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
    (``compress`` / ``flush``; the zip writer computes the CRC and sizes of the uncompressed
    bytes itself: :func:`mgn.base.deterministic.zip_bytes`). Keeps the parts written (a
    memoryview is kept, not copied) and deflates them at flush in one libdeflate call; leading
    parts of less than 64 KiB together (e.g. a ``.npy`` header before the array's own buffer) go
    first as stored blocks, so the large last part is deflated without being copied next to
    them.

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


#: Match distance of :func:`_zero_blocks`' copies: zlib's inflater copies a match byte by byte,
#: and at distances of 1-4 each byte waits for the one just written (the masks' zeros inflate 2-3x
#: slower than at distance 5+); 5-8 take one extra bit per 258-byte match.
ZERO_RUN_DISTANCE = 8

#: Base lengths and extra bits of deflate's length symbols 257..285 (RFC 1951 3.2.5).
_LENGTH_BASE = (
    3,
    4,
    5,
    6,
    7,
    8,
    9,
    10,
    11,
    13,
    15,
    17,
    19,
    23,
    27,
    31,
    35,
    43,
    51,
    59,
    67,
    83,
    99,
    115,
    131,
    163,
    195,
    227,
    258,
)
_LENGTH_EXTRA = (0,) * 8 + (1,) * 4 + (2,) * 4 + (3,) * 4 + (4,) * 4 + (5,) * 4 + (0,)
#: Base distances and extra bits of deflate's distance symbols 0..29 (RFC 1951 3.2.5).
_DIST_BASE = (
    1,
    2,
    3,
    4,
    5,
    7,
    9,
    13,
    17,
    25,
    33,
    49,
    65,
    97,
    129,
    193,
    257,
    385,
    513,
    769,
    1025,
    1537,
    2049,
    3073,
    4097,
    6145,
    8193,
    12289,
    16385,
    24577,
)
_DIST_EXTRA = (0, 0, 0, 0) + tuple(k // 2 for k in range(2, 28))
#: Order in which a dynamic block's header lists the code-length code's lengths (RFC 1951 3.2.7).
_CODE_LENGTH_ORDER = (16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15)


class _Bits:
    """Bits of a deflate stream, packed from the least significant bit of each byte on."""

    def __init__(self) -> None:
        self.value = 0
        self.count = 0

    def put(self, value: int, nbits: int) -> None:
        """``nbits`` bits of ``value``, least significant first (header fields, extra bits)."""
        self.value |= (value & ((1 << nbits) - 1)) << self.count
        self.count += nbits

    def code(self, code: tuple[int, int]) -> None:
        """A Huffman code (code, length), most significant bit first (RFC 1951 3.1.1)."""
        value, length = code
        self.put(int(f"{value:0{length}b}"[::-1], 2), length)

    def repeat(self, value: int, nbits: int, times: int) -> None:
        """``times`` copies of the ``nbits``-bit group ``value`` (already in stream order)."""
        if times > 0:
            self.put(value * (((1 << (nbits * times)) - 1) // ((1 << nbits) - 1)), nbits * times)

    def to_bytes(self) -> bytes:
        return self.value.to_bytes((self.count + 7) // 8, "little")


def _canonical(lengths: dict[int, int]) -> dict[int, tuple[int, int]]:
    """The canonical Huffman codes (code, length) of symbols with the given code lengths."""
    top = max(lengths.values())
    count = [0] * (top + 1)
    for n in lengths.values():
        count[n] += 1
    first, code = [0] * (top + 1), 0
    for n in range(1, top + 1):
        code = (code + count[n - 1]) << 1 if n > 1 else 0
        first[n] = code
    out = {}
    for sym in sorted(lengths):
        n = lengths[sym]
        out[sym] = (first[n], n)
        first[n] += 1
    return out


def _complete_lengths(symbols: set[int], spare: int) -> dict[int, int]:
    """Code lengths of a complete prefix code over ``symbols`` (a second symbol ``spare`` is
    added to a single one): k - 1 or k bits each, k = ceil(log2(count))."""
    syms = sorted(symbols | ({spare} if len(symbols) == 1 else set()))
    k = (len(syms) - 1).bit_length()
    short = (1 << k) - len(syms)
    return {s: k - 1 if i < short else k for i, s in enumerate(syms)}


def _length_symbol(n: int) -> tuple[int, int, int]:
    """(symbol, extra value, extra bits) of a match of length ``n`` (3..258)."""
    if n == 258:
        return 285, 0, 0
    i = max(j for j in range(28) if _LENGTH_BASE[j] <= n)
    return 257 + i, n - _LENGTH_BASE[i], _LENGTH_EXTRA[i]


@functools.lru_cache(maxsize=64)
def _zero_blocks(count: int) -> bytes:
    """One non-final dynamic-Huffman deflate block holding ``count`` * :data:`RUN_BLOCK` zero bytes,
    followed by an empty stored block (it ends byte-aligned, as zlib's sync flush): it inflates to
    those zeros after any preceding blocks. :data:`ZERO_RUN_DISTANCE` literal zeros, then matches
    of 258 bytes (and one of the rest) at that distance, which reach back into the block's own
    zeros only. Its codes have the fewest bits a stream of zeros allows at that distance (the
    literal, the 258-match, the end of block; one distance code): 3 bits per 258 bytes, a quarter
    of what zlib's fast levels take; zlib inflates it about as fast as zlib's own stream."""
    n, lits = count * RUN_BLOCK, ZERO_RUN_DISTANCE
    matches, rest = divmod(n - lits, 258)
    if 0 < rest < 3:
        matches, rest = matches - 1, rest + 258  # as two matches: 258 + rest = x + (258 + rest - x)
    lit = {0: 2, 285: 1, 256: 2}
    tail: list[tuple[int, int, int]] = []
    if rest > 258:
        tail = [_length_symbol(rest - 129), _length_symbol(129)]
    elif rest:
        tail = [_length_symbol(rest)]
    if tail:
        # 285: 1 bit, literal 0: 2, end of block and the tail's symbols 3-4 bits.
        extra = sorted({256} | {t[0] for t in tail})
        lit = {0: 2, 285: 1} | (
            dict.fromkeys(extra, 3) if len(extra) == 2 else {extra[0]: 3, extra[1]: 4, extra[2]: 4}
        )
    dist_sym = next(i for i in range(29, -1, -1) if _DIST_BASE[i] <= lits)
    dist_extra = (lits - _DIST_BASE[dist_sym], _DIST_EXTRA[dist_sym])
    dist = {dist_sym: 1, (1 if dist_sym == 0 else 0): 1}  # a complete code of two
    # The code lengths of both alphabets, zeros run-length coded (symbols 17 and 18).
    seq = [lit.get(i, 0) for i in range(max(lit) + 1)] + [
        dist.get(i, 0) for i in range(max(dist) + 1)
    ]
    ops: list[tuple[int, int, int]] = []
    i = 0
    while i < len(seq):
        j = i
        while j < len(seq) and seq[j] == 0 and j - i < 138:
            j += 1
        if j - i >= 11:
            ops.append((18, j - i - 11, 7))
        elif j - i >= 3:
            ops.append((17, j - i - 3, 3))
        else:
            ops.append((seq[i], 0, 0))
            j = i + 1
        i = j
    cl_lengths = _complete_lengths({op[0] for op in ops}, spare=0 if ops[0][0] else 1)
    cl_codes = _canonical(cl_lengths)
    hclen = max(4, 1 + max(_CODE_LENGTH_ORDER.index(s) for s in cl_lengths))
    b = _Bits()
    b.put(0b100, 3)  # BFINAL 0, BTYPE 2 (dynamic Huffman)
    b.put(max(lit) + 1 - 257, 5)
    b.put(max(dist), 5)
    b.put(hclen - 4, 4)
    for s in _CODE_LENGTH_ORDER[:hclen]:
        b.put(cl_lengths.get(s, 0), 3)
    for sym, value, nbits in ops:
        b.code(cl_codes[sym])
        b.put(value, nbits)
    lit_codes, dist_codes = _canonical(lit), _canonical(dist)
    zero = _Bits()
    zero.code(lit_codes[0])
    b.repeat(zero.value, zero.count, lits)
    match = _Bits()
    match.code(lit_codes[285])
    match.code(dist_codes[dist_sym])
    match.put(*dist_extra)
    b.repeat(match.value, match.count, matches)
    for sym, value, nbits in tail:
        b.code(lit_codes[sym])
        b.put(value, nbits)
        b.code(dist_codes[dist_sym])
        b.put(*dist_extra)
    b.code(lit_codes[256])
    b.put(0, 3)  # an empty stored block: BFINAL 0, BTYPE 0, then to the byte boundary
    return b.to_bytes() + b"\x00\x00\xff\xff"


#: The final empty block that ends a raw deflate stream after a sync flush (fixed Huffman,
#: BFINAL 1, end-of-block code only).
_FINAL_EMPTY_BLOCK = b"\x03\x00"


def deflate_runs(data: bytes | memoryview | npt.NDArray[Any], level: int) -> bytes:
    """Raw deflate stream (RFC 1951) of ``data`` made by zlib at ``level`` (1..9), for images
    that are mostly zeros (masks, ids, the CoM residual): the data is cut into blocks of
    :data:`RUN_BLOCK` bytes; each run of at least two all-zero blocks is a cached deflate block of
    zeros (:func:`_zero_blocks`, powers of two of blocks: 3 bits per 258 bytes, a quarter of
    zlib's own stream of zeros), the bytes between them are deflated by a fresh zlib compressor
    each (so no match reaches across a run). zlib's fast levels (1-3) keep their matches
    long-distance, which zlib inflates several times faster than libdeflate's compact streams of
    runs (:class:`ZipDeflate`); skipping the zeros makes it ~3x faster than deflating them. The
    same bytes in give the same stream out (for one zlib version)."""
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
                out.append(_zero_blocks(1 << bit))
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
) -> list[tuple[tuple[int, ...], memoryview]]:
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
        out.append((offset, planes[k].data))  # a view of the row, not a copy
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
        name,
        shape=a.shape,
        dtype=a.dtype,
        chunks=chunks,
        compression="gzip",
        compression_opts=min(_check_level(level), 9),
        shuffle=shuffle,
        **kwargs,
    )
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
