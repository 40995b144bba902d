"""The dataset configuration: one YAML file, validated, with MetaGraspNet defaults.

:class:`Config` gathers everything ``mgn generate`` needs besides the scene count, the output
folder and the seed. Every section is a frozen dataclass whose defaults are the MetaGraspNet
(MGN) values; a YAML file only needs the keys it changes::

    objects: {count: 10}
    camera: {views: [0, 5, 17], resolution_scale: 0.5}
    labels: {pj_physics: false}

Validation names the key, the value received and what was expected; unknown keys are errors
(``mgn config dump`` prints every key with its default). Units are SI (m, kg, s, rad).

Sections:

- ``objects``: which objects fall into each scene: ``names`` (explicit list, repeat a name for
  copies), or ``categories`` (each with ``copies`` = (min, max) copies, MGN 2-5) and/or a total
  ``count`` (a whole number, or ``[min, max]``: each scene draws its own count uniformly in
  min..max from its scene seed); with none of them, ``count`` defaults to 20 objects from
  categories drawn at random (MGN). ``user_objects``: YAML files of user objects (see
  :func:`mgn.objects.load_objects_yaml`) added to the catalogue; relative paths are relative to
  the config file. ``random_shapes``: seeded random procedural objects added to the catalogue
  (``random_shape_size``, ``random_shape_seed``; :mod:`mgn.objects.random_shapes`).
- ``tote``: :class:`mgn.objects.ToteSpec` fields. ``gripper``:
  :class:`mgn.hardware.ParallelJawGripper` fields. ``cup``: :class:`mgn.hardware.SuctionCup`
  fields. ``drop``: :class:`mgn.scene.DropOptions` fields.
- ``camera``: ``rig`` (``mgn``: the 37-view MetaGraspNet rig, drawn per scene; ``hemisphere``:
  every (radius, tilt, azimuth) of ``hemisphere``; ``poses``: your own cameras, ``poses`` = a
  list of 4x4 ``X_WC`` or ``{eye, target, up}``), ``views`` (indices of the rig's views to
  keep, e.g. ``[0, 5, 17]``; null = all), ``intrinsics`` (a preset: ``mgn_synthetic``,
  ``zivid2_plus_m130``, ``photoneo_phoxi_m``, ``realsense_d435``, ... — or your own
  ``{width, height, fx, fy, cx, cy, distortion}``; docs/cameras.md), ``resolution_scale`` (same
  field of view, scaled pixel count), depth ``sensor`` preset, ``randomize`` (per-view light and
  tote/floor colour randomisation).
- ``labels``: which labels to make (``suction``, ``paralleljaw``, ``pj_physics``, ``layout``,
  ``scene_grasps``).
- ``object_labels``: sizes of the per-object labels: ``suction_points``, ``pj_points`` (MGN:
  5000 each), ``pj_grasps`` (parallel-jaw grasps stored per object, an evenly strided subset of
  what the sampler finds, default 300; null stores them all, which can be 10^5 per object),
  ``physics_grasps`` (cap on the stored grasps per object given a physics score, an
  evenly strided subset; null, the default, scores every stored grasp; the capped count is
  recorded in each object's label metadata and in ``dataset.json`` ``physics_scores``),
  ``physics_grid`` (S of the S x S friction x mass grid, MGN 10), ``physics_search``
  (``staircase``: walk each grasp's monotone success boundary with checks and fall back to the
  full grid where they fail, the default; ``full``: simulate all S x S trials),
  ``physics_checks`` (extra inferred cells the staircase simulates to catch non-monotone grids:
  more checks, more trials, closer to the full grid; null, the default: 0 with the calibration,
  which catches such objects as a whole, 6 without; benchmarks/README.md measures the trade),
  ``physics_calibration`` (staircase only: the first N scored grasps of each object are simulated
  on the full grid and keep its exact scores; the staircase searches replayed on them decide
  which one scores the object's other grasps: the cheapest whose score error is within
  ``physics_tolerance``, else the full grid; 0 = off; default 32;
  docs/decisions/0032-object-labels-at-the-defaults.md), ``physics_calibration_min`` (the
  calibration's first stage: it stops after this many grasps when the plain staircase is within
  ``physics_tolerance`` on them, else goes on to ``physics_calibration``; default 12; 0 = one
  stage; docs/decisions/0071-two-stage-calibration.md), ``physics_tolerance`` (the mean
  absolute score error allowed, its 95 % bound on the calibration grasps; default 0.005, the
  simulation's own noise band; 0 = exact agreement on every calibration grasp),
  ``suction_model``, ``seed``.
- ``split``: the unseen-object split (docs/testsets.md): ``name`` (``all``: every category;
  ``train``: the ``unseen`` categories never appear; ``test``: they appear, at least one per
  scene when the composition allows) and ``unseen`` (``novel`` = the objects tagged ``novel``,
  or a list of object names / category ids).
- ``io``: how the files are written: ``archival`` (false: every array exactly as the models make
  it; true: the compact archival mode of docs/format.md — sensor depth on a 1/64 cm grid (at
  most 0.078 mm off) in an LZMA zip entry (``np.load`` reads it), grasp poses rounded
  (< 0.001°, 0.005 mm), the RGB PNG at libdeflate level 9; MetaGraspNet's scripts still read
  every file; ~0.8x the bytes, ~1.6x the write time).
- ``output``: ``formats``, the layouts ``mgn generate`` writes, a list of ``mgn`` (the scene
  folders, always written: the other layouts are made from them), ``bop`` (the BOP layout in
  ``DIR/bop/``, as ``mgn export bop`` writes it) and ``graspnet`` (grasp files in
  ``DIR/graspnet/``, as ``mgn export graspnet`` writes them); default ``[mgn]``. The exports
  are written per scene, right after the scene (docs/format.md, "Exports while generating").
- ``render``: how the RGB images are made (:class:`mgn.render.settings.RenderSettings`):
  ``engine`` (``raster``: the fast OpenGL preview; ``path``: the physically based path tracer),
  ``spp``, ``denoise`` (Intel Open Image Denoise through the optional ``pyoidn`` package; without
  it ``spp_without_denoiser`` samples are traced and a warning names the package),
  ``denoise_quality``, ``denoise_guides`` (``smoothed`` | ``raw`` | ``albedo`` | ``none``: the
  guide images the denoiser gets), ``denoise_resolution`` (``half`` | ``full``: the denoiser
  on 2 x 2 pixel blocks, the full-size detail restored from the albedo, or on every pixel),
  ``adaptive_samples`` / ``adaptive_max`` (adaptive sampling:
  extra samples where the first pass is noisy), ``max_bounces``, ``clamp``, ``exposure`` (EV),
  ``tone`` (``filmic`` | ``linear``),
  ``aperture_radius`` (m, defocus), ``shot_noise`` / ``read_noise`` (sensor noise) and
  ``randomize`` (path engine, when ``camera.randomize`` is on: switches ``lights``,
  ``environment``, ``materials`` (tote / floor), ``exposure`` and their ranges). Labels do not
  depend on the engine.
- ``selection``: a difficulty-balanced test set (docs/testsets.md): ``quota`` (views wanted per
  difficulty level, e.g. ``{1: 20, 2: 20, 3: 20, 4: 20, 5: 20}``; null = no selection),
  ``batch_scenes`` (scenes generated per batch), ``max_scenes`` (give up after this many
  scenes), ``prune_rejected`` (delete the files of the views not selected).
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import yaml

from mgn.base.yaml_file import read_yaml
from mgn.errors import InvalidArgumentError, MgnError
from mgn.hardware import ParallelJawGripper, SuctionCup
from mgn.objects import ToteSpec, make_tote
from mgn.pj.labels import DEFAULT_STORED_GRASPS
from mgn.pj.physics import CALIBRATION_TOLERANCE, ShakeScorer, default_staircase_checks
from mgn.render.path import FilmOptions, PathTraceOptions
from mgn.render.settings import RandomizeSettings, RenderSettings
from mgn.scene.cameras import Intrinsics, look_at
from mgn.scene.lens import lens_for
from mgn.scene.scene import DropOptions

__all__ = [
    "OUTPUT_FORMATS",
    "CameraConfig",
    "Config",
    "ConfigError",
    "HemisphereConfig",
    "IntrinsicsConfig",
    "IoConfig",
    "LabelsConfig",
    "ObjectLabelsConfig",
    "ObjectsConfig",
    "OutputConfig",
    "SelectionConfig",
    "SplitConfig",
    "default_config",
    "dump_config",
    "load_config",
]

INTRINSICS_PRESETS = (
    "mgn_synthetic",
    "zivid_two_like",
    "zivid2_plus_m130",
    "photoneo_phoxi_m",
    "realsense_d435",
)
SENSOR_PRESETS = ("ideal", "structured-light", "tof")
RIGS = ("mgn", "hemisphere", "poses")
SEAL_MODELS = ("spring", "strain", "smoothness")
#: Views of the MetaGraspNet rig.
MGN_NUM_VIEWS = 37
SPLIT_NAMES = ("all", "train", "test")
#: The layouts ``mgn generate`` can write (``output.formats``).
OUTPUT_FORMATS = ("mgn", "bop", "graspnet")
#: Difficulty levels of a view (paper Table IV, :mod:`mgn.view_labels.layout`).
DIFFICULTY_LEVELS = (1, 2, 3, 4, 5)


#: The random stream of a scene's object count drawn from an ``objects.count`` range ("coun").
_COUNT_STREAM = 0x636F756E


class ConfigError(InvalidArgumentError):
    """A configuration value or key is invalid (a ValueError); the message names the key."""


# ---------------------------------------------------------------------------------- validators

Check = Callable[[Any, str], Any]


def _fail(key: str, value: Any, expected: str) -> ConfigError:
    return ConfigError(f"config key '{key}': expected {expected}, got {value!r}")


def _bool(value: Any, key: str) -> bool:
    if not isinstance(value, bool):
        raise _fail(key, value, "true or false")
    return value


def _int(lo: int | None = None) -> Check:
    def check(value: Any, key: str) -> int:
        ok = isinstance(value, int) and not isinstance(value, bool)
        if not ok or (lo is not None and value < lo):
            raise _fail(key, value, "an integer" + (f" >= {lo}" if lo is not None else ""))
        return int(value)

    return check


_COUNT_EXPECTED = "an integer >= 1, or [min, max]: integers with 1 <= min <= max"


def _count(value: Any, key: str) -> int | tuple[int, int]:
    """``objects.count``: a whole number >= 1, or a [min, max] range of them."""

    def whole(v: Any) -> bool:
        return isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_))

    if whole(value) and int(value) >= 1:
        return int(value)
    if isinstance(value, (list, tuple)) and len(value) == 2 and all(whole(v) for v in value):
        lo, hi = int(value[0]), int(value[1])
        if 1 <= lo <= hi:
            return (lo, hi)
    raise _fail(key, list(value) if isinstance(value, tuple) else value, _COUNT_EXPECTED)


def _num(lo: float | None = None, *, strict: bool = True) -> Check:
    def check(value: Any, key: str) -> float:
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        ok = ok and math.isfinite(float(value))
        if ok and lo is not None:
            ok = float(value) > lo if strict else float(value) >= lo
        if not ok:
            bound = "" if lo is None else f" {'>' if strict else '>='} {lo:g}"
            raise _fail(key, value, f"a finite number{bound}")
        return float(value)

    return check


def _score_error(value: Any, key: str) -> float:
    v: float = _num(0.0, strict=False)(value, key)
    if v >= 1.0:
        raise _fail(key, value, "a score error in [0, 1)")
    return v


def _choice(*options: str) -> Check:
    def check(value: Any, key: str) -> str:
        if value not in options:
            raise _fail(key, value, "one of " + ", ".join(repr(o) for o in options))
        return str(value)

    return check


def _optional(inner: Check) -> Check:
    def check(value: Any, key: str) -> Any:
        return None if value is None else inner(value, key)

    return check


def _name(value: Any, key: str) -> str | int:
    if isinstance(value, bool) or not isinstance(value, (str, int)) or value == "":
        raise _fail(key, value, "an object name or category id")
    return value


def _path(value: Any, key: str) -> str:
    if not isinstance(value, str) or not value:
        raise _fail(key, value, "a file path")
    return value


def _list(inner: Check, *, length: int | None = None, nonempty: bool = True) -> Check:
    def check(value: Any, key: str) -> tuple[Any, ...]:
        if not isinstance(value, (list, tuple)):
            raise _fail(key, value, "a list" if length is None else f"a list of {length} values")
        if length is not None and len(value) != length:
            raise _fail(key, value, f"a list of {length} values")
        if nonempty and len(value) == 0:
            raise _fail(key, value, "a non-empty list")
        return tuple(inner(v, f"{key}[{i}]") for i, v in enumerate(value))

    return check


def _mapping(data: Any, key: str) -> dict[str, Any]:
    if data is None:
        return {}
    if not isinstance(data, Mapping):
        raise _fail(key or "<top level>", data, "a mapping of keys to values")
    return dict(data)


def _check_keys(data: Mapping[str, Any], valid: list[str], key: str) -> None:
    unknown = sorted(str(k) for k in set(data) - set(valid))
    if unknown:
        where = f"'{key}.{unknown[0]}'" if key else f"'{unknown[0]}'"
        raise ConfigError(
            f"config: unknown key {where}"
            + (f" (and {unknown[1:]})" if len(unknown) > 1 else "")
            + f"; valid keys{' of ' + repr(key) if key else ''}: {', '.join(sorted(valid))}"
        )


class _Section:
    """A config section: fields validated by ``_CHECKS`` (field name -> validator)."""

    _CHECKS: ClassVar[dict[str, Check]] = {}

    @classmethod
    def from_dict(cls, data: Any, key: str = "") -> Any:
        d = _mapping(data, key)
        names = [f.name for f in dataclasses.fields(cls)]  # type: ignore[arg-type]
        _check_keys(d, names, key)
        kwargs = {}
        for k, v in d.items():
            sub = f"{key}.{k}" if key else k
            kwargs[k] = cls._CHECKS[k](v, sub)
        try:
            return cls(**kwargs)
        except ConfigError:
            raise
        except (ValueError, TypeError) as e:
            raise ConfigError(f"config key '{key}': {e}") from e

    def to_dict(self) -> dict[str, Any]:
        return {f.name: _plain(getattr(self, f.name)) for f in dataclasses.fields(self)}  # type: ignore[arg-type]


def _plain(value: Any) -> Any:
    if isinstance(value, _Section):
        return value.to_dict()
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        if hasattr(value, "to_dict"):
            return value.to_dict()
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    return value


# ------------------------------------------------------------------------------------ sections


@dataclass(frozen=True)
class ObjectsConfig(_Section):
    """Which objects fall into each scene (see the module doc).

    Attributes:
        names: explicit objects (names or ids; repeat for copies), or None.
        categories: categories to use, each with ``copies`` copies, or None.
        count: total objects per scene: a whole number >= 1, or ``(min, max)`` (whole numbers,
            1 <= min <= max) for bins at several fill levels: each scene draws its count
            uniformly in min..max (both included) from a random stream of its own, derived
            from the scene seed (:meth:`scene_count`); or None. With neither ``names`` nor
            ``categories`` it defaults to 20 objects from randomly drawn categories with
            ``copies`` copies each. With ``categories`` the categories are cycled with their
            drawn copies until the scene's count is reached; ``refill`` drops the same objects
            again, so a scene keeps its drawn count; ``random_shapes`` join the catalogue the
            objects are drawn from and do not change the count. The count a scene drew is
            ``stats.num_dropped`` of its ``scene.json``.
        copies: (min, max) copies per chosen category (MGN: 2-5).
        user_objects: user-object YAML files added to the catalogue.
        refill: when objects leave the tote during the drop, drop the scene again (the same
            objects, a seed derived from the scene seed and the attempt) until every asked
            object stays in, at most ``refill_attempts`` drops; the scene with the most objects
            in the tote is kept (default true: a scene holds the objects asked for; the rare
            shortfall left is reported per scene). Off, the objects that left are removed (and
            reported).
        refill_attempts: drops at most per scene with ``refill`` (>= 1, default 5).
        random_shapes: seeded random procedural objects added to the catalogue as categories
            of their own (:mod:`mgn.objects.random_shapes`; >= 0, default 0 = none). A scene
            draws its categories from the whole catalogue, so with the 30 built-in objects,
            ``random_shapes: 30`` makes about half of a pile random shapes. Their
            parallel-jaw labels are not computed (``pj_skipped`` in their labels); every other
            label is.
        random_shape_size: (min, max) largest extent of a random shape, metres, drawn
            uniformly (0.01 <= min <= max <= 1; default 0.02-0.25).
        random_shape_seed: seed of the random shapes (>= 0, default 0); the same seed, count
            and size range give the same shapes, whatever the dataset seed.
        random_shape_dark: probability that a random shape is black or dark grey (0-1,
            default 0.25); it changes colours only, never shapes, densities or piles.
    """

    names: tuple[str | int, ...] | None = None
    categories: tuple[str | int, ...] | None = None
    count: int | tuple[int, int] | None = None
    copies: tuple[int, int] = (2, 5)
    user_objects: tuple[str, ...] = ()
    refill: bool = True
    refill_attempts: int = 5
    random_shapes: int = 0
    random_shape_size: tuple[float, float] = (0.02, 0.25)
    random_shape_seed: int = 0
    random_shape_dark: float = 0.25

    _CHECKS: ClassVar[dict[str, Check]] = {
        "names": _optional(_list(_name)),
        "categories": _optional(_list(_name)),
        "count": _optional(_count),
        "copies": _list(_int(1), length=2),
        "user_objects": _list(_path, nonempty=False),
        "refill": _bool,
        "refill_attempts": _int(1),
        "random_shapes": _int(0),
        "random_shape_size": _list(_num(0.0), length=2),
        "random_shape_seed": _int(0),
        "random_shape_dark": _num(0.0, strict=False),
    }

    #: Objects per scene when nothing is chosen.
    DEFAULT_COUNT = 20

    def __post_init__(self) -> None:
        if self.count is not None:
            object.__setattr__(self, "count", _count(self.count, "objects.count"))
        if self.names is not None and (self.categories is not None or self.count is not None):
            raise ConfigError(
                "config key 'objects': give 'names', or 'categories' and/or 'count', not both "
                f"(got names={list(self.names)!r}, categories={self.categories!r}, "
                f"count={self.count!r})"
            )
        lo, hi = self.copies
        if not 1 <= lo <= hi:
            raise _fail("objects.copies", list(self.copies), "[min, max] with 1 <= min <= max")
        smin, smax = (float(x) for x in self.random_shape_size)
        if not 0.01 <= smin <= smax <= 1.0:
            raise _fail(
                "objects.random_shape_size",
                list(self.random_shape_size),
                "[min, max] in metres with 0.01 <= min <= max <= 1",
            )
        if isinstance(self.random_shapes, bool) or int(self.random_shapes) < 0:
            raise _fail("objects.random_shapes", self.random_shapes, "an integer >= 0")
        if not 0.0 <= float(self.random_shape_dark) <= 1.0:
            raise _fail("objects.random_shape_dark", self.random_shape_dark, "a number in [0, 1]")

    @property
    def count_range(self) -> tuple[int, int] | None:
        """(min, max) objects per scene of ``count`` ((n, n) for a whole number; the default
        count when nothing is chosen); None when ``names`` or ``categories`` alone decide."""
        if self.names is not None:
            return None
        if self.count is None:
            return None if self.categories is not None else (self.DEFAULT_COUNT,) * 2
        if isinstance(self.count, tuple):
            return (int(self.count[0]), int(self.count[1]))
        return (int(self.count), int(self.count))

    def scene_count(self, seed: int) -> int | None:
        """The object count of the scene with scene seed ``seed``: ``count`` itself when it is a
        whole number (the default count when nothing is chosen), else drawn uniformly in
        [min, max] from a random stream of its own derived from ``seed`` (the other draws of
        the scene do not change); None when ``names`` or ``categories`` alone decide."""
        if self.names is not None or (self.count is None and self.categories is not None):
            return None
        if not isinstance(self.count, tuple):
            return self.DEFAULT_COUNT if self.count is None else int(self.count)
        lo, hi = self.count
        rng = np.random.default_rng([int(seed), _COUNT_STREAM])
        return int(rng.integers(int(lo), int(hi) + 1))

    def compose_kwargs(self, seed: int | None = None) -> dict[str, Any]:
        """Keyword arguments of :func:`mgn.scene.compose_objects` (without seed/catalogue) for
        the scene with scene seed ``seed`` (needed with a ``count`` range; see
        :meth:`scene_count`).

        Raises:
            InvalidArgumentError: ``count`` is a range and ``seed`` is None.
        """
        if self.names is not None:
            return {"names": list(self.names)}
        if isinstance(self.count, tuple) and seed is None:
            raise InvalidArgumentError(
                f"ObjectsConfig.compose_kwargs: objects.count is the range {list(self.count)}; "
                "give the scene seed it is drawn from"
            )
        count = self.scene_count(0 if seed is None else seed)
        cats = None if self.categories is None else list(self.categories)
        return {"categories": cats, "count": count, "copies": tuple(self.copies)}


@dataclass(frozen=True)
class HemisphereConfig(_Section):
    """A hemisphere rig: every (radius m, tilt from vertical rad, azimuth rad), radius-major."""

    radii: tuple[float, ...] = (0.75, 1.0)
    tilts: tuple[float, ...] = (0.3, 0.6)
    azimuths: tuple[float, ...] = (0.0, math.pi / 2, math.pi, 3 * math.pi / 2)

    _CHECKS: ClassVar[dict[str, Check]] = {
        "radii": _list(_num(0.0)),
        "tilts": _list(_num(0.0, strict=False)),
        "azimuths": _list(_num()),
    }

    @property
    def num_views(self) -> int:
        return len(self.radii) * len(self.tilts) * len(self.azimuths)


def _distortion(value: Any, key: str) -> tuple[float, ...]:
    coeffs: tuple[float, ...] = _list(_num(), nonempty=False)(value, key)
    if len(coeffs) not in (0, 4, 5, 8, 12, 14):
        raise _fail(
            key,
            value,
            "OpenCV distortion coefficients [k1, k2, p1, p2(, k3, ...)]: 4, 5, 8, 12 or 14 numbers",
        )
    return coeffs


@dataclass(frozen=True)
class IntrinsicsConfig(_Section):
    """User camera intrinsics (pixels; OpenCV pinhole, principal point in continuous image
    coordinates, the image centre is (width/2, height/2)).

    ``distortion`` (OpenCV order k1, k2, p1, p2, k3, ...) describes the real lens: images, depth
    and every pixel label are those of that lens (rendered as a covering pinhole and resampled,
    :mod:`mgn.scene.lens`), and each view's ``camera_params.json`` records the coefficients.
    Leave it out (or all zeros) for rectified images, which is what Zivid, Photoneo and
    RealSense deliver with their point clouds.
    """

    width: int = 0
    height: int = 0
    fx: float = 0.0
    fy: float = 0.0
    cx: float = 0.0
    cy: float = 0.0
    distortion: tuple[float, ...] = ()

    _CHECKS: ClassVar[dict[str, Check]] = {
        "width": _int(1),
        "height": _int(1),
        "fx": _num(0.0),
        "fy": _num(0.0),
        "cx": _num(),
        "cy": _num(),
        "distortion": _distortion,
    }

    @classmethod
    def from_dict(cls, data: Any, key: str = "") -> IntrinsicsConfig:
        d = _mapping(data, key)
        missing = [k for k in ("width", "height", "fx", "fy", "cx", "cy") if k not in d]
        if missing:
            raise ConfigError(
                f"config key '{key}': missing {', '.join(missing)}; expected a preset name "
                f"({', '.join(INTRINSICS_PRESETS)}) or width, height, fx, fy, cx, cy (px) and "
                "optionally distortion"
            )
        out: IntrinsicsConfig = super().from_dict(d, key)
        if out.distortion:
            try:  # the lens must be invertible over the image (built once, cached)
                lens_for(
                    Intrinsics(
                        out.width, out.height, out.fx, out.fy, out.cx, out.cy, out.distortion
                    )
                )
            except InvalidArgumentError as e:
                raise ConfigError(f"config key '{key}.distortion': {e}") from e
        return out


def _intrinsics(value: Any, key: str) -> str | IntrinsicsConfig:
    if isinstance(value, Mapping):
        return IntrinsicsConfig.from_dict(value, key)
    if isinstance(value, IntrinsicsConfig):
        return value
    if isinstance(value, str):
        preset: str = _choice(*INTRINSICS_PRESETS)(value, key)
        return preset
    raise _fail(
        key,
        value,
        f"a preset ({', '.join(INTRINSICS_PRESETS)}) or a mapping with width, "
        "height, fx, fy, cx, cy",
    )


def _camera_pose(value: Any, key: str) -> tuple[tuple[float, ...], ...]:
    """A camera pose X_WC: a 4x4 matrix (rows), or {eye, target, up} (look-at), world = tote."""

    if isinstance(value, Mapping):
        _check_keys(value, ["eye", "target", "up"], key)
        if "eye" not in value:
            raise _fail(key, dict(value), "a mapping with 'eye' (and 'target', 'up')")
        eye = _list(_num(), length=3)(value["eye"], f"{key}.eye")
        target = _list(_num(), length=3)(value.get("target", [0.0, 0.0, 0.0]), f"{key}.target")
        up = _list(_num(), length=3)(value.get("up", [0.0, 0.0, 1.0]), f"{key}.up")

        try:
            X = look_at(eye, target, up)
        except ValueError as e:
            raise ConfigError(f"config key '{key}': {e}") from e
    else:
        rows = _list(_list(_num(), length=4), length=4)(value, key)
        X = np.asarray(rows, np.float64)
        R = X[:3, :3]
        if not (
            np.allclose(R.T @ R, np.eye(3), atol=1e-6)
            and np.linalg.det(R) > 0
            and np.allclose(X[3], [0, 0, 0, 1])
        ):
            raise _fail(
                key,
                value,
                "a rigid 4x4 pose (rotation block orthonormal, det +1, last row [0, 0, 0, 1])",
            )
    return tuple(tuple(float(x) for x in row) for row in np.asarray(X))


@dataclass(frozen=True)
class CameraConfig(_Section):
    """Cameras and sensor (see the module doc).

    ``intrinsics`` is a preset name (:data:`INTRINSICS_PRESETS`, docs/cameras.md) or an
    :class:`IntrinsicsConfig` mapping. ``rig: poses`` takes the cameras from ``poses``: each a
    4x4 camera pose ``X_WC`` (OpenCV frame: x right, y down, z forward) in the tote frame, or
    ``{eye, target, up}`` in metres.
    """

    rig: str = "mgn"
    views: tuple[int, ...] | None = None
    hemisphere: HemisphereConfig = field(default_factory=HemisphereConfig)
    poses: tuple[tuple[tuple[float, ...], ...], ...] = ()
    intrinsics: str | IntrinsicsConfig = "mgn_synthetic"
    resolution_scale: float = 1.0
    sensor: str = "structured-light"
    randomize: bool = True

    _CHECKS: ClassVar[dict[str, Check]] = {
        "rig": _choice(*RIGS),
        "views": _optional(_list(_int(0))),
        "hemisphere": HemisphereConfig.from_dict,
        "poses": _list(_camera_pose, nonempty=False),
        "intrinsics": _intrinsics,
        "resolution_scale": _num(0.0),
        "sensor": _choice(*SENSOR_PRESETS),
        "randomize": _bool,
    }

    def __post_init__(self) -> None:
        if self.rig == "poses" and not self.poses:
            raise _fail("camera.poses", [], "at least one camera pose with rig: poses")
        if self.rig != "poses" and self.poses:
            raise _fail("camera.rig", self.rig, "'poses' when camera.poses is given")
        n = self.num_rig_views
        if self.views is not None:
            bad = [v for v in self.views if not 0 <= v < n]
            if bad:
                raise _fail("camera.views", list(self.views), f"view indices in 0..{n - 1}")
            if len(set(self.views)) != len(self.views):
                raise _fail("camera.views", list(self.views), "distinct view indices")

    @property
    def num_rig_views(self) -> int:
        if self.rig == "poses":
            return len(self.poses)
        return MGN_NUM_VIEWS if self.rig == "mgn" else self.hemisphere.num_views

    @property
    def view_indices(self) -> tuple[int, ...]:
        """The rig's views to render, in order."""
        return tuple(range(self.num_rig_views)) if self.views is None else self.views


