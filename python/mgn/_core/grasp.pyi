"""
mgn/grasp: suction seal, antipodal grasps, shake trials.
"""

from __future__ import annotations

import collections.abc
import typing

import numpy
import numpy.typing

import mgn._core.geometry

__all__: list[str] = [
    "SEAL_FAILURE_NAMES",
    "AntipodalOptions",
    "AntipodalResult",
    "AntipodalSampler",
    "CalibrationResult",
    "ClassificationMetrics",
    "Cup",
    "ParallelJawGripper",
    "PjWrenchOptions",
    "SealModel",
    "SealOptions",
    "SealResult",
    "SealTrial",
    "ShakeOptions",
    "ShakeResult",
    "ShakeTrajectoryResult",
    "StaircaseGridResult",
    "SuctionWrenchOptions",
    "calibrate_cup",
    "classification_metrics",
    "gripper_meshes",
    "hand_poses",
    "pj_wrench_scores",
    "predict_experiments",
    "shake_test",
    "shake_trajectory",
    "staircase_grid",
    "suction_wrench_scores",
]

class SealResult:
    """
    SealModel.evaluate() result (mgn/grasp/seal_model.hpp); mgn.suction.seal.SealResult documents each array.
    """
    @property
    def quality(self) -> numpy.ndarray: ...
    @property
    def reason(self) -> numpy.ndarray: ...
    @property
    def score(self) -> numpy.ndarray: ...
    @property
    def trial_reason(self) -> numpy.ndarray: ...
    @property
    def trial_sealed(self) -> numpy.ndarray: ...

class SealTrial:
    """
    SealModel.trial() result: failure name, projected ring (object frame, m), spring forces (N).
    """
    @property
    def center(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]:
        """
        projected centre, m
        """
    @property
    def elastic_force(self) -> numpy.ndarray:
        """
        (N,) float64, N
        """
    @property
    def failure(self) -> str: ...
    @property
    def ring_force(self) -> numpy.ndarray:
        """
        (N,3) float64, N
        """
    @property
    def ring_normals(self) -> numpy.ndarray:
        """
        (N,3) float32
        """
    @property
    def ring_points(self) -> numpy.ndarray:
        """
        (N,3) float32
        """
    @property
    def total_elastic_force(self) -> float:
        """
        N
        """

