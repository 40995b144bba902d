"""Warnings about configurations that run but give degenerate datasets (``mgn config check``,
``mgn generate``): far more objects than the tote holds, images too small to label, cameras that
cannot see into the tote, objects too small to render or grasp. Each warning names the setting.
"""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from mgn.objects import ObjectSpec, builtin_objects, load_objects_yaml
from mgn.objects.user import ImplausibleSizeWarning, UserObjectWarning
from mgn.pipeline.config import Config
from mgn.pipeline.scene_writer import scene_intrinsics

__all__ = [
    "MAX_OBJECT_FILL",
    "MIN_IMAGE_PX",
    "MIN_OBJECT_SIZE",
    "Catalogue",
    "config_warnings",
    "load_catalogue",
]

#: Warn when the bounding boxes of the asked objects add up to more than this multiple of the
#: tote's inner volume (a loose pile fills about half of its boxes' volume; beyond this most
#: objects are removed as they leave the tote).
MAX_OBJECT_FILL = 1.0
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
    notes: dict[str, list[UserObjectWarning]] = {}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for path in config.objects.user_objects:
            for spec in load_objects_yaml(path):
                specs.append(spec)
                sources[spec.name] = os.fspath(Path(path).resolve())
    for w in caught:
        msg = w.message
        if isinstance(msg, UserObjectWarning) and msg.object_name is not None:
            notes.setdefault(msg.object_name, []).append(msg)
        else:
            warnings.warn_explicit(msg, w.category, w.filename, w.lineno)
    return Catalogue(tuple(specs), sources, {k: tuple(v) for k, v in notes.items()})


def _asked_objects(config: Config) -> tuple[str, int]:
    """(setting, how many objects each scene drops at most)."""
    o = config.objects
    if o.names is not None:
        return "objects.names", len(o.names)
    if o.count is not None:
        return "objects.count", int(o.count)
    if o.categories is not None:
        return "objects.categories", len(o.categories) * int(o.copies[1])
    return "objects.count", o.DEFAULT_COUNT


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
    by_id = {str(s.category_id): s.name for s in catalogue.specs}
    names = [by_id.get(str(n), str(n)) for n in (config.objects.names or config.objects.categories
                                                 or ())]  # fmt: skip
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
    key, n = _asked_objects(config)
    pool = [sizes[s] for s in names if s in sizes] or list(sizes.values())
    mean_box = sum(v for _, v in pool) / max(len(pool), 1)
    tote_volume = tote.inner_length * tote.inner_width * tote.inner_height
    if n * mean_box > MAX_OBJECT_FILL * tote_volume:
        fits = int(MAX_OBJECT_FILL * tote_volume / mean_box) if mean_box > 0 else n
        found.append(
            f"{key}: {n} objects per scene; their boxes add up to "
            f"{n * mean_box / tote_volume:.1f}x the tote's inner volume, so most will leave the "
            f"tote and be removed (about {fits} fit)"
        )
    return found
