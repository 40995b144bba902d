#include <mgn/core/error.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/geometry/convex_decomposition.hpp>
#include <mgn/scene/drop.hpp>

#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <LinearMath/btConvexHullComputer.h>
#include <btBulletDynamicsCommon.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numeric>

namespace mgn {

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

btVector3 to_bt(const Vec3d& v) {
  return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z()));
}

btTransform to_bt(const Pose& X) {
  const Eigen::Quaterniond q(X.rotation());
  return btTransform(
      btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())),
      to_bt(Vec3d(X.translation())));
}

Pose from_bt(const btTransform& t) {
  const btQuaternion q = t.getRotation();
  Eigen::Quaterniond qd(double(q.w()), double(q.x()), double(q.y()), double(q.z()));
  qd.normalize();
  Pose X = Pose::Identity();
  X.linear() = qd.toRotationMatrix();
  const btVector3& p = t.getOrigin();
  X.translation() = Vec3d(double(p.x()), double(p.y()), double(p.z()));
  return X;
}

/// Principal frame B of an object: X_OB (origin at the CoM, axes = principal axes), and the
/// principal moments.
struct Principal {
  Pose X_OB = Pose::Identity();
  Vec3d moments = Vec3d::Zero();
};

Principal principal_frame(const DropObject& o, std::size_t i) {
  const Mat3d I = 0.5 * (o.inertia + o.inertia.transpose());
  if (!o.inertia.allFinite() ||
      (o.inertia - o.inertia.transpose()).norm() > 1e-6 * o.inertia.norm())
    throw_error<InvalidArgument>(kFn, ": objects[", i, "] ('", o.name,
                                 "'): inertia must be a finite symmetric 3x3 matrix");
  Eigen::SelfAdjointEigenSolver<Mat3d> es(I);
  Principal p;
  p.moments = es.eigenvalues();
  if (!(p.moments.minCoeff() > 0))
    throw_error<InvalidArgument>(kFn, ": objects[", i, "] ('", o.name,
                                 "'): inertia must be positive definite, got eigenvalues ",
                                 p.moments.transpose());
  Mat3d R = es.eigenvectors();
  if (R.determinant() < 0) R.col(2) *= -1.0;
  p.X_OB.linear() = R;
  p.X_OB.translation() = o.com;
  return p;
}

