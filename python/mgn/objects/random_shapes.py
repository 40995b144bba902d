"""Seeded random procedural objects: closed meshes of random shape, size, material and density,
built from the mesh builders of :mod:`mgn.objects.shapes`, for piles of many different shapes
(``objects.random_shapes`` of the dataset config, docs/models.md §6).

Every shape is one of these kinds, each with random proportions:

- ``revolved``: a body of revolution of a random profile (bottle, cone, spool, knob);
- ``ring``: a flat ring (tape roll, washer) or a torus (rubber ring, seal);
- ``tube``: a solid tube bent along a smooth random curve (cable piece, hose, rod);
- ``hook``: a C or U shape of a round or flat bar (clamp jaw, shackle, handle);
- ``coil``: a helix of a round wire (spring, coiled cable);
- ``prism``: a random polygon extruded, with a hole or two in half of them;
- ``plate``: a thin random polygon 2-8 mm thick (flat metal or plastic part);
- ``block``: a box with rounded edges, or a superellipsoid with smooth bumps.

The size of a shape is its largest bounding-box extent, drawn uniformly within the asked
range (metres). The material is a plain colour (black or dark grey, a reflectance below 5 %,
with probability ``dark``, default one in four), matte to glossy, plastic, rubber or metal; the
density is that of the material for a solid part (500-1500 kg/m^3 for plastics and rubber,
2700-7800 kg/m^3 for metal) and is lowered where the part would weigh more than
:data:`MAX_MASS_KG`. Everything is a function of the seed, the shape's index, the size range and
``dark``: the same arguments give the same bytes, and ``dark`` changes colours only.

Random shapes carry the ``random`` tag; their parallel-jaw grasp labels are not computed (the
dataset says so, ``pj_skipped``); every other label is.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import numpy as np

from mgn.errors import InvalidArgumentError

from .materials import make_material
from .shapes import (
    Mesh,
    extrude,
    revolve,
    rounded_box,
    superellipsoid,
    sweep_circle,
)
from .spec import Keypoint, MaterialSpec, ObjectSpec, size_tags

__all__ = [
    "DEFAULT_DARK",
    "KINDS",
    "MAX_MASS_KG",
    "RANDOM_SOURCE_PREFIX",
    "random_shape",
    "random_shape_source",
    "random_shapes",
    "random_shapes_from_source",
]

#: The kinds of random shape, drawn with equal probability.
KINDS: tuple[str, ...] = ("revolved", "ring", "tube", "hook", "coil", "prism", "plate", "block")

#: Heaviest random shape, kg: a denser draw is lowered to this mass.
MAX_MASS_KG = 3.0

#: ``source`` of random shapes in a scene file: this prefix, then the pool's parameters
#: (:func:`random_shape_source`).
RANDOM_SOURCE_PREFIX = "random-shapes:"

#: Default probability that a random shape is black or dark grey.
DEFAULT_DARK = 0.25

#: Thinnest wall, bar or plate of a random shape, metres.
MIN_THICKNESS = 0.002

_STREAM = 0x52534850  # separates the shapes' random stream from the scene seeds


def _check_size(size: Sequence[float]) -> tuple[float, float]:
    lo, hi = (float(x) for x in size)
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.01 <= lo <= hi <= 1.0):
        raise InvalidArgumentError(
            f"objects.random_shape_size: expected [min, max] in metres with 0.01 <= min <= max "
            f"<= 1.0, got {list(size)}"
        )
    return lo, hi


# ------------------------------------------------------------------------------------------------
# Geometry of each kind: a closed mesh of roughly unit size; scaled afterwards.
# ------------------------------------------------------------------------------------------------


def _smooth_curve(rng: np.random.Generator, n_ctrl: int, steps: int, bend: float) -> np.ndarray:
    """A smooth planar-ish curve of length about 1 through random turning angles."""
    turns = rng.uniform(-bend, bend, n_ctrl)
    climb = rng.uniform(-0.3, 0.3, n_ctrl)
    t = np.linspace(0.0, n_ctrl - 1, steps)
    heading = np.cumsum(np.interp(t, np.arange(n_ctrl), turns)) / steps * n_ctrl
    pitch = np.interp(t, np.arange(n_ctrl), climb)
    d = np.stack(
        [np.cos(heading) * np.cos(pitch), np.sin(heading) * np.cos(pitch), np.sin(pitch)], axis=1
    )
    pts = np.concatenate([[np.zeros(3)], np.cumsum(d, axis=0)]) / steps
    return pts


def _revolved(rng: np.random.Generator, size: float) -> Mesh:
    k = int(rng.integers(3, 7))
    height = 1.0
    z = np.linspace(0.0, height, k)
    r = rng.uniform(0.08, 0.45, k) * rng.choice([1.0, 0.6])
    r = np.maximum(r, MIN_THICKNESS / size)
    prof = np.concatenate([[[0.0, 0.0]], np.stack([r, z], 1), [[0.0, height]]])
    return revolve(prof, 32)


def _ring(rng: np.random.Generator, size: float) -> Mesh:
    outer = 0.5
    if rng.random() < 0.5:  # flat ring: a rectangle revolved
        wall = max(rng.uniform(0.06, 0.3) * outer, MIN_THICKNESS / size)
        h = max(rng.uniform(0.1, 0.6) * outer, MIN_THICKNESS / size)
        inner = outer - wall
        prof = np.array([[inner, 0.0], [outer, 0.0], [outer, h], [inner, h]])
        return revolve(prof, 48, closed=True)
    tube = max(rng.uniform(0.05, 0.18), MIN_THICKNESS / size)  # torus
    centre = outer - tube
    phi = np.arange(16) * (2 * np.pi / 16)
    prof = np.stack([centre + tube * np.cos(phi), tube * np.sin(phi)], 1)
    return revolve(prof, 48, closed=True)


def _tube(rng: np.random.Generator, size: float) -> Mesh:
    radius = max(rng.uniform(0.02, 0.08), MIN_THICKNESS / size)
    path = _smooth_curve(rng, int(rng.integers(2, 5)), 24, bend=1.5)
    for _ in range(20):  # a path that comes back near itself would make the tube cross itself
        gaps = np.linalg.norm(path[:, None] - path[None, :], axis=2)
        far = np.abs(np.arange(len(path))[:, None] - np.arange(len(path))[None, :]) > 4
        if gaps[far].min() > 2.5 * radius:
            break
        path = _smooth_curve(rng, int(rng.integers(2, 5)), 24, bend=1.5)
    else:
        path = np.stack([np.linspace(0.0, 1.0, 8), np.zeros(8), np.zeros(8)], 1)
    return sweep_circle(path, radius, 12)


def _hook(rng: np.random.Generator, size: float) -> Mesh:
    if rng.random() < 0.5:  # round bar along a C (arc of a circle) or a U
        radius = max(rng.uniform(0.03, 0.09), MIN_THICKNESS / size)
        if rng.random() < 0.5:
            span = rng.uniform(1.2, 1.8) * np.pi
            a = np.linspace(0.0, span, 28)
            path = np.stack([0.5 * np.cos(a), 0.5 * np.sin(a), np.zeros_like(a)], 1)
        else:
            w, leg = 0.35, rng.uniform(0.4, 1.0)
            a = np.linspace(np.pi, 2 * np.pi, 14)
            bottom = np.stack([w * np.cos(a), w * np.sin(a), np.zeros_like(a)], 1)
            up = np.linspace(0.0, leg, 6)[1:]
            left = np.stack([np.full(5, -w), up, np.zeros(5)], 1)[::-1]
            right = np.stack([np.full(5, w), up, np.zeros(5)], 1)
            path = np.concatenate([left, bottom, right])
        return sweep_circle(path, radius, 12)
    # flat C: a thick arc band extruded (a clamp's jaw, an open ring)
    outer = 0.5
    width = rng.uniform(0.12, 0.3)
    span = rng.uniform(1.1, 1.7) * np.pi
    a = np.linspace(0.0, span, 24)
    ro = np.stack([outer * np.cos(a), outer * np.sin(a)], 1)
    ri = np.stack([(outer - width) * np.cos(a), (outer - width) * np.sin(a)], 1)[::-1]
    thick = max(rng.uniform(0.05, 0.25), MIN_THICKNESS / size)
    return extrude(np.concatenate([ro, ri]), height=thick)


def _coil(rng: np.random.Generator, size: float) -> Mesh:
    turns = rng.uniform(1.5, 5.0)
    wire = max(rng.uniform(0.02, 0.06), MIN_THICKNESS / size)
    coil_r = rng.uniform(0.15, 0.4)
    pitch = max(rng.uniform(2.3, 5.0) * wire, 2.3 * wire)
    a = np.linspace(0.0, turns * 2 * np.pi, int(turns * 24) + 2)
    path = np.stack([coil_r * np.cos(a), coil_r * np.sin(a), pitch * a / (2 * np.pi)], 1)
    return sweep_circle(path, wire, 10)


def _polygon(rng: np.random.Generator, n: int, lo: float) -> np.ndarray:
    """A star-shaped random polygon about the origin (radii lo..1 x 0.5)."""
    step = 2 * np.pi / n
    ang = np.arange(n) * step + rng.uniform(-0.35, 0.35, n) * step
    r = 0.5 * rng.uniform(lo, 1.0, n)
    if rng.random() < 0.5:  # elongated
        stretch = rng.uniform(1.0, 3.0)
        pts = np.stack([r * np.cos(ang) * stretch, r * np.sin(ang)], 1)
    else:
        pts = np.stack([r * np.cos(ang), r * np.sin(ang)], 1)
    return pts


def _inside(poly: np.ndarray, p: np.ndarray) -> bool:
    """Whether point ``p`` lies inside the simple polygon ``poly`` (even-odd rule)."""
    x, y = poly[:, 0], poly[:, 1]
    x2, y2 = np.roll(x, -1), np.roll(y, -1)
    crosses = (y > p[1]) != (y2 > p[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        xs = x + (p[1] - y) * (x2 - x) / (y2 - y)
    return bool(np.count_nonzero(crosses & (xs > p[0])) % 2 == 1)


def _holes(rng: np.random.Generator, outer: np.ndarray, size: float) -> list[np.ndarray]:
    """Zero to two round holes well inside the polygon ``outer``."""
    if rng.random() < 0.5:
        return []
    edges = np.diff(np.concatenate([outer, outer[:1]]), axis=0)
    holes: list[np.ndarray] = []
    for _ in range(int(rng.integers(1, 3))):
        for _try in range(8):
            centre = outer.mean(axis=0) + rng.uniform(-0.3, 0.3, 2) * np.ptp(outer, axis=0)
            radius = rng.uniform(0.04, 0.15)
            if radius * size < 0.002 or not _inside(outer, centre):
                continue
            # distance of the centre to every edge of the polygon
            rel = centre - outer
            t = np.clip(np.sum(rel * edges, 1) / np.sum(edges * edges, 1), 0.0, 1.0)
            gap = np.linalg.norm(rel - t[:, None] * edges, axis=1).min()
            if gap < radius + 0.05 + 2 * MIN_THICKNESS / size:
                continue
            if any(
                np.linalg.norm(centre - h.mean(axis=0)) < radius + _hr + 0.05
                for h, _hr in ((h, np.linalg.norm(h[0] - h.mean(axis=0))) for h in holes)
            ):
                continue
            a = np.arange(16) * (2 * np.pi / 16)
            holes.append(centre + radius * np.stack([np.cos(a), np.sin(a)], 1))
            break
    return holes


def _prism(rng: np.random.Generator, size: float) -> Mesh:
    outer = _polygon(rng, int(rng.integers(3, 10)), 0.5)
    height = max(rng.uniform(0.08, 0.4), MIN_THICKNESS / size)
    return extrude(outer, _holes(rng, outer, size), height)


def _plate(rng: np.random.Generator, size: float) -> Mesh:
    outer = _polygon(rng, int(rng.integers(3, 9)), 0.6)
    ext = float(np.ptp(outer, axis=0).max())
    thick = rng.uniform(0.002, 0.008) / size * ext  # 2-8 mm after scaling
    return extrude(outer, _holes(rng, outer, size), thick)


def _block(rng: np.random.Generator, size: float) -> Mesh:
    mid = rng.uniform(0.25, 0.75)
    dims = np.array([1.0, mid, mid * rng.uniform(0.3, 1.0)])  # no bulky cubes of the largest size
    dims = np.maximum(dims, 2 * MIN_THICKNESS / size)
    if rng.random() < 0.5:
        radius = rng.uniform(0.05, 0.45) * dims.min()
        return rounded_box(dims, radius, max_edge=0.08, round_steps=3)
    e1, e2 = rng.uniform(0.3, 1.2, 2)
    amp = rng.uniform(0.0, 0.12)
    freq = rng.integers(1, 4, 3)
    phase = rng.uniform(0, 2 * np.pi, 3)

    def bumps(d: np.ndarray) -> np.ndarray:
        out: np.ndarray = 1.0 + amp * np.prod(np.sin(freq * d * np.pi + phase), axis=1)
        return out

    return superellipsoid(0.5 * dims, float(e1), float(e2), steps=12, noise=bumps)


_BUILDERS = {
    "revolved": _revolved,
    "ring": _ring,
    "tube": _tube,
    "hook": _hook,
    "coil": _coil,
    "prism": _prism,
    "plate": _plate,
    "block": _block,
}


# ------------------------------------------------------------------------------------------------
# Material and density
# ------------------------------------------------------------------------------------------------


def _material(
    rng: np.random.Generator, index: int, dark: float
) -> tuple[MaterialSpec, float, float]:
    """(material, density kg/m^3, friction) of one random shape; black or dark grey with
    probability ``dark`` (the same draws either way, so ``dark`` changes colours only)."""
    kind = str(rng.choice(["plastic", "plastic", "rubber", "metal"]))
    if rng.random() < dark:  # black or dark grey
        hsv = (rng.uniform(0, 1), rng.uniform(0.0, 0.2), rng.uniform(0.03, 0.2))
    else:
        hsv = (rng.uniform(0, 1), rng.uniform(0.0, 0.9), rng.uniform(0.25, 0.95))
    h, s, v = hsv
    i = int(h * 6) % 6
    f = h * 6 - int(h * 6)
    p, q, t = v * (1 - s), v * (1 - f * s), v * (1 - (1 - f) * s)
    srgb = [(v, t, p), (q, v, p), (p, v, t), (p, q, v), (t, p, v), (v, p, q)][i]
    c = np.asarray(srgb, dtype=np.float64)
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    color = (round(float(lin[0]), 4), round(float(lin[1]), 4), round(float(lin[2]), 4), 1.0)
    name = f"random_{kind}_{index:04d}"
    if kind == "metal":
        rough = float(rng.uniform(0.15, 0.6))
        mat = make_material(name, color, 0.7, 80.0, roughness=rough, metallic=1.0)
        return mat, float(rng.uniform(2700.0, 7800.0)), float(rng.uniform(0.3, 0.6))
    if kind == "rubber":
        rough = float(rng.uniform(0.6, 0.95))
        mat = make_material(name, color, 0.05, 5.0, roughness=rough)
        return mat, float(rng.uniform(1000.0, 1500.0)), float(rng.uniform(0.8, 1.2))
    rough = float(rng.uniform(0.2, 0.8))
    mat = make_material(name, color, 0.3, 40.0, roughness=rough)
    return mat, float(rng.uniform(500.0, 1400.0)), float(rng.uniform(0.4, 0.8))


# ------------------------------------------------------------------------------------------------
# Public API
# ------------------------------------------------------------------------------------------------


def _check_dark(dark: float) -> float:
    if isinstance(dark, bool) or not (0.0 <= float(dark) <= 1.0):
        raise InvalidArgumentError(
            f"objects.random_shape_dark: expected a probability in [0, 1], got {dark!r}"
        )
    return float(dark)


def random_shape(
    seed: int,
    index: int,
    size: Sequence[float] = (0.02, 0.25),
    category_id: int = 1,
    dark: float = DEFAULT_DARK,
) -> ObjectSpec:
    """Random shape number ``index`` of the pool of ``seed`` (module doc): a closed,
    outward-wound mesh in its object frame (bounding-box centre at the origin), largest extent
    within ``size`` = (min, max) metres, named ``random_shape_<index:04d>``; black or dark grey
    with probability ``dark`` (the shape, density and friction do not depend on it)."""
    lo, hi = _check_size(size)
    dark = _check_dark(dark)
    if isinstance(seed, bool) or int(seed) < 0 or isinstance(index, bool) or int(index) < 0:
        raise InvalidArgumentError(
            f"random_shape: seed and index must be integers >= 0, got {seed!r}, {index!r}"
        )
    rng = np.random.default_rng([_STREAM, int(seed), int(index)])
    kind = KINDS[int(rng.integers(len(KINDS)))]
    extent = float(rng.uniform(lo, hi))
    mesh = _BUILDERS[kind](rng, extent)
    # A random orientation of the built shape's frame, then z up along its thinnest extent
    # is left to the drop; only the extent is fixed here.
    v = mesh.vertices
    v = v - 0.5 * (v.min(axis=0) + v.max(axis=0))
    scale = extent / float(np.ptp(v, axis=0).max())
    v = v * scale
    mesh = Mesh(v, mesh.faces).oriented_outward()
    material, density, friction = _material(rng, index, dark)
    volume = mesh.signed_volume
    density = float(min(density, max(100.0, MAX_MASS_KG / volume)))
    ext = np.ptp(mesh.vertices, axis=0)
    half = 0.5 * ext
    keypoints = (
        Keypoint(1, "top", (0.0, 0.0, float(half[2]))),
        Keypoint(2, "bottom", (0.0, 0.0, float(-half[2]))),
    )
    tags = {"random"} | size_tags(ext)
    if max(material.base_color[:3]) < 0.05:
        tags.add("black")
    return ObjectSpec(
        category_id=category_id,
        name=f"random_shape_{index:04d}",
        description=f"random {kind}, {extent * 1000:.0f} mm, {material.name.split('_')[1]}",
        vertices=mesh.vertices,
        faces=mesh.faces,
        uvs=None,
        material=material,
        density=density,
        friction=friction,
        keypoints=keypoints,
        tags=frozenset(tags),
    )


def random_shape_source(
    count: int, size: Sequence[float], seed: int, first_id: int, dark: float = DEFAULT_DARK
) -> str:
    """The ``source`` string that names a pool of random shapes in a scene file (``dark`` is
    written only when it is not the default)."""
    lo, hi = _check_size(size)
    fields = f"count={int(count)};seed={int(seed)};size={lo!r},{hi!r};first_id={int(first_id)}"
    if _check_dark(dark) != DEFAULT_DARK:
        fields += f";dark={float(dark)!r}"
    return RANDOM_SOURCE_PREFIX + fields


@functools.lru_cache(maxsize=8)
def random_shapes(
    count: int,
    size: tuple[float, float] = (0.02, 0.25),
    seed: int = 0,
    first_id: int = 1,
    dark: float = DEFAULT_DARK,
) -> tuple[ObjectSpec, ...]:
    """The pool of ``count`` random shapes of ``seed`` (indices 0..count-1), category ids
    ``first_id``.. in order. Each shape depends only on (seed, its index, size, dark), so a
    larger pool starts with the same shapes."""
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 0:
        raise InvalidArgumentError(
            f"objects.random_shapes: expected an integer >= 0, got {count!r}"
        )
    return tuple(random_shape(seed, k, size, first_id + k, dark) for k in range(int(count)))


def random_shapes_from_source(source: str) -> tuple[ObjectSpec, ...]:
    """The pool named by a :func:`random_shape_source` string."""
    if not source.startswith(RANDOM_SOURCE_PREFIX):
        raise InvalidArgumentError(f"not a random-shapes source: {source!r}")
    try:
        fields = dict(kv.split("=", 1) for kv in source[len(RANDOM_SOURCE_PREFIX) :].split(";"))
        lo, hi = (float(x) for x in fields["size"].split(","))
        dark = float(fields.get("dark", DEFAULT_DARK))
        return random_shapes(
            int(fields["count"]), (lo, hi), int(fields["seed"]), int(fields["first_id"]), dark
        )
    except (KeyError, ValueError) as e:
        raise InvalidArgumentError(f"malformed random-shapes source {source!r}: {e}") from e
