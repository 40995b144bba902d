// The Bullet shake test of parallel-jaw grasps (see shake_trial.hpp).
//
// One small btDiscreteDynamicsWorld per trial: a kinematic palm that follows the prescribed hand
// trajectory, two dynamic finger boxes on slider joints whose force-limited velocity motors close
// them, and the object as one rigid body (a convex hull, or a compound of convex hulls) in its
// principal-axes frame. A fresh world per trial keeps every trial independent of the others and
// of the thread that runs it; the collision shapes, which Bullet only reads, are built once per
// worker thread (TrialShapes).
#include <mgn/core/error.hpp>
#include <mgn/core/parallel.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/grasp/shake_trial.hpp>

#include "grasp/detail/staircase_schedule.hpp"
#include "physics/bullet.hpp"
#include "physics/world.hpp"

#include <btBulletDynamicsCommon.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>

namespace mgn {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kGroupHand = 1 << 6;
constexpr int kGroupObject = 1 << 7;

void require(bool ok, const char* field, const char* expected, double got) {
  if (!ok) {
    throw_error<InvalidArgument>("ShakeOptions.", field, ": expected ", expected, ", got ", got);
  }
}

std::vector<double> linspace(double lo, double hi, int n) {
  std::vector<double> v(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) v[i] = n == 1 ? lo : lo + (hi - lo) * i / (n - 1);
  return v;
}

/// The shake test runs in decimetres (see physics/bullet.hpp).
constexpr const physics::BulletUnits& kUnits = physics::kShakeUnits;

/// How the object's parts become Bullet hulls: inner support-direction reduction to at most
/// max_hull_vertices, the margin outside the hull.
physics::HullShapeOptions hull_options(const ShakeOptions& o) {
  physics::HullShapeOptions h;
  h.reduction = HullReduction::InnerSupportDirections;
  h.max_vertices = o.max_hull_vertices;
  h.margin = o.margin;
  h.polyhedral = o.polyhedral_contacts;
  return h;
}

/// The object prepared once per call: hulls of every part in the principal frame B.
struct PreparedObject {
  physics::RigidGeometry geometry;
  Pose X_OB = Pose::Identity();             // principal frame at the centre of mass
  Vec3d principal_inertia = Vec3d::Zero();  // kg m² at density factor 1
  double mass = 0.0;
};

PreparedObject prepare(const PhysicsObject& object, const ShakeOptions& o) {
  validate_physics_object(object);
  PreparedObject p;
  p.mass = object.mass;
  const PrincipalFrame principal = principal_frame(object, "PhysicsObject");
  p.principal_inertia = principal.moments;
  p.X_OB = principal.X_OB;
  p.geometry = physics::rigid_geometry(object, principal, kUnits, hull_options(o));
  return p;
}

void validate_grasps(const ParallelJawGripper& gripper,
                     const std::vector<ParallelJawGrasp>& grasps) {
  for (std::size_t i = 0; i < grasps.size(); ++i) {
    const ParallelJawGrasp& g = grasps[i];
    try {
      (void)hand_pose(g, gripper);
    } catch (const InvalidArgument& e) {
      throw_error<InvalidArgument>("shake_test: grasps[", i, "]: ", e.what());
    }
    if (g.width > gripper.max_opening) {
      throw_error<InvalidArgument>(
          "shake_test: grasps[", i, "].width = ", g.width,
          " m is wider than the gripper's max_opening = ", gripper.max_opening, " m");
    }
  }
}

/// Per-trial random choices and setting.
struct TrialSetting {
  double friction = 1.0;
  double density_factor = 1.0;
  double angle = 0.25;      // rotational shake amplitude, rad
  double axis_angle = 0.0;  // direction of the rotation axis in the hand xy plane, rad
};

TrialSetting make_setting(double friction, double density, const ShakeOptions& o,
                          std::uint64_t trial_index) {
  Rng rng(o.seed, trial_index);
  TrialSetting s;
  s.friction = friction;
  s.density_factor = density;
  s.angle = rng.uniform(o.angle_min, o.angle_max);
  s.axis_angle = rng.uniform(0.0, 2.0 * kPi);
  return s;
}

struct TrialOutcome {
  bool success = false;
  bool ended_early = false;
  int steps = 0;
};

/// A trial's world: pools for four bodies (Bullet's defaults, 4096 manifolds and algorithms,
/// cost megabytes of memory to set up per trial); the narrow phase of (finger or palm, object
/// hull) pairs skipped while a pair is provably apart (the same simulation, see
/// physics/world.hpp).
physics::WorldOptions world_options() {
  physics::WorldOptions w;
  w.pool_size = 32;
  w.skip_separated_pairs = true;
  return w;
}

/// ShakeOptions::adapt_controller_gain: the most the controller's stiffness is raised (2^6).
constexpr double kMaxGainBackoff = 64.0;
/// ShakeOptions::adapt_controller_gain: consecutive flips of the force error that halve the gain.
constexpr int kFlipsToBackOff = 4;
/// ShakeOptions::adapt_controller_gain: a flip counts once both errors are at least this share of
/// the grip force.
constexpr double kFlipBand = 0.25;

/// The step per which ShakeOptions::controller_stiffness gives the force controller's move, s.
constexpr double kControllerStep = 1.0 / 400.0;

/// Peak of ShakeOptions::smooth_shake's profile sin x − sin(2x)/2: 3√3/4.
constexpr double kSmoothPeak = 1.299038105676658;

/// Hand trajectory: X_WH as a function of the phase and the time within it.
class HandPath {
 public:
  HandPath(const ParallelJawGripper& g, const ShakeOptions& o, const TrialSetting& s) : o_(o) {
    X_WH0_ = Pose::Identity();
    X_WH0_.linear() = Eigen::AngleAxisd(kPi, Vec3d::UnitX()).toRotationMatrix();
    const double Ts = o.shake_steps * o.dt;
    omega_s_ = Ts > 0 ? 2.0 * kPi * o.shake_cycles / Ts : 0.0;
    amp_s_ = omega_s_ > 0 ? o.shake_speed / omega_s_ : 0.0;
    const double Tr = o.rotate_steps * o.dt;
    omega_r_ = Tr > 0 ? 2.0 * kPi * o.rotate_cycles / Tr : 0.0;
    angle_ = s.angle;
    axis_ = Vec3d(std::cos(s.axis_angle), std::sin(s.axis_angle), 0.0);
    centre_ = Vec3d(0.0, 0.0, g.grasp_depth());
  }
  const Pose& initial() const { return X_WH0_; }
  /// ShakeOptions::smooth_shake's profile f(x) = sin x − sin(2x)/2 (f'(0) = f'(2π) = 0,
  /// |f'| <= 2 at x = π, max f = 3√3/4 at x = 2π/3), else sin x.
  static double smooth_profile(double x) { return std::sin(x) - 0.5 * std::sin(2.0 * x); }
  Pose translate(double t) const {
    Pose X = X_WH0_;
    const double x = omega_s_ * t;
    // Smooth: half the amplitude keeps the peak speed A ω (|f'| <= 2).
    const double z = o_.smooth_shake ? 0.5 * amp_s_ * smooth_profile(x) : amp_s_ * std::sin(x);
    X.translate(Vec3d(0.0, 0.0, z));
    return X;
  }
  Pose rotate(double t) const {
    const double x = omega_r_ * t;
    const double theta =
        o_.smooth_shake ? angle_ * smooth_profile(x) / kSmoothPeak : angle_ * std::sin(x);
    Pose R = Pose::Identity();
    R.linear() = Eigen::AngleAxisd(theta, axis_).toRotationMatrix();
    R.translation() = centre_ - R.linear() * centre_;
    return X_WH0_ * R;
  }

