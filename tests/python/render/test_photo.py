"""The photo-realistic RGB engine around the path tracer: config and CLI, materials (built-in,
user YAML, glTF PBR factors), pixel alignment with the raster labels, per-view randomisation,
denoising, and a tiny path-traced dataset."""

from __future__ import annotations

import base64
import colorsys
import json
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from PIL import Image

import mgn
from mgn import _core
from mgn.cli import main
from mgn.errors import InvalidArgumentError
from mgn.io.image_codecs import png_bytes
from mgn.objects import builtin_objects, load_objects_yaml, tote_mesh
from mgn.pipeline.config import ConfigError, dump_config, load_config
from mgn.render import denoiser, lighting, materials, photo, settings
from mgn.render.lighting import draw_lighting
from mgn.render.path import PathTraceOptions
from mgn.render.sensor import SURFACE_MIRROR, SURFACE_TRANSPARENT, surface_flags
from mgn.render.settings import RandomizeSettings, RenderSettings
from mgn.render.views import iter_views
from mgn.scene.cameras import CameraView, Intrinsics, look_at
from mgn.viz.report import image_engines

# ------------------------------------------------------------------------------ config / CLI


@pytest.mark.parametrize(
    ("section", "key"),
    [
        ({"engine": "cycles"}, "render.engine"),
        ({"spp": 0}, "render.spp"),
        ({"spp": 2.5}, "render.spp"),
        ({"denoise": "yes"}, "render.denoise"),
        ({"max_bounces": -1}, "render.max_bounces"),
        ({"tone": "aces"}, "render.tone"),
        ({"denoise_quality": "best"}, "render.denoise_quality"),
        ({"denoise_guides": "clean"}, "render.denoise_guides"),
        ({"exposure": float("nan")}, "render.exposure"),
        ({"aperture_radius": -0.001}, "render.aperture_radius"),
        ({"randomize": {"light_count": [3, 1]}}, "render.randomize.light_count"),
        ({"randomize": {"light_temperature": [100, 200]}}, "render.randomize.light_temperature"),
        ({"randomize": {"lights": 1}}, "render.randomize.lights"),
        ({"randomize": {"sun": True}}, "render.randomize.sun"),
        ({"bogus": 1}, "render.bogus"),
    ],
)
def test_render_config_errors_name_the_key(section: dict, key: str) -> None:
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        load_config({"render": section})


def test_switching_only_the_engine_gives_one_sample_and_the_denoiser() -> None:
    """A user who sets only ``render.engine: path`` gets the fast setting of
    docs/decisions/0031-path-default-spp.md: 1 spp, OIDN ``fast``, not the 16 spp of a slow
    preview-free render."""
    r = load_config({"render": {"engine": "path"}}).render
    assert (r.spp, r.denoise, r.denoise_quality) == (1, True, "fast")
    assert r.spp_without_denoiser >= 64  # undenoised images need many more samples


def test_render_config_round_trip() -> None:
    rnd = {"lights": False, "light_count": [2, 4]}
    cfg = load_config({"render": {"engine": "path", "spp": 8, "randomize": rnd}})
    assert cfg.render.engine == "path"
    assert cfg.render.spp == 8
    assert cfg.render.randomize.light_count == (2, 4)
    assert not cfg.render.randomize.lights

    again = load_config(yaml.safe_load(dump_config(cfg)))
    assert again.render == cfg.render
    assert "render:" in dump_config()
    assert "engine: raster" in dump_config()


@pytest.mark.parametrize(
    "command",
    [
        ["generate", "--out", "X", "--engine", "cycles"],
        ["scene", "render", "s.json", "--out", "X", "--engine", "cycles"],
        ["scene", "label", "s.json", "--out", "X", "--engine", "cycles"],
        ["pick", "s.json", "--out", "X", "--engine", "cycles"],
    ],
)
def test_cli_engine_choices(command: list[str], capsys: pytest.CaptureFixture[str]) -> None:

    with pytest.raises(SystemExit) as e:
        main(command)
    assert e.value.code == 2
    assert "--engine" in capsys.readouterr().err


def test_cli_spp_must_be_positive() -> None:

    base = RenderSettings(engine="path")
    with pytest.raises(InvalidArgumentError, match="--spp"):
        settings.with_engine(base, None, 0)
    got = settings.with_engine(base, "raster", 4)
    assert got.engine == "raster"
    assert got.spp == 4


# ------------------------------------------------------------------------------ materials


def test_builtin_materials_are_plausible() -> None:
    by_name = {o.name: o.material for o in builtin_objects()}
    for name, m in by_name.items():
        assert 0.0 <= m.roughness <= 1.0, name
        assert 0.0 <= m.metallic <= 1.0, name
    for name in ("wine_glass", "bottle_clear"):
        assert by_name[name].transmission == 1.0
        assert by_name[name].ior == 1.5
    assert by_name["hex_nut"].metallic == 1.0
    assert by_name["hex_nut"].roughness < 0.25
    assert by_name["l_bracket"].metallic == 1.0
    assert by_name["l_bracket"].roughness >= 0.3
    assert by_name["box_cereal"].roughness >= 0.6
    assert by_name["box_cereal"].metallic == 0.0
    assert by_name["cable_coil"].roughness >= 0.8  # rubber
    # Transparent-tagged objects are exactly the transmissive ones.
    for o in builtin_objects():
        assert ("transparent" in o.tags) == (o.material.transmission > 0.5), o.name


