#include <mgn/core/error.hpp>
#include <mgn/raytrace/ray_scene.hpp>

#include <embree3/rtcore.h>
#include <pmmintrin.h>
#include <xmmintrin.h>

#include <algorithm>
#include <cmath>
#include <mutex>

#include "raytrace/parallel_rays.hpp"
#include "raytrace/ray_scene_impl.hpp"

namespace mgn {

namespace {

std::mutex g_device_mutex;
std::string g_last_error;

const char* error_name(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE:
      return "no error";
    case RTC_ERROR_INVALID_ARGUMENT:
      return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION:
      return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY:
      return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU:
      return "unsupported CPU";
    case RTC_ERROR_CANCELLED:
      return "cancelled";
    default:
      return "unknown error";
  }
}

void device_error(void*, RTCError code, const char* message) {
  std::lock_guard<std::mutex> lock(g_device_mutex);
  g_last_error = std::string(error_name(code)) + ": " + (message ? message : "");
}

/// One process-wide Embree device (thread-safe per Embree's contract).
RTCDevice shared_device() {
  static RTCDevice device = [] {
    RTCDevice d = rtcNewDevice(nullptr);
    if (d == nullptr) throw_error<BackendError>("RayScene: Embree could not create a device");
    rtcSetDeviceErrorFunction(d, device_error, nullptr);
    return d;
  }();
  return device;
}

/// One ray (origin o, direction d, both 3 floats) into an Embree single ray.
void set_ray(RTCRay& r, const float* o, const float* d, float tnear, float tfar) {
  r.org_x = o[0];
  r.org_y = o[1];
  r.org_z = o[2];
  r.dir_x = d[0];
  r.dir_y = d[1];
  r.dir_z = d[2];
  r.tnear = tnear;
  r.tfar = tfar;
  r.time = 0.0f;
  r.mask = 0xFFFFFFFFu;
  r.id = 0;
  r.flags = 0;
}

/// One ray into lane k of an Embree packet (RTCRay4/8/16).
template <class Packet>
void set_lane(Packet& r, int k, const float* o, const float* d, float tnear, float tfar) {
  r.org_x[k] = o[0];
  r.org_y[k] = o[1];
  r.org_z[k] = o[2];
  r.dir_x[k] = d[0];
  r.dir_y[k] = d[1];
  r.dir_z[k] = d[2];
  r.tnear[k] = tnear;
  r.tfar[k] = tfar;
  r.time[k] = 0.0f;
  r.mask[k] = 0xFFFFFFFFu;
  r.id[k] = static_cast<unsigned>(k);
  r.flags[k] = 0;
}

/// Rays s .. s+m-1 (1 <= m <= 16) into an Embree packet; the lanes past m repeat the last ray
/// and are switched off in `valid`.
void set_packet(RTCRay16& r, int* valid, const Points3f& origins, const Points3f& directions,
                std::size_t s, std::size_t m, const CastOptions& options) {
  for (std::size_t k = 0; k < 16; ++k) {
    const std::size_t i = s + std::min(k, m - 1);
    valid[k] = k < m ? -1 : 0;
    set_lane(r, static_cast<int>(k), &origins(i, 0), &directions(i, 0), options.tnear,
             options.tfar);
  }
}

/// The Embree context of a query: coherent rays (packets) when options.coherent.
RTCIntersectContext cast_context(const CastOptions& options) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  if (options.coherent) ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  return ctx;
}

struct HitRecord {
  float t;
  float u, v;
  unsigned geom;
  unsigned prim;
};

struct AllHitsContext {
  RTCIntersectContext base;  // must be first: Embree passes a pointer to it
  std::vector<HitRecord>* hits;
};

