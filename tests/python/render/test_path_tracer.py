"""The path tracer (mgn.render.path) against analytic radiometry and the raster passes.

Every expected value is derived here from first principles (furnace tests, the irradiance of a
rect light by quadrature, Fresnel transmission of a pane), not taken from a previous run.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from mgn.errors import InvalidArgumentError
from mgn.geometry import make_box, make_sphere, mesh_from_arrays
from mgn.render.path import (
    AreaLight,
    Environment,
    FilmOptions,
    PathScene,
    PathTraceOptions,
    PbrMaterial,
    develop,
)
from mgn.scene.cameras import CameraView, Intrinsics, look_at

LAMBERT_WHITE = PbrMaterial(base_color=(1.0, 1.0, 1.0), ior=1.0, roughness=1.0)


def camera(eye, target, size: int, fov_deg: float, up=(0.0, 0.0, 1.0)) -> CameraView:
    f = 0.5 * size / math.tan(math.radians(fov_deg) / 2)
    K = Intrinsics(size, size, f, f, size / 2, size / 2)
    return CameraView(
        K, look_at(np.asarray(eye, float), np.asarray(target, float), np.asarray(up, float))
    )


def quad(size: float, z: float = 0.0):
    """Square of side `size` in the plane z, normal +z (CCW seen from +z)."""
    h = size / 2
    v = [[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]]
    return mesh_from_arrays(v, [[0, 1, 2], [0, 2, 3]])


def uniform(L: float) -> Environment:
    return Environment(kind="uniform", color=(1.0, 1.0, 1.0), intensity=L)


def interior(mask: np.ndarray) -> np.ndarray:
    """Pixels of `mask` whose 8 neighbours are in it too (no silhouette pixels, which mix the
    object and what is behind it)."""
    m = mask.copy()
    p = np.pad(mask, 1)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            m &= p[1 + di : 1 + di + mask.shape[0], 1 + dj : 1 + dj + mask.shape[1]]
    return m


BLACK = Environment(kind="uniform", color=(0.0, 0.0, 0.0), intensity=0.0)


# ---------------------------------------------------------------------------------------------
# Furnace tests.


@pytest.mark.parametrize("albedo", [1.0, 0.5])
def test_exterior_furnace_lambert_sphere_shows_albedo_times_L(albedo):
    """A convex Lambertian sphere of albedo a in a uniform dome L: every path leaves after one
    bounce and sees L, so the sphere shows a * L (and the background L)."""
    L = 0.8
    mat = PbrMaterial(base_color=(albedo,) * 3, ior=1.0)
    # Fine tessellation: smooth shading normals differ little from the facets (a cosine lobe
    # around the shading normal loses the directions below the facet).
    scene = PathScene([make_sphere(0.5, 128, 64)], np.eye(4)[None], [1], [[mat]], (), uniform(L))
    out = scene.render(camera((0, -3, 0.5), (0, 0, 0), 24, 25), PathTraceOptions(spp=8, seed=3))
    on = interior(out.instance_ids == 1)
    off = interior(out.instance_ids == 0)
    assert on.sum() > 150
    assert off.sum() > 50
    np.testing.assert_allclose(out.radiance[on], albedo * L, rtol=3e-3)
    np.testing.assert_allclose(out.radiance[off], L, rtol=1e-6)
    # No bounce allowed: the sphere is black, the dome still seen directly.
    out0 = scene.render(
        camera((0, -3, 0.5), (0, 0, 0), 24, 25), PathTraceOptions(spp=2, max_bounces=0)
    )
    assert np.all(out0.radiance[interior(out0.instance_ids == 1)] == 0)
    np.testing.assert_allclose(out0.radiance[interior(out0.instance_ids == 0)], L, rtol=1e-6)


@pytest.mark.parametrize("albedo", [1.0, 0.5])
@pytest.mark.parametrize("reduced_nee_depth", [0, 1])
def test_exterior_furnace_without_dome_shadow_rays_shows_albedo_times_L(albedo, reduced_nee_depth):
    """The furnace of the test above with the dome left to the BSDF-sampled rays
    (sample_sky_dome False) at every vertex, or from the first bounce's hit on (the camera
    ray's hit keeps its shadow ray to the dome, weighed against its bounce ray by MIS): the
    sphere still shows a * L."""
    L = 0.8
    mat = PbrMaterial(base_color=(albedo,) * 3, ior=1.0)
    scene = PathScene([make_sphere(0.5, 128, 64)], np.eye(4)[None], [1], [[mat]], (), uniform(L))
    view = camera((0, -3, 0.5), (0, 0, 0), 24, 25)
    opts = PathTraceOptions(
        spp=8, seed=3, sample_sky_dome=False, reduced_nee_depth=reduced_nee_depth
    )
    out = scene.render(view, opts)
    on = interior(out.instance_ids == 1)
    assert on.sum() > 150
    np.testing.assert_allclose(out.radiance[on], albedo * L, rtol=3e-3)
    np.testing.assert_allclose(out.radiance[interior(out.instance_ids == 0)], L, rtol=1e-6)
    # Label and camera rays, one bounce ray per sample that hits the sphere (and there one
    # shadow ray if the camera ray's hit samples the dome).
    n_hit = int((out.instance_ids == 1).sum())
    per_hit = 1 + (reduced_nee_depth > 0)
    assert out.rays < 24 * 24 * (8 + 1) + n_hit * 8 * per_hit * 1.1
    assert out.rays > 24 * 24 * (8 + 1) + n_hit * 8 * per_hit * 0.9


@pytest.mark.parametrize(
    ("max_bounces", "rr_depth"), [(0, 100), (1, 100), (2, 100), (3, 100), (200, 1)]
)
def test_interior_furnace_closed_emitting_sphere(max_bounces, rr_depth):
    """Inside a closed sphere whose inner surface emits E and reflects with albedo a (Lambert),
    every point receives the same radiance from every direction, so a path of k segments after
    the camera ray collects E (1 + a + ... + a^k) = E (1 - a^(k+1)) / (1 - a); with unlimited
    bounces E / (1 - a) (here with Russian roulette from the first bounce: unbiased)."""
    E, a = 0.6, 0.5
    mat = PbrMaterial(base_color=(a,) * 3, ior=1.0, emission=(E,) * 3)
    inner = make_sphere(1.0, 256, 128).flipped()  # normals (front sides) face the centre
    scene = PathScene([inner], np.eye(4)[None], [1], [[mat]], (), BLACK)
    view = camera((0, 0, 0), (1, 0.2, 0.1), 16, 90)
    out = scene.render(view, PathTraceOptions(spp=64, max_bounces=max_bounces, rr_depth=rr_depth))
    expected = E * (1 - a ** (max_bounces + 1)) / (1 - a)
    mean = out.radiance.mean()
    if rr_depth >= max_bounces:  # no roulette: every sample is exact
        # A few directions sampled about a smooth shading normal fall below the facet and are
        # lost: the mean is exact to 0.1 %, single pixels to 1 %.
        assert mean == pytest.approx(expected, rel=1e-3)
        np.testing.assert_allclose(out.radiance, expected, rtol=1e-2)
    else:
        sem = out.radiance[..., 1].std() / math.sqrt(out.radiance[..., 1].size)
        assert abs(mean - expected) < max(4 * sem, 0.01 * expected), (mean, expected, sem)


def test_no_light_enters_a_sealed_box_under_a_bright_sky():
    """Camera inside a closed box (white Lambert walls, a Lambert sphere and a sun-lit sky
    outside): no path can reach the sky or the sun, so every pixel is exactly black, while the
    walls' albedo guide is seen. Long paths (no roulette, 32 bounces) cast ~10^6 bounce and
    shadow rays through a closed mesh's edges and corners: a BVH query that let rays slip
    between triangles would light pixels up (the bounce and shadow rays use a non-robust BVH)."""
    wall = PbrMaterial(base_color=(0.95, 0.95, 0.95), ior=1.0, roughness=1.0)
    box = make_box([1.0, 0.8, 0.6])
    ball = make_sphere(0.15, 48, 24)
    Xb = np.eye(4)
    Xb[:3, 3] = (0.2, 0.1, -0.15)
    sky = Environment(kind="sky", intensity=3.0, sun_strength=20.0)
    scene = PathScene([box, ball], np.stack([np.eye(4), Xb]), [1, 2], [[wall], [wall]], (), sky)
    view = camera((-0.3, -0.25, 0.1), (0.4, 0.3, -0.2), 48, 100)
    out = scene.render(view, PathTraceOptions(spp=16, max_bounces=32, rr_depth=100, seed=5))
    assert out.rays > 10**6
    assert np.all(out.instance_ids > 0)
    assert np.all(out.radiance == 0.0)
    assert out.albedo.min() > 0.9
    # The same box open to the sky (its top removed) is lit: the test can see light.
    keep = np.abs(box.face_normals()[:, 2] - 1.0) > 1e-6
    open_box = mesh_from_arrays(box.vertices, box.faces[keep])
    lit = PathScene([open_box, ball], np.stack([np.eye(4), Xb]), [1, 2], [[wall], [wall]], (), sky)
    out2 = lit.render(view, PathTraceOptions(spp=4, max_bounces=8, seed=5))
    assert out2.radiance.mean() > 0.05


@pytest.mark.parametrize("metallic", [0.0, 1.0])
@pytest.mark.parametrize("roughness", [0.1, 0.3, 0.6, 1.0])
def test_ggx_sphere_in_furnace_shows_L(metallic, roughness):
    """A GGX sphere (dielectric over Lambert, or metal) of base colour 1 in a uniform dome L
    reflects everything it receives, so it shows L: single-scattering microfacets alone lose the
    light that bounces between microfacets (a metal at roughness 1 kept 0.37 L), which the
    multiple-scattering compensation returns; under the specular layer the diffuse lobe gets
    what the layer does not reflect. The red channel of a gold-coloured metal (base red 1, so
    Fresnel 1 in red) shows L as well, its other channels less (each bounce absorbs)."""
    L = 1.0
    base = (1.0, 1.0, 1.0) if metallic == 0.0 else (1.0, 0.78, 0.34)
    mat = PbrMaterial(base_color=base, metallic=metallic, roughness=roughness, ior=1.5)
    scene = PathScene([make_sphere(0.5, 128, 64)], np.eye(4)[None], [1], [[mat]], (), uniform(L))
    out = scene.render(
        camera((0, -3, 0), (0, 0, 0), 24, 22),
        PathTraceOptions(spp=64, seed=5, max_bounces=64, rr_depth=64),
    )
    v = out.radiance[interior(out.instance_ids == 1)]
    sem = v[:, 0].std() / math.sqrt(len(v))
    # 0.3 %: the shading normals of the tessellated sphere lose a few directions below facets.
    assert abs(v[:, 0].mean() - L) <= 4 * sem + 3e-3, (v.mean(0), sem)
    assert np.quantile(v[:, 0], 0.9) <= L * 1.05
    if metallic == 1.0:
        assert np.all(v[:, 1:].mean(0) < np.asarray(base[1:]) + 4 * sem + 3e-3)
        assert np.all(v[:, 1:].mean(0) > 0.4 * np.asarray(base[1:]))


# ---------------------------------------------------------------------------------------------
# Direct lighting.


def rect_irradiance(p, centre, size, Le, n=400):
    """Irradiance (W m^-2 per unit radiance colour) at point p (normal +z) from a horizontal rect
    light centred at `centre`, facing down, by midpoint quadrature of Le cos_s cos_l / r^2."""
    h = size / 2
    g = (np.arange(n) + 0.5) / n * size - h
    X, Y = np.meshgrid(g + centre[0], g + centre[1])
    d = np.stack([X - p[0], Y - p[1], np.full_like(X, centre[2] - p[2])], -1)
    r2 = (d**2).sum(-1)
    cos_s = d[..., 2] / np.sqrt(r2)
    cos_l = cos_s  # parallel planes
    return Le * (cos_s * cos_l / r2).sum() * (size / n) ** 2


def test_lambert_plane_under_rect_light_matches_analytic_irradiance():
    """A Lambertian plane of albedo a under a small rect light of radiance Le shows
    a / pi * E(p), E from the radiometric integral (direct lighting only)."""
    a, Le, size, height = 0.5, 20.0, 0.1, 0.5
    plane = quad(4.0)
    mat = PbrMaterial(base_color=(a,) * 3, ior=1.0)
    X_WL = np.diag([1.0, -1.0, -1.0, 1.0])  # facing down (+z_L = -z_W)
    X_WL[:3, 3] = (0.0, 0.0, height)
    light = AreaLight(X_WL, "rect", (size, size), (1.0, 1.0, 1.0), Le)
    scene = PathScene([plane], np.eye(4)[None], [1], [[mat]], [light], BLACK)
    view = camera((0.35, 0.0, 1.5), (0.35, 0.0, 0.0), 32, 60, up=(0, 1, 0))
    out = scene.render(view, PathTraceOptions(spp=64, max_bounces=1, seed=1))
    # Pixel centre rays -> points on the plane.
    K = view.K
    u, v = np.meshgrid(np.arange(K.width) + 0.5, np.arange(K.height) + 0.5)
    d_C = np.stack([(u - K.cx) / K.fx, (v - K.cy) / K.fy, np.ones_like(u)], -1)
    d_W = d_C @ view.X_WC[:3, :3].T
    t = -view.X_WC[2, 3] / d_W[..., 2]
    P = view.X_WC[:3, 3] + t[..., None] * d_W
    checked = 0
    for i, j in [(16, 16), (16, 4), (16, 28), (4, 16), (28, 28), (2, 2)]:
        E = rect_irradiance(P[i, j], (0.0, 0.0, height), size, Le)
        expected = a / math.pi * E
        got = out.radiance[i, j].mean()
        assert got == pytest.approx(expected, rel=0.02), ((i, j), got, expected)
        checked += 1
    assert checked == 6
    # Falloff sanity: the brightest pixel is the one under the light (x = 0).
    col = np.argmax(out.radiance[16, :, 1])
    assert abs(P[16, col, 0]) < 0.06


@pytest.mark.parametrize(("shadow_rays", "reduced_nee_depth"), [(2, 0), (1, 0), (1, 1)])
def test_lambert_plane_under_rect_light_and_sky_with_one_or_two_shadow_rays(
    shadow_rays, reduced_nee_depth
):
    """A Lambertian plane of albedo a under a small rect light of radiance Le and a uniform sky
    L shows a / pi * E(p) + a * L (direct lighting only; the light hides 1.3 % of the sky's
    projected solid angle), whether each vertex casts a shadow ray to the light and one to the
    sky or one ray to either of them."""
    a, Le, L, size, height = 0.5, 20.0, 0.5, 0.1, 0.5
    mat = PbrMaterial(base_color=(a,) * 3, ior=1.0)
    X_WL = np.diag([1.0, -1.0, -1.0, 1.0])  # facing down (+z_L = -z_W)
    X_WL[:3, 3] = (0.0, 0.0, height)
    light = AreaLight(X_WL, "rect", (size, size), (1.0, 1.0, 1.0), Le)
    scene = PathScene([quad(4.0)], np.eye(4)[None], [1], [[mat]], [light], uniform(L))
    view = camera((0.2, 0.0, 1.5), (0.2, 0.0, 0.0), 16, 60, up=(0, 1, 0))
    opts = PathTraceOptions(
        spp=256,
        max_bounces=1,
        seed=2,
        shadow_rays=shadow_rays,
        reduced_nee_depth=reduced_nee_depth,
    )
    out = scene.render(view, opts)
    K = view.K
    u, v = np.meshgrid(np.arange(K.width) + 0.5, np.arange(K.height) + 0.5)
    d_C = np.stack([(u - K.cx) / K.fx, (v - K.cy) / K.fy, np.ones_like(u)], -1)
    d_W = d_C @ view.X_WC[:3, :3].T
    t = -view.X_WC[2, 3] / d_W[..., 2]
    P = view.X_WC[:3, 3] + t[..., None] * d_W
    E = np.array(
        [[rect_irradiance(p, (0.0, 0.0, height), size, Le, n=100) for p in row] for row in P]
    )
    expected = a / math.pi * E + a * L
    got = out.radiance.mean(-1)
    assert got.mean() == pytest.approx(expected.mean(), rel=0.01)
    # Within 4 x 4 blocks (4096 samples each): the light's pattern, not only its total.
    blocks = (got - expected).reshape(4, 4, 4, 4).mean((1, 3))
    ref = expected.reshape(4, 4, 4, 4).mean((1, 3))
    assert np.all(np.abs(blocks) < 0.03 * ref), blocks / ref
    # Per sample: the camera ray, the shadow rays, the bounce ray (and per pixel one label ray).
    rays_per_sample = out.rays / (K.width * K.height * opts.spp)
    # (reduced_nee_depth 1: the camera ray's hit, the only vertex here, casts both.)
    shadow = 2 if reduced_nee_depth > 0 else shadow_rays
    assert rays_per_sample == pytest.approx(2 + shadow + 1 / opts.spp, abs=1e-3)


def test_emissive_quad_is_sampled_like_the_area_light_of_its_shape():
    """A small emissive mesh (a quad of two triangles, radiance Le on its front side) lighting a
    Lambertian plane: next-event estimation samples its triangles, so 64 samples match the
    analytic irradiance within 2 % (found by BSDF sampling alone, the 0.1 m quad subtends
    ~1 % of the hemisphere and 64 samples would miss it in most pixels), and the plane looks as
    under the AreaLight of the same shape and radiance, within the Monte Carlo error."""
    a, Le, size, height = 0.5, 20.0, 0.1, 0.5
    mat = PbrMaterial(base_color=(a,) * 3, ior=1.0)
    X_WL = np.diag([1.0, -1.0, -1.0, 1.0])  # facing down (+z_L = -z_W)
    X_WL[:3, 3] = (0.0, 0.0, height)
    emitter = PbrMaterial(base_color=(0.0,) * 3, ior=1.0, emission=(Le,) * 3)
    meshed = PathScene(
        [quad(4.0), quad(size)], np.stack([np.eye(4), X_WL]), [1, 2], [[mat], [emitter]], (), BLACK
    )
    light = AreaLight(X_WL, "rect", (size, size), (1.0, 1.0, 1.0), Le)
    analytic = PathScene([quad(4.0)], np.eye(4)[None], [1], [[mat]], [light], BLACK)
    view = camera((0.35, 0.0, 1.5), (0.35, 0.0, 0.0), 32, 60, up=(0, 1, 0))
    opts = PathTraceOptions(spp=64, max_bounces=1, seed=1)
    out = meshed.render(view, opts)
    ref = analytic.render(view, opts)
    K = view.K
    u, v = np.meshgrid(np.arange(K.width) + 0.5, np.arange(K.height) + 0.5)
    d_C = np.stack([(u - K.cx) / K.fx, (v - K.cy) / K.fy, np.ones_like(u)], -1)
    d_W = d_C @ view.X_WC[:3, :3].T
    P = view.X_WC[:3, 3] + (-view.X_WC[2, 3] / d_W[..., 2])[..., None] * d_W
    # Pixels whose whole footprint is on the plane, not partly on the quad's (black) back, which
    # the camera above sees between the plane's pixels x ~ -0.18 .. -0.02 m.
    on_plane = interior(out.instance_ids == 1)
    checked = 0
    for i, j in [(16, 20), (16, 1), (16, 28), (4, 16), (28, 28), (2, 2)]:
        assert on_plane[i, j]
        expected = a / math.pi * rect_irradiance(P[i, j], (0.0, 0.0, height), size, Le)
        got = out.radiance[i, j].mean()
        assert got == pytest.approx(expected, rel=0.02), ((i, j), got, expected)
        checked += 1
    assert checked == 6
    plane = on_plane
    assert plane.sum() > 0.8 * plane.size
    assert out.radiance[plane].mean() == pytest.approx(ref.radiance[plane].mean(), rel=0.01)
    np.testing.assert_allclose(out.radiance[plane], ref.radiance[plane], rtol=0.05, atol=1e-4)
    # The emitter seen from the front shows Le (a camera below it, looking up).
    up = camera((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 8, 4, up=(0, 1, 0))
    seen = meshed.render(up, PathTraceOptions(spp=4, max_bounces=1))
    np.testing.assert_allclose(seen.radiance[seen.instance_ids == 2], Le, rtol=1e-5)


def test_disc_light_and_soft_shadow():
    """A disc light over a plane with a small blocker casts a shadow with an umbra and a
    penumbra (soft shadow): values strictly between the umbra and the lit plane exist."""
    plane = quad(4.0)
    blocker = make_box([0.1, 0.1, 0.02])
    Xb = np.eye(4)
    Xb[:3, 3] = (0, 0, 0.25)
    X_WL = np.diag([1.0, -1.0, -1.0, 1.0])
    X_WL[:3, 3] = (0.0, 0.0, 0.5)
    light = AreaLight(X_WL, "disc", (0.08, 0.08), (1, 1, 1), 20.0)
    mat = PbrMaterial(base_color=(0.5,) * 3, ior=1.0)
    scene = PathScene(
        [plane, blocker], np.stack([np.eye(4), Xb]), [1, 2], [[mat], [mat]], [light], BLACK
    )
    # Look at the shadow from below the blocker's height, from the side.
    view = camera((0.0, -0.6, 0.2), (0.0, 0.0, 0.0), 48, 60)
    out = scene.render(view, PathTraceOptions(spp=64, max_bounces=1))
    row = out.radiance[..., 1][out.instance_ids == 1]
    lit = np.quantile(row, 0.95)
    dark = row.min()
    assert dark < 0.2 * lit
    mid = ((row > dark + 0.2 * (lit - dark)) & (row < dark + 0.8 * (lit - dark))).sum()
    assert mid >= 10  # penumbra pixels


# ---------------------------------------------------------------------------------------------
# Dielectrics.


@pytest.mark.parametrize("ior", [1.5, 2.5])
def test_glass_pane_at_normal_incidence_transmits_fresnel_loss(ior):
    """A clear pane (two parallel faces) in front of an emitter seen at normal incidence:
    R = ((n-1)/(n+1))^2 per surface; one pass through both faces transmits (1-R)^2; with all
    internal reflections (1-R)^2 / (1-R^2) = (1-R)/(1+R)."""
    Le = 1.0
    R = ((ior - 1) / (ior + 1)) ** 2
    pane = make_box([2.0, 2.0, 0.02])
    glass = PbrMaterial(base_color=(1, 1, 1), transmission=1.0, roughness=0.0, ior=ior)
    emitter = quad(4.0, z=-0.5)
    black_emitter = PbrMaterial(base_color=(0, 0, 0), ior=1.0, emission=(Le,) * 3)
    scene = PathScene(
        [pane, emitter],
        np.stack([np.eye(4), np.eye(4)]),
        [1, 2],
        [[glass], [black_emitter]],
        (),
        BLACK,
    )
    view = camera((0, 0, 1.0), (0, 0, 0), 32, 10, up=(0, 1, 0))
    one_pass = scene.render(view, PathTraceOptions(spp=64, max_bounces=2, rr_depth=100)).radiance
    full = scene.render(view, PathTraceOptions(spp=64, max_bounces=40, rr_depth=100)).radiance
    n = one_pass[..., 0].size * 64
    tol = 4 * math.sqrt(R * (1 - R) / n) + 1e-4
    assert one_pass.mean() == pytest.approx(Le * (1 - R) ** 2, abs=tol)
    assert full.mean() == pytest.approx(Le * (1 - R) / (1 + R), abs=tol)


def _fresnel(cos_i: np.ndarray, n: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance from air into a medium of index n."""
    sin_t = np.sqrt(1.0 - cos_i**2) / n
    cos_t = np.sqrt(1.0 - sin_t**2)
    rs = (cos_i - n * cos_t) / (cos_i + n * cos_t)
    rp = (n * cos_i - cos_t) / (n * cos_i + cos_t)
    return 0.5 * (rs**2 + rp**2)


