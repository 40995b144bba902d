"""Object-level parallel-jaw labels (``grasps/paralleljaw/*`` of ``textured.obj.hdf5``).

Pipeline per object (docs/models.md §5): sample contact points evenly on the surface (MetaGraspNet:
5000), run the antipodal robust sampler (5 perturbed probes per point, analytic score = accepted
probes / 5, up to 20 collision-free approaches per accepted probe), compute the soft-finger wrench
score with gravity along -z of the object frame, and, when a physics scorer is given, the
simulation score. Everything is in metres here; the writer converts to centimetres.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import numpy.typing as npt
from tqdm import tqdm

from mgn import _core
from mgn.base.units import M_TO_CM
from mgn.errors import InvalidArgumentError
from mgn.geometry.mesh import Mesh, SurfaceSamples, sample_surface
from mgn.hardware import ParallelJawGripper
from mgn.pj.sampler import AntipodalSampler, pj_wrench_scores

#: The C++ defaults of the sampler and the wrench score (the one place they are written).
_SAMPLER = _core.grasp.AntipodalOptions()
_WRENCH = _core.grasp.PjWrenchOptions()


@dataclass(frozen=True)
class PjLabels:
    """Parallel-jaw labels of one object (object frame, metres).

    Attributes:
        approach: (M, 3) unit approach directions a (into the object).
        closing: (M, 3) unit closing directions v (from p1 towards the second contact).
        p1: (M, 3) first contact points.
        width: (M,) contact widths w, m.
        quality_score: (M,) analytic score of the source point (accepted probes / probes).
        score_wrench: (M,) soft-finger wrench score (gravity -z of the object frame).
        quality_score_simulation: (M,) physics score, NaN where physics was not run.
        point_index: (M,) index of the source contact point among the sampled points.
        point_score: (N,) analytic score of every sampled point.
        num_points: contact points sampled.
        num_colliding: approaches dropped because the gripper hits the object.
        metadata: gripper, seeds, sampling grid and counts, as written to the file.
    """

    approach: npt.NDArray[np.float32]
    closing: npt.NDArray[np.float32]
    p1: npt.NDArray[np.float32]
    width: npt.NDArray[np.float32]
    quality_score: npt.NDArray[np.float32]
    score_wrench: npt.NDArray[np.float32]
    quality_score_simulation: npt.NDArray[np.float32]
    point_index: npt.NDArray[np.int64]
    point_score: npt.NDArray[np.float32]
    num_points: int
    num_colliding: int
    metadata: dict[str, Any] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.width)

    def pregrasp_transform(self) -> npt.NDArray[np.float32]:
        """(M, 10) MetaGraspNet rows [a (3), v (3), p1 (3, cm), w (cm)], float32."""
        return np.concatenate(
            [self.approach, self.closing, self.p1 * M_TO_CM, self.width[:, None] * M_TO_CM],
            axis=1,
        ).astype(np.float32)


#: Parallel-jaw grasps stored per object by default (``object_labels.pj_grasps``, ``mgn pj label
#: --grasps``): an evenly strided subset of what the sampler finds (docs/decisions/
#: 0032-object-labels-at-the-defaults.md says why this many).
DEFAULT_STORED_GRASPS = 300


def strided_subset(n: int, k: int) -> npt.NDArray[np.int64]:
    """Indices of an evenly strided subset of at most ``k`` of ``n`` items (all when n <= k):
    ``round(linspace(0, n - 1, k))``, first and last included, increasing, no repeats."""
    if n <= k:
        return np.arange(n, dtype=np.int64)
    return np.unique(np.linspace(0, n - 1, k).round().astype(np.int64))


#: A physics scorer: (mesh, labels without physics) -> (M,) scores in [0, 1] (e.g. the Bullet
#: shake test of docs/models.md §5).
PhysicsScorer = Callable[[Mesh, PjLabels], npt.ArrayLike]


def _check_arguments(mass: float, num_points: int, max_grasps: int | None) -> None:
    """label_object's checks of its sizes (InvalidArgumentError naming the argument)."""
    if not (isinstance(mass, (int, float)) and math.isfinite(mass) and mass > 0):
        raise InvalidArgumentError(
            f"label_object: mass must be a finite value > 0 kg, got {mass!r}"
        )
    if not (isinstance(num_points, int) and num_points > 0):
        raise InvalidArgumentError(
            f"label_object: num_points must be an integer > 0, got {num_points!r}"
        )
    if max_grasps is not None and (
        isinstance(max_grasps, bool) or not isinstance(max_grasps, int) or max_grasps < 1
    ):
        raise InvalidArgumentError(
            f"label_object: max_grasps must be an integer >= 1 or None, got {max_grasps!r}"
        )


