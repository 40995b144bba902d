"""Checks of a configuration beyond its keys and values (``mgn config check``, ``mgn generate``).

:func:`config_errors`: what fails every scene or leaves every scene empty; ``mgn config check``
exits 1 on it and :func:`mgn.pipeline.generate` refuses the config before writing anything.
:func:`config_warnings`: what runs but gives a degenerate dataset: far more objects than the tote
holds, images too small to label, cameras that cannot see into the tote, objects too small to
render or grasp, a bin in the wrong unit, and the user-object loader's warnings about the objects
the config uses. Each message names the setting.
"""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mgn.objects import ObjectSpec, ToteSpec, builtin_objects, load_objects_yaml, make_tote
from mgn.objects.random_shapes import random_shape_source, random_shapes
from mgn.objects.user import PLAUSIBLE_EXTENT_M, ImplausibleSizeWarning, UserObjectWarning
from mgn.pipeline.config import Config
from mgn.pipeline.scene_writer import scene_intrinsics

__all__ = [
    "MAX_OBJECT_FILL",
    "MAX_OBJECT_OVERFILL",
    "MIN_IMAGE_PX",
    "MIN_OBJECT_SIZE",
    "PLAUSIBLE_TOTE_EXTENT_M",
    "Catalogue",
    "config_errors",
    "config_warnings",
    "load_catalogue",
]

#: Warn when the bounding boxes of the asked objects add up to more than this multiple of the
#: tote's inner volume (a loose pile fills about half of its boxes' volume; beyond this most
#: objects are removed as they leave the tote).
MAX_OBJECT_FILL = 1.0
#: Refuse a config whose objects' boxes add up to more than this multiple of the tote's inner
#: volume: an order of magnitude beyond what fits (nine in ten objects would leave the tote, and
#: the drop of thousands of objects runs for many minutes before the refills give up).
MAX_OBJECT_OVERFILL = 10.0
#: Largest extents (m) of a bin (its mesh, its inner box) outside which it is reported as
#: implausible (a file in millimetres read as metres is the usual cause).
PLAUSIBLE_TOTE_EXTENT_M = (0.05, 5.0)
#: Warn when an image side is smaller than this, px.
MIN_IMAGE_PX = 64
#: Warn for objects whose largest extent is smaller than this, m.
MIN_OBJECT_SIZE = 0.005


@dataclass(frozen=True)
class Catalogue:
    """The objects a config can draw from.

    Attributes:
        specs: the built-in objects, then the user objects of ``objects.user_objects``.
        sources: user object name -> its YAML file (absolute path).
        notes: user object name -> the warnings its loader gave (size, missing files), kept so
            that each is reported once, and only for the objects a run uses.
    """

    specs: tuple[ObjectSpec, ...]
    sources: dict[str, str] = field(default_factory=dict)
    notes: dict[str, tuple[UserObjectWarning, ...]] = field(default_factory=dict)

    def used_names(self, config: Config) -> set[str]:
        """Names of the objects ``config.objects`` may put into a scene (every object of the
        catalogue when it draws at random)."""
        o = config.objects
        chosen = o.names if o.names is not None else o.categories
        if chosen is None:
            return {s.name for s in self.specs}
        by_id = {str(s.category_id): s.name for s in self.specs}
        return {by_id.get(str(n), str(n)) for n in chosen}

    def warn(self, names: set[str] | list[str], *, stacklevel: int = 2) -> None:
        """Give the loader's warnings about the objects ``names`` (Python warnings)."""
        for name in sorted(set(names)):
            for w in self.notes.get(name, ()):
                warnings.warn(w, stacklevel=stacklevel + 1)


