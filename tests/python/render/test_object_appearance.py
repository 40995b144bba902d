"""The object-appearance part of the path engine's randomisation
(``render.randomize.object_appearance``, :func:`mgn.render.lighting.draw_object_materials`):
off by default and then without effect on the photograph, drawn per (seed, view, object),
the probability and the colour ranges honoured, glass kept, bad settings named."""

from __future__ import annotations

import colorsys
from typing import Any

import numpy as np
import pytest

import mgn
from mgn.errors import InvalidArgumentError
from mgn.io.image_codecs import png_bytes
from mgn.objects import tote_mesh
from mgn.pipeline.config import ConfigError, load_config
from mgn.render import lighting, materials, photo
from mgn.render.lighting import draw_lighting, draw_object_materials
from mgn.render.path import FilmOptions, PathScene, PathTraceOptions, PbrMaterial, develop
from mgn.render.settings import RandomizeSettings, RenderSettings
from mgn.scene.cameras import CameraView, Intrinsics, look_at

# Undenoised, 2 samples: cheap, and the image is the tracer's alone.
_TRACE: dict[str, Any] = {"engine": "path", "spp": 2, "spp_without_denoiser": 2, "denoise": False}


def _settings(on: bool, **randomize: Any) -> RenderSettings:
    return RenderSettings(**_TRACE, randomize=RandomizeSettings(object_appearance=on, **randomize))


def _scene() -> tuple[list[tuple[mgn.Mesh, np.ndarray, int]], mgn.Mesh]:
    # A printed box (own uvs and texture), a can, clear glass and a metal nut.
    items = []
    placed = [
        ("box_tea", (-0.08, -0.04)),
        ("can_soda", (0.07, 0.05)),
        ("bottle_clear", (0.05, -0.08)),
        ("hex_nut", (-0.06, 0.08)),
    ]
    for k, (name, xy) in enumerate(placed):
        mesh = mgn.objects.get_object(name).to_mesh()
        X = np.eye(4)
        X[:3, 3] = (*xy, -float(np.asarray(mesh.bounds)[0, 2]))
        items.append((mesh, X, k + 1))
    return items, tote_mesh()


def _view(size: int = 48) -> CameraView:
    K = Intrinsics.mgn_synthetic().scaled(size / 1200.0)
    return CameraView(K, look_at((0.15, -0.25, 0.75), (0.0, 0.0, 0.03)))


def _key(m: PbrMaterial) -> tuple[Any, ...]:
    tex = None if m.base_color_texture is None else m.base_color_texture.tobytes()
    return (m, tex)


def _srgb_hsv(m: PbrMaterial) -> tuple[float, float, float]:
    c = np.asarray(m.base_color, np.float64)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    return colorsys.rgb_to_hsv(*(float(x) for x in s))


def test_off_by_default_and_then_the_photograph_is_unchanged() -> None:
    """Off (the default), the photograph equals a second implementation of the engine without
    the part: the scene's own meshes and materials, the lighting of (seed, view), traced and
    developed."""
    assert not RandomizeSettings().object_appearance
    items, tote = _scene()
    s = _settings(False)
    seed, v, view = 4, 3, _view()
    got, _ = photo.PhotoRenderer(items, tote, np.eye(4), None, s, seed=seed).render(view, v)
    lit = draw_lighting(s, seed, v)
    mats = [[materials.pbr_material(m) for m in mesh.materials] for mesh, _, _ in items]
    scene = PathScene(
        [m for m, _, _ in items] + [materials.box_uv_mesh(tote, materials.TEXTURE_TILE, "tote")],
        np.stack([X for _, X, _ in items] + [np.eye(4)]),
        [i for _, _, i in items] + [0],
        [*mats, [lit.tote] * max(1, len(tote.materials))],
        lit.lights,
        lit.environment,
    )
    out = scene.render(
        view,
        PathTraceOptions(
            spp=2, max_bounces=s.max_bounces, seed=seed, view_index=v, clamp=s.clamp, labels=False
        ),
    )
    want = develop(
        out.radiance, FilmOptions(exposure=lit.exposure, tone=s.tone, seed=seed, view_index=v)
    )
    assert png_bytes(got) == png_bytes(want)
    # Switched on with probability 0, only the objects' uv layout differs (box-projected uvs
    # for meshes without their own, unused): the same photograph.
    zero_s = _settings(True, object_probability=0.0)
    zero = photo.PhotoRenderer(items, tote, np.eye(4), None, zero_s, seed=seed)
    assert png_bytes(zero.render(view, v)[0]) == png_bytes(got)
    # With probability 1 the objects change, and nothing but the objects' materials is drawn
    # differently: the lighting of the view is the same.
    one_s = _settings(True, object_probability=1.0)
    one = photo.PhotoRenderer(items, tote, np.eye(4), None, one_s, seed=seed)
    assert png_bytes(one.render(view, v)[0]) != png_bytes(got)
    assert repr(one.lighting(v)) == repr(
        photo.PhotoRenderer(items, tote, np.eye(4), None, s, seed=seed).lighting(v)
    )