def _pane_under_lamp(ior: float, Le: float) -> PathScene:
    """A clear 2 m x 2 m x 2 cm pane at z = 0 (index of refraction ``ior``) under a 3 m x 3 m
    rect lamp of radiance ``Le`` facing down at z = 1.5 m, black environment."""
    X_WL = np.diag([1.0, -1.0, -1.0, 1.0])  # facing down, above the camera
    X_WL[:3, 3] = (0.0, 0.0, 1.5)
    light = AreaLight(X_WL, "rect", (3.0, 3.0), (1.0, 1.0, 1.0), Le)
    glass = PbrMaterial(base_color=(1, 1, 1), transmission=1.0, roughness=0.0, ior=ior)
    return PathScene([make_box([2.0, 2.0, 0.02])], np.eye(4)[None], [1], [[glass]], [light], BLACK)


def test_light_reflected_in_smooth_glass_is_split_not_sampled():
    """Fresnel splitting: at a smooth dielectric both the reflected and the refracted ray are
    traced to the light they meet first, weighted F and 1 - F. A clear pane under a large rect
    light (behind the camera, black environment) seen near normal incidence: with one bounce
    every sample of a pixel is exactly F(theta) Le (choosing reflection with probability F
    would give 0 or Le); with all internal reflections the mean is the slab's 2R / (1 + R) Le
    and the variance of one sample is well below the p (1 - p) Le^2 of the chosen-branch
    estimator (p = 2R / (1 + R)): only the internally reflected light stays random."""
    ior, Le = 1.5, 2.0
    scene = _pane_under_lamp(ior, Le)
    size = 64
    view = camera((0, 0, 1.0), (0, 0, 0), size, 10, up=(0, 1, 0))
    K = view.K
    u, v = np.meshgrid(np.arange(size) + 0.5, np.arange(size) + 0.5)
    cos_i = 1.0 / np.sqrt(((u - K.cx) / K.fx) ** 2 + ((v - K.cy) / K.fy) ** 2 + 1.0)
    one = scene.render(view, PathTraceOptions(spp=1, max_bounces=1, seed=3)).radiance
    np.testing.assert_allclose(one[..., 1], Le * _fresnel(cos_i, ior), rtol=2e-3)
    R = ((ior - 1) / (ior + 1)) ** 2
    p = 2 * R / (1 + R)
    samples = np.stack(
        [
            scene.render(
                view, PathTraceOptions(spp=1, max_bounces=40, rr_depth=100, seed=s)
            ).radiance[..., 1]
            for s in range(4)
        ]
    )
    n = samples.size
    mean, var = samples.mean(), samples.var(ddof=1)
    # Mean: within 4 standard errors of the analytic slab reflectance.
    assert mean == pytest.approx(Le * p, abs=4 * math.sqrt(var / n) + 1e-4)
    # Variance: the sample variance of a two-valued variable with a rare value has a relative
    # standard error of about sqrt(1 / (q n)), q ~ R (1 - R) its rarer outcome's probability.
    q = R * (1 - R)
    rel = math.sqrt(1.0 / (q * n))
    assert var * (1 - 4 * rel) < 0.7 * p * (1 - p) * Le**2, (var, p * (1 - p) * Le**2)


