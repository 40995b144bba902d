"""Adaptive sampling of the path tracer (PathTraceOptions.adaptive_samples / adaptive_max,
render.adaptive_samples): the extra samples go where the image is noisy, the expected value
stays that of the radiometric integral, the image is the same for any number of threads and
the labels do not change."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_path_tracer import camera, quad

from mgn.errors import InvalidArgumentError
from mgn.geometry import make_box, make_sphere
from mgn.render.path import AreaLight, Environment, PathScene, PathTraceOptions, PbrMaterial
from mgn.render.settings import RenderSettings

BLACK = Environment(kind="uniform", color=(0.0, 0.0, 0.0), intensity=0.0)


def mixed_scene() -> PathScene:
    """Glass sphere, metal box and a grey floor under a rect light and a sky: noisy (glass,
    shadows, indirect light) and quiet (directly lit floor) regions."""
    sphere, box, floor = make_sphere(0.3, 32, 16), make_box([0.3, 0.3, 0.3]), quad(3.0, z=-0.3)
    Xs, Xb = np.eye(4), np.eye(4)
    Xs[:3, 3] = (-0.35, 0, 0)
    Xb[:3, 3] = (0.35, 0, -0.15)
    mats = [
        [PbrMaterial(transmission=1.0, roughness=0.0)],
        [PbrMaterial(base_color=(0.9, 0.6, 0.2), metallic=1.0, roughness=0.3)],
        [PbrMaterial(base_color=(0.5, 0.5, 0.5))],
    ]
    X_WL = np.diag([1.0, -1.0, -1.0, 1.0])
    X_WL[:3, 3] = (0, 0, 1.2)
    return PathScene(
        [sphere, box, floor],
        np.stack([Xs, Xb, np.eye(4)]),
        [1, 2, 3],
        mats,
        [AreaLight(X_WL, "rect", (0.4, 0.4), intensity=15)],
        Environment(kind="sky", intensity=0.5),
    )


def test_adaptive_same_bytes_for_one_and_two_threads_and_labels_unchanged():
    scene = mixed_scene()
    view = camera((0, -2.0, 1.0), (0, 0, 0), 48, 50)
    opts = {"spp": 2, "seed": 9, "view_index": 2, "adaptive_samples": 1.0, "adaptive_max": 4}
    outs = [
        scene.render(view, PathTraceOptions(**opts, num_threads=t, aperture_radius=0.01))
        for t in (1, 2)
    ]
    for name in ("radiance", "albedo", "normal", "depth", "instance_ids"):
        assert getattr(outs[0], name).tobytes() == getattr(outs[1], name).tobytes(), name
    plain = scene.render(view, PathTraceOptions(spp=2, seed=9, view_index=2, aperture_radius=0.01))
    assert plain.instance_ids.tobytes() == outs[0].instance_ids.tobytes()
    assert plain.depth.tobytes() == outs[0].depth.tobytes()
    changed = np.any(plain.radiance != outs[0].radiance, axis=-1)
    # Extra samples were traced in some pixels (more rays) but not in all of them.
    assert outs[0].rays > plain.rays
    assert 0.05 < changed.mean() < 0.95, changed.mean()
    assert np.all(np.isfinite(outs[0].radiance))
    np.testing.assert_allclose(
        np.linalg.norm(outs[0].normal[outs[0].instance_ids > 0], axis=-1), 1, atol=1e-4
    )


def test_extra_samples_go_where_the_variance_is():
    """The per-pixel variance over 12 seeds (independent truth: the spread of independent
    renders) without adaptive sampling ranks the pixels; with 1 extra sample per pixel on
    average, uniform sampling would halve every pixel's variance. The noisiest quarter must
    gain more than that and the quietest half less: the extra samples went where the noise
    is."""
    scene = mixed_scene()
    view = camera((0, -2.0, 1.0), (0, 0, 0), 40, 50)

    def var(adaptive: float) -> np.ndarray:
        imgs = [
            scene.render(
                view, PathTraceOptions(spp=1, seed=s, adaptive_samples=adaptive, clamp_indirect=0.0)
            ).radiance.mean(-1)
            for s in range(12)
        ]
        return np.var(np.stack(imgs), axis=0, ddof=1)

    v0, v1 = var(0.0), var(1.0)
    order = np.argsort(v0.ravel())
    n = order.size
    noisy, quiet = order[-n // 4 :], order[: n // 2]
    ratio_noisy = v1.ravel()[noisy].sum() / v0.ravel()[noisy].sum()
    ratio_quiet = v1.ravel()[quiet].sum() / max(v0.ravel()[quiet].sum(), 1e-30)
    assert ratio_noisy < 0.45, ratio_noisy
    assert ratio_quiet > 0.6, ratio_quiet


def rect_irradiance(p, centre, size, Le, n=80):
    h = size / 2
    g = (np.arange(n) + 0.5) / n * size - h
    X, Y = np.meshgrid(g + centre[0], g + centre[1])
    d = np.stack([X - p[0], Y - p[1], np.full_like(X, centre[2] - p[2])], -1)
    r2 = (d**2).sum(-1)
    cos = d[..., 2] / np.sqrt(r2)
    return Le * (cos * cos / r2).sum() * (size / n) ** 2


def test_adaptive_sampling_keeps_the_analytic_irradiance():
    """A Lambertian plane (albedo a) under a rect light, with a box casting a soft shadow, seen
    at 4 spp + 4 adaptive samples on average (6 seeds): the unoccluded pixels show
    a / pi * E(p) (E by quadrature), in 4 x 4 pixel blocks within 3 % (Monte Carlo error ~1 %)
    and on average within 1 % — as without adaptive sampling."""
    a, Le, size, height = 0.5, 20.0, 0.3, 0.5
    mat = PbrMaterial(base_color=(a,) * 3, ior=1.0)
    X_WL = np.diag([1.0, -1.0, -1.0, 1.0])
    X_WL[:3, 3] = (0.0, 0.0, height)
    light = AreaLight(X_WL, "rect", (size, size), (1.0, 1.0, 1.0), Le)
    blocker = make_box([0.1, 0.1, 0.1])
    Xb = np.eye(4)
    Xb[:3, 3] = (0.35, 0.25, 0.05)
    scene = PathScene(
        [quad(4.0), blocker], np.stack([np.eye(4), Xb]), [1, 2], [[mat], [mat]], [light], BLACK
    )
    view = camera((0.0, 0.0, 1.5), (0.0, 0.0, 0.0), 32, 50, up=(0, 1, 0))
    K = view.K
    u, v = np.meshgrid(np.arange(K.width) + 0.5, np.arange(K.height) + 0.5)
    d_C = np.stack([(u - K.cx) / K.fx, (v - K.cy) / K.fy, np.ones_like(u)], -1)
    d_W = d_C @ view.X_WC[:3, :3].T
    t = -view.X_WC[2, 3] / d_W[..., 2]
    P = view.X_WC[:3, 3] + t[..., None] * d_W
    # Pixels whose footprint sees the light unoccluded (the box and its shadow are far enough).
    far = (np.hypot(P[..., 0] - 0.35, P[..., 1] - 0.25) > 0.3) & (np.abs(P[..., 0]) < 0.45)
    far &= np.abs(P[..., 1]) < 0.45
    expected = np.array(
        [
            [
                a / math.pi * rect_irradiance(P[i, j], (0, 0, height), size, Le)
                for j in range(K.width)
            ]
            for i in range(K.height)
        ]
    )
    means = {}
    for adaptive in (0.0, 4.0):
        imgs = [
            scene.render(
                view,
                PathTraceOptions(
                    spp=4, max_bounces=1, seed=s, adaptive_samples=adaptive, adaptive_max=12
                ),
            ).radiance.mean(-1)
            for s in range(6)
        ]
        img = np.mean(imgs, axis=0)
        blocks = far.reshape(8, 4, 8, 4).all(axis=(1, 3))
        got_b, exp_b = (x.reshape(8, 4, 8, 4).mean(axis=(1, 3))[blocks] for x in (img, expected))
        assert blocks.sum() >= 10
        np.testing.assert_allclose(got_b, exp_b, rtol=0.03)
        means[adaptive] = float(img[far].mean() / expected[far].mean())
    assert means[4.0] == pytest.approx(1.0, abs=0.01), means
    assert far.sum() > 200


@pytest.mark.parametrize(
    ("kw", "name"),
    [
        ({"adaptive_samples": -0.5}, "adaptive_samples"),
        ({"adaptive_samples": float("inf")}, "adaptive_samples"),
        ({"adaptive_max": 0}, "adaptive_max"),
        ({"adaptive_max": 65}, "adaptive_max"),
    ],
)
def test_bad_adaptive_settings_name_the_setting(kw, name):
    with pytest.raises(InvalidArgumentError, match=f"PathTraceOptions.{name}"):
        PathTraceOptions(**kw)
    with pytest.raises(InvalidArgumentError, match=f"RenderSettings.{name}"):
        RenderSettings(**kw)
