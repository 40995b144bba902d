#include <mgn/core/error.hpp>
#include <mgn/core/parallel.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/render/depth_sensor.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace mgn {

namespace {

float luminance(const Vec3f& c) { return 0.2126f * c.x() + 0.7152f * c.y() + 0.0722f * c.z(); }

// std::round (halves away from zero) without the libm call and without a branch (the rounding
// direction of a noisy depth is random, a branch mispredicts): exact for |x| < 2^52, where the
// truncation and x - t are exact; larger values are integers already.
double round_half_away(double x) {
  if (!(std::abs(x) < 0x1p52)) return std::round(x);
  const double t = static_cast<double>(static_cast<std::int64_t>(x));
  const double f = x - t;
  return t + static_cast<double>(f >= 0.5) - static_cast<double>(f <= -0.5);
}

// Marks the pixels of one image row that the projector does not light (rectified: the projector
// is offset along x, so a surface point and its occluder lie on the same row). A point at column
// u maps to the projector column u_p = u + 0.5 - fx b / z; an occluder of it has the same u_p and
// lies towards the projector (u' > u for b > 0). Sweeps from the projector side keeping the
// extreme u_p seen so far. z: the row's W depths (m, 0 = nothing seen); fx: focal length (px);
// baseline: b (m, != 0); tol: shadow tolerance (px); shadow: W flags, set to 1 where shadowed.
void mark_projector_shadow(const float* z, int W, double fx, double baseline, double tol,
                           std::uint8_t* shadow) {
  const double fb = fx * baseline;
  if (baseline > 0.0) {
    double min_up = std::numeric_limits<double>::infinity();
    for (int u = W - 1; u >= 0; --u) {
      if (z[u] <= 0.0f) continue;
      const double up = u + 0.5 - fb / z[u];
      if (up > min_up + tol) shadow[u] = 1;
      min_up = std::min(min_up, up);
    }
  } else {
    double max_up = -std::numeric_limits<double>::infinity();
    for (int u = 0; u < W; ++u) {
      if (z[u] <= 0.0f) continue;
      const double up = u + 0.5 - fb / z[u];
      if (up < max_up - tol) shadow[u] = 1;
      max_up = std::max(max_up, up);
    }
  }
}

// The depth (m) of the seen 4-neighbour of pixel (u, v) with the largest depth jump from zz, and
// that jump (m); {0, 0} where no seen neighbour differs. depth: the W x H image, row-major.
std::pair<double, double> largest_depth_jump(const std::vector<float>& depth, int W, int H, int u,
                                             std::size_t v, double zz) {
  double other = 0.0, jump = 0.0;
  const int du[4] = {-1, 1, 0, 0}, dv[4] = {0, 0, -1, 1};
  for (int k = 0; k < 4; ++k) {
    const long uu = u + du[k], vv = static_cast<long>(v) + dv[k];
    if (uu < 0 || uu >= W || vv < 0 || vv >= H) continue;
    const double zn = depth[static_cast<std::size_t>(vv) * W + uu];
    if (zn > 0.0 && std::abs(zn - zz) > jump) jump = std::abs(zn - zz), other = zn;
  }
  return {other, jump};
}

// The depth (m) reported at pixel (u, v) of true depth zz at a depth edge: where the seen
// 4-neighbour with the largest depth jump from zz jumps by more than p.edge_threshold, with
// probability p.flying_pixel_probability a uniform fraction of the way to that neighbour's depth
// (one draw from rng at an edge, a second where the pixel moves); zz otherwise.
double flying_pixel_depth(const std::vector<float>& depth, int W, int H, int u, std::size_t v,
                          double zz, const DepthSensorParams& p, Rng& rng) {
  const auto [other, jump] = largest_depth_jump(depth, W, H, u, v, zz);
  if (jump > p.edge_threshold && rng.uniform() < p.flying_pixel_probability) {
    return zz + rng.uniform() * (other - zz);
  }
  return zz;
}

// Adds sigma[k] times normals[k] to each of the first count depths z (m), then puts each on its
// grid (for p.depth_step > 0): the coarsest power-of-two multiple of p.depth_step not above
// p.depth_step_noise_fraction times sigma[k], rounding halves away from zero.
void add_noise_on_grid(std::size_t count, const std::vector<double>& sigma,
                       const std::vector<float>& normals, const DepthSensorParams& p,
                       std::vector<double>& z) {
  for (std::size_t k = 0; k < count; ++k) z[k] += sigma[k] * static_cast<double>(normals[k]);
  if (p.depth_step > 0.0) {
    for (std::size_t k = 0; k < count; ++k) {
      double step = p.depth_step;
      const double top = p.depth_step_noise_fraction * sigma[k];
      while (step * 2.0 <= top) step *= 2.0;
      z[k] = round_half_away(z[k] / step) * step;
    }
  }
}

// Checks the sizes of the depth and id images (K.width x K.height) and that every depth is
// finite and >= 0.
void check_depth_inputs(const std::vector<float>& depth,
                        const std::vector<std::int32_t>& instance_ids, const Intrinsics& K) {
  const int W = K.width, H = K.height;
  const std::size_t n = static_cast<std::size_t>(W) * H;
  if (depth.size() != n) {
    throw_error<InvalidArgument>("apply_depth_sensor: depth has ", depth.size(),
                                 " pixels; expected ", W, "x", H, " = ", n);
  }
  if (instance_ids.size() != n) {
    throw_error<InvalidArgument>("apply_depth_sensor: instance_ids has ", instance_ids.size(),
                                 " pixels; expected ", n);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!(std::isfinite(depth[i]) && depth[i] >= 0.0f)) {
      throw_error<InvalidArgument>(
          "apply_depth_sensor: depth must be finite and >= 0 m (0 = "
          "nothing seen), got ",
          depth[i], " at pixel ", i);
    }
  }
}

}  // namespace

