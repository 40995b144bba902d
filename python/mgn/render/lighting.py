"""The per-view domain randomisation of the path-traced photographs: the area lights, the
environment, the tote and floor materials and the exposure of one view (:func:`draw_lighting`,
:class:`ViewLighting`), each part switchable (:class:`mgn.render.settings.RandomizeSettings`).

Everything is drawn from the stream (seed, view index) only, one independent stream per part, so
a view looks the same whatever the number of threads or workers and whichever other views are
rendered: 1-3 rectangular area lights above the tote (size, position, colour temperature
(:func:`blackbody_rgb`), intensity), the environment (uniform / gradient / sky, intensity), the
tote and floor materials (colour, roughness and a procedural texture,
:func:`mgn.render.materials.procedural_texture`) and the exposure. The objects' own materials
(:func:`draw_object_materials`, off by default) are drawn from one further stream per object,
(seed, view index, object id), and a light at the camera (:func:`draw_camera_light`, off by
default) from a stream of its own, so they change nothing else in the view, except that a view
with the camera light may dim its other lights and environment (:func:`with_camera_light`; the
look of a 3D camera's projector in a dark cell). No distractor objects are added.

Units: metres, radiance in the tracer's units (a white Lambertian surface under irradiance E
shows E / pi); poses (4, 4) float64 ``X_AB``.
"""

from __future__ import annotations

import colorsys
import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError
from mgn.render.materials import (
    FLOOR_COLOR,
    FLOOR_ROUGHNESS,
    TEXTURES,
    TOTE_ROUGHNESS,
    procedural_pattern,
    procedural_texture,
    srgb_to_linear,
    two_colour_texture,
)
from mgn.render.path import AreaLight, Environment, PbrMaterial
from mgn.render.settings import RenderSettings

__all__ = [
    "DARK_TOTE",
    "ENVIRONMENTS",
    "TOTE_HSV",
    "ViewLighting",
    "blackbody_rgb",
    "draw_camera_light",
    "draw_lighting",
    "draw_object_materials",
    "with_camera_light",
]

#: Environment kinds the randomisation draws from.
ENVIRONMENTS = ("uniform", "gradient", "sky")
#: The randomised tote's colour (sRGB, HSV): hue uniform in [0, 1), saturation and value
#: uniform in these ranges.
TOTE_HSV = {"saturation": (0.2, 0.8), "value": (0.15, 0.75)}
#: With this probability a view's tote is black or dark grey plastic instead (the common
#: industrial tote): saturation and value uniform in these ranges (value 0.08-0.3 of sRGB is
#: a reflectance of about 1-7 %).
DARK_TOTE: dict[str, Any] = {
    "probability": 1.0 / 3.0,
    "saturation": (0.0, 0.15),
    "value": (0.08, 0.3),
}


def blackbody_rgb(temperature: float) -> tuple[float, float, float]:
    """Linear RGB tint of a black body at ``temperature`` K, white (1, 1, 1) at 6500 K and unit
    luminance: Planck's law sampled at the dominant wavelengths of the sRGB primaries (611, 549,
    464 nm), divided by the same at 6500 K. Accurate to a few percent in tint for 2500-10000 K,
    which is all lighting randomisation needs."""
    if not (math.isfinite(temperature) and temperature > 0):
        raise InvalidArgumentError(f"colour temperature must be > 0 K, got {temperature!r}")
    lam = np.array([611e-9, 549e-9, 464e-9])
    c2 = 1.4387769e-2  # m K, second radiation constant

    def planck(t: float) -> npt.NDArray[np.float64]:
        return 1.0 / (lam**5 * np.expm1(c2 / (lam * t)))

    rgb = planck(temperature) / planck(6500.0)
    rgb /= float(0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2])
    return (float(rgb[0]), float(rgb[1]), float(rgb[2]))


@dataclass(frozen=True)
class ViewLighting:
    """Everything drawn for one view: the lights, the environment, tote / floor materials and
    the exposure (EV, including the configured base)."""

    lights: tuple[Any, ...]
    environment: Any
    tote: Any
    floor: Any
    exposure: float
    summary: dict[str, Any] = field(default_factory=dict, compare=False)


def _look_down_pose(
    position: npt.NDArray[np.float64], target: npt.NDArray[np.float64], yaw: float
) -> npt.NDArray[np.float64]:
    """X_WL of a light at ``position`` whose +z axis points at ``target``."""
    z = target - position
    z /= np.linalg.norm(z)
    a = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    x = a - z * float(a @ z)
    if np.linalg.norm(x) < 1e-6:
        x = np.array([1.0, 0.0, 0.0]) - z * z[0]
    x /= np.linalg.norm(x)
    X = np.eye(4)
    X[:3, 0], X[:3, 1], X[:3, 2], X[:3, 3] = x, np.cross(z, x), z, position
    return X


