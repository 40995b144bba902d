"""Warnings about configurations that run but give degenerate datasets (``mgn config check``,
``mgn generate``): far more objects than the tote holds, images too small to label, cameras that
cannot see into the tote, objects too small to render or grasp. Each warning names the setting.
"""

from __future__ import annotations

import math

from mgn.objects import builtin_objects, load_objects_yaml
from mgn.pipeline.config import Config
from mgn.pipeline.scene_writer import scene_intrinsics

__all__ = [
    "MAX_OBJECT_FILL",
    "MIN_IMAGE_PX",
    "MIN_OBJECT_SIZE",
    "config_warnings",
]

#: Warn when the bounding boxes of the asked objects add up to more than this multiple of the
#: tote's inner volume (a loose pile fills about half of its boxes' volume; beyond this most
#: objects are removed as they leave the tote).
MAX_OBJECT_FILL = 1.0
#: Warn when an image side is smaller than this, px.
MIN_IMAGE_PX = 64
#: Warn for objects whose largest extent is smaller than this, m.
MIN_OBJECT_SIZE = 0.005


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


def _catalogue_sizes(config: Config) -> dict[str, tuple[float, float]]:
    """name -> (largest extent m, bounding-box volume m^3) of every object that can be drawn."""
    specs = list(builtin_objects())
    for path in config.objects.user_objects:
        specs.extend(load_objects_yaml(path))
    out = {}
    for s in specs:
        ext = s.vertices.max(axis=0) - s.vertices.min(axis=0)
        out[s.name] = (float(ext.max()), float(ext.prod()))
    return out


def config_warnings(config: Config) -> list[str]:
    """Human-readable warnings, each naming the setting, for a config that would give a
    degenerate dataset. An empty list: nothing suspicious."""
    warnings: list[str] = []
    tote = config.tote
    # Images.
    K = scene_intrinsics(config.camera)
    if min(K.width, K.height) < MIN_IMAGE_PX:
        warnings.append(
            f"camera.resolution_scale = {config.camera.resolution_scale}: images of "
            f"{K.width}x{K.height} px (< {MIN_IMAGE_PX} px) cannot show the objects"
        )
    # Cameras that cannot see into the tote.
    if config.camera.rig == "hemisphere":
        h = config.camera.hemisphere
        for i, t in enumerate(h.tilts):
            if not 0.0 <= t < math.radians(75.0):
                warnings.append(
                    f"camera.hemisphere.tilts[{i}] = {t} rad: a camera this far from vertical "
                    "looks at the tote walls, not into the tote; its views see no object"
                )
        for i, r in enumerate(h.radii):
            if r <= tote.inner_height:
                warnings.append(
                    f"camera.hemisphere.radii[{i}] = {r} m: the camera sits inside the tote "
                    f"(rim at {tote.inner_height} m) and sees no object"
                )
    # Objects.
    sizes = _catalogue_sizes(config)
    names = [str(n) for n in (config.objects.names or config.objects.categories or ())]
    for name, (extent, _) in sorted(sizes.items()):
        if extent < MIN_OBJECT_SIZE and (not names or name in names):
            where = "objects.user_objects" if config.objects.user_objects else "objects"
            warnings.append(
                f"{where}: object '{name}' is {extent * 1e3:.3g} mm across (< "
                f"{MIN_OBJECT_SIZE * 1e3:g} mm): check its mesh scale; it will cover no pixel "
                "and get no grasp"
            )
    key, n = _asked_objects(config)
    pool = [sizes[s] for s in names if s in sizes] or list(sizes.values())
    mean_box = sum(v for _, v in pool) / max(len(pool), 1)
    tote_volume = tote.inner_length * tote.inner_width * tote.inner_height
    if n * mean_box > MAX_OBJECT_FILL * tote_volume:
        fits = int(MAX_OBJECT_FILL * tote_volume / mean_box) if mean_box > 0 else n
        warnings.append(
            f"{key}: {n} objects per scene; their boxes add up to "
            f"{n * mean_box / tote_volume:.1f}x the tote's inner volume, so most will leave the "
            f"tote and be removed (about {fits} fit)"
        )
    return warnings