void collect_all_hits(const RTCFilterFunctionNArguments* args) {
  auto* ctx = reinterpret_cast<AllHitsContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    HitRecord h;
    h.t = RTCRayN_tfar(args->ray, args->N, i);
    h.u = RTCHitN_u(args->hit, args->N, i);
    h.v = RTCHitN_v(args->hit, args->N, i);
    h.geom = RTCHitN_geomID(args->hit, args->N, i);
    h.prim = RTCHitN_primID(args->hit, args->N, i);
    ctx->hits->push_back(h);
    args->valid[i] = 0;  // reject the hit so traversal continues
  }
}

void check_rays(const char* fn, const Points3f& origins, const Points3f& directions,
                const CastOptions& options) {
  if (origins.rows() != directions.rows()) {
    throw_error<InvalidArgument>(fn, ": origins has ", origins.rows(), " rows but directions has ",
                                 directions.rows(), "; expected the same number of rays");
  }
  if (!(options.tnear >= 0.0f) || std::isnan(options.tfar) || options.tnear > options.tfar) {
    throw_error<InvalidArgument>(fn, ": expected 0 <= tnear <= tfar, got tnear=", options.tnear,
                                 " tfar=", options.tfar);
  }
  for (Eigen::Index i = 0; i < origins.rows(); ++i) {
    if (!origins.row(i).allFinite() || !directions.row(i).allFinite()) {
      throw_error<InvalidArgument>(fn, ": ray ", i,
                                   " has a non-finite origin or direction; expected finite values");
    }
    if (directions.row(i).squaredNorm() == 0.0f) {
      throw_error<InvalidArgument>(fn, ": ray ", i,
                                   " has a zero direction; expected a non-zero vector");
    }
  }
}

// Appends hits (sorted by t) to kept, one per surface crossing: a ray through a shared edge or
// vertex hits every adjacent face at (almost) the same t, and a primitive may be reported from
// several BVH leaves, so a hit within 1e-5 (1 + |t|) of a kept hit on the same geometry is left
// out. Stops when kept holds max_hits hits.
void keep_one_hit_per_crossing(const std::vector<HitRecord>& hits, int max_hits,
                               std::vector<HitRecord>& kept) {
  for (const HitRecord& h : hits) {
    bool duplicate = false;
    for (auto it = kept.rbegin(); it != kept.rend(); ++it) {
      if (h.t - it->t > 1e-5f * (1.0f + std::abs(h.t))) break;
      if (it->geom == h.geom) {
        duplicate = true;
        break;
      }
    }
    if (!duplicate) kept.push_back(h);
    if (static_cast<int>(kept.size()) >= max_hits) break;
  }
}

}  // namespace

RayScene::RayScene(const std::vector<RayGeometry>& geometries, bool all_hits)
    : impl_(std::make_unique<Impl>()) {
  const char* fn = "RayScene";
  if (geometries.empty())
    throw_error<InvalidArgument>(fn, ": no geometry given; expected at least one mesh");
  detail::FtzDazGuard guard;
  RTCDevice device = shared_device();
  impl_->scene = rtcNewScene(device);
  // intersect_all collects the hits with a filter function in the intersect context.
  impl_->all_hits = all_hits;
  rtcSetSceneFlags(impl_->scene,
                   all_hits ? RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION
                            : RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
  impl_->bounds.row(0).setConstant(std::numeric_limits<double>::infinity());
  impl_->bounds.row(1).setConstant(-std::numeric_limits<double>::infinity());
  for (std::size_t g = 0; g < geometries.size(); ++g) {
    const RayGeometry& item = geometries[g];
    if (item.mesh == nullptr) throw_error<InvalidArgument>(fn, ": geometry ", g, " has no mesh");
    require_non_empty(*item.mesh, std::string(fn) + ": geometry " + std::to_string(g));
    if (!item.X_WO.matrix().allFinite()) {
      throw_error<InvalidArgument>(fn, ": geometry ", g,
                                   " has a non-finite pose; expected a finite 4x4 transform");
    }
    if (item.instance_id < 0) {
      throw_error<InvalidArgument>(fn, ": geometry ", g, " has instance id ", item.instance_id,
                                   "; expected >= 0");
    }
    const Mesh world = item.mesh->transformed(item.X_WO);
    const auto nv = world.num_vertices();
    const auto nf = world.num_faces();
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                           RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                           static_cast<size_t>(nv)));
    auto* ib = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(unsigned), static_cast<size_t>(nf)));
    if (vb == nullptr || ib == nullptr) {
      rtcReleaseGeometry(geom);
      throw_error<BackendError>(fn, ": Embree could not allocate buffers for geometry ", g, ": ",
                                g_last_error);
    }
    std::copy(world.vertices().data(), world.vertices().data() + 3 * nv, vb);
    for (Eigen::Index i = 0; i < 3 * nf; ++i)
      ib[i] = static_cast<unsigned>(world.faces().data()[i]);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(impl_->scene, geom, static_cast<unsigned>(g));
    rtcReleaseGeometry(geom);
    impl_->instance_ids.push_back(item.instance_id);
    impl_->world_normals.push_back(world.face_normals());
    impl_->triangles += nf;
    const auto b = world.bounds();
    impl_->bounds.row(0) = impl_->bounds.row(0).cwiseMin(b.row(0));
    impl_->bounds.row(1) = impl_->bounds.row(1).cwiseMax(b.row(1));
  }
  rtcCommitScene(impl_->scene);
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE) {
    throw_error<BackendError>(fn, ": Embree failed to build the scene: ", g_last_error);
  }
}