def test_drawn_from_seed_view_and_object_only() -> None:
    s = _settings(True, object_probability=1.0)
    base = (PbrMaterial(base_color=(0.5, 0.2, 0.1)), PbrMaterial(base_color=(0.1, 0.1, 0.1)))

    def draw(seed: int, v: int, obj: int) -> tuple[Any, ...]:
        return tuple(_key(m) for m in draw_object_materials(s, seed, v, obj, base))

    a = draw(7, 3, 2)
    assert a == draw(7, 3, 2)
    assert a != draw(7, 4, 2)
    assert a != draw(8, 3, 2)
    assert a != draw(7, 3, 1)
    # One object's draw does not depend on the number or materials of the others.
    alone = draw_object_materials(s, 7, 3, 2, base[:1])
    assert _key(alone[0]) == _key(draw_object_materials(s, 7, 3, 2, base)[0])
    # Off, or with the scene's randomisation off: the materials as given.
    assert draw_object_materials(_settings(False), 7, 3, 2, base) == base
    assert draw_object_materials(s, 7, 3, 2, base, randomize=False) == base


def test_photograph_independent_of_other_views_and_threads() -> None:
    items, tote = _scene()
    s = _settings(True)
    pngs = []
    for threads, views in ((1, (5,)), (2, (2, 0, 5))):
        pr = photo.PhotoRenderer(items, tote, np.eye(4), None, s, seed=9, num_threads=threads)
        for v in views:
            rgb, _ = pr.render(_view(), v)
        pngs.append(png_bytes(rgb))
    assert pngs[0] == pngs[1]


