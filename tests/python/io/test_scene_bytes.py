"""The compact view files: every array reads back bit-identical to the array written, and the
keys and dtypes MetaGraspNet's own scripts read (Scripts/visualize_2d.py, visualize_layout.py,
colored_pcl.py: np.load / h5py, the operations they apply) still work unchanged."""

from __future__ import annotations

import io
import math
import zipfile
from dataclasses import replace
from pathlib import Path

import cv2
import h5py
import numpy as np
import pytest
from PIL import Image

from mgn.base.deterministic import npz_bytes
from mgn.io.dataset import View
from mgn.io.image_codecs import (
    FLOAT_DELTA_ENCODING,
    FLOAT_GRADIENT_ENCODING,
    decode_float_gradient,
    decode_float_image,
    depth_picture_png,
    encode_float_gradient,
    encode_float_image,
)
from mgn.io.scene_folder import ARCHIVAL_DEPTH_STEP_CM, ARCHIVAL_ROTATION_STEP, write_view
from mgn.io.scene_schema import UNITS_ATTR, ViewRecord, from_cm
from mgn.render.sensor import apply_depth_sensor, sensor_params
from mgn.render.views import depth_picture, depth_picture_indexed
from mgn.scene.cameras import Intrinsics

H, W, N = 48, 64, 3


def _cm(a: np.ndarray) -> np.ndarray:
    """The writer's metre -> centimetre rule, written out: float64 product, then float32."""
    return (a.astype(np.float64) * 100.0).astype(np.float32)


def _record(rng: np.random.Generator, *, categories=(5, 300, 7), valid_is_finite=True):
    inst = rng.integers(0, N + 1, size=(H, W)).astype(np.int32)
    amodal = np.stack([(inst == i + 1) | (rng.random((H, W)) < 0.2) for i in range(N)])
    # Noisy floats: every mantissa bit carries information.
    depth = (0.6 + 0.3 * rng.random((H, W))).astype(np.float32)
    depth[rng.random((H, W)) < 0.2] = np.nan
    ideal = (0.6 + 0.3 * rng.random((H, W))).astype(np.float32)
    valid = np.isfinite(depth)
    if not valid_is_finite:
        valid = valid.copy()
        valid[0, :5] = ~valid[0, :5]
    sem = np.where(inst > 0, np.asarray(categories)[np.maximum(inst - 1, 0)], 0)
    occ_map = rng.random((H, W)).astype(np.float32)
    com = rng.random((H, W)).astype(np.float32)
    pose = np.eye(4)
    pose[:3, 3] = rng.random(3)
    X_CO = np.repeat(pose[None], N, axis=0)
    hand = np.repeat(pose[None], 5, axis=0)
    h5 = {
        "camera/pose_relative_to_world": pose[None],
        "objects/poses_relative_to_camera": X_CO,
        "objects/categories": np.asarray(categories, float),
        "objects/bbox_loose": rng.random((N, 4)) * 10,
        "non_colliding_grasps/paralleljaw/franka_poses_relative_to_camera": hand,
        "non_colliding_grasps/paralleljaw/contact_poses_relative_to_camera": hand,
        "non_colliding_grasps/paralleljaw/contact_width": rng.random(5) * 0.05,
        "non_colliding_grasps/paralleljaw/score_analytical": rng.random(5),
        "non_colliding_grasps/paralleljaw/score_simulation": rng.random(5),
        "non_colliding_grasps/paralleljaw/object_id": np.arange(5) % N,
        "non_colliding_grasps/suctioncup/suction_poses_relative_to_camera": hand,
        "keypts/com/keypts_relative_to_camera": rng.random((4, 4)),
        "keypts/com/object_id": np.arange(4) % N,
    }
    order = {str(i + 1): {"id": i + 1, "parents": [], "children": []} for i in range(N)}
    csv = "0,-1,0\n0,0,0\n0,0,0\n"
    return ViewRecord(
        index=3,
        rgb=rng.integers(0, 256, size=(H, W, 3), dtype=np.uint8),
        depth=depth,
        depth_ideal=ideal,
        valid_depth=valid,
        instances=inst,
        semantic=sem,
        occlusion_map=occ_map,
        amodal=amodal,
        intrinsics=Intrinsics(W, H, 50.0, 50.0, W / 2, H / 2),
        scene_hdf5=h5,
        order_json=order,
        order_csv=csv,
        layout_json={},
        extra_npz={"com_heatmap": com},
    )


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a).view(np.uint8)


