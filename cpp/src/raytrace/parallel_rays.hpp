#pragma once
// Private fast paths for bundles of parallel rays (suction cup projections, hole checks): rays
// start at base + x_i u + y_i v and all travel along `dir`. No input validation, one thread,
// Embree packets of 16, no allocation. Used inside per-candidate work that is already threaded.
#include <mgn/raytrace/ray_scene.hpp>

namespace mgn::detail {

struct ParallelRays {
  Vec3d base;                      ///< origin of offset (0, 0)
  Vec3d u, v;                      ///< in-plane axes of the offsets
  Vec3d dir;                       ///< common direction (unit)
  const Eigen::Vector2d* offsets;  ///< (count) offsets (x_i, y_i) in metres
  int count;
  double scale = 1.0;  ///< offsets are multiplied by this
  float tfar = std::numeric_limits<float>::infinity();
};

/// First hits: t[i] (inf on a miss), normal[i] (unit geometric normal of the face hit) and, when
/// `face` is not null, face[i] (index of the face hit in its geometry; -1 on a miss).
void parallel_first_hits(const RayScene& scene, const ParallelRays& rays, float* t, Vec3f* normal,
                         int* face = nullptr);

/// True if every ray hits something within tfar (stops at the first packet with a miss).
bool parallel_all_hit(const RayScene& scene, const ParallelRays& rays);

/// True if any ray hits something within tfar (stops at the first packet with a hit).
bool parallel_any_hit(const RayScene& scene, const ParallelRays& rays);

}  // namespace mgn::detail