/// Convex hull shape of a part, in frame B, shrunk by the margin (Bullet adds it back).
/// Its vertices are reduced to at most `max_vertices` (0: all) within `tolerance` (m).
/// With `polyhedral` the hull is not shrunk and gets Bullet's polyhedral features.
std::unique_ptr<btConvexHullShape> hull_shape(const Mesh& part, const Pose& X_BO, double margin,
                                              int max_vertices, double tolerance, bool polyhedral) {
  const auto& V = part.vertices();
  std::vector<double> coords(static_cast<std::size_t>(3 * V.rows()));
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const Vec3d p = X_BO * Vec3d(V.row(v).cast<double>().transpose());
    coords[3 * v] = p.x();
    coords[3 * v + 1] = p.y();
    coords[3 * v + 2] = p.z();
  }
  btConvexHullComputer hc;
  const btScalar shrunk =
      hc.compute(coords.data(), 3 * sizeof(double), static_cast<int>(V.rows()),
                 polyhedral ? btScalar(0) : btScalar(margin), btScalar(polyhedral ? 0.0 : 0.3));
  auto shape = std::make_unique<btConvexHullShape>();
  if (shrunk >= 0 && hc.vertices.size() >= 4) {
    if (max_vertices > 0 && hc.vertices.size() > max_vertices) {
      Points3d hv(hc.vertices.size(), 3);
      for (int k = 0; k < hc.vertices.size(); ++k)
        hv.row(k) << double(hc.vertices[k].x()), double(hc.vertices[k].y()),
            double(hc.vertices[k].z());
      for (Eigen::Index k : reduce_convex_points(hv, max_vertices, tolerance))
        shape->addPoint(hc.vertices[static_cast<int>(k)], false);
    } else {
      for (int k = 0; k < hc.vertices.size(); ++k) shape->addPoint(hc.vertices[k], false);
    }
  } else {
    for (Eigen::Index v = 0; v < V.rows(); ++v)
      shape->addPoint(btVector3(btScalar(coords[3 * v]), btScalar(coords[3 * v + 1]),
                                btScalar(coords[3 * v + 2])),
                      false);
  }
  shape->recalcLocalAabb();
  if (polyhedral) {
    shape->setMargin(btScalar(margin));
    shape->initializePolyhedralFeatures();
  } else {
    shape->setMargin(btScalar(std::max(0.0, shrunk > 0 ? double(shrunk) : 0.0)));
  }
  return shape;
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
    if (b(0, 0) > -hx + tol || b(1, 0) < hx - tol || b(0, 1) > -hy + tol || b(1, 1) < hy - tol ||
        b(1, 2) < box.inner_height - tol || b(0, 2) > tol)
      throw_error<InvalidArgument>(
          kFn, ": the tote mesh (bounds x [", b(0, 0), ", ", b(1, 0), "], y [", b(0, 1), ", ",
          b(1, 1), "], z [", b(0, 2), ", ", b(1, 2),
          "]) does not enclose the tote box's cavity; expected the mesh of make_tote(spec) in "
          "the tote frame for the same dimensions");
  }
  if (!o.window_min.allFinite() || !o.window_max.allFinite())
    throw_error<InvalidArgument>(kFn, ": options.window_min/max must be finite");
  if ((o.window_min.array() > o.window_max.array()).any())
    throw_error<InvalidArgument>(kFn, ": options.window_min must be <= window_max, got min (",
                                 o.window_min.transpose(), ") max (", o.window_max.transpose(),
                                 ")");
  if (o.window_min.x() < -0.5 * box.inner_length || o.window_max.x() > 0.5 * box.inner_length ||
      o.window_min.y() < -0.5 * box.inner_width || o.window_max.y() > 0.5 * box.inner_width ||
      o.window_min.z() < 0)
    throw_error<InvalidArgument>(
        kFn, ": the release window (min ", o.window_min.transpose(), ", max ",
        o.window_max.transpose(),
        ") must lie above the tote's cavity (|x| <= ", 0.5 * box.inner_length,
        ", |y| <= ", 0.5 * box.inner_width, ", z >= 0)");
  require(std::isfinite(o.dt) && o.dt > 0 && o.dt <= 0.02, "options.dt", o.dt, "in (0, 0.02] s");
  require(std::isfinite(o.max_time) && o.max_time > o.dt, "options.max_time", o.max_time,
          "finite and > dt (s)");
  require(o.max_time / o.dt <= 1e7, "options.max_time / dt", o.max_time / o.dt, "<= 1e7 steps");
  require(o.solver_iterations >= 1 && o.solver_iterations <= 1000, "options.solver_iterations",
          o.solver_iterations, "in [1, 1000]");
  require(std::isfinite(o.linear_rest) && o.linear_rest > 0, "options.linear_rest", o.linear_rest,
          "finite and > 0 (m/s)");
  require(std::isfinite(o.angular_rest) && o.angular_rest > 0, "options.angular_rest",
          o.angular_rest, "finite and > 0 (rad/s)");
  require(std::isfinite(o.rest_time) && o.rest_time > 0 && o.rest_time < o.max_time,
          "options.rest_time", o.rest_time, "in (0, max_time) s");
  require(std::isfinite(o.gravity) && o.gravity > 0, "options.gravity", o.gravity,
          "finite and > 0 (m/s^2)");
  require(std::isfinite(o.collision_margin) && o.collision_margin > 0 && o.collision_margin <= 0.01,
          "options.collision_margin", o.collision_margin, "in (0, 0.01] m");
  require(std::isfinite(o.contact_distance) && o.contact_distance > 0, "options.contact_distance",
          o.contact_distance, "finite and > 0 (m)");
  require(o.max_hull_vertices == 0 || (o.max_hull_vertices >= 4 && o.max_hull_vertices <= 100000),
          "options.max_hull_vertices", o.max_hull_vertices, "0 (keep all) or in [4, 100000]");
  require(std::isfinite(o.hull_tolerance) && o.hull_tolerance >= 0, "options.hull_tolerance",
          o.hull_tolerance, "finite and >= 0 (m)");
  require(std::isfinite(o.resettle_time) && o.resettle_time >= 0 && o.resettle_time / o.dt <= 1e7,
          "options.resettle_time", o.resettle_time, "finite, >= 0 s and <= 1e7 steps");
  require(std::isfinite(o.rolling_friction) && o.rolling_friction >= 0, "options.rolling_friction",
          o.rolling_friction, "finite and >= 0");
  require(std::isfinite(o.angular_damping) && o.angular_damping >= 0 && o.angular_damping < 1,
          "options.angular_damping", o.angular_damping, "in [0, 1)");
  require(std::isfinite(o.tote_friction) && o.tote_friction >= 0, "options.tote_friction",
          o.tote_friction, "finite and >= 0");
  require(std::isfinite(o.tote_restitution) && o.tote_restitution >= 0 && o.tote_restitution <= 1,
          "options.tote_restitution", o.tote_restitution, "in [0, 1]");

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
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  std::unique_ptr<btTriangleMesh> tote_triangles;
  ~World() {
    for (auto& b : bodies)
      if (b->isInWorld()) world.removeRigidBody(b.get());
  }
};

}  // namespace