 private:
  const ShakeOptions& o_;
  Pose X_WH0_;
  double omega_s_ = 0, amp_s_ = 0, omega_r_ = 0, angle_ = 0;
  Vec3d axis_, centre_;
};

/// What a trial reports after every step (for recording).
struct StepState {
  double time;
  ShakePhase phase;
  Pose X_WO, X_WH;
  double left, right;
  bool touch_left, touch_right;
  double force_left, force_right;  // normal pad force of the last step, N
  int hull_contacts;               // (finger, object hull) pairs in contact
  int points_left, points_right;   // contact points closer than contact_distance, per finger
  int iterations;                  // solver iterations of the step just run (0: none run yet)
};

/// The collision shapes of one shake_test call: the object's hulls (a compound if several) and
/// the gripper's palm and fingers, built once and used by every trial world of a worker thread.
/// Bullet only reads a shape during collision detection, and a shape built from the same points
/// and options is the same whether it is built once or per trial, so sharing them leaves every
/// trial bit-identical; it saves rebuilding tens of hulls per trial (with polyhedral contacts,
/// their face data too: about 5 ms per trial for a 27-part mug).
struct TrialShapes {
  physics::RigidShape object;
  std::unique_ptr<btBoxShape> palm_box, finger_box;
  std::unique_ptr<btConvexHullShape> mesh[3];  // palm, left, right (mesh gripper)
  btCollisionShape* palm = nullptr;
  btCollisionShape* finger[2] = {nullptr, nullptr};

  TrialShapes(const PreparedObject& obj, const ParallelJawGripper& g, const ShakeOptions& o) {
    object = physics::rigid_shape(obj.geometry, kUnits, hull_options(o), false);
    if (g.has_meshes()) {
      // A user's mesh gripper: palm and fingers are the convex hulls of their meshes (hand frame
      // H, fingers closed; at an inner-face offset d each finger moves by -d / +d along x).
      physics::HullShapeOptions h;
      h.margin = o.margin;
      h.shrink_by_margin = true;  // the surface stays the mesh's, as with the boxes
      h.polyhedral = o.polyhedral_contacts;
      const Mesh* meshes[3] = {&g.palm_mesh, &g.finger_left_mesh, &g.finger_right_mesh};
      for (int k = 0; k < 3; ++k)
        mesh[k] = physics::hull_shape(physics::hull_points(*meshes[k], Pose::Identity(), kUnits, h),
                                      kUnits, h);
      palm = mesh[0].get();
      finger[0] = mesh[1].get();
      finger[1] = mesh[2].get();
    } else {
      palm_box = std::make_unique<btBoxShape>(kUnits.vector(Vec3d(0.5 * g.palm_size)));
      finger_box = std::make_unique<btBoxShape>(kUnits.vector(Vec3d(0.5 * g.finger_size)));
      for (btBoxShape* b : {palm_box.get(), finger_box.get()}) {
        b->setMargin(btScalar(kUnits.length * o.margin));
        if (o.polyhedral_contacts) b->initializePolyhedralFeatures();
      }
      palm = palm_box.get();
      finger[0] = finger[1] = finger_box.get();
    }
  }
  TrialShapes(const TrialShapes&) = delete;
  TrialShapes& operator=(const TrialShapes&) = delete;
};

/// One trial's Bullet world. The palm and the fingers are kinematic bodies that follow the hand
/// path; the object is the only dynamic body, so the solver never has to balance a light object
/// between two heavy pushers. The finger pads are soft (Bullet's implicit contact stiffness and
/// damping), which makes the squeeze force well defined, and a force controller sets the common
/// finger offset so that the mean pad force equals the grip force: the fingers move together,
/// symmetric about the hand axis, like the rack and pinion of a Franka hand.
class TrialWorld {
 public:
  TrialWorld(const PreparedObject& obj, const TrialShapes& shapes, const ParallelJawGripper& g,
             const ParallelJawGrasp& grasp, const TrialSetting& s, const ShakeOptions& o)
      : g_(g),
        o_(o),
        path_(g, o, s),
        physics_(world_options()),
        world_(physics_.dynamics()),
        dispatcher_(physics_.dispatcher()) {
    world_.setGravity(btVector3(0, 0, 0));
    btContactSolverInfo& info = world_.getSolverInfo();
    // Light objects squeezed hard need more sequential-impulse iterations to stay steady.
    const double trial_mass = obj.mass * s.density_factor;
    const double load = o.grip_force / (150.0 * trial_mass * std::max(o.gravity, 1.0));
    const int boost = static_cast<int>(std::clamp(std::ceil(load), 1.0, 8.0));
    // ShakeOptions::compound_solver_iterations: a shape of several hulls may use others.
    const bool compound = obj.geometry.hulls.size() > 1;
    const bool own = compound && o.compound_solver_iterations > 0;
    const int iterations = own ? o.compound_solver_iterations : o.solver_iterations;
    base_iterations_ = iterations * boost;
    info.m_numIterations = base_iterations_;
    boost_ = boost;
    point_budget_ = own ? o.compound_iteration_points : 0.0;
    // Friction in both tangent directions (Bullet's default is one direction per contact point,
    // which lets a held object creep sideways).
    info.m_solverMode |= SOLVER_USE_2_FRICTION_DIRECTIONS;
    X_OB_ = obj.X_OB;

    if (g.has_meshes()) {
      palm_centre_ = Vec3d::Zero();
      finger_z_ = 0.0;
      finger_half_x_ = 0.0;
    } else {
      const Vec3d& f = g.finger_size;
      palm_centre_ = Vec3d(0.0, 0.0, g.flange_to_tip - f.z() - 0.5 * g.palm_size.z());
      finger_z_ = g.flange_to_tip - 0.5 * f.z();
      finger_half_x_ = 0.5 * f.x();
    }

    d_ = 0.5 * g.collision_opening(grasp.width);
    const Pose X_WH = path_.initial();
    palm_ = make_kinematic(shapes.palm, palm_pose(X_WH), 1.0);
    for (int side = 0; side < 2; ++side) {
      fingers_[side] = make_kinematic(shapes.finger[side], finger_pose(X_WH, side, d_), 1.0);
      fingers_[side]->setContactStiffnessAndDamping(btScalar(o.pad_stiffness),
                                                    btScalar(o.pad_damping));
    }

    // Object: one hull, or a compound of hulls, in its principal frame B.
    const double m = obj.mass * s.density_factor;
    // Inertia floor (see ShakeOptions::inertia_floor): m (floor·R)² about every principal axis.
    radius_ = obj.geometry.bounding_radius;
    const double rho = o.inertia_floor * radius_;
    const Vec3d I = (obj.principal_inertia * s.density_factor).cwiseMax(m * rho * rho);
    const Pose X_HO = hand_pose(grasp, g).inverse();
    btRigidBody::btRigidBodyConstructionInfo ci =
        physics::body_info(m, I, shapes.object.shape(), X_WH * X_HO * obj.X_OB, kUnits);
    ci.m_friction = btScalar(s.friction);
    ci.m_restitution = 0;
    object_ = std::make_unique<btRigidBody>(ci);
    object_->setActivationState(DISABLE_DEACTIVATION);
    world_.addRigidBody(object_.get(), kGroupObject, kGroupHand);
  }