@dataclass(frozen=True)
class LabelsConfig(_Section):
    """Which labels to make."""

    suction: bool = True
    paralleljaw: bool = True
    pj_physics: bool = True
    layout: bool = True
    scene_grasps: bool = True

    _CHECKS = dict.fromkeys(
        ("suction", "paralleljaw", "pj_physics", "layout", "scene_grasps"), _bool
    )


def _physics_grasps(value: Any, key: str) -> int | None:
    if value is None:
        return None
    ok = isinstance(value, int) and not isinstance(value, bool) and value >= 1
    if not ok:
        raise _fail(
            key,
            value,
            "null (every grasp is shaken) or an integer >= 1 (grasps shaken per object); "
            "labels.pj_physics: false switches the physics scores off",
        )
    return int(value)


@dataclass(frozen=True)
class ObjectLabelsConfig(_Section):
    """Sizes of the per-object labels (computed once per object and cached)."""

    suction_points: int = 5000
    pj_points: int = 5000
    pj_grasps: int | None = DEFAULT_STORED_GRASPS
    physics_grasps: int | None = None
    physics_grid: int = 10
    physics_search: str = "staircase"
    physics_checks: int | None = None
    physics_calibration: int = ShakeScorer.calibration_grasps
    physics_calibration_min: int = ShakeScorer.calibration_min_grasps
    physics_tolerance: float = CALIBRATION_TOLERANCE
    suction_model: str = "spring"
    seed: int = 0

    @property
    def staircase_checks(self) -> int:
        """``physics_checks``, or when null its default for ``physics_calibration``
        (:func:`mgn.pj.physics.default_staircase_checks`: 0 with the calibration, 6 without)."""
        if self.physics_checks is not None:
            return self.physics_checks
        return default_staircase_checks(self.physics_calibration)

    _CHECKS: ClassVar[dict[str, Check]] = {
        "suction_points": _int(1),
        "pj_points": _int(1),
        "pj_grasps": _optional(_int(1)),
        "physics_grasps": _physics_grasps,
        "physics_grid": _int(1),
        "physics_search": _choice("staircase", "full"),
        "physics_checks": _optional(_int(0)),
        "physics_calibration": _int(0),
        "physics_calibration_min": _int(0),
        "physics_tolerance": _score_error,
        "suction_model": _choice(*SEAL_MODELS),
        "seed": _int(0),
    }


