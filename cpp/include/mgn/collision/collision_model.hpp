#pragma once
/// @file collision_model.hpp  Mesh-mesh collision and distance queries (FCL, OBBRSS BVH).
///
/// A CollisionModel is built once from a mesh (in its own frame) and is immutable and shareable
/// across threads. Queries place two models with world poses X_WA, X_WB. Batched queries take N
/// pose pairs and return per-pair results; they run on `num_threads` threads and give identical
/// results for any thread count.

#include <mgn/core/parallel.hpp>
#include <mgn/geometry/mesh.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace mgn {

/// Immutable FCL bounding-volume hierarchy of a mesh.
class CollisionModel {
 public:
  /// Builds the BVH. Throws InvalidArgument for an empty mesh.
  explicit CollisionModel(const Mesh& mesh);
  ~CollisionModel();
  CollisionModel(const CollisionModel&) = delete;
  CollisionModel& operator=(const CollisionModel&) = delete;

  std::int64_t num_triangles() const;
  std::int64_t num_vertices() const;

  struct Impl;
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

/// Options of a collision query.
struct CollisionRequest {
  int num_threads = 0;  ///< batch only; 0 = all hardware threads
};

/// Options of a distance query.
struct DistanceRequest {
  double rel_err = 0.0;  ///< relative error tolerance of the BVH traversal
  double abs_err = 0.0;  ///< absolute error tolerance, m
  int num_threads = 0;   ///< batch only; 0 = all hardware threads
};

/// Per-pair distance results. Colliding pairs report distance 0 and the points of one contact.
struct DistanceResult {
  std::vector<double> distance;       ///< (N) m, >= 0
  Points3d points_a;                  ///< (N,3) closest point on A, world frame
  Points3d points_b;                  ///< (N,3) closest point on B, world frame
  std::vector<std::uint8_t> collide;  ///< (N) 1 if the pair intersects
};

/// Whether A at X_WA and B at X_WB intersect (surfaces; a mesh fully inside another closed mesh
/// without touching surfaces does not count). Throws InvalidArgument on a non-finite pose.
bool collide(const CollisionModel& a, const Pose& X_WA, const CollisionModel& b, const Pose& X_WB);

/// Batched collide: poses_a and poses_b have N entries each, or one of them has 1 (broadcast).
std::vector<std::uint8_t> collide(const CollisionModel& a, const std::vector<Pose>& X_WA,
                                  const CollisionModel& b, const std::vector<Pose>& X_WB,
                                  const CollisionRequest& request = {});

/// Batched separation distance with closest points (same broadcasting as collide()).
DistanceResult distance(const CollisionModel& a, const std::vector<Pose>& X_WA,
                        const CollisionModel& b, const std::vector<Pose>& X_WB,
                        const DistanceRequest& request = {});

}  // namespace mgn
