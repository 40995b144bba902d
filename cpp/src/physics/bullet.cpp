#include "physics/bullet.hpp"

#ifndef MGN_BULLET_EXT
#error "MGN_BULLET_EXT (0 or 1) is set by cpp/CMakeLists.txt"
#endif
#if MGN_BULLET_EXT
#include "physics/bullet_ext/hull_support.hpp"
#endif

#include <mgn/core/error.hpp>
#include <mgn/geometry/convex_decomposition.hpp>

#include <Eigen/Geometry>
#include <algorithm>

namespace mgn::physics {

btTransform BulletUnits::pose(const Pose& X) const {
  const Mat3d R = X.linear();
  btMatrix3x3 B(btScalar(R(0, 0)), btScalar(R(0, 1)), btScalar(R(0, 2)), btScalar(R(1, 0)),
                btScalar(R(1, 1)), btScalar(R(1, 2)), btScalar(R(2, 0)), btScalar(R(2, 1)),
                btScalar(R(2, 2)));
  return btTransform(B, vector(Vec3d(X.translation())));
}

Pose BulletUnits::pose(const btTransform& T) const {
  Pose X = Pose::Identity();
  const btMatrix3x3& B = T.getBasis();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) X.linear()(r, c) = B[r][c];
  X.translation() = vector(T.getOrigin());
  // Bullet works in single precision: re-orthonormalise so the pose is a clean rigid transform.
  const Eigen::Quaterniond q(X.linear());
  X.linear() = q.normalized().toRotationMatrix();
  return X;
}

namespace {

/// x, y, z only (w = 0, as from a float array).
btVector3 copy(const btVector3& v) { return btVector3(v.x(), v.y(), v.z()); }

std::vector<Vec3d> to_points(const btAlignedObjectArray<btVector3>& v) {
  std::vector<Vec3d> out(static_cast<std::size_t>(v.size()));
  for (int k = 0; k < v.size(); ++k)
    out[static_cast<std::size_t>(k)] = Vec3d(double(v[k].x()), double(v[k].y()), double(v[k].z()));
  return out;
}

}  // namespace

HullPoints hull_points(const Mesh& part, const Pose& X_BO, const BulletUnits& u,
                       const HullShapeOptions& o) {
  HullPoints h;
  btScalar* shrunk = &h.shrunk;
  std::vector<btVector3>& out = h.points;
  const Points3f& V = part.vertices();
  std::vector<double> coords(static_cast<std::size_t>(3 * V.rows()));
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const Vec3d p = u.length * (X_BO * Vec3d(V.row(v).cast<double>().transpose()));
    for (int k = 0; k < 3; ++k) coords[static_cast<std::size_t>(3 * v + k)] = p[k];
  }
  btConvexHullComputer hc;
  *shrunk = hc.compute(coords.data(), 3 * sizeof(double), static_cast<int>(V.rows()),
                       o.shrink_by_margin ? btScalar(u.length * o.margin) : btScalar(0),
                       btScalar(o.shrink_by_margin ? 0.3 : 0.0));
  if (*shrunk < 0 || hc.vertices.size() < 4) {  // degenerate: the raw points
    for (Eigen::Index v = 0; v < V.rows(); ++v)
      out.emplace_back(btScalar(coords[3 * v]), btScalar(coords[3 * v + 1]),
                       btScalar(coords[3 * v + 2]));
    return h;
  }
  if (o.max_vertices > 0 && hc.vertices.size() > o.max_vertices) {
    switch (o.reduction) {
      case HullReduction::InnerGreedy: {
        Points3d hv(hc.vertices.size(), 3);
        for (int k = 0; k < hc.vertices.size(); ++k)
          hv.row(k) << double(hc.vertices[k].x()), double(hc.vertices[k].y()),
              double(hc.vertices[k].z());
        for (Eigen::Index k : reduce_convex_points(hv, o.max_vertices, u.length * o.tolerance))
          out.push_back(copy(hc.vertices[static_cast<int>(k)]));
        return h;
      }
      case HullReduction::InnerSupportDirections: {
        const std::vector<Vec3d> few =
            spread_support_points(to_points(hc.vertices), o.max_vertices);
        std::vector<double> q;
        for (const Vec3d& v : few) q.insert(q.end(), {v.x(), v.y(), v.z()});
        hc.compute(q.data(), 3 * sizeof(double), static_cast<int>(few.size()), 0.0, 0.0);
        break;  // the hull of the support points, below
      }
      case HullReduction::Outer: {
        for (const Vec3d& v :
             outer_hull_vertices(to_points(hc.vertices), o.max_vertices, u.length * o.tolerance))
          out.emplace_back(btScalar(v.x()), btScalar(v.y()), btScalar(v.z()));
        return h;
      }
    }
  }
  for (int k = 0; k < hc.vertices.size(); ++k) out.push_back(copy(hc.vertices[k]));
  return h;
}

std::unique_ptr<btConvexHullShape> hull_shape(const HullPoints& hull, const BulletUnits& units,
                                              const HullShapeOptions& o) {
#if MGN_BULLET_EXT
  // Bullet's btConvexHullShape with a vectorised support search (same answers, see
  // bullet_ext/hull_support.hpp).
  auto shape = std::make_unique<FastHullShape>(hull.points);
#else
  auto shape = std::make_unique<btConvexHullShape>();
  for (const btVector3& p : hull.points) shape->addPoint(p, false);
#endif
  shape->recalcLocalAabb();
  if (o.shrink_by_margin)
    shape->setMargin(btScalar(std::max(0.0, hull.shrunk > 0 ? double(hull.shrunk) : 0.0)));
  else
    shape->setMargin(btScalar(units.length * o.margin));
  if (o.polyhedral) shape->initializePolyhedralFeatures();
  return shape;
}

RigidGeometry rigid_geometry(const RigidObject& object, const PrincipalFrame& principal,
                             const BulletUnits& units, const HullShapeOptions& options) {
  RigidGeometry g;
  const Pose X_BO = principal.X_OB.inverse();
  for (const Mesh& part : object.convex_parts) {
    g.hulls.push_back(hull_points(part, X_BO, units, options));
    for (const btVector3& p : g.hulls.back().points)
      g.bounding_radius = std::max(g.bounding_radius, double(p.length()) / units.length);
  }
  return g;
}

RigidShape rigid_shape(const RigidGeometry& geometry, const BulletUnits& units,
                       const HullShapeOptions& options, bool always_compound) {
  RigidShape s;
  for (const HullPoints& h : geometry.hulls) s.hulls.push_back(hull_shape(h, units, options));
  if (always_compound || s.hulls.size() > 1) s.compound = compound_of(s.hulls);
  return s;
}

std::unique_ptr<btCompoundShape> compound_of(
    const std::vector<std::unique_ptr<btConvexHullShape>>& hulls) {
  auto compound = std::make_unique<btCompoundShape>(true, static_cast<int>(hulls.size()));
  for (const auto& h : hulls) compound->addChildShape(btTransform::getIdentity(), h.get());
  return compound;
}

btRigidBody::btRigidBodyConstructionInfo body_info(double mass, const Vec3d& moments,
                                                   btCollisionShape* shape, const Pose& X_WB,
                                                   const BulletUnits& units) {
  btRigidBody::btRigidBodyConstructionInfo info(btScalar(mass), nullptr, shape,
                                                units.inertia(moments));
  info.m_startWorldTransform = units.pose(X_WB);
  return info;
}

}  // namespace mgn::physics