namespace {

/// drop_objects() and, with `X_WO_start`, settle_objects(): the objects then start at rest at
/// these poses instead of at random release poses.
DropResult simulate(const std::vector<DropObject>& objects, const Mesh& tote, const ToteBox& box,
                    const DropOptions& o, const std::vector<Pose>* X_WO_start) {
  validate(objects, tote, box, o);
  const std::size_t n = objects.size();
  const double hx = 0.5 * box.inner_length, hy = 0.5 * box.inner_width, H = box.inner_height;

  auto w = std::make_unique<World>();
  w->world.setGravity(btVector3(0, 0, btScalar(-o.gravity)));
  w->world.getSolverInfo().m_numIterations = o.solver_iterations;
  // Two friction directions per contact, kept from step to step (see DropOptions).
  if (o.two_friction_directions)
    w->world.getSolverInfo().m_solverMode |=
        SOLVER_USE_2_FRICTION_DIRECTIONS | SOLVER_ENABLE_FRICTION_DIRECTION_CACHING;

  // --- the static tote ---
  std::vector<const btCollisionObject*> tote_bodies;
  auto add_static = [&](std::unique_ptr<btCollisionShape> shape, const btTransform& X) {
    btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, shape.get());
    info.m_startWorldTransform = X;
    info.m_friction = btScalar(o.tote_friction);
    info.m_restitution = btScalar(o.tote_restitution);
    auto body = std::make_unique<btRigidBody>(info);
    w->world.addRigidBody(body.get());
    tote_bodies.push_back(body.get());
    w->shapes.push_back(std::move(shape));
    w->bodies.push_back(std::move(body));
  };
  if (o.tote_collision == ToteCollision::Boxes) {
    const double T = std::max(box.wall_thickness, 0.02);  // thickened outwards
    const double F = std::max(box.floor_thickness, 0.02);
    auto add_box = [&](const Vec3d& lo, const Vec3d& hi) {
      auto shape = std::make_unique<btBoxShape>(to_bt(0.5 * (hi - lo)));
      shape->setMargin(btScalar(std::min(o.collision_margin, 0.25 * (hi - lo).minCoeff())));
      if (o.polyhedral_contacts) shape->initializePolyhedralFeatures();
      btTransform X;
      X.setIdentity();
      X.setOrigin(to_bt(0.5 * (hi + lo)));
      add_static(std::move(shape), X);
    };
    add_box(Vec3d(-hx - T, -hy - T, -F), Vec3d(hx + T, hy + T, 0));  // floor
    add_box(Vec3d(-hx - T, -hy - T, -F), Vec3d(-hx, hy + T, H));     // -x wall
    add_box(Vec3d(hx, -hy - T, -F), Vec3d(hx + T, hy + T, H));       // +x wall
    add_box(Vec3d(-hx, -hy - T, -F), Vec3d(hx, -hy, H));             // -y wall
    add_box(Vec3d(-hx, hy, -F), Vec3d(hx, hy + T, H));               // +y wall
  } else {
    w->tote_triangles = std::make_unique<btTriangleMesh>(true, false);
    const auto& V = tote.vertices();
    const auto& Fc = tote.faces();
    for (Eigen::Index f = 0; f < Fc.rows(); ++f) {
      auto vtx = [&](int c) { return btVector3(V(Fc(f, c), 0), V(Fc(f, c), 1), V(Fc(f, c), 2)); };
      w->tote_triangles->addTriangle(vtx(0), vtx(1), vtx(2), false);
    }
    auto shape = std::make_unique<btBvhTriangleMeshShape>(w->tote_triangles.get(), true);
    shape->setMargin(btScalar(0.0));
    btTransform X;
    X.setIdentity();
    add_static(std::move(shape), X);
  }