class SealOptions:
    """
    Options of SealModel.evaluate (mgn/grasp/seal_model.hpp, SI units); the defaults are the C++ struct's, validate() checks the ranges.
    """
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def angle_sigma(self) -> float:
        """
        std of each Euler angle of the normal perturbation, rad
        """
    @angle_sigma.setter
    def angle_sigma(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def first_index(self) -> int:
        """
        candidate i draws from the stream (seed, first_index + i)
        """
    @first_index.setter
    def first_index(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def num_threads(self) -> int:
        """
        0 = all hardware threads
        """
    @num_threads.setter
    def num_threads(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def num_trials(self) -> int:
        """
        perturbed trials per candidate
        """
    @num_trials.setter
    def num_trials(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def on_surface_tolerance(self) -> float:
        """
        candidates must lie on the mesh within this distance along the normal, m
        """
    @on_surface_tolerance.setter
    def on_surface_tolerance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def perturb(self) -> bool:
        """
        false: one deterministic trial at the nominal pose
        """
    @perturb.setter
    def perturb(self, arg0: bool) -> None: ...
    @property
    def position_sigma(self) -> float:
        """
        std of the point jitter per axis, m (< 0: cup radius / 4)
        """
    @position_sigma.setter
    def position_sigma(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def seed(self) -> int: ...
    @seed.setter
    def seed(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...

class SuctionWrenchOptions:
    """
    Constants of suction_wrench_scores (mgn/grasp/wrench.hpp); the defaults are the C++ struct's, validate() checks the ranges.
    """
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def gravity(self) -> float:
        """
        m/s^2
        """
    @gravity.setter
    def gravity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def k(self) -> float:
        """
        tau_max = k * cup radius * pi * sqrt(2) (k in N, radius in m)
        """
    @k.setter
    def k(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class Cup:
    """
    Suction cup parameters for the seal models (SI units; see mgn.SuctionCup).
    """

    name: str
    def __init__(self) -> None: ...
    def compression_stiffness(self) -> float: ...
    def pressure_force(self) -> float: ...
    def validate(self) -> None: ...
    @property
    def approach_height(self) -> float: ...
    @approach_height.setter
    def approach_height(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def body_height(self) -> float: ...
    @body_height.setter
    def body_height(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def c1(self) -> float: ...
    @c1.setter
    def c1(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def c2(self) -> float: ...
    @c2.setter
    def c2(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def compensable_height(self) -> float: ...
    @compensable_height.setter
    def compensable_height(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def hole_rays(self) -> int: ...
    @hole_rays.setter
    def hole_rays(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def num_points(self) -> int: ...
    @num_points.setter
    def num_points(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def outer_radius(self) -> float: ...
    @outer_radius.setter
    def outer_radius(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def pressure_difference(self) -> float: ...
    @pressure_difference.setter
    def pressure_difference(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def radius(self) -> float: ...
    @radius.setter
    def radius(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def youngs_modulus(self) -> float: ...
    @youngs_modulus.setter
    def youngs_modulus(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class SealModel:
    """
    Immutable seal model of one object for one cup.
    """
    def __init__(self, mesh: mgn._core.geometry.Mesh, cup: Cup, model: str = "spring") -> None: ...
    def evaluate(
        self, points: typing.Any, normals: typing.Any, options: SealOptions = ...
    ) -> SealResult:
        """
        Seal scores of (N,3) candidates (object frame, m; unit outward normals).
        """
    def trial(
        self,
        point: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
        normal: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
    ) -> SealTrial: ...
    def with_cup(self, cup: Cup) -> SealModel: ...
    @property
    def cup(self) -> Cup: ...
    @property
    def model(self) -> str: ...

class ClassificationMetrics:
    """
    Confusion counts and rates (mgn/grasp/calibration.hpp); NaN for a zero denominator.
    """
    def to_dict(self) -> dict:
        """
        {name: value} of the fields above, for JSON.
        """
    @property
    def accuracy(self) -> float:
        """
        (tp + tn) / count
        """
    @property
    def fn(self) -> int: ...
    @property
    def fp(self) -> int: ...
    @property
    def npv(self) -> float:
        """
        tn / (tn + fn)
        """
    @property
    def ppv(self) -> float:
        """
        tp / (tp + fp), precision
        """
    @property
    def sensitivity(self) -> float:
        """
        tp / (tp + fn)
        """
    @property
    def specificity(self) -> float:
        """
        tn / (tn + fp)
        """
    @property
    def tn(self) -> int: ...
    @property
    def tp(self) -> int: ...

class CalibrationResult:
    """
    calibrate_cup() result (mgn/grasp/calibration.hpp).
    """
    @property
    def cup(self) -> Cup:
        """
        the initial cup with the fitted c1, c2
        """
    @property
    def evaluations(self) -> int: ...
    @property
    def objective(self) -> float:
        """
        training accuracy of the fitted cup
        """
    @property
    def predicted(self) -> numpy.ndarray:
        """
        (N,) bool nominal prediction of the fitted cup
        """
    @property
    def test(self) -> ClassificationMetrics: ...
    @property
    def test_indices(self) -> numpy.ndarray:
        """
        (H,) int64 ascending
        """
    @property
    def train(self) -> ClassificationMetrics: ...
    @property
    def train_indices(self) -> numpy.ndarray:
        """
        (T,) int64 ascending
        """

class AntipodalResult:
    """
    AntipodalSampler.sample() result (mgn/grasp/antipodal.hpp); mgn.pj.sampler.AntipodalResult documents each array.
    """
    @property
    def approach(self) -> numpy.ndarray: ...
    @property
    def closing(self) -> numpy.ndarray: ...
    @property
    def num_accepted_probes(self) -> int: ...
    @property
    def num_colliding(self) -> int: ...
    @property
    def num_kept(self) -> numpy.ndarray: ...
    @property
    def p1(self) -> numpy.ndarray: ...
    @property
    def point_index(self) -> numpy.ndarray: ...
    @property
    def point_score(self) -> numpy.ndarray: ...
    @property
    def probe(self) -> numpy.ndarray: ...
    @property
    def score(self) -> numpy.ndarray: ...
    @property
    def width(self) -> numpy.ndarray: ...

class AntipodalOptions:
    """
    Options of AntipodalSampler.sample (mgn/grasp/antipodal.hpp, SI units); the defaults are the C++ struct's (MetaGraspNet), validate() checks the ranges.
    """
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def approaches_kept(self) -> int:
        """
        collision-free approaches kept per accepted probe
        """
    @approaches_kept.setter
    def approaches_kept(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def approaches_tried(self) -> int:
        """
        random approach directions tried per accepted probe
        """
    @approaches_tried.setter
    def approaches_tried(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def check_collision(self) -> bool:
        """
        false: keep the first approaches_kept approaches unchecked
        """
    @check_collision.setter
    def check_collision(self, arg0: bool) -> None: ...
    @property
    def first_index(self) -> int:
        """
        point i uses the random stream (seed, first_index + i)
        """
    @first_index.setter
    def first_index(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def friction_coef(self) -> float:
        """
        mu; friction cone half-angle atan(mu)
        """
    @friction_coef.setter
    def friction_coef(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def num_threads(self) -> int:
        """
        0 = all hardware threads
        """
    @num_threads.setter
    def num_threads(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def offset(self) -> float:
        """
        bound of the start offset per axis, m
        """
    @offset.setter
    def offset(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def probes(self) -> int:
        """
        perturbed probes per contact point
        """
    @probes.setter
    def probes(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def seed(self) -> int: ...
    @seed.setter
    def seed(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def start_offset(self) -> float:
        """
        the probe ray starts this far outside the surface, m
        """
    @start_offset.setter
    def start_offset(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def tilt(self) -> float:
        """
        bound of each Euler angle of the probe tilt, rad
        """
    @tilt.setter
    def tilt(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class PjWrenchOptions:
    """
    Constants of pj_wrench_scores (mgn/grasp/pj_wrench.hpp, SI units); the defaults are the C++ struct's, validate() checks the ranges.
    """
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def contact_radius(self) -> float:
        """
        radius of the soft contact patch, m
        """
    @contact_radius.setter
    def contact_radius(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def friction(self) -> float:
        """
        mu between finger pads and object
        """
    @friction.setter
    def friction(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def gravity(self) -> float:
        """
        m/s^2
        """
    @gravity.setter
    def gravity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def grip_force(self) -> float:
        """
        normal force per finger, N
        """
    @grip_force.setter
    def grip_force(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class ParallelJawGripper:
    """
    Parallel-jaw gripper (SI units; see mgn.hardware.ParallelJawGripper). Box gripper unless palm_mesh, finger_left_mesh and finger_right_mesh are all set (closed, hand frame, fingers at opening 0).
    """

    finger_left_mesh: mgn._core.geometry.Mesh
    finger_right_mesh: mgn._core.geometry.Mesh
    name: str
    palm_mesh: mgn._core.geometry.Mesh
    def __init__(self) -> None: ...
    def collision_opening(self, width: typing.SupportsFloat | typing.SupportsIndex) -> float: ...
    def grasp_depth(self) -> float: ...
    def has_meshes(self) -> bool: ...
    def validate(self) -> None: ...
    @property
    def collision_margin(self) -> float: ...
    @collision_margin.setter
    def collision_margin(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def contact_from_tip(self) -> float: ...
    @contact_from_tip.setter
    def contact_from_tip(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def finger_size(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]: ...
    @finger_size.setter
    def finger_size(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"]
    ) -> None: ...
    @property
    def flange_to_tip(self) -> float: ...
    @flange_to_tip.setter
    def flange_to_tip(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def friction(self) -> float: ...
    @friction.setter
    def friction(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def max_opening(self) -> float: ...
    @max_opening.setter
    def max_opening(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def palm_size(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]: ...
    @palm_size.setter
    def palm_size(
        self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"]
    ) -> None: ...

class AntipodalSampler:
    """
    Immutable antipodal grasp sampler of one object for one gripper.
    """
    def __init__(self, mesh: mgn._core.geometry.Mesh, gripper: ParallelJawGripper) -> None: ...
    def collides(
        self, X_OH: typing.Any, opening: typing.SupportsFloat | typing.SupportsIndex
    ) -> bool: ...
    def sample(
        self, points: typing.Any, normals: typing.Any, options: AntipodalOptions = ...
    ) -> AntipodalResult:
        """
        Antipodal grasps from (N,3) contact points and unit outward normals (object frame, m).
        """
    @property
    def gripper(self) -> ParallelJawGripper: ...

class ShakeOptions:
    """
    Options of the Bullet shake test (SI units; see mgn.pj.physics).
    """

    adapt_controller_gain: bool
    controller_net_force: bool
    limit_controller_gain: bool
    polyhedral_contacts: bool
    smooth_shake: bool
    staircase: bool
    def __init__(self) -> None: ...
    def density_factors(self) -> list[float]: ...
    def frictions(self) -> list[float]: ...
    def staircase_verified_rows(self) -> int:
        """
        Rows whose boundary the staircase verifies: ceil(staircase_verify_share * grid).
        """
    def validate(self) -> None: ...
    @property
    def angle_max(self) -> float: ...
    @angle_max.setter
    def angle_max(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def angle_min(self) -> float: ...
    @angle_min.setter
    def angle_min(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def close_speed(self) -> float: ...
    @close_speed.setter
    def close_speed(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def close_steps(self) -> int: ...
    @close_steps.setter
    def close_steps(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def compound_iteration_points(self) -> float: ...
    @compound_iteration_points.setter
    def compound_iteration_points(
        self, arg0: typing.SupportsFloat | typing.SupportsIndex
    ) -> None: ...
    @property
    def compound_solver_iterations(self) -> int: ...
    @compound_solver_iterations.setter
    def compound_solver_iterations(
        self, arg0: typing.SupportsInt | typing.SupportsIndex
    ) -> None: ...
    @property
    def contact_distance(self) -> float: ...
    @contact_distance.setter
    def contact_distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def controller_stiffness(self) -> float: ...
    @controller_stiffness.setter
    def controller_stiffness(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def density_max(self) -> float: ...
    @density_max.setter
    def density_max(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def density_min(self) -> float: ...
    @density_min.setter
    def density_min(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def dt(self) -> float: ...
    @dt.setter
    def dt(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def first_grasp_index(self) -> int: ...
    @first_grasp_index.setter
    def first_grasp_index(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def friction_max(self) -> float: ...
    @friction_max.setter
    def friction_max(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def friction_min(self) -> float: ...
    @friction_min.setter
    def friction_min(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def gravity(self) -> float: ...
    @gravity.setter
    def gravity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def grid(self) -> int: ...
    @grid.setter
    def grid(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def grip_force(self) -> float: ...
    @grip_force.setter
    def grip_force(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def hold_tolerance(self) -> float: ...
    @hold_tolerance.setter
    def hold_tolerance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def inertia_floor(self) -> float: ...
    @inertia_floor.setter
    def inertia_floor(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def iterations_per_hull_contact(self) -> float: ...
    @iterations_per_hull_contact.setter
    def iterations_per_hull_contact(
        self, arg0: typing.SupportsFloat | typing.SupportsIndex
    ) -> None: ...
    @property
    def lost_contact_steps(self) -> int: ...
    @lost_contact_steps.setter
    def lost_contact_steps(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def margin(self) -> float: ...
    @margin.setter
    def margin(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def max_hull_vertices(self) -> int: ...
    @max_hull_vertices.setter
    def max_hull_vertices(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def num_threads(self) -> int: ...
    @num_threads.setter
    def num_threads(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def pad_damping(self) -> float: ...
    @pad_damping.setter
    def pad_damping(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def pad_stiffness(self) -> float: ...
    @pad_stiffness.setter
    def pad_stiffness(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def rotate_cycles(self) -> int: ...
    @rotate_cycles.setter
    def rotate_cycles(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def rotate_steps(self) -> int: ...
    @rotate_steps.setter
    def rotate_steps(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def seed(self) -> int: ...
    @seed.setter
    def seed(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def settle_steps(self) -> int: ...
    @settle_steps.setter
    def settle_steps(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def shake_cycles(self) -> int: ...
    @shake_cycles.setter
    def shake_cycles(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def shake_speed(self) -> float: ...
    @shake_speed.setter
    def shake_speed(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def shake_steps(self) -> int: ...
    @shake_steps.setter
    def shake_steps(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def solver_iterations(self) -> int: ...
    @solver_iterations.setter
    def solver_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def staircase_checks(self) -> int: ...
    @staircase_checks.setter
    def staircase_checks(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def staircase_verify_share(self) -> float: ...
    @staircase_verify_share.setter
    def staircase_verify_share(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class ShakeResult:
    """
    shake_test() result (mgn/grasp/shake_trial.hpp): G grasps on an S x S friction x density grid.
    """
    @property
    def density_factors(self) -> numpy.ndarray:
        """
        (S,) density factors
        """
    @property
    def fallback(self) -> numpy.ndarray:
        """
        (G,) bool: a staircase check failed and the full grid was simulated
        """
    @property
    def frictions(self) -> numpy.ndarray:
        """
        (S,) friction coefficients
        """
    @property
    def score(self) -> numpy.ndarray:
        """
        (G,) float64 success fraction over the grid
        """
    @property
    def total_steps(self) -> int:
        """
        simulation steps of all trials
        """
    @property
    def trial_ended_early(self) -> numpy.ndarray:
        """
        (G, S, S) bool
        """
    @property
    def trial_simulated(self) -> numpy.ndarray:
        """
        (G, S, S) bool: simulated (else inferred by the staircase search)
        """
    @property
    def trial_steps(self) -> numpy.ndarray:
        """
        (G, S, S) int steps simulated
        """
    @property
    def trial_success(self) -> numpy.ndarray:
        """
        (G, S, S) bool [grasp][friction i][density j]
        """

class StaircaseGridResult:
    """
    staircase_grid() result: success and simulated (S, S) bool [friction i][density j], fallback, trials.
    """
    @property
    def fallback(self) -> bool:
        """
        a check contradicted its inference: every cell was simulated
        """
    @property
    def simulated(self) -> numpy.ndarray:
        """
        (S, S) bool: trial() was called
        """
    @property
    def success(self) -> numpy.ndarray:
        """
        (S, S) bool
        """
    @property
    def trials(self) -> int:
        """
        calls of trial()
        """

class ShakeTrajectoryResult:
    """
    shake_trajectory() result, one row per recorded step (world W: z up; poses (K, 4, 4) m).
    """
    @property
    def X_WH(self) -> numpy.ndarray:
        """
        (K, 4, 4) hand pose
        """
    @property
    def X_WO(self) -> numpy.ndarray:
        """
        (K, 4, 4) object pose
        """
    @property
    def contact_left(self) -> numpy.ndarray:
        """
        (K,) bool
        """
    @property
    def contact_right(self) -> numpy.ndarray:
        """
        (K,) bool
        """
    @property
    def density_factor(self) -> float: ...
    @property
    def ended_early(self) -> bool: ...
    @property
    def finger_left(self) -> numpy.ndarray:
        """
        (K,) finger opening, m
        """
    @property
    def finger_right(self) -> numpy.ndarray:
        """
        (K,) finger opening, m
        """
    @property
    def force_left(self) -> numpy.ndarray:
        """
        (K,) normal force of the -x pad over the last step, N
        """
    @property
    def force_right(self) -> numpy.ndarray:
        """
        (K,) normal force of the +x pad over the last step, N
        """
    @property
    def friction(self) -> float: ...
    @property
    def phase(self) -> numpy.ndarray:
        """
        (K,) int8 ShakePhase
        """
    @property
    def steps(self) -> int: ...
    @property
    def success(self) -> bool: ...
    @property
    def time(self) -> numpy.ndarray:
        """
        (K,) s since the start
        """

def calibrate_cup(
    surfaces: collections.abc.Sequence[mgn._core.geometry.Mesh],
    surface_index: typing.Any,
    points: typing.Any,
    normals: typing.Any,
    sealed: typing.Any,
    cup: Cup,
    c1_min: typing.SupportsFloat | typing.SupportsIndex = 0.001,
    c1_max: typing.SupportsFloat | typing.SupportsIndex = 1.0,
    c2_min: typing.SupportsFloat | typing.SupportsIndex = 0.001,
    c2_max: typing.SupportsFloat | typing.SupportsIndex = 1.0,
    global_evaluations: typing.SupportsInt | typing.SupportsIndex = 200,
    local_evaluations: typing.SupportsInt | typing.SupportsIndex = 100,
    xtol_rel: typing.SupportsFloat | typing.SupportsIndex = 0.0001,
    ftol_abs: typing.SupportsFloat | typing.SupportsIndex = 1e-09,
    holdout_fraction: typing.SupportsFloat | typing.SupportsIndex = 0.3,
    seed: typing.SupportsInt | typing.SupportsIndex = 0,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> CalibrationResult:
    """
    Fit c1, c2 of the cup to measured outcomes (see mgn.calibration.fit).
    """

def classification_metrics(
    predicted: collections.abc.Sequence[bool], measured: collections.abc.Sequence[bool]
) -> ClassificationMetrics:
    """
    Confusion counts and PPV, NPV, sensitivity, specificity, accuracy (NaN for a zero denominator).
    """

def gripper_meshes(
    gripper: ParallelJawGripper, opening: typing.SupportsFloat | typing.SupportsIndex
) -> tuple[mgn._core.geometry.Mesh, mgn._core.geometry.Mesh, mgn._core.geometry.Mesh]:
    """
    (palm, finger_left, finger_right) closed meshes in the hand frame at an opening (m).
    """

def hand_poses(
    p1: typing.Any,
    closing: typing.Any,
    approach: typing.Any,
    width: typing.Any,
    gripper: ParallelJawGripper,
) -> numpy.ndarray:
    """
    (N,4,4) hand (flange) poses X_OH of grasps in the object frame.
    """

def pj_wrench_scores(
    p1: typing.Any,
    closing: typing.Any,
    width: typing.Any,
    mass: typing.SupportsFloat | typing.SupportsIndex,
    com: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
    gravity_direction: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
    options: PjWrenchOptions = ...,
) -> numpy.ndarray: ...
def predict_experiments(
    surfaces: collections.abc.Sequence[mgn._core.geometry.Mesh],
    surface_index: typing.Any,
    points: typing.Any,
    normals: typing.Any,
    cup: Cup,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> numpy.ndarray:
    """
    Nominal spring-model seal prediction (bool per experiment) for a cup.
    """

def shake_test(
    parts: collections.abc.Sequence[mgn._core.geometry.Mesh],
    mass: typing.SupportsFloat | typing.SupportsIndex,
    com: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
    inertia: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 3]"],
    grasps: typing.Any,
    gripper: ParallelJawGripper,
    options: ShakeOptions,
) -> ShakeResult:
    """
    Shake test of (N, 10) grasps [a, v, p1, w] (m); a ShakeResult (GIL released).
    """

def shake_trajectory(
    parts: collections.abc.Sequence[mgn._core.geometry.Mesh],
    mass: typing.SupportsFloat | typing.SupportsIndex,
    com: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
    inertia: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 3]"],
    grasp: typing.Any,
    gripper: ParallelJawGripper,
    friction: typing.SupportsFloat | typing.SupportsIndex,
    density_factor: typing.SupportsFloat | typing.SupportsIndex,
    options: ShakeOptions,
    record_every: typing.SupportsInt | typing.SupportsIndex = 5,
    trial_index: typing.SupportsInt | typing.SupportsIndex = 0,
) -> ShakeTrajectoryResult:
    """
    One recorded shake trial (poses in the world W: z up, gravity -z).
    """

def staircase_grid(
    S: typing.SupportsInt | typing.SupportsIndex,
    trial: collections.abc.Callable[[int, int], bool],
    checks: typing.SupportsInt | typing.SupportsIndex,
    verified_rows: typing.SupportsInt | typing.SupportsIndex = -1,
) -> StaircaseGridResult:
    """
    The staircase search of shake_test on an S x S grid: trial(i, j) -> bool is called for the cells it simulates (friction index i, density index j); the boundary is verified in rows i < verified_rows (-1: every row); a StaircaseGridResult.
    """

def suction_wrench_scores(
    contacts: typing.Any,
    approach: typing.Any,
    mass: typing.SupportsFloat | typing.SupportsIndex,
    com: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
    gravity_direction: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"],
    cup_radius: typing.SupportsFloat | typing.SupportsIndex,
    options: SuctionWrenchOptions = ...,
) -> numpy.ndarray: ...

SEAL_FAILURE_NAMES: tuple = (
    "none",
    "miss",
    "obstruction",
    "hill",
    "hole",
    "force",
    "strain",
    "rough",
)