def _unseen(value: Any, key: str) -> str | tuple[str | int, ...]:
    if value == "novel":
        return "novel"
    if isinstance(value, str):
        raise _fail(key, value, "'novel' or a list of object names / category ids")
    names: tuple[str | int, ...] = _list(_name)(value, key)
    if len(set(names)) != len(names):
        raise _fail(key, list(value), "distinct object names")
    return names


@dataclass(frozen=True)
class SplitConfig(_Section):
    """The unseen-object split (see the module doc and docs/testsets.md).

    Attributes:
        name: ``all`` (no split), ``train`` (unseen categories never appear) or ``test``
            (unseen categories appear: each scene gets at least one when the pool allows).
        unseen: ``"novel"`` (the objects tagged ``novel``) or object names / category ids.
    """

    name: str = "all"
    unseen: str | tuple[str | int, ...] = "novel"

    _CHECKS: ClassVar[dict[str, Check]] = {"name": _choice(*SPLIT_NAMES), "unseen": _unseen}


def _quota(value: Any, key: str) -> tuple[int, ...] | None:
    if value is None:
        return None
    if not isinstance(value, Mapping) or not value:
        raise _fail(key, value, "a mapping of difficulty levels 1..5 to view counts")
    counts = [0] * len(DIFFICULTY_LEVELS)
    for level, n in value.items():
        try:
            lv = int(level) if not isinstance(level, bool) else -1
        except (TypeError, ValueError):
            lv = -1
        if lv not in DIFFICULTY_LEVELS or (isinstance(level, str) and level.strip() != str(lv)):
            raise _fail(f"{key}.{level}", level, "a difficulty level 1..5")
        counts[lv - 1] = _int(0)(n, f"{key}.{lv}")
    if sum(counts) == 0:
        raise _fail(key, dict(value), "at least one level with a quota >= 1")
    return tuple(counts)