  ~TrialWorld() {
    world_.removeRigidBody(object_.get());
    for (auto& f : fingers_) world_.removeRigidBody(f.get());
    world_.removeRigidBody(palm_.get());
  }

  TrialWorld(const TrialWorld&) = delete;
  TrialWorld& operator=(const TrialWorld&) = delete;

  template <typename Recorder>
  TrialOutcome run(Recorder&& record) {
    TrialOutcome out;
    double time = 0.0;
    Pose X_WH = path_.initial();
    StepState last = state(time, ShakePhase::Close, X_WH);
    record(last);

    // Closing, gravity off.
    int settled = 0;
    for (int k = 0; k < o_.close_steps; ++k) {
      step(X_WH, X_WH, last);
      time += o_.dt;
      ++out.steps;
      last = state(time, ShakePhase::Close, X_WH);
      record(last);
      const bool at_force = std::abs(0.5 * (last.force_left + last.force_right) - o_.grip_force) <
                            0.05 * o_.grip_force;
      settled = (last.touch_left && last.touch_right && at_force) ? settled + 1 : 0;
      if (o_.settle_steps > 0 && settled >= o_.settle_steps) break;
      if (o_.lost_contact_steps > 0 && !last.touch_left && !last.touch_right && d_ <= 0.0) {
        out.ended_early = true;  // closed on nothing
        return out;
      }
    }

    world_.setGravity(btVector3(0, 0, btScalar(-kUnits.length * o_.gravity)));
    int lost[2] = {0, 0};
    // Held-load windows (ShakeOptions::hold_tolerance), in steps of each shake phase: if the
    // object stays at rest in the hand from step `from` to step `to` (both fingers touching at
    // `to`), the rest of the phase only repeats loads held in the window, and the phase ends
    // there. Translation: a window over the first cycle's extremes of the acceleration
    // [T/(4n), T/n]; the later cycles repeat it (without the initial velocity jump), so the
    // hand skips to t = T, where it has the same pose and velocity as at T/n. Rotation: the
    // last half swing [T − T/(2n), T − T/(4n)]; the rest mirrors it in time, so the trial ends
    // as a success. Rounding widens the windows.
    struct Window {
      int from = 0, to = 0;
      bool on = false;
    } window[3];
    if (o_.hold_tolerance > 0 && !o_.smooth_shake) {  // the windows assume the sine profile
      const int ns = o_.shake_steps, cs = o_.shake_cycles, nr = o_.rotate_steps;
      const int cycle = cs >= 2 && ns % cs == 0 ? ns / cs : 0;
      window[1] = {cycle / 4, cycle, cycle >= 4};
      const int from = nr - static_cast<int>(std::ceil(nr / (2.0 * o_.rotate_cycles)));
      const int to = nr - static_cast<int>(std::floor(nr / (4.0 * o_.rotate_cycles)));
      window[2] = {from, to, from >= 1 && to < nr};
    }
    for (int phase = 1; phase <= 2; ++phase) {
      const int n = phase == 1 ? o_.shake_steps : o_.rotate_steps;
      const Window& w = window[phase];
      Pose X_HO_ref = Pose::Identity();
      bool held = true;
      for (int k = 0; k < n; ++k) {
        const double t = (k + 1) * o_.dt;
        const Pose X_next = phase == 1 ? path_.translate(t) : path_.rotate(t);
        step(X_WH, X_next, last);
        X_WH = X_next;
        time += o_.dt;
        ++out.steps;
        last = state(time, phase == 1 ? ShakePhase::Translate : ShakePhase::Rotate, X_WH);
        record(last);
        lost[0] = last.touch_left ? 0 : lost[0] + 1;
        lost[1] = last.touch_right ? 0 : lost[1] + 1;
        if (o_.lost_contact_steps > 0 && std::max(lost[0], lost[1]) >= o_.lost_contact_steps) {
          out.ended_early = true;
          return out;
        }
        if (!w.on || k + 1 < w.from || k + 1 > w.to) continue;
        const Pose X_HO = X_WH.inverse() * last.X_WO;
        if (k + 1 == w.from) {
          X_HO_ref = X_HO;
          continue;
        }
        const Pose D = X_HO_ref.inverse() * X_HO;
        const double turn = Eigen::AngleAxisd(D.linear()).angle();
        held = held && D.translation().norm() + turn * radius_ <= o_.hold_tolerance;
        if (k + 1 < w.to) continue;
        if (held && last.touch_left && last.touch_right) {
          out.ended_early = true;
          if (phase == 2) {
            out.success = true;
            return out;
          }
          time += (n - w.to) * o_.dt;  // skip to the end of the translation
          break;
        }
      }
    }
    out.success = last.touch_left && last.touch_right;
    return out;
  }

