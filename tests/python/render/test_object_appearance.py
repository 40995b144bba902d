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
    ],
)
def test_camera_light_bad_settings_name_the_setting(field: str, value: Any) -> None:
    with pytest.raises(InvalidArgumentError, match=f"RandomizeSettings.{field}"):
        RandomizeSettings(**{field: value})