def test_probability_ranges_and_glass() -> None:
    glass = PbrMaterial(base_color=(1.0, 1.0, 1.0), roughness=0.02, transmission=1.0)
    metal = PbrMaterial(base_color=(0.7, 0.7, 0.7), metallic=1.0, roughness=0.2)
    base = (PbrMaterial(base_color=(0.5, 0.2, 0.1)), glass, metal)
    n = 1500
    hsv: list[tuple[float, float, float]] = []
    for p in (0.2, 0.5):
        s = _settings(True, object_probability=p)
        changed, rough, kinds = 0, [], set()
        for k in range(n):
            out = draw_object_materials(s, 1, k // 20, k % 20 + 1, base)
            assert out[1] is glass  # glass (transmission > 0) is kept
            if out[0] is base[0]:
                assert out[2] is metal
                continue
            changed += 1
            for m in (out[0], out[2]):  # a metal slot becomes a painted (dielectric) one
                assert m.metallic == 0.0
                assert m.transmission == 0.0
                rough.append(m.roughness)
                if m.base_color_texture is None:
                    kinds.add("plain")
                    hsv.append(_srgb_hsv(m))
                else:
                    # A pattern between two colours on a white base: no texel is brighter
                    # than the brightest colour allowed (a blend's largest channel is at most
                    # the larger of the two colours' largest channels).
                    kinds.add("pattern")
                    assert m.base_color == (1.0, 1.0, 1.0)
                    assert m.base_color_texture.max() <= 255 * s.randomize.object_value[1] + 1
                    texels = np.unique(m.base_color_texture.reshape(-1, 3), axis=0)
                    assert len(texels) >= 2
        # Binomial count of replaced objects: within 5 standard deviations of n p.
        assert abs(changed - n * p) < 5 * np.sqrt(n * p * (1 - p)), (p, changed)
        h = np.asarray(hsv)
        r = s.randomize
        assert np.all(
            (h[:, 1] >= r.object_saturation[0] - 1e-6) & (h[:, 1] <= r.object_saturation[1] + 1e-6)
        )
        assert np.all((h[:, 2] >= r.object_value[0] - 1e-6) & (h[:, 2] <= r.object_value[1] + 1e-6))
        assert np.all(
            (np.asarray(rough) >= r.object_roughness[0])
            & (np.asarray(rough) <= r.object_roughness[1])
        )
        assert kinds == {"plain", "pattern"}
    # Black / dark grey, white and saturated colours of every hue occur among the ~520 plain
    # colours (black / dark grey: value < 0.15 and saturation < 0.2, 2.2 % of the draws).
    h = np.asarray(hsv)
    assert np.sum((h[:, 2] < 0.15) & (h[:, 1] < 0.2)) >= 2
    assert np.sum((h[:, 2] > 0.85) & (h[:, 1] < 0.2)) >= 2
    assert len(np.unique(np.floor(h[h[:, 1] > 0.5, 0] * 6))) == 6
    # A narrower value range is honoured.
    s = _settings(True, object_probability=1.0, object_value=(0.1, 0.2))
    plain = [
        m
        for k in range(80)
        if (m := draw_object_materials(s, 2, 0, k + 1, base)[0]).base_color_texture is None
    ]
    assert len(plain) > 5
    for m in plain:
        assert 0.1 - 1e-6 <= _srgb_hsv(m)[2] <= 0.2 + 1e-6


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("object_appearance", "yes"),
        ("object_probability", 1.5),
        ("object_probability", -0.1),
        ("object_probability", True),
        ("object_probability", "half"),
        ("object_value", (0.5, 0.2)),
        ("object_value", (0.0, 1.2)),
        ("object_saturation", (-0.1, 0.5)),
        ("object_roughness", (0.2,)),
        ("object_roughness", (0.5, 1.5)),
    ],
)
def test_bad_settings_name_the_setting(field: str, value: Any) -> None:
    with pytest.raises(InvalidArgumentError, match=f"RandomizeSettings.{field}"):
        RandomizeSettings(**{field: value})
    with pytest.raises(ConfigError, match=f"render.randomize.{field}"):
        load_config({"render": {"randomize": {field: value}}})


def test_bad_object_id() -> None:
    s = _settings(True)
    with pytest.raises(InvalidArgumentError, match="object_id"):
        draw_object_materials(s, 0, 0, -1, (PbrMaterial(),))


def test_config_round_trip() -> None:
    cfg = load_config(
        {"render": {"randomize": {"object_appearance": True, "object_probability": 0.25}}}
    )
    assert cfg.render.randomize.object_appearance
    assert cfg.render.randomize.object_probability == 0.25
    assert "draw_object_materials" in lighting.__all__


# ------------------------------------------------------------------------------ camera light


def _cam_settings(on: bool, **randomize: Any) -> RenderSettings:
    return RenderSettings(**_TRACE, randomize=RandomizeSettings(camera_light=on, **randomize))


def test_camera_light_drawn_from_seed_and_view_beside_the_camera() -> None:
    assert not RandomizeSettings().camera_light
    view = _view()
    target = np.array([0.0, 0.0, 0.0])
    s = _cam_settings(True, camera_light_probability=1.0)
    r = s.randomize
    a = lighting.draw_camera_light(s, 3, 4, view.X_WC, target_W=target)
    assert a is not None
    again = lighting.draw_camera_light(s, 3, 4, view.X_WC, target_W=target)
    assert again is not None
    assert repr(a) == repr(again)
    assert np.array_equal(a.X_WL, again.X_WL)
    for v in range(40):
        light = lighting.draw_camera_light(s, 3, v, view.X_WC, target_W=target)
        assert light is not None
        # In the camera's image plane, within the offset range, facing along the view.
        X_CL = np.linalg.inv(view.X_WC) @ light.X_WL
        assert abs(X_CL[2, 3]) < 1e-12
        off = float(np.hypot(X_CL[0, 3], X_CL[1, 3]))
        assert r.camera_light_offset[0] - 1e-12 <= off <= r.camera_light_offset[1] + 1e-12
        assert np.allclose(light.X_WL[:3, 2], view.X_WC[:3, 2])
        assert r.camera_light_size[0] <= light.size[0] == light.size[1] <= r.camera_light_size[1]
        # Irradiance on the target (small-light approximation, the target faces world +z),
        # computed here from the light: within the configured range.
        w = target - light.X_WL[:3, 3]
        d = float(np.linalg.norm(w))
        e = light.intensity * light.size[0] ** 2 * (light.X_WL[:3, 2] @ w / d) * (-w[2] / d) / d**2
        lo, hi = r.camera_light_irradiance
        assert lo * (1 - 1e-9) <= e <= hi * (1 + 1e-9)
    assert lighting.draw_camera_light(_cam_settings(False), 3, 4, view.X_WC) is None
    assert lighting.draw_camera_light(s, 3, 4, view.X_WC, randomize=False) is None