def load_catalogue(config: Config) -> Catalogue:
    """The built-in and user objects of ``config``; the warnings of the user-object loader are
    kept in :attr:`Catalogue.notes` instead of being given for every object of the files."""
    specs = list(builtin_objects())
    sources: dict[str, str] = {}
    said: list[UserObjectWarning] = []
    for path in config.objects.user_objects:
        for spec in load_objects_yaml(path, notes=said):
            specs.append(spec)
            sources[spec.name] = os.fspath(Path(path).resolve())
    o = config.objects
    if o.random_shapes:
        size = (float(o.random_shape_size[0]), float(o.random_shape_size[1]))
        first = len(specs) + 1
        dark = float(o.random_shape_dark)
        source = random_shape_source(o.random_shapes, size, o.random_shape_seed, first, dark)
        for spec in random_shapes(o.random_shapes, size, o.random_shape_seed, first, dark):
            specs.append(spec)
            sources[spec.name] = source
    notes: dict[str, list[UserObjectWarning]] = {}
    for w in said:
        notes.setdefault(str(w.object_name), []).append(w)
    return Catalogue(tuple(specs), sources, {k: tuple(v) for k, v in notes.items()})


def _asked_objects(config: Config) -> tuple[str, int]:
    """(setting, how many objects each scene drops at most: the max of an ``objects.count``
    range)."""
    o = config.objects
    if o.names is not None:
        return "objects.names", len(o.names)
    if o.count is not None:
        return "objects.count", int(o.count[1] if isinstance(o.count, tuple) else o.count)
    if o.categories is not None:
        return "objects.categories", len(o.categories) * int(o.copies[1])
    return "objects.count", o.DEFAULT_COUNT


def _up_to(config: Config) -> str:
    """``"up to "`` when ``objects.count`` is a range (the messages give its max)."""
    return "up to " if isinstance(config.objects.count, tuple) else ""


def _sizes(catalogue: Catalogue) -> dict[str, tuple[float, float]]:
    """name -> (largest extent m, bounding-box volume m^3) of every object that can be drawn."""
    out = {}
    for s in catalogue.specs:
        ext = s.vertices.max(axis=0) - s.vertices.min(axis=0)
        out[s.name] = (float(ext.max()), float(ext.prod()))
    return out


def config_warnings(config: Config, catalogue: Catalogue | None = None) -> list[str]:
    """Human-readable warnings, each naming the setting, for a config that would give a
    degenerate dataset, and the user-object loader's warnings (size, missing files) about the
    objects the config uses (each once). An empty list: nothing suspicious.

    ``catalogue``: the config's objects when already loaded (:func:`load_catalogue`)."""
    found: list[str] = []
    tote = config.tote
    # Images.
    K = scene_intrinsics(config.camera)
    if min(K.width, K.height) < MIN_IMAGE_PX:
        found.append(
            f"camera.resolution_scale = {config.camera.resolution_scale}: images of "
            f"{K.width}x{K.height} px (< {MIN_IMAGE_PX} px) cannot show the objects"
        )
    # Cameras that cannot see into the tote.
    if config.camera.rig == "hemisphere":
        h = config.camera.hemisphere
        for i, t in enumerate(h.tilts):
            if not 0.0 <= t < math.radians(75.0):
                found.append(
                    f"camera.hemisphere.tilts[{i}] = {t} rad: a camera this far from vertical "
                    "looks at the tote walls, not into the tote; its views see no object"
                )
        for i, r in enumerate(h.radii):
            if r <= tote.inner_height:
                found.append(
                    f"camera.hemisphere.radii[{i}] = {r} m: the camera sits inside the tote "
                    f"(rim at {tote.inner_height} m) and sees no object"
                )
    # Objects: each object the config may use, each warning once.
    catalogue = load_catalogue(config) if catalogue is None else catalogue
    sizes = _sizes(catalogue)
    used = catalogue.used_names(config)
    for name in sorted(used):
        extent = sizes.get(name, (1.0, 0.0))[0]
        notes = catalogue.notes.get(name, ())
        if extent < MIN_OBJECT_SIZE and not any(
            isinstance(w, ImplausibleSizeWarning) for w in notes
        ):  # (the loader's own size warning names the file, the object and its scale)
            where = "objects.user_objects" if name in catalogue.sources else "objects"
            source = f" ('{catalogue.sources[name]}')" if name in catalogue.sources else ""
            found.append(
                f"{where}{source}: object '{name}' is {extent * 1e3:.3g} mm across (< "
                f"{MIN_OBJECT_SIZE * 1e3:g} mm): check its mesh scale; it will cover no pixel "
                "and get no grasp"
            )
        found.extend(str(w) for w in notes)
    fill = _fill(config, catalogue, sizes)
    if fill is not None and fill[2] <= MAX_OBJECT_OVERFILL:
        key, n, ratio, fits = fill
        found.append(
            f"{key}: {_up_to(config)}{n} objects per scene; their boxes add up to "
            f"{ratio:.1f}x the tote's inner "
            f"volume, so most will leave the tote and be removed (about {fits} fit)"
        )
    found += _tote_warnings(config)
    found += _camera_problems(config)[1]
    rs = config.render
    if (
        tuple(config.tote.color) != ToteSpec().color
        and config.camera.randomize
        and (rs.engine == "raster" or rs.randomize.materials)
    ):
        found.append(
            f"tote.color = {list(config.tote.color)} is not used: camera.randomize draws the "
            "tote's colour per view; set camera.randomize: false"
            + (" (or render.randomize.materials: false)" if rs.engine == "path" else "")
            + " to keep it"
        )
    o = config.objects
    if o.names is None and (o.categories is None or o.count is not None):
        used = catalogue.used_names(config)
        large = sorted(n for n in _too_large(config, catalogue) if n in used)
        if large:
            key = "objects.count" if o.categories is None else "objects.categories"
            found.append(
                f"{key}: the objects of each scene are drawn at random, and "
                f"{', '.join(repr(n) for n in large)} cannot lie in the tote's cavity: every "
                "scene that draws one fails"
            )
    return found


