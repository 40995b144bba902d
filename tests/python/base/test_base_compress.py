"""mgn.base.compress: libdeflate's streams decode with the other implementations every reader
uses (zlib for zip entries and HDF5's gzip filter, libpng through Pillow and OpenCV), to the
bytes put in; HDF5 files written chunk by chunk read back equal to the array through h5py's own
filters and are byte-identical to the file HDF5 writes itself with the same chunk streams."""

from __future__ import annotations

import io
import zipfile
import zlib
from pathlib import Path

import cv2
import deflate
import h5py
import numpy as np
import pytest
from PIL import Image

from mgn.base.compress import (
    RUN_BLOCK,
    ZERO_RUN_DISTANCE,
    ZipDeflate,
    ZipRunDeflate,
    _zero_blocks,
    deflate_raw,
    deflate_runs,
    h5_write_deflated,
    png_encode,
    shuffled_chunks,
    zlib_runs_stream,
    zlib_stream,
)
from mgn.base.deterministic import NPZ_DATE_TIME, _NpzLzma, npz_bytes
from mgn.errors import InvalidArgumentError, IoError
from mgn.io.dataset import View


def _payload() -> bytes:
    rng = np.random.default_rng(3)
    smooth = np.cumsum(rng.integers(-2, 3, 50_000)).astype(np.int32).tobytes()
    return smooth + bytes(20_000) + rng.integers(0, 256, 5_000, dtype=np.uint8).tobytes()


@pytest.mark.parametrize("level", [1, 5, 6, 9, 12])
def test_streams_inflate_with_zlib_to_the_input(level: int):
    data = _payload()
    assert zlib.decompress(deflate_raw(data, level), -15) == data
    stream = zlib_stream(data, level)
    assert zlib.decompress(stream) == data  # header and Adler-32 checked by zlib
    assert len(stream) < len(data) / 2
    assert zlib_stream(data, level) == stream  # same input, same bytes


def test_zip_compressor_stores_a_small_head_and_deflates_the_rest():
    data = _payload()
    head = b"\x93NUMPY header" * 5
    z = ZipDeflate(6)
    assert z.compress(head) == b""
    assert z.compress(memoryview(data)) == b""
    stream = z.flush()
    assert zlib.decompress(stream, -15) == head + data
    # The head is a stored block (byte 0: not final, type 0), then LEN and its complement.
    assert stream[0] == 0
    assert int.from_bytes(stream[1:3], "little") == len(head)
    assert int.from_bytes(stream[3:5], "little") == len(head) ^ 0xFFFF
    # A head of 64 KiB or more is deflated with the rest.
    z = ZipDeflate(6)
    z.compress(data[:70_000])
    z.compress(data[70_000:])
    assert z.flush() == deflate_raw(data, 6)
    empty = ZipDeflate(1)
    assert zlib.decompress(empty.flush(), -15) == b""


@pytest.mark.parametrize("level", [1, 3])
def test_run_streams_inflate_with_zlib_to_the_input(level: int):
    """deflate_runs on buffers with all-zero blocks anywhere (single ones, which are deflated,
    and runs, which come from the cache), an unaligned tail, all zeros, nothing: zlib inflates
    every stream to the input, inside a zip entry too, and the same input gives the same
    stream."""
    b = RUN_BLOCK
    rng = np.random.default_rng(9)
    x = np.zeros(40 * b + 123, np.uint8)
    x[3 * b + 5] = 1  # a single non-zero byte between runs
    x[10 * b : 11 * b] = 7  # a whole block
    x[12 * b : 12 * b + 10] = 1  # one zero block (13*b..) then a run of zeros
    x[25 * b + 1] = 9
    x[-1] = 2  # in the tail
    noisy = rng.integers(0, 3, 3 * b + 5, dtype=np.uint8)
    cases = [
        b"",
        bytes(10),
        bytes(b),
        bytes(2 * b),
        bytes(5 * b + 7),
        x.tobytes(),
        noisy.tobytes(),
        x[1:].tobytes(),
    ]
    for data in cases:
        stream = deflate_runs(data, level)
        assert zlib.decompress(stream, -15) == data
        assert deflate_runs(data, level) == stream
        assert zlib.decompress(zlib_runs_stream(data, level)) == data
    # A numpy array (e.g. bool masks) is read as its bytes.
    mask = np.zeros((5, 200, 300), bool)
    mask[2, 50:90, 100:180] = True
    assert zlib.decompress(deflate_runs(mask, level), -15) == mask.tobytes()
    # Long zero runs cost a few bytes per block, not the block.
    assert len(deflate_runs(bytes(64 * b), level)) < 64 * b // 100
    # In an npz entry.
    with np.load(io.BytesIO(npz_bytes(mask=mask, zlib_levels={"mask": level}))) as z:
        assert np.array_equal(z["mask"], mask)
    with pytest.raises(InvalidArgumentError, match="zlib level 10"):
        deflate_runs(b"abc", 10)


