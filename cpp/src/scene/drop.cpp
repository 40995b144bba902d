#include <mgn/core/error.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/geometry/convex_decomposition.hpp>
#include <mgn/scene/drop.hpp>

#include "physics/bullet.hpp"
#include "physics/hull_cache.hpp"
#include "physics/world.hpp"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numeric>

namespace mgn {

DropHullCacheInfo drop_hull_cache_info() {
  const physics::HullCacheInfo c = physics::hull_cache_info();
  DropHullCacheInfo i;
  i.entries = c.entries;
  i.bytes = c.bytes;
  i.capacity = c.capacity;
  i.hits = c.hits;
  i.misses = c.misses;
  i.evictions = c.evictions;
  return i;
}

void clear_drop_hull_cache() { physics::clear_hull_cache(); }

void set_drop_hull_cache_capacity(std::size_t bytes) { physics::set_hull_cache_capacity(bytes); }

const char* to_string(DropStatus status) {
  switch (status) {
    case DropStatus::Kept:
      return "kept";
    case DropStatus::LeftTote:
      return "left_tote";
    case DropStatus::NotSettled:
      return "not_settled";
  }
  return "unknown";
}

namespace {

constexpr const char* kFn = "drop_objects";

void require(bool ok, const char* what, double value, const char* expected) {
  if (!ok) throw_error<InvalidArgument>(kFn, ": ", what, " must be ", expected, ", got ", value);
}

struct Aabb {
  Vec3d lo, hi;
  bool overlaps(const Aabb& o, double gap) const {
    return (lo.array() < o.hi.array() + gap).all() && (o.lo.array() < hi.array() + gap).all();
  }
};

Aabb world_aabb(const Points3d& pts_O, const Pose& X_WO) {
  Aabb b{Vec3d::Constant(1e300), Vec3d::Constant(-1e300)};
  for (Eigen::Index k = 0; k < pts_O.rows(); ++k) {
    const Vec3d p = X_WO * Vec3d(pts_O.row(k).transpose());
    b.lo = b.lo.cwiseMin(p);
    b.hi = b.hi.cwiseMax(p);
  }
  return b;
}

void validate(const std::vector<DropObject>& objects, const Mesh& tote, const ToteBox& box,
              const DropOptions& o) {
  if (objects.empty()) throw_error<InvalidArgument>(kFn, ": expected at least one object, got 0");
  require(std::isfinite(box.inner_length) && box.inner_length > 0, "box.inner_length",
          box.inner_length, "finite and > 0 (m)");
  require(std::isfinite(box.inner_width) && box.inner_width > 0, "box.inner_width", box.inner_width,
          "finite and > 0 (m)");
  require(std::isfinite(box.inner_height) && box.inner_height > 0, "box.inner_height",
          box.inner_height, "finite and > 0 (m)");
  require(std::isfinite(box.wall_thickness) && box.wall_thickness > 0, "box.wall_thickness",
          box.wall_thickness, "finite and > 0 (m)");
  require(std::isfinite(box.floor_thickness) && box.floor_thickness > 0, "box.floor_thickness",
          box.floor_thickness, "finite and > 0 (m)");
  if (tote.empty()) throw_error<InvalidArgument>(kFn, ": the tote mesh is empty");
  {
    const auto b = tote.bounds();
    const double hx = 0.5 * box.inner_length, hy = 0.5 * box.inner_width, tol = 1e-4;
    const double top = box.walls ? box.inner_height : 0.0;  // a table top has no rim
    if (b(0, 0) > -hx + tol || b(1, 0) < hx - tol || b(0, 1) > -hy + tol || b(1, 1) < hy - tol ||
        b(1, 2) < top - tol || b(0, 2) > tol)
      throw_error<InvalidArgument>(
          kFn, ": the tote mesh (bounds x [", b(0, 0), ", ", b(1, 0), "], y [", b(0, 1), ", ",
          b(1, 1), "], z [", b(0, 2), ", ", b(1, 2),
          "]) does not enclose the tote box's cavity; expected the mesh of make_tote(spec) in "
          "the tote frame for the same dimensions");
  }
  try {
    mgn::validate(o);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(std::string(kFn) + ": " + e.what());
  }
  if (o.window_min.x() < -0.5 * box.inner_length || o.window_max.x() > 0.5 * box.inner_length ||
      o.window_min.y() < -0.5 * box.inner_width || o.window_max.y() > 0.5 * box.inner_width ||
      o.window_min.z() < 0)
    throw_error<InvalidArgument>(
        kFn, ": the release window (min ", o.window_min.transpose(), ", max ",
        o.window_max.transpose(),
        ") must lie above the tote's cavity (|x| <= ", 0.5 * box.inner_length,
        ", |y| <= ", 0.5 * box.inner_width, ", z >= 0)");

  const double diag = std::hypot(box.inner_length, box.inner_width);
  const double width = std::min(box.inner_length, box.inner_width);
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const DropObject& ob = objects[i];
    auto where = [&] { return detail::concat("objects[", i, "] ('", ob.name, "')"); };
    if (ob.convex_parts.empty())
      throw_error<InvalidArgument>(kFn, ": ", where(), " has no convex parts");
    for (const Mesh& p : ob.convex_parts)
      if (p.num_vertices() < 4 || !p.vertices().allFinite())
        throw_error<InvalidArgument>(kFn, ": ", where(),
                                     ": every convex part needs >= 4 finite vertices");
    if (!(std::isfinite(ob.mass) && ob.mass > 0))
      throw_error<InvalidArgument>(kFn, ": ", where(), ": mass must be finite and > 0 kg, got ",
                                   ob.mass);
    if (!ob.com.allFinite())
      throw_error<InvalidArgument>(kFn, ": ", where(), ": com must be finite");
    if (!(std::isfinite(ob.friction) && ob.friction >= 0))
      throw_error<InvalidArgument>(kFn, ": ", where(), ": friction must be >= 0, got ",
                                   ob.friction);
    if (!(std::isfinite(ob.restitution) && ob.restitution >= 0 && ob.restitution <= 1))
      throw_error<InvalidArgument>(kFn, ": ", where(), ": restitution must be in [0, 1], got ",
                                   ob.restitution);
    Vec3d lo = Vec3d::Constant(1e300), hi = Vec3d::Constant(-1e300);
    for (const Mesh& p : ob.convex_parts) {
      const auto b = p.bounds();
      lo = lo.cwiseMin(Vec3d(b.row(0).transpose()));
      hi = hi.cwiseMax(Vec3d(b.row(1).transpose()));
    }
    std::array<double, 3> e{hi.x() - lo.x(), hi.y() - lo.y(), hi.z() - lo.z()};
    std::sort(e.begin(), e.end());
    if (e[1] > width || e[2] > diag)
      throw_error<InvalidArgument>(
          kFn, ": ", where(), " is larger than the tote: its extents (", e[0], ", ", e[1], ", ",
          e[2], ") m cannot lie in a ", box.inner_length, " x ", box.inner_width,
          " m cavity (expected second-largest extent <= ", width, " and largest <= ", diag, ")");
  }
}

/// Owns every Bullet object of one simulation.
struct World {
  physics::World physics;  // Bullet's world with Bullet's default pools (physics/world.hpp)
  btDiscreteDynamicsWorld& world = physics.dynamics();
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  // Per object: its hull shapes (shared, read-only: physics/hull_cache.hpp) and its compound.
  std::vector<std::shared_ptr<const physics::PreparedHulls>> hulls;
  std::vector<std::unique_ptr<btCompoundShape>> compounds;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  std::unique_ptr<btTriangleMesh> tote_triangles;
  ~World() {
    for (auto& b : bodies)
      if (b->isInWorld()) world.removeRigidBody(b.get());
  }
};

}  // namespace