@dataclass(frozen=True)
class SelectionConfig(_Section):
    """A difficulty-balanced test set (see the module doc and docs/testsets.md).

    Attributes:
        quota: views wanted per difficulty level (index 0 = level 1), or None (no selection).
            In YAML/JSON a mapping ``{1: n1, ..., 5: n5}``; missing levels get 0.
        batch_scenes: scenes per batch (the composition of a batch depends on the quotas left
            after the previous batches only).
        max_scenes: stop with an error once this many scenes were generated without meeting
            every quota (a resumed run may raise it).
        prune_rejected: delete the files of the views that were not selected.
    """

    quota: tuple[int, ...] | None = None
    batch_scenes: int = 4
    max_scenes: int = 100
    prune_rejected: bool = False

    _CHECKS: ClassVar[dict[str, Check]] = {
        "quota": _quota,
        "batch_scenes": _int(1),
        "max_scenes": _int(1),
        "prune_rejected": _bool,
    }

    def __post_init__(self) -> None:
        if self.quota is not None and (
            len(self.quota) != len(DIFFICULTY_LEVELS) or min(self.quota) < 0
        ):
            raise _fail("selection.quota", self.quota, "5 view counts >= 0 (levels 1..5)")

    @property
    def quota_dict(self) -> dict[str, int] | None:
        """``{"1": n1, ..., "5": n5}`` (the dataset.json form), or None."""
        if self.quota is None:
            return None
        return {str(lv): int(n) for lv, n in zip(DIFFICULTY_LEVELS, self.quota, strict=True)}

    def to_dict(self) -> dict[str, Any]:
        d = super().to_dict()
        d["quota"] = self.quota_dict
        return d


