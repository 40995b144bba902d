"""Will a suction cup seal here? Typed façade over the C++ seal models (docs/models.md §1–3).

Frames and units: points and normals are in the object frame O, metres; normals are unit outward
surface normals and the cup approaches along ``-normal``. Scores are in [0, 1].
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.base.core_result import from_core
from mgn.geometry.mesh import Mesh
from mgn.hardware import SuctionCup

#: The seal models: the force-based spring-mass model of MetaGraspNet and two baselines.
SealModelName = Literal["spring", "strain", "smoothness"]
SEAL_MODELS: tuple[str, ...] = ("spring", "strain", "smoothness")
#: Failure reason names, indexed by the codes in :attr:`SealResult.reason`.
FAILURE_REASONS: tuple[str, ...] = tuple(_core.grasp.SEAL_FAILURE_NAMES)

#: The C++ defaults (mgn/grasp/seal_model.hpp, mgn/grasp/wrench.hpp): the one place they are
#: written; the keyword defaults below read them.
_SEAL = _core.grasp.SealOptions()
_WRENCH = _core.grasp.SuctionWrenchOptions()


#: :class:`~mgn.hardware.SuctionCup` fields the seal models do not use (the hold test's and the
#: wrench score's bending limit, :mod:`mgn.suction.hold`); the C++ cup has no such field.
PYTHON_ONLY_CUP_FIELDS: tuple[str, ...] = ("bending_k",)


def core_cup(cup: SuctionCup) -> _core.grasp.Cup:
    """The C++ cup for a :class:`~mgn.hardware.SuctionCup` (same field names, SI units; the
    fields of :data:`PYTHON_ONLY_CUP_FIELDS` are left out)."""
    c = _core.grasp.Cup()
    for f in dataclasses.fields(cup):
        if f.name in PYTHON_ONLY_CUP_FIELDS:
            continue
        setattr(c, f.name, getattr(cup, f.name))
    c.validate()
    return c


@dataclass(frozen=True)
class SealResult:
    """Per-candidate seal results.

    Attributes:
        score: (N,) float32 fraction of sealed trials (the robust score).
        quality: (N,) float32 mean trial quality (smoothness model: deform x fit; else = score).
        reason: (N,) uint8 most frequent failure of the failed trials (0 "none" if all sealed);
            names in :data:`FAILURE_REASONS`.
        trial_sealed: (N, T) bool outcome of each trial.
        trial_reason: (N, T) uint8 failure code of each trial.
    """

    score: npt.NDArray[np.float32]
    quality: npt.NDArray[np.float32]
    reason: npt.NDArray[np.uint8]
    trial_sealed: npt.NDArray[np.bool_]
    trial_reason: npt.NDArray[np.uint8]

    def reason_names(self) -> list[str]:
        """The failure reason of every candidate as a name ("none", "miss", "hole", ...)."""
        return [FAILURE_REASONS[int(r)] for r in self.reason]


class SealModel:
    """A seal model of one object for one cup; build once, evaluate many candidates.

    Args:
        mesh: the object, metres, object frame.
        cup: the suction cup (default: the MetaGraspNet cup).
        model: ``"spring"`` (default, MetaGraspNet's force-based model), ``"strain"``
            (Dex-Net 3.0 style) or ``"smoothness"`` (SuctionNet-1Billion style).
    """

    def __init__(
        self, mesh: Mesh, cup: SuctionCup | None = None, model: SealModelName = "spring"
    ) -> None:
        self.cup = cup if cup is not None else SuctionCup()
        self.model = model
        self._core = _core.grasp.SealModel(mesh, core_cup(self.cup), model)

    def evaluate(
        self,
        points: npt.ArrayLike,
        normals: npt.ArrayLike,
        *,
        num_trials: int = _SEAL.num_trials,
        angle_sigma: float = _SEAL.angle_sigma,
        position_sigma: float | None = None,
        perturb: bool = _SEAL.perturb,
        seed: int = _SEAL.seed,
        first_index: int = _SEAL.first_index,
        num_threads: int = _SEAL.num_threads,
    ) -> SealResult:
        """Robust seal score of N candidates (points (N, 3) on the surface, normals (N, 3)).

        Each of ``num_trials`` trials tilts the normal by Euler angles ~ N(0, ``angle_sigma``)
        rad and moves the point by ~ N(0, ``position_sigma``) m per axis (default: radius / 4).
        ``perturb=False`` runs one deterministic trial at the nominal pose. Candidate i draws from
        the random stream (``seed``, ``first_index`` + i): chunked jobs give identical results.

        Raises:
            InvalidArgumentError: shapes differ, NaN or zero normals, or a point is not on the
                mesh surface (within 1 mm along its normal).
        """
        o = _core.grasp.SealOptions()
        o.num_trials = int(num_trials)
        o.angle_sigma = float(angle_sigma)
        if position_sigma is not None:
            o.position_sigma = float(position_sigma)
        o.perturb = bool(perturb)
        o.seed = int(seed)
        o.first_index = int(first_index)
        o.num_threads = int(num_threads)
        return from_core(SealResult, self._core.evaluate(points, normals, o))

    def trial(self, point: Sequence[float], normal: Sequence[float]) -> _core.grasp.SealTrial:
        """One deterministic trial with its intermediate quantities (failure name, projected
        ring points and normals, elastic and ring-spring forces in N) for plots and debugging."""
        return self._core.trial(np.asarray(point, np.float64), np.asarray(normal, np.float64))


def suction_wrench_scores(
    contacts: npt.ArrayLike,
    approach: npt.ArrayLike,
    *,
    mass: float,
    com: npt.ArrayLike,
    gravity_direction: npt.ArrayLike = (0.0, 0.0, -1.0),
    cup_radius: float = 0.007,
    k: float = _WRENCH.k,
) -> npt.NDArray[np.float32]:
    """Suction wrench score in [0, 1] of each contact: 1 - min(1, tau / tau_max).

    tau is the bending part (about axes normal to the approach) of the gravity torque of the
    object (``mass`` kg at ``com``, m) about the contact; tau_max = k * cup_radius * pi * sqrt(2).
    ``approach`` points into the surface. All vectors in one frame (object or world).
    """
    o = _core.grasp.SuctionWrenchOptions()
    o.k = float(k)
    return _core.grasp.suction_wrench_scores(
        contacts,
        approach,
        float(mass),
        np.asarray(com, np.float64),
        np.asarray(gravity_direction, np.float64),
        float(cup_radius),
        o,
    )