def _fill(
    config: Config,
    catalogue: Catalogue,
    sizes: dict[str, tuple[float, float]],
    typical: bool = False,
) -> tuple[str, int, float, int] | None:
    """(setting, objects per scene, their boxes / the tote's inner volume, about how many fit)
    when the boxes add up to more than :data:`MAX_OBJECT_FILL` tote volumes; else None. Each
    drawn object counts with the mean box of the objects drawn from, or with ``typical`` their
    lower median box (one huge object in the pool fails only the scenes that draw it)."""
    tote = config.tote
    key, n = _asked_objects(config)
    by_id = {str(s.category_id): s.name for s in catalogue.specs}
    chosen = config.objects.names or config.objects.categories or ()
    names = [by_id.get(str(c), str(c)) for c in chosen]
    pool = [sizes[s] for s in names if s in sizes] or list(sizes.values())
    if typical and config.objects.names is None:
        boxes = sorted(v for _, v in pool)
        mean_box = boxes[(len(boxes) - 1) // 2] if boxes else 0.0
    else:
        mean_box = sum(v for _, v in pool) / max(len(pool), 1)
    tote_volume = tote.inner_length * tote.inner_width * tote.inner_height
    if n * mean_box <= MAX_OBJECT_FILL * tote_volume:
        return None
    fits = int(MAX_OBJECT_FILL * tote_volume / mean_box) if mean_box > 0 else n
    return key, n, n * mean_box / tote_volume, fits


def _tote_warnings(config: Config) -> list[str]:
    """A bin (its mesh or its inner box) outside :data:`PLAUSIBLE_TOTE_EXTENT_M`: probably a
    file or a number in the wrong unit."""
    tote, out = config.tote, []
    lo, hi = PLAUSIBLE_TOTE_EXTENT_M
    inner = max(tote.inner_length, tote.inner_width, tote.inner_height)
    if not lo <= inner <= hi:
        out.append(
            f"tote.inner_length / inner_width / inner_height: {tote.inner_length:g} x "
            f"{tote.inner_width:g} x {tote.inner_height:g} m is "
            + ("too large" if inner > hi else "too small")
            + f" for a bin (expected {lo:g} .. {hi:g} m); the sizes are in metres"
        )
    if tote.mesh is not None:
        v, _ = make_tote(tote)
        extent = float(np.ptp(v, axis=0).max())
        if not lo <= extent <= hi:
            hint = (
                "if the file is in millimetres, use tote.mesh_scale 0.001"
                if extent > hi
                else "check tote.mesh_scale (the file's unit)"
            )
            out.append(
                f"tote.mesh '{tote.mesh}' (mesh_scale {tote.mesh_scale:g}) is {extent:.3g} m "
                f"across, too {'large' if extent > hi else 'small'} for a bin around an inner box "
                f"of {tote.inner_length:g} x {tote.inner_width:g} x {tote.inner_height:g} m; "
                f"{hint}"
            )
    return out


def _unknown_names(config: Config, catalogue: Catalogue) -> list[str]:
    """objects.names / objects.categories entries that name no object of the catalogue."""
    known = {s.name for s in catalogue.specs} | {str(s.category_id) for s in catalogue.specs}
    out = []
    for key in ("names", "categories"):
        chosen = getattr(config.objects, key) or ()
        unknown = sorted({str(n) for n in chosen if str(n) not in known})
        if unknown:
            more = " (user objects: objects.user_objects or --add)" if not catalogue.sources else ""
            out.append(
                f"objects.{key}: unknown object(s) {', '.join(map(repr, unknown))}; known: "
                f"{', '.join(sorted(s.name for s in catalogue.specs))}, or their category ids"
                f"{more}"
            )
    return out


def _too_large(config: Config, catalogue: Catalogue) -> dict[str, tuple[float, float, float]]:
    """name -> sorted extents (m) of the objects that cannot lie in the tote's cavity (the
    drop's rule: second-largest extent <= the cavity's width, largest <= its diagonal)."""
    t = config.tote
    width, diag = min(t.inner_length, t.inner_width), math.hypot(t.inner_length, t.inner_width)
    out = {}
    for s in catalogue.specs:
        e = sorted(float(x) for x in np.ptp(np.asarray(s.vertices, np.float64), axis=0))
        if e[1] > width or e[2] > diag:
            out[s.name] = (e[0], e[1], e[2])
    return out


def _window_errors(config: Config) -> list[str]:
    """The drop's release window must lie above the tote's cavity."""
    t, d = config.tote, config.drop
    lo, hi = np.asarray(d.window_min, np.float64), np.asarray(d.window_max, np.float64)
    hx, hy = 0.5 * t.inner_length, 0.5 * t.inner_width
    if lo[0] < -hx or hi[0] > hx or lo[1] < -hy or hi[1] > hy or lo[2] < 0:
        return [
            f"drop.window_min / drop.window_max: the release window x [{lo[0]:g}, {hi[0]:g}], "
            f"y [{lo[1]:g}, {hi[1]:g}], z >= {lo[2]:g} m does not lie above the tote's cavity "
            f"(|x| <= {hx:g}, |y| <= {hy:g}, z >= 0; tote.inner_length x inner_width = "
            f"{t.inner_length:g} x {t.inner_width:g} m): every drop fails; make the window "
            "smaller or the tote larger"
        ]
    return []


def _camera_problems(config: Config) -> tuple[list[str], list[str]]:
    """(errors, warnings) of the cameras of ``camera.rig: poses``: a camera with the whole tote
    behind it fails every scene (error); one below the tote's floor, or seeing no part of the
    cavity, gives views without any object (a warning; an error when no camera sees in)."""
    cam = config.camera
    if cam.rig != "poses":
        return [], []
    t = config.tote
    K = scene_intrinsics(cam)
    hx, hy, h = 0.5 * t.inner_length, 0.5 * t.inner_width, t.inner_height
    ox, oy = t.outer_size[0] / 2, t.outer_size[1] / 2
    outer = np.array(
        [[x, y, z] for x in (-ox, ox) for y in (-oy, oy) for z in (-t.floor_thickness, h)]
    )
    g = np.linspace(-1.0, 1.0, 9)
    cavity = np.array([[a * hx, b * hy, z] for a in g for b in g for z in (0.0, 0.5 * h)])
    errors, warns, blind = [], [], 0
    for i, X in enumerate(np.asarray(cam.poses, np.float64)):
        if i not in cam.view_indices:
            continue
        R, c = X[:3, :3], X[:3, 3]
        where = f"camera.poses[{i}] (eye {np.round(c, 3).tolist()} m)"
        z_outer = (outer - c) @ R[:, 2]
        if np.all(z_outer <= 0):
            errors.append(
                f"{where}: the camera looks away from the tote (all of it is behind the camera; "
                "OpenCV frame, z forward): rendering its view fails every scene; point it at the "
                "tote (e.g. {eye: [...], target: [0, 0, 0]})"
            )
            continue
        pc = (cavity - c) @ R
        front = pc[:, 2] > 1e-6
        u = K.fx * pc[front, 0] / pc[front, 2] + K.cx
        v = K.fy * pc[front, 1] / pc[front, 2] + K.cy
        sees = bool(np.any((u >= 0) & (u <= K.width) & (v >= 0) & (v <= K.height)))
        if c[2] < 0:
            blind += 1
            warns.append(
                f"{where}: the camera is below the tote's floor (z = {c[2]:g} m < 0): it sees "
                "the underside, and its views show no object"
            )
        elif not sees:
            blind += 1
            warns.append(
                f"{where}: no part of the tote's cavity is in its image; its views show no object"
            )
    if blind and blind == len(cam.view_indices) and not errors:
        errors.append(
            "camera.poses: no camera sees into the tote (every view would show no object): "
            + "; ".join(warns)
        )
        warns = []
    return errors, warns


def config_errors(config: Config, catalogue: Catalogue | None = None) -> list[str]:
    """What makes every scene of ``config`` fail or come out empty, each naming the setting:
    unknown object names, an object larger than the tote that every scene holds, a release
    window outside the tote, objects all below 1 mm, far more objects than the tote could ever
    hold (refused before anything is allocated), a camera facing away from the tote, cameras
    none of which sees into it. An empty list: nothing that fails for sure. ``mgn config check``
    prints these and exits 1; :func:`mgn.pipeline.generate` refuses such a config before it
    writes anything. (Out-of-range values, e.g. ``render.max_bounces``, fail in
    :func:`mgn.pipeline.load_config` already.)"""
    catalogue = load_catalogue(config) if catalogue is None else catalogue
    found: list[str] = _unknown_names(config, catalogue)
    found += _window_errors(config)
    o = config.objects
    chosen = o.names if o.names is not None else o.categories
    if chosen is not None and not found:
        used = catalogue.used_names(config)
        large = {n: e for n, e in _too_large(config, catalogue).items() if n in used}
        key = "objects.names" if o.names is not None else "objects.categories"
        every = o.names is not None or o.count is None  # else a scene draws some categories
        for name, e in sorted(large.items()) if every else ():
            t = config.tote
            found.append(
                f"{key}: object '{name}' ({e[2]:.3g} x {e[1]:.3g} x {e[0]:.3g} m) is larger than "
                f"the tote's cavity ({t.inner_length:g} x {t.inner_width:g} m): every scene that "
                "holds it fails (check its scale, or use a larger tote)"
            )
        sizes = _sizes(catalogue)
        tiny = [n for n in sorted(used) if sizes.get(n, (1.0, 0.0))[0] < PLAUSIBLE_EXTENT_M[0]]
        if used and len(tiny) == len(used):
            found.append(
                f"{key}: every object is smaller than {PLAUSIBLE_EXTENT_M[0] * 1e3:g} mm ("
                + ", ".join(f"'{n}' {sizes[n][0] * 1e3:.3g} mm" for n in tiny)
                + "): no scene would hold an object one can see or grasp; check their scale"
            )
    fill = _fill(config, catalogue, _sizes(catalogue))
    least = _fill(config, catalogue, _sizes(catalogue), typical=True)
    if fill is not None and least is not None and least[2] > MAX_OBJECT_OVERFILL:
        key, n, ratio, fits = fill
        found.append(
            f"{key}: {_up_to(config)}{n} objects per scene; their boxes add up to "
            f"{ratio:.3g}x the tote's inner "
            f"volume (more than {MAX_OBJECT_OVERFILL:g}x), about {fits} fit; expected at most "
            f"about {int(fits * MAX_OBJECT_OVERFILL / MAX_OBJECT_FILL)}"
        )
    found += _camera_problems(config)[0]
    return found
