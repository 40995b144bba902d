#include <mgn/collision/collision_model.hpp>
#include <mgn/core/error.hpp>

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include <algorithm>

namespace mgn {

struct CollisionModel::Impl {
  std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> bvh;
  std::int64_t vertices = 0;
  std::int64_t triangles = 0;
};

CollisionModel::CollisionModel(const Mesh& mesh) : impl_(std::make_unique<Impl>()) {
  require_non_empty(mesh, "CollisionModel");
  std::vector<fcl::Vector3d> points(static_cast<std::size_t>(mesh.num_vertices()));
  for (Eigen::Index i = 0; i < mesh.num_vertices(); ++i)
    points[i] = mesh.vertices().row(i).transpose().cast<double>();
  std::vector<fcl::Triangle> tris(static_cast<std::size_t>(mesh.num_faces()));
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    tris[f] = fcl::Triangle(mesh.faces()(f, 0), mesh.faces()(f, 1), mesh.faces()(f, 2));
  }
  auto bvh = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
  if (bvh->beginModel(static_cast<int>(tris.size()), static_cast<int>(points.size())) !=
          fcl::BVH_OK ||
      bvh->addSubModel(points, tris) != fcl::BVH_OK || bvh->endModel() != fcl::BVH_OK) {
    throw_error<BackendError>("CollisionModel: FCL failed to build the BVH of mesh '", mesh.name(),
                              "'");
  }
  bvh->computeLocalAABB();  // done once here: queries never mutate the model
  impl_->bvh = std::move(bvh);
  impl_->vertices = mesh.num_vertices();
  impl_->triangles = mesh.num_faces();
}

CollisionModel::~CollisionModel() = default;
std::int64_t CollisionModel::num_triangles() const { return impl_->triangles; }
std::int64_t CollisionModel::num_vertices() const { return impl_->vertices; }

namespace {

void check_pose(const char* fn, const char* which, std::size_t i, const Pose& X) {
  if (!X.matrix().allFinite()) {
    throw_error<InvalidArgument>(fn, ": ", which, "[", i,
                                 "] has non-finite entries; expected a finite rigid transform");
  }
}

std::size_t broadcast_size(const char* fn, std::size_t na, std::size_t nb) {
  if (na == 0 || nb == 0) {
    if (na == 0 && nb == 0) return 0;
    throw_error<InvalidArgument>(fn, ": got ", na, " poses for A and ", nb,
                                 " for B; expected equal counts or one of them 1");
  }
  if (na != nb && na != 1 && nb != 1) {
    throw_error<InvalidArgument>(fn, ": got ", na, " poses for A and ", nb,
                                 " for B; expected equal counts or one of them 1");
  }
  return std::max(na, nb);
}

bool collide_one(const CollisionModel& a, const Pose& X_WA, const CollisionModel& b,
                 const Pose& X_WB, fcl::Vector3d* contact) {
  fcl::CollisionRequestd request(1, contact != nullptr);
  fcl::CollisionResultd result;
  fcl::collide(a.impl().bvh.get(), fcl::Transform3d(X_WA.matrix()), b.impl().bvh.get(),
               fcl::Transform3d(X_WB.matrix()), request, result);
  if (result.isCollision() && contact != nullptr && result.numContacts() > 0)
    *contact = result.getContact(0).pos;
  return result.isCollision();
}

}  // namespace

bool collide(const CollisionModel& a, const Pose& X_WA, const CollisionModel& b, const Pose& X_WB) {
  check_pose("collide", "X_WA", 0, X_WA);
  check_pose("collide", "X_WB", 0, X_WB);
  return collide_one(a, X_WA, b, X_WB, nullptr);
}

std::vector<std::uint8_t> collide(const CollisionModel& a, const std::vector<Pose>& X_WA,
                                  const CollisionModel& b, const std::vector<Pose>& X_WB,
                                  const CollisionRequest& request) {
  const std::size_t n = broadcast_size("collide", X_WA.size(), X_WB.size());
  for (std::size_t i = 0; i < X_WA.size(); ++i) check_pose("collide", "X_WA", i, X_WA[i]);
  for (std::size_t i = 0; i < X_WB.size(); ++i) check_pose("collide", "X_WB", i, X_WB[i]);
  std::vector<std::uint8_t> out(n, 0);
  parallel_for(n, request.num_threads, 64, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      out[i] = collide_one(a, X_WA[X_WA.size() == 1 ? 0 : i], b, X_WB[X_WB.size() == 1 ? 0 : i],
                           nullptr);
    }
  });
  return out;
}

DistanceResult distance(const CollisionModel& a, const std::vector<Pose>& X_WA,
                        const CollisionModel& b, const std::vector<Pose>& X_WB,
                        const DistanceRequest& request) {
  const char* fn = "distance";
  const std::size_t n = broadcast_size(fn, X_WA.size(), X_WB.size());
  for (std::size_t i = 0; i < X_WA.size(); ++i) check_pose(fn, "X_WA", i, X_WA[i]);
  for (std::size_t i = 0; i < X_WB.size(); ++i) check_pose(fn, "X_WB", i, X_WB[i]);
  if (!(request.rel_err >= 0.0) || !(request.abs_err >= 0.0)) {
    throw_error<InvalidArgument>(fn, ": rel_err and abs_err must be >= 0, got ", request.rel_err,
                                 " and ", request.abs_err);
  }
  DistanceResult out;
  out.distance.assign(n, 0.0);
  out.points_a = Points3d::Zero(static_cast<Eigen::Index>(n), 3);
  out.points_b = Points3d::Zero(static_cast<Eigen::Index>(n), 3);
  out.collide.assign(n, 0);
  parallel_for(n, request.num_threads, 32, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Pose& xa = X_WA[X_WA.size() == 1 ? 0 : i];
      const Pose& xb = X_WB[X_WB.size() == 1 ? 0 : i];
      const auto row = static_cast<Eigen::Index>(i);
      fcl::Vector3d contact = fcl::Vector3d::Zero();
      // FCL's mesh-mesh distance is undefined for intersecting meshes: test collision first.
      if (collide_one(a, xa, b, xb, &contact)) {
        out.collide[i] = 1;
        out.points_a.row(row) = contact.transpose();
        out.points_b.row(row) = contact.transpose();
        continue;
      }
      fcl::DistanceRequestd req(true, true, request.rel_err, request.abs_err);
      fcl::DistanceResultd res;
      fcl::distance(a.impl().bvh.get(), fcl::Transform3d(xa.matrix()), b.impl().bvh.get(),
                    fcl::Transform3d(xb.matrix()), req, res);
      out.distance[i] = std::max(0.0, res.min_distance);
      out.points_a.row(row) = res.nearest_points[0].transpose();
      out.points_b.row(row) = res.nearest_points[1].transpose();
    }
  });
  return out;
}

}  // namespace mgn