@pytest.mark.parametrize("valid_is_finite", [True, False])
def test_view_arrays_read_back_bit_identical(tmp_path: Path, valid_is_finite: bool):
    rec = _record(np.random.default_rng(1), valid_is_finite=valid_is_finite)
    write_view(tmp_path, rec)
    with np.load(tmp_path / "3.npz") as z:
        stored = {k: z[k] for k in z.files}
    assert set(stored) == {
        "depth",
        "instances_objects",
        "instances_semantic",
        "occlusion",
        "occlusion_objects",
    }
    assert np.array_equal(_bits(stored["depth"]), _bits(_cm(rec.depth)))  # NaNs included
    assert np.array_equal(stored["instances_objects"], rec.instances)
    assert np.array_equal(stored["instances_semantic"], rec.semantic)
    assert np.array_equal(_bits(stored["occlusion"]), _bits(rec.occlusion_map))
    assert np.array_equal(stored["occlusion_objects"], rec.amodal)
    view = View(tmp_path, 3)
    assert np.array_equal(_bits(view.mgn_image("depth_ideal")), _bits(_cm(rec.depth_ideal)))
    assert np.array_equal(_bits(view.com_heatmap), _bits(rec.extra_npz["com_heatmap"]))
    assert np.array_equal(view.valid_depth, rec.valid_depth)
    with h5py.File(tmp_path / "3_mgn.hdf5", "r") as h5:
        # valid_depth is stored exactly when it cannot be derived from the depth.
        assert ("valid_depth" in h5) == (not valid_is_finite)
    assert np.array_equal(view.rgb, rec.rgb)
    # The reader gives the SI arrays back.
    assert np.array_equal(view.instances, rec.instances)
    assert np.array_equal(view.semantic, rec.semantic)


def test_category_ids_beyond_uint16_stay_float32(tmp_path: Path):
    rec = _record(np.random.default_rng(2), categories=(5, 70000, 7))
    write_view(tmp_path, rec)
    with np.load(tmp_path / "3.npz") as z:
        sem = z["instances_semantic"]
    assert sem.dtype == np.float32
    assert np.array_equal(sem, rec.semantic)


def test_metagraspnet_scripts_read_the_files_unchanged(tmp_path: Path):
    """What the published scripts do with the files, on mgn's files and on the same arrays with
    MetaGraspNet's original float32 ids: the results agree."""
    rec = _record(np.random.default_rng(3))
    write_view(tmp_path, rec)
    with np.load(str(tmp_path / "3.npz")) as data:
        depth = data["depth"]
        instances_objects = data["instances_objects"]
        instances_semantic = data["instances_semantic"]
        occlusion = data["occlusion"]
        occlusion_masks = data["occlusion_objects"]
    original_ids = rec.instances.astype(np.float32)  # MetaGraspNet's dtype
    # visualize_layout.py: the object count and one mask per object.
    num = len(np.unique(instances_objects)) - 1
    assert num == len(np.unique(original_ids)) - 1 == N
    for i in range(num):
        assert np.array_equal(instances_objects == (i + 1), original_ids == (i + 1))
    # visualize_2d.py: per-pixel ids into a uint8 label image, occlusion in percent, contours of
    # the amodal masks.
    seg = np.zeros(depth.shape, dtype=np.uint8)
    nz = instances_objects != 0
    seg[nz] = [int(x) for x in instances_objects[nz]]
    assert np.array_equal(seg, original_ids.astype(np.uint8))
    assert (occlusion * 100).dtype == np.float32
    assert np.array_equal(np.asarray(instances_semantic, np.float32), rec.semantic)
    # The amodal masks keep MetaGraspNet's bool (N, H, W) (contoured at level 0.8 there).
    assert occlusion_masks.dtype == bool
    assert np.array_equal(occlusion_masks, rec.amodal)
    # colored_pcl.py: NaN -> 0 in a float32 depth (Open3D wants float32), cm -> m by 100.
    assert depth.dtype == np.float32
    assert depth.flags.c_contiguous
    depth[np.isnan(depth)] = 0.0
    f = h5py.File(str(tmp_path / "3_scene.hdf5"), "r")
    try:
        g = f["non_colliding_grasps"]["paralleljaw"]
        poses = list(g["franka_poses_relative_to_camera"])
        widths = list(g["contact_width"])
        ids = list(g["object_id"])
        sa, ss = list(g["score_analytical"]), list(g["score_simulation"])
        assert len(poses) == len(widths) == len(ids) == len(sa) == len(ss) == 5
        for grasp_transform in poses:
            before = grasp_transform[0, 3]
            grasp_transform[0, 3] /= 100  # in place: needs a float dtype
            assert grasp_transform[0, 3] == np.float32(before) / np.float32(100)
        for name in ("contact_poses_relative_to_camera",):
            assert g[name].dtype == np.float32
        assert f["non_colliding_grasps"]["suctioncup"][
            "suction_poses_relative_to_camera"
        ].dtype == (np.float32)
        keypts = list(f["keypts"]["com"]["keypts_relative_to_camera"])
        assert all(k.dtype == np.float32 and k.shape == (4,) for k in keypts)
    finally:
        f.close()
    # visualize_layout.py reads the order matrix with np.loadtxt.
    order_mat = np.loadtxt(str(tmp_path / "3_order.csv"), delimiter=",")
    assert order_mat.shape == (N, N)


