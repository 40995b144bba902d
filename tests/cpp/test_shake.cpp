// The Bullet shake test of parallel-jaw grasps (MODELS.md §5, physics score).
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/geometry/convex_decomposition.hpp>
#include <mgn/geometry/mass_properties.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/grasp/shake_trial.hpp>

#include "grasp/detail/staircase_schedule.hpp"
#include "physics/world.hpp"

#include <Eigen/Geometry>
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <set>
#include <thread>
#include <utility>

namespace mgn {
namespace {

/// A solid box of the given size and mass, centred at the origin of O.
PhysicsObject box_object(const Vec3d& size, double mass) {
  PhysicsObject o;
  o.convex_parts = {make_box(size)};
  o.mass = mass;
  o.com = Vec3d::Zero();
  const double x2 = size.x() * size.x(), y2 = size.y() * size.y(), z2 = size.z() * size.z();
  o.inertia = (mass / 12.0 * Vec3d(y2 + z2, x2 + z2, x2 + y2)).asDiagonal();
  return o;
}

/// Grasp across x through the centre of a box of width w, hand coming from +z.
ParallelJawGrasp centre_grasp(double w) {
  ParallelJawGrasp g;
  g.p1 = Vec3d(-0.5 * w, 0, 0);
  g.closing = Vec3d::UnitX();
  g.approach = -Vec3d::UnitZ();
  g.width = w;
  return g;
}

/// Sets the Bullet extension switches of the physics world for its lifetime (tests only).
class ExtensionSwitches {
 public:
  explicit ExtensionSwitches(const physics::ExtensionSwitches& s)
      : saved_(physics::extension_switches()) {
    physics::set_extension_switches(s);
  }
  ~ExtensionSwitches() { physics::set_extension_switches(saved_); }
  ExtensionSwitches(const ExtensionSwitches&) = delete;
  ExtensionSwitches& operator=(const ExtensionSwitches&) = delete;