 private:
  std::unique_ptr<btRigidBody> make_kinematic(btCollisionShape* shape, const Pose& X,
                                              double friction) {
    btRigidBody::btRigidBodyConstructionInfo ci(0, nullptr, shape);
    ci.m_startWorldTransform = kUnits.pose(X);
    ci.m_friction = btScalar(friction);
    auto body = std::make_unique<btRigidBody>(ci);
    body->setCollisionFlags(body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    body->setActivationState(DISABLE_DEACTIVATION);
    world_.addRigidBody(body.get(), kGroupHand, kGroupObject);
    return body;
  }

  Pose palm_pose(const Pose& X_WH) const {
    Pose X = X_WH;
    X.translate(palm_centre_);
    return X;
  }

  /// Finger box centre for an inner-face offset d from the hand axis (side 0: −x, 1: +x).
  Pose finger_pose(const Pose& X_WH, int side, double d) const {
    const double sign = side == 0 ? -1.0 : 1.0;
    Pose X = X_WH;
    X.translate(Vec3d(sign * (d + finger_half_x_), 0.0, finger_z_));
    return X;
  }

  /// Bullet moves a kinematic body to its new pose before the solve and derives its velocity
  /// from the jump, which makes contacts see the move one step late. Instead each hand body stays
  /// at its pose at the start of the step, with the velocity of the move to its pose at the end
  /// (through a virtual previous pose), and jumps there after the step.
  static void drive(btRigidBody& body, const Pose& now_pose, const Pose& next_pose) {
    const btTransform now = kUnits.pose(now_pose);
    const btTransform next = kUnits.pose(next_pose);
    btTransform before;
    before.setBasis((now.getBasis() * next.getBasis().transpose()) * now.getBasis());
    before.setOrigin(now.getOrigin() * 2 - next.getOrigin());
    body.setWorldTransform(now);
    body.setInterpolationWorldTransform(before);
  }

  /// Force controller of the common finger offset d: close at close_speed until a finger
  /// touches, then move by (mean pad force − grip force) / controller stiffness per step,
  /// limited to close_speed.
  double next_offset(const StepState& s) {
    const double vmax = o_.close_speed * o_.dt;
    if (!s.touch_left && !s.touch_right) {
      flips_ = -1;
      return std::max(0.0, d_ - vmax);
    }
    const double error = 0.5 * (s.force_left + s.force_right) - o_.grip_force;
    if (o_.adapt_controller_gain) {
      // ShakeOptions::adapt_controller_gain: an error that flips sign on 4 consecutive steps
      // without shrinking to half, beyond a quarter of the grip force throughout, is a
      // sustained period-2 oscillation, a loop gain at or above 2 (the solver's contact stiffer
      // than the model below), not the ringing of a finger arriving at close_speed: halve the
      // gain for the rest of the trial.
      if (flips_ >= 0) {
        const double a = std::abs(last_error_), b = std::abs(error);
        const bool flip =
            last_error_ * error < 0 && b >= 0.5 * a && std::min(a, b) >= kFlipBand * o_.grip_force;
        flips_ = flip ? flips_ + 1 : 0;
      } else {
        flips_ = 0;
      }
      if (flips_ >= kFlipsToBackOff && gain_backoff_ < kMaxGainBackoff) {
        gain_backoff_ *= 2.0;
        flips_ = 0;
      }
      last_error_ = error;
    }
    // ShakeOptions::controller_stiffness is per 1/400 s: a step dt moves the fingers dt·400
    // times as far for the same error (exactly controller_stiffness at dt = 1/400 s).
    double stiffness = o_.controller_stiffness;
    if (o_.dt != kControllerStep) stiffness *= kControllerStep / o_.dt;
    if (o_.limit_controller_gain) {
      // A move of the fingers by x within one step changes the mean pad force by about
      // n (k + c/dt) x: n touching points per pad, each a spring k and a damper c moved at
      // x/dt. Moving by at most the error over that stiffness keeps the loop stable (see
      // ShakeOptions::limit_controller_gain).
      const double points = 0.5 * (s.points_left + s.points_right);
      stiffness = std::max(stiffness, points * (o_.pad_stiffness + o_.pad_damping / o_.dt));
    }
    const double delta = std::clamp(error / (gain_backoff_ * stiffness), -vmax, vmax);
    return std::clamp(d_ + delta, 0.0, 0.5 * g_.max_opening);
  }

  void step(const Pose& X_WH, const Pose& X_WH_next, const StepState& s) {
    const double d_next = next_offset(s);
    drive(*palm_, palm_pose(X_WH), palm_pose(X_WH_next));
    for (int side = 0; side < 2; ++side) {
      drive(*fingers_[side], finger_pose(X_WH, side, d_), finger_pose(X_WH_next, side, d_next));
    }
    int iterations = base_iterations_;
    const int points = s.points_left + s.points_right;
    if (point_budget_ > 0 && points > point_budget_) {
      // ShakeOptions::compound_iteration_points: the fingers touched the compound at more points
      // than the budget at the last step; its iterations shrink in proportion, down to
      // solver_iterations.
      const int floor = std::min(o_.solver_iterations, o_.compound_solver_iterations);
      const int budget =
          static_cast<int>(std::ceil(o_.compound_solver_iterations * point_budget_ / points));
      iterations = std::max(floor, budget) * boost_;
    }
    if (o_.iterations_per_hull_contact > 0) {
      // ShakeOptions::iterations_per_hull_contact: the (finger, hull) pairs in contact at the
      // last step set this step's iterations (a compound held by several hulls needs more).
      const int want =
          static_cast<int>(std::ceil(o_.iterations_per_hull_contact * s.hull_contacts));
      iterations = std::max(iterations, want);
    }
    world_.getSolverInfo().m_numIterations = iterations;
    world_.stepSimulation(btScalar(o_.dt), 0, btScalar(o_.dt));
    last_iterations_ = iterations;
    d_ = d_next;
    // The hand bodies jump to their end-of-step poses (velocity unchanged until the next step).
    palm_->setWorldTransform(kUnits.pose(palm_pose(X_WH_next)));
    palm_->setInterpolationWorldTransform(palm_->getWorldTransform());
    for (int side = 0; side < 2; ++side) {
      fingers_[side]->setWorldTransform(kUnits.pose(finger_pose(X_WH_next, side, d_)));
      fingers_[side]->setInterpolationWorldTransform(fingers_[side]->getWorldTransform());
    }
  }

  StepState state(double time, ShakePhase phase, const Pose& X_WH) {
    StepState s;
    s.time = time;
    s.phase = phase;
    s.X_WH = X_WH;
    s.X_WO = kUnits.pose(object_->getWorldTransform()) * X_OB_.inverse();
    s.left = s.right = d_;
    s.touch_left = s.touch_right = false;
    s.force_left = s.force_right = 0.0;
    s.hull_contacts = 0;
    s.points_left = s.points_right = 0;
    s.iterations = last_iterations_;
    // The fingers' opening directions in W (ShakeOptions::controller_net_force): −x_H, +x_H.
    const Vec3d x_H = X_WH.linear().col(0);
    const int n = dispatcher_.getNumManifolds();
    for (int i = 0; i < n; ++i) {
      const btPersistentManifold* m = dispatcher_.getManifoldByIndexInternal(i);
      const btCollisionObject* a = m->getBody0();
      const btCollisionObject* b = m->getBody1();
      const btCollisionObject* other = a == object_.get() ? b : (b == object_.get() ? a : nullptr);
      if (other == nullptr) continue;
      const int side = other == fingers_[0].get() ? 0 : (other == fingers_[1].get() ? 1 : -1);
      if (side < 0) continue;
      s.hull_contacts += m->getNumContacts() > 0;  // one manifold per (finger, hull)
      bool& touch = side == 0 ? s.touch_left : s.touch_right;
      double& force = side == 0 ? s.force_left : s.force_right;
      int& points = side == 0 ? s.points_left : s.points_right;
      for (int c = 0; c < m->getNumContacts(); ++c) {
        const btManifoldPoint& p = m->getContactPoint(c);
        if (p.getDistance() < kUnits.length * o_.contact_distance) {
          touch = true;
          ++points;
        }
        const double f = kUnits.force(p.getAppliedImpulse(), o_.dt);
        if (!o_.controller_net_force) {
          force += f;
          continue;
        }
        // The normal on B points towards A: the contact pushes A along it, B against it.
        const btVector3& nB = p.m_normalWorldOnB;
        const Vec3d on_finger = (a == object_.get() ? -1.0 : 1.0) * Vec3d(nB.x(), nB.y(), nB.z());
        force += f * on_finger.dot(side == 0 ? -x_H : x_H);
      }
    }
    return s;
  }

  const ParallelJawGripper& g_;
  const ShakeOptions& o_;
  HandPath path_;
  Pose X_OB_;
  Vec3d palm_centre_;
  double finger_z_ = 0;
  double finger_half_x_ = 0;  // finger box: centre to inner face along x, m (meshes: 0)
  double d_ = 0;              // current inner-face offset of both fingers from the hand axis, m
  double radius_ = 0;         // object: largest distance of a hull vertex from the com, m
  int base_iterations_ = 1;   // solver iterations of this trial without per-hull ones
  int boost_ = 1;             // the light-object multiplier of the solver iterations, 1..8
  double point_budget_ = 0;   // ShakeOptions::compound_iteration_points (a compound), else 0
  int last_iterations_ = 0;   // solver iterations of the last step run (0: none yet)
  double gain_backoff_ = 1;   // controller stiffness multiplier (adapt_controller_gain), >= 1
  double last_error_ = 0;     // the controller's force error at the previous step, N
  int flips_ = -1;            // consecutive flips of that error (-1: no previous touching step)

  physics::World physics_;  // Bullet's world (physics/world.hpp)
  btDiscreteDynamicsWorld& world_;
  btCollisionDispatcher& dispatcher_;

  std::unique_ptr<btRigidBody> palm_, object_;
  std::unique_ptr<btRigidBody> fingers_[2];
};

}  // namespace

void ShakeOptions::validate() const {
  require(grid >= 1, "grid", "an integer >= 1", grid);
  require(std::isfinite(friction_min) && friction_min >= 0, "friction_min", "a finite value >= 0",
          friction_min);
  require(std::isfinite(friction_max) && friction_max >= friction_min, "friction_max",
          "a finite value >= friction_min", friction_max);
  require(std::isfinite(density_min) && density_min > 0, "density_min", "a finite value > 0",
          density_min);
  require(std::isfinite(density_max) && density_max >= density_min, "density_max",
          "a finite value >= density_min", density_max);
  require(std::isfinite(dt) && dt > 0 && dt <= 0.1, "dt", "a time step in (0, 0.1] s", dt);
  require(close_steps >= 1, "close_steps", "an integer >= 1", close_steps);
  require(shake_steps >= 0, "shake_steps", "an integer >= 0", shake_steps);
  require(rotate_steps >= 0, "rotate_steps", "an integer >= 0", rotate_steps);
  require(std::isfinite(gravity) && gravity >= 0, "gravity", "a finite value >= 0 (m/s^2)",
          gravity);
  require(std::isfinite(shake_speed) && shake_speed >= 0, "shake_speed", "a finite value >= 0",
          shake_speed);
  require(shake_cycles >= 1, "shake_cycles", "an integer >= 1", shake_cycles);
  require(rotate_cycles >= 1, "rotate_cycles", "an integer >= 1", rotate_cycles);
  require(std::isfinite(angle_min) && angle_min >= 0 && angle_min <= kPi, "angle_min",
          "an angle in [0, pi] rad", angle_min);
  require(std::isfinite(angle_max) && angle_max >= angle_min && angle_max <= kPi, "angle_max",
          "an angle in [angle_min, pi] rad", angle_max);
  require(std::isfinite(grip_force) && grip_force > 0, "grip_force", "a finite force > 0 (N)",
          grip_force);
  require(std::isfinite(close_speed) && close_speed > 0, "close_speed", "a finite speed > 0",
          close_speed);
  require(std::isfinite(pad_stiffness) && pad_stiffness > 0, "pad_stiffness",
          "a finite stiffness > 0 (N/m)", pad_stiffness);
  require(std::isfinite(pad_damping) && pad_damping >= 0, "pad_damping",
          "a finite damping >= 0 (N s/m)", pad_damping);
  require(std::isfinite(inertia_floor) && inertia_floor >= 0 && inertia_floor <= 10,
          "inertia_floor", "a factor in [0, 10]", inertia_floor);
  require(std::isfinite(controller_stiffness) && controller_stiffness > 0, "controller_stiffness",
          "a finite stiffness > 0 (N/m)", controller_stiffness);
  require(std::isfinite(contact_distance) && contact_distance > 0, "contact_distance",
          "a finite distance > 0 (m)", contact_distance);
  require(settle_steps >= 0, "settle_steps", "an integer >= 0", settle_steps);
  require(std::isfinite(hold_tolerance) && hold_tolerance >= 0 && hold_tolerance < 0.1,
          "hold_tolerance", "a distance in [0, 0.1) m (0 = off)", hold_tolerance);
  require(lost_contact_steps >= 0, "lost_contact_steps", "an integer >= 0", lost_contact_steps);
  require(std::isfinite(margin) && margin > 0 && margin < 0.01, "margin",
          "a collision margin in (0, 0.01) m", margin);
  require(max_hull_vertices >= 8 && max_hull_vertices <= 100000, "max_hull_vertices",
          "an integer in [8, 100000]", max_hull_vertices);
  require(solver_iterations >= 1 && solver_iterations <= 1000, "solver_iterations",
          "an integer in [1, 1000]", solver_iterations);
  require(compound_solver_iterations >= 0 && compound_solver_iterations <= 1000,
          "compound_solver_iterations", "an integer in [0, 1000] (0 = solver_iterations)",
          compound_solver_iterations);
  require(std::isfinite(compound_iteration_points) && compound_iteration_points >= 0 &&
              compound_iteration_points <= 10000,
          "compound_iteration_points", "a number of contact points in [0, 10000] (0 = off)",
          compound_iteration_points);
  require(std::isfinite(iterations_per_hull_contact) && iterations_per_hull_contact >= 0 &&
              iterations_per_hull_contact <= 100,
          "iterations_per_hull_contact", "a factor in [0, 100] (0 = off)",
          iterations_per_hull_contact);
  require(staircase_checks >= 0, "staircase_checks", "an integer >= 0", staircase_checks);
  require(std::isfinite(staircase_verify_share) && staircase_verify_share >= 0 &&
              staircase_verify_share <= 1,
          "staircase_verify_share", "a share of the rows in [0, 1]", staircase_verify_share);
  require(num_threads >= 0, "num_threads", "an integer >= 0 (0 = all hardware threads)",
          num_threads);
}

int ShakeOptions::staircase_verified_rows() const {
  return static_cast<int>(std::ceil(staircase_verify_share * grid - 1e-9));
}

std::vector<double> ShakeOptions::frictions() const {
  return linspace(friction_min, friction_max, grid);
}

std::vector<double> ShakeOptions::density_factors() const {
  return linspace(density_min, density_max, grid);
}

void validate_physics_object(const PhysicsObject& object) {
  if (object.convex_parts.empty()) {
    throw_error<InvalidArgument>(
        "PhysicsObject.convex_parts: expected at least one convex part, got none");
  }
  for (std::size_t i = 0; i < object.convex_parts.size(); ++i) {
    const Points3f& V = object.convex_parts[i].vertices();
    if (V.rows() < 4) {
      throw_error<InvalidArgument>("PhysicsObject.convex_parts[", i,
                                   "]: expected at least 4 vertices, got ", V.rows());
    }
    const Eigen::MatrixXd P = V.cast<double>();
    const Eigen::MatrixXd C = P.rowwise() - P.colwise().mean();
    Eigen::SelfAdjointEigenSolver<Mat3d> eig(C.transpose() * C / double(V.rows()));
    const Vec3d& ev = eig.eigenvalues();
    if (!(ev[0] > 1e-12 * ev[2]) || !(ev[2] > 0)) {
      throw_error<InvalidArgument>("PhysicsObject.convex_parts[", i,
                                   "]: expected a solid part, got points that are (nearly) ",
                                   ev[2] > 0 ? "coplanar" : "coincident");
    }
  }
  if (!std::isfinite(object.mass) || !(object.mass > 0)) {
    throw_error<InvalidArgument>("PhysicsObject.mass: expected a finite mass > 0 kg, got ",
                                 object.mass);
  }
  if (!object.com.allFinite()) {
    throw_error<InvalidArgument>("PhysicsObject.com: expected a finite point (m)");
  }
  const Mat3d& I = object.inertia;
  if (!I.allFinite()) {
    throw_error<InvalidArgument>("PhysicsObject.inertia: expected finite values (kg m^2)");
  }
  if ((I - I.transpose()).cwiseAbs().maxCoeff() > 1e-6 * I.cwiseAbs().maxCoeff()) {
    throw_error<InvalidArgument>("PhysicsObject.inertia: expected a symmetric matrix");
  }
  Eigen::SelfAdjointEigenSolver<Mat3d> eig(I);
  if (!(eig.eigenvalues()[0] > 0)) {
    throw_error<InvalidArgument>(
        "PhysicsObject.inertia: expected a positive-definite matrix, smallest eigenvalue ",
        eig.eigenvalues()[0]);
  }
}

namespace detail {

StaircaseGrid staircase_walk(int S, const std::function<bool(int, int)>& trial, int checks,
                             int verified_rows) {
  if (S < 1) throw_error<InvalidArgument>("staircase_grid: S must be >= 1, got ", S);
  if (verified_rows < 0 || verified_rows > S) verified_rows = S;
  if (checks < 0) throw_error<InvalidArgument>("staircase_grid: checks must be >= 0, got ", checks);
  StaircaseGrid g;
  const std::size_t n = static_cast<std::size_t>(S) * S;
  g.success.assign(n, 0);
  g.simulated.assign(n, 0);
  auto at = [S](int i, int j) { return static_cast<std::size_t>(i) * S + j; };
  auto run = [&](int i, int j) {
    const bool ok = trial(i, j);
    g.success[at(i, j)] = ok;
    g.simulated[at(i, j)] = 1;
    ++g.trials;
    return ok;
  };
  // The walk: b[i] = successes in row i (cells j < b[i]), b[i] in [b[i-1], S]. Cell (i, j)
  // succeeds iff j < b[i], so b[i] is found by probing cells: row 0 first probes its hardest
  // cell (S-1: most grids succeed everywhere, one trial then settles the grid); every row
  // probes the previous row's boundary cell, then gallops right (lo, lo+1, lo+3, ...) and
  // bisects the last gap. A row whose lower bound is S costs nothing.
  std::vector<int> b(static_cast<std::size_t>(S), 0);
  int lo = 0;
  for (int i = 0; i < S; ++i) {
    int hi = S;  // b[i] in [lo, hi]
    if (i == 0 && lo < hi) {
      if (run(i, hi - 1))
        lo = hi;
      else
        hi = hi - 1;
    }
    for (int step = 1; lo < hi;) {  // gallop: probe lo + step - 1
      const int j = std::min(lo + step - 1, hi - 1);
      if (run(i, j)) {
        lo = j + 1;
        step *= 2;
      } else {
        hi = j;
        break;
      }
    }
    while (lo < hi) {  // bisect: b[i] in [lo, hi]
      const int m = lo + (hi - lo) / 2;
      if (run(i, m))
        lo = m + 1;
      else
        hi = m;
    }
    b[i] = lo;
    for (int k = 0; k < lo; ++k) g.success[at(i, k)] = 1;  // inferred (or simulated) successes
  }
  // Verification: in every row the inferred cell nearest to the boundary on each side (the
  // last success b-1, else b-2 if the walk simulated b-1; the first failure b, else b+1), then
  // the first `checks` other inferred cells in a golden-ratio (low-discrepancy) order over the
  // grid, which finds isolated failures away from the boundary. The first contradiction stops
  // the checks and every remaining cell is simulated.
  std::vector<std::pair<int, int>> candidates;
  std::vector<std::uint8_t> queued(n, 0);
  for (int i = 0; i < verified_rows; ++i) {
    for (const int side : {-1, 1}) {
      int cj = side < 0 ? b[i] - 1 : b[i];
      if (cj >= 0 && cj < S && g.simulated[at(i, cj)]) cj += side;
      if (cj < 0 || cj >= S || g.simulated[at(i, cj)] || queued[at(i, cj)]) continue;
      queued[at(i, cj)] = 1;
      candidates.emplace_back(i, cj);
    }
  }
  std::vector<std::pair<int, int>> rest;
  for (int i = 0; i < S; ++i)
    for (int j = 0; j < S; ++j)
      if (!g.simulated[at(i, j)] && !queued[at(i, j)]) rest.emplace_back(i, j);
  std::vector<std::pair<double, std::size_t>> order(rest.size());
  for (std::size_t k = 0; k < rest.size(); ++k) {
    const double x = double(k + 1) * 0.6180339887498949;
    order[k] = {x - std::floor(x), k};
  }
  std::sort(order.begin(), order.end());
  const std::size_t extra = std::min(static_cast<std::size_t>(checks), rest.size());
  for (std::size_t k = 0; k < extra; ++k) candidates.push_back(rest[order[k].second]);
  bool contradicted = false;
  for (const auto& [ci, cj] : candidates) {
    const bool inferred = g.success[at(ci, cj)] != 0;
    if (run(ci, cj) != inferred) {
      contradicted = true;
      break;
    }
  }
  g.fallback = contradicted;
  return g;
}

void staircase_schedule(std::size_t grasps, int S, int checks, int verified_rows, int num_threads,
                        const std::function<TrialRunner()>& make_runner,
                        std::vector<std::uint8_t>& success, std::vector<std::uint8_t>& fallback) {
  const std::size_t per_grasp = static_cast<std::size_t>(S) * S;
  success.assign(grasps * per_grasp, 0);
  fallback.assign(grasps, 0);
  const std::size_t workers =
      std::min<std::size_t>(static_cast<std::size_t>(resolve_num_threads(num_threads)), grasps);
  std::size_t next = 0;            // next grasp to walk
  std::size_t walking = 0;         // grasps whose walk is running
  std::vector<std::size_t> cells;  // trials of fallen-back grasps still to run (LIFO)
  std::mutex mutex;
  std::condition_variable changed;
  // (No grasps: no worker.)
  parallel_for(workers, static_cast<int>(workers), 1, [&](std::size_t, std::size_t) {
    const TrialRunner trial = make_runner();
    std::unique_lock<std::mutex> lock(mutex);
    for (;;) {
      if (!cells.empty()) {  // fallback cells first
        const std::size_t t = cells.back();
        cells.pop_back();
        lock.unlock();
        const bool ok = trial(t);
        lock.lock();
        success[t] = ok;
        continue;
      }
      if (next >= grasps) {  // no grasp left: wait for fallback cells until every walk ended
        if (walking == 0) return;
        changed.wait(lock, [&] { return !cells.empty() || walking == 0; });
        continue;
      }
      const std::size_t g = next++;
      ++walking;
      lock.unlock();
      const std::size_t base = g * per_grasp;
      StaircaseGrid sg;
      try {
        sg = staircase_walk(
            S, [&](int i, int j) { return trial(base + static_cast<std::size_t>(i) * S + j); },
            checks, verified_rows);
      } catch (...) {  // let the waiting threads end, then report the error
        lock.lock();
        --walking;
        next = grasps;
        changed.notify_all();
        throw;
      }
      lock.lock();
      --walking;
      fallback[g] = sg.fallback;
      for (std::size_t c = per_grasp; c-- > 0;) {
        if (sg.fallback && !sg.simulated[c])
          cells.push_back(base + c);  // simulated by any thread, lowest index first
        else
          success[base + c] = sg.success[c];  // simulated or inferred
      }
      changed.notify_all();
    }
  });
}

}  // namespace detail

StaircaseGrid staircase_grid(int S, const std::function<bool(int, int)>& trial, int checks,
                             int verified_rows) {
  StaircaseGrid g = detail::staircase_walk(S, trial, checks, verified_rows);
  if (g.fallback) {
    for (std::size_t c = 0; c < g.success.size(); ++c) {
      if (g.simulated[c]) continue;
      g.success[c] = trial(static_cast<int>(c) / S, static_cast<int>(c) % S);
      g.simulated[c] = 1;
      ++g.trials;
    }
  }
  return g;
}

ShakeResult shake_test(const PhysicsObject& object, const ParallelJawGripper& gripper,
                       const std::vector<ParallelJawGrasp>& grasps, const ShakeOptions& options) {
  options.validate();
  gripper.validate();
  validate_grasps(gripper, grasps);
  const PreparedObject prepared = prepare(object, options);

  ShakeResult r;
  const int S = options.grid;
  const std::size_t per_grasp = static_cast<std::size_t>(S) * S;
  const std::size_t n = grasps.size() * per_grasp;
  r.grid = S;
  r.frictions = options.frictions();
  r.density_factors = options.density_factors();
  r.trial_success.assign(n, 0);
  r.trial_ended_early.assign(n, 0);
  r.trial_steps.assign(n, 0);
  r.trial_simulated.assign(n, 0);
  r.fallback.assign(grasps.size(), 0);
  // One set of shapes per worker (see TrialShapes).
  auto run_trial = [&](const TrialShapes& shapes, std::size_t t) {
    const std::size_t g = t / per_grasp;
    const std::size_t i = (t % per_grasp) / S;
    const std::size_t j = t % S;
    const TrialSetting s = make_setting(r.frictions[i], r.density_factors[j], options,
                                        t + options.first_grasp_index * per_grasp);
    TrialWorld world(prepared, shapes, gripper, grasps[g], s, options);
    const TrialOutcome o = world.run([](const StepState&) {});
    r.trial_success[t] = o.success;
    r.trial_ended_early[t] = o.ended_early;
    r.trial_steps[t] = o.steps;
    r.trial_simulated[t] = 1;
    return o.success;
  };
  // Threads take work one item at a time (a grasp costs from ~17 trials to S² with the
  // staircase, so fixed contiguous ranges leave one thread idle while another finishes a slow
  // range): trials of the full grid from a shared counter, staircase grasps through
  // detail::staircase_schedule. Every trial depends only on its index, so the results do not
  // depend on which thread runs it. One set of shapes per worker (see TrialShapes).
  if (options.staircase) {
    std::vector<std::uint8_t> success;
    detail::staircase_schedule(
        grasps.size(), S, options.staircase_checks, options.staircase_verified_rows(),
        options.num_threads,
        [&]() -> detail::TrialRunner {
          auto shapes = std::make_shared<const TrialShapes>(prepared, gripper, options);
          return [&, shapes](std::size_t t) { return run_trial(*shapes, t); };
        },
        success, r.fallback);
    r.trial_success = std::move(success);
  } else {
    parallel_workers_dynamic(n, options.num_threads, 1, [&](BlockQueue& trials) {
      const TrialShapes shapes(prepared, gripper, options);
      for (std::size_t t, end; trials.next(t, end);) run_trial(shapes, t);
    });
  }
  r.score.assign(grasps.size(), 0.0);
  for (std::size_t t = 0; t < n; ++t) {
    r.score[t / per_grasp] += r.trial_success[t];
    r.total_steps += r.trial_steps[t];
  }
  for (double& s : r.score) s /= static_cast<double>(per_grasp);
  return r;
}

ShakeTrajectory shake_trajectory(const PhysicsObject& object, const ParallelJawGripper& gripper,
                                 const ParallelJawGrasp& grasp, double friction,
                                 double density_factor, const ShakeOptions& options,
                                 int record_every, std::uint64_t trial_index) {
  options.validate();
  gripper.validate();
  validate_grasps(gripper, {grasp});
  if (!std::isfinite(friction) || friction < 0) {
    throw_error<InvalidArgument>("shake_trajectory: friction must be finite and >= 0, got ",
                                 friction);
  }
  if (!std::isfinite(density_factor) || !(density_factor > 0)) {
    throw_error<InvalidArgument>("shake_trajectory: density_factor must be finite and > 0, got ",
                                 density_factor);
  }
  if (record_every < 1) {
    throw_error<InvalidArgument>("shake_trajectory: record_every must be >= 1, got ", record_every);
  }
  const PreparedObject prepared = prepare(object, options);
  const TrialSetting s = make_setting(friction, density_factor, options, trial_index);
  ShakeTrajectory tr;
  tr.friction = friction;
  tr.density_factor = density_factor;
  int count = 0;
  StepState last{};
  bool pending = false;
  auto push = [&tr](const StepState& st) {
    tr.time.push_back(st.time);
    tr.phase.push_back(static_cast<std::int8_t>(st.phase));
    tr.X_WO.push_back(st.X_WO);
    tr.X_WH.push_back(st.X_WH);
    tr.finger_left.push_back(st.left);
    tr.finger_right.push_back(st.right);
    tr.contact_left.push_back(st.touch_left);
    tr.contact_right.push_back(st.touch_right);
    tr.force_left.push_back(st.force_left);
    tr.force_right.push_back(st.force_right);
    tr.contact_points.push_back(st.points_left + st.points_right);
    tr.solver_iterations.push_back(st.iterations);
  };
  const TrialShapes shapes(prepared, gripper, options);
  TrialWorld world(prepared, shapes, gripper, grasp, s, options);
  const TrialOutcome o = world.run([&](const StepState& st) {
    if (count++ % record_every == 0) {
      push(st);
      pending = false;
    } else {
      last = st;
      pending = true;
    }
  });
  if (pending) push(last);
  tr.success = o.success;
  tr.ended_early = o.ended_early;
  tr.steps = o.steps;
  return tr;
}

}  // namespace mgn