namespace {

/// The drop runs in metres (see physics/bullet.hpp).
constexpr const physics::BulletUnits& kUnits = physics::kDropUnits;

/// How the convex parts become Bullet hulls (see DropOptions).
physics::HullShapeOptions hull_options(const DropOptions& o) {
  physics::HullShapeOptions h;
  h.reduction = HullReduction::Outer;
  h.max_vertices = o.max_hull_vertices;
  h.tolerance = o.hull_tolerance;
  h.margin = o.collision_margin;
  h.shrink_by_margin = !o.polyhedral_contacts;  // polyhedral clipping ignores margins
  h.polyhedral = o.polyhedral_contacts;
  return h;
}

/// One drop (or settle) simulation, in named steps: build_tote(), release_poses(),
/// add_bodies(), step_until_rest(), measure_contacts(), final_objects().
class DropSimulation {
 public:
  DropSimulation(const std::vector<DropObject>& objects, const Mesh& tote, const ToteBox& box,
                 const DropOptions& o)
      : objects_(objects),
        tote_(tote),
        box_(box),
        o_(o),
        n_(objects.size()),
        hx_(0.5 * box.inner_length),
        hy_(0.5 * box.inner_width),
        H_(box.inner_height),
        w_(std::make_unique<World>()) {
    w_->world.setGravity(btVector3(0, 0, btScalar(-kUnits.length * o.gravity)));
    w_->world.getSolverInfo().m_numIterations = o.solver_iterations;
    // Two friction directions per contact, kept from step to step (see DropOptions).
    if (o.two_friction_directions)
      w_->world.getSolverInfo().m_solverMode |=
          SOLVER_USE_2_FRICTION_DIRECTIONS | SOLVER_ENABLE_FRICTION_DIRECTION_CACHING;
    result_.objects.resize(n_);
    X_OB_.resize(n_);
    body_.assign(n_, nullptr);
    hull_points_.resize(n_);
    for (std::size_t i = 0; i < n_; ++i) hull_points_[i] = part_vertices(objects[i]);
  }