def draw_lighting(
    settings: RenderSettings,
    seed: int,
    view_index: int,
    *,
    target_W: npt.ArrayLike = (0.0, 0.0, 0.0),
    tote_color: Sequence[float] = (0.2, 0.35, 0.6),
    randomize: bool = True,
) -> ViewLighting:
    """The lights, environment, tote / floor materials and exposure of view ``view_index``,
    drawn from (seed, view_index) by the switches of ``settings.randomize`` (all off when
    ``randomize`` is false: one 1 m x 1 m light 1.6 m above ``target_W``, a soft gradient
    environment, the tote in ``tote_color``, a grey floor, the configured exposure)."""

    r = settings.randomize
    target = np.asarray(target_W, np.float64)
    ss = np.random.SeedSequence([int(seed) & (2**63 - 1), int(view_index), 0x50484F54])
    # One independent stream per part: switching one part off does not change the others.
    g_light, g_env, g_mat, g_exp = (np.random.Generator(np.random.PCG64(s)) for s in ss.spawn(4))
    summary: dict[str, Any] = {}

    lights = []
    if randomize and r.lights:
        n = int(g_light.integers(r.light_count[0], r.light_count[1] + 1))
        for _ in range(n):
            side = g_light.uniform(*r.light_size)
            aspect = g_light.uniform(0.5, 1.0)
            h = g_light.uniform(*r.light_height)
            rad = r.light_offset * math.sqrt(g_light.random())
            phi = g_light.uniform(0.0, 2 * math.pi)
            pos = target + np.array([rad * math.cos(phi), rad * math.sin(phi), h])
            temp = g_light.uniform(*r.light_temperature)
            # Each light casts 1/n of the drawn irradiance on the target: a small light facing
            # the target at distance d and height h gives E = L A h / d^3 (A cos0 cos(theta)/d^2).
            e = g_light.uniform(*r.light_irradiance) / n
            area = side * side * aspect
            d = float(np.linalg.norm(pos - target))
            lights.append(
                AreaLight(
                    _look_down_pose(pos, target, g_light.uniform(0.0, math.pi)),
                    "rect",
                    (side, side * aspect),
                    blackbody_rgb(temp),
                    e * d**3 / (area * h),
                )
            )
        summary["lights"] = n
    else:
        lights.append(
            AreaLight(
                _look_down_pose(target + np.array([0.25, -0.2, 1.6]), target, 0.0),
                "rect",
                (1.0, 1.0),
                (1.0, 1.0, 1.0),
                20.0,
            )
        )
    if randomize and r.environment:
        kind = ENVIRONMENTS[int(g_env.integers(len(ENVIRONMENTS)))]
        inten = float(g_env.uniform(*r.environment_intensity))
        tint = blackbody_rgb(float(g_env.uniform(5000.0, 9000.0)))
        sun = g_env.normal(size=3)
        sun[2] = abs(sun[2]) + 0.5
        sun /= np.linalg.norm(sun)
        env = Environment(
            kind=kind,
            color=tint,
            zenith=tuple(0.8 * np.asarray(tint) * (0.75, 0.85, 1.0)),
            horizon=(0.9, 0.9, 0.9),
            ground=(0.25, 0.24, 0.22),
            sun_direction=tuple(sun),
            intensity=inten,
        )
        summary["environment"] = kind
    else:
        env = Environment(
            kind="gradient",
            zenith=(0.55, 0.6, 0.7),
            horizon=(0.8, 0.8, 0.8),
            ground=(0.25, 0.24, 0.22),
            intensity=0.4,
        )
    if randomize and r.materials:
        hue = g_mat.random()
        sat = g_mat.uniform(*TOTE_HSV["saturation"])
        val = g_mat.uniform(*TOTE_HSV["value"])
        tote_roughness = float(g_mat.uniform(0.35, 0.75))
        tote_texture = procedural_texture("noise", g_mat, contrast=0.15)
        kind = TEXTURES[int(g_mat.integers(len(TEXTURES)))]
        floor_rgb = srgb_to_linear(
            np.array(_hsv_to_rgb(g_mat.random(), g_mat.uniform(0, 0.4), g_mat.uniform(0.25, 0.8)))
        )
        floor = PbrMaterial(
            base_color=tuple(floor_rgb),
            roughness=float(g_mat.uniform(0.3, 0.95)),
            base_color_texture=procedural_texture(kind, g_mat, contrast=0.35),
        )
        # Drawn last, so that the other draws of the stream do not depend on it.
        if g_mat.random() < DARK_TOTE["probability"]:
            sat = g_mat.uniform(*DARK_TOTE["saturation"])
            val = g_mat.uniform(*DARK_TOTE["value"])
        tote_rgb = srgb_to_linear(np.array(_hsv_to_rgb(hue, sat, val)))
        tote = PbrMaterial(
            base_color=tuple(tote_rgb),
            roughness=tote_roughness,
            base_color_texture=tote_texture,
        )
        summary["floor_texture"] = kind
        summary["tote_hsv"] = (float(hue), float(sat), float(val))
    else:
        rgb = (float(tote_color[0]), float(tote_color[1]), float(tote_color[2]))
        tote = PbrMaterial(base_color=rgb, roughness=TOTE_ROUGHNESS)
        floor = PbrMaterial(base_color=FLOOR_COLOR, roughness=FLOOR_ROUGHNESS)
    exposure = settings.exposure
    if randomize and r.exposure and r.exposure_range > 0:
        exposure += float(g_exp.uniform(-r.exposure_range, r.exposure_range))
    return ViewLighting(tuple(lights), env, tote, floor, exposure, summary)


