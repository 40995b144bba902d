#pragma once
/// @file point_inside.hpp  Whether points lie inside a closed triangle mesh (ray parity, Embree).
///
/// The one point-inside-mesh test of mgn, used by the scene grasp collision check, the antipodal
/// sampler (a gripper part fully inside the object) and the renderer (camera inside a mesh).
///
/// Method: a ray from the point along a fixed direction, off every axis and diagonal, is cast
/// against the mesh (Embree, single precision); the point is inside when the ray crosses the
/// surface an odd number of times. Hits at (almost) the same distance on the same mesh, as when
/// the ray passes through a shared edge or vertex, count as one crossing (see
/// RayScene::intersect_all). Points outside the mesh's axis-aligned bounding box are outside
/// without a ray cast.
///
/// Boundary: a point on the surface (within float rounding of its coordinates, about 1e-7 times
/// their magnitude) is undetermined: it may be reported inside or outside. Two crossings closer
/// than about 1e-5 m along the ray (walls thinner than that) count as one, so points near such
/// thin features may be misclassified. Every other point is classified by the exact parity.
///
/// The answer is meaningful only for a closed (watertight) mesh; for an open mesh it is the
/// parity along one ray. Coordinates are in the mesh's own frame, in the mesh's units (m).

#include <mgn/geometry/mesh.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace mgn {

class RayScene;

/// Point-in-closed-mesh test: builds an Embree BVH of the mesh once (the mesh is copied and
/// need not outlive this object). Immutable; queries are thread-safe.
class PointInsideTest {
 public:
  /// Builds the BVH of `mesh` (own frame). Throws InvalidArgument for an empty mesh.
  explicit PointInsideTest(const Mesh& mesh);
  ~PointInsideTest();
  PointInsideTest(const PointInsideTest&) = delete;
  PointInsideTest& operator=(const PointInsideTest&) = delete;

  /// Whether point p (mesh frame, m) is inside the mesh. Throws InvalidArgument if p is not
  /// finite.
  bool contains(const Vec3d& p) const;

  /// contains() of each of the (N,3) points (mesh frame, m) -> (N) 1 inside / 0 outside, computed
  /// on the calling thread (meant for small batches inside already parallel loops). Throws
  /// InvalidArgument if a point is not finite.
  std::vector<std::uint8_t> contains_each(const Points3d& points) const;

  /// Whether any of the (N,3) points is inside (same answer as any of contains_each(points)).
  bool contains_any(const Points3d& points) const;

  /// The fixed ray direction of the parity test (unit, mesh frame).
  static Vec3d ray_direction();

 private:
  std::unique_ptr<RayScene> rays_;
  Vec3d lo_, hi_;  // bounding box of the mesh, m
  int max_hits_ = 1;
};

}  // namespace mgn