  /// X_WO_start: the settle start poses (at rest), or nullptr for random release poses.
  DropResult run(const std::vector<Pose>* X_WO_start) {
    // Guard walls while the objects fall into the tote (not when a resting pile settles).
    guard_ = (box_.walls && X_WO_start == nullptr) ? o_.guard_height : 0.0;
    build_tote();
    std::vector<Pose> X_WO = release_poses();
    if (X_WO_start != nullptr) X_WO = *X_WO_start;  // settle: start at rest where given
    add_bodies(X_WO);
    step_until_rest();
    measure_contacts();
    final_objects();
    return std::move(result_);
  }

 private:
  /// Every part vertex of an object (object frame), for bounding boxes.
  static Points3d part_vertices(const DropObject& ob) {
    Eigen::Index rows = 0;
    for (const Mesh& part : ob.convex_parts) rows += part.num_vertices();
    Points3d P(rows, 3);
    rows = 0;
    for (const Mesh& part : ob.convex_parts) {
      P.middleRows(rows, part.num_vertices()) = part.vertices().cast<double>();
      rows += part.num_vertices();
    }
    return P;
  }

  /// A static body of the tote (`guard`: a guard wall, lowered by lower_guards()).
  void add_static(std::unique_ptr<btCollisionShape> shape, const btTransform& X,
                  bool guard = false) {
    btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, shape.get());
    info.m_startWorldTransform = X;
    info.m_friction = btScalar(o_.tote_friction);
    info.m_restitution = btScalar(o_.tote_restitution);
    auto body = std::make_unique<btRigidBody>(info);
    w_->world.addRigidBody(body.get());
    if (guard)
      guard_bodies_.push_back(body.get());
    else
      tote_bodies_.push_back(body.get());
    w_->shapes.push_back(std::move(shape));
    w_->bodies.push_back(std::move(body));
  }

  /// A static axis-aligned box of the tote from corner `lo` to corner `hi` (m, tote frame), its
  /// margin at most a quarter of its thinnest side (`guard`: see add_static()).
  void add_static_box(const Vec3d& lo, const Vec3d& hi, bool guard = false) {
    auto shape = std::make_unique<btBoxShape>(kUnits.vector(Vec3d(0.5 * (hi - lo))));
    shape->setMargin(
        btScalar(kUnits.length * std::min(o_.collision_margin, 0.25 * (hi - lo).minCoeff())));
    if (o_.polyhedral_contacts) shape->initializePolyhedralFeatures();
    btTransform X;
    X.setIdentity();
    X.setOrigin(kUnits.vector(Vec3d(0.5 * (hi + lo))));
    add_static(std::move(shape), X, guard);
  }

  /// The static tote: five boxes fitted to the cavity, or the triangle mesh; and the guard walls
  /// (four boxes on the walls, from the rim up by guard_) if any.
  void build_tote() {
    if (guard_ > 0) {
      const double T = std::max(box_.wall_thickness, 0.02);
      const double hx = hx_, hy = hy_, lo = H_, hi = H_ + guard_;
      auto add_guard = [&](const Vec3d& a, const Vec3d& b) {
        add_static_box(a, b, /*guard=*/true);
      };
      add_guard(Vec3d(-hx - T, -hy - T, lo), Vec3d(-hx, hy + T, hi));  // -x
      add_guard(Vec3d(hx, -hy - T, lo), Vec3d(hx + T, hy + T, hi));    // +x
      add_guard(Vec3d(-hx, -hy - T, lo), Vec3d(hx, -hy, hi));          // -y
      add_guard(Vec3d(-hx, hy, lo), Vec3d(hx, hy + T, hi));            // +y
    }
    if (o_.tote_collision == ToteCollision::Boxes) {
      const double T = std::max(box_.wall_thickness, 0.02);  // thickened outwards
      const double F = std::max(box_.floor_thickness, 0.02);
      const double hx = hx_, hy = hy_, H = H_;
      auto add_box = [&](const Vec3d& lo, const Vec3d& hi) { add_static_box(lo, hi); };
      if (!box_.walls) {  // a table top: the slab alone, its edges exact
        add_box(Vec3d(-hx, -hy, -F), Vec3d(hx, hy, 0));
        return;
      }
      add_box(Vec3d(-hx - T, -hy - T, -F), Vec3d(hx + T, hy + T, 0));  // floor
      add_box(Vec3d(-hx - T, -hy - T, -F), Vec3d(-hx, hy + T, H));     // -x wall
      add_box(Vec3d(hx, -hy - T, -F), Vec3d(hx + T, hy + T, H));       // +x wall
      add_box(Vec3d(-hx, -hy - T, -F), Vec3d(hx, -hy, H));             // -y wall
      add_box(Vec3d(-hx, hy, -F), Vec3d(hx, hy + T, H));               // +y wall
    } else {
      w_->tote_triangles = std::make_unique<btTriangleMesh>(true, false);
      const auto& V = tote_.vertices();
      const auto& Fc = tote_.faces();
      for (Eigen::Index f = 0; f < Fc.rows(); ++f) {
        auto vtx = [&](int c) {
          return kUnits.vector(Vec3d(V.row(Fc(f, c)).cast<double>().transpose()));
        };
        w_->tote_triangles->addTriangle(vtx(0), vtx(1), vtx(2), false);
      }
      auto shape = std::make_unique<btBvhTriangleMeshShape>(w_->tote_triangles.get(), true);
      shape->setMargin(btScalar(0.0));
      btTransform X;
      X.setIdentity();
      add_static(std::move(shape), X);
    }
  }

