#pragma once
// Private: the state of a RayScene (its Embree scene and per-geometry data), shared with the
// path tracer (render/detail/pt_scene.hpp) so that both use one Embree loader and one BVH.
#include <mgn/raytrace/ray_scene.hpp>

#include <embree3/rtcore.h>
#include <pmmintrin.h>
#include <xmmintrin.h>

#include <utility>

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

/// An owned Embree scene (released on destruction; move-only).
class OwnedScene {
 public:
  OwnedScene() = default;
  explicit OwnedScene(RTCScene s) : scene_(s) {}
  OwnedScene(const OwnedScene&) = delete;
  OwnedScene& operator=(const OwnedScene&) = delete;
  OwnedScene(OwnedScene&& o) noexcept : scene_(o.scene_) { o.scene_ = nullptr; }
  OwnedScene& operator=(OwnedScene&& o) noexcept {
    std::swap(scene_, o.scene_);
    return *this;
  }
  ~OwnedScene() {
    if (scene_) rtcReleaseScene(scene_);
  }
  RTCScene get() const { return scene_; }

 private:
  RTCScene scene_ = nullptr;
};

/// A second BVH over the geometries of `scene` (the same Embree geometries, attached under the
/// same geometry ids: the vertex and index buffers are shared, only the BVH is new), built
/// without RTC_SCENE_FLAG_ROBUST: Embree's faster, not watertight triangle test, whose hit
/// distances differ from the robust scene's in the last bits and which may (rarely) let a ray
/// through a shared edge or vertex. For queries whose answers are averaged (a path tracer's
/// bounce and shadow rays), never for labels. Throws BackendError if Embree fails.
OwnedScene non_robust_scene(const RayScene& scene);

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