RayScene::~RayScene() = default;
RayScene::RayScene(RayScene&&) noexcept = default;
RayScene& RayScene::operator=(RayScene&&) noexcept = default;

std::size_t RayScene::num_geometries() const { return impl_->instance_ids.size(); }
std::int64_t RayScene::num_triangles() const { return impl_->triangles; }
Eigen::Matrix<double, 2, 3, Eigen::RowMajor> RayScene::bounds() const { return impl_->bounds; }

namespace {

/// Casts the first-hit query of every ray and calls on_hit(ray, t, geomID, primID, u, v) for each
/// ray that hits (misses are left to the caller's defaults).
template <typename OnHit>
void trace_first_hits(RTCScene scene, const Points3f& origins, const Points3f& directions,
                      const CastOptions& options, const OnHit& on_hit) {
  const Eigen::Index n = origins.rows();
  auto body = [&](std::size_t begin, std::size_t end) {
    detail::FtzDazGuard guard;
    RTCIntersectContext ctx = cast_context(options);
    if (options.coherent) {
      alignas(64) RTCRayHit16 rh;
      alignas(64) int valid[16];
      for (std::size_t s = begin; s < end; s += 16) {
        const std::size_t m = std::min<std::size_t>(16, end - s);
        set_packet(rh.ray, valid, origins, directions, s, m, options);
        for (std::size_t k = 0; k < 16; ++k) {
          rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
          rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect16(valid, scene, &ctx, &rh);
        for (std::size_t k = 0; k < m; ++k) {
          if (rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) continue;
          on_hit(static_cast<Eigen::Index>(s + k), rh.ray.tfar[k], rh.hit.geomID[k],
                 rh.hit.primID[k], rh.hit.u[k], rh.hit.v[k]);
        }
      }
    } else {
      RTCRayHit rh;
      for (std::size_t i = begin; i < end; ++i) {
        set_ray(rh.ray, &origins(i, 0), &directions(i, 0), options.tnear, options.tfar);
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &ctx, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        on_hit(static_cast<Eigen::Index>(i), rh.ray.tfar, rh.hit.geomID, rh.hit.primID, rh.hit.u,
               rh.hit.v);
      }
    }
  };
  parallel_for(static_cast<std::size_t>(n), options.num_threads, 4096, body);
}

}  // namespace

RayHits RayScene::intersect(const Points3f& origins, const Points3f& directions,
                            const CastOptions& options) const {
  check_rays("RayScene::intersect", origins, directions, options);
  const Eigen::Index n = origins.rows();
  RayHits out;
  out.distance.assign(static_cast<std::size_t>(n), std::numeric_limits<float>::infinity());
  out.points = Points3f::Zero(n, 3);
  out.normals = Points3f::Zero(n, 3);
  out.instance_ids.assign(static_cast<std::size_t>(n), -1);
  out.face_ids.assign(static_cast<std::size_t>(n), -1);
  out.barycentric = Points2f::Zero(n, 2);
  const Impl& impl = *impl_;
  trace_first_hits(impl.scene, origins, directions, options,
                   [&](Eigen::Index i, float t, unsigned geom, unsigned prim, float u, float v) {
                     impl.fill_hit(i, origins, directions, t, geom, prim, u, v, out);
                   });
  return out;
}

RayHitIds RayScene::intersect_ids(const Points3f& origins, const Points3f& directions,
                                  const CastOptions& options) const {
  check_rays("RayScene::intersect_ids", origins, directions, options);
  const auto n = static_cast<std::size_t>(origins.rows());
  RayHitIds out;
  out.instance_ids.assign(n, -1);
  out.face_ids.assign(n, -1);
  const Impl& impl = *impl_;
  trace_first_hits(impl.scene, origins, directions, options,
                   [&](Eigen::Index i, float, unsigned geom, unsigned prim, float, float) {
                     out.instance_ids[static_cast<std::size_t>(i)] = impl.instance_ids[geom];
                     out.face_ids[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(prim);
                   });
  return out;
}

std::vector<std::uint8_t> RayScene::occluded(const Points3f& origins, const Points3f& directions,
                                             const CastOptions& options) const {
  check_rays("RayScene::occluded", origins, directions, options);
  const Eigen::Index n = origins.rows();
  std::vector<std::uint8_t> out(static_cast<std::size_t>(n), 0);
  const Impl& impl = *impl_;
  auto body = [&](std::size_t begin, std::size_t end) {
    detail::FtzDazGuard guard;
    RTCIntersectContext ctx = cast_context(options);
    if (options.coherent) {
      alignas(64) RTCRay16 r;
      alignas(64) int valid[16];
      for (std::size_t s = begin; s < end; s += 16) {
        const std::size_t m = std::min<std::size_t>(16, end - s);
        set_packet(r, valid, origins, directions, s, m, options);
        rtcOccluded16(valid, impl.scene, &ctx, &r);
        for (std::size_t k = 0; k < m; ++k)
          out[s + k] = r.tfar[k] == -std::numeric_limits<float>::infinity();
      }
    } else {
      RTCRay r;
      for (std::size_t i = begin; i < end; ++i) {
        set_ray(r, &origins(i, 0), &directions(i, 0), options.tnear, options.tfar);
        rtcOccluded1(impl.scene, &ctx, &r);
        out[i] = r.tfar == -std::numeric_limits<float>::infinity();
      }
    }
  };
  parallel_for(static_cast<std::size_t>(n), options.num_threads, 4096, body);
  return out;
}

RayAllHits RayScene::intersect_all(const Points3f& origins, const Points3f& directions,
                                   int max_hits_per_ray, const CastOptions& options) const {
  if (!impl_->all_hits) {
    throw_error<Unsupported>(
        "RayScene::intersect_all: this scene was built with all_hits = false (no all-hits "
        "queries); build it with all_hits = true");
  }
  check_rays("RayScene::intersect_all", origins, directions, options);
  if (max_hits_per_ray <= 0) {
    throw_error<InvalidArgument>("RayScene::intersect_all: max_hits_per_ray must be > 0, got ",
                                 max_hits_per_ray);
  }
  const Eigen::Index n = origins.rows();
  std::vector<std::vector<HitRecord>> per_ray(static_cast<std::size_t>(n));
  const Impl& impl = *impl_;
  auto body = [&](std::size_t begin, std::size_t end) {
    detail::FtzDazGuard guard;
    std::vector<HitRecord> hits;
    for (std::size_t i = begin; i < end; ++i) {
      hits.clear();
      AllHitsContext ctx;
      rtcInitIntersectContext(&ctx.base);
      ctx.base.filter = collect_all_hits;
      ctx.hits = &hits;
      RTCRayHit rh;
      set_ray(rh.ray, &origins(i, 0), &directions(i, 0), options.tnear, options.tfar);
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(impl.scene, &ctx.base, &rh);
      std::sort(hits.begin(), hits.end(), [](const HitRecord& a, const HitRecord& b) {
        return a.t < b.t ||
               (a.t == b.t && (a.geom < b.geom || (a.geom == b.geom && a.prim < b.prim)));
      });
      keep_one_hit_per_crossing(hits, max_hits_per_ray, per_ray[i]);
    }
  };
  parallel_for(static_cast<std::size_t>(n), options.num_threads, 1024, body);

  RayAllHits out;
  out.offsets.resize(static_cast<std::size_t>(n) + 1, 0);
  for (Eigen::Index i = 0; i < n; ++i)
    out.offsets[i + 1] = out.offsets[i] + static_cast<std::int64_t>(per_ray[i].size());
  const auto total = static_cast<Eigen::Index>(out.offsets.back());
  out.distance.resize(static_cast<std::size_t>(total));
  out.points.resize(total, 3);
  out.normals.resize(total, 3);
  out.instance_ids.resize(static_cast<std::size_t>(total));
  out.face_ids.resize(static_cast<std::size_t>(total));
  out.ray_ids.resize(static_cast<std::size_t>(total));
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::Index k = static_cast<Eigen::Index>(out.offsets[i]);
    for (const HitRecord& h : per_ray[i]) {
      out.distance[k] = h.t;
      out.points.row(k) = origins.row(i) + h.t * directions.row(i);
      out.normals.row(k) = impl.world_normals[h.geom].row(h.prim);
      out.instance_ids[k] = impl.instance_ids[h.geom];
      out.face_ids[k] = static_cast<std::int32_t>(h.prim);
      out.ray_ids[k] = static_cast<std::int32_t>(i);
      ++k;
    }
  }
  return out;
}

void camera_rays(const Mat3d& K, int width, int height, const Pose& X_WC, Points3f& origins,
                 Points3f& directions) {
  if (width <= 0 || height <= 0) {
    throw_error<InvalidArgument>("camera_rays: image size must be positive, got ", width, "x",
                                 height);
  }
  const double fx = K(0, 0), fy = K(1, 1), cx = K(0, 2), cy = K(1, 2);
  if (!(fx > 0) || !(fy > 0) || !std::isfinite(cx) || !std::isfinite(cy)) {
    throw_error<InvalidArgument>("camera_rays: expected fx, fy > 0 and finite cx, cy, got fx=", fx,
                                 " fy=", fy, " cx=", cx, " cy=", cy);
  }
  if (!X_WC.matrix().allFinite())
    throw_error<InvalidArgument>("camera_rays: X_WC has non-finite entries");
  const Eigen::Index n = static_cast<Eigen::Index>(width) * height;
  origins.resize(n, 3);
  directions.resize(n, 3);
  const Mat3d R = X_WC.linear();
  const Eigen::RowVector3f o = X_WC.translation().cast<float>().transpose();
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const Eigen::Index i = static_cast<Eigen::Index>(v) * width + u;
      const Vec3d d_C((u + 0.5 - cx) / fx, (v + 0.5 - cy) / fy, 1.0);
      origins.row(i) = o;
      directions.row(i) = (R * d_C.normalized()).cast<float>().transpose();
    }
  }
}

}  // namespace mgn