def _external(cls: type, data: Any, key: str) -> Any:
    """Build one of mgn's own dataclasses (ToteSpec, gripper, cup, DropOptions) from a mapping."""
    d = _mapping(data, key)
    _check_keys(d, [f.name for f in dataclasses.fields(cls)], key)
    kwargs = {k: tuple(v) if isinstance(v, list) else v for k, v in d.items()}
    try:
        return cls(**kwargs)
    except ConfigError:
        raise
    except (ValueError, TypeError) as e:
        # The dataclasses name the field as "<Class>.<field>"; name the config key the same way.
        m = re.search(rf"{cls.__name__}\.(\w+)", str(e))
        sub = f"{key}.{m.group(1)}" if m and m.group(1) in kwargs else key
        raise ConfigError(f"config key '{sub}': {e}") from e


def _render(data: Any, key: str) -> RenderSettings:
    """The ``render`` section: RenderSettings with its nested ``randomize`` mapping. The values
    are also checked against the ranges of the tracer and the film (whatever the engine), so
    that a value the tracer refuses fails here, not in every scene."""
    d = _mapping(data, key)
    _check_keys(d, [f.name for f in dataclasses.fields(RenderSettings)], key)
    if "randomize" in d:
        d["randomize"] = _external(RandomizeSettings, d["randomize"], f"{key}.randomize")
    settings: RenderSettings = _external(RenderSettings, d, key)
    s = settings
    checks: tuple[tuple[str, Callable[[], Any]], ...] = (
        ("spp", lambda: PathTraceOptions(spp=s.spp)),
        ("spp_without_denoiser", lambda: PathTraceOptions(spp=s.spp_without_denoiser)),
        ("max_bounces", lambda: PathTraceOptions(max_bounces=s.max_bounces)),
        ("clamp", lambda: PathTraceOptions(clamp=s.clamp)),
        ("aperture_radius", lambda: PathTraceOptions(aperture_radius=s.aperture_radius)),
        ("adaptive_samples", lambda: PathTraceOptions(adaptive_samples=s.adaptive_samples)),
        ("adaptive_max", lambda: PathTraceOptions(adaptive_max=s.adaptive_max)),
        ("exposure", lambda: FilmOptions(exposure=s.exposure)),
        ("shot_noise", lambda: FilmOptions(shot_noise=s.shot_noise)),
        ("read_noise", lambda: FilmOptions(read_noise=s.read_noise)),
    )
    for name, build in checks:
        try:
            build()
        except InvalidArgumentError as e:
            raise ConfigError(f"config key '{key}.{name}': {e}") from e
    return settings