def test_builtin_mesh_carries_pbr_and_sensor_flags() -> None:

    glass = mgn.objects.get_object("bottle_clear").to_mesh().materials[0]
    assert glass.has_pbr
    assert glass.transmission == 1.0
    assert glass.ior == pytest.approx(1.5)
    assert surface_flags(glass) & SURFACE_TRANSPARENT
    m = mgn.geometry.Material()
    m.has_pbr, m.metallic, m.roughness = True, 1.0, 0.1
    assert surface_flags(m) & SURFACE_MIRROR
    m.roughness = 0.6  # brushed metal scatters: not a mirror
    assert not surface_flags(m) & SURFACE_MIRROR
    t = mgn.geometry.Material()
    t.has_pbr, t.transmission = True, 1.0
    assert surface_flags(t) & SURFACE_TRANSPARENT
    assert not surface_flags(mgn.geometry.Material()) & SURFACE_TRANSPARENT


def _write_gltf(path: Path, material: dict, extensions: list[str]) -> None:
    """A one-triangle-pair glTF (embedded buffer) with the given material."""
    pos = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32)
    idx = np.array([0, 1, 2, 0, 2, 3], np.uint16)
    data = pos.tobytes() + idx.tobytes()
    doc = {
        "asset": {"version": "2.0"},
        "extensionsUsed": extensions,
        "scenes": [{"nodes": [0]}],
        "scene": 0,
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [material],
        "buffers": [
            {
                "byteLength": len(data),
                "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode(),
            }
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 12},
        ],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": 4,
                "type": "VEC3",
                "min": [0, 0, 0],
                "max": [1, 1, 0],
            },
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
    }
    path.write_text(json.dumps(doc))


def test_glb_pbr_factors_read_back(tmp_path: Path) -> None:
    trimesh = pytest.importorskip("trimesh")
    box = trimesh.creation.box((0.1, 0.1, 0.1))
    box.visual = trimesh.visual.TextureVisuals(
        material=trimesh.visual.material.PBRMaterial(
            baseColorFactor=[51, 102, 204, 255], metallicFactor=0.8, roughnessFactor=0.3
        )
    )
    box.export(tmp_path / "box.glb")
    m = mgn.load_mesh(tmp_path / "box.glb").materials[0]
    assert m.has_pbr
    assert m.metallic == pytest.approx(0.8, abs=1e-6)
    assert m.roughness == pytest.approx(0.3, abs=1e-6)
    assert np.allclose(np.asarray(m.base_color)[:3], np.array([51, 102, 204]) / 255, atol=1e-3)
    # KHR_materials_transmission and KHR_materials_ior from a hand-written glTF.
    mat = {
        "pbrMetallicRoughness": {
            "baseColorFactor": [0.9, 0.95, 1.0, 1.0],
            "metallicFactor": 0.0,
            "roughnessFactor": 0.05,
        },
        "extensions": {
            "KHR_materials_transmission": {"transmissionFactor": 1.0},
            "KHR_materials_ior": {"ior": 1.45},
        },
    }
    _write_gltf(tmp_path / "pane.gltf", mat, ["KHR_materials_transmission", "KHR_materials_ior"])
    g = mgn.load_mesh(tmp_path / "pane.gltf").materials[0]
    assert g.has_pbr
    assert g.transmission == pytest.approx(1.0)
    assert g.roughness == pytest.approx(0.05, abs=1e-6)
    assert g.metallic == 0.0
    # A plain OBJ/STL has no PBR description: the tracer derives one.
    stl = mgn.load_mesh(Path(__file__).resolve().parents[2] / "data" / "cube.stl")
    assert not any(mm.has_pbr for mm in stl.materials)


def _user_yaml(tmp_path: Path, extra: str) -> Path:
    src = Path(__file__).resolve().parents[2] / "data" / "cube.stl"
    p = tmp_path / "objs.yaml"
    p.write_text(
        "objects:\n  - name: part_a\n    mesh: " + str(src) + "\n    scale: 1.0\n"
        "    density: 1000\n    friction: 0.5\n" + extra
    )
    return p


@pytest.mark.parametrize(
    ("extra", "field"),
    [
        ("    metallic: 1.5\n", "metallic"),
        ("    roughness: -0.1\n", "roughness"),
        ("    ior: 0.9\n", "ior"),
        ("    transmission: yes\n", "transmission"),
    ],
)
def test_user_object_pbr_errors_name_file_object_field(
    tmp_path: Path, extra: str, field: str
) -> None:

    with pytest.raises(InvalidArgumentError, match=rf"objs\.yaml.*part_a.*'{field}'"):
        load_objects_yaml(_user_yaml(tmp_path, extra))