#: Tag of the object-appearance streams (seed, view index, tag, object id), apart from the
#: lighting streams (seed, view index, 0x50484F54).
_APPEARANCE_TAG = 0x4F424A41


def draw_object_materials(
    settings: RenderSettings,
    seed: int,
    view_index: int,
    object_id: int,
    materials: Sequence[PbrMaterial],
    *,
    randomize: bool = True,
) -> tuple[PbrMaterial, ...]:
    """The materials of object ``object_id`` (>= 0) in view ``view_index``: ``materials``
    (one per material slot) unchanged, or, when ``settings.randomize.object_appearance`` and
    ``randomize`` are on and the object's draw (probability ``object_probability``) says so, a
    new material per slot (:class:`mgn.render.settings.RandomizeSettings`): a random colour,
    or a procedural pattern between two random colours, a random roughness, metallic 0; slots
    with transmission > 0 are kept. Drawn from the stream (seed, view index, object id) only."""
    mats = tuple(materials)
    r = settings.randomize
    if not (randomize and r.object_appearance):
        return mats
    if isinstance(object_id, bool) or not isinstance(object_id, (int, np.integer)) or object_id < 0:
        raise InvalidArgumentError(f"object_id must be an integer >= 0, got {object_id!r}")
    ss = np.random.SeedSequence(
        [int(seed) & (2**63 - 1), int(view_index), _APPEARANCE_TAG, int(object_id)]
    )
    g = np.random.Generator(np.random.PCG64(ss))
    if not g.random() < r.object_probability:
        return mats
    out = []
    for m in mats:
        # Every slot draws the same numbers, kept or not: a slot's draw does not depend on
        # the materials of the slots before it.
        first = _draw_object_colour(g, r.object_saturation, r.object_value)
        roughness = float(g.uniform(*r.object_roughness))
        pattern = procedural_pattern(TEXTURES[int(g.integers(len(TEXTURES)))], g)
        texture = None
        base = first
        if pattern is not None:
            second = _draw_object_colour(g, r.object_saturation, r.object_value)
            texture = two_colour_texture(pattern, first, second)
            base = (1.0, 1.0, 1.0)
        if m.transmission > 0.0:
            out.append(m)
            continue
        out.append(
            PbrMaterial(
                base_color=base,
                metallic=0.0,
                roughness=roughness,
                ior=m.ior,
                emission=m.emission,
                base_color_texture=texture,
            )
        )
    return tuple(out)


#: Tag of the camera-light stream (seed, view index, tag).
_CAMERA_LIGHT_TAG = 0x43414D4C


def draw_camera_light(
    settings: RenderSettings,
    seed: int,
    view_index: int,
    X_WC: npt.ArrayLike,
    *,
    target_W: npt.ArrayLike = (0.0, 0.0, 0.0),
    randomize: bool = True,
) -> AreaLight | None:
    """The light at the camera of view ``view_index`` (camera pose ``X_WC``, OpenCV frame:
    +z along the viewing direction), or None: drawn, when
    ``settings.randomize.camera_light`` and ``randomize`` are on, with probability
    ``camera_light_probability`` from the stream (seed, view index) of its own. A white
    square light in the camera's image plane, ``camera_light_offset`` from the optical centre,
    emitting along +z of the camera, its radiance set so that it casts the drawn
    ``camera_light_irradiance`` on ``target_W`` (E = L A cos(a) cos(b) / d^2)."""
    drawn = _draw_camera_light(settings, seed, view_index, X_WC, target_W, randomize)
    return None if drawn is None else drawn[0]


