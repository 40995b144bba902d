#pragma once
// Private: the state of a RayScene (its Embree scene and per-geometry data), shared with the
// path tracer (render/path_tracer.cpp) so that both use one Embree loader and one BVH.
#include <mgn/raytrace/ray_scene.hpp>

#include <embree3/rtcore.h>
#include <pmmintrin.h>
#include <xmmintrin.h>

namespace mgn {

namespace detail {

/// Embree wants flush-to-zero and denormals-are-zero in tracing threads. The mode is saved and
/// restored so a call made on the Python thread leaves its floating-point state unchanged.
class FtzDazGuard {
 public:
  FtzDazGuard() : saved_(_mm_getcsr()) {
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
  }
  ~FtzDazGuard() { _mm_setcsr(saved_); }

 private:
  unsigned int saved_;
};

}  // namespace detail

struct RayScene::Impl {
  RTCScene scene = nullptr;
  std::vector<std::int32_t> instance_ids;  // by Embree geomID
  std::vector<Points3f> world_normals;     // per geometry, per face
  std::int64_t triangles = 0;
  bool all_hits = true;  // built with the context filter intersect_all needs
  Eigen::Matrix<double, 2, 3, Eigen::RowMajor> bounds;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
  }

  void fill_hit(Eigen::Index i, const Points3f& origins, const Points3f& directions, float t,
                unsigned geom, unsigned prim, float u, float v, RayHits& out) const {
    out.distance[i] = t;
    out.points.row(i) = origins.row(i) + t * directions.row(i);
    out.normals.row(i) = world_normals[geom].row(prim);
    out.instance_ids[i] = instance_ids[geom];
    out.face_ids[i] = static_cast<std::int32_t>(prim);
    out.barycentric.row(i) << u, v;
  }
};

}  // namespace mgn