def test_sensor_depth_on_its_grid_is_stored_on_the_grid_and_reads_back_in_metres(tmp_path: Path):
    """The sensor presets report z on power-of-two multiples of a 1/256 cm grid: the npz holds exact
    multiples of it (float32 cm, MetaGraspNet's dtype) and the reader's metres equal the sensor's
    float32 bit for bit."""
    rng = np.random.default_rng(4)
    K = Intrinsics(W, H, 50.0, 50.0, W / 2, H / 2)
    ideal = (0.5 + 0.7 * rng.random((H, W))).astype(np.float32)
    ids = np.ones((H, W), np.int32)
    for preset, step_cm in (("structured-light", 2.0**-8), ("tof", 2.0**-6)):
        sensed = apply_depth_sensor(ideal, ids, K, preset, seed=7)
        assert sensed.valid.mean() > 0.5
        rec = replace(_record(rng), depth=sensed.depth, valid_depth=sensed.valid)
        write_view(tmp_path, rec)
        with np.load(tmp_path / "3.npz") as z:
            stored = z["depth"]
        assert stored.dtype == np.float32
        ok = np.isfinite(stored)
        assert np.array_equal(ok, sensed.valid)
        k = stored[ok].astype(np.float64) / step_cm
        assert np.array_equal(k, np.round(k))  # exact multiples of the preset's grid
        # Within half a step of the sensor's metres, and the metres come back bit for bit.
        assert np.abs(stored[ok] - sensed.depth[ok].astype(np.float64) * 100).max() < 1e-4
        assert np.array_equal(_bits(View(tmp_path, 3).depth), _bits(sensed.depth))
        if preset == "structured-light":
            # The grid grows with the noise (docs/cameras.md): at each pixel the coarsest
            # 2^k * 1/256 cm not above sigma(z) / 2, sigma = 0.1 mm + 0.2 mm/m^2 z^2.
            p = sensor_params(preset)
            z = ideal.astype(np.float64)
            half = 0.5 * (p.sigma_a + p.sigma_b * (z - p.sigma_z0) ** 2)
            grid = np.full(z.shape, p.depth_step)
            for _ in range(16):
                grid = np.where(grid * 2.0 <= half, grid * 2.0, grid)
            grid_cm = (grid * 100.0)[ok]
            k = stored[ok].astype(np.float64) / grid_cm
            assert np.array_equal(k, np.round(k))
            assert (grid_cm >= 2.0**-7).mean() > 0.5  # coarser than 1/256 cm beyond 0.53 m
            assert np.any(np.round(k) % 2 == 1)  # and not coarser than that


def test_float_images_round_trip_every_bit_pattern():
    """The delta coding of mgn's float images restores any float32 bit pattern (NaN payloads,
    infinities, -0.0, subnormals, jumps that overflow int32)."""
    rng = np.random.default_rng(5)
    bits = rng.integers(-(2**31), 2**31, size=(7, 33), dtype=np.int64).astype(np.int32)
    a = bits.view(np.float32).copy()
    a[0, :6] = [np.nan, np.inf, -np.inf, -0.0, 1e-45, np.finfo(np.float32).max]
    coded = encode_float_image(a)
    assert coded.dtype == np.int32
    assert np.array_equal(_bits(decode_float_image(coded)), _bits(a))
    # A smooth image gives small differences (what makes deflate effective).
    ramp = np.linspace(70.0, 71.0, 64, dtype=np.float32)[None, :].repeat(3, 0)
    assert np.abs(encode_float_image(ramp)[:, 1:]).max() < 2**16
    # The gradient coding too (and on a single row / column).
    for image in (a, a[:1], a[:, :1]):
        coded = encode_float_gradient(image)
        assert coded.dtype == np.int32
        assert coded.shape == image.shape
        assert np.array_equal(_bits(decode_float_gradient(coded)), _bits(image))


