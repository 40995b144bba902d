"""Tests of mgn.render: the camera rig, the OSMesa renderer against Embree, depth sensors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import translation

import mgn
from mgn.io.view_images import render_views
from mgn.objects import get_object, tote_mesh
from mgn.render import Instance, Renderer, apply_depth_sensor, sensor_params, surface_flags
from mgn.scene.cameras import CameraView, Intrinsics, hemisphere_rig, mgn_rig, mgn_rig_from_params

SMALL = Intrinsics.mgn_synthetic().scaled(0.25)  # 300 x 300, same field of view


def place(spec_name: str, x: float, y: float, yaw: float = 0.0) -> tuple[mgn.Mesh, np.ndarray]:
    """A built-in object resting on the tote floor (z = 0) at (x, y), turned by yaw."""
    mesh = get_object(spec_name).to_mesh()
    X = translation(x, y, -float(np.asarray(mesh.bounds)[0, 2]))
    c, s = math.cos(yaw), math.sin(yaw)
    X[:2, :2] = [[c, -s], [s, c]]
    return mesh, X


@pytest.fixture(scope="module")
def scene() -> list[tuple[mgn.Mesh, np.ndarray, int]]:
    names = ["mug", "wine_glass", "box_cereal", "pear", "bottle_clear", "can_soda"]
    spots = [(-0.1, -0.07), (0.0, 0.0), (0.1, 0.07), (-0.1, 0.08), (0.12, -0.08), (0.0, 0.09)]
    out = []
    for k, (name, (x, y)) in enumerate(zip(names, spots, strict=True)):
        mesh, X = place(name, x, y, yaw=0.4 * k)
        out.append((mesh, X, k + 1))
    return out


def test_intrinsics_presets_and_validation() -> None:
    k = Intrinsics.mgn_synthetic()
    assert (k.width, k.height) == (1200, 1200)
    assert k.fx == pytest.approx(1200 * 35 / 20.955) == pytest.approx(2004.3, abs=0.05)
    assert (k.cx, k.cy) == (600.0, 600.0)
    z = Intrinsics.zivid_two_like()
    assert (z.width, z.height) == (1944, 1200)
    params = k.camera_params()
    assert params["horizontal_aperture"] == pytest.approx(20.955)
    assert params["resolution"] == {"height": 1200, "width": 1200}
    with pytest.raises(ValueError, match="focal"):
        Intrinsics(100, 100, 0.0, 100.0, 50.0, 50.0)
    with pytest.raises(ValueError, match="image size"):
        Intrinsics(0, 100, 100.0, 100.0, 50.0, 50.0)


def test_mgn_rig_views_look_at_the_tote_centre() -> None:
    target = np.array([0.2, -0.1, 0.3])
    poses, p = mgn_rig(123, target)
    assert poses.shape == (37, 4, 4)
    assert 0.7 <= p.R_start < 0.8
    assert 1.0 <= p.R_end < 1.4
    assert 0.3 <= p.theta_start < 0.8
    assert 0.1 <= p.theta_end < 0.3
    assert math.pi <= p.phi_end < 2 * math.pi
    # View 0 straight down from R_start.
    np.testing.assert_allclose(poses[0][:3, 2], [0, 0, -1], atol=1e-12)
    np.testing.assert_allclose(poses[0][:3, 3], target + [0, 0, p.R_start], atol=1e-12)
    for i_r in range(3):
        for i_t in range(3):
            for i_p in range(4):
                X = poses[1 + 12 * i_r + 4 * i_t + i_p]
                d = X[:3, 3] - target
                R = p.R_start + i_r * (p.R_end - p.R_start) / 2
                theta = p.theta_start + i_t * (p.theta_end - p.theta_start) / 2
                phi = i_p * p.phi_end / 4
                expected = R * np.array(
                    [
                        math.cos(phi) * math.sin(theta),
                        math.sin(phi) * math.sin(theta),
                        math.cos(theta),
                    ]
                )
                np.testing.assert_allclose(d, expected, atol=1e-12)
                # The optical axis (camera z) passes through the target.
                np.testing.assert_allclose(X[:3, 2], -d / np.linalg.norm(d), atol=1e-12)
                np.testing.assert_allclose(X[:3, :3].T @ X[:3, :3], np.eye(3), atol=1e-12)
    np.testing.assert_array_equal(mgn_rig_from_params(p, target), poses)
    np.testing.assert_array_equal(mgn_rig(123, target)[0], poses)
    custom = hemisphere_rig([0.6, 0.9], [0.2], [0.0, math.pi / 2], target)
    assert custom.shape == (4, 4, 4)
    np.testing.assert_allclose(np.linalg.norm(custom[3, :3, 3] - target), 0.9)


def test_rendered_depth_and_ids_agree_with_embree(scene) -> None:
    tote = tote_mesh()
    r = Renderer(SMALL.width, SMALL.height)
    insts = []
    for mesh, X, inst in scene:
        insts.append(Instance(r.add_mesh(mesh), X, inst))
    insts.append(Instance(r.add_mesh(tote), np.eye(4), 0, randomize_color=True))
    r.set_instances(insts)
    rays_scene = mgn.RayScene(
        [m for m, _, _ in scene] + [tote],
        np.stack([X for _, X, _ in scene] + [np.eye(4)]),
        [i for _, _, i in scene] + [0],
    )
    poses, _ = mgn_rig(5, (0, 0, 0))
    for v in (0, 14, 36):
        view = CameraView(SMALL, poses[v])
        out = r.render(view, randomize=True, seed=1, view_index=v)
        assert out.rgb.shape == (300, 300, 3)
        assert out.rgb.dtype == np.uint8
        assert out.depth.dtype == np.float32
        assert out.instance_ids.dtype == np.int32
        o, d = view.rays()
        hits = rays_scene.intersect(o, d, coherent=True)
        truth_ids = np.where(hits.hit, hits.instance_ids, 0).reshape(300, 300)
        z = (hits.distance * (d @ view.X_WC[:3, 2])).reshape(300, 300)
        objects = truth_ids > 0
        assert objects.sum() > 2000
        err = np.abs(out.depth - z)[objects]
        assert np.mean(err < 1e-3) >= 0.99, v
        assert np.mean(out.instance_ids == truth_ids) >= 0.99, v
        # Where nothing is hit the depth is 0.
        assert np.all(out.depth[~hits.hit.reshape(300, 300)] == 0)


def test_transparent_object_invalid_in_structured_light_valid_in_ideal(scene) -> None:
    glass_id = 2  # wine_glass, opacity 0.15
    assert surface_flags(scene[1][0]) & mgn.render.SURFACE_TRANSPARENT
    r = Renderer(SMALL.width, SMALL.height)
    insts = [Instance(r.add_mesh(m), X, i) for m, X, i in scene]
    insts.append(Instance(r.add_mesh(tote_mesh()), np.eye(4), 0))
    r.set_instances(insts)
    view = CameraView(SMALL, mgn_rig(2, (0, 0, 0))[0][0])
    out = r.render(view, rgb=False)
    glass = out.instance_ids == glass_id
    assert glass.sum() > 200
    flags = r.surface_flags_by_id()
    sl = apply_depth_sensor(
        out.depth, out.instance_ids, SMALL, "structured-light", flags_by_id=flags, seed=3
    )
    ideal = apply_depth_sensor(out.depth, out.instance_ids, SMALL, "ideal", flags_by_id=flags)
    tof = apply_depth_sensor(out.depth, out.instance_ids, SMALL, "tof", flags_by_id=flags, seed=3)
    assert not sl.valid[glass].any()
    assert np.isnan(sl.depth[glass]).all()
    assert not tof.valid[glass].any()
    assert ideal.valid[glass].all()
    np.testing.assert_array_equal(ideal.depth[glass], out.depth[glass])
    # Opaque objects: valid (except projector shadows) with sub-millimetre noise.
    opaque = (out.instance_ids > 0) & ~glass & (out.instance_ids != 5)  # 5: clear bottle
    ok = sl.valid & opaque
    assert ok.sum() > 0.8 * opaque.sum()
    noise = sl.depth[ok] - out.depth[ok]
    assert 0 < np.std(noise) < 1e-3
    np.testing.assert_array_equal(sl.depth_ideal, out.depth)
    # Same seed, same noise.
    params = sensor_params("structured-light")
    again = apply_depth_sensor(
        out.depth, out.instance_ids, SMALL, params, flags_by_id=flags, seed=3
    )
    np.testing.assert_array_equal(again.depth, sl.depth)
    # The same bytes for any number of threads.
    for threads in (1, 2):
        other = apply_depth_sensor(
            out.depth,
            out.instance_ids,
            SMALL,
            "tof",
            flags_by_id=flags,
            seed=3,
            num_threads=threads,
        )
        assert other.depth.tobytes() == tof.depth.tobytes()
        np.testing.assert_array_equal(other.valid, tof.valid)


def test_amodal_pass_of_a_subset(scene) -> None:
    r = Renderer(SMALL.width, SMALL.height)
    r.set_instances([Instance(r.add_mesh(m), X, i) for m, X, i in scene])
    view = CameraView(SMALL, mgn_rig(4, (0, 0, 0))[0][20])
    full = r.render(view, rgb=False, depth=False)
    assert full.rgb is None
    assert full.depth is None
    for inst in (1, 3):
        alone = r.render(view, rgb=False, depth=False, visible_instances=[inst])
        assert set(np.unique(alone.instance_ids)) <= {0, inst}
        visible = full.instance_ids == inst
        amodal = alone.instance_ids == inst
        assert np.all(amodal[visible])  # the visible mask lies inside the amodal one
        assert amodal.sum() >= visible.sum() > 0


def test_bad_input_gives_clear_errors(scene) -> None:
    r = Renderer(64, 64)
    K = Intrinsics(64, 64, 80.0, 80.0, 32.0, 32.0)
    view = CameraView(K, mgn.scene.cameras.look_at((0, 0, 1.0), (0, 0, 0), (0, 1, 0)))
    with pytest.raises(mgn.InvalidArgumentError, match="nothing to draw"):
        r.render(view)  # empty scene
    with pytest.raises(ValueError, match="non-finite"):
        CameraView(K, np.full((4, 4), np.nan))
    r.set_instances([Instance(r.add_mesh(tote_mesh()), np.eye(4), 0)])
    assert r.render(view).depth.max() > 0
    inside_wall = np.eye(4)
    inside_wall[:3, 3] = (0.204, 0.0, 0.1)  # the +x wall spans x in [0.200, 0.208]
    with pytest.raises(mgn.InvalidArgumentError, match="inside"):
        r.render(CameraView(K, inside_wall))
    with pytest.raises(mgn.InvalidArgumentError, match="at most"):
        r.render(CameraView(Intrinsics(128, 128, 80.0, 80.0, 64.0, 64.0), view.X_WC))
    with pytest.raises(ValueError, match="sensor preset"):
        sensor_params("lidar")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="empty scene"):
        render_views([], None, [0])
    with pytest.raises(ValueError, match="view index"):
        render_views(scene[:1], tote_mesh(), [37])


def test_render_views_writes_images(scene, tmp_path) -> None:
    from PIL import Image

    res = render_views(scene[:3], tote_mesh(), [0, 7], tmp_path, rig_seed=9, K=SMALL, seed=4)
    assert [r.index for r in res] == [0, 7]
    again = render_views(scene[:3], tote_mesh(), [7], None, rig_seed=9, K=SMALL, seed=4)
    np.testing.assert_array_equal(again[0].rgb, res[1].rgb)
    np.testing.assert_array_equal(again[0].depth, res[1].depth)
    for r in res:
        v = r.index
        rgb = np.asarray(Image.open(tmp_path / f"{v}_rgb.png"))
        np.testing.assert_array_equal(rgb, r.rgb)
        ids = np.asarray(Image.open(tmp_path / f"{v}_instances.png"))
        np.testing.assert_array_equal(ids, r.instance_ids)
        assert set(np.unique(ids)) <= {0, 1, 2, 3}
        assert len(np.unique(ids)) >= 3
        with np.load(tmp_path / f"{v}_depth.npz") as z:
            np.testing.assert_array_equal(z["valid_depth"], r.valid)
            np.testing.assert_allclose(z["depth"], r.depth * 100, rtol=1e-6)  # cm
            seen = r.depth_ideal > 0
            np.testing.assert_allclose(z["depth_ideal"][seen], r.depth_ideal[seen] * 100, rtol=1e-6)
            assert np.isnan(z["depth_ideal"][~seen]).all()
        with Image.open(tmp_path / f"{v}_depth.png") as im:
            assert im.mode == "P"  # a palette PNG (docs/format.md)
            pic = np.asarray(im.convert("RGB"))
        assert pic.shape == (300, 300, 3)
        assert np.all(pic[~r.valid] == 0)
    # The tote and floor are drawn with id 0 and the camera sees them: depth beyond the objects.
    assert np.all(res[0].depth_ideal > 0)


def test_builtin_textures_reach_the_mesh() -> None:
    mesh = get_object("box_cereal").to_mesh()
    data = mesh.materials[0].texture_data
    assert data[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_rig_prints_the_37_poses(capsys) -> None:
    import json

    from mgn.cli.main import main

    assert main(["render", "rig", "--seed", "5", "--target", "0", "0", "0"]) == 0
    out = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(np.asarray(out["X_WC"]), mgn_rig(5, (0, 0, 0))[0])
    assert main(["render", "demo", "/nonexistent/x", "--objects", "0"]) == 1


def test_texture_orientation_follows_the_obj_uv_convention() -> None:
    import io

    from PIL import Image

    # Texture quadrants (row 0 = top of the image): red | green over blue | white.
    tex = np.zeros((8, 8, 3), np.uint8)
    tex[:4, :4] = (255, 0, 0)
    tex[:4, 4:] = (0, 255, 0)
    tex[4:, :4] = (0, 0, 255)
    tex[4:, 4:] = (255, 255, 255)
    buf = io.BytesIO()
    Image.fromarray(tex).save(buf, format="PNG")
    mat = mgn.Material()
    mat.base_color = np.ones(4, np.float32)
    mat.texture_data = buf.getvalue()
    v = np.array([[-0.1, -0.1, 0], [0.1, -0.1, 0], [0.1, 0.1, 0], [-0.1, 0.1, 0]], np.float32)
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)  # v = 1 at the image top
    quad = mgn.Mesh(v, np.array([[0, 1, 2], [0, 2, 3]], np.int32), uv, [mat], [], "quad")
    r = Renderer(64, 64)
    r.set_instances([Instance(r.add_mesh(quad), np.eye(4), 1)])
    K = Intrinsics(64, 64, 100.0, 100.0, 32.0, 32.0)
    # Straight down, image up = world +y, image right = world +x.
    view = CameraView(K, mgn.scene.cameras.look_at((0, 0, 0.5), (0, 0, 0), (0, 1, 0)))
    rgb = r.render(view, shadows=False).rgb.astype(int)
    tl, tr, bl, br = rgb[20, 20], rgb[20, 44], rgb[44, 20], rgb[44, 44]
    assert tl[0] > 2 * max(tl[1], tl[2])  # red
    assert tr[1] > 2 * max(tr[0], tr[2])  # green
    assert bl[2] > 2 * max(bl[0], bl[1])  # blue
    assert min(br) > 0.8 * max(br)  # white (grey)