// ---------------------------------------------------------------------------------------------
// Private fast paths for bundles of parallel rays (see parallel_rays.hpp).

namespace mgn::detail {

OwnedScene non_robust_scene(const RayScene& scene) {
  const RayScene::Impl& impl = scene.impl();
  FtzDazGuard guard;
  RTCDevice device = shared_device();
  OwnedScene out(rtcNewScene(device));
  if (out.get() == nullptr)
    throw_error<BackendError>("non_robust_scene: Embree could not create a scene: ", g_last_error);
  rtcSetSceneFlags(out.get(), RTC_SCENE_FLAG_NONE);
  rtcSetSceneBuildQuality(out.get(), RTC_BUILD_QUALITY_HIGH);
  for (std::size_t g = 0; g < impl.instance_ids.size(); ++g) {
    const auto id = static_cast<unsigned>(g);
    rtcAttachGeometryByID(out.get(), rtcGetGeometry(impl.scene, id), id);
  }
  rtcCommitScene(out.get());
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE)
    throw_error<BackendError>("non_robust_scene: Embree failed to build the scene: ", g_last_error);
  return out;
}

namespace {

/// Packet width of the parallel-ray fast paths. 8 (one AVX2 register of floats): on the AVX2
/// machines measured (no AVX-512), the suction seal trials spent ~10 % less CPU with packets of
/// 8 than of 16; every ray's own answer does not depend on its packet.
constexpr int kPacket = 8;
using ParallelRay = RTCRay8;
using ParallelRayHit = RTCRayHit8;

void fill_packet(ParallelRay& r, int* valid, const ParallelRays& rays, int start) {
  const int m = std::min(kPacket, rays.count - start);
  const Eigen::Vector3f d = rays.dir.cast<float>();
  for (int k = 0; k < kPacket; ++k) {
    const Eigen::Vector2d& off = rays.offsets[start + std::min(k, m - 1)];
    const Eigen::Vector3f o =
        (rays.base + rays.scale * (off.x() * rays.u + off.y() * rays.v)).cast<float>();
    valid[k] = k < m ? -1 : 0;
    set_lane(r, k, o.data(), d.data(), 0.0f, rays.tfar);
  }
}

}  // namespace