 private:
  physics::ExtensionSwitches saved_;
};

/// The full schedule (no held-load windows: they have their own tests) on an S x S grid.
ShakeOptions small_grid(int S, double fmin, double fmax) {
  ShakeOptions o;
  o.hold_tolerance = 0.0;
  o.grid = S;
  o.friction_min = fmin;
  o.friction_max = fmax;
  o.num_threads = 1;
  return o;
}

/// A hold-only test: gravity for `steps` steps, no shaking.
ShakeOptions hold_only(double friction) {
  ShakeOptions o = small_grid(1, friction, friction);
  o.density_min = o.density_max = 1.0;
  o.shake_speed = 0.0;
  o.shake_steps = 200;
  o.rotate_steps = 0;
  return o;
}

TEST(Shake, LightBoxWithHighFrictionIsHeld) {
  const PhysicsObject box = box_object(Vec3d(0.04, 0.04, 0.04), 0.05);
  ShakeOptions o = small_grid(3, 1.0, 2.0);
  const ShakeResult r = shake_test(box, ParallelJawGripper{}, {centre_grasp(0.04)}, o);
  ASSERT_EQ(r.score.size(), 1u);
  ASSERT_EQ(r.trial_success.size(), 9u);
  EXPECT_GE(r.score[0], 0.99);
  for (std::size_t t = 0; t < 9; ++t) {
    EXPECT_FALSE(r.trial_ended_early[t]);
    EXPECT_GT(r.trial_steps[t], o.shake_steps + o.rotate_steps);
  }
}

TEST(Shake, VeryLightObjectsSqueezedHardAreStillHeld) {
  // 2–6 g at 20 N (F / m g up to 1000): the solver iterations are raised for them.
  for (double m : {0.002, 0.006}) {
    ShakeOptions o = small_grid(1, 1.0, 1.0);
    o.density_min = o.density_max = 1.0;
    const ShakeResult r = shake_test(box_object(Vec3d(0.04, 0.04, 0.04), m), ParallelJawGripper{},
                                     {centre_grasp(0.04)}, o);
    EXPECT_EQ(r.trial_success[0], 1) << m << " kg";
  }
}

TEST(Shake, FinelyTessellatedSphereIsTouchedAndHeld) {
  // Vertex–face contacts of a fine hull (a regression test for Bullet's length tolerances).
  const double r = 0.02, m = 0.03;
  PhysicsObject ball;
  ball.convex_parts = {make_sphere(r, 32, 16)};
  ball.mass = m;
  ball.inertia = Mat3d::Identity() * 0.4 * m * r * r;
  ShakeOptions o = small_grid(2, 1.0, 2.0);
  const ShakeResult res = shake_test(ball, ParallelJawGripper{}, {centre_grasp(2 * r)}, o);
  EXPECT_GE(res.score[0], 0.99);
  // The fingers stop at the sphere (2 r apart, minus the pad sink), not inside it.
  const ShakeTrajectory tr =
      shake_trajectory(ball, ParallelJawGripper{}, centre_grasp(2 * r), 1.0, 1.0, o, 50);
  EXPECT_NEAR(tr.finger_left.back() + tr.finger_right.back(), 2 * r, 4e-3);
}

TEST(Shake, HeavySlipperyWideObjectIsDropped) {
  const PhysicsObject heavy = box_object(Vec3d(0.07, 0.06, 0.06), 3.0);
  ShakeOptions o = small_grid(3, 0.05, 0.15);
  const ShakeResult r = shake_test(heavy, ParallelJawGripper{}, {centre_grasp(0.07)}, o);
  EXPECT_LE(r.score[0], 0.01);
  // Dropped objects end the trial early, well before the full sequence.
  for (std::size_t t = 0; t < r.trial_steps.size(); ++t) {
    EXPECT_TRUE(r.trial_ended_early[t]);
    EXPECT_LT(r.trial_steps[t], o.shake_steps + o.rotate_steps);
  }
}

TEST(Shake, HeldLoadWindowsKeepTheCoulombLimitOfTheTranslationalShake) {
  // A centred box hanging from two pads of F each: at the translational shake's peak
  // acceleration a = v omega the pads must carry m (g + a) along the approach axis. Well above
  // that limit the box is held (with hold_tolerance: skipping the second cycle and the last
  // quarter of the rotation), well below it is dropped, with or without the windows.
  const double m = 1.0;
  const PhysicsObject box = box_object(Vec3d(0.04, 0.04, 0.04), m);
  for (const double hold : {0.0, 5e-4}) {
    for (const double factor : {0.5, 2.5}) {
      ShakeOptions o = small_grid(1, 0, 0);
      o.density_min = o.density_max = 1.0;
      o.hold_tolerance = hold;
      const double omega = 2 * M_PI * o.shake_cycles / (o.shake_steps * o.dt);
      o.friction_min = o.friction_max =
          factor * m * (o.gravity + o.shake_speed * omega) / (2 * o.grip_force);
      const ShakeResult r = shake_test(box, ParallelJawGripper{}, {centre_grasp(0.04)}, o);
      ShakeOptions full = o;
      full.hold_tolerance = 0.0;
      const ShakeResult f = shake_test(box, ParallelJawGripper{}, {centre_grasp(0.04)}, full);
      EXPECT_EQ(r.trial_success[0] != 0, factor > 1.0) << hold << " " << factor;
      EXPECT_EQ(f.trial_success[0] != 0, factor > 1.0) << factor;
      const int skipped = hold > 0 && factor > 1.0 ? o.shake_steps / 2 + o.rotate_steps / 4 : 0;
      EXPECT_EQ(r.trial_steps[0], f.trial_steps[0] - skipped) << hold << " " << factor;
    }
  }
}

TEST(Shake, StaticHoldFollowsCoulombBoundOfTheGripForce) {
  // Two fingers pressing with F each hold a weight m g iff 2 mu F >= m g.
  const double m = 1.0, F = 20.0;
  const double mu_star = m * 9.81 / (2.0 * F);  // 0.245
  const PhysicsObject box = box_object(Vec3d(0.04, 0.04, 0.04), m);
  for (double factor : {0.7, 0.85, 1.2, 1.5}) {
    ShakeOptions o = hold_only(factor * mu_star);
    o.grip_force = F;
    const ShakeResult r = shake_test(box, ParallelJawGripper{}, {centre_grasp(0.04)}, o);
    EXPECT_EQ(r.trial_success[0] != 0, factor > 1.0) << "friction factor " << factor;
  }
}

TEST(Shake, IterationsPerHullContactKeepTheCoulombBoundAtACoarseStep) {
  // The same Coulomb bound at dt = 1/100 s with 10 iterations per (finger, hull) pair in
  // contact: a box held by both fingers gets 20 iterations instead of 10 (the option is active).
  const double m = 1.0, F = 20.0;
  const double mu_star = m * 9.81 / (2.0 * F);
  const PhysicsObject box = box_object(Vec3d(0.04, 0.04, 0.04), m);
  for (double factor : {0.7, 0.85, 1.2, 1.5}) {
    ShakeOptions o = hold_only(factor * mu_star);
    o.grip_force = F;
    o.dt = 1.0 / 100.0;
    o.close_steps = 200;
    o.shake_steps = 100;
    o.settle_steps = o.lost_contact_steps = 5;
    o.iterations_per_hull_contact = 10.0;
    const ShakeResult r = shake_test(box, ParallelJawGripper{}, {centre_grasp(0.04)}, o);
    EXPECT_EQ(r.trial_success[0] != 0, factor > 1.0) << "friction factor " << factor;
  }
}

TEST(Shake, IterationsPerHullContactChangeNothingOnASingleHullUpToHalfTheIterations) {
  // A single hull makes at most 2 (finger, hull) pairs: 5 per pair asks for at most the 10 of
  // solver_iterations, so every trial is bit-identical to the default. 15 per pair (30
  // iterations) must still hold the box everywhere.
  const PhysicsObject box = box_object(Vec3d(0.04, 0.05, 0.05), 0.3);
  ShakeOptions o = small_grid(3, 0.5, 2.0);
  const ShakeResult base = shake_test(box, ParallelJawGripper{}, {centre_grasp(0.04)}, o);
  o.iterations_per_hull_contact = 0.5 * o.solver_iterations;
  const ShakeResult same = shake_test(box, ParallelJawGripper{}, {centre_grasp(0.04)}, o);
  EXPECT_EQ(same.trial_success, base.trial_success);
  EXPECT_EQ(same.trial_steps, base.trial_steps);
  o.iterations_per_hull_contact = 15.0;
  const ShakeResult more = shake_test(box, ParallelJawGripper{}, {centre_grasp(0.04)}, o);
  EXPECT_GE(more.score[0], 0.99);
}

/// The box of box_object() cut into `slabs` equal slabs along y: a compound of that many hulls
/// with the box's mass properties.
PhysicsObject slab_box(const Vec3d& size, double mass, int slabs) {
  PhysicsObject o = box_object(size, mass);
  o.convex_parts.clear();
  for (int k = 0; k < slabs; ++k) {
    Pose X = Pose::Identity();
    X.translation() = Vec3d(0.0, -0.5 * size.y() + (k + 0.5) * size.y() / slabs, 0.0);
    o.convex_parts.push_back(make_box(Vec3d(size.x(), size.y() / slabs, size.z())).transformed(X));
  }
  return o;
}

/// Every recorded pose and finger offset of two trajectories are the same bits.
bool same_trajectory(const ShakeTrajectory& a, const ShakeTrajectory& b) {
  if (a.steps != b.steps || a.success != b.success || a.X_WO.size() != b.X_WO.size()) return false;
  for (std::size_t k = 0; k < a.X_WO.size(); ++k) {
    if (a.X_WO[k].matrix() != b.X_WO[k].matrix()) return false;
    if (a.finger_left[k] != b.finger_left[k] || a.force_left[k] != b.force_left[k]) return false;
  }
  return true;
}

TEST(Shake, CompoundSolverIterationsChangeNothingOnASingleHull) {
  // One hull is not a compound: whatever compound_solver_iterations is, every trial is
  // bit-identical to the default, to the pose of every step.
  const PhysicsObject box = box_object(Vec3d(0.04, 0.05, 0.05), 0.3);
  const ParallelJawGripper g;
  ShakeOptions o = small_grid(3, 0.3, 1.5);
  const ShakeResult base = shake_test(box, g, {centre_grasp(0.04)}, o);
  const ShakeTrajectory base_tr = shake_trajectory(box, g, centre_grasp(0.04), 0.3, 1.0, o, 1, 2);
  for (const int it : {1, 10, 40, 1000}) {
    o.compound_solver_iterations = it;
    const ShakeResult r = shake_test(box, g, {centre_grasp(0.04)}, o);
    EXPECT_EQ(r.trial_success, base.trial_success) << it;
    EXPECT_EQ(r.trial_steps, base.trial_steps) << it;
    EXPECT_TRUE(
        same_trajectory(shake_trajectory(box, g, centre_grasp(0.04), 0.3, 1.0, o, 1, 2), base_tr))
        << it;
  }
}

TEST(Shake, CompoundSolverIterationsReplaceTheSolverIterationsOfACompound) {
  // A 2-slab box is a compound: compound_solver_iterations = 40 simulates it exactly as
  // solver_iterations = 40 does (same bits every step), differently from the default 10, and
  // 0 or the value of solver_iterations change nothing.
  const PhysicsObject slabs = slab_box(Vec3d(0.04, 0.06, 0.03), 0.05, 2);
  const ParallelJawGripper g;
  const ParallelJawGrasp grasp = centre_grasp(0.04);
  ShakeOptions o = small_grid(1, 0.5, 0.5);
  o.compound_solver_iterations = 0;
  const ShakeTrajectory base = shake_trajectory(slabs, g, grasp, 0.5, 1.0, o, 1, 0);
  o.compound_solver_iterations = o.solver_iterations;
  EXPECT_TRUE(same_trajectory(shake_trajectory(slabs, g, grasp, 0.5, 1.0, o, 1, 0), base));
  o.compound_solver_iterations = 40;
  const ShakeTrajectory compound40 = shake_trajectory(slabs, g, grasp, 0.5, 1.0, o, 1, 0);
  EXPECT_FALSE(same_trajectory(compound40, base));
  ShakeOptions all40 = small_grid(1, 0.5, 0.5);
  all40.compound_solver_iterations = 0;
  all40.solver_iterations = 40;
  EXPECT_TRUE(
      same_trajectory(shake_trajectory(slabs, g, grasp, 0.5, 1.0, all40, 1, 0), compound40));
  // It replaces solver_iterations whatever that is.
  all40.compound_solver_iterations = 40;
  all40.solver_iterations = 3;
  EXPECT_TRUE(
      same_trajectory(shake_trajectory(slabs, g, grasp, 0.5, 1.0, all40, 1, 0), compound40));
}

TEST(Shake, CompoundIterationPointsScaleACompoundsIterationsByItsContactPoints) {
  // The rule, step by step: a compound's step runs compound_solver_iterations (40) when the
  // fingers touched it at no more than compound_iteration_points P points at the step before,
  // else ceil(40 P / n), at least solver_iterations (10); both times the light-object
  // multiplier ceil(grip_force / (150 m g)). A 4-slab box gripped through its centre is pressed
  // face-on at 16 points (8 per pad) while held: 40 iterations at the default P = 24 and at
  // P = 16, 30 at P = 12, 20 at P = 8, 10 at P = 1; a 12.5 g one runs 2x that.
  const PhysicsObject slabs = slab_box(Vec3d(0.04, 0.06, 0.03), 0.05, 4);
  const ParallelJawGripper g;
  const ParallelJawGrasp grasp = centre_grasp(0.04);
  ShakeOptions o = small_grid(1, 0.5, 0.5);
  o.shake_steps = 200;
  o.rotate_steps = 100;
  EXPECT_EQ(o.compound_solver_iterations, 40);
  EXPECT_EQ(o.compound_iteration_points, 24.0);
  for (const double density : {1.0, 0.25}) {
    const double m = slabs.mass * density;
    const int boost = static_cast<int>(std::ceil(o.grip_force / (150.0 * m * o.gravity)));
    EXPECT_EQ(boost, density == 1.0 ? 1 : 2);
    for (const auto& [points, held] :
         {std::pair{24.0, 40}, std::pair{16.0, 40}, std::pair{12.0, 30}, std::pair{8.0, 20},
          std::pair{1.0, 10}}) {
      ShakeOptions p = o;
      p.compound_iteration_points = points;
      const ShakeTrajectory tr = shake_trajectory(slabs, g, grasp, 0.5, density, p, 1, 0);
      ASSERT_EQ(tr.solver_iterations.size(), tr.contact_points.size());
      ASSERT_GT(tr.solver_iterations.size(), 300u);
      EXPECT_EQ(tr.solver_iterations[0], 0);  // the initial state: no step run
      int at16 = 0;
      for (size_t k = 1; k < tr.solver_iterations.size(); ++k) {
        const int n = tr.contact_points[k - 1];
        const int per =
            n > points ? std::max(10, static_cast<int>(std::ceil(40.0 * points / n))) : 40;
        EXPECT_EQ(tr.solver_iterations[k], per * boost) << k << " " << n << " " << points;
        at16 += n == 16 && tr.solver_iterations[k] == held * boost;
      }
      EXPECT_GT(at16, 250) << density << " " << points;  // held at 16 points most of the trial
    }
  }
  // Off: every step of the compound runs 40 (x2).
  ShakeOptions off = o;
  off.compound_iteration_points = 0;
  const ShakeTrajectory all = shake_trajectory(slabs, g, grasp, 0.5, 0.25, off, 1, 0);
  for (size_t k = 1; k < all.solver_iterations.size(); ++k) {
    EXPECT_EQ(all.solver_iterations[k], 80) << k;
  }
  // One hull is not a compound: solver_iterations every step, and the same trial bits whatever
  // the budget.
  const PhysicsObject box = box_object(Vec3d(0.04, 0.06, 0.03), 0.05);
  ShakeOptions one_point = o;
  one_point.compound_iteration_points = 1;
  const ShakeTrajectory one = shake_trajectory(box, g, grasp, 0.5, 1.0, one_point, 1, 0);
  for (size_t k = 1; k < one.solver_iterations.size(); ++k) {
    EXPECT_EQ(one.solver_iterations[k], 10) << k;
  }
  EXPECT_TRUE(same_trajectory(shake_trajectory(box, g, grasp, 0.5, 1.0, off, 1, 0), one));
}

TEST(Shake, AdaptedControllerGainSettlesALightCompoundAtEveryIterationCountTested) {
  // A 12.5 g two-slab box pressed face-on by each pad at 8 points: with 30 or 40 compound
  // solver iterations (x2 for the light object) the solver answers a finger move more stiffly
  // than limit_controller_gain's model, and without adapt_controller_gain the closing falls into
  // a period-2 oscillation (mean pad force jumping by tens of N every step) and runs all
  // close_steps. With it, the closing settles at the grip force (within the 5 % settle band)
  // at 10 (compound_solver_iterations 0), 20, 30, 40 and 80 iterations. At 10 it changes no
  // bit of the closing.
  const PhysicsObject slabs = slab_box(Vec3d(0.04, 0.06, 0.03), 0.05, 2);
  const ParallelJawGripper g;
  const ParallelJawGrasp grasp = centre_grasp(0.04);
  ShakeOptions o = small_grid(1, 0.5, 0.5);
  o.shake_steps = o.rotate_steps = 0;
  for (const int it : {0, 20, 30, 40, 80}) {
    o.compound_solver_iterations = it;
    o.adapt_controller_gain = true;
    const ShakeTrajectory tr = shake_trajectory(slabs, g, grasp, 0.5, 0.25, o, 1, 0);
    EXPECT_LT(tr.steps, o.close_steps) << it;
    const double f = 0.5 * (tr.force_left.back() + tr.force_right.back());
    EXPECT_NEAR(f, o.grip_force, 0.05 * o.grip_force) << it;
    o.adapt_controller_gain = false;
    const ShakeTrajectory fixed = shake_trajectory(slabs, g, grasp, 0.5, 0.25, o, 1, 0);
    if (it == 0) {
      EXPECT_TRUE(same_trajectory(fixed, tr));
    }
    if (it != 30 && it != 40) continue;
    EXPECT_EQ(fixed.steps, o.close_steps) << it;
    double jump = 0.0;  // the smallest step-to-step change of the mean pad force, last 100 steps
    for (size_t k = fixed.force_left.size() - 100; k < fixed.force_left.size(); ++k) {
      const double a = fixed.force_left[k] + fixed.force_right[k];
      const double b = fixed.force_left[k - 1] + fixed.force_right[k - 1];
      jump = k == fixed.force_left.size() - 100 ? 0.5 * std::abs(a - b)
                                                : std::min(jump, 0.5 * std::abs(a - b));
    }
    EXPECT_GT(jump, 20.0) << it;
  }
}

TEST(Shake, ClosingSettlesAtTheGripForceAtAnyTimeStep) {
  // The force controller's move is given per 1/400 s, so a closing on a box settles at the grip
  // force in about the same simulated time at dt = 1/400, 1/800 and 1/1600 s (every step count
  // scaled): the mean pad force of the last settled step within 5 % of grip_force (the settle
  // criterion) and within 2 % of the 1/400 s closing's, the settle time within 25 % of it.
  const PhysicsObject box = box_object(Vec3d(0.04, 0.05, 0.05), 0.3);
  const ParallelJawGripper g;
  double force400 = 0.0, time400 = 0.0;
  for (const int f : {1, 2, 4}) {
    ShakeOptions o = small_grid(1, 1.0, 1.0);
    o.dt = 1.0 / (400.0 * f);
    o.close_steps *= f;
    o.settle_steps *= f;
    o.shake_steps = o.rotate_steps = 0;
    const ShakeTrajectory tr = shake_trajectory(box, g, centre_grasp(0.04), 1.0, 1.0, o, 1, 0);
    ASSERT_LT(tr.steps, o.close_steps) << "dt 1/" << 400 * f << " s: the closing never settled";
    const double force = 0.5 * (tr.force_left.back() + tr.force_right.back());
    const double time = tr.time.back();
    EXPECT_NEAR(force, o.grip_force, 0.05 * o.grip_force) << "dt 1/" << 400 * f;
    if (f == 1) {
      force400 = force;
      time400 = time;
      continue;
    }
    EXPECT_NEAR(force, force400, 0.02 * o.grip_force) << "dt 1/" << 400 * f;
    EXPECT_NEAR(time, time400, 0.25 * time400) << "dt 1/" << 400 * f;
  }
}

/// A 50 g block x in [-w/2 - 10 mm, w/2], |y| <= 30 mm, |z| <= 15 mm with a 90-degree V-groove
/// along z in its −x face (apex at x = -w/2 + 10 mm): two convex hulls. A 20 mm wide pad closing
/// along +x touches the groove's walls with its two edges (y = ±10 mm, at x = −w/2), where the
/// contact normals are ±45 degrees from x; the +x face is flat.
PhysicsObject grooved_block(double w) {
  const double x0 = -0.5 * w, xr = 0.5 * w;
  PhysicsObject o = box_object(Vec3d(xr - x0 + 0.01, 0.06, 0.03), 0.05);
  o.convex_parts.clear();
  for (const double sy : {1.0, -1.0}) {
    Points3f P(10, 3);
    const double xy[5][2] = {
        {x0 - 0.01, 0.02}, {x0 + 0.01, 0.0}, {xr, 0.0}, {xr, 0.03}, {x0 - 0.01, 0.03}};
    for (int k = 0; k < 5; ++k) {
      for (int h = 0; h < 2; ++h) {
        P.row(2 * k + h) << float(xy[k][0]), float(sy * xy[k][1]), h == 0 ? -0.015f : 0.015f;
      }
    }
    o.convex_parts.push_back(convex_hull_of_points(P));
  }
  return o;
}

TEST(Shake, NetPadForceCountsOnlyTheForceAlongTheClosingDirection) {
  // Frictionless closing on the grooved block: the −x pad's two contacts push it at 45 degrees,
  // the +x pad's flat contact straight back, and the object at rest needs the same force along
  // x on both pads, F. Summed normal forces read √2 F on the grooved pad, so the controller
  // holds (√2 F + F)/2 = grip: F = 2 grip/(1 + √2) = 0.83 grip. The net force along the
  // opening direction reads F on both pads: F = grip. The +x pad's force (one flat face: the
  // same in both readings) shows which; mean over 0.15 s from 0.05 s after both pads touch,
  // the closing run to its end (settle_steps 0: without friction the block rocks in the
  // groove, and the net reading does not stay within the 5 % that ends a closing).
  const double w = 0.04;
  const PhysicsObject block = grooved_block(w);
  const ParallelJawGripper g;
  for (const bool net : {false, true}) {
    ShakeOptions o = small_grid(1, 0.0, 0.0);
    o.shake_steps = o.rotate_steps = 0;
    o.controller_net_force = net;
    o.settle_steps = 0;
    const ShakeTrajectory tr = shake_trajectory(block, g, centre_grasp(w), 0.0, 1.0, o, 1, 0);
    std::size_t first = 0;
    while (first < tr.time.size() && !(tr.contact_left[first] && tr.contact_right[first])) ++first;
    const std::size_t from = first + 20, to = first + 80;
    ASSERT_LT(to, tr.time.size()) << "net " << net;
    double left = 0.0, right = 0.0;
    for (std::size_t k = from; k < to; ++k) {
      ASSERT_TRUE(tr.contact_left[k] && tr.contact_right[k]) << "net " << net << " step " << k;
      left += tr.force_left[k] / double(to - from);  // as the controller read it
      right += tr.force_right[k] / double(to - from);
    }
    const double expected = net ? o.grip_force : 2.0 * o.grip_force / (1.0 + std::sqrt(2.0));
    EXPECT_NEAR(right, expected, 0.04 * o.grip_force) << "net " << net;
    EXPECT_NEAR(left, net ? expected : std::sqrt(2.0) * expected, 0.06 * o.grip_force)
        << "net " << net;
  }
}

TEST(Shake, DefaultControllerReadsTheNetPadForce) {
  // At the default options the controller reads the net force along the opening direction: on
  // the grooved block (see above) the flat +x pad then settles at the grip force, not at the
  // summed reading's 2/(1 + sqrt 2) = 0.83 of it, and the grooved pad reads the same force.
  const double w = 0.04;
  const PhysicsObject block = grooved_block(w);
  ShakeOptions o = small_grid(1, 0.0, 0.0);
  ASSERT_TRUE(o.controller_net_force);
  o.shake_steps = o.rotate_steps = 0;
  o.settle_steps = 0;
  const ShakeTrajectory tr =
      shake_trajectory(block, ParallelJawGripper{}, centre_grasp(w), 0.0, 1.0, o, 1, 0);
  std::size_t first = 0;
  while (first < tr.time.size() && !(tr.contact_left[first] && tr.contact_right[first])) ++first;
  const std::size_t from = first + 20, to = first + 80;
  ASSERT_LT(to, tr.time.size());
  double left = 0.0, right = 0.0;
  for (std::size_t k = from; k < to; ++k) {
    left += tr.force_left[k] / double(to - from);
    right += tr.force_right[k] / double(to - from);
  }
  EXPECT_NEAR(right, o.grip_force, 0.04 * o.grip_force);
  EXPECT_NEAR(left, o.grip_force, 0.06 * o.grip_force);
}

TEST(Shake, NetPadForceChangesNoOutcomeOnAFaceOnGrasp) {
  // A box squeezed face-on: every contact normal is along x, so both readings are the same force
  // and every trial of a grid the same outcome.
  const PhysicsObject box = box_object(Vec3d(0.04, 0.05, 0.05), 0.8);
  ShakeOptions o = small_grid(3, 0.2, 1.0);
  o.controller_net_force = false;
  const ShakeResult sum = shake_test(box, ParallelJawGripper{}, {centre_grasp(0.04)}, o);
  o.controller_net_force = true;
  const ShakeResult net = shake_test(box, ParallelJawGripper{}, {centre_grasp(0.04)}, o);
  EXPECT_EQ(net.trial_success, sum.trial_success);
  int held = 0;
  for (const std::uint8_t s : sum.trial_success) held += s;
  EXPECT_GT(held, 0);
  EXPECT_LT(held, 9);
}

TEST(Shake, ScoreRisesWithFriction) {
  const PhysicsObject box = box_object(Vec3d(0.04, 0.05, 0.05), 0.8);
  const ParallelJawGrasp grasp = centre_grasp(0.04);
  std::vector<int> outcome;
  for (double mu : {0.05, 0.1, 0.2, 0.4, 0.8, 1.6}) {
    ShakeOptions o = small_grid(1, mu, mu);
    o.density_min = o.density_max = 1.0;
    outcome.push_back(shake_test(box, ParallelJawGripper{}, {grasp}, o).trial_success[0]);
  }
  EXPECT_EQ(outcome.front(), 0);
  EXPECT_EQ(outcome.back(), 1);
  for (std::size_t i = 1; i < outcome.size(); ++i) EXPECT_GE(outcome[i], outcome[i - 1]) << i;
  // The same over a grid: the per-friction success counts do not decrease.
  ShakeOptions o = small_grid(4, 0.1, 1.0);
  const ShakeResult r = shake_test(box, ParallelJawGripper{}, {grasp}, o);
  int prev = -1;
  for (int i = 0; i < 4; ++i) {
    int held = 0;
    for (int j = 0; j < 4; ++j) held += r.trial_success[i * 4 + j];
    EXPECT_GE(held, prev) << "friction " << r.frictions[i];
    prev = held;
  }
}

TEST(Shake, HeavierIsHarderToHold) {
  const PhysicsObject box = box_object(Vec3d(0.04, 0.05, 0.05), 4.0);
  ShakeOptions o = small_grid(4, 0.3, 0.3);
  o.grid = 4;
  o.friction_min = o.friction_max = 0.3;
  o.density_min = 0.05;
  o.density_max = 1.0;
  const ShakeResult r = shake_test(box, ParallelJawGripper{}, {centre_grasp(0.04)}, o);
  // Same friction for every row: per density factor the outcome may only fall as mass grows.
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(r.trial_success[i * 4 + 0], 1);
    EXPECT_EQ(r.trial_success[i * 4 + 3], 0);
    for (int j = 1; j < 4; ++j)
      EXPECT_LE(r.trial_success[i * 4 + j], r.trial_success[i * 4 + j - 1]);
  }
}

TEST(Shake, ThreadsAndSeedGiveIdenticalResults) {
  const PhysicsObject box = box_object(Vec3d(0.04, 0.05, 0.05), 0.8);
  std::vector<ParallelJawGrasp> grasps = {centre_grasp(0.04), centre_grasp(0.04)};
  grasps[1].p1 = Vec3d(-0.02, 0.01, 0.015);  // off-centre: torque about the closing axis
  ShakeOptions o = small_grid(3, 0.2, 1.0);
  o.seed = 7;
  o.num_threads = 1;
  const ShakeResult a = shake_test(box, ParallelJawGripper{}, grasps, o);
  o.num_threads = 2;
  const ShakeResult b = shake_test(box, ParallelJawGripper{}, grasps, o);
  const ShakeResult c = shake_test(box, ParallelJawGripper{}, grasps, o);
  EXPECT_EQ(a.trial_success, b.trial_success);
  EXPECT_EQ(a.trial_steps, b.trial_steps);
  EXPECT_EQ(a.trial_ended_early, b.trial_ended_early);
  EXPECT_EQ(a.score, b.score);
  EXPECT_EQ(b.trial_steps, c.trial_steps);
  EXPECT_EQ(a.total_steps, b.total_steps);
}

TEST(Shake, TrajectoryMatchesTheBatchTrialAndThePrescribedHandPath) {
  const PhysicsObject box = box_object(Vec3d(0.04, 0.05, 0.05), 0.8);
  const ParallelJawGripper gripper;
  const ParallelJawGrasp grasp = centre_grasp(0.04);
  ShakeOptions o = small_grid(2, 0.3, 1.0);
  o.seed = 3;
  const ShakeResult r = shake_test(box, gripper, {grasp}, o);
  for (std::uint64_t t = 0; t < 4; ++t) {
    const ShakeTrajectory tr = shake_trajectory(box, gripper, grasp, r.frictions[t / 2],
                                                r.density_factors[t % 2], o, 1, t);
    EXPECT_EQ(tr.success, r.trial_success[t] != 0);
    EXPECT_EQ(tr.steps, r.trial_steps[t]);
    ASSERT_EQ(tr.time.size(), static_cast<std::size_t>(tr.steps) + 1);
  }
  const ShakeTrajectory tr = shake_trajectory(box, gripper, grasp, 1.0, 1.0, o, 7, 0);
  ASSERT_GE(tr.time.size(), 3u);
  EXPECT_EQ(tr.time.front(), 0.0);
  EXPECT_NEAR(tr.time.back(), tr.steps * o.dt, 1e-9);
  // Initially the hand points down (z_H = −z_W) and the object sits at X_WH0 · X_HO.
  const Pose X_WO0 = tr.X_WH.front() * hand_pose(grasp, gripper).inverse();
  EXPECT_LT((tr.X_WO.front().matrix() - X_WO0.matrix()).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_NEAR(tr.X_WH.front().linear().col(2).z(), -1.0, 1e-12);
  EXPECT_NEAR(tr.finger_left.front() + tr.finger_right.front(), 0.07, 1e-6);  // w + 30 mm
  // Held: at the end the fingers squeeze the 40 mm box, the object has moved with the hand.
  EXPECT_TRUE(tr.success);
  EXPECT_NEAR(tr.finger_left.back() + tr.finger_right.back(), 0.04, 2e-3);
  const Pose X_HO_end = tr.X_WH.back().inverse() * tr.X_WO.back();
  EXPECT_LT((X_HO_end.translation() - hand_pose(grasp, gripper).inverse().translation()).norm(),
            0.01);
  // The hand moves only along its approach axis in the translational phase, with peak speed
  // 0.5 m/s: amplitude A = v T / (2 pi n).
  const double A = o.shake_speed * o.shake_steps * o.dt / (2 * M_PI * o.shake_cycles);
  double max_offset = 0;
  for (std::size_t k = 0; k < tr.time.size(); ++k) {
    if (tr.phase[k] != static_cast<std::int8_t>(ShakePhase::Translate)) continue;
    const Vec3d d = tr.X_WH[k].translation() - tr.X_WH.front().translation();
    EXPECT_LT(std::hypot(d.x(), d.y()), 1e-12);
    max_offset = std::max(max_offset, std::abs(d.z()));
  }
  EXPECT_NEAR(max_offset, A, 0.05 * A);
}

TEST(Shake, EarlyExitAndSettledClosingChangeFewOutcomes) {
  const PhysicsObject box = box_object(Vec3d(0.04, 0.05, 0.05), 1.5);
  std::vector<ParallelJawGrasp> grasps = {centre_grasp(0.04)};
  ShakeOptions fast = small_grid(4, 0.1, 1.0);
  fast.num_threads = 2;
  ShakeOptions full = fast;
  full.settle_steps = 0;
  full.lost_contact_steps = 0;
  const ShakeResult a = shake_test(box, ParallelJawGripper{}, grasps, fast);
  const ShakeResult b = shake_test(box, ParallelJawGripper{}, grasps, full);
  int same = 0, held = 0, early = 0;
  for (std::size_t t = 0; t < a.trial_success.size(); ++t) {
    same += a.trial_success[t] == b.trial_success[t];
    held += b.trial_success[t];
    early += a.trial_ended_early[t];
  }
  EXPECT_GE(same, 15);  // of 16
  EXPECT_GT(held, 0);   // mixed outcomes, and some trials did end early
  EXPECT_LT(held, 16);
  EXPECT_GT(early, 0);
  EXPECT_LT(a.total_steps, b.total_steps);
  const int schedule = full.close_steps + full.shake_steps + full.rotate_steps;
  for (std::int32_t s : b.trial_steps) EXPECT_EQ(s, schedule);  // the whole schedule, no early end
}

TEST(Shake, InertiaFloorChangesFewOutcomesWhereExactInertiaIsStable) {
  // A heavy box (F / m g ~ 1) is steady with its exact inertia; the floor (x4.5 here) must not
  // change what friction and gravity decide.
  const PhysicsObject box = box_object(Vec3d(0.04, 0.05, 0.05), 1.5);
  ShakeOptions with = small_grid(4, 0.2, 1.0);
  with.num_threads = 2;
  ShakeOptions without = with;
  without.inertia_floor = 0.0;
  const ShakeResult a = shake_test(box, ParallelJawGripper{}, {centre_grasp(0.04)}, with);
  const ShakeResult b = shake_test(box, ParallelJawGripper{}, {centre_grasp(0.04)}, without);
  int same = 0, held = 0;
  for (std::size_t t = 0; t < a.trial_success.size(); ++t) {
    same += a.trial_success[t] == b.trial_success[t];
    held += a.trial_success[t];
  }
  EXPECT_GE(same, 15);  // of 16
  EXPECT_GT(held, 0);   // mixed outcomes: the comparison means something
  EXPECT_LT(held, 16);
}

TEST(Shake, BadInputIsRejectedWithAClearMessage) {
  const PhysicsObject box = box_object(Vec3d(0.04, 0.04, 0.04), 0.05);
  const ParallelJawGripper g;
  const ShakeOptions o = small_grid(2, 0.5, 1.0);
  auto expect_error = [&](const PhysicsObject& obj, const ParallelJawGrasp& grasp,
                          const ShakeOptions& opt, const std::string& fragment) {
    try {
      shake_test(obj, g, {grasp}, opt);
      ADD_FAILURE() << "no error for " << fragment;
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  PhysicsObject bad = box;
  bad.mass = 0;
  expect_error(bad, centre_grasp(0.04), o, "mass");
  bad = box;
  bad.inertia(1, 1) = NAN;
  expect_error(bad, centre_grasp(0.04), o, "inertia");
  bad = box;
  bad.inertia(0, 0) = -1;
  expect_error(bad, centre_grasp(0.04), o, "positive-definite");
  bad = box;
  bad.convex_parts.clear();
  expect_error(bad, centre_grasp(0.04), o, "convex_parts");
  bad = box;
  Points3f flat(4, 3);
  flat << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0;
  Faces ff(2, 3);
  ff << 0, 1, 2, 1, 3, 2;
  bad.convex_parts = {Mesh(flat, ff)};
  expect_error(bad, centre_grasp(0.04), o, "coplanar");
  expect_error(box, centre_grasp(0.09), o, "max_opening");
  ParallelJawGrasp skew = centre_grasp(0.04);
  skew.approach = Vec3d(1, 0, 1).normalized();
  expect_error(box, skew, o, "grasps[0]");
  ShakeOptions bo = o;
  bo.grid = 0;
  expect_error(box, centre_grasp(0.04), bo, "grid");
  bo = o;
  bo.dt = -1;
  expect_error(box, centre_grasp(0.04), bo, "dt");
  bo = o;
  bo.grip_force = NAN;
  expect_error(box, centre_grasp(0.04), bo, "grip_force");
  bo = o;
  bo.hold_tolerance = -1e-3;
  expect_error(box, centre_grasp(0.04), bo, "hold_tolerance");
  bo.hold_tolerance = NAN;
  expect_error(box, centre_grasp(0.04), bo, "hold_tolerance");
  bo = o;
  bo.iterations_per_hull_contact = -1;
  expect_error(box, centre_grasp(0.04), bo, "iterations_per_hull_contact");
  bo.iterations_per_hull_contact = NAN;
  expect_error(box, centre_grasp(0.04), bo, "iterations_per_hull_contact");
  bo = o;
  bo.compound_iteration_points = -1;
  expect_error(box, centre_grasp(0.04), bo, "compound_iteration_points");
  bo.compound_iteration_points = NAN;
  expect_error(box, centre_grasp(0.04), bo, "compound_iteration_points");
  bo = o;
  bo.compound_solver_iterations = -1;
  expect_error(box, centre_grasp(0.04), bo, "compound_solver_iterations");
  bo.compound_solver_iterations = 1001;
  expect_error(box, centre_grasp(0.04), bo, "compound_solver_iterations");
  EXPECT_THROW(shake_trajectory(box, g, centre_grasp(0.04), 1.0, 1.0, o, 0), InvalidArgument);
  EXPECT_THROW(shake_trajectory(box, g, centre_grasp(0.04), 1.0, -1.0, o, 1), InvalidArgument);
  // No grasps: an empty result, not an error.
  const ShakeResult empty = shake_test(box, g, {}, o);
  EXPECT_TRUE(empty.score.empty());
}

TEST(Staircase, EqualsTheFullGridOnEveryMonotoneGridWithFewTrials) {
  // Every monotone grid (boundary b_i non-decreasing in the friction index i, success for
  // density index j < b_i) of S = 1..6 and random ones of S = 10: the staircase reproduces every
  // cell without fallback, calls each cell at most once, and stays within the documented trial
  // bounds (S + 1 + checks for a grid that succeeds everywhere; 39 + checks for S = 10).
  auto check = [](int S, const std::vector<int>& b, int checks) {
    std::vector<int> calls(static_cast<std::size_t>(S * S), 0);
    auto truth = [&](int i, int j) { return j < b[static_cast<std::size_t>(i)]; };
    const StaircaseGrid g = staircase_grid(
        S,
        [&](int i, int j) {
          ++calls[static_cast<std::size_t>(i * S + j)];
          return truth(i, j);
        },
        checks);
    EXPECT_FALSE(g.fallback);
    int simulated = 0;
    for (int k = 0; k < S * S; ++k) {
      ASSERT_LE(calls[k], 1);
      ASSERT_EQ(calls[k], g.simulated[k]);
      simulated += calls[k];
      ASSERT_EQ(g.success[k], truth(k / S, k % S) ? 1 : 0) << "S " << S << " cell " << k;
    }
    EXPECT_EQ(g.trials, simulated);
    if (S == 10) {
      EXPECT_LE(g.trials, 39 + checks);
    }
    if (b[0] == S) {
      EXPECT_LE(g.trials, S + 1 + checks);
    }
  };
  for (int S = 1; S <= 6; ++S) {
    std::vector<int> b(static_cast<std::size_t>(S), 0);
    int count = 0;
    while (true) {  // every non-decreasing b in [0, S]^S
      check(S, b, 0);
      check(S, b, 3);
      ++count;
      int k = S - 1;
      while (k >= 0 && b[k] == S) --k;
      if (k < 0) break;
      ++b[k];
      for (int m = k + 1; m < S; ++m) b[m] = b[k];
    }
    EXPECT_GT(count, S);
  }
  std::uint64_t state = 12345;
  auto next = [&state](int n) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<int>((state >> 33) % static_cast<std::uint64_t>(n));
  };
  for (int rep = 0; rep < 300; ++rep) {
    std::vector<int> b(10);
    for (int i = 0; i < 10; ++i) b[i] = std::max(i > 0 ? b[i - 1] : 0, next(11));
    check(10, b, next(20));
  }
  // A grid that succeeds everywhere: one walk trial, (0, S-2) and the last column, the checks.
  const StaircaseGrid all = staircase_grid(
      10, [](int, int) { return true; }, 5);
  EXPECT_EQ(all.trials, 11 + 5);
  EXPECT_THROW(staircase_grid(
                   0, [](int, int) { return true; }, 4),
               InvalidArgument);
  EXPECT_THROW(staircase_grid(
                   3, [](int, int) { return true; }, -1),
               InvalidArgument);
}

TEST(Staircase, FallsBackToTheFullGridWhereMonotonicityIsViolated) {
  // Boundary at j = 5 in every row, but cell (3, 2) fails although (2, 2) succeeds (more
  // friction made it worse): the walk infers (3, 2) a success; a check catches it and every
  // cell is simulated, so the result is the truth.
  const int S = 10;
  auto truth = [](int i, int j) { return j < 5 && !(i == 3 && j == 2); };
  const StaircaseGrid g = staircase_grid(S, truth, 100);
  EXPECT_TRUE(g.fallback);
  EXPECT_EQ(g.trials, S * S);
  for (int i = 0; i < S; ++i)
    for (int j = 0; j < S; ++j) EXPECT_EQ(g.success[i * S + j], truth(i, j) ? 1 : 0);
  // Without checks away from the boundary the violation goes unnoticed (the cell is wrong).
  const StaircaseGrid blind = staircase_grid(S, truth, 0);
  EXPECT_FALSE(blind.fallback);
  EXPECT_FALSE(blind.simulated[3 * S + 2]);
  EXPECT_EQ(blind.success[3 * S + 2], 1);
}

TEST(Staircase, ScheduleGivesEachGraspsStaircaseGridAndSharesFallbacks) {
  // Synthetic grids (no physics): per grasp a monotone boundary, some with a flipped cell that
  // makes the search fall back. For 1, 2 and 3 threads every cell and fallback flag must equal
  // staircase_grid() run grasp by grasp, every trial must run at most once and exactly the
  // cells staircase_grid() simulates must run. Grasp 0 falls back and its trials are slow
  // (20 ms each with 2 or 3 threads, ~0.7 s in all: long enough for the other threads to be
  // scheduled on a loaded machine; 2 ms failed once at load 9), the others are instant: the
  // threads that finish the others must take over some of grasp 0's fallback cells (with
  // contiguous ranges one thread would run all of them).
  const int S = 6;
  const std::size_t G = 9, per = S * S;
  std::vector<int> bound(G);
  std::vector<int> flip(G, -1);  // cell index made wrong, -1: none
  for (std::size_t g = 0; g < G; ++g) {
    bound[g] = static_cast<int>((g * 7) % (S + 1));
    if (g % 3 == 0) flip[g] = static_cast<int>((g * 13 + 5) % per);
  }
  flip[0] = 2 * S + 1;  // (2, 1), inside the success region: found by the checks below
  bound[0] = S;
  auto truth = [&](std::size_t t) {
    const std::size_t g = t / per, c = t % per;
    const bool ok = static_cast<int>(c % S) < bound[g] + static_cast<int>(c / S) % 2;
    return static_cast<int>(c) == flip[g] ? !ok : ok;
  };
  const int checks = static_cast<int>(per);  // verify every cell: grasp 0 surely falls back
  std::vector<std::uint8_t> want(G * per), want_sim(G * per);
  std::vector<std::uint8_t> want_fallback(G);
  for (std::size_t g = 0; g < G; ++g) {
    const StaircaseGrid sg = staircase_grid(
        S, [&](int i, int j) { return truth(g * per + i * S + j); }, checks);
    for (std::size_t c = 0; c < per; ++c) {
      want[g * per + c] = sg.success[c];
      want_sim[g * per + c] = sg.simulated[c];
    }
    want_fallback[g] = sg.fallback;
  }
  ASSERT_TRUE(want_fallback[0]);
  for (const int threads : {1, 2, 3}) {
    std::vector<std::atomic<int>> runs(G * per);
    std::vector<std::thread::id> who(G * per);
    std::mutex m;
    auto make = [&]() -> detail::TrialRunner {
      return [&](std::size_t t) {
        if (t < per && threads > 1) std::this_thread::sleep_for(std::chrono::milliseconds(20));
        ++runs[t];
        std::lock_guard<std::mutex> lock(m);
        who[t] = std::this_thread::get_id();
        return truth(t);
      };
    };
    std::vector<std::uint8_t> success, fallback;
    detail::staircase_schedule(G, S, checks, -1, threads, make, success, fallback);
    EXPECT_EQ(success, want) << threads << " threads";
    EXPECT_EQ(fallback, want_fallback) << threads << " threads";
    for (std::size_t t = 0; t < G * per; ++t)
      EXPECT_EQ(runs[t].load(), want_sim[t] ? 1 : 0) << "trial " << t << ", " << threads;
    if (threads > 1) {  // grasp 0's first trial is its walker's; others ran some of its cells
      int shared = 0;
      for (std::size_t t = 1; t < per; ++t) shared += runs[t] && who[t] != who[0];
      EXPECT_GT(shared, 0) << threads << " threads";
    }
  }
  // An exception in a trial reaches the caller (no thread is left waiting).
  auto failing = [&]() -> detail::TrialRunner {
    return [&](std::size_t t) -> bool {
      if (t == 3 * per) throw_error<InvalidArgument>("trial ", t);
      return truth(t);
    };
  };
  std::vector<std::uint8_t> success, fallback;
  EXPECT_THROW(detail::staircase_schedule(G, S, checks, -1, 2, failing, success, fallback),
               InvalidArgument);
}

TEST(Staircase, ChecksFindViolationsNextToTheBoundaryAlwaysAndAnywhereWithAFullBudget) {
  // Monotone random grids with one cell flipped. (a) A flipped cell next to its row's boundary
  // (j = b_i - 1 or j = b_i) is simulated by the walk or verified, even with no extra checks,
  // so the search returns the truth. (b) With checks >= S*S every inferred cell is verified: the
  // result always equals the truth.
  std::uint64_t state = 777;
  auto next = [&state](int n) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<int>((state >> 33) % static_cast<std::uint64_t>(n));
  };
  const int S = 10;
  int near_cases = 0;
  for (int rep = 0; rep < 400; ++rep) {
    std::vector<int> b(S);
    for (int i = 0; i < S; ++i) b[i] = std::max(i > 0 ? b[i - 1] : 0, next(S + 1));
    const int fi = next(S), fj = next(S);
    auto truth = [&](int i, int j) { return (j < b[i]) != (i == fi && j == fj); };
    const StaircaseGrid full = staircase_grid(S, truth, S * S);
    for (int i = 0; i < S; ++i)
      for (int j = 0; j < S; ++j)
        ASSERT_EQ(full.success[i * S + j], truth(i, j) ? 1 : 0) << "rep " << rep;
    if (fj == b[fi] - 1 || fj == b[fi]) {
      ++near_cases;
      const StaircaseGrid band = staircase_grid(S, truth, 0);
      for (int i = 0; i < S; ++i)
        for (int j = 0; j < S; ++j)
          ASSERT_EQ(band.success[i * S + j], truth(i, j) ? 1 : 0)
              << "rep " << rep << " flipped " << fi << "," << fj;
    }
  }
  EXPECT_GT(near_cases, 40);
}

TEST(Staircase, ShakeTestScoresEqualTheFullGridOnABox) {
  // A real case: a 70 g box 40 x 40 x 60 mm, grasped at heights from the centre to near its top
  // edge (scores between 0 and 1): the staircase search gives the full grid's scores.
  const PhysicsObject box = box_object(Vec3d(0.04, 0.04, 0.06), 0.07);
  std::vector<ParallelJawGrasp> grasps;
  for (double dz : {0.0, 0.012, 0.022, 0.027}) {
    ParallelJawGrasp g = centre_grasp(0.04);
    g.p1.z() = dz;
    grasps.push_back(g);
  }
  ShakeOptions o = small_grid(5, 0.1, 1.0);
  o.grip_force = 5.0;
  o.num_threads = 2;
  const ShakeResult full = shake_test(box, ParallelJawGripper{}, grasps, o);
  o.staircase = true;
  o.staircase_checks = 2;  // the default would verify almost every cell of a 5 x 5 grid
  const ShakeResult stair = shake_test(box, ParallelJawGripper{}, grasps, o);
  int simulated = 0;
  for (auto v : stair.trial_simulated) simulated += v;
  EXPECT_LT(simulated, static_cast<int>(full.trial_success.size()));
  for (std::size_t g = 0; g < grasps.size(); ++g)
    EXPECT_EQ(stair.score[g], full.score[g]) << "grasp " << g;
  for (std::size_t t = 0; t < full.trial_success.size(); ++t)
    if (stair.trial_simulated[t]) {
      EXPECT_EQ(stair.trial_success[t], full.trial_success[t]);
    }
}

TEST(Staircase, ResultsDoNotDependOnThreadCountWithUnevenGrasps) {
  // Grasps of very different cost (a grid that holds everywhere settles in a few trials, one
  // near the top edge needs the walk and may fall back to every cell) are handed to the threads
  // one at a time: whichever thread runs a grasp, and in whatever order, every trial's outcome,
  // step count and simulated flag must equal the single-thread run's, and the full grid's
  // (threads handed single trials) must equal it where simulated.
  const PhysicsObject box = box_object(Vec3d(0.04, 0.04, 0.06), 0.07);
  std::vector<ParallelJawGrasp> grasps;
  for (double dz : {0.027, 0.0, 0.022, 0.0, 0.012, 0.027, 0.0}) {
    ParallelJawGrasp g = centre_grasp(0.04);
    g.p1.z() = dz;
    grasps.push_back(g);
  }
  ShakeOptions o = small_grid(4, 0.1, 1.0);
  o.grip_force = 5.0;
  o.staircase = true;
  o.staircase_checks = 1;
  o.num_threads = 1;
  const ShakeResult one = shake_test(box, ParallelJawGripper{}, grasps, o);
  o.num_threads = 3;
  const ShakeResult three = shake_test(box, ParallelJawGripper{}, grasps, o);
  EXPECT_EQ(one.trial_success, three.trial_success);
  EXPECT_EQ(one.trial_steps, three.trial_steps);
  EXPECT_EQ(one.trial_simulated, three.trial_simulated);
  EXPECT_EQ(one.trial_ended_early, three.trial_ended_early);
  EXPECT_EQ(one.fallback, three.fallback);
  EXPECT_EQ(one.score, three.score);
  int min_trials = 16, max_trials = 0;  // the grasps really differ in cost
  for (std::size_t g = 0; g < grasps.size(); ++g) {
    int k = 0;
    for (int c = 0; c < 16; ++c) k += one.trial_simulated[g * 16 + c];
    min_trials = std::min(min_trials, k);
    max_trials = std::max(max_trials, k);
  }
  EXPECT_LT(min_trials, max_trials);
  o.staircase = false;
  const ShakeResult full = shake_test(box, ParallelJawGripper{}, grasps, o);
  for (std::size_t t = 0; t < full.trial_success.size(); ++t) {
    if (!one.trial_simulated[t]) continue;
    EXPECT_EQ(full.trial_success[t], one.trial_success[t]) << "trial " << t;
    EXPECT_EQ(full.trial_steps[t], one.trial_steps[t]) << "trial " << t;
  }
}

TEST(Shake, TrialsOfABatchEqualTrialsRunAloneWithTheirOwnShapes) {
  // shake_test builds the collision shapes once per worker and runs many trials with them;
  // shake_trajectory builds fresh shapes for its one trial. Every trial of a batch must be the
  // trial run alone: same outcome, same early exit, same number of steps (a step count is exact
  // to the step, so any state carried from one trial to the next would show). A two-part object
  // (a compound shape), grasps that hold and grasps that drop, both contact modes.
  PhysicsObject two = box_object(Vec3d(0.04, 0.05, 0.06), 1.2);
  Pose up = Pose::Identity(), down = Pose::Identity();
  up.translation() = Vec3d(0, 0, 0.015);
  down.translation() = Vec3d(0, 0, -0.015);
  two.convex_parts = {make_box(Vec3d(0.04, 0.05, 0.03)).transformed(up),
                      make_box(Vec3d(0.04, 0.05, 0.03)).transformed(down)};
  std::vector<ParallelJawGrasp> grasps = {centre_grasp(0.04), centre_grasp(0.04),
                                          centre_grasp(0.04)};
  grasps[1].p1 = Vec3d(-0.02, 0.015, 0.02);  // off-centre: torque about the closing axis
  grasps[2].p1 = Vec3d(-0.02, -0.01, -0.025);
  for (const bool polyhedral : {false, true}) {
    ShakeOptions o = small_grid(2, 0.1, 1.0);
    o.seed = 11;
    o.polyhedral_contacts = polyhedral;
    const ShakeResult r = shake_test(two, ParallelJawGripper{}, grasps, o);
    int held = 0, early = 0;
    for (std::size_t t = 0; t < r.trial_success.size(); ++t) {
      const std::size_t g = t / 4, i = (t % 4) / 2, j = t % 2;
      const ShakeTrajectory alone = shake_trajectory(
          two, ParallelJawGripper{}, grasps[g], r.frictions[i], r.density_factors[j], o, 1000, t);
      EXPECT_EQ(alone.success, r.trial_success[t] != 0) << "trial " << t << " " << polyhedral;
      EXPECT_EQ(alone.ended_early, r.trial_ended_early[t] != 0) << "trial " << t;
      EXPECT_EQ(alone.steps, r.trial_steps[t]) << "trial " << t << " " << polyhedral;
      held += r.trial_success[t];
      early += r.trial_ended_early[t];
    }
    EXPECT_GT(held, 0);  // mixed outcomes: the comparison covers held and dropped objects
    EXPECT_GT(early, 0);
  }
}

TEST(Shake, SkippingSeparatedPairsChangesNoTrial) {
  // The physics world's separated-pair skip (physics/world.hpp) skips Bullet's narrow phase only
  // where it would add nothing: every trial must be the same to the step with it on and off.
  // A compound of nine
  // small hulls with gaps between them (most hulls near a pad do not touch it), off-centre
  // grasps that hold and drop, both contact modes, the box and a mesh gripper.
  PhysicsObject grid = box_object(Vec3d(0.04, 0.05, 0.05), 0.6);
  grid.convex_parts.clear();
  for (int iy = -1; iy <= 1; ++iy) {
    for (int iz = -1; iz <= 1; ++iz) {
      Pose X = Pose::Identity();
      X.translation() = Vec3d(0.0, 0.017 * iy, 0.017 * iz);
      X.linear() = Eigen::AngleAxisd(0.3 * (iy + 2 * iz), Vec3d::UnitX()).toRotationMatrix();
      grid.convex_parts.push_back(make_box(Vec3d(0.036, 0.012, 0.012)).transformed(X));
    }
  }
  std::vector<ParallelJawGrasp> grasps = {centre_grasp(0.04), centre_grasp(0.04),
                                          centre_grasp(0.04)};
  grasps[1].p1 = Vec3d(-0.02, 0.012, 0.015);
  grasps[2].p1 = Vec3d(-0.02, -0.02, -0.01);
  ParallelJawGripper meshes;
  const GripperMeshes m = gripper_meshes(meshes, 0.0);
  meshes.palm_mesh = m.palm;
  meshes.finger_left_mesh = m.finger_left;
  meshes.finger_right_mesh = m.finger_right;
  int held = 0, dropped = 0;
  for (const bool polyhedral : {true, false}) {
    for (const ParallelJawGripper& gripper : {ParallelJawGripper{}, meshes}) {
      ShakeOptions o = small_grid(3, 0.1, 1.5);
      o.polyhedral_contacts = polyhedral;
      ShakeResult plain;
      {
        const ExtensionSwitches off({/*one_sided_rows=*/true, /*skip_separated_pairs=*/false});
        plain = shake_test(grid, gripper, grasps, o);
      }
      const ShakeResult skipping = shake_test(grid, gripper, grasps, o);
      for (std::size_t t = 0; t < plain.trial_success.size(); ++t) {
        EXPECT_EQ(skipping.trial_success[t], plain.trial_success[t]) << "trial " << t;
        EXPECT_EQ(skipping.trial_ended_early[t], plain.trial_ended_early[t]) << "trial " << t;
        EXPECT_EQ(skipping.trial_steps[t], plain.trial_steps[t]) << "trial " << t;
        held += plain.trial_success[t];
        dropped += !plain.trial_success[t];
      }
    }
  }
  EXPECT_GT(held, 0);  // mixed outcomes: the comparison covers held and dropped objects
  EXPECT_GT(dropped, 0);
}

TEST(Shake, OneSidedSolverRowsChangeNoTrial) {
  // The physics world's one-sided solver (physics/bullet_ext/one_sided_solver.hpp) changes
  // nothing but the cost: the object's pose and the fingers, step by step, are the same bits as
  // with Bullet's own solver (a light and a heavy object: a held and a dropped trial).
  const PhysicsObject box = box_object(Vec3d(0.04, 0.05, 0.05), 0.06);
  ShakeOptions o;
  o.seed = 5;
  std::set<bool> outcomes;
  for (const auto& [friction, density] : {std::pair{1.0, 1.0}, std::pair{0.05, 20.0}}) {
    const ShakeTrajectory fast =
        shake_trajectory(box, ParallelJawGripper{}, centre_grasp(0.04), friction, density, o, 1);
    ShakeTrajectory plain;
    {
      const ExtensionSwitches off({/*one_sided_rows=*/false, /*skip_separated_pairs=*/true});
      plain =
          shake_trajectory(box, ParallelJawGripper{}, centre_grasp(0.04), friction, density, o, 1);
    }
    ASSERT_EQ(fast.steps, plain.steps);
    EXPECT_EQ(fast.success, plain.success);
    ASSERT_EQ(fast.X_WO.size(), plain.X_WO.size());
    ASSERT_GT(fast.X_WO.size(), 10u);
    for (std::size_t k = 0; k < fast.X_WO.size(); ++k) {
      ASSERT_TRUE(fast.X_WO[k].matrix() == plain.X_WO[k].matrix()) << "record " << k;
      ASSERT_EQ(fast.finger_left[k], plain.finger_left[k]) << "record " << k;
      ASSERT_EQ(fast.finger_right[k], plain.finger_right[k]) << "record " << k;
    }
    outcomes.insert(fast.success);
  }
  EXPECT_EQ(outcomes.size(), 2u);  // both kinds of trial were compared
}

TEST(Shake, MeshGripperIsSimulatedWithItsOwnFingers) {
  // A user's mesh gripper: with the box gripper's own meshes it holds the box like the boxes do;
  // with fingers moved 60 mm sideways (they pass beside the box) it holds nothing, so the score
  // must follow the meshes, not the box fields (which stay the defaults).
  const PhysicsObject box = box_object(Vec3d(0.04, 0.04, 0.04), 0.05);
  const ShakeOptions o = small_grid(2, 1.0, 2.0);
  const ParallelJawGripper boxes;
  const ShakeResult by_boxes = shake_test(box, boxes, {centre_grasp(0.04)}, o);
  ParallelJawGripper same = boxes;
  const GripperMeshes m = gripper_meshes(boxes, 0.0);
  same.palm_mesh = m.palm;
  same.finger_left_mesh = m.finger_left;
  same.finger_right_mesh = m.finger_right;
  const ShakeResult by_meshes = shake_test(box, same, {centre_grasp(0.04)}, o);
  EXPECT_EQ(by_boxes.score[0], 1.0);
  EXPECT_EQ(by_meshes.score[0], 1.0);
  ParallelJawGripper aside = same;
  Pose shift = Pose::Identity();
  shift.translation() = Vec3d(0.0, 0.06, 0.0);
  aside.finger_left_mesh = m.finger_left.transformed(shift);
  aside.finger_right_mesh = m.finger_right.transformed(shift);
  const ShakeResult missed = shake_test(box, aside, {centre_grasp(0.04)}, o);
  EXPECT_EQ(missed.score[0], 0.0);
  const ShakeTrajectory tr = shake_trajectory(box, aside, centre_grasp(0.04), 1.0, 1.0, o, 10);
  for (std::size_t k = 0; k < tr.contact_left.size(); ++k)
    EXPECT_FALSE(tr.contact_left[k] || tr.contact_right[k]) << "a finger touched at " << k;
}

}  // namespace
}  // namespace mgn
