#pragma once
// The support mapping of a convex hull shape, vectorised (private: Bullet types do not appear in
// installed headers).
//
// Mirrors Bullet 3.24: btConvexHullShape::localGetSupportingVertexWithoutMargin,
// btConvexHullShape::batchedUnitVectorGetSupportingVertexWithoutMargin and the scalar scan of
// btVector3::maxDot (LinearMath/btVector3.h, built without BT_USE_SSE).
//
// Bullet's btConvexHullShape finds its support vertex (the vertex of largest dot product with a
// direction) by a scalar scan of its vertices (btVector3::maxDot: Debian's Bullet is built
// without SIMD); in a drop this scan is about half of the simulation time. HullSupport keeps the
// vertices as a structure of arrays and scans 4 (SSE2) or 8 (AVX) of them at once with the same
// single-precision operations in the same order, (x * dx + y * dy) + z * dz without fused
// multiply-adds, and the same tie rule (the first vertex of the largest dot product), so it
// returns exactly the vertex Bullet's scan returns: the simulation is unchanged, bit for bit.
#include "physics/bullet_ext/version.hpp"

#include <LinearMath/btVector3.h>
#include <btBulletCollisionCommon.h>

#include <cstddef>
#include <vector>

namespace mgn::physics {

class HullSupport {
 public:
  HullSupport() = default;
  /// The vertices (x, y, z of each; w ignored).
  HullSupport(const btVector3* points, int count);

  /// Index of the first vertex of largest dot(vertex, d), and that dot product (`dot`); -1 (and
  /// `dot` = -SIMD_INFINITY, i.e. -FLT_MAX) if there is no vertex or no dot product exceeds
  /// -FLT_MAX (as btVector3::maxDot).
  long argmax(const btVector3& d, btScalar& dot) const;

  int size() const { return count_; }
  /// Vertex i (0 <= i < size()), w = 0; read from the arrays just scanned (in cache).
  btVector3 vertex(long i) const {
    const auto k = static_cast<std::size_t>(i);
    return btVector3(x_[k], y_[k], z_[k]);
  }

  /// Tests only: scan 8 (AVX), 4 (SSE2) or 1 vertex at a time, at most what the processor
  /// supports (any other value: the widest supported); returns the width now used. Every width
  /// gives the same answers.
  static int set_width(int width);

 private:
  int count_ = 0;
  std::vector<float> x_, y_, z_;  // padded to a multiple of 8 with copies of vertex 0
};

/// A btConvexHullShape whose support queries use HullSupport (same answers, faster). Its shape
/// type is CUSTOM_POLYHEDRAL_SHAPE_TYPE, so that Bullet's narrow phase (which switches on the
/// type and scans a CONVEX_HULL_SHAPE_PROXYTYPE's vertices itself) calls the virtual support
/// functions; Bullet treats both types alike otherwise (convex, polyhedral, the same margin and
/// bounding box). The points are fixed at construction: do not call addPoint() afterwards.
class FastHullShape : public btConvexHullShape {
 public:
  explicit FastHullShape(const std::vector<btVector3>& points);

  btVector3 localGetSupportingVertexWithoutMargin(const btVector3& vec) const override;
  void batchedUnitVectorGetSupportingVertexWithoutMargin(const btVector3* vectors,
                                                         btVector3* supportVerticesOut,
                                                         int numVectors) const override;

 private:
  HullSupport support_;
};

}  // namespace mgn::physics