void parallel_first_hits(const RayScene& scene, const ParallelRays& rays, float* t, Vec3f* normal,
                         int* face) {
  detail::FtzDazGuard guard;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  alignas(64) ParallelRayHit rh;
  alignas(64) int valid[kPacket];
  const auto& impl = scene.impl();
  for (int s = 0; s < rays.count; s += kPacket) {
    fill_packet(rh.ray, valid, rays, s);
    for (int k = 0; k < kPacket; ++k) {
      rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect8(valid, impl.scene, &ctx, &rh);
    const int m = std::min(kPacket, rays.count - s);
    for (int k = 0; k < m; ++k) {
      if (rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) {
        t[s + k] = std::numeric_limits<float>::infinity();
        normal[s + k].setZero();
        if (face) face[s + k] = -1;
      } else {
        t[s + k] = rh.ray.tfar[k];
        normal[s + k] = impl.world_normals[rh.hit.geomID[k]].row(rh.hit.primID[k]).transpose();
        if (face) face[s + k] = static_cast<int>(rh.hit.primID[k]);
      }
    }
  }
}

namespace {
/// Casts occlusion packets; returns early as soon as `stop(occluded)` is true for any ray.
template <typename Stop>
bool parallel_occlusion_until(const RayScene& scene, const ParallelRays& rays, Stop stop) {
  detail::FtzDazGuard guard;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  alignas(64) ParallelRay r;
  alignas(64) int valid[kPacket];
  for (int s = 0; s < rays.count; s += kPacket) {
    fill_packet(r, valid, rays, s);
    rtcOccluded8(valid, scene.impl().scene, &ctx, &r);
    const int m = std::min(kPacket, rays.count - s);
    for (int k = 0; k < m; ++k) {
      if (stop(r.tfar[k] == -std::numeric_limits<float>::infinity())) return true;
    }
  }
  return false;
}
}  // namespace

bool parallel_all_hit(const RayScene& scene, const ParallelRays& rays) {
  return !parallel_occlusion_until(scene, rays, [](bool occluded) { return !occluded; });
}

bool parallel_any_hit(const RayScene& scene, const ParallelRays& rays) {
  return parallel_occlusion_until(scene, rays, [](bool occluded) { return occluded; });
}

}  // namespace mgn::detail
