#pragma once
// Private: the path tracer's film (pt_film.cpp): the camera rays of the pixels' samples, the
// 16x16 pixel tiles the threads take one at a time, the label rays (depth, instance ids), and
// the accumulation of the samples (radiance and the denoiser's albedo and normal guides) into a
// PathTraceOutput, for the first pass and for the adaptive pass's extra samples.
#include <mgn/render/path_tracer.hpp>

#include <cstdint>
#include <vector>

#include "render/detail/pt_math.hpp"
#include "render/detail/pt_scene.hpp"

namespace mgn::pt {

/// A pinhole camera: intrinsics (px) and the camera's origin and axes in the world.
struct Camera {
  float fx, fy, cx, cy;
  F3 o;
  F3 r0, r1, r2;  // columns of R_WC
  F3 to_world(F3 v) const { return r0 * v.x + r1 * v.y + r2 * v.z; }
};

/// What the passes of one render share.
struct FilmJob {
  const PathScene::Geometry& geometry;
  const PathScene::Lighting& lighting;
  const PathTraceOptions& options;
  Camera cam;
  float aperture = 0.0f;     // lens radius (m); 0: pinhole
  float focus = 0.0f;        // distance of the plane in focus along the optical axis (m)
  std::uint64_t stream = 0;  // the view's sampler stream (from options.seed and view_index)
};

/// The first pass: options.spp samples of each pixel of the (out.height, out.width) image,
/// tile by tile on options.num_threads threads. Writes the means of out.radiance, out.albedo
/// and the normalised mean of out.normal, and, when options.labels, out.depth and
/// out.instance_ids (pinhole rays through the pixel centres). Returns the number of rays traced.
std::int64_t trace_pixels(const FilmJob& job, PathTraceOutput& out);

/// The adaptive pass: extra[v * width + u] more samples of pixel (u, v) (from a second sampler
/// stream), merged into the first pass's means of out.radiance, out.albedo and out.normal.
/// Returns the number of rays traced.
std::int64_t trace_extra_samples(const FilmJob& job, const std::vector<std::uint8_t>& extra,
                                 PathTraceOutput& out);

}  // namespace mgn::pt