def test_gradient_coding_leaves_zigzagged_residuals_of_the_bit_patterns():
    """The coded value of pixel (y, x) is zigzag(b[y, x] - b[y, x-1] - b[y-1, x] + b[y-1, x-1])
    of the bit patterns b (missing neighbours 0), computed here pixel by pixel in Python ints: zero
    on a plane of bit patterns, small non-negative numbers for small residuals of either sign."""
    rng = np.random.default_rng(12)
    h, w = 6, 9
    bits = 0x42C80000 + 3 * np.arange(w)[None, :] + 7 * np.arange(h)[:, None]  # a plane
    bits = bits + rng.integers(-2, 3, size=(h, w))  # small residuals
    bits[2, 4] = 0x7FC00000  # NaN
    image = bits.astype(np.uint32).view(np.float32)
    coded = encode_float_gradient(image)

    def b(y: int, x: int) -> int:
        return int(bits[y, x]) if y >= 0 and x >= 0 else 0

    for y in range(h):
        for x in range(w):
            r = (b(y, x) - b(y, x - 1) - b(y - 1, x) + b(y - 1, x - 1) + 2**31) % 2**32 - 2**31
            zigzag = 2 * r if r >= 0 else -2 * r - 1  # 0 .. 2^32 - 1, stored as int32 bits
            assert int(coded[y, x]) % 2**32 == zigzag, (y, x)
    # Away from the NaN (rows 2-3) and the first column the residuals are four noise terms of
    # at most 2 each: |r| <= 8, zigzagged <= 16.
    assert 0 <= coded[4:, 1:].min()
    assert coded[4:, 1:].max() <= 16


def test_mgn_images_are_stored_delta_coded_and_read_back(tmp_path: Path):
    rec = _record(np.random.default_rng(6))
    write_view(tmp_path, rec)
    with h5py.File(tmp_path / "3_mgn.hdf5", "r") as h5:
        for name in ("depth_ideal", "com_heatmap"):
            assert h5[name].dtype == np.int32
            assert h5[name].attrs["mgn_encoding"] == FLOAT_GRADIENT_ENCODING
    view = View(tmp_path, 3)
    assert np.array_equal(_bits(view.mgn_image("depth_ideal")), _bits(_cm(rec.depth_ideal)))
    assert np.array_equal(_bits(view.com_heatmap), _bits(rec.extra_npz["com_heatmap"]))
    # Files written before the gradient coding (row differences) still read back.
    (tmp_path / "3_mgn.hdf5").unlink()
    with h5py.File(tmp_path / "3_mgn.hdf5", "w") as h5:
        h5["depth_ideal"] = encode_float_image(rec.depth_ideal)
        h5["depth_ideal"].attrs["mgn_encoding"] = FLOAT_DELTA_ENCODING
        h5["depth_ideal"].attrs[UNITS_ATTR] = "m"
    old = View(tmp_path, 3)
    assert np.array_equal(_bits(old.depth_ideal), _bits(rec.depth_ideal))


def rng_noise(h: int, w: int) -> np.ndarray:
    return np.random.default_rng(11).standard_normal((h, w))


