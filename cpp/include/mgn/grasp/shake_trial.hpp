#pragma once
/// @file shake_trial.hpp  Physics score of parallel-jaw grasps: the Bullet shake test
/// (docs/models.md §5, "Physics score").
///
/// One trial = one grasp × one (friction, density factor) setting: the object is placed in the
/// open gripper, gravity off; the fingers close at a set speed until they touch, then a force
/// controller holds the pad force at grip_force (fingers symmetric about the hand axis, like a
/// Franka hand; soft pads, see ShakeOptions); then,
/// with gravity on, the hand translates back and forth along its approach axis and then rotates
/// back and forth about an axis perpendicular to it through the grasp centre. The trial succeeds
/// if both fingers still touch the object at the end. The score of a grasp is the success
/// fraction over the S×S grid of settings.
///
/// A gripper given by meshes (ParallelJawGripper::has_meshes()) is simulated as the convex hulls
/// of its palm and finger meshes; otherwise as its boxes.
///
/// Frames: O = object (the frame of the convex parts and of the grasps); H = hand (flange) frame
/// of gripper.hpp (z = approach, x = closing); W = simulation world, z up, gravity −z, with the
/// hand initially at the origin pointing down: X_WH(0) = rotation of π about x. Units SI.
///
/// Deviations from MetaGraspNet's step counts (defaults; every one can be switched off):
///  - closing ends once both fingers touch the object at the grip force for `settle_steps`
///    steps, instead of always running `close_steps` (= 400) steps;
///  - a trial ends early, as a failure, once the object has lost contact with a finger for
///    `lost_contact_steps` consecutive steps, or (closing) once the fingers closed on nothing
///    (it cannot become a success by then in all but rare bounces; tests and
///    benchmarks/bench_shake.py measure the agreement with the full step counts).
///  - a trial skips the translational cycles after the first, and ends early as a success
///    before the last quarter of the rotational shake, once the rest of the phase only repeats
///    loads the object has held without moving (ShakeOptions::hold_tolerance; 0 = off);
///  - small rotational inertia is raised to a floor (ShakeOptions::inertia_floor) for solver
///    stability; the test measures how little it changes outcomes where both are stable.
/// The exact shake profiles are mgn's (smooth sinusoids, see ShakeOptions), as MetaGraspNet
/// does not publish its controller gains.

#include <mgn/core/types.hpp>
#include <mgn/geometry/mesh.hpp>
#include <mgn/grasp/gripper.hpp>
#include <mgn/physics/rigid_object.hpp>

#include <cstdint>
#include <functional>
#include <vector>