def test_user_object_pbr_values_reach_the_tracer(tmp_path: Path) -> None:

    extra = "    metallic: 1.0\n    roughness: 0.2\n    ior: 1.4\n    transmission: 0.0\n"
    (spec,) = load_objects_yaml(_user_yaml(tmp_path, extra))
    assert (spec.material.metallic, spec.material.roughness, spec.material.ior) == (1.0, 0.2, 1.4)
    pbr = materials.pbr_material(spec.to_mesh().materials[0])
    assert (pbr.metallic, pbr.roughness, pbr.transmission) == (1.0, pytest.approx(0.2), 0.0)
    assert pbr.ior == pytest.approx(1.4)


# ------------------------------------------------------------------------------ randomisation


def test_blackbody_tints() -> None:
    warm, white, cool = (np.array(lighting.blackbody_rgb(t)) for t in (3000.0, 6500.0, 10000.0))
    assert np.allclose(white, 1.0, atol=1e-9)
    assert warm[0] > warm[1] > warm[2]
    assert cool[2] > cool[1] > cool[0]
    for c in (warm, cool):
        assert 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2] == pytest.approx(1.0)


def _lighting_key(lit: lighting.ViewLighting) -> tuple:
    lights = tuple((a.X_WL.tobytes(), a.size, a.color, a.intensity) for a in lit.lights)
    tex = tuple(
        None if m.base_color_texture is None else m.base_color_texture.tobytes()
        for m in (lit.tote, lit.floor)
    )
    return (lights, lit.environment, lit.tote, lit.floor, tex, lit.exposure)


def test_randomisation_is_drawn_from_seed_and_view() -> None:
    s = RenderSettings(engine="path")
    a = _lighting_key(draw_lighting(s, 7, 3))
    assert a == _lighting_key(draw_lighting(s, 7, 3))
    assert a != _lighting_key(draw_lighting(s, 7, 4))
    assert a != _lighting_key(draw_lighting(s, 8, 3))
    # Many views: the ranges are honoured and every environment / texture kind occurs.
    kinds, textures, counts = set(), set(), set()
    for v in range(60):
        lit = draw_lighting(s, 1, v)
        counts.add(len(lit.lights))
        kinds.add(lit.environment.kind)
        textures.add(lit.summary["floor_texture"])
        assert abs(lit.exposure) <= s.randomize.exposure_range
        for light in lit.lights:
            assert s.randomize.light_size[0] <= light.size[0] <= s.randomize.light_size[1]
            h = light.X_WL[2, 3]
            assert s.randomize.light_height[0] <= h <= s.randomize.light_height[1]
            # Every light faces the tote (its +z axis points down at the target).
            assert light.X_WL[2, 2] < 0
    assert counts == {1, 2, 3}
    assert kinds == set(lighting.ENVIRONMENTS)
    assert textures == set(materials.TEXTURES)


def test_randomisation_switches_are_independent() -> None:
    on = RenderSettings(engine="path")
    off_lights = RenderSettings(engine="path", randomize=RandomizeSettings(lights=False))
    a, b = draw_lighting(on, 5, 2), draw_lighting(off_lights, 5, 2)
    assert len(b.lights) == 1
    assert b.lights[0].size == (1.0, 1.0)
    assert (a.environment, a.tote, a.floor, a.exposure) == (
        b.environment,
        b.tote,
        b.floor,
        b.exposure,
    )
    fixed = draw_lighting(on, 5, 2, randomize=False)
    assert fixed.exposure == on.exposure
    assert fixed.tote.base_color_texture is None


def _tote_hsv(lit: lighting.ViewLighting) -> tuple[float, float, float]:
    # Back from the tracer's linear RGB to sRGB HSV (the inverse of srgb_to_linear).
    c = np.asarray(lit.tote.base_color[:3], np.float64)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    return colorsys.rgb_to_hsv(*(float(x) for x in s))


def test_tote_colour_includes_black_and_dark_grey_totes() -> None:
    s = RenderSettings(engine="path")
    n = 300
    hsv = [_tote_hsv(draw_lighting(s, 11, v)) for v in range(n)]
    sat = np.array([h[1] for h in hsv])
    val = np.array([h[2] for h in hsv])
    dark_cfg = lighting.DARK_TOTE
    dark = val < lighting.TOTE_HSV["value"][0] - 1e-9
    # Every colour lies in one of the two ranges; the dark ones are (nearly) grey.
    in_dark = (val >= dark_cfg["value"][0] - 1e-6) & (val <= dark_cfg["value"][1] + 1e-6)
    in_dark &= sat <= dark_cfg["saturation"][1] + 1e-6
    lo, hi = lighting.TOTE_HSV["value"]
    in_base = (val >= lo - 1e-6) & (val <= hi + 1e-6)
    in_base &= sat >= lighting.TOTE_HSV["saturation"][0] - 1e-6
    in_base &= sat <= lighting.TOTE_HSV["saturation"][1] + 1e-6
    assert np.all(in_dark | in_base)
    # About a third are dark: the share of draws in the dark range only (value below the other
    # range) is p * (0.15 - 0.08) / (0.3 - 0.08) of n, binomial, 5 standard deviations.
    p = (
        dark_cfg["probability"]
        * (lo - dark_cfg["value"][0])
        / (dark_cfg["value"][1] - dark_cfg["value"][0])
    )
    assert abs(dark.sum() - p * n) < 5 * np.sqrt(n * p * (1 - p))
    # Reflectance of the darkest totes: a few per cent, as black plastic.
    assert (
        np.max(
            np.asarray(
                [draw_lighting(s, 11, v).tote.base_color[0] for v in np.flatnonzero(dark)[:20]]
            )
        )
        < 0.08
    )


