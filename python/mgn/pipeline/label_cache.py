"""Object labels, computed once per object and cached on disk.

Each object's suction and parallel-jaw labels (:func:`mgn.suction.label_object`,
:func:`mgn.pj.label_object`) depend only on its geometry, its density, the cup or gripper and the
label parameters, never on a scene. They are computed once and kept in
``$MGN_CACHE_DIR/labels`` (default ``~/.cache/mgn/labels``, next to the convex-decomposition
cache of :func:`mgn.geometry.convex.cache_dir`), one file per object and label kind:

    labels/suction-<sha256>.npz    labels/pj-<sha256>.npz

The key hashes everything the labels depend on: the mesh (vertex and face bytes), the density,
the cup (or gripper, including the bytes of its mesh files), the label parameters, the mgn
version and :data:`CACHE_VERSION`. A changed input therefore never reads a stale entry, and an
unreadable entry is recomputed. The entries are written atomically and are byte-reproducible.

The dataset's ``models/<3-digit id>/`` folders are then written from these labels with the
existing writers (:func:`mgn.io.model_folder.write_model_folder`,
:func:`mgn.io.grasp_file.write_suction_labels`, :func:`~mgn.io.grasp_file.write_pj_labels`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import os
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mgn import _core
from mgn._core import __version__
from mgn.base.atomic import _io_error, atomic_write_bytes, disk_full_error, disk_full_message
from mgn.base.deterministic import npz_bytes
from mgn.errors import IoError
from mgn.geometry.convex import cache_dir
from mgn.geometry.mesh import SurfaceSamples, mass_properties, sample_surface
from mgn.io.grasp_file import write_pj_labels, write_suction_labels
from mgn.io.model_folder import write_model_folder, write_tote
from mgn.objects import ObjectSpec
from mgn.pipeline.config import Config
from mgn.pj.labels import PjLabels
from mgn.pj.labels import label_object as pj_label_object
from mgn.pj.physics import ShakeOptions, ShakeScorer, search_options
from mgn.suction.labels import SuctionLabels
from mgn.suction.labels import label_object as suction_label_object

__all__ = [
    "CACHE_VERSION",
    "ObjectLabels",
    "compute_object_labels",
    "label_cache_dir",
    "label_keys",
    "load_cached_labels",
    "object_labels",
    "save_cached_labels",
    "write_models",
]

#: Bump when the label layout or algorithms change, so old cache entries are not reused.
CACHE_VERSION = "object-labels-12"


@dataclass(frozen=True)
class ObjectLabels:
    """The labels of one object (object frame, metres).

    Attributes:
        name: object name; category_id: its category id.
        suction: suction labels, or None when ``labels.suction`` is off.
        paralleljaw: parallel-jaw labels (with the physics score when ``labels.pj_physics``),
            or None when ``labels.paralleljaw`` is off.
    """

    name: str
    category_id: int
    suction: SuctionLabels | None
    paralleljaw: PjLabels | None


def label_cache_dir() -> Path:
    """``$MGN_CACHE_DIR/labels`` or ``~/.cache/mgn/labels``."""

    return cache_dir().parent / "labels"


def _hash_file(h: Any, path: str | None) -> None:
    if path is None:
        return
    try:
        h.update(Path(path).read_bytes())
    except OSError:
        h.update(f"missing:{path}".encode())


def label_keys(spec: ObjectSpec, config: Config) -> dict[str, str]:
    """Cache keys ``{"suction": sha256, "paralleljaw": sha256}`` of the labels of ``spec``
    under ``config`` (only the kinds switched on)."""
    base = hashlib.sha256()
    base.update(f"{CACHE_VERSION}|{__version__}".encode())
    base.update(np.ascontiguousarray(spec.vertices, np.float64).tobytes())
    base.update(np.ascontiguousarray(spec.faces, np.int32).tobytes())
    base.update(repr(float(spec.density)).encode())
    ol = config.object_labels
    keys = {}
    if config.labels.suction:
        h = base.copy()
        params = {
            "cup": config.cup.to_dict(),
            "points": ol.suction_points,
            "model": ol.suction_model,
            "seed": ol.seed,
            "grid": ol.physics_grid,
        }
        h.update(json.dumps(params, sort_keys=True).encode())
        keys["suction"] = h.hexdigest()
    if config.labels.paralleljaw:
        h = base.copy()
        params = {
            "gripper": config.gripper.to_dict(),
            "points": ol.pj_points,
            "grasps": ol.pj_grasps,
            "seed": ol.seed,
            "physics": config.labels.pj_physics,
            "physics_grasps": ol.physics_grasps if config.labels.pj_physics else None,
            "physics_grid": ol.physics_grid if config.labels.pj_physics else None,
            "physics_search": ol.physics_search if config.labels.pj_physics else None,
            "physics_checks": (
                ol.staircase_checks
                if config.labels.pj_physics and ol.physics_search == "staircase"
                else None
            ),
            "physics_calibration": (
                ol.physics_calibration
                if config.labels.pj_physics and ol.physics_search == "staircase"
                else None
            ),
            "physics_calibration_min": (
                ol.physics_calibration_min
                if config.labels.pj_physics
                and ol.physics_search == "staircase"
                and 0 < ol.physics_calibration_min < ol.physics_calibration
                else None
            ),
            "physics_tolerance": (
                ol.physics_tolerance
                if config.labels.pj_physics
                and ol.physics_search == "staircase"
                and ol.physics_calibration > 0
                else None
            ),
        }
        h.update(json.dumps(params, sort_keys=True).encode())
        for f in ("palm_mesh", "finger_left_mesh", "finger_right_mesh"):
            _hash_file(h, getattr(config.gripper, f))
        keys["paralleljaw"] = h.hexdigest()
    return keys


#: CPU seconds of one shake trial of a single-hull object (Bullet, 1/400 s, MetaGraspNet's
#: schedule; a 2-core x86 machine measures 0.014-0.021 per trial with the sampling included,
#: docs/decisions/0055-shake-time-step-1-400.md), and of the other object labels per 1000
#: surface points (suction and parallel-jaw sampling); the estimate of
#: :func:`estimate_label_seconds`.
TRIAL_CPU_S = 0.017
SAMPLING_CPU_S_PER_1000_POINTS = 0.6
#: CPU per trial of a compound (several hulls, 40 solver iterations) over a single hull's: the
#: mean over 7 built-in compounds against 6 single-hull objects in one run, 1.3-2.9x per object
#: (docs/decisions/0068-adaptive-controller-gain.md); the high end of
#: :func:`estimate_label_seconds`.
COMPOUND_TRIAL_FACTOR = 2.4


def estimate_label_seconds(config: Config, num_objects: int, threads: int) -> tuple[float, float]:
    """A rough (low, high) wall-time range in seconds for computing the labels of
    ``num_objects`` objects under ``config`` on ``threads`` cores, before anything is known of
    their shapes: the low end assumes convex parts whose grasps the plain staircase search
    scores, the high end non-convex parts (several hulls, :data:`COMPOUND_TRIAL_FACTOR` times
    the cost per trial) that need the thorough search. Shown by ``mgn generate`` before it
    starts."""

    ol = config.object_labels
    points = (ol.suction_points if config.labels.suction else 0) + (
        ol.pj_points if config.labels.paralleljaw else 0
    )
    base = SAMPLING_CPU_S_PER_1000_POINTS * points / 1000.0
    trials_low = trials_high = 0.0
    if config.labels.paralleljaw and config.labels.pj_physics:
        cells = ol.physics_grid**2
        grasps = ol.pj_grasps if ol.pj_grasps is not None else 20_000
        if ol.physics_grasps is not None:
            grasps = min(grasps, ol.physics_grasps)
        if ol.physics_search == "full":
            trials_low = trials_high = grasps * cells
        else:
            k = min(ol.physics_calibration, grasps)
            k_low = min(ol.physics_calibration_min, k) if ol.physics_calibration_min > 0 else k
            trials_low = k_low * cells + (grasps - k_low) * max(6.0, 0.1 * cells)
            trials_high = k * cells + (grasps - k) * max(12.0, 0.5 * cells)
    per = max(1, threads)
    low = num_objects * (base + trials_low * TRIAL_CPU_S) / per
    high = num_objects * (base + COMPOUND_TRIAL_FACTOR * trials_high * TRIAL_CPU_S) / per
    return low, high


def shake_options(config: Config, num_threads: int = 0) -> ShakeOptions:
    """The shake-test options of ``config.object_labels`` (grid, search, checks)."""

    ol = config.object_labels
    return search_options(
        ol.physics_grid,
        ol.physics_search == "staircase",
        ol.physics_calibration,
        ol.physics_checks,
        num_threads,
    )


def compute_object_labels(
    spec: ObjectSpec, config: Config, num_threads: int = 0, progress: bool | None = None
) -> ObjectLabels:
    """Compute the labels of one object (no cache). Deterministic for the config's seed,
    whatever ``num_threads`` (0 = all cores). ``progress``: a per-grasp progress bar with an
    estimate of the time left for the physics scores (None: when stderr is a terminal)."""

    mesh = spec.to_mesh()
    props = mass_properties(mesh, spec.density)
    ol = config.object_labels
    # The even surface samples are drawn once when both kinds use the same count (same seed).
    shared: SurfaceSamples | None = None
    if config.labels.suction and config.labels.paralleljaw and ol.suction_points == ol.pj_points:
        shared = sample_surface(mesh, ol.suction_points, method="even", seed=ol.seed)
    suction = None
    if config.labels.suction:
        suction = suction_label_object(
            mesh,
            mass=props.mass,
            com=props.center_of_mass,
            inertia=props.inertia,
            cup=config.cup,
            model=ol.suction_model,  # type: ignore[arg-type]
            num_points=ol.suction_points,
            seed=ol.seed,
            num_threads=num_threads,
            samples=shared,
            grid=ol.physics_grid,
        )
    pj = None
    report = mesh.validate()
    if config.labels.paralleljaw and "random" in spec.tags:
        pj = _no_pj_labels(
            config,
            "random shape (objects.random_shapes): parallel-jaw labels "
            "are not computed for random shapes",
        )
    elif config.labels.paralleljaw and not report.is_watertight:
        pj = _no_pj_labels(
            config,
            f"open mesh ({report.num_boundary_edges} boundary edges, "
            "allow_open): the antipodal sampler needs a closed volume",
        )
    elif config.labels.paralleljaw:
        physics = None
        if config.labels.pj_physics:
            physics = ShakeScorer(
                density=spec.density,
                gripper=config.gripper,
                options=shake_options(config, num_threads),
                max_grasps=ol.physics_grasps,
                calibration_grasps=ol.physics_calibration,
                calibration_min_grasps=ol.physics_calibration_min,
                calibration_tolerance=ol.physics_tolerance,
                progress=progress,
            )
        pj = pj_label_object(
            mesh,
            mass=props.mass,
            com=props.center_of_mass,
            gripper=config.gripper,
            num_points=ol.pj_points,
            seed=ol.seed,
            num_threads=num_threads,
            physics=physics,
            samples=shared,
            max_grasps=ol.pj_grasps,
        )
    return ObjectLabels(spec.name, spec.category_id, suction, pj)


def _no_pj_labels(config: Config, reason: str) -> PjLabels:
    """Parallel-jaw labels with no grasp (an ``allow_open`` object), ``pj_skipped`` = reason."""

    f3 = np.zeros((0, 3), np.float32)
    f1 = np.zeros(0, np.float32)
    metadata = {
        "pj_gripper": config.gripper.to_dict(),
        "pj_seed": int(config.object_labels.seed),
        "pj_num_points": 0,
        "pj_num_accepted_probes": 0,
        "pj_num_colliding": 0,
        "pj_physics": "not run (no grasps)",
        "pj_skipped": reason,
        "mgn_version": _core.__version__,
    }
    return PjLabels(
        approach=f3,
        closing=f3.copy(),
        p1=f3.copy(),
        width=f1,
        quality_score=f1.copy(),
        score_wrench=f1.copy(),
        quality_score_simulation=f1.copy(),
        point_index=np.zeros(0, np.int64),
        point_score=f1.copy(),
        num_points=0,
        num_colliding=0,
        metadata=metadata,
    )


def _pack(labels: SuctionLabels | PjLabels) -> bytes:
    arrays: dict[str, Any] = {}
    scalars: dict[str, Any] = {}
    for f in dataclasses.fields(labels):
        value = getattr(labels, f.name)
        if isinstance(value, np.ndarray):
            arrays[f.name] = value
        else:
            scalars[f.name] = value
    meta = json.dumps(scalars).encode("utf-8")  # key order kept: the metadata is written as is
    return npz_bytes(**arrays, _scalars=np.frombuffer(meta, np.uint8))


def _unpack(path: Path, cls: type) -> Any | None:
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
        scalars = json.loads(bytes(data.pop("_scalars")).decode("utf-8"))
        return cls(**data, **scalars)
    except (OSError, KeyError, ValueError, TypeError):
        return None  # unreadable, partial or outdated entry: recompute


def _entry(kind: str, key: str) -> Path:
    prefix = "suction" if kind == "suction" else "pj"
    return label_cache_dir() / f"{prefix}-{key}.npz"


def load_cached_labels(spec: ObjectSpec, config: Config) -> ObjectLabels | None:
    """The cached labels of ``spec`` under ``config``, or None if any kind is missing."""
    keys = label_keys(spec, config)
    found: dict[str, Any] = {"suction": None, "paralleljaw": None}
    for kind, key in keys.items():
        path = _entry(kind, key)
        if not path.is_file():
            return None
        value = _unpack(path, SuctionLabels if kind == "suction" else PjLabels)
        if value is None:
            return None
        found[kind] = value
    return ObjectLabels(spec.name, spec.category_id, found["suction"], found["paralleljaw"])


def save_cached_labels(spec: ObjectSpec, config: Config, labels: ObjectLabels) -> None:
    """Store ``labels`` in the cache. An unwritable cache folder is not an error (the cache is
    an optimisation only)."""
    keys = label_keys(spec, config)
    for kind, key in keys.items():
        value = labels.suction if kind == "suction" else labels.paralleljaw
        if value is None:
            continue
        with contextlib.suppress(OSError):
            atomic_write_bytes(_entry(kind, key), _pack(value))


def object_labels(
    spec: ObjectSpec, config: Config, *, num_threads: int = 0, use_cache: bool = True
) -> ObjectLabels:
    """The labels of ``spec``: from the cache, else computed and stored in the cache."""
    if use_cache:
        cached = load_cached_labels(spec, config)
        if cached is not None:
            return cached
    labels = compute_object_labels(spec, config, num_threads)
    if use_cache:
        save_cached_labels(spec, config, labels)
    return labels


def write_models(
    root: str | os.PathLike[str],
    specs: Sequence[ObjectSpec],
    labels: Mapping[str, ObjectLabels],
    config: Config,
) -> list[Path]:
    """Write ``<root>/models/<3-digit id>/`` for every spec (with its labels), plus the tote
    (``<root>/tote/``), ``gripper.yaml`` and ``suction_cup.yaml``. Returns the object folders.

    Each object folder is built completely under ``<root>/.tmp-models-<pid>/`` and then renamed
    into place (replacing an older one), so an interrupted run never leaves a partial folder.
    """

    out = Path(root)
    staging = out / f".tmp-models-{os.getpid()}"
    folders = []
    current = out / "models"
    try:
        for spec in specs:
            current = out / "models" / f"{spec.category_id:03d}"
            tmp = write_model_folder(spec, staging, overwrite=True)
            lab = labels.get(spec.name)
            h5 = tmp / "textured.obj.hdf5"
            if lab is not None and lab.suction is not None:
                write_suction_labels(h5, lab.suction)
            if lab is not None and lab.paralleljaw is not None:
                write_pj_labels(h5, lab.paralleljaw)
            target = out / "models" / tmp.name
            target.parent.mkdir(parents=True, exist_ok=True)
            if target.exists():
                shutil.rmtree(target)
            tmp.replace(target)
            folders.append(target)
        current = out / "tote"
        write_tote(config.tote, out)
        current = out / "gripper.yaml"
        config.gripper.to_yaml(current)
        current = out / "suction_cup.yaml"
        config.cup.to_yaml(current)
    except (OSError, RuntimeError) as e:  # h5py reports some write failures as RuntimeError
        # Named by the folder being written, not by the staging copy or the HDF5 error text.
        if disk_full_error(e) is not None:
            raise IoError(disk_full_message(current)) from e
        if isinstance(e, IoError) or not isinstance(e, OSError):
            raise
        raise _io_error(current, e) from e
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return folders