@dataclass(frozen=True)
class IoConfig(_Section):
    """How the scene files are written (docs/format.md).

    Attributes:
        archival: the compact archival mode (lossy: the sensor depth rounded to
            :data:`mgn.io.scene_folder.ARCHIVAL_DEPTH_STEP_CM`, grasp poses to 2^-16 per rotation
            entry and 1/1024 cm; views through a lens also the ideal depth and ``com_heatmap``
            to 1/65535); false keeps every array bit for bit.
    """

    archival: bool = False

    _CHECKS: ClassVar[dict[str, Check]] = {"archival": _bool}


def _formats(value: Any, key: str) -> tuple[str, ...]:
    expected = (
        "a list of distinct layouts out of "
        + ", ".join(repr(f) for f in OUTPUT_FORMATS)
        + " that includes 'mgn' (the other layouts are made from the mgn scene folders)"
    )
    if not isinstance(value, (list, tuple)) or not value:
        raise _fail(key, value, expected)
    for i, v in enumerate(value):
        if v not in OUTPUT_FORMATS:
            raise _fail(f"{key}[{i}]", v, "one of " + ", ".join(repr(f) for f in OUTPUT_FORMATS))
    if len(set(value)) != len(value) or "mgn" not in value:
        raise _fail(key, value, expected)
    return tuple(str(v) for v in value)