def test_dark_tote_draw_leaves_the_other_draws_unchanged(monkeypatch: pytest.MonkeyPatch) -> None:
    s = RenderSettings(engine="path")
    monkeypatch.setitem(lighting.DARK_TOTE, "probability", 0.0)
    never = [draw_lighting(s, 3, v) for v in range(8)]
    monkeypatch.setitem(lighting.DARK_TOTE, "probability", 1.0)
    always = [draw_lighting(s, 3, v) for v in range(8)]
    for a, b in zip(never, always, strict=True):
        assert repr((a.lights, a.environment, a.exposure)) == repr(
            (b.lights, b.environment, b.exposure)
        )
        assert a.floor.base_color == b.floor.base_color
        assert a.floor.roughness == b.floor.roughness
        assert np.array_equal(a.floor.base_color_texture, b.floor.base_color_texture)
        assert a.tote.roughness == b.tote.roughness
        assert np.array_equal(a.tote.base_color_texture, b.tote.base_color_texture)
        ha, hb = _tote_hsv(a), _tote_hsv(b)
        assert ha[2] >= lighting.TOTE_HSV["value"][0] - 1e-6
        assert hb[2] <= lighting.DARK_TOTE["value"][1] + 1e-6
        assert hb[1] <= lighting.DARK_TOTE["saturation"][1] + 1e-6


def test_procedural_textures() -> None:
    g = np.random.default_rng(0)
    for kind in ("noise", "checker", "stripes"):
        t = materials.procedural_texture(kind, g, size=64)
        assert t.shape == (64, 64, 3)
        assert t.dtype == np.uint8
        assert t.max() == 255 or kind == "noise"
        assert t.min() < t.max()
        # Tileable: the first and last rows / columns are neighbours of similar level.
        assert abs(int(t[0, :, 0].mean()) - int(t[-1, :, 0].mean())) < 60
    assert materials.procedural_texture("plain", g) is None
    with pytest.raises(InvalidArgumentError, match="texture kind"):
        materials.procedural_texture("marble", g)


# ------------------------------------------------------------------------------ tracer


def _small_scene() -> tuple[list, mgn.Mesh]:

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
        c, s = np.cos(0.4 * k), np.sin(0.4 * k)
        X[:2, :2] = [[c, -s], [s, c]]
        X[:3, 3] = (*xy, -float(np.asarray(mesh.bounds)[0, 2]))
        items.append((mesh, X, k + 1))
    return items, tote_mesh()


def _view(size: int = 64) -> CameraView:
    K = Intrinsics.mgn_synthetic().scaled(size / 1200.0)
    return CameraView(K, look_at((0.15, -0.25, 0.75), (0.0, 0.0, 0.03)))


def test_path_ids_and_depth_align_with_the_raster() -> None:

    items, tote = _small_scene()
    view = _view(96)
    raster = next(
        iter(iter_views(items, tote, [(0, view)], sensor="ideal", randomize=False, floor=False))
    )
    s = RenderSettings(engine="path", spp=1, denoise=False, spp_without_denoiser=1)
    pr = photo.PhotoRenderer(items, tote, np.eye(4), None, s, randomize=False)
    rgb, out = pr.render(view, 0, labels=True)
    agree = out.instance_ids == raster.instance_ids
    assert agree.mean() >= 0.999, agree.mean()
    assert len(np.unique(raster.instance_ids)) == 5  # background and the four objects
    seen_r, seen_p = raster.depth_ideal > 0, out.depth > 0
    assert (seen_r == seen_p).mean() >= 0.999  # the tote is seen at the same pixels too
    assert seen_r.mean() > 0.5
    both = agree & seen_r & seen_p
    close = np.isclose(out.depth[both], raster.depth_ideal[both], rtol=1e-3, atol=1e-4)
    assert close.mean() >= 0.999, close.mean()
    # Without its label rays (the pipeline's way) the tracer makes the same photograph.
    rgb_only, out_only = pr.render(view, 0)
    assert np.array_equal(rgb_only, rgb)
    assert not out_only.instance_ids.any()
    assert not out_only.depth.any()
    assert out_only.rays < out.rays
    # The path-traced views of iter_views come with exactly the raster labels.
    pv = next(iter(iter_views(items, tote, [(0, view)], sensor="ideal", randomize=True, render=s)))
    assert np.array_equal(pv.instance_ids, raster.instance_ids)
    assert pv.engine == {"engine": "path", "spp": 1, "denoised": False, "max_bounces": 6}
    assert pv.rgb.shape == raster.rgb.shape
    assert pv.rgb.dtype == np.uint8