namespace mgn {

/// The object to shake: its convex parts and rigid-body properties at density factor 1 (mass,
/// com, inertia; friction and restitution are not used: the friction comes from the grid). One
/// type with the drop's objects (see mgn/physics/rigid_object.hpp for the fields and defaults).
using PhysicsObject = RigidObject;

/// Parameters of the shake test. Defaults: MetaGraspNet where it publishes a value (grid, ranges,
/// the phases' durations 2 s / 2 s / 1.5 s, 0.5 m/s, 0.2–0.3 rad), otherwise mgn's choice. The
/// step is half MetaGraspNet's 1/200 s (every step count doubled, so the durations are its): at
/// 1/200 s Bullet's solver drops light objects and lets round ones slip that a finer step holds,
/// and a grasp's score differs from the converged simulation's by up to 0.05 on average per
/// object; at 1/400 s by ~0.01, the physics' own noise
/// (docs/decisions/0055-shake-time-step-1-400.md).
struct ShakeOptions {
  int grid = 10;              ///< S: S×S settings per grasp, >= 1
  double friction_min = 0.5;  ///< Coulomb friction of the finger–object contact, >= 0
  double friction_max = 2.0;  ///< friction values = linspace(min, max, S)
  double density_min = 0.25;  ///< density (mass) factor, > 0
  double density_max = 1.0;   ///< factors = linspace(min, max, S)
  double dt = 1.0 / 400.0;    ///< simulation step, s
  int close_steps = 800;      ///< maximum steps of the closing phase (gravity off)
  int shake_steps = 800;      ///< translational shake steps
  int rotate_steps = 600;     ///< rotational shake steps
  double gravity = 9.81;      ///< m/s², along −z of W (on during the shake phases)
  /// Translational shake: hand offset s(t) = A sin(2π n t / T) along its approach axis, with n =
  /// shake_cycles, T = shake_steps·dt and A chosen so that the peak speed is shake_speed.
  double shake_speed = 0.5;  ///< m/s
  int shake_cycles = 2;      ///< full back-and-forth cycles, >= 1
  /// Rotational shake: angle θ(t) = θ_max sin(2π n t / T) about an axis ⟂ approach through the
  /// grasp centre, n = rotate_cycles, T = rotate_steps·dt; θ_max ~ U(angle_min, angle_max) and
  /// the axis direction ~ U(0, 2π) in the hand's xy plane, drawn per trial from Rng(seed, trial).
  double angle_min = 0.2;    ///< rad
  double angle_max = 0.3;    ///< rad
  int rotate_cycles = 1;     ///< >= 1
  double grip_force = 20.0;  ///< normal force each finger pad presses with, N, > 0
  double close_speed = 0.1;  ///< finger speed limit (closing and force control), m/s, > 0
  /// Finger pads are soft: Bullet's implicit contact stiffness per contact point (N/m) and
  /// damping (N s/m). They make the squeeze force well defined (a pad sinks ~F/(n·k)).
  double pad_stiffness = 1e4;
  double pad_damping = 20.0;
  /// Force controller: the fingers move by (mean pad force − grip_force)/controller_stiffness
  /// per 1/400 s of simulated time (N/m, > 0; larger = gentler), limited to close_speed: a step
  /// dt moves them by (dt · 400 s⁻¹) times that, so the closing's dynamics in time do not depend
  /// on dt (at dt = 1/400 s, one step moves them by the error over controller_stiffness).
  double controller_stiffness = 1e5;
  /// Keep the force controller stable on many contact points: the per-step stiffness
  /// K = controller_stiffness / (dt · 400 s⁻¹) is raised to at least
  /// n·(pad_stiffness + pad_damping/dt), n = the mean number of contact points closer than
  /// contact_distance per pad (how much the mean pad force changes in one step when the fingers
  /// move). Without it the controller's force error e obeys
  /// e[k+1] = (1 − α − β) e[k] + β e[k−1] (α = n·pad_stiffness/K, β = n·pad_damping/(dt·K)),
  /// which diverges into a period-2 force oscillation of tens of N once α + 2β > 2 (n > 7.7 at
  /// the defaults: compounds held by several hulls), and the closing then never settles.
  /// Changes nothing while n <= 5.5 at dt = 1/400 s (one hull touches a pad with at most 4
  /// points).
  bool limit_controller_gain = true;
  /// Keep the force controller stable whatever stiffness the solver's contacts present: when
  /// the controller's force error e (mean pad force − grip_force, at steps where a finger
  /// touches) has flipped sign on 4 consecutive steps, each time without shrinking to half
  /// (|e[k]| >= |e[k−1]|/2) and at least grip_force/4 on both steps, the controller's stiffness
  /// is doubled for the rest of the trial (at most 64x). That is a sustained period-2
  /// oscillation, a loop gain at or above 2, which limit_controller_gain's model
  /// n·(pad_stiffness + pad_damping/dt) does not foresee: at some iteration counts
  /// (compound_solver_iterations 20-40 on light compounds pressed face-on at 8 points per pad)
  /// Bullet's sequential-impulse solver answers a finger move up to ~2x as stiffly, and the
  /// closing then oscillates by tens of N and never settles. Changes nothing in a trial whose
  /// errors never flip like that (docs/decisions/0068-adaptive-controller-gain.md).
  bool adapt_controller_gain = true;
  /// The pad force the controller and the closing's settle test read. true (default): the net
  /// contact force on the finger along its opening direction (the force that resists closing),
  /// so the forces on a finger wedged in a concavity (a finger inside a pipe's bore, touching
  /// the wall on both faces) cancel as they do for a real gripper's motor, instead of reading
  /// as grip force while the other finger has not reached the object. false: the sum of the
  /// normal forces of every contact point of the finger, whatever face of it touches (the same
  /// reading on a pad pressed face-on against the object).
  bool controller_net_force = true;
  /// Inertia floor: every principal moment is raised to at least m·(inertia_floor·R)², R = the
  /// largest distance of a hull vertex from the centre of mass (0 = exact inertia). Bullet's
  /// sequential-impulse solver spins up small, light objects squeezed by a large grip force
  /// when their inertia is below m R² (the impulse at a contact turns them more than it moves
  /// them); friction and gravity torques, which decide the test, do not depend on inertia.
  double inertia_floor = 1.0;
  double contact_distance = 1e-3;  ///< a finger "touches" if a contact point is closer, m
  /// Closing ends when both fingers touch and the mean pad force has been within 5 % of
  /// grip_force for this many steps (0 = always run close_steps).
  int settle_steps = 20;
  /// A shake trial ends (as a failure) once a finger has not touched the object for this many
  /// consecutive steps (0 = never end early).
  int lost_contact_steps = 20;
  /// Held-load windows, m (0 = off: the full schedule). Translation: if the object's pose in
  /// the hand frame stays within this distance (a rotation counts as its angle × the object's
  /// bounding radius) of its pose at t = T/(4n) through t = T/n (the first cycle's extremes of
  /// the acceleration) and both fingers touch, the hand skips to the end of the translation (the
  /// later cycles repeat those loads; same pose and velocity there). Rotation: if it stays
  /// within it from the last zero crossing of θ (t = T − T/(2n)) to the last extreme
  /// (t = T − T/(4n)) and both fingers touch, the trial ends there as a success: the rest, θ going
  /// back from ±θ_max to 0, repeats the loads of that window mirrored in time (same tilt, same
  /// hand accelerations, opposite angular velocity), so an object the window did not move is
  /// not moved by the rest.
  /// Simulated objects are seldom exactly at rest in the hand (they slip at the velocity jump
  /// that starts the shake and creep), so the tolerance decides how often the windows apply.
  /// In [0, 0.1) m; default 3 mm, which changes no more outcomes than the physics' own noise
  /// (docs/decisions/0007-shake-held-load-windows.md). Has no effect with smooth_shake (its
  /// windows assume the sine profile).
  double hold_tolerance = 3e-3;
  /// Shake profile. false (default, MetaGraspNet's schedule): the hand follows z = A sin(ωt)
  /// along its approach axis and θ = θ_max sin(ω_r t) about the trial's axis, so each phase
  /// starts and ends at full speed (a velocity jump within one step). true: both follow
  /// f(x) = sin x − sin(2x)/2 (zero velocity at the start and end of every cycle), with the
  /// translation's amplitude halved so the peak speed stays `shake_speed` and the rotation
  /// scaled by 4/(3√3) so the peak angle stays θ_max; scores move by ~0.01 on average
  /// (docs/decisions/0006-shake-smooth-profile.md). hold_tolerance has no effect with it.
  bool smooth_shake = false;
  double margin = 5e-4;  ///< Bullet collision margin of every shape, m, > 0
  /// Bullet's polyhedral clipping (a full contact patch per step) instead of GJK points
  /// gathered over steps; on by default (the scores of mgn's datasets). GJK points are
  /// 1.2-1.5x faster per trial but change some scores
  /// (docs/decisions/0002-shake-contacts-and-shapes.md; benchmarks/bench_shake.py measures both).
  bool polyhedral_contacts = true;
  /// Hulls with more vertices are replaced by the hull of their support points along this many
  /// well-spread directions (an inner approximation; V-HACD's usual cap is 64), >= 8.
  int max_hull_vertices = 64;
  /// Bullet sequential-impulse iterations, >= 1; multiplied by ceil(grip_force / (150 m g))
  /// (at most 8) for light objects, which the solver otherwise lets spin out of the grip.
  int solver_iterations = 10;
  /// Solver iterations of an object whose shake shape has more than one convex part (a
  /// compound), used instead of solver_iterations (and multiplied alike for light objects);
  /// 0 = the same as solver_iterations. In [0, 1000], default 40. The sequential-impulse solver
  /// leaves the friction of a pad touching several hulls unconverged at 10 iterations, which
  /// lets some compounds creep out of a grip that holds them
  /// (docs/decisions/0064-compound-solver-iterations.md,
  /// docs/decisions/0068-adaptive-controller-gain.md). compound_iteration_points bounds what
  /// they cost.
  int compound_solver_iterations = 40;
  /// Contact points of a compound's iteration budget (0 = off): a step of a compound whose
  /// fingers touched it at n > this many points at the previous step (points closer than
  /// contact_distance, both fingers together) runs ceil(compound_solver_iterations × this / n)
  /// iterations instead of compound_solver_iterations, at least solver_iterations (both times
  /// the light-object multiplier), so a step's solver work stays about that of
  /// compound_solver_iterations on this many points (each point is three solver rows). A hex nut
  /// pressed face-on across 7 hulls per pad touches at ~50 points; it holds with 10 iterations as
  /// with 40, which cost it 1.9x the CPU per trial. The compounds whose scores 40 iterations move
  /// touch at 10-14 points on average. In [0, 10000], default 24
  /// (docs/decisions/0070-compound-iteration-budget.md).
  double compound_iteration_points = 24.0;
  /// Iterations per hull contact (0 = off): each step runs at least ceil(this × the number of
  /// (finger, object hull) pairs in contact at the previous step) iterations. A single hull
  /// makes at most 2 pairs, so with this <= solver_iterations / 2 it is simulated as without;
  /// an object held by several hulls of a compound gets more iterations, which its solve needs
  /// to converge at a coarser dt (docs/decisions/0005-shake-time-step.md). >= 0.
  double iterations_per_hull_contact = 0.0;
  /// Staircase search instead of the full grid: success is monotone wherever physics behaves
  /// (more friction helps, more mass hurts), so each grasp's success boundary is found by
  /// galloping and bisection row by row (see staircase_grid()), the cells on both sides of it
  /// are verified, plus `staircase_checks` other inferred cells spread over the grid; if one of
  /// them contradicts the inference the grasp falls back to the full grid. Every simulated cell
  /// uses the same trial (index, random stream) as the full grid. The shake outcomes of real
  /// grasps are not exactly monotone (isolated failures anywhere in the grid), so more checks
  /// buy agreement with trials (docs/decisions/0003-shake-staircase-search.md). Default off.
  bool staircase = false;
  int staircase_checks = 6;  ///< >= 0
  /// Share of the grid's rows, lowest frictions first, whose boundary cells the staircase
  /// verifies (rows i < ceil(share·S); 1 = every row, the default; 0 = none, the walk alone).
  /// The isolated failing cells of real grasps sit where the grip is marginal, at low friction
  /// and high mass; mgn.pj.ShakeScorer verifies the lower half (0.5) when its object-level
  /// calibration is on (docs/decisions/0009-shake-calibrated-checks.md). In [0, 1].
  double staircase_verify_share = 1.0;
  /// 0 = all hardware threads; results do not depend on it. The threads take grasps (staircase)
  /// or trials (full grid) one at a time, as a grasp costs ~17 to S² trials.
  int num_threads = 0;
  std::uint64_t seed = 0;  ///< seed of the per-trial random streams
  /// Index of the first grasp in a larger list: grasp g of this call uses the random streams of
  /// grasp first_grasp_index + g, so scoring a list in consecutive pieces gives the same scores
  /// as scoring it whole (used to report progress).
  std::uint64_t first_grasp_index = 0;

