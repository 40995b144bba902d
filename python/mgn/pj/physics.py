"""Physics score of parallel-jaw grasps: the Bullet shake test (typed façade, docs/models.md §5).

Per grasp, S×S trials (friction ``linspace(*friction_range, S)`` × density factor
``linspace(*density_range, S)``): the object sits in the open gripper with gravity off, the
fingers close and squeeze with ``grip_force``, then the hand shakes along its approach axis and
rotates about an axis perpendicular to it. A trial succeeds if both fingers still touch the
object at the end; the score is the success fraction. All in C++ (``mgn._core.grasp.shake_test``),
trials in parallel, identical results for any thread count.

Grasps are (N, 10) rows ``[a (3), v (3), p1 (3), w]`` in metres (MetaGraspNet's order, SI
units; the file writer converts to cm), or objects with ``approach``, ``closing``, ``p1`` and
``width`` attributes.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass, replace
from dataclasses import field as dataclass_field
from typing import Any

import numpy as np
import numpy.typing as npt
from tqdm import tqdm

from mgn import _core
from mgn.base.core_result import from_core, to_core
from mgn.errors import InvalidArgumentError
from mgn.geometry.convex import cached_convex_decomposition, drop_contained_parts
from mgn.geometry.mesh import mass_properties
from mgn.hardware import ParallelJawGripper, default_gripper
from mgn.pj.labels import strided_subset
from mgn.pj.sampler import core_gripper

Mesh = _core.geometry.Mesh

#: Grasps per thread in one shake_scores call of ShakeScorer's progress bar.
_PIECE_PER_THREAD = 16

#: Phase codes of ShakeTrajectory.phase.
PHASE_NAMES = ("close", "translate", "rotate")

#: The C++ defaults (cpp/include/mgn/grasp/shake_trial.hpp), the one place they are written.
_CORE = _core.grasp.ShakeOptions()


@dataclass(frozen=True)
class ShakeOptions:
    """Parameters of the shake test (SI units).

    MetaGraspNet values: ``grid`` 10, the two ranges, the phases' durations (2 s, 2 s, 1.5 s),
    0.5 m/s and 0.2–0.3 rad. ``dt`` is 1/400 s, half MetaGraspNet's (800/800/600 steps): at
    1/200 s the solver drops light objects and lets round ones slip that a finer step holds
    (docs/decisions/0055-shake-time-step-1-400.md). The others are mgn's (see
    ``cpp/include/mgn/grasp/shake_trial.hpp``):
    ``settle_steps`` and ``lost_contact_steps`` end phases and trials early (0 disables them),
    ``inertia_floor`` stabilises light objects, the pads are soft (``pad_stiffness`` N/m per
    contact point, ``pad_damping`` N s/m). ``limit_controller_gain`` (on by default) keeps the
    grip-force controller stable when a pad touches a compound at many points (its stiffness is
    raised to at least n (``pad_stiffness`` + ``pad_damping``/``dt``) for n points per pad;
    nothing changes with at most 5 points, so never for one hull; docs/models.md, "Grip-force
    controller"). ``adapt_controller_gain`` (on by default) doubles that stiffness for the rest
    of a trial, up to 64x, each time the force error flips sign without halving while at least a
    quarter of ``grip_force`` (a period-2 oscillation: the solver's contacts respond more stiffly
    than the model at some iteration counts); it changes nothing in a trial without such a flip.
    ``staircase`` finds each grasp's success boundary
    (success is monotone: more friction helps, more mass hurts) by galloping and bisection row
    by row, verifies the cells on both sides of it (in the lowest ``staircase_verify_share`` of
    the friction rows; 1 = all) and ``staircase_checks`` other inferred cells, and falls back
    to the full grid where a check contradicts monotonicity (``ShakeScores.fallback``); see
    ``staircase_grid`` in the header for the order and bounds.
    ``first_grasp_index``: grasp ``g`` of a call draws the random streams of grasp
    ``first_grasp_index + g``, so a grasp list scored in consecutive pieces gets the same scores
    as scored whole.
    ``polyhedral_contacts`` (on by default): whole contact patches from Bullet's polyhedral
    clipping; off, GJK contact points are 1.2–1.5× faster per trial but change some outcomes
    (``benchmarks/bench_shake.py`` measures both). ``hold_tolerance`` (m, default 3 mm, 0 = the
    full schedule) skips the parts of the shake that repeat loads the object held within that
    distance of its pose in the hand (docs/models.md, "Held-load windows"; 1.02–1.21× fewer
    CPU-s per trial, no more changed outcomes than the physics' own noise; no effect with
    ``smooth_shake``).
    ``smooth_shake`` (off by default): the hand's shake profile starts and ends every cycle at
    rest (f(x) = sin x − sin(2x)/2, same peak speed and angle) instead of the sine's velocity
    jumps; a can's grids become more nearly monotone (with ``dt`` 1/100 s and 200/200/150
    steps, the staircase matches its full grid more often at 1.8× fewer CPU-s per trial than at
    1/200 s), a
    mug's less (docs/models.md, "Smooth shake profile"; scores move by ~0.01 on average).
    ``iterations_per_hull_contact`` (0 = off): every step runs at least this many solver
    iterations per (finger, object hull) pair in contact at the previous step (a compound held
    by several hulls needs more to converge at a coarser ``dt``; a single hull makes at most 2
    pairs; docs/models.md, "A coarser step judged by its own grids").
    ``compound_solver_iterations`` (default 40; 0 = the same as ``solver_iterations``, in
    [0, 1000]): the solver iterations of an object whose shake shape has more than one convex
    part (docs/models.md, "Solver iterations"). ``compound_iteration_points`` (default 24, in
    [0, 10000]; 0 = off): a compound's step after one where the fingers touched it at n > this
    many points runs ceil(``compound_solver_iterations`` x this / n) iterations instead, at least
    ``solver_iterations`` (a hex nut pressed face-on across many hulls holds as well with 10).
    ``controller_stiffness`` is per 1/400 s of simulated time: a step ``dt`` moves the fingers
    ``dt`` x 400/s times (mean pad force − ``grip_force``)/``controller_stiffness``, so the
    closing settles alike at any ``dt``. ``controller_net_force`` (on by default): the controller
    reads each pad's net normal force along its opening direction, so a finger wedged in a
    concavity (inside a pipe's or a cup's bore) does not read as gripping; off, it reads the sum
    of the normal forces on every face of the finger (the same force on a face-on contact;
    docs/models.md, "Grip-force controller").
    Every default is the C++ struct's.
    """

    grid: int = _CORE.grid
    friction_range: tuple[float, float] = (_CORE.friction_min, _CORE.friction_max)
    density_range: tuple[float, float] = (_CORE.density_min, _CORE.density_max)
    dt: float = _CORE.dt
    close_steps: int = _CORE.close_steps
    shake_steps: int = _CORE.shake_steps
    rotate_steps: int = _CORE.rotate_steps
    gravity: float = _CORE.gravity
    shake_speed: float = _CORE.shake_speed
    shake_cycles: int = _CORE.shake_cycles
    angle_range: tuple[float, float] = (_CORE.angle_min, _CORE.angle_max)
    rotate_cycles: int = _CORE.rotate_cycles
    grip_force: float = _CORE.grip_force
    close_speed: float = _CORE.close_speed
    pad_stiffness: float = _CORE.pad_stiffness
    pad_damping: float = _CORE.pad_damping
    controller_stiffness: float = _CORE.controller_stiffness
    limit_controller_gain: bool = _CORE.limit_controller_gain
    adapt_controller_gain: bool = _CORE.adapt_controller_gain
    controller_net_force: bool = _CORE.controller_net_force
    inertia_floor: float = _CORE.inertia_floor
    contact_distance: float = _CORE.contact_distance
    settle_steps: int = _CORE.settle_steps
    lost_contact_steps: int = _CORE.lost_contact_steps
    hold_tolerance: float = _CORE.hold_tolerance
    smooth_shake: bool = _CORE.smooth_shake
    margin: float = _CORE.margin
    polyhedral_contacts: bool = _CORE.polyhedral_contacts
    max_hull_vertices: int = _CORE.max_hull_vertices
    solver_iterations: int = _CORE.solver_iterations
    compound_solver_iterations: int = _CORE.compound_solver_iterations
    compound_iteration_points: float = _CORE.compound_iteration_points
    iterations_per_hull_contact: float = _CORE.iterations_per_hull_contact
    staircase: bool = _CORE.staircase
    staircase_checks: int = _CORE.staircase_checks
    staircase_verify_share: float = _CORE.staircase_verify_share
    num_threads: int = _CORE.num_threads
    seed: int = _CORE.seed
    first_grasp_index: int = _CORE.first_grasp_index

    def to_core(self) -> _core.grasp.ShakeOptions:
        """The C++ options (validated there; errors name the field)."""
        pairs = {"friction_range": "friction", "density_range": "density", "angle_range": "angle"}
        o = to_core(self, _core.grasp.ShakeOptions(), skip=pairs)
        for name, prefix in pairs.items():
            lo, hi = _pair(name, getattr(self, name))
            setattr(o, prefix + "_min", lo)
            setattr(o, prefix + "_max", hi)
        o.validate()
        return o


def _pair(name: str, value: Any) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError) as e:
        raise InvalidArgumentError(
            f"ShakeOptions.{name}: expected (min, max), got {value!r}"
        ) from e
    return lo, hi


@dataclass(frozen=True)
class ShakeScores:
    """Result of :func:`shake_scores` for G grasps and an S×S grid.

    Attributes:
        score: (G,) success fraction per grasp.
        trial_success: (G, S, S) bool, [grasp, friction index, density index].
        trial_ended_early: (G, S, S) bool, trial stopped once the object was lost.
        trial_steps: (G, S, S) int32 simulation steps run.
        frictions: (S,) friction coefficients of the grid.
        density_factors: (S,) density (mass) factors of the grid.
        total_steps: sum of trial_steps.
        trial_simulated: (G, S, S) bool, the trial was simulated (False: inferred by the
            staircase search).
        fallback: (G,) bool, the staircase search fell back to the full grid.
    """

    score: npt.NDArray[np.float64]
    trial_success: npt.NDArray[np.bool_]
    trial_ended_early: npt.NDArray[np.bool_]
    trial_steps: npt.NDArray[np.int32]
    frictions: npt.NDArray[np.float64]
    density_factors: npt.NDArray[np.float64]
    total_steps: int
    trial_simulated: npt.NDArray[np.bool_]
    fallback: npt.NDArray[np.bool_]

    @property
    def num_trials(self) -> int:
        """Trials simulated (all of the grid unless the staircase search inferred some)."""
        return int(self.trial_simulated.sum())

    @property
    def early_fraction(self) -> float:
        """Share of trials that ended early (0 when there are none)."""
        return float(self.trial_ended_early.mean()) if self.trial_ended_early.size else 0.0


@dataclass(frozen=True)
class ShakeTrajectory:
    """One recorded trial (world W: z up, gravity −z; the hand starts at the origin, pointing down).

    Attributes:
        time: (K,) s.  phase: (K,) int8 index into PHASE_NAMES.
        X_WO, X_WH: (K, 4, 4) object and hand (flange) poses.
        finger_left, finger_right: (K,) inner-face offsets of the fingers from the hand axis, m
            (the −x finger's face is at x = −finger_left in the hand frame).
        contact_left, contact_right: (K,) bool, the finger touches the object.
        force_left, force_right: (K,) force of each pad on the object over the step just run
            as the grip-force controller reads it (``ShakeOptions.controller_net_force``), N (0
            at the initial state).
        success, ended_early, steps, friction, density_factor: the trial's outcome and setting.
    """

    time: npt.NDArray[np.float64]
    phase: npt.NDArray[np.int8]
    X_WO: npt.NDArray[np.float64]
    X_WH: npt.NDArray[np.float64]
    finger_left: npt.NDArray[np.float64]
    finger_right: npt.NDArray[np.float64]
    contact_left: npt.NDArray[np.bool_]
    contact_right: npt.NDArray[np.bool_]
    force_left: npt.NDArray[np.float64]
    force_right: npt.NDArray[np.float64]
    success: bool
    ended_early: bool
    steps: int
    friction: float
    density_factor: float


def _gripper(gripper: ParallelJawGripper | None) -> _core.grasp.ParallelJawGripper:
    """The C++ gripper (boxes or meshes) through the one conversion, core_gripper()."""
    if gripper is None:
        gripper = default_gripper()
    if not isinstance(gripper, ParallelJawGripper):
        raise InvalidArgumentError(
            f"gripper: expected a mgn.hardware.ParallelJawGripper, got {type(gripper).__name__}"
        )
    return core_gripper(gripper)


def _parts(mesh_or_parts: Mesh | Sequence[Mesh]) -> list[Mesh]:
    if isinstance(mesh_or_parts, Mesh):
        return [mesh_or_parts]
    parts = list(mesh_or_parts)
    if not all(isinstance(p, Mesh) for p in parts):
        raise InvalidArgumentError("mesh_or_parts: expected a mgn.Mesh or a sequence of them")
    return parts


def grasp_rows(grasps: Any) -> npt.NDArray[np.float64]:
    """(N, 10) float64 rows [a, v, p1, w] from an array or from objects with grasp attributes."""
    if isinstance(grasps, np.ndarray) or (
        isinstance(grasps, Sequence) and grasps and not hasattr(grasps[0], "approach")
    ):
        rows = np.asarray(grasps, dtype=np.float64)
        if rows.ndim == 1 and rows.shape[0] == 10:
            rows = rows.reshape(1, 10)
        if rows.ndim != 2 or rows.shape[1] != 10:
            raise InvalidArgumentError(
                f"grasps: expected an array of shape (N, 10) [a, v, p1, w], got {rows.shape}"
            )
        return np.ascontiguousarray(rows)
    items = list(grasps)
    out = np.empty((len(items), 10), dtype=np.float64)
    for i, g in enumerate(items):
        try:
            out[i, 0:3] = g.approach
            out[i, 3:6] = g.closing
            out[i, 6:9] = g.p1
            out[i, 9] = g.width
        except AttributeError as e:
            raise InvalidArgumentError(
                f"grasps[{i}]: expected approach, closing, p1 and width attributes"
            ) from e
    return out


def _inputs(
    mass: float, com: npt.ArrayLike, inertia: npt.ArrayLike
) -> tuple[float, npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    c = np.asarray(com, dtype=np.float64)
    inertia_arr = np.asarray(inertia, dtype=np.float64)
    if c.shape != (3,):
        raise InvalidArgumentError(f"com: expected shape (3,), got {c.shape}")
    if inertia_arr.shape != (3, 3):
        raise InvalidArgumentError(f"inertia: expected shape (3, 3), got {inertia_arr.shape}")
    return float(mass), c, inertia_arr


def shake_scores(
    mesh_or_parts: Mesh | Sequence[Mesh],
    mass: float,
    com: npt.ArrayLike,
    inertia: npt.ArrayLike,
    grasps: Any,
    gripper: ParallelJawGripper | None = None,
    options: ShakeOptions | None = None,
) -> ShakeScores:
    """Physics scores of parallel-jaw grasps on one object.

    Args:
        mesh_or_parts: the object (used as its convex hull) or its convex parts, object frame.
        mass: kg at density factor 1.  com: (3,) centre of mass, m.
        inertia: (3, 3) inertia about the centre of mass at density factor 1, kg m^2.
        grasps: (N, 10) rows [a, v, p1, w] (m) or grasp objects (see module docstring).
        gripper: defaults to the MetaGraspNet gripper.  options: defaults to ShakeOptions().
    """
    m, c, inertia_arr = _inputs(mass, com, inertia)
    rows = grasp_rows(grasps)
    g = _gripper(gripper)
    o = (options if options is not None else ShakeOptions()).to_core()
    r = _core.grasp.shake_test(_parts(mesh_or_parts), m, c, inertia_arr, rows, g, o)
    return from_core(ShakeScores, r, total_steps=int(r.total_steps))


def shake_trajectory(
    mesh_or_parts: Mesh | Sequence[Mesh],
    mass: float,
    com: npt.ArrayLike,
    inertia: npt.ArrayLike,
    grasp: Any,
    friction: float,
    density_factor: float,
    gripper: ParallelJawGripper | None = None,
    options: ShakeOptions | None = None,
    *,
    record_every: int = 5,
    trial_index: int = 0,
) -> ShakeTrajectory:
    """One shake trial recorded every ``record_every`` steps (for :mod:`mgn.viz.shake_trial`).

    ``trial_index`` selects the random stream (rotation axis and angle); trial
    ``g*S*S + i*S + j`` of :func:`shake_scores` is reproduced with ``frictions[i]`` and
    ``density_factors[j]``.
    """
    m, c, inertia_arr = _inputs(mass, com, inertia)
    row = grasp_rows([grasp] if hasattr(grasp, "approach") else grasp)
    if row.shape[0] != 1:
        raise InvalidArgumentError(f"grasp: expected one grasp, got {row.shape[0]}")
    g = _gripper(gripper)
    o = (options if options is not None else ShakeOptions()).to_core()
    t = _core.grasp.shake_trajectory(
        _parts(mesh_or_parts),
        m,
        c,
        inertia_arr,
        row[0],
        g,
        float(friction),
        float(density_factor),
        o,
        int(record_every),
        int(trial_index),
    )
    return from_core(ShakeTrajectory, t)


def replay_staircase(
    trial_success: npt.ArrayLike, checks: int, verified_rows: int = -1
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
    """The staircase search's scores on grids already simulated (no physics).

    Every cell of a grid is a deterministic trial (its own random stream, the same whichever
    search simulates it), so the search's result is a function of the full grid: this runs
    ``_core.grasp.staircase_grid`` (the search of :func:`shake_scores` with
    ``staircase=True``) on the stored outcomes.

    Args:
        trial_success: (G, S, S) bool full-grid outcomes (``ShakeScores.trial_success``).
        checks: ``ShakeOptions.staircase_checks`` of the search replayed, >= 0.
        verified_rows: rows whose boundary the search verifies (-1: every row;
            ``ShakeOptions.to_core().staircase_verified_rows()``).

    Returns:
        (G,) scores the search would give (success fraction) and (G,) trials it would simulate.
    """
    grids = np.asarray(trial_success, dtype=bool)
    if grids.ndim != 3 or grids.shape[1] != grids.shape[2]:
        raise InvalidArgumentError(f"trial_success: expected shape (G, S, S), got {grids.shape}")
    S = grids.shape[1]
    score = np.empty(grids.shape[0], np.float64)
    trials = np.empty(grids.shape[0], np.int64)
    for g in range(grids.shape[0]):
        cells: list[list[bool]] = grids[g].tolist()

        def trial(i: int, j: int, cells: list[list[bool]] = cells) -> bool:
            return cells[i][j]

        r = _core.grasp.staircase_grid(S, trial, int(checks), int(verified_rows))
        score[g] = float(np.count_nonzero(r.success)) / (S * S)
        trials[g] = r.trials
    return score, trials


#: ``staircase_checks`` of the staircase search when the object-level calibration is on
#: (:class:`ShakeScorer` ``calibration_grasps`` > 0). The calibration's full grids catch the
#: objects whose grids have isolated failing cells away from the success boundary, which is what
#: the per-grasp golden-ratio checks are for; replayed on 590 stored grids of 7 objects the
#: policy's scores equal the full grid's on 99.8 % of grasps with 0 checks as with 6, at 25-30 %
#: fewer trials per grasp (docs/decisions/0009-shake-calibrated-checks.md). The cells next to
#: each row's boundary are verified whatever this is.
CALIBRATED_STAIRCASE_CHECKS = 0

#: ``staircase_verify_share`` of the staircase search when the object-level calibration is on:
#: the boundary is verified in the lower half of the friction rows only. The isolated failing
#: cells of real grasps sit where the grip is marginal (low friction, high mass); replayed on
#: the stored grids the policy's agreement with the full grid is the same as with every row
#: verified (99.8 %, 590 grasps at 1/200 s; 99.8 %, 520 with f5; 99.6-100 % on five other
#: physics variants) at a third fewer trials per grasp
#: (docs/decisions/0009-shake-calibrated-checks.md).
CALIBRATED_STAIRCASE_VERIFY_SHARE = 0.5


#: Mean absolute physics-score error the object-level calibration allows a staircase search
#: (its 95 % upper bound on the calibration grasps, :func:`calibrate_staircase`): the physics'
#: own noise band. Moving every grasp by 1 um along its approach (physically nothing) changes
#: the full-grid scores by a mean |d| of 0 (cereal box, mug), 0.001-0.002 (soda can), 0.0045
#: (water bottle) and 0.005-0.007 (marker pen); a search whose error stays below 0.005 cannot
#: be told from the full grid by the simulation itself
#: (docs/decisions/0032-object-labels-at-the-defaults.md).
CALIBRATION_TOLERANCE = 0.005

#: Calibration grasps of the object-level calibration's first stage (:class:`ShakeScorer`
#: ``calibration_min_grasps``): when the cheapest search (the options' own staircase) is within
#: the tolerance on the full grids of this many grasps, the calibration stops there; otherwise
#: it goes on to ``calibration_grasps`` and chooses on all of them. With no wrong grasp of 12
#: the error bound is 0.0022 (one cell of a 10 x 10 grid times the rate's 95 % bound, 0.22),
#: within the 0.005 tolerance, and an object whose grids the search reproduces saves 20 of the
#: 32 full grids (docs/decisions/0071-two-stage-calibration.md).
CALIBRATION_MIN_GRASPS = 12

#: ``staircase_checks`` of the calibration's second search, the checked staircase (every
#: row's boundary verified as well). On the calibration grids of a soda can its mean error is
#: 0.002 against the plain search's 0.009, at ~30 instead of ~16 trials per grasp.
CHECKED_STAIRCASE_CHECKS = 6

#: ``staircase_checks`` of the calibration's third search, the sampled staircase: no row's
#: boundary verified, this many golden-ratio checks over the inferred cells (on a grid that
#: succeeds everywhere 25 trials against the thorough search's 35; the isolated failing cells
#: of objects with many convex parts lie anywhere on the grid, not next to the boundary;
#: docs/decisions/0042-object-labels-of-multi-hull-objects.md).
SAMPLED_STAIRCASE_CHECKS = 24

#: ``staircase_checks`` of the calibration's fourth search, the thorough staircase (~48 trials
#: per grasp; mean error 0.0005-0.001 on a soda can and a marker pen).
THOROUGH_STAIRCASE_CHECKS = 24


def shake_parts(mesh: Mesh, contained_part_tolerance: float | None = None) -> list[Mesh]:
    """The convex parts :class:`ShakeScorer` simulates ``mesh`` as: its cached convex
    decomposition (:func:`mgn.geometry.convex.cached_convex_decomposition`, default options),
    without the parts that lie inside another part within ``contained_part_tolerance`` (m,
    >= 0; :func:`mgn.geometry.convex.drop_contained_parts`; None, the default: every part)."""
    parts = cached_convex_decomposition(mesh)
    if contained_part_tolerance is None:
        return parts
    return drop_contained_parts(parts, contained_part_tolerance)


def default_staircase_checks(calibration_grasps: int) -> int:
    """The staircase checks to use when the user gave none: :data:`CALIBRATED_STAIRCASE_CHECKS`
    (0) with the object-level calibration (``calibration_grasps`` > 0), else
    ``ShakeOptions.staircase_checks`` (6: without calibration the per-grasp checks are the only
    guard against isolated failing cells)."""
    if int(calibration_grasps) > 0:
        return CALIBRATED_STAIRCASE_CHECKS
    return int(ShakeOptions.staircase_checks)


def default_staircase_verify_share(calibration_grasps: int) -> float:
    """The share of rows whose boundary the staircase verifies by default:
    :data:`CALIBRATED_STAIRCASE_VERIFY_SHARE` (0.5) with the object-level calibration, else
    ``ShakeOptions.staircase_verify_share`` (1: every row)."""
    if int(calibration_grasps) > 0:
        return CALIBRATED_STAIRCASE_VERIFY_SHARE
    return float(ShakeOptions.staircase_verify_share)


def search_options(
    grid: int,
    staircase: bool,
    calibration_grasps: int,
    checks: int | None = None,
    num_threads: int = 0,
) -> ShakeOptions:
    """The ShakeOptions of a :class:`ShakeScorer` with ``calibration_grasps``: an S = ``grid``
    search (``staircase`` or the full grid) whose checks (None: :func:`default_staircase_checks`)
    and verified rows (:func:`default_staircase_verify_share`) follow the calibration. One
    place for the pipeline's config and ``mgn pj label``."""
    return ShakeOptions(
        grid=grid,
        staircase=staircase,
        staircase_checks=(
            default_staircase_checks(calibration_grasps) if checks is None else checks
        ),
        staircase_verify_share=default_staircase_verify_share(calibration_grasps),
        num_threads=num_threads,
    )


@dataclass(frozen=True)
class StaircaseCalibration:
    """The search the object-level calibration chose for an object's other grasps.

    Attributes:
        grasps: calibration grasps (simulated on the full grid; their scores are exact).
        mismatches: calibration grasps whose score the chosen search, replayed on their grids,
            gets wrong; for the full grid, those the options' own search got wrong.
        staircase: True if the other grasps get a staircase search, False for the full grid.
        search: ``"staircase"`` (the options' search), ``"checked staircase"`` (every row's
            boundary verified and :data:`CHECKED_STAIRCASE_CHECKS` checks), ``"sampled
            staircase"`` (no row's boundary verified, :data:`SAMPLED_STAIRCASE_CHECKS`
            checks), ``"thorough staircase"`` (every row's boundary verified and
            :data:`THOROUGH_STAIRCASE_CHECKS` checks) or ``"full grid"``.
        mean_abs_error: mean |score error| of the chosen search on the calibration grasps.
        max_abs_error: the largest of them.
        error_bound: 95 % upper bound on the search's mean |score error| over the object's
            grasps (:func:`error_bound`); 0 for the full grid.
        trials_per_grasp: mean trials of the chosen search on the calibration grids.
    """

    grasps: int
    mismatches: int
    staircase: bool
    search: str = "staircase"
    mean_abs_error: float = 0.0
    max_abs_error: float = 0.0
    error_bound: float = 0.0
    trials_per_grasp: float = 0.0

    def to_json(self) -> dict[str, Any]:
        """The record written to the label metadata (``pj_physics_estimator``)."""
        return {
            "calibration_grasps": self.grasps,
            "search": self.search,
            "calibration_mismatches": self.mismatches,
            "mean_abs_error": round(self.mean_abs_error, 6),
            "max_abs_error": round(self.max_abs_error, 6),
            "error_bound_95": round(self.error_bound, 6),
            "trials_per_grasp": round(self.trials_per_grasp, 2),
        }


def _calibration_errors(
    grids: npt.NDArray[np.bool_], checks: int, verified_rows: int
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
    """(|search score - full-grid score| per grasp, trials per grasp) of a replayed search."""
    replayed, trials = replay_staircase(grids, checks, verified_rows)
    full = grids.sum(axis=(1, 2)) / float(grids.shape[1] * grids.shape[2])
    return np.abs(replayed - full), trials


def _binomial_upper(m: int, n: int, alpha: float = 0.05) -> float:
    """Clopper-Pearson one-sided upper (1 - alpha) confidence bound on a rate observed as m
    events in n trials (the p whose binomial CDF at m is alpha), by bisection."""
    if m >= n:
        return 1.0

    def cdf(p: float) -> float:
        return sum(math.comb(n, k) * p**k * (1.0 - p) ** (n - k) for k in range(m + 1))

    lo, hi = m / n, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if cdf(mid) > alpha else (lo, mid)
    return hi


def error_bound(errors: npt.ArrayLike, cell: float) -> float:
    """Upper bound (95 %) on the mean absolute score error of a search, from its errors on
    n calibration grasps of which m are wrong: the Clopper-Pearson upper bound on the share of
    wrong grasps (m of n; ~3/n when m = 0) times the mean size of a wrong score (at least
    ``cell``, the score of one grid cell, 1/S^2: a search that errs misses at least one cell).
    Rare misses that the calibration grasps did not show are covered by the rate's bound; on
    constructed populations of grids it holds in >= 90 % of the draws (tests)."""
    e = np.asarray(errors, np.float64)
    if len(e) == 0:
        return 1.0
    wrong = e[e > 0]
    size = max(float(wrong.mean()) if len(wrong) else 0.0, float(cell))
    return min(1.0, _binomial_upper(len(wrong), len(e)) * size)


def calibrate_staircase(
    trial_success: npt.ArrayLike,
    checks: int,
    max_mismatches: int = 0,
    verified_rows: int = -1,
    tolerance: float = 0.0,
) -> StaircaseCalibration:
    """The object-level policy: which search scores an object's other grasps, decided on the
    full grids of its calibration grasps.

    The searches are tried in order of cost, each replayed (:func:`replay_staircase`) on the
    calibration grids: the given staircase (``checks``, ``verified_rows``), then with
    ``tolerance`` > 0 the checked staircase (every row verified,
    :data:`CHECKED_STAIRCASE_CHECKS` checks), the sampled one (no row verified,
    :data:`SAMPLED_STAIRCASE_CHECKS` checks) and the thorough one (every row verified,
    :data:`THOROUGH_STAIRCASE_CHECKS` checks). The first one whose score differs from the full
    grid's on at most ``max_mismatches`` calibration grasps, or whose error bound
    (:func:`error_bound` of its absolute score errors) is at most ``tolerance``, is chosen;
    if none is, the full grid.

    Args:
        trial_success: (K, S, S) bool full-grid outcomes of the calibration grasps.
        checks: ``ShakeOptions.staircase_checks`` of the first search, >= 0.
        max_mismatches: >= 0.  verified_rows: as in :func:`replay_staircase`.
        tolerance: mean absolute score error allowed (its 95 % bound), >= 0; 0 = exact
            agreement only (``max_mismatches``), as the first search alone.
    """
    if int(max_mismatches) < 0:
        raise InvalidArgumentError(f"max_mismatches: expected >= 0, got {max_mismatches}")
    if not (np.isfinite(tolerance) and 0.0 <= float(tolerance) < 1.0):
        raise InvalidArgumentError(f"tolerance: expected a score error in [0, 1), got {tolerance}")
    grids = np.asarray(trial_success, dtype=bool)
    tiers = [("staircase", int(checks), int(verified_rows))]
    if tolerance > 0:
        tiers += [
            ("checked staircase", CHECKED_STAIRCASE_CHECKS, -1),
            ("sampled staircase", SAMPLED_STAIRCASE_CHECKS, 0),
            ("thorough staircase", THOROUGH_STAIRCASE_CHECKS, -1),
        ]
    first_mismatches = 0
    for k, (name, c, rows) in enumerate(tiers):
        errors, trials = _calibration_errors(grids, c, rows)
        mismatches = int(np.count_nonzero(errors))
        first_mismatches = mismatches if k == 0 else first_mismatches
        bound = error_bound(errors, 1.0 / (grids.shape[1] * grids.shape[2]))
        if mismatches <= int(max_mismatches) or bound <= tolerance:
            return StaircaseCalibration(
                grasps=int(grids.shape[0]),
                mismatches=mismatches,
                staircase=True,
                search=name,
                mean_abs_error=float(errors.mean()),
                max_abs_error=float(errors.max()),
                error_bound=bound,
                trials_per_grasp=float(trials.mean()),
            )
    return StaircaseCalibration(
        grasps=int(grids.shape[0]),
        mismatches=first_mismatches,
        staircase=False,
        search="full grid",
        trials_per_grasp=float(grids.shape[1] * grids.shape[2]),
    )


def search_of(calibration: StaircaseCalibration, options: ShakeOptions) -> ShakeOptions:
    """The ShakeOptions of the search ``calibration`` chose, from the scorer's ``options``."""
    if calibration.search == "full grid":
        return replace(options, staircase=False)
    if calibration.search == "checked staircase":
        return replace(
            options, staircase_checks=CHECKED_STAIRCASE_CHECKS, staircase_verify_share=1.0
        )
    if calibration.search == "sampled staircase":
        return replace(
            options, staircase_checks=SAMPLED_STAIRCASE_CHECKS, staircase_verify_share=0.0
        )
    if calibration.search == "thorough staircase":
        return replace(
            options, staircase_checks=THOROUGH_STAIRCASE_CHECKS, staircase_verify_share=1.0
        )
    return options


@dataclass
class ShakeScorer:
    """The physics scorer of :func:`mgn.pj.label_object` (``physics=ShakeScorer(...)``).

    Every grasp gets a score by default (``max_grasps=None``), found with the staircase search
    of ``options`` (``ShakeOptions.staircase``, on by default here). ``max_grasps`` caps the cost:
    only an evenly strided subset of at most that many grasps is simulated and the others keep
    NaN in ``quality_score_simulation`` (:func:`mgn.pj.label_object` records how many were
    scored in the label metadata). The object is simulated as its cached convex decomposition
    (:func:`mgn.geometry.convex.cached_convex_decomposition`) with uniform ``density``
    (kg/m^3); ``contained_part_tolerance`` (m, >= 0; None, the default: off) leaves out the
    parts that lie inside another part within that distance (:func:`shake_parts`; the union
    moves by at most that much; at 1e-4 the marker pen keeps 5 of its 7 hulls and the duck of
    pybullet_data 11 of 12, at no measured saving:
    docs/decisions/0048-shake-shape-without-contained-hulls.md).
    ``progress`` shows a progress bar with an ETA on stderr (None: when stderr is a terminal);
    the scores do not depend on it.

    Object-level policy (staircase only, ``calibration_grasps`` > 0): the first grasps to
    score are simulated on the full grid and keep its exact scores; :func:`calibrate_staircase`
    then replays the staircase searches on their grids and picks the cheapest whose score error
    is within the physics' own noise band: the options' search if it reproduces every
    calibration grid (up to ``calibration_mismatches``) or its 95 % error bound is at most
    ``calibration_tolerance``, else the checked, the sampled or the thorough staircase (more
    cells verified), else the full grid. The calibration runs in two stages: the first
    ``calibration_min_grasps`` grasps (default :data:`CALIBRATION_MIN_GRASPS`; 0 = one stage),
    and only if the options' own search is not chosen on them, the rest of the first
    ``calibration_grasps`` (default 32), after which the choice is made on all of them. The
    outcomes that a search misses (the isolated failing cells of cans and bottles) are a
    property of the object's physics, so the choice is made once per object, before its
    grasps are scored.
    Every grasp keeps its random streams, so the scores do not depend on the thread count or
    the progress bar. The choice of the last call is ``last_calibration`` (None without
    calibration), recorded in ``__name__`` and, by :func:`mgn.pj.label_object`, in the label
    metadata (``pj_physics_estimator``: search, calibration errors, error bound; see
    docs/decisions/0032-object-labels-at-the-defaults.md and
    0042-object-labels-of-multi-hull-objects.md); ``last_trials`` counts the shake trials it
    simulated (``pj_physics_trials``).
    """

    density: float = 1000.0
    gripper: ParallelJawGripper | None = None
    options: ShakeOptions = dataclass_field(
        default_factory=lambda: ShakeOptions(
            grid=5,
            staircase=True,
            staircase_checks=CALIBRATED_STAIRCASE_CHECKS,
            staircase_verify_share=CALIBRATED_STAIRCASE_VERIFY_SHARE,
        )
    )
    max_grasps: int | None = None
    progress: bool | None = None
    calibration_grasps: int = 32
    calibration_min_grasps: int = CALIBRATION_MIN_GRASPS
    calibration_mismatches: int = 0
    calibration_tolerance: float = CALIBRATION_TOLERANCE
    contained_part_tolerance: float | None = None
    last_calibration: StaircaseCalibration | None = dataclass_field(
        default=None, init=False, compare=False
    )
    last_trials: int = dataclass_field(default=0, init=False, compare=False)

    @property
    def __name__(self) -> str:  # recorded in the label metadata
        o = self.options
        search = "full grid"
        if o.staircase:
            rows = o.to_core().staircase_verified_rows()
            search = (
                f"staircase search ({o.staircase_checks} checks, boundary verified in "
                f"{rows} of {o.grid} friction rows)"
            )
        c = self.last_calibration
        if o.staircase and c is not None:
            verdict = "staircase kept" if c.search == "staircase" else f"{c.search} for the rest"
            search += (
                f" calibrated on {c.grasps} full grids ({verdict}: differed on {c.mismatches}, "
                f"mean |error| {c.mean_abs_error:.4f}, 95 % bound {c.error_bound:.4f}, "
                f"tolerance {self.calibration_tolerance:g})"
            )
        cap = "every grasp" if self.max_grasps is None else f"at most {self.max_grasps} grasps"
        return f"Bullet shake test, grid {o.grid}x{o.grid}, {search}, {cap}"

    def __call__(self, mesh: Mesh, labels: Any) -> npt.NDArray[np.float32]:

        n = len(labels)
        out = np.full(n, np.nan, np.float32)
        self.last_calibration = None
        self.last_trials = 0
        if n == 0:
            return out
        if self.max_grasps is not None and self.max_grasps < 1:
            raise InvalidArgumentError(
                f"ShakeScorer.max_grasps: expected >= 1, got {self.max_grasps}"
            )
        for name in ("calibration_grasps", "calibration_min_grasps", "calibration_mismatches"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
                raise InvalidArgumentError(
                    f"ShakeScorer.{name}: expected an integer >= 0, got {value!r}"
                )
        tol = self.calibration_tolerance
        if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not 0 <= tol < 1:
            raise InvalidArgumentError(
                f"ShakeScorer.calibration_tolerance: expected a score error in [0, 1), got {tol!r}"
            )
        ctol = self.contained_part_tolerance
        if ctol is not None and (
            isinstance(ctol, bool) or not isinstance(ctol, (int, float)) or not 0 <= ctol < 1
        ):
            raise InvalidArgumentError(
                "ShakeScorer.contained_part_tolerance: expected a distance in [0, 1) m, "
                f"got {ctol!r}"
            )
        k = n if self.max_grasps is None else min(n, self.max_grasps)
        idx = strided_subset(n, k)
        props = mass_properties(mesh, self.density)
        rows = np.concatenate(
            [
                np.asarray(labels.approach, np.float64)[idx],
                np.asarray(labels.closing, np.float64)[idx],
                np.asarray(labels.p1, np.float64)[idx],
                np.asarray(labels.width, np.float64)[idx, None],
            ],
            axis=1,
        )
        parts = shake_parts(mesh, None if ctol is None else float(ctol))
        progress = sys.stderr.isatty() if self.progress is None else bool(self.progress)
        o = self.options
        score = np.empty(len(rows), np.float32)
        name = getattr(mesh, "name", "") or "object"
        with tqdm(
            total=len(rows), desc=f"physics {name}", unit="grasp", disable=not progress
        ) as bar:

            def run(start: int, stop: int, options: ShakeOptions) -> list[ShakeScores]:
                # Pieces of _PIECE_PER_THREAD grasps per thread with the progress bar (grasp g
                # keeps its random streams through first_grasp_index). The threads share a
                # piece's grasps one at a time, but a piece ends when its slowest grasp does
                # (a grasp costs 17 to S*S trials with the staircase): pieces of 2 grasps per
                # thread kept 2 threads 80-88 % busy on real grasps, 16 keep them ~95 % busy
                # (docs/decisions/0004-shake-thread-scheduling.md). Without it, one call.
                threads = _core.core.resolve_num_threads(int(options.num_threads))
                step = _PIECE_PER_THREAD * threads if progress else max(stop - start, 1)
                pieces = []
                for a in range(start, stop, step):
                    b = min(a + step, stop)
                    piece = shake_scores(
                        parts,
                        props.mass,
                        props.center_of_mass,
                        props.inertia,
                        rows[a:b],
                        self.gripper,
                        replace(options, first_grasp_index=options.first_grasp_index + a),
                    )
                    score[a:b] = piece.score
                    bar.update(b - a)
                    pieces.append(piece)
                    self.last_trials += int(piece.num_trials)
                return pieces

            first = 0
            rest = o
            if o.staircase and self.calibration_grasps > 0:
                first = min(self.calibration_grasps, len(rows))
                full = replace(o, staircase=False)

                def calibrate(grids: npt.NDArray[np.bool_]) -> StaircaseCalibration:
                    return calibrate_staircase(
                        grids,
                        o.staircase_checks,
                        self.calibration_mismatches,
                        o.to_core().staircase_verified_rows(),
                        self.calibration_tolerance,
                    )

                # Two stages: the first calibration_min_grasps full grids, and the rest of the
                # calibration grasps only when the cheapest search is not within the tolerance
                # on those.
                early = first
                if 0 < self.calibration_min_grasps < first:
                    early = self.calibration_min_grasps
                grids = np.concatenate([p.trial_success for p in run(0, early, full)])
                self.last_calibration = calibrate(grids)
                if self.last_calibration.search == "staircase":
                    first = early
                elif early < first:
                    more = [p.trial_success for p in run(early, first, full)]
                    self.last_calibration = calibrate(np.concatenate([grids, *more]))
                rest = search_of(self.last_calibration, o)
            run(first, len(rows), rest)
        out[idx] = score
        return out