def with_camera_light(
    lit: ViewLighting,
    settings: RenderSettings,
    seed: int,
    view_index: int,
    X_WC: npt.ArrayLike,
    *,
    target_W: npt.ArrayLike = (0.0, 0.0, 0.0),
    randomize: bool = True,
) -> ViewLighting:
    """``lit`` with the light at the camera of :func:`draw_camera_light` added, and the other
    lights and the environment scaled by the factor drawn from ``camera_light_ambient`` (the
    same stream, drawn after the light, so the light does not depend on the range); ``lit``
    itself when the view has no camera light. The summary gains ``camera_light``: the light's
    offset from the optical centre (m), its side (m), its irradiance on ``target_W`` and the
    ambient factor."""
    drawn = _draw_camera_light(settings, seed, view_index, X_WC, target_W, randomize)
    if drawn is None:
        return lit
    light, ambient, info = drawn
    lights = lit.lights
    env = lit.environment
    if ambient != 1.0:
        lights = tuple(dataclasses.replace(x, intensity=x.intensity * ambient) for x in lit.lights)
        env = dataclasses.replace(env, intensity=env.intensity * ambient)
    summary = {**lit.summary, "camera_light": {**info, "ambient": ambient}}
    return dataclasses.replace(lit, lights=(*lights, light), environment=env, summary=summary)


def _draw_camera_light(
    settings: RenderSettings,
    seed: int,
    view_index: int,
    X_WC: npt.ArrayLike,
    target_W: npt.ArrayLike,
    randomize: bool,
) -> tuple[AreaLight, float, dict[str, float]] | None:
    """(light, ambient factor, summary) of the camera light of a view, or None."""
    r = settings.randomize
    if not (randomize and r.camera_light):
        return None
    X = np.asarray(X_WC, np.float64)
    if X.shape != (4, 4) or not np.all(np.isfinite(X)):
        raise InvalidArgumentError(f"X_WC must be a finite (4, 4) pose, got shape {X.shape}")
    ss = np.random.SeedSequence([int(seed) & (2**63 - 1), int(view_index), _CAMERA_LIGHT_TAG])
    g = np.random.Generator(np.random.PCG64(ss))
    if not g.random() < r.camera_light_probability:
        return None
    side = float(g.uniform(*r.camera_light_size))
    offset = float(g.uniform(*r.camera_light_offset))
    phi = float(g.uniform(0.0, 2.0 * math.pi))
    e = float(g.uniform(*r.camera_light_irradiance))
    ambient = float(g.uniform(*r.camera_light_ambient))
    X_CL = np.eye(4)
    X_CL[:2, :2] = [[math.cos(phi), -math.sin(phi)], [math.sin(phi), math.cos(phi)]]
    X_CL[:2, 3] = (offset * math.cos(phi), offset * math.sin(phi))
    X_WL = X @ X_CL
    to_target = np.asarray(target_W, np.float64) - X_WL[:3, 3]
    d = float(np.linalg.norm(to_target))
    # The light's normal and the target's (world +z, the tote floor) against the ray.
    cos_l = max(float(X_WL[:3, 2] @ to_target) / d, 1e-3)
    cos_t = max(float(-to_target[2]) / d, 1e-3)
    radiance = e * d * d / (side * side * cos_l * cos_t)
    light = AreaLight(X_WL, "rect", (side, side), (1.0, 1.0, 1.0), radiance)
    return light, ambient, {"offset": offset, "size": side, "irradiance": e}


def _draw_object_colour(
    g: np.random.Generator, saturation: tuple[float, float], value: tuple[float, float]
) -> tuple[float, float, float]:
    """Linear RGB of an sRGB HSV colour: hue uniform in [0, 1), saturation and value uniform
    in the given ranges."""
    hue = float(g.random())
    sat = float(g.uniform(*saturation))
    val = float(g.uniform(*value))
    rgb = srgb_to_linear(np.array(_hsv_to_rgb(hue, sat, val)))
    return (float(rgb[0]), float(rgb[1]), float(rgb[2]))


def _hsv_to_rgb(h: float, s: float, v: float) -> tuple[float, float, float]:

    return colorsys.hsv_to_rgb(h, s, v)