def test_camera_light_probability() -> None:
    n = 1000
    for p in (0.25, 0.5):
        s = _cam_settings(True, camera_light_probability=p)
        lit = sum(lighting.draw_camera_light(s, 5, v, _view().X_WC) is not None for v in range(n))
        assert abs(lit - n * p) < 5 * np.sqrt(n * p * (1 - p)), (p, lit)


def test_camera_light_changes_nothing_else() -> None:
    items, tote = _scene()
    view, seed, v = _view(), 2, 1
    off = photo.PhotoRenderer(items, tote, np.eye(4), None, _cam_settings(False), seed=seed)
    zero = photo.PhotoRenderer(
        items, tote, np.eye(4), None, _cam_settings(True, camera_light_probability=0.0), seed=seed
    )
    one = photo.PhotoRenderer(
        items, tote, np.eye(4), None, _cam_settings(True, camera_light_probability=1.0), seed=seed
    )
    a, b, c = (png_bytes(pr.render(view, v)[0]) for pr in (off, zero, one))
    assert a == b
    assert a != c
    # The light adds light: the mean of the picture rises.
    assert one.render(view, v)[0].mean() > off.render(view, v)[0].mean()


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("camera_light", 1),
        ("camera_light_probability", 2.0),
        ("camera_light_size", (0.0, 0.1)),
        ("camera_light_offset", (0.2, 0.1)),
        ("camera_light_irradiance", (-1.0, 2.0)),
        ("camera_light_ambient", (0.5, 1.5)),
        ("camera_light_ambient", (-0.1, 0.5)),
    ],
)
def test_camera_light_bad_settings_name_the_setting(field: str, value: Any) -> None:
    with pytest.raises(InvalidArgumentError, match=f"RandomizeSettings.{field}"):
        RandomizeSettings(**{field: value})


def test_camera_light_ambient_scales_the_other_lights_and_the_environment() -> None:
    """``camera_light_ambient`` scales every other light and the environment by one factor
    drawn in its range, only in views with the camera light; the camera light itself is the
    one :func:`draw_camera_light` draws whatever the range; the default (1, 1) changes nothing
    else."""
    view, seed = _view(), 6
    dim = _cam_settings(True, camera_light_probability=0.5, camera_light_ambient=(0.05, 0.3))
    plain = _cam_settings(True, camera_light_probability=0.5)
    assert RandomizeSettings().camera_light_ambient == (1.0, 1.0)
    factors = []
    for v in range(30):
        base = draw_lighting(dim, seed, v)
        got = lighting.with_camera_light(base, dim, seed, v, view.X_WC)
        light = lighting.draw_camera_light(dim, seed, v, view.X_WC)
        assert repr(light) == repr(lighting.draw_camera_light(plain, seed, v, view.X_WC))
        if light is None:
            assert got is base
            continue
        assert repr(got.lights[-1]) == repr(light)
        assert len(got.lights) == len(base.lights) + 1
        f = got.environment.intensity / base.environment.intensity
        assert 0.05 - 1e-12 <= f <= 0.3 + 1e-12
        assert got.summary["camera_light"]["ambient"] == pytest.approx(f, rel=1e-12)
        for a, b in zip(got.lights[:-1], base.lights, strict=True):
            assert a.intensity == pytest.approx(f * b.intensity, rel=1e-12)
            assert np.array_equal(a.X_WL, b.X_WL)
            assert (a.size, a.color) == (b.size, b.color)
        assert (got.tote, got.floor, got.exposure) == (base.tote, base.floor, base.exposure)
        unchanged = lighting.with_camera_light(base, plain, seed, v, view.X_WC)
        assert unchanged.lights[:-1] == base.lights
        assert unchanged.environment == base.environment
        factors.append(f)
    # Drawn per view: some views with the light, different factors.
    assert len(factors) >= 5
    assert np.ptp(factors) > 0.05