def test_first_glass_walls_are_traced_on_both_branches():
    """At the first three smooth-dielectric vertices of a camera sample both the reflected and
    the refracted ray are traced in full (weighted F and 1 - F), not one chosen at random. A clear
    pane under a rect lamp (black environment), seen near normal incidence: the light reflected
    by the top face, and by the bottom face back through the top one, reaches every sample; only
    the light of three or more internal reflections is left to chance (the fourth face's draw:
    at most (1 - R)^2 R^2 / (1 - R^2) Le, on average R^2 of that). So every 1-spp sample lies
    within 1.5 R^2 Le of the slab's mean 2R / (1 + R) Le, where a random choice at each face
    gives 0 or Le and splitting the first light only leaves the internally reflected
    (1 - R)^2 R Le (~15 R^2 Le) to chance."""
    ior, Le = 1.5, 2.0
    scene = _pane_under_lamp(ior, Le)
    view = camera((0, 0, 1.0), (0, 0, 0), 16, 4, up=(0, 1, 0))
    samples = np.stack(
        [
            scene.render(
                view, PathTraceOptions(spp=1, max_bounces=40, rr_depth=100, seed=s)
            ).radiance[..., 1]
            for s in range(6)
        ]
    )
    R = ((ior - 1) / (ior + 1)) ** 2  # within 2 degrees of normal incidence: R(theta) ~ R(0)
    mean = Le * 2 * R / (1 + R)
    assert np.abs(samples - mean).max() < 1.5 * R**2 * Le, np.abs(samples - mean).max()