@pytest.mark.parametrize("denoise", [True, False])
def test_same_png_for_one_and_two_threads(denoise: bool) -> None:

    if denoise and not denoiser.denoiser_available():
        pytest.fail("pyoidn (test extra) is not installed")
    items, tote = _small_scene()
    s = RenderSettings(
        engine="path",
        spp=2,
        spp_without_denoiser=2,
        denoise=denoise,
        shot_noise=0.02,
        read_noise=0.002,
    )
    pngs = []
    for threads in (1, 2):
        pr = photo.PhotoRenderer(items, tote, np.eye(4), None, s, seed=3, num_threads=threads)
        rgb, _ = pr.render(_view(48), 5)
        pngs.append(png_bytes(rgb))
    assert pngs[0] == pngs[1]


def test_denoiser_reduces_the_error() -> None:
    if not denoiser.denoiser_available():
        pytest.fail("pyoidn (test extra) is not installed")
    items, tote = _small_scene()
    view = _view(64)

    def radiance(spp: int) -> Any:
        s = RenderSettings(engine="path", spp=spp, denoise=False, spp_without_denoiser=spp)
        pr = photo.PhotoRenderer(items, tote, np.eye(4), None, s, randomize=False, seed=1)
        lit = pr.lighting(0)

        return pr._scene_for(lit).render(view, PathTraceOptions(spp=spp, seed=1, clamp=20.0))

    ref = radiance(256).radiance
    noisy = radiance(4)
    den = denoiser.denoise(noisy.radiance, noisy.albedo, noisy.normal)
    mse_raw = float(np.mean((noisy.radiance - ref) ** 2))
    mse_den = float(np.mean((den - ref) ** 2))
    assert mse_den < 0.5 * mse_raw, (mse_den, mse_raw)