@pytest.mark.parametrize("count", [1, 2, 3, 7, 8, 10, 137, 256])
def test_zero_blocks_inflate_to_zeros_after_any_data(count: int):
    """The hand-made deflate blocks of zeros (one dynamic block + an empty stored block): zlib
    and libdeflate (two inflaters) give exactly count * RUN_BLOCK zeros, after a preceding
    deflated part whose last bytes are not zero (the matches reach back into the block only);
    counts 8 and 10 are the cases where the bytes after the 258-byte matches are 0 and 1-2. The
    distance of the matches is ZERO_RUN_DISTANCE (the first that many bytes are literals)."""
    n = count * RUN_BLOCK
    zeros = _zero_blocks(count)
    head = zlib.compressobj(3, zlib.DEFLATED, -15)
    prefix = bytes(range(1, 200)) * 3
    stream = head.compress(prefix) + head.flush(zlib.Z_SYNC_FLUSH) + zeros + b"\x03\x00"
    assert zlib.decompress(stream, -15) == prefix + bytes(n)
    assert deflate.deflate_decompress(stream, len(prefix) + n) == prefix + bytes(n)
    # A brute-force reading of the block's Huffman codes: 3 bits per 258-byte match at most.
    assert len(zeros) <= 40 + 3 * (n // 258) // 8 + 8
    assert zeros[-4:] == b"\x00\x00\xff\xff"  # byte-aligned end, as zlib's sync flush
    assert _zero_blocks(count) is zeros  # cached
    assert ZERO_RUN_DISTANCE >= 5  # distances 1-4 inflate slowly in zlib


def test_zero_blocks_cut_anywhere_are_a_clear_error():
    """A stream of zero blocks with a byte changed or cut short does not inflate to zeros
    silently: zlib reports an error or gives other bytes (the zip entry's CRC catches those)."""
    stream = deflate_runs(bytes(8 * RUN_BLOCK), 3)
    with pytest.raises(zlib.error):
        zlib.decompress(stream[: len(stream) // 2], -15)
    bad = bytearray(stream)
    bad[3] ^= 0xFF
    try:
        out = zlib.decompress(bytes(bad), -15)
    except zlib.error:
        return
    assert out != bytes(8 * RUN_BLOCK)


def test_levels_outside_libdeflate_range_are_refused():
    with pytest.raises(InvalidArgumentError, match="deflate level 13"):
        deflate_raw(b"abc", 13)
    with pytest.raises(InvalidArgumentError, match="deflate level 0"):
        ZipDeflate(0)


def test_shuffled_chunks_match_a_direct_reading_of_the_hdf5_shuffle_filter():
    rng = np.random.default_rng(4)
    a = rng.random((5, 3, 2)).astype(np.float32)
    chunks = shuffled_chunks(a, (2, 3, 1))
    assert [off for off, _ in chunks] == [(r, 0, c) for r in (0, 2, 4) for c in (0, 1)]
    for (r, _, c), raw in chunks:
        block = np.zeros((2, 3, 1), np.float32)  # beyond the edge: zeros
        part = a[r : r + 2, :, c : c + 1]
        block[: part.shape[0]] = part
        values = block.reshape(-1).view(np.uint8).reshape(-1, 4)
        expected = b"".join(values[:, k].tobytes() for k in range(4))  # byte planes
        assert raw == expected
    with pytest.raises(InvalidArgumentError, match="chunk shape"):
        shuffled_chunks(a, (2, 3))
    # Without the shuffle: each chunk's values in C order, as they are.
    for (r, _, c), raw in shuffled_chunks(a, (2, 3, 1), shuffle=False):
        block = np.zeros((2, 3, 1), np.float32)
        part = a[r : r + 2, :, c : c + 1]
        block[: part.shape[0]] = part
        assert raw == block.tobytes()


def test_hdf5_chunks_without_shuffle_read_back_through_the_gzip_filter(tmp_path: Path):
    """``shuffle=False``: gzip-only chunks holding the values as they are; h5py reads them
    back. A few repeated float32 values (scores) take fewer bytes unshuffled."""
    rng = np.random.default_rng(8)
    repeated = rng.choice(rng.random(5).astype(np.float32), size=3000)
    with h5py.File(tmp_path / "a.h5", "w") as h5:
        h5_write_deflated(h5, "x", repeated, (1024,), 6, shuffle=False, track_times=False)
        h5_write_deflated(h5, "s", repeated, (1024,), 6, track_times=False)
    with h5py.File(tmp_path / "a.h5", "r") as h5:
        x, s = h5["x"], h5["s"]
        assert x.compression == "gzip"
        assert not x.shuffle
        assert s.shuffle
        assert np.asarray(x[()]).tobytes() == repeated.tobytes()
        for k in (0, 1024, 2048):
            _, stored = x.id.read_direct_chunk((k,))
            block = np.zeros(1024, np.float32)
            block[: len(repeated[k : k + 1024])] = repeated[k : k + 1024]
            assert zlib.decompress(stored) == block.tobytes()

        def size(d: h5py.Dataset) -> int:
            return sum(len(d.id.read_direct_chunk((k,))[1]) for k in (0, 1024, 2048))

        assert size(x) < size(s)


@pytest.mark.parametrize(
    ("shape", "dtype", "chunks"),
    [
        ((1000, 4, 4), np.float32, (300, 1, 1)),
        ((130, 77), np.int32, (64, 77)),
        ((70, 33), np.bool_, (64, 33)),
        ((257,), np.float64, (257,)),
    ],
)
def test_hdf5_chunks_written_directly_read_back_through_the_gzip_filter(
    tmp_path: Path, shape, dtype, chunks
):
    rng = np.random.default_rng(6)
    a = (rng.random(shape) * 100).astype(dtype)
    if dtype == np.float32:
        a[rng.random(shape) < 0.1] = np.nan
    with h5py.File(tmp_path / "a.h5", "w") as h5:
        h5_write_deflated(h5, "x", a, chunks, 6, track_times=False)
        # Second writer: HDF5 itself (its own zlib), chunk layout and filters the same.
        h5.create_dataset("ref", data=a, chunks=chunks, compression="gzip", shuffle=True)
    with h5py.File(tmp_path / "a.h5", "r") as h5:
        x = h5["x"]
        assert x.dtype == a.dtype
        assert x.chunks == chunks
        assert x.compression == "gzip"
        assert x.shuffle
        assert np.asarray(x[()]).tobytes() == a.tobytes()  # NaN bits included
        assert np.asarray(h5["ref"][()]).tobytes() == a.tobytes()
        # Chunk by chunk, the stored stream inflates to the shuffled bytes HDF5 wrote itself.
        for offset, raw in shuffled_chunks(a, chunks):
            mask, stored = x.id.read_direct_chunk(offset)
            assert mask == 0
            assert zlib.decompress(stored) == raw
            _, ref = h5["ref"].id.read_direct_chunk(offset)
            n = np.prod([min(c, s - o) for c, s, o in zip(chunks, shape, offset, strict=True)])
            if n == int(np.prod(chunks)):  # HDF5 pads partial chunks with whatever: full only
                assert zlib.decompress(ref) == raw


@pytest.mark.parametrize("kind", ["rgb", "grey", "grey16", "palette"])
def test_png_decodes_with_pillow_and_opencv(kind: str):
    rng = np.random.default_rng(7)
    h, w = 37, 53
    palette = None
    if kind == "rgb":
        img = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
        img[:10] = 17  # a flat band
    elif kind == "grey":
        img = rng.integers(0, 256, (h, w), dtype=np.uint8)
    elif kind == "grey16":
        img = rng.integers(0, 65536, (h, w), dtype=np.uint16)
    else:
        palette = rng.integers(0, 256, (200, 3), dtype=np.uint8)
        img = rng.integers(0, 200, (h, w), dtype=np.uint8)
    data = png_encode(img, level=6, palette=palette)
    with Image.open(io.BytesIO(data)) as im:
        im.load()  # checks every CRC and the zlib stream
        pil = np.asarray(im.convert("RGB") if palette is not None else im)
    expected = palette[img] if palette is not None else img
    assert pil.dtype == expected.dtype
    assert np.array_equal(pil, expected)
    cv = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    if kind in ("rgb", "palette"):
        cv = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)[..., ::-1]
    assert cv.dtype == expected.dtype
    assert np.array_equal(cv, expected)
    assert png_encode(img, level=6, palette=palette) == data


def test_png_refuses_images_it_cannot_store():
    with pytest.raises(InvalidArgumentError, match="expected"):
        png_encode(np.zeros((4, 4), np.float32), level=6)
    with pytest.raises(InvalidArgumentError, match="palette of 2 colours"):
        png_encode(np.full((4, 4), 5, np.uint8), level=6, palette=np.zeros((2, 3), np.uint8))


def _zipfile_npz(arrays: dict, compressors: dict) -> bytes:
    """The npz ``zipfile`` writes for ``arrays`` (the second implementation zip_bytes is checked
    against): every entry dated 1980-01-01, rw-r--r--, zip64 headers, the entry's compressor
    (name -> (zip method, compressor or None)) in place of zipfile's own."""
    out = io.BytesIO()
    with zipfile.ZipFile(out, mode="w", allowZip64=True) as zf:
        for name, array in arrays.items():
            method, comp = compressors[name]
            info = zipfile.ZipInfo(f"{name}.npy", date_time=NPZ_DATE_TIME)
            info.compress_type = method
            info.external_attr = 0o644 << 16
            with zf.open(info, mode="w", force_zip64=True) as fh:
                if comp is not None:
                    fh._compressor = comp
                np.lib.format.write_array(fh, np.asarray(array), allow_pickle=False)
    return out.getvalue()


def test_npz_bytes_are_the_bytes_zipfile_writes():
    """npz_bytes' own zip writer (CRC-32 by libdeflate) gives byte for byte the archive Python's
    zipfile writes with the same compressed streams: stored, deflated, zlib run-deflated and
    LZMA entries, empty and 0-d arrays; np.load reads every array back."""
    rng = np.random.default_rng(5)
    mask = np.zeros((3, 90, 1200), bool)
    mask[1, 10:40, 100:700] = True
    arrays = {
        "depth": rng.random((37, 41)).astype(np.float32),
        "mask": mask,
        "ids": rng.integers(0, 9, (50, 60)).astype(np.uint16),
        "empty": np.zeros((0, 3), np.float32),
        "scalar": np.array(7.5),
        "lz": rng.random(300).astype(np.float32),
    }
    data = npz_bytes(**arrays, level=5, zlib_levels={"mask": 3}, lzma_entries=("lz",))
    reference = _zipfile_npz(
        arrays,
        {
            "depth": (zipfile.ZIP_DEFLATED, ZipDeflate(5)),
            "mask": (zipfile.ZIP_DEFLATED, ZipRunDeflate(3)),
            "ids": (zipfile.ZIP_DEFLATED, ZipDeflate(5)),
            "empty": (zipfile.ZIP_DEFLATED, ZipDeflate(5)),
            "scalar": (zipfile.ZIP_DEFLATED, ZipDeflate(5)),
            "lz": (zipfile.ZIP_LZMA, _NpzLzma()),
        },
    )
    assert data == reference
    stored = npz_bytes(**arrays, compress=False, lzma_entries=("lz",))
    assert stored == _zipfile_npz(
        arrays,
        dict.fromkeys(arrays, (zipfile.ZIP_STORED, None)) | {"lz": (zipfile.ZIP_LZMA, _NpzLzma())},
    )
    with np.load(io.BytesIO(data)) as z:
        for name, array in arrays.items():
            assert z[name].dtype == array.dtype
            assert z[name].shape == array.shape
            assert np.array_equal(z[name], array)
    # Every entry's CRC checks (zipfile recomputes it while reading).
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        assert zf.testzip() is None


def test_a_corrupt_npz_entry_is_an_error_naming_the_file(tmp_path: Path):
    """A view's npz with a byte of its run-deflated masks changed: mgn's reader raises IoError
    naming the file (zlib's error or the entry's CRC-32), never returns other masks."""
    mask = np.zeros((4, 300, 1200), bool)
    mask[2, 100:200, 300:900] = True
    data = bytearray(npz_bytes(occlusion_objects=mask, zlib_levels={"occlusion_objects": 3}))
    path = tmp_path / "0.npz"
    for at in (len(data) // 3, len(data) // 2):  # inside the entry's zero blocks
        bad = bytearray(data)
        bad[at] ^= 0x5A
        path.write_bytes(bytes(bad))
        view = View(tmp_path, 0)
        with pytest.raises(IoError, match=r"0.npz"):
            view.npz_array("occlusion_objects")