def test_tinted_glass_pane_tints_once_per_pass_through_the_wall():
    """A tinted pane (base colour c) transmits c (1-R)^2 in one pass and c (1-R)/(1+R) with all
    internal reflections: the tint applies to light that crosses the wall (in and out), once,
    and not again per interface (a tint c per interface would give c^2: a bottle seen through
    its two walls darkened to c^4, the dark glass of the benchmark scene against Cycles)."""
    ior, c = 1.5, np.array([0.5, 0.8, 0.9])
    R = ((ior - 1) / (ior + 1)) ** 2
    glass = PbrMaterial(base_color=tuple(c), transmission=1.0, roughness=0.0, ior=ior)
    black_emitter = PbrMaterial(base_color=(0, 0, 0), ior=1.0, emission=(1.0,) * 3)
    scene = PathScene(
        [make_box([2.0, 2.0, 0.02]), quad(4.0, z=-0.5)],
        np.stack([np.eye(4), np.eye(4)]),
        [1, 2],
        [[glass], [black_emitter]],
        (),
        BLACK,
    )
    view = camera((0, 0, 1.0), (0, 0, 0), 32, 10, up=(0, 1, 0))
    one = scene.render(view, PathTraceOptions(spp=64, max_bounces=2, rr_depth=100)).radiance
    full = scene.render(view, PathTraceOptions(spp=64, max_bounces=40, rr_depth=100)).radiance
    tol = 4 * math.sqrt(R * (1 - R) / (one[..., 0].size * 64)) + 1e-4
    np.testing.assert_allclose(one.reshape(-1, 3).mean(0), c * (1 - R) ** 2, atol=tol)
    np.testing.assert_allclose(full.reshape(-1, 3).mean(0), c * (1 - R) / (1 + R), atol=tol)


def test_closed_thin_glass_shell_in_the_furnace_shows_L():
    """A hollow glass sphere (outer radius 0.5 m, a 1.5 mm wall: a closed outer surface and an
    inward-facing inner one, like the walls of a bottle) in a uniform dome L. Clear glass neither
    absorbs nor emits, and every path leaves the shell (concentric spheres trap no ray), so the
    shell shows L: the 1/eta^2 radiance scaling of every refraction must be undone by the
    refraction that leaves the same medium, whichever way the surfaces face (a missing or doubled
    scaling is off by a factor 2.25). Fresnel splitting (the sky seen along both the reflected
    and the refracted ray, weighted F and 1 - F) makes single samples differ from L, so the mean
    is checked within 4 standard errors and every pixel within 10 %."""
    outer = make_sphere(0.5, 64, 32)
    inner_src = make_sphere(0.4985, 64, 32)
    inner = mesh_from_arrays(np.asarray(inner_src.vertices), np.asarray(inner_src.faces)[:, ::-1])
    glass = PbrMaterial(base_color=(1, 1, 1), transmission=1.0, roughness=0.0, ior=1.5)
    scene = PathScene(
        [outer, inner],
        np.stack([np.eye(4), np.eye(4)]),
        [1, 1],
        [[glass], [glass]],
        (),
        uniform(0.7),
    )
    out = scene.render(
        camera((0, -3, 0), (0, 0, 0), 24, 22), PathTraceOptions(spp=64, max_bounces=64, rr_depth=3)
    )
    px = out.radiance[interior(out.instance_ids == 1)]
    assert float(px.mean()) == pytest.approx(
        0.7, abs=4 * float(px.std()) / math.sqrt(px.size) + 1e-4
    )
    np.testing.assert_allclose(px, 0.7, rtol=0.1)


@pytest.mark.parametrize("roughness", [0.1, 0.3, 0.6, 1.0])
def test_rough_glass_sphere_in_the_furnace_shows_L(roughness):
    """A rough dielectric (GGX reflection and refraction, Walter et al. 2007, with the
    multiple-scattering compensation) sphere in a uniform dome L neither absorbs nor emits, so it
    shows L at every roughness (single scattering alone showed 0.97 L at roughness 0.3, 0.72 L at
    0.6, 0.35 L at 1). The environment is sampled at the rough surface too (next-event estimation
    with MIS on the reflection side): a wrong pdf there would shift the mean."""
    glass = PbrMaterial(base_color=(1, 1, 1), transmission=1.0, roughness=roughness, ior=1.5)
    scene = PathScene([make_sphere(0.5, 64, 32)], np.eye(4)[None], [1], [[glass]], (), uniform(0.7))
    out = scene.render(
        camera((0, -3, 0), (0, 0, 0), 24, 22), PathTraceOptions(spp=64, max_bounces=64, rr_depth=64)
    )
    v = out.radiance[interior(out.instance_ids == 1)] / 0.7
    sigma = v.std() / math.sqrt(v.size)
    assert abs(v.mean() - 1.0) <= 4 * sigma + 3e-3, (v.mean(), sigma)


@pytest.mark.parametrize("roughness", [0.0, 0.06])
def test_slightly_rough_pane_transmits_like_the_smooth_one(roughness):
    """At normal incidence a pane of small roughness transmits what the smooth pane does,
    (1-R)/(1+R) with all internal reflections (the emitter behind fills every direction the
    rough surfaces spread the light into)."""
    ior = 1.5
    R = ((ior - 1) / (ior + 1)) ** 2
    glass = PbrMaterial(base_color=(1, 1, 1), transmission=1.0, roughness=roughness, ior=ior)
    black_emitter = PbrMaterial(base_color=(0, 0, 0), ior=1.0, emission=(1.0,) * 3)
    scene = PathScene(
        [make_box([2.0, 2.0, 0.02]), quad(40.0, z=-0.5)],
        np.stack([np.eye(4), np.eye(4)]),
        [1, 2],
        [[glass], [black_emitter]],
        (),
        BLACK,
    )
    view = camera((0, 0, 1.0), (0, 0, 0), 32, 10, up=(0, 1, 0))
    full = scene.render(view, PathTraceOptions(spp=64, max_bounces=40, rr_depth=100)).radiance
    assert full.mean() == pytest.approx((1 - R) / (1 + R), rel=2e-3)


def test_denoiser_albedo_and_normal_are_taken_through_smooth_glass():
    """The albedo and normal buffers (the denoiser's guides) show what is seen through a smooth
    glass pane, not the pane: a red Lambertian floor behind a clear pane gives a red albedo
    (weighted by the pane's transmittance, the reflected share shows the black dome) and the
    floor's normal; behind a frosted pane the pane itself is the guide."""
    red = PbrMaterial(base_color=(0.8, 0.1, 0.1), ior=1.0)
    X = np.eye(4)
    X[:3, 3] = (0, 0, 0.3)
    view = camera((0, 0, 1.0), (0, 0, 0), 16, 10, up=(0, 1, 0))
    for roughness, expect in ((0.0, (0.8, 0.1, 0.1)), (0.5, (0.9, 0.9, 0.9))):
        glass = PbrMaterial(base_color=(0.9, 0.9, 0.9), transmission=1.0, roughness=roughness)
        scene = PathScene(
            [quad(4.0), make_box([2.0, 2.0, 0.02])],
            np.stack([np.eye(4), X]),
            [1, 2],
            [[red], [glass]],
            (),
            BLACK,
        )
        out = scene.render(view, PathTraceOptions(spp=64, max_bounces=8))
        assert np.all(out.instance_ids == 2)
        albedo = out.albedo.reshape(-1, 3).mean(0)
        if roughness == 0.0:  # transmitted share (1 - R)^2 ~ 0.92 reaches the floor
            np.testing.assert_allclose(albedo / albedo[0], np.array(expect) / expect[0], atol=0.02)
            assert albedo[0] > 0.8 * 0.85
        else:
            np.testing.assert_allclose(albedo, expect, atol=1e-5)
        np.testing.assert_allclose(out.normal.reshape(-1, 3).mean(0), (0, 0, 1), atol=1e-3)