def test_projector_light_alone_leaves_black_shadows() -> None:
    """With the other lights and the environment off (ambient 0), a small light beside the
    camera leaves the floor behind a box, seen from the light, black: the floor points whose
    segments to all four corners of the light cross the box (computed here by a slab test,
    independent of the tracer) get under 5 % of the radiance of the floor points that see the
    whole light (what is left is light the box reflects), while with the ambient left on they
    keep more than 15 %."""
    box = mgn.geometry.make_box((0.08, 0.08, 0.12))
    X_box = np.eye(4)
    X_box[2, 3] = 0.06
    floor = mgn.geometry.make_box((1.2, 1.2, 0.02))
    X_floor = np.eye(4)
    X_floor[2, 3] = -0.01
    K = Intrinsics.mgn_synthetic().scaled(64 / 1200.0)
    view = CameraView(K, look_at((0.0, 0.0, 0.6), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0)))
    origins, dirs = view.rays()
    o, d = origins.reshape(-1, 3).astype(np.float64), dirs.reshape(-1, 3).astype(np.float64)
    t = -o[:, 2] / d[:, 2]
    P = o + t[:, None] * d  # the floor point (z = 0) of each pixel

    def blocked(P: np.ndarray, q: np.ndarray) -> np.ndarray:
        # Does the segment P -> q cross the box |x|, |y| <= 0.04, 0 <= z <= 0.12?
        lo, hi = np.array([-0.04, -0.04, 0.0]), np.array([0.04, 0.04, 0.12])
        seg = q - P
        with np.errstate(divide="ignore", invalid="ignore"):
            t0, t1 = (lo - P) / seg, (hi - P) / seg
        near = np.nanmax(np.minimum(t0, t1), axis=1)
        far = np.nanmin(np.maximum(t0, t1), axis=1)
        return (near < far) & (far > 1e-6) & (near < 1.0 - 1e-6)

    results = {}
    for ambient in (0.0, 1.0):
        s = RenderSettings(
            engine="path",
            spp=64,
            spp_without_denoiser=64,
            denoise=False,
            randomize=RandomizeSettings(
                camera_light=True,
                camera_light_probability=1.0,
                camera_light_size=(0.01, 0.01),
                camera_light_offset=(0.15, 0.15),
                camera_light_irradiance=(6.0, 6.0),
                camera_light_ambient=(ambient, ambient),
                materials=False,
            ),
        )
        pr = photo.PhotoRenderer([(box, X_box, 1)], None, np.eye(4), (floor, X_floor), s, seed=1)
        _, out = pr.render(view, 0)
        lum = np.asarray(out.radiance, np.float64).reshape(-1, 3).mean(axis=1)
        light = lighting.draw_camera_light(s, 1, 0, view.X_WC)
        assert light is not None
        X, (a, b) = light.X_WL, light.size
        corners = [
            X[:3, :3] @ (sx * a / 2, sy * b / 2, 0) + X[:3, 3] for sx in (-1, 1) for sy in (-1, 1)
        ]
        hits = np.stack([blocked(P, q) for q in corners])
        on_floor = np.hypot(P[:, 0], P[:, 1]) < 0.3
        # Floor pixels not covered by the box in the image (the box's footprint seen from the
        # camera: the segment from the camera to the floor point crosses the box).
        visible = on_floor & ~blocked(P, view.position)
        umbra = visible & hits.all(axis=0)
        lit = visible & ~hits.any(axis=0)
        assert umbra.sum() >= 20, umbra.sum()
        assert lit.sum() >= 200, lit.sum()
        results[ambient] = lum[umbra].mean() / lum[lit].mean()
    assert results[0.0] < 0.05, results
    assert results[1.0] > 0.15, results