@dataclass(frozen=True)
class OutputConfig(_Section):
    """Which layouts ``mgn generate`` writes (see the module doc).

    Attributes:
        formats: ``mgn`` (always) and any of ``bop`` (``DIR/bop/``, :func:`mgn.io.bop.export_bop`
            with its defaults) and ``graspnet`` (``DIR/graspnet/``,
            :func:`mgn.io.graspnet.export_graspnet` with its defaults), written per scene.
    """

    formats: tuple[str, ...] = ("mgn",)

    _CHECKS: ClassVar[dict[str, Check]] = {"formats": _formats}

    def __post_init__(self) -> None:
        _formats(self.formats, "output.formats")

    @property
    def exports(self) -> tuple[str, ...]:
        """The layouts besides ``mgn``, in :data:`OUTPUT_FORMATS` order."""
        return tuple(f for f in OUTPUT_FORMATS if f != "mgn" and f in self.formats)


@dataclass(frozen=True)
class Config(_Section):
    """The whole dataset configuration (see the module doc for the sections)."""

    objects: ObjectsConfig = field(default_factory=ObjectsConfig)
    tote: ToteSpec = field(default_factory=ToteSpec)
    gripper: ParallelJawGripper = field(default_factory=ParallelJawGripper)
    cup: SuctionCup = field(default_factory=SuctionCup)
    camera: CameraConfig = field(default_factory=CameraConfig)
    labels: LabelsConfig = field(default_factory=LabelsConfig)
    object_labels: ObjectLabelsConfig = field(default_factory=ObjectLabelsConfig)
    drop: DropOptions = field(default_factory=DropOptions)
    split: SplitConfig = field(default_factory=SplitConfig)
    selection: SelectionConfig = field(default_factory=SelectionConfig)
    render: RenderSettings = field(default_factory=RenderSettings)
    io: IoConfig = field(default_factory=IoConfig)
    output: OutputConfig = field(default_factory=OutputConfig)

    _CHECKS: ClassVar[dict[str, Check]] = {
        "objects": ObjectsConfig.from_dict,
        "tote": lambda v, k: _external(ToteSpec, v, k),
        "gripper": lambda v, k: _external(ParallelJawGripper, v, k),
        "cup": lambda v, k: _external(SuctionCup, v, k),
        "camera": CameraConfig.from_dict,
        "labels": LabelsConfig.from_dict,
        "object_labels": ObjectLabelsConfig.from_dict,
        "drop": lambda v, k: _external(DropOptions, v, k),
        "split": SplitConfig.from_dict,
        "selection": SelectionConfig.from_dict,
        "render": _render,
        "io": IoConfig.from_dict,
        "output": OutputConfig.from_dict,
    }

    @classmethod
    def from_dict(
        cls, data: Any, key: str = "", *, base_dir: str | os.PathLike[str] | None = None
    ) -> Config:
        """Build and validate from a mapping. Relative paths (user objects, gripper meshes) are
        resolved against ``base_dir`` when given.

        Raises:
            ConfigError: naming the key, the value and what was expected.
        """
        config: Config = super().from_dict(data, key)
        intr = config.camera.intrinsics
        if (
            "bop" in config.output.formats
            and isinstance(intr, IntrinsicsConfig)
            and any(c != 0.0 for c in intr.distortion)
        ):
            raise ConfigError(
                "config key 'output.formats': 'bop' needs pinhole views (BOP's cam_K has no "
                "lens distortion), but 'camera.intrinsics.distortion' is "
                f"{list(intr.distortion)}; leave 'bop' out or the distortion"
            )
        if base_dir is not None:
            config = config.resolved(base_dir)
        if config.tote.mesh is not None and (
            base_dir is not None or Path(config.tote.mesh).is_absolute()
        ):
            try:
                make_tote(config.tote)  # the file reads and fits the inner box
            except MgnError as e:
                raise ConfigError(f"config key 'tote.mesh': {e}") from e
        return config

    def resolved(self, base_dir: str | os.PathLike[str]) -> Config:
        """The same config with relative file paths made absolute against ``base_dir``."""
        base = Path(base_dir).resolve()

        def absolute(p: str | None) -> str | None:
            return None if p is None or Path(p).is_absolute() else os.fspath(base / p)

        objects = dataclasses.replace(
            self.objects, user_objects=tuple(absolute(p) or p for p in self.objects.user_objects)
        )
        tote = self.tote
        if tote.mesh is not None and not Path(tote.mesh).is_absolute():
            tote = dataclasses.replace(tote, mesh=absolute(tote.mesh))
        g = self.gripper
        meshes: dict[str, Any] = {
            f: absolute(getattr(g, f))
            for f in ("palm_mesh", "finger_left_mesh", "finger_right_mesh")
            if absolute(getattr(g, f)) is not None
        }
        return dataclasses.replace(
            self,
            objects=objects,
            tote=tote,
            gripper=dataclasses.replace(g, **meshes) if meshes else g,
        )

    def to_yaml(self) -> str:
        """YAML text of every key (see :func:`dump_config`)."""
        return dump_config(self)