def _noisy_buffers(h: int, w: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A noisy HDR radiance image (with a NaN and an inf) and its albedo and normal guides."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    albedo = np.stack([(xx // 8 % 2) * 0.6 + 0.2, yy / h, np.full_like(xx, 0.5)], axis=-1)
    normal = np.stack([np.sin(xx / 9), np.cos(yy / 7), np.ones_like(xx)], axis=-1)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    radiance = albedo * rng.exponential(1.0, (h, w, 1)) * 3.0
    radiance[1, 2] = np.nan
    radiance[3, 1] = np.inf
    return radiance.astype(np.float32), albedo.astype(np.float32), normal.astype(np.float32)


def test_denoise_reuses_its_filter_and_matches_pyoidn() -> None:
    """denoiser.denoise keeps one OIDN device and filter per thread count; every call, whatever
    came before (another shape, fewer guides, another thread count, guides declared clean or
    noisy), gives the bytes of pyoidn's own convenience API (a separate device) on the same
    cleaned inputs."""
    if not denoiser.denoiser_available():
        pytest.fail("pyoidn (test extra) is not installed")
    import pyoidn

    def reference(
        rad: np.ndarray, alb: np.ndarray | None, nrm: np.ndarray | None, clean: bool = False
    ) -> np.ndarray:
        c = np.nan_to_num(rad, nan=0.0, posinf=0.0)
        out = pyoidn.denoise(c, alb, nrm, hdr=True, quality="fast", clean_aux=clean)
        return np.maximum(out, 0.0)

    big, small = _noisy_buffers(48, 64, 1), _noisy_buffers(40, 24, 2)
    want_big, want_small = reference(*big), reference(*small)
    want_albedo_only = reference(big[0], big[1], None)
    assert not np.array_equal(want_big, want_albedo_only)  # the normal guide is used
    first = denoiser.denoise(*big, guides="raw")
    assert first.dtype == np.float32
    assert first.shape == big[0].shape
    assert np.isfinite(first).all()
    assert first.min() >= 0.0
    assert first.tobytes() == want_big.tobytes()
    assert denoiser.denoise(*big, guides="raw").tobytes() == first.tobytes()  # the cached filter
    assert denoiser.denoise(*small, guides="raw").tobytes() == want_small.tobytes()  # another shape
    # the default: both guides smoothed and declared clean (cleanAux), then back to noisy
    smooth = reference(big[0], denoiser._smooth3(big[1]), denoiser._smooth3(big[2]), clean=True)
    assert not np.array_equal(smooth, want_big)
    assert denoiser.denoise(*big).tobytes() == smooth.tobytes()
    assert denoiser.denoise(*big, guides="raw").tobytes() == first.tobytes()
    for unbind in ("raw", "albedo"):  # a missing normal, or guides="albedo", unbinds it
        args = (big[0], big[1]) if unbind == "raw" else big
        assert denoiser.denoise(*args, guides=unbind).tobytes() == want_albedo_only.tobytes()
    assert (
        denoiser.denoise(*big, guides="none").tobytes() == reference(big[0], None, None).tobytes()
    )
    assert denoiser.denoise(*big, num_threads=1, guides="raw").tobytes() == first.tobytes()
    assert denoiser.denoise(*big, guides="raw").tobytes() == first.tobytes()
    assert np.isnan(big[0][1, 2]).all()
    assert np.isinf(big[0][3, 1]).all()
    assert np.isnan(big[0]).sum() == 3
    assert np.isinf(big[0]).sum() == 3


def test_denoise_rejects_bad_inputs() -> None:
    if not denoiser.denoiser_available():
        pytest.fail("pyoidn (test extra) is not installed")
    rad, alb, nrm = _noisy_buffers(16, 16, 3)
    with pytest.raises(InvalidArgumentError, match="radiance must have shape"):
        denoiser.denoise(rad[..., 0])
    with pytest.raises(InvalidArgumentError, match="radiance must have shape"):
        denoiser.denoise(rad[:0])
    with pytest.raises(InvalidArgumentError, match=r"albedo must have the radiance's shape"):
        denoiser.denoise(rad, alb[:8], nrm)
    with pytest.raises(InvalidArgumentError, match=r"normal must have the radiance's shape"):
        denoiser.denoise(rad, alb, nrm[..., :2])
    with pytest.raises(InvalidArgumentError, match="num_threads"):
        denoiser.denoise(rad, alb, nrm, num_threads=-1)
    with pytest.raises(InvalidArgumentError, match="quality"):
        denoiser.denoise(rad, alb, nrm, "best")
    with pytest.raises(InvalidArgumentError, match="guides must be one of"):
        denoiser.denoise(rad, alb, nrm, guides="clean")
    with pytest.raises(InvalidArgumentError, match=r"albedo must have"):  # the first one named
        denoiser.denoise(rad, alb[:8], nrm[..., :2])
    assert denoiser.denoise(rad, alb, nrm).shape == rad.shape  # still works after the errors
    # Finite radiance goes to OIDN as it is (no copy): untouched, and the same image as the
    # radiance with its NaN and inf replaced by 0.
    finite = np.nan_to_num(rad, nan=0.0, posinf=0.0)
    kept = finite.copy()
    assert np.array_equal(denoiser.denoise(finite, alb, nrm), denoiser.denoise(rad, alb, nrm))
    assert np.array_equal(finite, kept)


def test_half_resolution_blocks_and_interpolation_are_opencvs() -> None:
    """The ``half`` denoise's 2 x 2 block means are OpenCV's INTER_AREA halving and its doubling
    is OpenCV's INTER_LINEAR (pixel centres aligned) for even sizes; a linear ramp survives the
    round trip exactly away from the border; odd sizes repeat the last row / column."""
    import cv2

    img = np.random.default_rng(5).random((24, 18, 3)).astype(np.float32)
    blk = denoiser._blocks2(img)
    np.testing.assert_allclose(
        blk, cv2.resize(img, (9, 12), interpolation=cv2.INTER_AREA), atol=1e-6
    )
    np.testing.assert_allclose(
        denoiser._double(blk, 24, 18),
        cv2.resize(blk, (18, 24), interpolation=cv2.INTER_LINEAR),
        atol=1e-6,
    )
    yy, xx = np.mgrid[0:20, 0:30].astype(np.float32)
    ramp = np.stack([0.1 * xx + 0.05 * yy, 0.2 * yy, np.full_like(xx, 0.7)], axis=-1)
    back = denoiser._double(denoiser._blocks2(ramp), 20, 30)
    np.testing.assert_allclose(back[1:-1, 1:-1], ramp[1:-1, 1:-1], atol=1e-5)
    odd = img[:23, :17]
    ob = denoiser._blocks2(odd)
    assert ob.shape == (12, 9, 3)
    np.testing.assert_allclose(ob[-1, -1], odd[22, 16], atol=1e-6)  # the corner block: one pixel
    np.testing.assert_allclose(ob[-1, 0], odd[22, 0:2].mean(axis=0), atol=1e-6)
    assert denoiser._double(ob, 23, 17).shape == (23, 17, 3)


def test_half_resolution_albedo_ratio_fades_at_silhouettes() -> None:
    """The albedo ratio is applied in full where a pixel's normal agrees with its blocks'
    (cosine >= 0.97), not at all where it turns away (<= 0.85: a silhouette), linearly between;
    the normals' lengths do not matter."""
    up = np.array([0.0, 0.0, 1.0], np.float32)

    def tilted(deg: float) -> np.ndarray:
        t = np.radians(deg)
        return np.array([np.sin(t), 0.0, np.cos(t)], np.float32)

    cos_mid = 0.5 * (0.85 + 0.97)
    normal = np.stack(
        [2.0 * up, tilted(10.0), tilted(90.0), tilted(np.degrees(np.arccos(cos_mid)))]
    )[None]
    # two blocks of one row, both facing up (different lengths): every pixel's doubled normal
    # faces up; albedo 0.3 at full size over 0.1 in the blocks: a ratio of 3
    normal_blocks = np.stack([up, 0.5 * up])[None]
    albedo = np.full((1, 4, 3), 0.3, np.float32)
    albedo_blocks = np.full((1, 2, 3), 0.1, np.float32)
    denoised = np.ones((1, 2, 3), np.float32)
    got = _core.render.restore_half_resolution(
        denoised, 1, 4, albedo, albedo_blocks, normal, normal_blocks, 0.02, 0.85, 0.97
    )
    assert got.dtype == np.float32
    assert got.shape == (1, 4, 3)
    np.testing.assert_allclose(got[0, :, 0], [3.0, 3.0, 1.0, 2.0], atol=1e-4)


def _restore_by_numpy(
    den: np.ndarray, h: int, w: int, a: np.ndarray, ab: np.ndarray, n: np.ndarray, nb: np.ndarray
) -> np.ndarray:
    """A second implementation of the half-resolution restore with OpenCV's doubling and
    NumPy's arithmetic in float64."""
    import cv2

    def double(x: np.ndarray) -> np.ndarray:
        pad = cv2.resize(x, (2 * x.shape[1], 2 * x.shape[0]), interpolation=cv2.INTER_LINEAR)
        return pad[:h, :w].astype(np.float64)

    ratio = np.maximum(a, 0.02) / np.maximum(double(ab), 0.02)
    nd = double(nb)
    cos = (n * nd).sum(-1) / np.maximum(
        np.linalg.norm(n, axis=-1) * np.linalg.norm(nd, axis=-1), 1e-12
    )
    g = np.clip((cos - 0.85) / 0.12, 0.0, 1.0)[..., None]
    return np.maximum(double(den) * (1.0 + g * (ratio - 1.0)), 0.0)


@pytest.mark.parametrize("shape", [(40, 30), (39, 31)])
def test_half_resolution_restore_matches_a_second_implementation(shape: tuple[int, int]) -> None:
    """The C++ restore (doubling, albedo ratio, silhouette fade, clamp) equals a NumPy/OpenCV
    composition on random images, for even and odd sizes and any thread count."""
    h, w = shape
    rng = np.random.default_rng(11)
    hb, wb = (h + 1) // 2, (w + 1) // 2
    den = (rng.random((hb, wb, 3)) * 2 - 0.2).astype(np.float32)  # some negatives: clamped
    a = rng.random((h, w, 3)).astype(np.float32)
    n = rng.normal(size=(h, w, 3)).astype(np.float32)
    n[0, 0] = 0.0  # a zero normal: no ratio there
    ab = denoiser._blocks2(a)
    nb = denoiser._blocks2(n)
    want = _restore_by_numpy(den, h, w, a, ab, n, nb)
    outs = [
        _core.render.restore_half_resolution(den, h, w, a, ab, n, nb, num_threads=t)
        for t in (1, 2, 3)
    ]
    np.testing.assert_allclose(outs[0], want, rtol=2e-5, atol=2e-6)
    assert all(o.tobytes() == outs[0].tobytes() for o in outs[1:])
    flat = _core.render.restore_half_resolution(den, h, w)  # without albedo: the doubling alone
    np.testing.assert_allclose(flat, np.maximum(denoiser._double(den, h, w), 0.0), atol=0)
    with pytest.raises(InvalidArgumentError, match="albedo_blocks"):
        _core.render.restore_half_resolution(den, h, w, a, ab[:-1], n, nb)
    with pytest.raises(InvalidArgumentError, match="denoised"):
        _core.render.restore_half_resolution(den, 4 * h, w)


def test_half_resolution_denoise_keeps_full_size_print() -> None:
    """A one-pixel checker printed on a surface under smooth light, traced noisily: the ``half``
    denoise runs OIDN on 2 x 2 blocks (where the checker averages out) yet returns the checker
    at full size and contrast, through the ratio of the exact (``raw``) albedo, with a twentieth
    of the input's squared error; without an albedo it returns the blocks' interpolation (no
    checker)."""
    if not denoiser.denoiser_available():
        pytest.fail("pyoidn (test extra) is not installed")
    h, w = 64, 48
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    checker = np.where((yy + xx) % 2 == 0, 0.8, 0.2).astype(np.float32)
    albedo = np.repeat(checker[..., None], 3, axis=2)
    light = (1.0 + 0.3 * xx / w)[..., None].astype(np.float32)
    clean = albedo * light
    rng = np.random.default_rng(6)
    noisy = (clean * rng.gamma(8.0, 1.0 / 8.0, (h, w, 1))).astype(np.float32)
    normal = np.zeros((h, w, 3), np.float32)
    normal[..., 2] = 1.0
    out = denoiser.denoise(noisy, albedo, normal, resolution="half", guides="raw")
    assert out.shape == noisy.shape
    assert out.dtype == np.float32
    assert out.min() >= 0.0
    err_out = float(np.mean((out - clean) ** 2))
    err_in = float(np.mean((noisy - clean) ** 2))
    assert err_out < 0.05 * err_in, (err_out, err_in)
    # the checker survives: light and dark pixels alternate as in the print, at 4 : 1
    dark, lit = out[(yy + xx) % 2 == 1].mean(), out[(yy + xx) % 2 == 0].mean()
    assert lit / dark == pytest.approx(4.0, rel=0.02), (lit, dark)
    flat = denoiser.denoise(noisy, None, None, resolution="half", guides="none")
    assert abs(flat[(yy + xx) % 2 == 0].mean() / flat[(yy + xx) % 2 == 1].mean() - 1.0) < 0.1
    with pytest.raises(InvalidArgumentError, match="resolution must be one of"):
        denoiser.denoise(noisy, albedo, normal, resolution="quarter")
    with pytest.raises(InvalidArgumentError, match="denoise_resolution"):
        RenderSettings(engine="path", denoise_resolution="quarter")
    # a one-pixel-high image is denoised at full size
    assert denoiser.denoise(noisy[:1], albedo[:1], normal[:1], resolution="half").shape == (1, w, 3)


def test_smoothed_guides_are_opencvs_3x3_gaussian() -> None:
    """The ``smoothed`` guides' blur is a 3 x 3 Gaussian of sigma 0.5 px with the border pixels
    repeated: OpenCV's GaussianBlur (BORDER_REPLICATE) gives the same image; a constant image
    stays constant and a single bright pixel spreads into exactly its 3 x 3 neighbourhood."""
    import cv2

    img = np.random.default_rng(4).random((23, 17, 3)).astype(np.float32)
    want = cv2.GaussianBlur(img, (3, 3), 0.5, borderType=cv2.BORDER_REPLICATE)
    got = denoiser._smooth3(img)
    assert got.dtype == np.float32
    assert got.flags.c_contiguous
    assert got.shape == img.shape
    np.testing.assert_allclose(got, want, atol=1e-6)
    for threads in (1, 2, 5):  # the thread count does not change the image
        assert denoiser._smooth3(img, threads).tobytes() == got.tobytes()
    one_row = img[:1]
    np.testing.assert_allclose(
        denoiser._smooth3(one_row),
        cv2.GaussianBlur(one_row, (3, 3), 0.5, borderType=cv2.BORDER_REPLICATE),
        atol=1e-6,
    )
    flat = np.full((5, 6, 3), 0.3, np.float32)
    np.testing.assert_allclose(denoiser._smooth3(flat), flat, atol=1e-7)
    dot = np.zeros((7, 7, 3), np.float32)
    dot[3, 3] = 1.0
    blurred = denoiser._smooth3(dot)
    assert np.count_nonzero(blurred[..., 0]) == 9
    assert abs(blurred.sum() / 3 - 1.0) < 1e-6
    w = np.exp(-0.5 / 0.25)  # the side weight before normalisation, sigma 0.5
    assert blurred[3, 4, 0] == pytest.approx(blurred[3, 3, 0] * w, rel=1e-5)


def test_missing_denoiser_warns_and_traces_more_samples(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(denoiser, "_DENOISER", None)
    monkeypatch.setattr(denoiser, "_DENOISER_CHECKED", True)
    monkeypatch.setattr(photo, "_WARNED_NO_DENOISER", False)
    items, tote = _small_scene()
    s = RenderSettings(engine="path", spp=2, spp_without_denoiser=6)
    with pytest.warns(RuntimeWarning, match="pyoidn"):
        pr = photo.PhotoRenderer(items, tote, np.eye(4), None, s)
    assert pr.spp == 6
    assert pr.describe() == {"engine": "path", "spp": 6, "denoised": False, "max_bounces": 6}
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # warned once per process
        photo.PhotoRenderer(items, tote, np.eye(4), None, s)
    with pytest.raises(ImportError, match="pyoidn"):
        denoiser.denoise(np.zeros((4, 4, 3), np.float32))


def test_tiny_path_traced_dataset_validates(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:

    monkeypatch.setenv("MGN_CACHE_DIR", str(tmp_path / "cache"))
    cfg = {
        "objects": {"names": ["box_tea", "can_soda", "bottle_clear"]},
        "camera": {"views": [0, 9], "resolution_scale": 0.05},
        "labels": {
            "suction": False,
            "paralleljaw": False,
            "pj_physics": False,
            "scene_grasps": False,
        },
        "drop": {"max_time": 1.0},
        "render": {"spp": 2},
    }
    (tmp_path / "cfg.yaml").write_text(json.dumps(cfg))
    out = tmp_path / "ds"
    assert (
        main(
            [
                "generate",
                "--out",
                str(out),
                "--scenes",
                "1",
                "--config",
                str(tmp_path / "cfg.yaml"),
                "--engine",
                "path",
                "--quiet",
            ]
        )
        == 0
    )
    assert main(["validate", str(out)]) == 0
    info = json.loads((out / "dataset.json").read_text())
    assert info["config"]["render"]["engine"] == "path"
    manifest = json.loads((out / "scene0" / "manifest.json").read_text())
    assert manifest["render"]["engine"] == "path"
    assert image_engines(mgn.Dataset(out)).startswith("path tracer, ")

    rgb = np.asarray(Image.open(out / "scene0" / "0_rgb.png"))
    assert rgb.shape == (60, 60, 3)
    assert rgb.std() > 5