def test_denoiser_guides_behind_glass_are_weighted_by_fresnel_not_drawn_at_random():
    """At smooth glass both Fresnel branches give the guides, weighted by their shares, so one
    sample per pixel already gives every pixel the expected guide: a clear pane (ior 1.5) over a
    red floor under a black dome shows the floor's albedo times the transmitted share (the
    reflected share sees the black dome) in EVERY pixel, between (1 - R)^2 and (1 - R) of it
    (the second interface's choice still varies). Drawing one branch at random, as before, left
    ~4 % of the pixels black (the reflection) at 1 spp."""
    red = PbrMaterial(base_color=(0.8, 0.1, 0.1), ior=1.0)
    X = np.eye(4)
    X[:3, 3] = (0, 0, 0.3)
    view = camera((0, 0, 1.0), (0, 0, 0), 32, 10, up=(0, 1, 0))
    glass = PbrMaterial(base_color=(1, 1, 1), transmission=1.0, roughness=0.0, ior=1.5)
    scene = PathScene(
        [quad(4.0), make_box([2.0, 2.0, 0.02])],
        np.stack([np.eye(4), X]),
        [1, 2],
        [[red], [glass]],
        (),
        BLACK,
    )
    out = scene.render(view, PathTraceOptions(spp=1, max_bounces=8, seed=5))
    assert np.all(out.instance_ids == 2)
    R = ((1.5 - 1) / (1.5 + 1)) ** 2  # 0.04 at normal incidence (the view is within 5 degrees)
    a = out.albedo.reshape(-1, 3)[:, 0]
    assert a.min() >= 0.8 * (1 - R) ** 2 - 2e-3, a.min()
    assert a.max() <= 0.8 * (1 - R) + 2e-3, a.max()
    np.testing.assert_allclose(
        out.normal.reshape(-1, 3), np.tile((0, 0, 1), (a.size, 1)), atol=1e-3
    )


def test_roulette_does_not_count_the_vertices_at_smooth_glass():
    """Russian roulette starts at the rr_depth-th vertex that is not a smooth dielectric: a grey
    floor seen through a clear pane (two glass vertices before the floor, one after it on the
    way back up) with rr_depth = 2 and max_bounces = 4 has at most one counted vertex per
    path, so no path is rouletted and the image equals the one without roulette byte for byte;
    counting every vertex (roulette at the floor, behind the pane's two) would change it. The
    same floor without the pane is rouletted at rr_depth = 1 (fewer rays), and roulette from
    the first vertex on, glass included, keeps the mean (within Monte Carlo error)."""
    grey = PbrMaterial(base_color=(0.5, 0.5, 0.5), ior=1.0, roughness=1.0)
    glass = PbrMaterial(base_color=(1, 1, 1), transmission=1.0, roughness=0.0, ior=1.5)
    floor, pane = quad(6.0, z=-0.5), make_box([3.0, 3.0, 0.02])
    with_pane = PathScene(
        [pane, floor], np.stack([np.eye(4), np.eye(4)]), [1, 2], [[glass], [grey]], (), uniform(1.0)
    )
    bare = PathScene([floor], np.eye(4)[None], [2], [[grey]], (), uniform(1.0))
    view = camera((0, 0, 1.0), (0, 0, 0), 24, 20, up=(0, 1, 0))

    def render(scene, rr_depth, spp=4, max_bounces=4):
        opts = PathTraceOptions(spp=spp, max_bounces=max_bounces, rr_depth=rr_depth, seed=7)
        return scene.render(view, opts)

    pane2, pane_off = render(with_pane, 2), render(with_pane, 100)
    np.testing.assert_array_equal(pane2.radiance, pane_off.radiance)
    assert pane2.rays == pane_off.rays
    # Without the pane the floor is the first counted vertex: rouletted paths cast fewer rays.
    assert render(bare, 1).rays < 0.9 * render(bare, 100).rays
    spp = 64
    ref = render(with_pane, 100, spp, 8).radiance[..., 0]
    rr = render(with_pane, 0, spp, 8).radiance[..., 0]
    se = math.sqrt((rr.var() + ref.var()) / rr.size)  # pixel means scatter about their mean
    assert rr.mean() == pytest.approx(ref.mean(), abs=4 * se + 1e-4)


def test_glass_sphere_total_internal_reflection_keeps_energy():
    """A clear glass sphere in a uniform dome L reflects and refracts without absorption: every
    path eventually escapes (total internal reflection included), so the sphere shows L (the
    mean within 4 standard errors, every pixel within 10 %: with Fresnel splitting single samples
    differ from L)."""
    glass = PbrMaterial(base_color=(1, 1, 1), transmission=1.0, roughness=0.0, ior=1.5)
    scene = PathScene([make_sphere(0.5, 64, 32)], np.eye(4)[None], [1], [[glass]], (), uniform(0.7))
    out = scene.render(
        camera((0, -3, 0), (0, 0, 0), 24, 22), PathTraceOptions(spp=64, max_bounces=64, rr_depth=64)
    )
    px = out.radiance[interior(out.instance_ids == 1)]
    se = float(px.std()) / math.sqrt(px.size)
    assert float(px.mean()) == pytest.approx(0.7, abs=4 * se + 1e-4)
    np.testing.assert_allclose(px, 0.7, rtol=0.1)


# ---------------------------------------------------------------------------------------------
# Labels against the raster renderer, determinism.