  // --- release poses (per-object random streams), de-overlapped in order of height ---
  std::vector<Pose> X_WO(n);
  std::vector<Points3d> hull_points(n);  // every part vertex, object frame
  for (std::size_t i = 0; i < n; ++i) {
    Rng rng(o.seed, i);
    Eigen::Quaterniond q(rng.normal(), rng.normal(), rng.normal(), rng.normal());
    if (q.norm() < 1e-12) q = Eigen::Quaterniond::Identity();
    q.normalize();
    X_WO[i] = Pose::Identity();
    X_WO[i].linear() = q.toRotationMatrix();
    const Vec3d p(rng.uniform(o.window_min.x(), o.window_max.x()),
                  rng.uniform(o.window_min.y(), o.window_max.y()),
                  rng.uniform(o.window_min.z(), o.window_max.z()));
    Eigen::Index rows = 0;
    for (const Mesh& part : objects[i].convex_parts) rows += part.num_vertices();
    hull_points[i].resize(rows, 3);
    rows = 0;
    for (const Mesh& part : objects[i].convex_parts) {
      hull_points[i].middleRows(rows, part.num_vertices()) = part.vertices().cast<double>();
      rows += part.num_vertices();
    }
    // The drawn point is the centre of the object's rotated bounding box.
    const Aabb b = world_aabb(hull_points[i], X_WO[i]);
    X_WO[i].translation() = p - 0.5 * (b.lo + b.hi);
  }
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return X_WO[a].translation().z() < X_WO[b].translation().z();
  });
  constexpr double kGap = 0.005;
  std::vector<Aabb> placed;
  for (std::size_t i : order) {
    Aabb b = world_aabb(hull_points[i], X_WO[i]);
    double lift = 0.0;
    const bool inside = b.lo.x() > -hx + kGap && b.hi.x() < hx - kGap && b.lo.y() > -hy + kGap &&
                        b.hi.y() < hy - kGap;
    lift = std::max(lift, (inside ? 0.0 : H) + kGap - b.lo.z());
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
    placed.push_back(world_aabb(hull_points[i], X_WO[i]));
  }
  if (X_WO_start != nullptr) X_WO = *X_WO_start;  // settle: start at rest where given

  // --- dynamic bodies ---
  DropResult result;
  result.objects.resize(n);
  std::vector<Pose> X_OB(n);
  std::vector<btRigidBody*> body(n, nullptr);
  for (std::size_t i = 0; i < n; ++i) {
    const DropObject& ob = objects[i];
    const Principal pr = principal_frame(ob, i);
    X_OB[i] = pr.X_OB;
    const Pose X_BO = pr.X_OB.inverse();
    auto compound =
        std::make_unique<btCompoundShape>(true, static_cast<int>(ob.convex_parts.size()));
    btTransform identity;
    identity.setIdentity();
    for (const Mesh& part : ob.convex_parts) {
      auto hull = hull_shape(part, X_BO, o.collision_margin, o.max_hull_vertices, o.hull_tolerance,
                             o.polyhedral_contacts);
      compound->addChildShape(identity, hull.get());
      w->shapes.push_back(std::move(hull));
    }
    btRigidBody::btRigidBodyConstructionInfo info(btScalar(ob.mass), nullptr, compound.get(),
                                                  to_bt(pr.moments));
    info.m_startWorldTransform = to_bt(X_WO[i] * pr.X_OB);
    info.m_friction = btScalar(ob.friction);
    info.m_restitution = btScalar(ob.restitution);
    info.m_rollingFriction = btScalar(o.rolling_friction);
    info.m_spinningFriction = btScalar(o.rolling_friction);
    info.m_angularDamping = btScalar(o.angular_damping);
    auto rb = std::make_unique<btRigidBody>(info);
    // Sleeping: Bullet's own timer (the process-wide gDeactivationTime) is not used; a body
    // found at rest below (our test) is marked WANTS_DEACTIVATION, and Bullet freezes an island
    // once all its bodies are so marked and wakes it when something moving touches it. The
    // per-body thresholds keep the mark only while the body stays slower than the rest speeds.
    rb->setActivationState(ACTIVE_TAG);
    rb->setSleepingThresholds(btScalar(o.linear_rest), btScalar(o.angular_rest));
    // Continuous collision detection against tunnelling through thin walls.
    const Aabb local = world_aabb(hull_points[i], Pose::Identity());
    const double min_extent = (local.hi - local.lo).minCoeff();
    rb->setCcdMotionThreshold(btScalar(0.5 * min_extent));
    rb->setCcdSweptSphereRadius(btScalar(0.2 * min_extent));
    w->world.addRigidBody(rb.get());
    body[i] = rb.get();
    result.objects[i].X_WO_release = X_WO[i];
    w->shapes.push_back(std::move(compound));
    w->bodies.push_back(std::move(rb));
  }

  // --- simulate ---
  const auto max_steps = static_cast<std::int64_t>(std::ceil(o.max_time / o.dt - 1e-9));
  const auto rest_steps = static_cast<std::int64_t>(std::ceil(o.rest_time / o.dt - 1e-9));
  const auto resettle_steps = static_cast<std::int64_t>(std::ceil(o.resettle_time / o.dt - 1e-9));
  // At rest: slower than the thresholds now, and moved less than they allow over the last
  // rest_time (a pose reference that is reset whenever the object strays further from it). A
  // speed spike of a resting object (solver jitter) does not restart the count; real motion does.
  std::vector<std::int64_t> at_rest(n, 0);
  std::vector<btTransform> rest_ref(n);
  for (std::size_t i = 0; i < n; ++i) rest_ref[i] = body[i]->getCenterOfMassTransform();
  const double max_shift = o.linear_rest * o.rest_time;
  const double max_turn = o.angular_rest * o.rest_time;
  const double fall_z = -box.floor_thickness - 0.02;
  const double tol = o.collision_margin + o.contact_distance;
  auto pose_of = [&](std::size_t i) {
    return Pose(from_bt(body[i]->getWorldTransform()) * X_OB[i].inverse());
  };
  auto outside_walls = [&](std::size_t i) {
    const Aabb b = world_aabb(hull_points[i], pose_of(i));
    return b.lo.x() < -hx - tol || b.hi.x() > hx + tol || b.lo.y() < -hy - tol ||
           b.hi.y() > hy + tol || b.lo.z() < -tol;
  };
  auto remove = [&](std::size_t i) {
    result.objects[i].X_WO = pose_of(i);
    result.objects[i].status = DropStatus::LeftTote;
    w->world.removeRigidBody(body[i]);
  };
  std::int64_t step = 0;
  std::int64_t limit = max_steps;
  bool all_rest = false;
  // Objects left the tote: the rest may have leaned on them and must come to rest again, with
  // resettle_time more to do so.
  auto restart = [&]() {
    limit = std::max(limit, max_steps + resettle_steps);
    ++result.resettle_rounds;
    all_rest = false;
    for (std::size_t i = 0; i < n; ++i) {
      if (!body[i]->isInWorld()) continue;
      at_rest[i] = 0;
      rest_ref[i] = body[i]->getCenterOfMassTransform();
      body[i]->activate(true);
    }
  };
  std::vector<std::size_t> on_rim;
  while (true) {
    while (step < limit) {
      w->world.stepSimulation(btScalar(o.dt), 0, btScalar(o.dt));
      ++step;
      all_rest = true;
      on_rim.clear();
      for (std::size_t i = 0; i < n; ++i) {
        btRigidBody* rb = body[i];
        if (!rb->isInWorld()) continue;
        if (double(rb->getCenterOfMassPosition().z()) < fall_z) {
          remove(i);
          continue;
        }
        const btTransform& X = rb->getCenterOfMassTransform();
        const double shift = double((X.getOrigin() - rest_ref[i].getOrigin()).length());
        const double turn = double(X.getRotation().angleShortestPath(rest_ref[i].getRotation()));
        if (shift > max_shift || turn > max_turn) {
          rest_ref[i] = X;  // moving: start a new window here
          at_rest[i] = 0;
        } else {
          ++at_rest[i];
        }
        const bool slow = double(rb->getLinearVelocity().length()) < o.linear_rest &&
                          double(rb->getAngularVelocity().length()) < o.angular_rest;
        if (!slow || at_rest[i] < rest_steps) all_rest = false;
        if (slow && at_rest[i] >= rest_steps && rb->getActivationState() == ACTIVE_TAG)
          rb->setActivationState(WANTS_DEACTIVATION);
        // Came to rest on or over the rim: it leaves now, not after the whole pile rests.
        if (slow && at_rest[i] == rest_steps && outside_walls(i)) on_rim.push_back(i);
      }
      if (!on_rim.empty()) {
        for (std::size_t i : on_rim) remove(i);
        restart();
        continue;
      }
      if (all_rest) break;
    }
    // Time is up: objects on or over the rim leave; whatever leaned on them settles again.
    bool removed = false;
    for (std::size_t i = 0; i < n; ++i)
      if (body[i]->isInWorld() && outside_walls(i)) {
        remove(i);
        removed = true;
      }
    if (!removed) break;
    restart();
    if (step >= limit) break;
  }
  result.steps = step;
  result.simulated_time = double(step) * o.dt;
  result.settled = all_rest;

  // --- contacts at the final state ---
  // Sleeping bodies get no fresh contacts with the (inactive) tote: wake them (no motion).
  for (std::size_t i = 0; i < n; ++i)
    if (body[i]->isInWorld()) body[i]->activate(true);
  w->world.performDiscreteCollisionDetection();
  std::vector<std::uint32_t> contacts(n, 0);
  auto object_index = [&](const btCollisionObject* c) -> long {
    for (std::size_t i = 0; i < n; ++i)
      if (body[i] == c) return static_cast<long>(i);
    return -1;
  };
  auto is_tote = [&](const btCollisionObject* c) {
    return std::find(tote_bodies.begin(), tote_bodies.end(), c) != tote_bodies.end();
  };
  double max_pen = 0.0;
  btDispatcher* d = w->world.getDispatcher();
  for (int m = 0; m < d->getNumManifolds(); ++m) {
    const btPersistentManifold* man = d->getManifoldByIndexInternal(m);
    const btCollisionObject* a = man->getBody0();
    const btCollisionObject* b = man->getBody1();
    for (int c = 0; c < man->getNumContacts(); ++c) {
      const btManifoldPoint& pt = man->getContactPoint(c);
      const double dist = double(pt.getDistance());
      max_pen = std::max(max_pen, -dist);
      if (dist > o.contact_distance) continue;
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
      if (nz > kAxis && double(p_tote.z()) < 0.5 * H) contacts[obj] |= ContactFloor;
      if (nx > kAxis) contacts[obj] |= ContactWallMinusX;
      if (nx < -kAxis) contacts[obj] |= ContactWallPlusX;
      if (ny > kAxis) contacts[obj] |= ContactWallMinusY;
      if (ny < -kAxis) contacts[obj] |= ContactWallPlusY;
    }
  }
  result.max_penetration = max_pen;

  // --- final poses and what is kept ---
  for (std::size_t i = 0; i < n; ++i) {
    DroppedObject& r = result.objects[i];
    btRigidBody* rb = body[i];
    if (!rb->isInWorld()) continue;  // fell out, pose recorded then
    r.X_WO = from_bt(rb->getWorldTransform()) * X_OB[i].inverse();
    r.settled = at_rest[i] >= rest_steps &&
                double(rb->getLinearVelocity().length()) < o.linear_rest &&
                double(rb->getAngularVelocity().length()) < o.angular_rest;
    r.contacts = contacts[i];
    const Aabb b = world_aabb(hull_points[i], r.X_WO);
    if (b.lo.x() < -hx - tol || b.hi.x() > hx + tol || b.lo.y() < -hy - tol ||
        b.hi.y() > hy + tol || b.lo.z() < -tol) {
      r.status = DropStatus::LeftTote;
      r.contacts = 0;
    } else if (!r.settled && o.remove_unsettled) {
      r.status = DropStatus::NotSettled;
      r.contacts = 0;
    }
  }
  return result;
}

}  // namespace

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