  /// Throws InvalidArgument naming the first invalid field.
  void validate() const;
  /// Rows whose boundary the staircase verifies: ceil(staircase_verify_share · grid).
  int staircase_verified_rows() const;
  /// The S friction values, linspace(friction_min, friction_max, grid).
  std::vector<double> frictions() const;
  /// The S density factors, linspace(density_min, density_max, grid).
  std::vector<double> density_factors() const;
};

/// Scores of a batch of grasps. Trial t = g·S² + i·S + j uses friction i and density factor j.
struct ShakeResult {
  int grid = 0;                                 ///< S
  std::vector<double> score;                    ///< (G) success fraction per grasp, in [0, 1]
  std::vector<std::uint8_t> trial_success;      ///< (G·S²) 1 if both fingers touch at the end
  std::vector<std::uint8_t> trial_ended_early;  ///< (G·S²) 1 if a shortcut ended the trial early
  std::vector<std::int32_t> trial_steps;        ///< (G·S²) simulation steps run
  std::vector<double> frictions;                ///< (S)
  std::vector<double> density_factors;          ///< (S)
  std::int64_t total_steps = 0;                 ///< sum of trial_steps
  /// (G·S²) 1 if the trial was simulated, 0 if its outcome was inferred (staircase only; the
  /// full grid simulates every trial).
  std::vector<std::uint8_t> trial_simulated;
  std::vector<std::uint8_t> fallback;  ///< (G) 1 if the staircase fell back to the full grid
};

/// Outcome of staircase_grid().
struct StaircaseGrid {
  std::vector<std::uint8_t> success;    ///< (S·S) row-major [friction i][density j]
  std::vector<std::uint8_t> simulated;  ///< (S·S) 1 where `trial` was called
  bool fallback = false;                ///< a check failed: every cell was simulated
  int trials = 0;                       ///< calls of `trial`
};

/// Success over an S×S grid whose success is assumed monotone: non-decreasing in the friction
/// index i and non-increasing in the density index j, so row i succeeds exactly for j < b[i]
/// with b non-decreasing. The walk finds b row by row (i = 0..S-1) from the lower bound b[i-1]:
/// row 0 first probes its hardest cell (0, S-1), which settles a grid that succeeds everywhere
/// with one trial; then each row probes the cell at its lower bound and gallops right (offsets
/// 0, 1, 3, 7, ...) and bisects the last gap; a row whose lower bound is S costs nothing. Cells
/// left of b[i] are inferred successes, the others inferred failures. Verification: in every row
/// i < verified_rows (the lowest frictions; -1, the default, or more than S: every row) the
/// inferred cell nearest to the boundary on each side (the last success b[i]-1, or b[i]-2
/// where the walk simulated b[i]-1; the first failure b[i], or b[i]+1), then the first `checks`
/// other inferred cells in a golden-ratio (low-discrepancy) order are simulated; if any
/// contradicts its inference, every remaining cell is simulated (fallback), so the result is
/// then exact. With checks >= S·S every cell is verified. Trials without fallback, all rows
/// verified: at most 39 + checks for S = 10 (every monotone 10×10 grid enumerated), S + 1 +
/// checks for a grid that succeeds everywhere (verified_rows + 1 + checks with fewer rows).
/// `trial(i, j)` runs one trial, never twice for a cell. Deterministic. Throws InvalidArgument for
/// S < 1 or checks < 0.
StaircaseGrid staircase_grid(int S, const std::function<bool(int, int)>& trial, int checks,
                             int verified_rows = -1);

/// Phases of a trial (ShakeTrajectory::phase).
enum class ShakePhase : std::int8_t { Close = 0, Translate = 1, Rotate = 2 };

/// A recorded trial for visualisation: one entry per recorded step (the initial state, every
/// `record_every`-th step and the last step).
struct ShakeTrajectory {
  std::vector<double> time;        ///< s since the start
  std::vector<std::int8_t> phase;  ///< ShakePhase
  std::vector<Pose> X_WO;          ///< object pose in W
  std::vector<Pose> X_WH;          ///< hand (flange) pose in W
  /// Inner face of the −x finger at x = −finger_left in H, and of the +x finger at
  /// x = +finger_right (the fingers move independently); opening = left + right, m.
  std::vector<double> finger_left;
  std::vector<double> finger_right;
  std::vector<std::uint8_t> contact_left;   ///< finger at −x of H touches the object
  std::vector<std::uint8_t> contact_right;  ///< finger at +x of H touches the object
  /// Force of the −x and +x finger pads on the object over the step just run as the grip-force
  /// controller reads it (ShakeOptions::controller_net_force: by default the net normal force
  /// along the finger's opening direction), N (0 at the initial state).
  std::vector<double> force_left;
  std::vector<double> force_right;
  /// Contact points of both fingers on the object closer than contact_distance (C++ only).
  std::vector<int> contact_points;
  /// Bullet solver iterations of the step just run (0 at the initial state; C++ only).
  std::vector<int> solver_iterations;
  bool success = false;
  bool ended_early = false;
  int steps = 0;  ///< simulation steps run
  double friction = 0.0;
  double density_factor = 0.0;
};

/// Validates an object: at least one part, each part with at least 4 vertices not all coplanar,
/// finite positive mass, finite com, finite symmetric positive-definite inertia.
/// Throws InvalidArgument naming the field.
void validate_physics_object(const PhysicsObject& object);

/// Shake test of every grasp over the S×S grid, trials in parallel (deterministic for any
/// options.num_threads). Throws InvalidArgument on bad input (object, gripper, options, a grasp
/// that is not a valid frame or is wider than gripper.max_opening), before any simulation.
ShakeResult shake_test(const PhysicsObject& object, const ParallelJawGripper& gripper,
                       const std::vector<ParallelJawGrasp>& grasps, const ShakeOptions& options);

/// One trial (the same simulation as in shake_test for this setting, with the random stream of
/// trial index `trial_index`), recorded every `record_every` (>= 1) steps.
ShakeTrajectory shake_trajectory(const PhysicsObject& object, const ParallelJawGripper& gripper,
                                 const ParallelJawGrasp& grasp, double friction,
                                 double density_factor, const ShakeOptions& options,
                                 int record_every = 5, std::uint64_t trial_index = 0);

}  // namespace mgn