  /// Random release poses (per-object random streams), de-overlapped in order of height.
  std::vector<Pose> release_poses() const {
    constexpr double kGap = 0.005;  // m, clearance to the walls and between bounding boxes
    std::vector<Pose> X_WO(n_);
    std::vector<bool> fits(n_, true);  // the rotated bounding box fits between the walls
    for (std::size_t i = 0; i < n_; ++i) {
      Rng rng(o_.seed, i);
      Eigen::Quaterniond q(rng.normal(), rng.normal(), rng.normal(), rng.normal());
      if (q.norm() < 1e-12) q = Eigen::Quaterniond::Identity();
      q.normalize();
      X_WO[i] = Pose::Identity();
      X_WO[i].linear() = q.toRotationMatrix();
      const Vec3d p(rng.uniform(o_.window_min.x(), o_.window_max.x()),
                    rng.uniform(o_.window_min.y(), o_.window_max.y()),
                    rng.uniform(o_.window_min.z(), o_.window_max.z()));
      // The drawn point is the centre of the object's rotated bounding box, moved inwards where
      // that box would reach beyond a wall (kGap clear of it), if the box fits between them.
      const Aabb b = world_aabb(hull_points_[i], X_WO[i]);
      // An object with less than 2 kGap to spare starts centred between the walls.
      Vec3d c = p;
      for (int k = 0; k < 2; ++k) {
        const double slack = (k == 0 ? hx_ : hy_) - 0.5 * (b.hi[k] - b.lo[k]);
        const double room = std::max(slack - kGap, 0.0);
        if (slack >= 0)
          c[k] = std::clamp(c[k], -room, room);
        else
          fits[i] = false;
      }
      X_WO[i].translation() = c - 0.5 * (b.lo + b.hi);
    }
    std::vector<std::size_t> order(n_);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return X_WO[a].translation().z() < X_WO[b].translation().z();
    });
    std::vector<Aabb> placed;
    for (std::size_t i : order) {
      Aabb b = world_aabb(hull_points_[i], X_WO[i]);
      double lift = 0.0;
      // Not inside the walls: above them (the guard walls' top while they stand).
      lift = std::max(lift, (fits[i] ? 0.0 : H_ + guard_) + kGap - b.lo.z());
      for (bool moved = true; moved;) {
        moved = false;
        Aabb c{b.lo + Vec3d(0, 0, lift), b.hi + Vec3d(0, 0, lift)};
        for (const Aabb& other : placed)
          if (c.overlaps(other, kGap)) {
            lift = other.hi.z() + 2 * kGap - b.lo.z();  // 2x: no float ping-pong at the boundary
            moved = true;
            c = Aabb{b.lo + Vec3d(0, 0, lift), b.hi + Vec3d(0, 0, lift)};
          }
      }
      if (lift > 0) X_WO[i].translation().z() += lift;
      placed.push_back(world_aabb(hull_points_[i], X_WO[i]));
    }
    return X_WO;
  }

  /// One dynamic body per object, in its principal frame, starting at rest at X_WO.
  void add_bodies(const std::vector<Pose>& X_WO) {
    const physics::HullShapeOptions hulls = hull_options(o_);
    for (std::size_t i = 0; i < n_; ++i) {
      const DropObject& ob = objects_[i];
      const PrincipalFrame pr =
          principal_frame(ob, detail::concat(kFn, ": objects[", i, "] ('", ob.name, "')"));
      X_OB_[i] = pr.X_OB;
      // The hull shapes of this object, prepared once per process (physics/hull_cache.hpp).
      std::shared_ptr<const physics::PreparedHulls> prepared =
          physics::prepared_hulls(ob, pr, kUnits, hulls);
      std::unique_ptr<btCompoundShape> shape = physics::compound_of(prepared->hulls);
      btRigidBody::btRigidBodyConstructionInfo info =
          physics::body_info(ob.mass, pr.moments, shape.get(), X_WO[i] * pr.X_OB, kUnits);
      info.m_friction = btScalar(ob.friction);
      info.m_restitution = btScalar(ob.restitution);
      info.m_rollingFriction = btScalar(o_.rolling_friction);
      info.m_spinningFriction = btScalar(o_.rolling_friction);
      info.m_angularDamping = btScalar(o_.angular_damping);
      auto rb = std::make_unique<btRigidBody>(info);
      // Sleeping: Bullet's own timer (the process-wide gDeactivationTime) is not used; a body
      // found at rest below (our test) is marked WANTS_DEACTIVATION, and Bullet freezes an
      // island once all its bodies are so marked and wakes it when something moving touches it.
      // The per-body thresholds keep the mark only while the body stays slower than the rest
      // speeds.
      rb->setActivationState(ACTIVE_TAG);
      rb->setSleepingThresholds(btScalar(kUnits.length * o_.linear_rest),
                                btScalar(o_.angular_rest));
      // Continuous collision detection against tunnelling through thin walls.
      const Aabb local = world_aabb(hull_points_[i], Pose::Identity());
      const double min_extent = (local.hi - local.lo).minCoeff();
      rb->setCcdMotionThreshold(btScalar(kUnits.length * 0.5 * min_extent));
      rb->setCcdSweptSphereRadius(btScalar(kUnits.length * 0.2 * min_extent));
      w_->world.addRigidBody(rb.get());
      body_[i] = rb.get();
      result_.objects[i].X_WO_release = X_WO[i];
      w_->hulls.push_back(std::move(prepared));
      w_->compounds.push_back(std::move(shape));
      w_->bodies.push_back(std::move(rb));
    }
  }

  Pose pose_of(std::size_t i) const {
    return Pose(kUnits.pose(body_[i]->getWorldTransform()) * X_OB_[i].inverse());
  }

  /// Not entirely inside the walls (on or over the rim, or below the floor). Without walls (a
  /// table top): below the top, i.e. falling or hanging off an edge.
  bool outside_walls(const Pose& X_WO, std::size_t i) const {
    const double tol = o_.collision_margin + o_.contact_distance;
    const Aabb b = world_aabb(hull_points_[i], X_WO);
    if (!box_.walls) return b.lo.z() < -tol;
    return b.lo.x() < -hx_ - tol || b.hi.x() > hx_ + tol || b.lo.y() < -hy_ - tol ||
           b.hi.y() > hy_ + tol || b.lo.z() < -tol;
  }

  void remove(std::size_t i) {
    result_.objects[i].X_WO = pose_of(i);
    result_.objects[i].status = DropStatus::LeftTote;
    w_->world.removeRigidBody(body_[i]);
  }

  /// Objects left the tote: the rest may have leaned on them and must come to rest again, with
  /// resettle_time more to do so.
  void restart() {
    limit_ = std::max(limit_, max_steps_ + resettle_steps_);
    ++result_.resettle_rounds;
    all_rest_ = false;
    for (std::size_t i = 0; i < n_; ++i) {
      if (!body_[i]->isInWorld()) continue;
      at_rest_[i] = 0;
      rest_ref_[i] = body_[i]->getCenterOfMassTransform();
      body_[i]->activate(true);
    }
  }

  /// One simulation step and the rest test of every object; returns the objects that came to
  /// rest on or over the rim in this step.
  std::vector<std::size_t> step_and_test() {
    w_->world.stepSimulation(btScalar(o_.dt), 0, btScalar(o_.dt));
    ++step_;
    all_rest_ = true;
    std::vector<std::size_t> on_rim;
    const double fall_z = -box_.floor_thickness - 0.02;
    const double max_shift = o_.linear_rest * o_.rest_time;
    const double max_turn = o_.angular_rest * o_.rest_time;
    for (std::size_t i = 0; i < n_; ++i) {
      btRigidBody* rb = body_[i];
      if (!rb->isInWorld()) continue;
      if (double(rb->getCenterOfMassPosition().z()) < kUnits.length * fall_z) {
        remove(i);
        continue;
      }
      // At rest: slower than the thresholds now, and moved less than they allow over the last
      // rest_time (a pose reference that is reset whenever the object strays further from it).
      // A speed spike of a resting object (solver jitter) does not restart the count; real
      // motion does.
      const btTransform& X = rb->getCenterOfMassTransform();
      const double shift =
          double((X.getOrigin() - rest_ref_[i].getOrigin()).length()) / kUnits.length;
      const double turn = double(X.getRotation().angleShortestPath(rest_ref_[i].getRotation()));
      if (shift > max_shift || turn > max_turn) {
        rest_ref_[i] = X;  // moving: start a new window here
        at_rest_[i] = 0;
      } else {
        ++at_rest_[i];
      }
      const bool slow = double(rb->getLinearVelocity().length()) / kUnits.length < o_.linear_rest &&
                        double(rb->getAngularVelocity().length()) < o_.angular_rest;
      if (!slow || at_rest_[i] < rest_steps_) all_rest_ = false;
      if (slow && at_rest_[i] >= rest_steps_ && rb->getActivationState() == ACTIVE_TAG)
        rb->setActivationState(WANTS_DEACTIVATION);
      // Came to rest on or over the rim: it leaves now, not after the whole pile rests.
      if (slow && at_rest_[i] == rest_steps_ && outside_walls(pose_of(i), i)) on_rim.push_back(i);
    }
    return on_rim;
  }

  /// Steps until every object in the tote is at rest or the time is up; objects that left the
  /// tote are removed on the way and the rest settles again (see the file comment).
  void step_until_rest() {
    max_steps_ = static_cast<std::int64_t>(std::ceil(o_.max_time / o_.dt - 1e-9));
    rest_steps_ = static_cast<std::int64_t>(std::ceil(o_.rest_time / o_.dt - 1e-9));
    resettle_steps_ = static_cast<std::int64_t>(std::ceil(o_.resettle_time / o_.dt - 1e-9));
    limit_ = max_steps_;
    at_rest_.assign(n_, 0);
    rest_ref_.resize(n_);
    for (std::size_t i = 0; i < n_; ++i) rest_ref_[i] = body_[i]->getCenterOfMassTransform();
    for (bool guarded = guard_ > 0;; guarded = false) {
      settle();
      if (!guarded) break;
      lower_guards();
    }
    result_.steps = step_;
    result_.simulated_time = double(step_) * o_.dt;
    result_.settled = all_rest_;
  }

  /// The guard walls go: the pile settles again, with resettle_time from now to do so.
  void lower_guards() {
    for (btRigidBody* g : guard_bodies_) w_->world.removeRigidBody(g);
    guard_bodies_.clear();
    limit_ = step_ + resettle_steps_;
    all_rest_ = false;
    for (std::size_t i = 0; i < n_; ++i) {
      if (!body_[i]->isInWorld()) continue;
      at_rest_[i] = 0;
      rest_ref_[i] = body_[i]->getCenterOfMassTransform();
      body_[i]->activate(true);
    }
  }

  /// Steps until every object in the tote is at rest or limit_ is reached, removing objects that
  /// left the tote (the rest settles again, see restart()).
  void settle() {
    while (true) {
      while (step_ < limit_) {
        const std::vector<std::size_t> on_rim = step_and_test();
        if (!on_rim.empty()) {
          for (std::size_t i : on_rim) remove(i);
          restart();
          continue;
        }
        if (all_rest_) break;
      }
      // Time is up: objects on or over the rim leave; whatever leaned on them settles again.
      bool removed = false;
      for (std::size_t i = 0; i < n_; ++i)
        if (body_[i]->isInWorld() && outside_walls(pose_of(i), i)) {
          remove(i);
          removed = true;
        }
      if (!removed) break;
      restart();
      if (step_ >= limit_) break;
    }
  }

  /// Tote contacts of every object and the deepest penetration, at the final state.
  void measure_contacts() {
    // Sleeping bodies get no fresh contacts with the (inactive) tote: wake them (no motion).
    for (std::size_t i = 0; i < n_; ++i)
      if (body_[i]->isInWorld()) body_[i]->activate(true);
    w_->world.performDiscreteCollisionDetection();
    contacts_.assign(n_, 0);
    auto object_index = [&](const btCollisionObject* c) -> long {
      for (std::size_t i = 0; i < n_; ++i)
        if (body_[i] == c) return static_cast<long>(i);
      return -1;
    };
    auto is_tote = [&](const btCollisionObject* c) {
      return std::find(tote_bodies_.begin(), tote_bodies_.end(), c) != tote_bodies_.end();
    };
    double max_pen = 0.0;
    btDispatcher* d = w_->world.getDispatcher();
    for (int m = 0; m < d->getNumManifolds(); ++m) {
      const btPersistentManifold* man = d->getManifoldByIndexInternal(m);
      const btCollisionObject* a = man->getBody0();
      const btCollisionObject* b = man->getBody1();
      for (int c = 0; c < man->getNumContacts(); ++c) {
        const btManifoldPoint& pt = man->getContactPoint(c);
        const double dist = double(pt.getDistance()) / kUnits.length;
        max_pen = std::max(max_pen, -dist);
        if (dist > o_.contact_distance) continue;
        long obj = -1;
        btVector3 n_tote_to_obj;
        btVector3 p_tote;
        if (is_tote(a) && !is_tote(b)) {
          obj = object_index(b);
          n_tote_to_obj = -pt.m_normalWorldOnB;  // normal on B points towards A
          p_tote = pt.getPositionWorldOnA();
        } else if (is_tote(b) && !is_tote(a)) {
          obj = object_index(a);
          n_tote_to_obj = pt.m_normalWorldOnB;
          p_tote = pt.getPositionWorldOnB();
        }
        if (obj < 0) continue;
        constexpr double kAxis = 0.7;
        const double nx = n_tote_to_obj.x(), ny = n_tote_to_obj.y(), nz = n_tote_to_obj.z();
        if (nz > kAxis && double(p_tote.z()) / kUnits.length < 0.5 * H_)
          contacts_[obj] |= ContactFloor;
        if (!box_.walls) continue;  // a table top's edges are not walls
        if (nx > kAxis) contacts_[obj] |= ContactWallMinusX;
        if (nx < -kAxis) contacts_[obj] |= ContactWallPlusX;
        if (ny > kAxis) contacts_[obj] |= ContactWallMinusY;
        if (ny < -kAxis) contacts_[obj] |= ContactWallPlusY;
      }
    }
    result_.max_penetration = max_pen;
  }

  /// Final poses and what is kept.
  void final_objects() {
    for (std::size_t i = 0; i < n_; ++i) {
      DroppedObject& r = result_.objects[i];
      btRigidBody* rb = body_[i];
      if (!rb->isInWorld()) continue;  // fell out, pose recorded then
      r.X_WO = pose_of(i);
      r.settled = at_rest_[i] >= rest_steps_ &&
                  double(rb->getLinearVelocity().length()) / kUnits.length < o_.linear_rest &&
                  double(rb->getAngularVelocity().length()) < o_.angular_rest;
      r.contacts = contacts_[i];
      if (outside_walls(r.X_WO, i)) {
        r.status = DropStatus::LeftTote;
        r.contacts = 0;
      } else if (!r.settled && o_.remove_unsettled) {
        r.status = DropStatus::NotSettled;
        r.contacts = 0;
      }
    }
  }

  const std::vector<DropObject>& objects_;
  const Mesh& tote_;
  const ToteBox& box_;
  const DropOptions& o_;
  const std::size_t n_;
  const double hx_, hy_, H_;
  std::unique_ptr<World> w_;
  std::vector<const btCollisionObject*> tote_bodies_;
  std::vector<btRigidBody*> guard_bodies_;  // guard walls while they stand
  double guard_ = 0.0;                      // m, guard wall height above the rim (0: none)
  std::vector<Points3d> hull_points_;       // every part vertex, object frame
  std::vector<Pose> X_OB_;
  std::vector<btRigidBody*> body_;
  DropResult result_;
  // Stepping state.
  std::int64_t step_ = 0, limit_ = 0, max_steps_ = 0, rest_steps_ = 0, resettle_steps_ = 0;
  bool all_rest_ = false;
  std::vector<std::int64_t> at_rest_;
  std::vector<btTransform> rest_ref_;
  std::vector<std::uint32_t> contacts_;
};