def test_depth_picture_is_a_palette_png_that_reads_as_the_rgb_picture(tmp_path: Path):
    rec = _record(np.random.default_rng(7))
    # 100 depth levels and invalid pixels: 101 colours.
    depth = np.repeat(np.linspace(0.6, 0.9, 100, dtype=np.float32), H * W // 100 + 1)[: H * W]
    depth = depth.reshape(H, W)
    depth[:3] = np.nan
    # The picture is of the noise-free depth where the sensor gives a value (docs/format.md);
    # the sensor depth differs from it by noise and has invalid pixels of its own.
    sensor = (depth + np.float32(1e-3) * np.float32(rng_noise(H, W))).astype(np.float32)
    sensor[5:7] = np.nan
    rec = replace(rec, depth=sensor, depth_ideal=depth, valid_depth=np.isfinite(sensor))
    write_view(tmp_path, rec)
    with Image.open(tmp_path / "3_depth.png") as im:
        assert im.mode == "P"
        rgb = np.asarray(im.convert("RGB"))
    # The noise-free depth where the sensor has a value, black where it has none.
    assert np.array_equal(rgb, depth_picture(np.where(np.isfinite(sensor), depth, np.nan)))
    assert not np.array_equal(rgb, depth_picture(rec.depth))
    assert (rgb[:3] == 0).all()
    assert (rgb[5:7] == 0).all()
    assert (rgb[7:] != 0).any(axis=-1).all()
    # OpenCV, as MetaGraspNet's scripts read their PNGs, gives the same picture (BGR).
    bgr = cv2.imread(str(tmp_path / "3_depth.png"), cv2.IMREAD_COLOR)
    assert np.array_equal(bgr[..., ::-1], rgb)
    assert np.array_equal(cv2.imread(str(tmp_path / "3_rgb.png"))[..., ::-1], rec.rgb)
    # Every level and invalid pixels still fit one palette; the picture spans the colour map.
    depth = np.concatenate([1.0 / np.linspace(1.0, 2.0, 1000), [np.nan]]).astype(np.float32)
    depth = depth.reshape(1, -1)
    with Image.open(io.BytesIO(depth_picture_png(depth))) as im:
        assert im.mode == "P"
        rgb = np.asarray(im.convert("RGB"))
    assert np.array_equal(rgb, depth_picture(depth))
    index, palette = depth_picture_indexed(depth)
    assert len(np.unique(index)) == len(palette) == 256  # black and all 255 levels
    assert (rgb[0, -1] == 0).all()


def test_archival_mode_rounds_depth_to_its_grid_and_keeps_the_metagraspnet_dtypes(tmp_path: Path):
    rng = np.random.default_rng(8)
    rec = _record(rng)
    exact, arch = tmp_path / "exact", tmp_path / "archival"
    write_view(exact, rec)
    write_view(arch, rec, archival=True)
    with np.load(arch / "3.npz") as z, np.load(exact / "3.npz") as e:
        assert {k: z[k].dtype for k in z.files} == {k: e[k].dtype for k in e.files}
        d = z["depth"]
        assert np.array_equal(e["occlusion_objects"], z["occlusion_objects"])
    ok = np.isfinite(d)
    assert np.array_equal(ok, np.isfinite(rec.depth))
    step = ARCHIVAL_DEPTH_STEP_CM
    k = d[ok].astype(np.float64) / step
    assert np.array_equal(k, np.round(k))
    # At most half a step (0.078 mm) from the model's depth, for the sensor and the ideal depth.
    assert np.abs(d[ok] - _cm(rec.depth)[ok]).max() <= step / 2 + 1e-5
    view = View(arch, 3)
    ideal = view.mgn_image("depth_ideal")
    assert np.abs(ideal - _cm(rec.depth_ideal)).max() <= step / 2 + 1e-5
    com = view.com_heatmap
    assert com.dtype == np.float32
    assert np.abs(com - rec.extra_npz["com_heatmap"]).max() <= 0.5 / 65535 + 1e-7
    assert np.array_equal(view.valid_depth, rec.valid_depth)
    size = {p.name: p.stat().st_size for p in arch.iterdir()}
    assert size["3_mgn.hdf5"] < (exact / "3_mgn.hdf5").stat().st_size
    # The depth is an LZMA zip entry (np.load reads it, above), the others deflate; the RGB PNG
    # (another zlib level) reads back the same pixels with PIL and OpenCV.
    with zipfile.ZipFile(arch / "3.npz") as zf:
        methods = {i.filename: i.compress_type for i in zf.infolist()}
    assert methods.pop("depth.npy") == zipfile.ZIP_LZMA
    assert set(methods.values()) == {zipfile.ZIP_DEFLATED}
    assert np.array_equal(np.asarray(Image.open(arch / "3_rgb.png")), rec.rgb)
    assert np.array_equal(cv2.imread(str(arch / "3_rgb.png"))[..., ::-1], rec.rgb)
    # Grasp poses: float32, rotations within 2^-17 and translations within 1/2048 cm of the
    # exact file; object poses and scores exact.
    with h5py.File(arch / "3_scene.hdf5", "r") as a, h5py.File(exact / "3_scene.hdf5", "r") as e:
        g = "non_colliding_grasps/paralleljaw/franka_poses_relative_to_camera"
        assert a[g].dtype == np.float32
        assert a[g].shape == e[g].shape
        pa, pe = a[g][()], e[g][()]
        assert np.abs(pa[:, :3, :3] - pe[:, :3, :3]).max() <= 2.0**-17 + 1e-7
        assert np.abs(pa[:, :3, 3] - pe[:, :3, 3]).max() <= 2.0**-11 + 1e-5
        assert np.array_equal(pa[:, 3], pe[:, 3])
        k = pa[:, :3, :3].astype(np.float64) / ARCHIVAL_ROTATION_STEP
        assert np.array_equal(k, np.round(k))
        for key in (
            "objects/poses_relative_to_camera",
            "non_colliding_grasps/paralleljaw/score_analytical",
        ):
            assert np.array_equal(a[key][()], e[key][()])


def _random_poses(rng: np.random.Generator, m: int) -> np.ndarray:
    """(m, 4, 4) rigid poses with random rotations (QR of Gaussian matrices), metres."""
    q, r = np.linalg.qr(rng.normal(size=(m, 3, 3)))
    q = q * np.sign(np.diagonal(r, axis1=1, axis2=2))[:, None, :]
    q[np.linalg.det(q) < 0, :, 0] *= -1
    X = np.repeat(np.eye(4)[None], m, axis=0)
    X[:, :3, :3] = q
    X[:, :3, 3] = rng.normal(size=(m, 3)) * 0.2 + [0.0, 0.0, 0.8]
    return X


def _moved_along_axes(X: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """The poses X moved by ``offset`` (3,) expressed in their own axes (same rotation)."""
    out = X.copy()
    out[:, :3, 3] = X[:, :3, 3] + np.einsum("mij,j->mi", X[:, :3, :3], offset)
    return out


def _grasp_record(rng: np.random.Generator, m: int = 700, k: int = 300) -> ViewRecord:
    """A record whose tool poses share their rotation with the contact poses (as the grasp
    labels do: the flange and the suction tool sit on the contact frame's approach axis), except
    the colliding suction group, whose rotations differ."""
    rec = _record(rng)
    h5 = dict(rec.scene_hdf5)
    pj_contact = _random_poses(rng, m)
    su_contact = _random_poses(rng, k)
    other = _random_poses(rng, k)
    for group in ("non_colliding_grasps", "colliding_grasps"):
        h5[f"{group}/paralleljaw/contact_poses_relative_to_camera"] = pj_contact
        h5[f"{group}/paralleljaw/franka_poses_relative_to_camera"] = _moved_along_axes(
            pj_contact, np.array([0.01, 0.0, -0.1041])
        )
        h5[f"{group}/paralleljaw/object_id"] = np.arange(m) % N
        h5[f"{group}/suctioncup/contact_poses_relative_to_camera"] = su_contact
        h5[f"{group}/suctioncup/object_id"] = np.arange(k) % N
    h5["non_colliding_grasps/suctioncup/suction_poses_relative_to_camera"] = _moved_along_axes(
        su_contact, np.array([0.0, 0.0, -0.1321])
    )
    h5["colliding_grasps/suctioncup/suction_poses_relative_to_camera"] = other
    h5["colliding_grasps/suctioncup/score_analytical"] = rng.random(k)
    return replace(rec, scene_hdf5=h5)


@pytest.mark.parametrize("archival", [False, True])
def test_tool_poses_sharing_the_contact_rotation_read_back_bit_identical(
    tmp_path: Path, archival: bool
):
    """Tool poses whose rotation equals the contact poses' are virtual datasets over them; what
    h5py reads (as MetaGraspNet's colored_pcl.py does: whole, and row by row with ``list``) and
    what mgn.Dataset reads are the arrays written, bit for bit; other tool poses stay plain."""
    rec = _grasp_record(np.random.default_rng(11))
    write_view(tmp_path, rec, archival=archival)
    # The arrays the writer stores: float32 cm (archival: on the archival grids), computed here
    # independently of the file.
    ref = {
        path: _cm_pose(np.asarray(a), archival)
        for path, a in rec.scene_hdf5.items()
        if path.endswith("poses_relative_to_camera") and "grasps/" in path
    }
    virtual = {
        "non_colliding_grasps/paralleljaw/franka_poses_relative_to_camera",
        "colliding_grasps/paralleljaw/franka_poses_relative_to_camera",
        "non_colliding_grasps/suctioncup/suction_poses_relative_to_camera",
    }
    with h5py.File(str(tmp_path / "3_scene.hdf5"), "r") as f:
        for path, expected in ref.items():
            ds = f[path]
            assert ds.is_virtual == (path in virtual), path
            assert ds.dtype == np.float32
            assert ds.shape == expected.shape
            assert np.array_equal(_bits(ds[()]), _bits(expected)), path
            rows = list(ds)
            assert len(rows) == len(expected)
            assert np.array_equal(_bits(np.stack(rows)), _bits(expected)), path
            # colored_pcl.py scales the translation of each row in place.
            rows[0][0, 3] /= 100
        # The suction contact poses are chunked by their first three rows, unshuffled (repeated
        # rotations), the parallel-jaw ones by entry.
        su = f["colliding_grasps/suctioncup/contact_poses_relative_to_camera"]
        assert su.chunks == (300, 3, 4)
        assert not su.shuffle
        assert f["colliding_grasps/paralleljaw/contact_poses_relative_to_camera"].chunks == (
            700,
            1,
            1,
        )
    view = View(tmp_path, 3)
    assert not any(k.startswith("mgn_pose_columns") for k in view.hdf5)
    for path, expected in ref.items():
        back = view.hdf5[path]
        # The reader's metre conversion of the stored cm (the same for plain datasets).
        assert np.array_equal(_bits(back), _bits(from_cm(path, expected))), path
        assert np.array_equal(_bits(view.hdf5_dataset(path)), _bits(back)), path


def _cm_pose(X: np.ndarray, archival: bool) -> np.ndarray:
    """The float32 cm poses the writer stores (archival: rotation entries on 2^-16, translations
    on ARCHIVAL_POSE_STEP_CM), written out independently of the writer."""
    out = X.astype(np.float64)
    out[:, :3, 3] *= 100.0
    out = out.astype(np.float32)
    if archival:
        rs, ts = np.float32(ARCHIVAL_ROTATION_STEP), np.float32(2.0**-10)
        out[:, :3, :3] = np.round(out[:, :3, :3] / rs) * rs
        out[:, :3, 3] = np.round(out[:, :3, 3] / ts) * ts
    return out


def _com_by_hand(depth_m, inst, X_WC, K, params) -> np.ndarray:
    """The heat map of docs/models.md §7 pixel by pixel in plain Python floats."""
    fx, fy, cx, cy = K
    out = np.zeros(inst.shape, np.float32)
    for v in range(inst.shape[0]):
        for u in range(inst.shape[1]):
            i, z = int(inst[v, u]), float(depth_m[v, u])
            if i == 0 or not np.isfinite(z) or z <= 0:
                continue
            p = [z * (u + 0.5 - cx) / fx, z * (v + 0.5 - cy) / fy, z]
            w = [
                sum(float(X_WC[r, k]) * p[k] for k in range(3)) + float(X_WC[r, 3])
                for r in range(3)
            ]
            c = params[i - 1]
            d = math.sqrt(sum((w[r] - c[r]) ** 2 for r in range(3)))
            span = max(c[4] - c[3], 1e-12)
            out[v, u] = min(max((c[4] - d) / span, 0.0), 1.0)
    return out


@pytest.mark.parametrize("exact", [True, False])
def test_com_heatmap_stored_as_residual_reads_back_bit_identical(tmp_path: Path, exact: bool):
    """With the scene's CoM parameters the heat map is stored as its difference from the
    prediction: a heat map that is the formula (computed here pixel by pixel) leaves a zero
    residual, any other (noise added) still reads back bit for bit; depth_ideal is kept in
    metres, bit for bit, and read in cm as before."""
    rng = np.random.default_rng(21)
    rec = _record(rng)
    X_WC = np.asarray(rec.scene_hdf5["camera/pose_relative_to_world"], float).reshape(4, 4)
    k = rec.intrinsics
    # Centres of mass near the seen surface (0.75 m in front of the camera), heat maps that
    # range over [0, 1] across the image.
    c_W = (X_WC @ [0.0, 0.0, 0.75, 1.0])[:3] + rng.normal(size=(N, 3)) * 0.05
    params = np.column_stack([c_W, 0.01 + 0.02 * rng.random(N), 0.4 + 0.2 * rng.random(N)])
    com = _com_by_hand(rec.depth_ideal, rec.instances, X_WC, (k.fx, k.fy, k.cx, k.cy), params)
    assert np.count_nonzero(com) > H * W // 4  # a real heat map, not zeros
    if not exact:
        com = com + rng.normal(size=com.shape).astype(np.float32) * 1e-3
    rec = replace(rec, extra_npz={"com_heatmap": com}, com_parameters=params)
    write_view(tmp_path, rec)
    with h5py.File(tmp_path / "3_mgn.hdf5", "r") as h5:
        assert h5["com_heatmap"].attrs["mgn_encoding"] == "float32-bits-minus-com-prediction"
        assert h5["com_heatmap"].dtype == np.int32
        assert (not np.any(h5["com_heatmap"][()])) == exact
        assert h5["depth_ideal"].attrs["mgn_units"] == "m"
    view = View(tmp_path, 3)
    assert np.array_equal(_bits(view.com_heatmap), _bits(com))
    assert np.array_equal(_bits(view.depth_ideal), _bits(rec.depth_ideal))
    assert np.array_equal(
        _bits(View(tmp_path, 3).mgn_image("depth_ideal")), _bits(_cm(rec.depth_ideal))
    )


def test_archival_mode_with_com_parameters_keeps_the_mgn_images_exact(tmp_path: Path):
    """Archival mode with the CoM parameters: the sensor depth is rounded, but depth_ideal and
    the heat map (its residual from the prediction) read back bit for bit."""
    rng = np.random.default_rng(22)
    rec = _record(rng)
    X_WC = np.asarray(rec.scene_hdf5["camera/pose_relative_to_world"], float).reshape(4, 4)
    k = rec.intrinsics
    c_W = (X_WC @ [0.0, 0.0, 0.75, 1.0])[:3] + rng.normal(size=(N, 3)) * 0.05
    params = np.column_stack([c_W, 0.01 + 0.02 * rng.random(N), 0.4 + 0.2 * rng.random(N)])
    com = _com_by_hand(rec.depth_ideal, rec.instances, X_WC, (k.fx, k.fy, k.cx, k.cy), params)
    rec = replace(rec, extra_npz={"com_heatmap": com}, com_parameters=params)
    write_view(tmp_path, rec, archival=True)
    with h5py.File(tmp_path / "3_mgn.hdf5", "r") as h5:
        assert h5["com_heatmap"].attrs["mgn_encoding"] == "float32-bits-minus-com-prediction"
        assert h5["depth_ideal"].attrs["mgn_units"] == "m"
        assert h5["depth_ideal"].compression == "gzip"  # level 6 in the archival mode
        assert h5["depth_ideal"].compression_opts == 6
        assert h5["depth_ideal"].compression == "gzip"  # level 6 in the archival mode
        assert h5["depth_ideal"].compression_opts == 6
    view = View(tmp_path, 3)
    assert np.array_equal(_bits(view.com_heatmap), _bits(com))
    assert np.array_equal(_bits(view.depth_ideal), _bits(rec.depth_ideal))
    step = np.float32(ARCHIVAL_DEPTH_STEP_CM)
    stored = view.npz_array("depth")
    finite = np.isfinite(stored)
    assert np.all(np.round(stored[finite] / step) * step == stored[finite])


def test_npz_lzma_entries_read_back_bit_identical_and_reproducibly():
    """An LZMA entry (the archival sensor depth) is read by np.load bit for bit, the same bytes
    every time, and smaller than deflate on a noisy float32 image on a grid."""
    rng = np.random.default_rng(31)
    depth = (np.round((70.0 + 0.03 * rng.standard_normal((120, 160))) * 256) / 256).astype(
        np.float32
    )
    depth[rng.random(depth.shape) < 0.05] = np.nan
    arrays = {"depth": depth, "occlusion_objects": rng.random((2, 120, 160)) < 0.5}
    a = npz_bytes(**arrays, lzma_entries=("depth",))
    assert a == npz_bytes(**arrays, lzma_entries=("depth",))
    with np.load(io.BytesIO(a)) as z:
        assert np.array_equal(_bits(z["depth"]), _bits(depth))
        assert np.array_equal(z["occlusion_objects"], arrays["occlusion_objects"])
    with zipfile.ZipFile(io.BytesIO(a)) as zf:
        info = zf.getinfo("depth.npy")
        assert info.compress_type == zipfile.ZIP_LZMA
        assert info.compress_size < 0.9 * _deflated_size(npz_bytes(depth=depth), "depth.npy")


def _deflated_size(data: bytes, name: str) -> int:
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        return zf.getinfo(name).compress_size