std::uint8_t surface_flags(const Material& m) {
  std::uint8_t f = 0;
  if (m.opacity * m.base_color[3] < 0.5f) f |= kSurfaceTransparent;
  if (m.has_pbr && m.transmission >= 0.5f) f |= kSurfaceTransparent;
  const bool textured = !m.texture_path.empty() || !m.texture_data.empty();
  if (!textured && luminance(m.base_color.head<3>()) < 0.03f) f |= kSurfaceDark;
  if (luminance(m.specular) >= 0.8f && m.shininess >= 200.0f) f |= kSurfaceMirror;
  // A polished metal reflects the projector away from the camera like a mirror.
  if (m.has_pbr && m.metallic >= 0.5f && m.roughness <= 0.25f) f |= kSurfaceMirror;
  return f;
}

std::uint8_t surface_flags(const Mesh& mesh) {
  std::uint8_t f = 0;
  for (const Material& m : mesh.materials()) f |= surface_flags(m);
  return f;
}

DepthSensorParams DepthSensorParams::preset_defaults(DepthSensorPreset preset) {
  DepthSensorParams p;
  p.preset = preset;
  switch (preset) {
    case DepthSensorPreset::Ideal:
      break;
    case DepthSensorPreset::StructuredLight:
      p.min_range = 0.3;
      p.max_range = 2.0;
      p.sigma_a = 0.1e-3;
      p.sigma_b = 0.2e-3;
      p.sigma_z0 = 0.0;
      p.baseline = 0.1;
      p.invalid_transparent = p.invalid_dark = p.invalid_mirror = true;
      p.depth_step = 0.01 / 256.0;
      p.depth_step_noise_fraction = 0.5;
      break;
    case DepthSensorPreset::ToF:
      p.min_range = 0.5;
      p.max_range = 4.5;
      p.sigma_a = 1.2e-3;
      p.sigma_b = 1.9e-3;
      p.sigma_z0 = 0.4;
      p.edge_threshold = 0.02;
      p.flying_pixel_probability = 0.5;
      p.invalid_transparent = p.invalid_dark = p.invalid_mirror = true;
      p.depth_step = 0.01 / 64.0;
      p.depth_step_noise_fraction = 0.5;
      break;
  }
  return p;
}

void DepthSensorParams::validate() const {
  const double nonneg[] = {
      min_range,           max_range,      sigma_a,    sigma_b,
      shadow_tolerance_px, edge_threshold, depth_step, depth_step_noise_fraction};
  const char* names[] = {
      "min_range",           "max_range",      "sigma_a",    "sigma_b",
      "shadow_tolerance_px", "edge_threshold", "depth_step", "depth_step_noise_fraction"};
  for (int i = 0; i < 8; ++i) {
    if (!(std::isfinite(nonneg[i]) && nonneg[i] >= 0.0)) {
      throw_error<InvalidArgument>("DepthSensorParams: ", names[i],
                                   " must be finite and >= 0, got ", nonneg[i]);
    }
  }
  if (!std::isfinite(sigma_z0) || !std::isfinite(baseline)) {
    throw_error<InvalidArgument>("DepthSensorParams: sigma_z0 and baseline must be finite");
  }
  if (min_range > max_range) {
    throw_error<InvalidArgument>("DepthSensorParams: min_range (", min_range,
                                 ") must be <= max_range (", max_range, ")");
  }
  if (!(flying_pixel_probability >= 0.0 && flying_pixel_probability <= 1.0)) {
    throw_error<InvalidArgument>(
        "DepthSensorParams: flying_pixel_probability must be in [0, 1], "
        "got ",
        flying_pixel_probability);
  }
}