/// drop_objects() and, with `X_WO_start`, settle_objects(): the objects then start at rest at
/// these poses instead of at random release poses.
DropResult simulate(const std::vector<DropObject>& objects, const Mesh& tote, const ToteBox& box,
                    const DropOptions& o, const std::vector<Pose>* X_WO_start) {
  validate(objects, tote, box, o);
  return DropSimulation(objects, tote, box, o).run(X_WO_start);
}

}  // namespace

void validate(const DropOptions& o) {
  auto require = [](bool ok, const char* field, double value, const char* expected) {
    if (!ok)
      throw_error<InvalidArgument>("DropOptions.", field, " must be ", expected, ", got ", value);
  };
  if (!o.window_min.allFinite() || !o.window_max.allFinite())
    throw_error<InvalidArgument>("DropOptions.window_min/window_max must be finite, got min (",
                                 o.window_min.transpose(), ") max (", o.window_max.transpose(),
                                 ")");
  if ((o.window_min.array() > o.window_max.array()).any())
    throw_error<InvalidArgument>("DropOptions.window_min must be <= window_max, got min (",
                                 o.window_min.transpose(), ") max (", o.window_max.transpose(),
                                 ")");
  require(std::isfinite(o.dt) && o.dt > 0 && o.dt <= 0.02, "dt", o.dt, "in (0, 0.02] s");
  require(std::isfinite(o.max_time) && o.max_time > o.dt, "max_time", o.max_time,
          "finite and > dt (s)");
  require(o.max_time / o.dt <= 1e7, "max_time", o.max_time, "at most 1e7 steps of dt");
  require(o.solver_iterations >= 1 && o.solver_iterations <= 1000, "solver_iterations",
          o.solver_iterations, "in [1, 1000]");
  require(std::isfinite(o.linear_rest) && o.linear_rest > 0, "linear_rest", o.linear_rest,
          "finite and > 0 (m/s)");
  require(std::isfinite(o.angular_rest) && o.angular_rest > 0, "angular_rest", o.angular_rest,
          "finite and > 0 (rad/s)");
  require(std::isfinite(o.rest_time) && o.rest_time > 0 && o.rest_time < o.max_time, "rest_time",
          o.rest_time, "in (0, max_time) s");
  require(std::isfinite(o.gravity) && o.gravity > 0, "gravity", o.gravity,
          "finite and > 0 (m/s^2)");
  require(std::isfinite(o.collision_margin) && o.collision_margin > 0 && o.collision_margin <= 0.01,
          "collision_margin", o.collision_margin, "in (0, 0.01] m");
  require(std::isfinite(o.contact_distance) && o.contact_distance > 0, "contact_distance",
          o.contact_distance, "finite and > 0 (m)");
  require(o.max_hull_vertices == 0 || (o.max_hull_vertices >= 8 && o.max_hull_vertices <= 100000),
          "max_hull_vertices", o.max_hull_vertices, "0 (keep all) or in [8, 100000]");
  require(std::isfinite(o.hull_tolerance) && o.hull_tolerance >= 0, "hull_tolerance",
          o.hull_tolerance, "finite and >= 0 (m)");
  require(std::isfinite(o.guard_height) && o.guard_height >= 0 && o.guard_height <= 10,
          "guard_height", o.guard_height, "in [0, 10] m");
  require(std::isfinite(o.resettle_time) && o.resettle_time >= 0 && o.resettle_time / o.dt <= 1e7,
          "resettle_time", o.resettle_time, "finite, >= 0 s and at most 1e7 steps of dt");
  require(std::isfinite(o.rolling_friction) && o.rolling_friction >= 0, "rolling_friction",
          o.rolling_friction, "finite and >= 0");
  require(std::isfinite(o.angular_damping) && o.angular_damping >= 0 && o.angular_damping < 1,
          "angular_damping", o.angular_damping, "in [0, 1)");
  require(std::isfinite(o.tote_friction) && o.tote_friction >= 0, "tote_friction", o.tote_friction,
          "finite and >= 0");
  require(std::isfinite(o.tote_restitution) && o.tote_restitution >= 0 && o.tote_restitution <= 1,
          "tote_restitution", o.tote_restitution, "in [0, 1]");
}

