#include <mgn/core/error.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/render/path_tracer.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "render/detail/pt_adaptive.hpp"
#include "render/detail/pt_film.hpp"
#include "render/detail/pt_integrator.hpp"
#include "render/detail/pt_math.hpp"
#include "render/detail/pt_scene.hpp"

// The path tracer: option checks and PathScene::render, which runs the film's passes
// (pt_film.cpp) with the integrator (pt_integrator.cpp) over the scene (pt_scene.cpp).

namespace mgn {

using pt::f3;
using pt::F3;

void PathTraceOptions::validate() const {
  const char* w = "PathTraceOptions";
  if (spp < 1) throw_error<InvalidArgument>(w, ".spp must be >= 1, got ", spp);
  if (max_bounces < 0 || max_bounces > 1000)
    throw_error<InvalidArgument>(w, ".max_bounces must be in [0, 1000], got ", max_bounces);
  if (num_threads < 0)
    throw_error<InvalidArgument>(w, ".num_threads must be >= 0 (0 = all), got ", num_threads);
  if (rr_depth < 0) throw_error<InvalidArgument>(w, ".rr_depth must be >= 0, got ", rr_depth);
  if (!(aperture_radius >= 0.0) || !std::isfinite(aperture_radius))
    throw_error<InvalidArgument>(w, ".aperture_radius must be finite and >= 0 (m), got ",
                                 aperture_radius);
  if (!(focus_distance >= 0.0) || !std::isfinite(focus_distance))
    throw_error<InvalidArgument>(w, ".focus_distance must be finite and >= 0 (m), got ",
                                 focus_distance);
  if (!(clamp >= 0.0) || !std::isfinite(clamp))
    throw_error<InvalidArgument>(w, ".clamp must be finite and >= 0 (0 = off), got ", clamp);
  if (!(clamp_indirect >= 0.0) || !std::isfinite(clamp_indirect))
    throw_error<InvalidArgument>(w, ".clamp_indirect must be finite and >= 0 (0 = off), got ",
                                 clamp_indirect);
  if (!(fresnel_split_min >= 0.0) || !std::isfinite(fresnel_split_min))
    throw_error<InvalidArgument>(
        w, ".fresnel_split_min must be finite and >= 0 (path throughput, 0 = always split), got ",
        fresnel_split_min);
  if (!(guide_split_min >= 0.0) || !std::isfinite(guide_split_min))
    throw_error<InvalidArgument>(
        w, ".guide_split_min must be finite and >= 0 (share of a pixel's guide, 0 = always), got ",
        guide_split_min);
  if (!(adaptive_samples >= 0.0) || !std::isfinite(adaptive_samples))
    throw_error<InvalidArgument>(
        w, ".adaptive_samples must be finite and >= 0 (extra samples per pixel, 0 = off), got ",
        adaptive_samples);
  if (shadow_rays < 1 || shadow_rays > 2)
    throw_error<InvalidArgument>(w, ".shadow_rays must be 1 or 2, got ", shadow_rays);
  if (reduced_nee_depth < 0)
    throw_error<InvalidArgument>(w, ".reduced_nee_depth must be >= 0, got ", reduced_nee_depth);
  if (adaptive_max < 1 || adaptive_max > 64)
    throw_error<InvalidArgument>(
        w, ".adaptive_max must be in [1, 64] (extra samples of one pixel), got ", adaptive_max);
}

PathTraceOutput PathScene::render(const CameraView& view, const PathTraceOptions& options) const {
  options.validate();
  view.validate("PathScene::render: view");
  const Geometry& G = *geometry_;
  const Lighting& L = *lighting_;
  const int W = view.K.width, H = view.K.height;
  PathTraceOutput out;
  out.width = W;
  out.height = H;
  const std::size_t np = static_cast<std::size_t>(W) * H;
  out.radiance.assign(3 * np, 0.0f);
  out.albedo.assign(3 * np, 0.0f);
  out.normal.assign(3 * np, 0.0f);
  out.depth.assign(np, 0.0f);
  out.instance_ids.assign(np, 0);

  pt::Camera cam;
  cam.fx = static_cast<float>(view.K.fx);
  cam.fy = static_cast<float>(view.K.fy);
  cam.cx = static_cast<float>(view.K.cx);
  cam.cy = static_cast<float>(view.K.cy);
  const Mat3d R = view.X_WC.linear();
  cam.o = f3(Vec3d(view.X_WC.translation()));
  cam.r0 = f3(Vec3d(R.col(0)));
  cam.r1 = f3(Vec3d(R.col(1)));
  cam.r2 = f3(Vec3d(R.col(2)));

  float focus = static_cast<float>(options.focus_distance);
  const float aperture = static_cast<float>(options.aperture_radius);
  std::int64_t total_rays = 0;
  if (aperture > 0.0f && focus == 0.0f) {
    detail::FtzDazGuard guard;
    pt::Integrator it(G, L, options);
    RTCRayHit rh;
    // Depth at the image centre through the principal point.
    const F3 dc = F3((0.5f * W - cam.cx) / cam.fx, (0.5f * H - cam.cy) / cam.fy, 1.0f);
    const float len = length(dc);
    focus = it.intersect_primary(cam.o, cam.to_world(dc / len),
                                 std::numeric_limits<float>::infinity(), rh)
                ? rh.ray.tfar / len
                : 1.0f;
    total_rays += it.counters.rays;
  }
  const std::uint64_t stream =
      mix64(options.seed ^ mix64(options.view_index + 0x5851F42D4C957F2DULL));
  const pt::FilmJob job{G, L, options, cam, aperture, focus, stream};
  total_rays += pt::trace_pixels(job, out);

  // Adaptive sampling: extra samples where the first pass looks noisy. The decision depends on
  // the first pass only (deterministic); sample j of pixel (u, v) is index base | j of a second
  // stream, so the image is the same for any number of threads.
  if (options.adaptive_samples > 0.0) {
    const std::vector<std::uint8_t> extra =
        pt::allocate_extra_samples(pt::noise_estimate(out.radiance, out.albedo, W, H),
                                   options.adaptive_samples, options.adaptive_max);
    total_rays += pt::trace_extra_samples(job, extra, out);
  }
  out.rays = total_rays;
  return out;
}

}  // namespace mgn