def _scored(labels: PjLabels, physics: PhysicsScorer, mesh: Mesh) -> PjLabels:
    """``labels`` with the physics scores of ``physics`` and their metadata."""
    sim = np.asarray(physics(mesh, labels), np.float32).reshape(-1)
    if sim.shape != (len(labels),):
        raise InvalidArgumentError(
            f"label_object: the physics scorer returned {sim.shape[0]} scores for "
            f"{len(labels)} grasps"
        )
    scorer = getattr(physics, "__name__", type(physics).__name__)
    scored = int(np.count_nonzero(np.isfinite(sim)))
    estimator = getattr(physics, "last_calibration", None)
    labels = replace(
        labels,
        quality_score_simulation=sim,
        metadata=labels.metadata
        | {
            "pj_physics": f"run ({scorer})",
            "pj_physics_scored": scored,
            "pj_physics_unscored": len(sim) - scored,
        },
    )
    # HDF5 attributes hold no None: the keys are written only where the scorer has them.
    if estimator is not None:
        labels.metadata["pj_physics_estimator"] = estimator.to_json()
    trials = getattr(physics, "last_trials", None)
    if trials is not None:
        labels.metadata["pj_physics_trials"] = int(trials)
    return labels


def label_object(
    mesh: Mesh,
    *,
    mass: float,
    com: npt.ArrayLike,
    gripper: ParallelJawGripper | None = None,
    num_points: int = 5000,
    seed: int = 0,
    num_threads: int = 0,
    progress: bool = False,
    chunk: int | None = None,
    physics: PhysicsScorer | None = None,
    friction: float = _WRENCH.friction,
    grip_force: float = _WRENCH.grip_force,
    contact_radius: float = _WRENCH.contact_radius,
    sampler_options: dict[str, Any] | None = None,
    samples: SurfaceSamples | None = None,
    max_grasps: int | None = None,
) -> PjLabels:
    """Parallel-jaw labels of one object: see the module docstring. Deterministic for ``seed``.

    Args:
        mesh: the object, metres, object frame; must be watertight. A closed mesh wound inward
            is used with its winding reversed (same geometry).
        mass: kg (> 0); com: centre of mass (m, object frame) — for the wrench score.
        gripper: the gripper (default: MetaGraspNet's Franka-like hand).
        num_points: contact points sampled evenly on the surface.
        progress: show a tqdm progress bar.
        chunk: points per native call (labels do not depend on it); None: 250 with a
            progress bar, else all at once (every call waits for its slowest thread).
        physics: optional scorer filling ``quality_score_simulation``; None leaves it NaN.
            The metadata then records ``pj_physics_scored`` / ``pj_physics_unscored``: how
            many grasps got a score and how many kept NaN (a capped scorer), and
            ``pj_physics_estimator``: how the scores were computed and their error bound (the
            scorer's ``last_calibration.to_json()``, e.g. :class:`mgn.pj.ShakeScorer`'s; absent
            when it has none) and ``pj_physics_trials`` (its ``last_trials``).
        friction, grip_force, contact_radius: wrench-score constants (see pj_wrench_scores).
        sampler_options: extra keyword arguments of :meth:`AntipodalSampler.sample`
            (probes, tilt, offset, friction_coef, approaches_tried, approaches_kept, ...).
        samples: the contact points, if already drawn: they must be
            ``sample_surface(mesh, num_points, method="even", seed=seed)`` of the given mesh
            (e.g. shared with :func:`mgn.suction.label_object`); None draws them here. They are
            ignored (drawn again) when the mesh is used with its winding reversed.
        max_grasps: grasps stored, >= 1: when the sampler finds more, an evenly strided subset
            of at most this many is kept (the sampler lists the grasps point by point, and the
            points cover the surface evenly, so the subset does too); None keeps them all. The
            metadata records ``pj_num_found`` (grasps the sampler found) and, when given,
            ``pj_max_grasps``.

    Raises:
        InvalidArgumentError: non-positive mass or num_points, a mesh with no closed volume, an
            invalid gripper.
    """

    _check_arguments(mass, num_points, max_grasps)
    if chunk is None:
        chunk = 250 if progress else max(1, num_points)
    if chunk < 1:
        raise InvalidArgumentError(f"label_object: chunk must be >= 1, got {chunk!r}")
    gripper = gripper if gripper is not None else ParallelJawGripper()
    opts = dict(sampler_options or {})
    for reserved in ("seed", "first_index", "num_threads"):
        if reserved in opts:
            raise InvalidArgumentError(
                f"label_object: pass {reserved} as an argument, not in sampler_options"
            )
    if samples is not None and len(samples.points) != num_points:
        raise InvalidArgumentError(
            f"label_object: samples holds {len(samples.points)} points, expected num_points = "
            f"{num_points}"
        )
    report = mesh.validate()
    if report.is_watertight and report.is_winding_consistent and report.signed_volume < 0:
        # Inward-wound closed mesh (e.g. a mirrored STL export): the surface normals would point
        # into the object and every probe would fail. Same geometry, outward winding (as the
        # user-object path does); the labels are in the same object frame.
        mesh = mesh.flipped()
        samples = None  # the flipped mesh draws different points and normals
    sampler = AntipodalSampler(mesh, gripper)
    if samples is None:
        samples = sample_surface(mesh, num_points, method="even", seed=seed)
    points = np.asarray(samples.points, np.float64)
    normals = np.asarray(samples.normals, np.float64)

    parts = []
    bar = tqdm(
        total=len(points), desc=f"pj {mesh.name or 'object'}", unit="pt", disable=not progress
    )
    for start in range(0, len(points), chunk):
        stop = min(start + chunk, len(points))
        # Point k draws from the stream (seed, k) whatever the chunking.
        parts.append(
            sampler.sample(
                points[start:stop],
                normals[start:stop],
                seed=seed,
                first_index=start,
                num_threads=num_threads,
                **opts,
            )
        )
        bar.update(stop - start)
    bar.close()

    def cat(name: str, dtype: type) -> np.ndarray:
        return np.concatenate([np.asarray(getattr(p, name)) for p in parts]).astype(dtype)

    offsets = np.repeat(list(range(0, len(points), chunk)), [len(p.width) for p in parts])
    point_index = cat("point_index", np.int64) + offsets.astype(np.int64)
    p1, closing, width = cat("p1", np.float64), cat("closing", np.float64), cat("width", np.float64)
    approach, score = cat("approach", np.float32), cat("score", np.float32)
    found = len(width)
    if max_grasps is not None and found > max_grasps:
        keep = strided_subset(found, max_grasps)
        point_index, p1, closing, width = point_index[keep], p1[keep], closing[keep], width[keep]
        approach, score = approach[keep], score[keep]
    wrench = pj_wrench_scores(
        p1,
        closing,
        width,
        mass=mass,
        com=com,
        friction=friction,
        grip_force=grip_force,
        contact_radius=contact_radius,
    )
    metadata: dict[str, Any] = {
        "pj_gripper": gripper.to_dict(),
        "pj_seed": int(seed),
        "pj_num_points": int(num_points),
        "pj_grid": "even surface sampling (farthest-point from an area-weighted pool)",
        "pj_sampler": {
            "probes": _SAMPLER.probes,
            "tilt_rad": _SAMPLER.tilt,
            "offset_m": _SAMPLER.offset,
            "start_offset_m": _SAMPLER.start_offset,
            "friction_coef": _SAMPLER.friction_coef,
            "approaches_tried": _SAMPLER.approaches_tried,
            "approaches_kept": _SAMPLER.approaches_kept,
        }
        | dict(opts),
        "pj_num_accepted_probes": int(sum(p.num_accepted_probes for p in parts)),
        "pj_num_colliding": int(sum(p.num_colliding for p in parts)),
        "pj_num_found": int(found),
        "pj_wrench": {
            "model": "soft finger, elliptic limit surface, gravity -z of the object frame",
            "friction": friction,
            "grip_force_N": grip_force,
            "contact_radius_m": contact_radius,
        },
        "pj_physics": "not run (quality_score_simulation is NaN)",
        "mgn_version": _core.__version__,
    }
    if max_grasps is not None:
        metadata["pj_max_grasps"] = int(max_grasps)
    labels = PjLabels(
        approach=approach,
        closing=closing.astype(np.float32),
        p1=p1.astype(np.float32),
        width=width.astype(np.float32),
        quality_score=score,
        score_wrench=np.asarray(wrench, np.float32),
        quality_score_simulation=np.full(len(width), np.nan, np.float32),
        point_index=point_index,
        point_score=cat("point_score", np.float32),
        num_points=int(num_points),
        num_colliding=int(metadata["pj_num_colliding"]),
        metadata=metadata,
    )
    if physics is not None:
        labels = _scored(labels, physics, mesh)
    return labels