DepthImage apply_depth_sensor(const std::vector<float>& depth,
                              const std::vector<std::int32_t>& instance_ids,
                              const std::vector<std::uint8_t>& flags_by_id, const Intrinsics& K,
                              const DepthSensorParams& p, std::uint64_t seed, int num_threads) {
  K.validate("apply_depth_sensor: K");
  p.validate();
  const int W = K.width, H = K.height;
  check_depth_inputs(depth, instance_ids, K);
  const std::size_t n = static_cast<std::size_t>(W) * H;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  DepthImage out;
  out.width = W;
  out.height = H;
  out.depth_ideal = depth;
  out.depth.assign(n, nan);
  out.valid.assign(n, 0);
  const bool ideal = p.preset == DepthSensorPreset::Ideal;
  const bool noisy = p.sigma_a > 0.0 || p.sigma_b > 0.0;
  auto flags_of = [&](std::int32_t id) -> std::uint8_t {
    return id >= 0 && static_cast<std::size_t>(id) < flags_by_id.size() ? flags_by_id[id] : 0;
  };

  parallel_for(static_cast<std::size_t>(H), num_threads, 8, [&](std::size_t v0, std::size_t v1) {
    std::vector<std::uint8_t> shadow(static_cast<std::size_t>(W));
    // The row's pixels that get noise: column, noise-free depth (m), sigma (m); their normals.
    std::vector<int> noisy_u(static_cast<std::size_t>(W));
    std::vector<double> noisy_z(static_cast<std::size_t>(W)),
        noisy_sigma(static_cast<std::size_t>(W));
    std::vector<float> normals(static_cast<std::size_t>(W));
    for (std::size_t v = v0; v < v1; ++v) {
      const float* z = &depth[v * W];
      const std::int32_t* ids = &instance_ids[v * W];
      float* out_z = &out.depth[v * W];
      std::uint8_t* out_valid = &out.valid[v * W];
      // Projector visibility along the row (mark_projector_shadow).
      std::fill(shadow.begin(), shadow.end(), 0);
      if (!ideal && p.baseline != 0.0) {
        mark_projector_shadow(z, W, K.fx, p.baseline, p.shadow_tolerance_px, shadow.data());
      }
      // Row v draws from Rng(seed, v): first the flying-pixel uniforms (left to right, pass 1),
      // then one normal per noisy pixel in a batch (pass 2), applied with the grid (pass 3).
      Rng rng(seed, v);
      std::size_t count = 0;
      for (int u = 0; u < W; ++u) {
        double zz = z[u];
        if (zz <= 0.0 || zz < p.min_range || zz > p.max_range) continue;
        if (ideal) {
          out_z[u] = z[u];
          out_valid[u] = 1;
          continue;
        }
        const std::uint8_t f = flags_of(ids[u]);
        if ((p.invalid_transparent && (f & kSurfaceTransparent)) ||
            (p.invalid_dark && (f & kSurfaceDark)) || (p.invalid_mirror && (f & kSurfaceMirror)))
          continue;
        if (shadow[u]) continue;
        if (p.flying_pixel_probability > 0.0 && p.edge_threshold > 0.0) {
          zz = flying_pixel_depth(depth, W, H, u, v, zz, p, rng);
        }
        const double sigma = p.sigma_a + p.sigma_b * (zz - p.sigma_z0) * (zz - p.sigma_z0);
        noisy_u[count] = u;
        noisy_z[count] = zz;
        noisy_sigma[count] = sigma;
        ++count;
      }
      // Pass 2: the normals (sigma >= 0; a pixel with sigma = 0 adds 0 times its normal).
      if (noisy) {
        rng.normals(normals.data(), count);
      } else {
        std::fill(normals.begin(), normals.begin() + count, 0.0f);
      }
      // Pass 3: noise, then the grid (add_noise_on_grid); a value that ends <= 0 is invalid.
      add_noise_on_grid(count, noisy_sigma, normals, p, noisy_z);
      for (std::size_t k = 0; k < count; ++k) {
        if (!(noisy_z[k] > 0.0)) continue;
        out_z[noisy_u[k]] = static_cast<float>(noisy_z[k]);
        out_valid[noisy_u[k]] = 1;
      }
    }
  });
  return out;
}

}  // namespace mgn