_SECTION_DOCS = {
    "objects": "objects per scene: names | categories (copies each) and/or count (int, or "
    "[min, max]: each scene draws its own); user YAMLs",
    "tote": "the bin (m): mgn.objects.ToteSpec; mesh: your bin file (tote frame), the inner_* "
    "box inside its cavity; walls: false for a table top (a board of inner_length x inner_width); "
    "color is used only with camera.randomize: false (else drawn per view)",
    "gripper": "parallel-jaw gripper (m): mgn.hardware.ParallelJawGripper",
    "cup": "suction cup (m, bar; bending_k N, the hold and wrench scores' bending limit): "
    "mgn.hardware.SuctionCup",
    "camera": "rig: mgn (37 views) | hemisphere | poses; views: indices to keep (null = all); "
    "intrinsics: preset or {width, height, fx, fy, cx, cy, distortion}",
    "labels": "which labels to make",
    "object_labels": "per-object label sizes (cached per object)",
    "drop": "drop simulation (m, s): mgn.scene.DropOptions",
    "split": "unseen-object split: name all | train | test; unseen: novel | [names]",
    "selection": "difficulty-balanced test set: quota {level: views} (null = off), batches",
    "render": "RGB images: engine raster (fast preview) | path (path tracer), spp, denoise, "
    "film; randomize: per-view lights / environment / tote+floor materials / exposure",
    "io": "files: archival true = compact archival mode (sensor depth on a 1/64 cm grid as LZMA, "
    "grasp poses rounded; docs/format.md), false = every array exact",
    "output": "layouts written per scene: formats, a list of mgn (always) | bop (DIR/bop/, as "
    "mgn export bop) | graspnet (DIR/graspnet/, as mgn export graspnet)",
}


class _Dumper(yaml.SafeDumper):  # type: ignore[misc]  # PyYAML has no type information
    """Block style, except lists of scalars on one line ([0.2, 0.35, 0.6, 1.0])."""

    def represent_list(self, data: list[Any]) -> yaml.Node:
        flow = all(not isinstance(v, (list, dict)) for v in data)
        return self.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


_Dumper.add_representer(list, _Dumper.represent_list)


def dump_config(config: Config | None = None) -> str:
    """YAML text of ``config`` (default: the MGN defaults), one commented block per section.
    :func:`load_config` of this text gives back an equal config."""
    c = config if config is not None else Config()
    d = c.to_dict()
    out = ["# mgn dataset configuration (SI units). Defaults: MetaGraspNet.\n"]
    for name, value in d.items():
        out.append(f"\n# {_SECTION_DOCS[name]}\n")
        out.append(yaml.dump({name: value}, Dumper=_Dumper, sort_keys=False))
    return "".join(out)


def default_config() -> Config:
    """The MetaGraspNet defaults."""
    return Config()


def load_config(source: str | os.PathLike[str] | Mapping[str, Any] | None) -> Config:
    """A :class:`Config` from a YAML file, a mapping or None (defaults).

    Relative paths in a file are taken relative to the file's folder.

    Raises:
        IoError: the file does not exist or is a folder.
        ConfigError: a binary file, invalid YAML, an unknown key or a bad value (the message
            names the key).
    """
    if source is None:
        return Config()
    if isinstance(source, Mapping):
        return Config.from_dict(source)

    path = Path(source)
    try:
        data = read_yaml(path, "config file")
    except InvalidArgumentError as e:
        raise ConfigError(str(e)) from None
    try:
        return Config.from_dict(data, base_dir=path.parent)
    except ConfigError as e:
        raise ConfigError(f"{path}: {e}") from None