DropResult drop_objects(const std::vector<DropObject>& objects, const Mesh& tote,
                        const ToteBox& box, const DropOptions& o) {
  return simulate(objects, tote, box, o, nullptr);
}

DropResult settle_objects(const std::vector<DropObject>& objects,
                          const std::vector<Pose>& X_WO_start, const Mesh& tote, const ToteBox& box,
                          const DropOptions& o) {
  constexpr const char* fn = "settle_objects";
  if (X_WO_start.size() != objects.size())
    throw_error<InvalidArgument>(fn, ": X_WO_start has ", X_WO_start.size(),
                                 " poses, expected one per object (", objects.size(), ")");
  for (std::size_t i = 0; i < X_WO_start.size(); ++i) {
    const Mat4d M = X_WO_start[i].matrix();
    const Mat3d R = M.topLeftCorner<3, 3>();
    if (!M.allFinite() || (R.transpose() * R - Mat3d::Identity()).norm() > 1e-6 ||
        R.determinant() < 0 || (M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-12)
      throw_error<InvalidArgument>(fn, ": X_WO_start[", i, "] ('", objects[i].name,
                                   "') must be a finite rigid transform (rotation and "
                                   "translation), got\n",
                                   M);
  }
  try {
    return simulate(objects, tote, box, o, &X_WO_start);
  } catch (const InvalidArgument& e) {  // validate() names drop_objects: name this function
    const std::string what = e.what(), prefix = kFn;
    if (what.compare(0, prefix.size(), prefix) != 0) throw;
    throw InvalidArgument(fn + what.substr(prefix.size()));
  }
}

}  // namespace mgn