def tote_scene_items(n_objects: int = 6):
    from mgn.objects import builtin_objects, tote_mesh

    items = []
    for k, spec in enumerate(builtin_objects()[:n_objects]):
        mesh = spec.to_mesh()
        lo = np.asarray(mesh.bounds)[0]
        X = np.eye(4)
        yaw = 0.7 * k
        X[:2, :2] = [[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]
        X[:3, 3] = (-0.12 + 0.09 * (k % 3), -0.07 + 0.12 * (k // 3), -lo[2])
        items.append((mesh, X, k + 1))
    items.append((tote_mesh(), np.eye(4), 0))
    return items


def path_scene(items, lights=(), env=None):
    meshes = [m for m, _, _ in items]
    mats = [
        [PbrMaterial.from_material(x) for x in (m.materials or [None])]
        if m.materials
        else [PbrMaterial()]
        for m in meshes
    ]
    return PathScene(
        meshes, np.stack([X for _, X, _ in items]), [i for _, _, i in items], mats, lights, env
    )


def test_primary_ids_and_depth_agree_with_raster_renderer():
    from mgn.render import Instance, Renderer
    from mgn.scene.cameras import mgn_rig

    items = tote_scene_items()
    K = Intrinsics.mgn_synthetic().scaled(0.12)
    poses, _ = mgn_rig(7, (0.0, 0.0, 0.0))
    r = Renderer(K.width, K.height)
    r.set_instances([Instance(r.add_mesh(m), X, i) for m, X, i in items])
    scene = path_scene(items)
    for v in (0, 17):
        view = CameraView(K, poses[v])
        ras = r.render(view, rgb=False)
        out = scene.render(view, PathTraceOptions(spp=1, max_bounces=0))
        agree = (ras.instance_ids == out.instance_ids).mean()
        assert agree >= 0.999, agree
        assert (out.instance_ids > 0).mean() > 0.05
        both = (ras.depth > 0) & (out.depth > 0) & (ras.instance_ids == out.instance_ids)
        assert ((ras.depth > 0) == (out.depth > 0)).mean() >= 0.999
        assert both.mean() > 0.3
        assert np.abs(ras.depth[both] - out.depth[both]).max() < 1e-3


def test_same_seed_same_bytes_for_one_and_two_threads():
    sphere = make_sphere(0.3, 32, 16)
    box = make_box([0.3, 0.3, 0.3])
    floor = quad(3.0, z=-0.3)
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
    scene = PathScene(
        [sphere, box, floor],
        np.stack([Xs, Xb, np.eye(4)]),
        [1, 2, 3],
        mats,
        [AreaLight(X_WL, "rect", (0.4, 0.4), intensity=15)],
        Environment(kind="sky", intensity=0.5),
    )
    view = camera((0, -2.0, 1.0), (0, 0, 0), 40, 50)
    outs = [
        scene.render(
            view,
            PathTraceOptions(spp=4, seed=9, view_index=2, num_threads=t, aperture_radius=0.01),
        )
        for t in (1, 2)
    ]
    for name in ("radiance", "albedo", "normal", "depth", "instance_ids"):
        assert getattr(outs[0], name).tobytes() == getattr(outs[1], name).tobytes(), name
    film = [FilmOptions(shot_noise=0.05, read_noise=0.01, seed=4, num_threads=t) for t in (1, 2)]
    assert (
        develop(outs[0].radiance, film[0]).tobytes() == develop(outs[1].radiance, film[1]).tobytes()
    )
    other = scene.render(view, PathTraceOptions(spp=4, seed=10, view_index=2))
    assert other.radiance.tobytes() != outs[0].radiance.tobytes()
    assert np.all(np.isfinite(outs[0].radiance))
    np.testing.assert_allclose(
        np.linalg.norm(outs[0].normal[outs[0].instance_ids > 0], axis=-1), 1, atol=1e-4
    )
    # The shadow-ray settings: the same bytes for any thread count too; the sky here has a
    # sun, so even without the dome's shadow rays the environment is sampled; the radiance
    # changes, the labels and the first hit's guides do not.
    fewer = [
        scene.render(
            view,
            PathTraceOptions(
                spp=4,
                seed=9,
                view_index=2,
                num_threads=t,
                aperture_radius=0.01,
                shadow_rays=1,
                sample_sky_dome=False,
                reduced_nee_depth=1,
            ),
        )
        for t in (1, 2)
    ]
    for name in ("radiance", "albedo", "normal", "depth", "instance_ids"):
        assert getattr(fewer[0], name).tobytes() == getattr(fewer[1], name).tobytes(), name
    assert fewer[0].rays < outs[0].rays
    assert fewer[0].radiance.tobytes() != outs[0].radiance.tobytes()
    for name in ("albedo", "normal", "depth", "instance_ids"):
        assert getattr(fewer[0], name).tobytes() == getattr(outs[0], name).tobytes(), name


def test_with_lighting_shares_geometry_and_changes_light():
    scene = PathScene(
        [make_sphere(0.5, 24, 12)], np.eye(4)[None], [1], [[LAMBERT_WHITE]], (), uniform(1.0)
    )
    brighter = scene.with_lighting([], uniform(2.0))
    view = camera((0, -3, 0), (0, 0, 0), 16, 25)
    a = scene.render(view, PathTraceOptions(spp=2)).radiance
    b = brighter.render(view, PathTraceOptions(spp=2)).radiance
    np.testing.assert_allclose(b, 2 * a, rtol=1e-5)
    assert brighter.num_triangles == scene.num_triangles


# ---------------------------------------------------------------------------------------------
# develop().


def srgb(x):
    x = np.asarray(x, float)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def test_develop_tone_curves_and_exposure():
    rad = np.array([[[0.0, 0.18, 1.0], [0.5, 4.0, np.nan]]], np.float32)
    lin = develop(rad, FilmOptions(tone="linear"))
    expected = np.round(srgb(np.clip(np.nan_to_num(rad), 0, 1)) * 255)
    np.testing.assert_array_equal(lin, expected)
    film = develop(rad, FilmOptions(tone="filmic", exposure=1.0))
    expected = np.round(srgb(1 - np.exp(-2 * np.nan_to_num(rad))) * 255)
    np.testing.assert_array_equal(film, expected)
    assert film.dtype == np.uint8
    assert film.shape == (1, 2, 3)


def test_develop_sensor_noise_statistics_and_seed():
    rad = np.full((64, 64, 3), 0.25, np.float32)
    clean = develop(rad, FilmOptions(tone="linear"))
    noisy = develop(rad, FilmOptions(tone="linear", read_noise=0.02, seed=1))
    again = develop(rad, FilmOptions(tone="linear", read_noise=0.02, seed=1))
    other = develop(rad, FilmOptions(tone="linear", read_noise=0.02, seed=2))
    assert noisy.tobytes() == again.tobytes()
    assert noisy.tobytes() != other.tobytes()
    assert np.all(clean == clean[0, 0, 0])
    # Read noise of std 0.02 around 0.25 in linear -> sRGB slope there * 0.02 * 255 counts.
    slope = (srgb(0.26) - srgb(0.24)) / 0.02
    std = noisy.astype(float).std()
    assert std == pytest.approx(slope * 0.02 * 255, rel=0.15)


# ---------------------------------------------------------------------------------------------
# Errors.


def test_bad_parameters_name_the_setting():
    with pytest.raises(InvalidArgumentError, match=r"PathTraceOptions.spp must be >= 1, got 0"):
        PathTraceOptions(spp=0)
    with pytest.raises(InvalidArgumentError, match=r"PathTraceOptions.max_bounces"):
        PathTraceOptions(max_bounces=-1)
    with pytest.raises(InvalidArgumentError, match=r"PathTraceOptions.shadow_rays must be 1 or 2"):
        PathTraceOptions(shadow_rays=3)
    with pytest.raises(InvalidArgumentError, match=r"PathTraceOptions.reduced_nee_depth must be"):
        PathTraceOptions(reduced_nee_depth=-1)
    with pytest.raises(
        InvalidArgumentError, match=r"PbrMaterial.roughness must be in \[0, 1\], got -0.1"
    ):
        PbrMaterial(roughness=-0.1)
    with pytest.raises(InvalidArgumentError, match=r"PbrMaterial.roughness"):
        PbrMaterial(roughness=1.5)
    with pytest.raises(InvalidArgumentError, match=r"PbrMaterial.metallic"):
        PbrMaterial(metallic=2.0)
    with pytest.raises(InvalidArgumentError, match=r"PbrMaterial.ior"):
        PbrMaterial(ior=0.5)
    X = np.eye(4)
    X[0, 3] = np.nan
    with pytest.raises(InvalidArgumentError, match=r"AreaLight.X_WL"):
        AreaLight(X)
    with pytest.raises(InvalidArgumentError, match=r"AreaLight.intensity must be finite and >= 0"):
        AreaLight(np.eye(4), intensity=-1.0)
    with pytest.raises(InvalidArgumentError, match=r"AreaLight.shape"):
        AreaLight(np.eye(4), shape="triangle")
    with pytest.raises(InvalidArgumentError, match=r"Environment.kind"):
        Environment(kind="hdri")
    with pytest.raises(InvalidArgumentError, match=r"Environment.intensity"):
        Environment(intensity=-2)
    with pytest.raises(InvalidArgumentError, match=r"FilmOptions.tone"):
        FilmOptions(tone="aces")
    with pytest.raises(InvalidArgumentError, match=r"FilmOptions.shot_noise"):
        FilmOptions(shot_noise=-1)
    sphere = make_sphere(0.5, 16, 8)
    with pytest.raises(InvalidArgumentError, match=r"geometry 0 .* has 2 materials; expected"):
        PathScene([sphere], np.eye(4)[None], [1], [[PbrMaterial(), PbrMaterial()]])
    with pytest.raises(InvalidArgumentError, match=r"instance id -3"):
        PathScene([sphere], np.eye(4)[None], [-3], [[PbrMaterial()]])
    with pytest.raises(InvalidArgumentError, match=r"develop: radiance"):
        develop(np.zeros((4, 4)))


# ---------------------------------------------------------------------------------------------
# Thin lens.


def test_thin_lens_blur_circle_and_autofocus():
    """A tiny emitter at distance d seen through a thin lens of aperture radius A focused at s
    spreads over a disc of radius f * A * |1/s - 1/d| px (f in px) and keeps its total radiance
    sum (each lens point sees the same emitter, shifted); focused on it (also by the automatic
    focus on the image centre) it stays as sharp as with a pinhole."""
    f, d, A = 100.0, 1.0, 0.05
    emitter = quad(0.01, z=0.0)
    mat = PbrMaterial(base_color=(0, 0, 0), ior=1.0, emission=(1.0, 1.0, 1.0))
    scene = PathScene([emitter], np.eye(4)[None], [1], [[mat]], (), BLACK)
    K = Intrinsics(33, 33, f, f, 16.5, 16.5)
    view = CameraView(K, look_at(np.array([0, 0, d]), np.zeros(3), np.array([0, 1.0, 0])))
    pin = scene.render(view, PathTraceOptions(spp=64, max_bounces=0)).radiance[..., 0]
    s = 0.5
    # 4096 spp: the blurred total is a Monte Carlo sum of ~1 % relative std (3.8 % at 256 spp
    # over seeds, too close to the 5 % tolerance).
    blur = scene.render(
        view, PathTraceOptions(spp=4096, max_bounces=0, aperture_radius=A, focus_distance=s)
    ).radiance[..., 0]
    auto = scene.render(view, PathTraceOptions(spp=64, max_bounces=0, aperture_radius=A)).radiance[
        ..., 0
    ]
    radius = f * A * abs(1 / s - 1 / d)  # 5 px
    v, u = np.nonzero(blur > 0)
    r = np.hypot(u + 0.5 - 16.5, v + 0.5 - 16.5)
    assert r.max() <= radius + 1.5
    assert r.max() >= radius - 1.0
    assert blur.sum() == pytest.approx(pin.sum(), rel=0.05)
    assert (pin > 0).sum() <= 4
    v, u = np.nonzero(auto > 0)
    assert np.hypot(u + 0.5 - 16.5, v + 0.5 - 16.5).max() <= 1.5
    assert auto.sum() == pytest.approx(pin.sum(), rel=0.05)


def test_base_color_texture_is_looked_up_at_the_mesh_uvs():
    """A quad textured with 2x2 texels (sRGB) under a uniform dome L = 1 (one bounce: the open
    plane sees the whole upper dome) shows each texel's linear colour in its quadrant, with
    texel row 0 (the image top) at v = 1."""
    h = 0.5
    v = [[-h, -h, 0], [h, -h, 0], [h, h, 0], [-h, h, 0]]
    uv = [[0, 0], [1, 0], [1, 1], [0, 1]]
    plane = mesh_from_arrays(v, [[0, 1, 2], [0, 2, 3]], uvs=uv)
    tex = np.array([[[255, 0, 0], [0, 255, 0]], [[0, 0, 255], [128, 128, 128]]], np.uint8)
    mat = PbrMaterial(base_color=(1, 1, 1), ior=1.0, base_color_texture=tex)
    scene = PathScene([plane], np.eye(4)[None], [1], [[mat]], (), uniform(1.0))
    view = camera((0, 0, 2.0), (0, 0, 0), 40, 20, up=(0, 1, 0))  # image up = world +y
    out = scene.render(view, PathTraceOptions(spp=4, max_bounces=1))
    # Texel centres are at uv 0.25 / 0.75, i.e. world +-0.25: find their pixels.
    K = view.K
    lin = srgb_to_linear(tex.astype(float) / 255)
    for (x, y), texel in [
        ((-0.25, 0.25), lin[0, 0]),
        ((0.25, 0.25), lin[0, 1]),
        ((-0.25, -0.25), lin[1, 0]),
        ((0.25, -0.25), lin[1, 1]),
    ]:
        p_C = np.linalg.inv(view.X_WC) @ np.array([x, y, 0.0, 1.0])
        u = int(K.fx * p_C[0] / p_C[2] + K.cx)
        w = int(K.fy * p_C[1] / p_C[2] + K.cy)
        # (the pixel footprint blends ~2 % of the neighbour texel through bilinear filtering)
        np.testing.assert_allclose(out.radiance[w, u], texel, atol=0.03)


def srgb_to_linear(c):
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


@pytest.mark.parametrize("sample_sky_dome", [True, False])
def test_sky_dome_colours_and_sun_irradiance(sample_sky_dome):
    """Directly seen, the gradient dome shows the zenith colour straight up and the ground colour
    below the horizon; the sky's sun disc adds an irradiance of sun_strength * pi * lum(zenith)
    at normal incidence, i.e. a * sun_strength * lum(zenith) in the radiance of a Lambertian
    plane of albedo a facing the sun (sky minus gradient with the same colours)."""
    kw = {
        "zenith": (0.2, 0.3, 0.6),
        "horizon": (0.7, 0.7, 0.7),
        "ground": (0.1, 0.2, 0.1),
        "intensity": 2.0,
    }
    grad = Environment(kind="gradient", **kw)
    sky = Environment(kind="sky", sun_direction=(0, 0, 1), sun_strength=4.0, **kw)
    dummy = quad(0.01, z=-50.0)
    scene = PathScene([dummy], np.eye(4)[None], [1], [[PbrMaterial()]], (), grad)
    up = scene.render(camera((0, 0, 0), (0, 0, 1), 8, 5, up=(0, 1, 0)), PathTraceOptions(spp=1))
    zenith = np.multiply(kw["zenith"], 2.0)
    np.testing.assert_allclose(up.radiance, np.broadcast_to(zenith, (8, 8, 3)), rtol=5e-3)
    down = scene.render(camera((0, 0, 0), (1, 0, -1), 8, 5), PathTraceOptions(spp=1))
    ground = np.multiply(kw["ground"], 2.0)
    np.testing.assert_allclose(down.radiance, np.broadcast_to(ground, (8, 8, 3)), rtol=1e-6)
    a = 0.5
    plane = quad(40.0)
    mat = PbrMaterial(base_color=(a,) * 3, ior=1.0)
    view = camera((0.3, 0.2, 1.0), (0.3, 0.2, 0.0), 16, 30, up=(0, 1, 0))
    opts = PathTraceOptions(spp=64, max_bounces=1, sample_sky_dome=sample_sky_dome)
    s_grad = PathScene([plane], np.eye(4)[None], [1], [[mat]], (), grad).render(view, opts)
    s_sky = PathScene([plane], np.eye(4)[None], [1], [[mat]], (), sky).render(view, opts)
    lum_zenith = 2.0 * (0.2126 * 0.2 + 0.7152 * 0.3 + 0.0722 * 0.6)
    diff = (s_sky.radiance - s_grad.radiance).mean()
    assert diff == pytest.approx(a * 4.0 * lum_zenith, rel=0.02)
    if not sample_sky_dome:
        # The dome found by the BSDF-sampled rays alone: the same mean as with its shadow rays
        # (the plane sees the whole upper dome: one ray per sample after the camera ray).
        with_dome = PathScene([plane], np.eye(4)[None], [1], [[mat]], (), grad).render(
            view, PathTraceOptions(spp=64, max_bounces=1)
        )
        assert s_grad.radiance.mean() == pytest.approx(with_dome.radiance.mean(), rel=0.01)
        n = view.K.width * view.K.height
        assert s_grad.rays == n * (64 * 2 + 1)  # label, camera and bounce rays


def ggx_lambda(c, alpha):
    return 0.5 * (-1 + np.sqrt(1 + alpha**2 * (1 - c**2) / c**2))


def ggx_single_albedo(mu, alpha, n=400):
    """Directional albedo of white single-scattering GGX (F = 1) for cos theta_o = mu, by
    quadrature over the hemisphere of D G2 / (4 cos_o cos_i) cos_i, in (theta, phi) with
    theta = pi/2 s^2 (cells shrink towards the normal)."""
    s = (np.arange(n) + 0.5) / n
    th = 0.5 * np.pi * s**2
    ph = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * np.pi
    T, P = np.meshgrid(th, ph, indexing="ij")
    wi = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    dw = (np.sin(T) * np.pi * s[:, None] / n) * (2 * np.pi / (2 * n))
    wo = np.array([np.sqrt(1 - mu**2), 0.0, mu])
    hv = wi + wo
    hv /= np.linalg.norm(hv, axis=-1, keepdims=True)
    D = alpha**2 / (np.pi * (hv[..., 2] ** 2 * (alpha**2 - 1) + 1) ** 2)
    G2 = 1 / (1 + ggx_lambda(mu, alpha) + ggx_lambda(wi[..., 2], alpha))
    return float((D * G2 / (4 * mu) * dw).sum())


@functools.cache
def ggx_albedo_table(alpha):
    """E(mu) of ggx_single_albedo at 48 values of mu, and E_avg = 2 int E mu dmu."""
    mus = (np.arange(48) + 0.5) / 48
    E = np.array([ggx_single_albedo(m, alpha) for m in mus])
    return mus, E, float(2 * (E * mus).sum() / len(mus))


def ggx_metal_radiance(p, cam, centre, size, Le, f0, alpha, n=240):
    """Radiance towards `cam` from point p (normal +z) of a GGX metal (Schlick F, height-
    correlated Smith G2) lit by a horizontal rect light facing down, by quadrature over the
    light of f(wo, wi) Le cos_i cos_l / r^2. f has the multiple-scattering lobe of Kulla and
    Conty 2017 (docs/rendering.md): F_ms (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)),
    F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg)), F_avg = (20 f0 + 1) / 21, with E by the
    quadrature above (interpolated from 48 values of mu)."""
    mus, E, E_avg = ggx_albedo_table(alpha)
    F_avg = (20 * f0 + 1) / 21
    F_ms = F_avg**2 * E_avg / (1 - F_avg * (1 - E_avg))
    h = size / 2
    g = (np.arange(n) + 0.5) / n * size - h
    X, Y = np.meshgrid(g + centre[0], g + centre[1])
    d = np.stack([X - p[0], Y - p[1], np.full_like(X, centre[2] - p[2])], -1)
    r2 = (d**2).sum(-1)
    wi = d / np.sqrt(r2)[..., None]
    wo = np.asarray(cam, float) - p
    wo = wo / np.linalg.norm(wo)
    hv = wi + wo
    hv /= np.linalg.norm(hv, axis=-1, keepdims=True)
    a2 = alpha**2
    D = a2 / (np.pi * (hv[..., 2] ** 2 * (a2 - 1) + 1) ** 2)
    G2 = 1 / (1 + ggx_lambda(wo[2], alpha) + ggx_lambda(wi[..., 2], alpha))
    F = f0 + (1 - f0) * (1 - (wo * hv).sum(-1)) ** 5
    f = F * D * G2 / (4 * wo[2] * wi[..., 2])
    e_o = np.interp(wo[2], mus, E)
    e_i = np.interp(wi[..., 2], mus, E)
    f = f + F_ms * (1 - e_o) * (1 - e_i) / (np.pi * (1 - E_avg))
    cos_i = wi[..., 2]
    cos_l = wi[..., 2]
    return Le * (f * cos_i * cos_l / r2).sum() * (size / n) ** 2


def test_glossy_metal_plane_under_rect_light_matches_quadrature():
    """Light sampling and BSDF sampling combined by MIS give the reflected radiance of a rough
    GGX metal plane under a rect light (direct lighting only), pixel by pixel within 3 %."""
    f0, roughness, Le, size, height = 0.9, 0.4, 5.0, 0.2, 0.5
    mat = PbrMaterial(base_color=(f0,) * 3, metallic=1.0, roughness=roughness)
    X_WL = np.diag([1.0, -1.0, -1.0, 1.0])
    X_WL[:3, 3] = (0.0, 0.0, height)
    light = AreaLight(X_WL, "rect", (size, size), (1.0, 1.0, 1.0), Le)
    scene = PathScene([quad(4.0)], np.eye(4)[None], [1], [[mat]], [light], BLACK)
    eye = np.array([0.6, 0.0, 0.6])
    view = camera(eye, (-0.1, 0.0, 0.0), 24, 40)
    out = scene.render(view, PathTraceOptions(spp=256, max_bounces=1, seed=2))
    K = view.K
    expected = np.zeros((K.height, K.width))
    for i in range(K.height):
        for j in range(K.width):
            d_C = np.array([(j + 0.5 - K.cx) / K.fx, (i + 0.5 - K.cy) / K.fy, 1.0])
            d_W = view.X_WC[:3, :3] @ d_C
            p = eye + (-eye[2] / d_W[2]) * d_W
            expected[i, j] = ggx_metal_radiance(
                p, eye, (0.0, 0.0, height), size, Le, f0, roughness**2, n=100
            )
    got = out.radiance[..., 1]
    bright = expected > 0.2 * expected.max()
    assert 20 <= bright.sum() <= 400
    np.testing.assert_allclose(got[bright], expected[bright], rtol=0.03)
    # The highlight sum (all pixels) agrees too.
    assert got.sum() == pytest.approx(expected.sum(), rel=0.01)


def test_bad_shapes_and_types_are_invalid_argument_errors():
    with pytest.raises(InvalidArgumentError, match=r"PbrMaterial.base_color must be 3 numbers"):
        PbrMaterial(base_color=(1, 1))
    with pytest.raises(InvalidArgumentError, match=r"AreaLight.X_WL must be a \(4, 4\) pose"):
        AreaLight(np.eye(3))
    with pytest.raises(InvalidArgumentError, match=r"PathTraceOptions.seed must be >= 0"):
        PathTraceOptions(seed=-1)
    with pytest.raises(InvalidArgumentError, match=r"PathTraceOptions.spp must be an integer"):
        PathTraceOptions(spp=2.5)
    with pytest.raises(InvalidArgumentError, match=r"base_color_texture must be an \(H, W, 3\)"):
        PbrMaterial(base_color_texture=np.zeros((4, 4), np.uint8))


def test_clamp_indirect_clamps_only_light_found_after_the_first_bounce():
    """Interior furnace (E = 0.6, a = 0.5, two bounces): the camera ray's hit emits E, the first
    bounce brings a E (direct light), the second a^2 E = 0.15 (indirect). The emitting walls are
    sampled by next-event estimation as well as hit, so the indirect light comes in two MIS
    weighted parts, each clamped on its own: clamp_indirect = 1e-6 removes the indirect light and
    nothing else (E + a E); the default (10) changes nothing."""
    E, a = 0.6, 0.5
    mat = PbrMaterial(base_color=(a,) * 3, ior=1.0, emission=(E,) * 3)
    scene = PathScene(
        [make_sphere(1.0, 256, 128).flipped()], np.eye(4)[None], [1], [[mat]], (), BLACK
    )
    view = camera((0, 0, 0), (1, 0.2, 0.1), 8, 90)
    base = {"spp": 16, "max_bounces": 2, "rr_depth": 100}
    clamped = scene.render(view, PathTraceOptions(**base, clamp_indirect=1e-6)).radiance
    default = scene.render(view, PathTraceOptions(**base)).radiance
    off = scene.render(view, PathTraceOptions(**base, clamp_indirect=0.0)).radiance
    assert clamped.mean() == pytest.approx(E + a * E, rel=2e-3)
    assert default.tobytes() == off.tobytes()
    assert default.mean() == pytest.approx(E * (1 + a + a * a), rel=2e-3)
    with pytest.raises(InvalidArgumentError, match=r"PathTraceOptions.clamp_indirect"):
        PathTraceOptions(clamp_indirect=-1.0)


def _pane_stack_under_lamp(ior: float, Le: float, n: int) -> PathScene:
    """``n`` clear 2 m x 2 m x 2 cm panes at z = 0, 0.1, ... under the rect lamp of
    `_pane_under_lamp` (radiance ``Le``, facing down at z = 1.5 m), black environment."""
    X_WL = np.diag([1.0, -1.0, -1.0, 1.0])
    X_WL[:3, 3] = (0.0, 0.0, 1.5)
    light = AreaLight(X_WL, "rect", (3.0, 3.0), (1.0, 1.0, 1.0), Le)
    glass = PbrMaterial(base_color=(1, 1, 1), transmission=1.0, roughness=0.0, ior=ior)
    poses = np.stack([np.eye(4)] * n)
    poses[:, 2, 3] = 0.1 * np.arange(n)
    return PathScene(
        [make_box([2.0, 2.0, 0.02])] * n,
        poses,
        list(range(1, n + 1)),
        [[glass]] * n,
        [light],
        BLACK,
    )


def test_fresnel_split_min_keeps_the_mean_of_a_pane_stack():
    """Past the first three glass walls (traced on both branches) Fresnel splitting runs only
    while the path's throughput is at least `fresnel_split_min`; dimmer paths follow their random
    direction alone. Both are unbiased: three clear panes under a lamp, seen near normal
    incidence, reflect R3 Le, R3 from the slab formulas (each slab R1 = 2R / (1 + R),
    T1 = (1 - R) / (1 + R), stacks combined with their internal reflections), with splitting
    always (0), by default (0.1) and never (1e9) past the branched walls, each within 4 standard
    errors; never splitting casts fewer rays than always splitting."""
    ior, Le = 1.5, 2.0
    scene = _pane_stack_under_lamp(ior, Le, 3)
    view = camera((0, 0, 1.0), (0, 0, 0.1), 16, 4, up=(0, 1, 0))
    R = ((ior - 1) / (ior + 1)) ** 2
    R1, T1 = 2 * R / (1 + R), (1 - R) / (1 + R)
    Ra, Ta = R1, T1
    for _ in range(2):  # add one slab below the stack
        Ra, Ta = Ra + Ta**2 * R1 / (1 - Ra * R1), Ta * T1 / (1 - Ra * R1)
    truth = Le * Ra
    rays = {}
    for split_min in (0.0, 0.1, 1e9):
        opts = PathTraceOptions(
            spp=64, max_bounces=40, rr_depth=100, seed=3, fresnel_split_min=split_min
        )
        out = scene.render(view, opts)
        px = out.radiance[..., 1].ravel()  # per-pixel means of 64 samples
        se = px.std(ddof=1) / math.sqrt(px.size)
        assert abs(px.mean() - truth) < 4 * se + 1e-4, (split_min, px.mean(), truth, se)
        rays[split_min] = out.rays
    assert rays[1e9] < rays[0.0], rays


def test_guide_split_min_changes_guides_not_radiance():
    """`guide_split_min` only decides whether the denoiser guides of the other Fresnel direction
    are followed behind further glass: through a stack of panes the radiance is the same bytes
    for 0 and 1, and 1 casts fewer rays (no guide rays)."""
    scene = _pane_stack_under_lamp(1.5, 2.0, 3)
    view = camera((0, 0, 1.0), (0, 0, 0.1), 16, 4, up=(0, 1, 0))
    outs = [
        scene.render(view, PathTraceOptions(spp=4, max_bounces=40, seed=1, guide_split_min=g))
        for g in (0.0, 1.0)
    ]
    np.testing.assert_array_equal(outs[0].radiance, outs[1].radiance)
    assert outs[1].rays < outs[0].rays, (outs[0].rays, outs[1].rays)


@pytest.mark.parametrize("name", ["fresnel_split_min", "guide_split_min"])
def test_split_thresholds_must_be_finite_and_not_negative(name):
    for bad in (-0.1, math.inf, math.nan):
        with pytest.raises(InvalidArgumentError, match=name):
            PathTraceOptions(**{name: bad})
