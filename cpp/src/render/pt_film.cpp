#include <mgn/core/error.hpp>
#include <mgn/core/parallel.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/render/path_tracer.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "render/detail/pt_film.hpp"
#include "render/detail/pt_integrator.hpp"
#include "render/detail/pt_math.hpp"
#include "render/detail/pt_scene.hpp"

namespace mgn {

namespace pt {

namespace {

constexpr int kTile = 16;  // tile side (px); a tile row's samples are one packet of 16 rays

/// Lane `l` of a 16-ray packet: the ray o + t d for t in [0, inf), no hit yet; `on` false
/// leaves the lane inactive (valid[l] = 0) for a tile narrower than the packet.
inline void set_packet_lane(RTCRayHit16& rh, int* valid, int l, bool on, const F3& o, const F3& d) {
  valid[l] = on ? -1 : 0;
  rh.ray.org_x[l] = o.x;
  rh.ray.org_y[l] = o.y;
  rh.ray.org_z[l] = o.z;
  rh.ray.dir_x[l] = d.x;
  rh.ray.dir_y[l] = d.y;
  rh.ray.dir_z[l] = d.z;
  rh.ray.tnear[l] = 0.0f;
  rh.ray.tfar[l] = std::numeric_limits<float>::infinity();
  rh.ray.time[l] = 0.0f;
  rh.ray.mask[l] = 0xFFFFFFFFu;
  rh.ray.id[l] = static_cast<unsigned>(l);
  rh.ray.flags[l] = 0;
  rh.hit.geomID[l] = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0][l] = RTC_INVALID_GEOMETRY_ID;
}

/// The camera ray of one sample of pixel (u, v): jittered in the pixel (sampler dimension 0)
/// and, with an aperture, leaving a point of the lens (dimension 1) towards the focus plane.
void camera_ray(const FilmJob& job, const pt::PixelSampler& s, int u, int v, F3& o, F3& d) {
  const Camera& cam = job.cam;
  const float aperture = job.aperture, focus = job.focus;
  const pt::Sample2 j = s.get(0);
  F3 dc(((u + j.x) - cam.cx) / cam.fx, ((v + j.y) - cam.cy) / cam.fy, 1.0f);
  o = cam.o;
  if (aperture > 0.0f) {
    const pt::Sample2 ls = s.get(1);
    const pt::Sample2 dd = pt::concentric_disc(ls.x, ls.y);
    const F3 lens(dd.x * aperture, dd.y * aperture, 0.0f);
    dc = dc * focus - lens;
    o = cam.o + cam.to_world(lens);
  }
  d = normalize(cam.to_world(dc));
}

/// The path of lane l of a traced camera packet, continued from the packet's first hit; its
/// radiance (non-finite -> 0, clamped to `clamp` luminance if set) and guides a, n.
F3 trace_lane(const FilmJob& job, Integrator& it, const RTCRayHit16& rh16, int l, F3 o, F3 d,
              const pt::PixelSampler& s, F3& a, F3& n) {
  const float clamp = static_cast<float>(job.options.clamp);
  RTCRayHit first;
  first.ray.tfar = rh16.ray.tfar[l];
  first.hit.geomID = rh16.hit.geomID[l];
  first.hit.primID = rh16.hit.primID[l];
  first.hit.u = rh16.hit.u[l];
  first.hit.v = rh16.hit.v[l];
  F3 c = it.trace(o, d, s, a, n, &first);
  if (!all_finite(c)) c = F3(0.0f);
  if (clamp > 0.0f) {
    const float lum = luminance(c);
    if (lum > clamp) c *= clamp / lum;
  }
  return c;
}

/// The Embree context of the camera-ray packets (coherent rays from one tile row).
RTCIntersectContext coherent_context() {
  RTCIntersectContext c;
  rtcInitIntersectContext(&c);
  c.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  return c;
}

}  // namespace

std::int64_t trace_pixels(const FilmJob& job, PathTraceOutput& out) {
  const PathScene::Geometry& G = job.geometry;
  const PathScene::Lighting& L = job.lighting;
  const PathTraceOptions& options = job.options;
  const Camera& cam = job.cam;
  const int W = out.width, H = out.height;
  const int tiles_x = (W + kTile - 1) / kTile, tiles_y = (H + kTile - 1) / kTile;
  const std::size_t n_tiles = static_cast<std::size_t>(tiles_x) * tiles_y;
  std::atomic<std::int64_t> total_rays{0};
  const std::uint64_t stream = job.stream;
  const float inv_spp = 1.0f / static_cast<float>(options.spp);
  const int spp_log2 = pt::ceil_log2(static_cast<std::uint32_t>(options.spp));

  // Threads take tiles one at a time (parallel_workers_dynamic); a tile's pixels depend only on
  // their indices.
  auto worker = [&](BlockQueue& tiles) {
    detail::FtzDazGuard guard;
    Integrator it(G, L, options);
    RTCIntersectContext coherent = coherent_context();
    const RTCScene scene = G.rays->impl().scene;  // camera rays: the robust BVH, as the labels
    alignas(64) RTCRayHit16 rh16;
    alignas(64) int valid16[16];
    pt::PairSeeds pair_seeds;  // the sampler's per-pair seeds of the current pixel block
    for (std::size_t tile, tile_end; tiles.next(tile, tile_end);) {
      const int tx = static_cast<int>(tile % tiles_x), ty = static_cast<int>(tile / tiles_x);
      const int u1 = std::min(W, (tx + 1) * kTile), v1 = std::min(H, (ty + 1) * kTile);
      for (int v = ty * kTile; v < v1; ++v) {
        // Labels: the pinhole rays through the pixel centres of this tile row, as one coherent
        // packet (at most kTile = 16 rays).
        if (options.labels) {
          const int u0 = tx * kTile, m = u1 - u0;
          float len[kTile];
          for (int k = 0; k < kTile; ++k) {
            const int u = u0 + std::min(k, m - 1);
            const F3 dc((u + 0.5f - cam.cx) / cam.fx, (v + 0.5f - cam.cy) / cam.fy, 1.0f);
            len[k] = length(dc);
            const F3 d = cam.to_world(dc / len[k]);
            set_packet_lane(rh16, valid16, k, k < m, cam.o, d);
          }
          rtcIntersect16(valid16, scene, &coherent, &rh16);
          it.counters.rays += m;
          for (int k = 0; k < m; ++k) {
            if (rh16.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) continue;
            const std::size_t pix = static_cast<std::size_t>(v) * W + u0 + k;
            out.depth[pix] = rh16.ray.tfar[k] / len[k];
            out.instance_ids[pix] = G.geoms[rh16.hit.geomID[k]].instance_id;
          }
        }
        // Camera rays: sample k of the (at most kTile = 16) pixels of this tile row as one
        // coherent packet; each path then continues on its own. Per pixel the samples are
        // summed in the order k = 0, 1, ... as before.
        const int u0 = tx * kTile, m = u1 - u0;
        pt::PixelStream pixel_stream[kTile];
        F3 sum[kTile], alb[kTile], nrm[kTile];
        F3 org[kTile], dir[kTile];
        for (int l = 0; l < m; ++l) {
          pixel_stream[l] = pt::pixel_stream(stream, static_cast<std::uint32_t>(u0 + l),
                                             static_cast<std::uint32_t>(v), spp_log2);
          sum[l] = alb[l] = nrm[l] = F3(0.0f);
        }
        for (int k = 0; k < options.spp; ++k) {
          for (int l = 0; l < kTile; ++l) {
            const int ll = std::min(l, m - 1);
            const pt::PixelSampler s(pixel_stream[ll].seed,
                                     pixel_stream[ll].base | static_cast<std::uint32_t>(k),
                                     &pair_seeds);
            camera_ray(job, s, u0 + ll, v, org[l], dir[l]);
            set_packet_lane(rh16, valid16, l, l < m, org[l], dir[l]);
          }
          rtcIntersect16(valid16, scene, &coherent, &rh16);
          it.counters.rays += m;
          for (int l = 0; l < m; ++l) {
            const pt::PixelSampler s(pixel_stream[l].seed,
                                     pixel_stream[l].base | static_cast<std::uint32_t>(k),
                                     &pair_seeds);
            F3 a, n;
            sum[l] += trace_lane(job, it, rh16, l, org[l], dir[l], s, a, n);
            alb[l] += a;
            nrm[l] += n;
          }
        }
        for (int l = 0; l < m; ++l) {
          const std::size_t pix = static_cast<std::size_t>(v) * W + u0 + l;
          float* r = &out.radiance[3 * pix];
          r[0] = sum[l].x * inv_spp;
          r[1] = sum[l].y * inv_spp;
          r[2] = sum[l].z * inv_spp;
          float* a = &out.albedo[3 * pix];
          a[0] = alb[l].x * inv_spp;
          a[1] = alb[l].y * inv_spp;
          a[2] = alb[l].z * inv_spp;
          const F3 nn = normalize(nrm[l]);
          float* n = &out.normal[3 * pix];
          n[0] = nn.x;
          n[1] = nn.y;
          n[2] = nn.z;
        }
      }
    }
    total_rays += it.counters.rays;
  };
  parallel_workers_dynamic(n_tiles, options.num_threads, 1, worker);
  return total_rays.load();
}

std::int64_t trace_extra_samples(const FilmJob& job, const std::vector<std::uint8_t>& extra,
                                 PathTraceOutput& out) {
  const PathScene::Geometry& G = job.geometry;
  const PathScene::Lighting& L = job.lighting;
  const PathTraceOptions& options = job.options;
  const int W = out.width, H = out.height;
  const int tiles_x = (W + kTile - 1) / kTile, tiles_y = (H + kTile - 1) / kTile;
  const std::size_t n_tiles = static_cast<std::size_t>(tiles_x) * tiles_y;
  std::atomic<std::int64_t> total_rays{0};
  const std::uint64_t stream = job.stream;
  const std::uint64_t stream2 = mix64(stream ^ 0xA0761D6478BD642FULL);
  const int extra_log2 = pt::ceil_log2(static_cast<std::uint32_t>(options.adaptive_max));
  auto extra_worker = [&](BlockQueue& tiles) {
    detail::FtzDazGuard guard;
    Integrator it(G, L, options);
    RTCIntersectContext coherent = coherent_context();
    const RTCScene scene = G.rays->impl().scene;
    alignas(64) RTCRayHit16 rh16;
    alignas(64) int valid16[16];
    pt::PairSeeds pair_seeds;
    struct Job {
      std::size_t pix;
      int u, v, j;
      pt::PixelStream ps;
    };
    std::vector<Job> jobs;
    std::vector<F3> sum, alb, nrm;  // per pixel of the tile
    for (std::size_t tile, tile_end; tiles.next(tile, tile_end);) {
      const int tx = static_cast<int>(tile % tiles_x), ty = static_cast<int>(tile / tiles_x);
      const int u0 = tx * kTile, v0 = ty * kTile;
      const int u1 = std::min(W, u0 + kTile), v1 = std::min(H, v0 + kTile);
      // The tile's extra samples (pixel by pixel, j = 0, 1, ...), traced 16 at a time with
      // their camera rays as one packet; each pixel sums its samples in the order j.
      jobs.clear();
      for (int v = v0; v < v1; ++v) {
        for (int u = u0; u < u1; ++u) {
          const std::size_t pix = static_cast<std::size_t>(v) * W + u;
          if (extra[pix] == 0) continue;
          const pt::PixelStream ps = pt::pixel_stream(stream2, static_cast<std::uint32_t>(u),
                                                      static_cast<std::uint32_t>(v), extra_log2);
          for (int j = 0; j < extra[pix]; ++j) jobs.push_back({pix, u, v, j, ps});
        }
      }
      if (jobs.empty()) continue;
      sum.assign(static_cast<std::size_t>(kTile) * kTile, F3(0.0f));
      alb = nrm = sum;
      for (std::size_t b0 = 0; b0 < jobs.size(); b0 += 16) {
        const int m = static_cast<int>(std::min<std::size_t>(16, jobs.size() - b0));
        F3 org[16], dir[16];
        for (int l = 0; l < 16; ++l) {
          const Job& jb = jobs[b0 + std::min(l, m - 1)];
          const pt::PixelSampler s(jb.ps.seed, jb.ps.base | static_cast<std::uint32_t>(jb.j),
                                   &pair_seeds);
          camera_ray(job, s, jb.u, jb.v, org[l], dir[l]);
          set_packet_lane(rh16, valid16, l, l < m, org[l], dir[l]);
        }
        rtcIntersect16(valid16, scene, &coherent, &rh16);
        it.counters.rays += m;
        for (int l = 0; l < m; ++l) {
          const Job& jb = jobs[b0 + l];
          const pt::PixelSampler s(jb.ps.seed, jb.ps.base | static_cast<std::uint32_t>(jb.j),
                                   &pair_seeds);
          F3 a, n;
          const F3 c = trace_lane(job, it, rh16, l, org[l], dir[l], s, a, n);
          const std::size_t t = static_cast<std::size_t>(jb.v - v0) * kTile + (jb.u - u0);
          sum[t] += c;
          alb[t] += a;
          nrm[t] += n;
        }
      }
      const float n1 = static_cast<float>(options.spp);
      for (int v = v0; v < v1; ++v) {
        for (int u = u0; u < u1; ++u) {
          const std::size_t pix = static_cast<std::size_t>(v) * W + u;
          if (extra[pix] == 0) continue;
          const std::size_t t = static_cast<std::size_t>(v - v0) * kTile + (u - u0);
          const float inv_n = 1.0f / (n1 + static_cast<float>(extra[pix]));
          float* r = &out.radiance[3 * pix];
          float* a = &out.albedo[3 * pix];
          float* n = &out.normal[3 * pix];
          r[0] = (r[0] * n1 + sum[t].x) * inv_n;
          r[1] = (r[1] * n1 + sum[t].y) * inv_n;
          r[2] = (r[2] * n1 + sum[t].z) * inv_n;
          a[0] = (a[0] * n1 + alb[t].x) * inv_n;
          a[1] = (a[1] * n1 + alb[t].y) * inv_n;
          a[2] = (a[2] * n1 + alb[t].z) * inv_n;
          const F3 nn = normalize(F3(n[0], n[1], n[2]) * n1 + nrm[t]);
          n[0] = nn.x;
          n[1] = nn.y;
          n[2] = nn.z;
        }
      }
    }
    total_rays += it.counters.rays;
  };
  parallel_workers_dynamic(n_tiles, options.num_threads, 1, extra_worker);
  return total_rays.load();
}

}  // namespace pt

namespace {

float linear_to_srgb(float c) {
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Development.

void FilmOptions::validate() const {
  const char* w = "FilmOptions";
  if (!std::isfinite(exposure))
    throw_error<InvalidArgument>(w, ".exposure must be finite (EV), got ", exposure);
  if (!(shot_noise >= 0.0) || !std::isfinite(shot_noise))
    throw_error<InvalidArgument>(w, ".shot_noise must be finite and >= 0, got ", shot_noise);
  if (!(read_noise >= 0.0) || !std::isfinite(read_noise))
    throw_error<InvalidArgument>(w, ".read_noise must be finite and >= 0, got ", read_noise);
  if (num_threads < 0)
    throw_error<InvalidArgument>(w, ".num_threads must be >= 0 (0 = all), got ", num_threads);
}

std::vector<std::uint8_t> develop(const std::vector<float>& radiance, int width, int height,
                                  const FilmOptions& film) {
  film.validate();
  if (width <= 0 || height <= 0 ||
      radiance.size() != static_cast<std::size_t>(width) * height * 3) {
    throw_error<InvalidArgument>(
        "develop: radiance has ", radiance.size(),
        " values; expected an (H, W, 3) image with H, W > 0, got H=", height, " W=", width);
  }
  const std::size_t np = static_cast<std::size_t>(width) * height;
  std::vector<std::uint8_t> out(3 * np);
  const float gain = static_cast<float>(std::exp2(film.exposure));
  const bool noisy = film.shot_noise > 0.0 || film.read_noise > 0.0;
  const std::uint64_t stream = mix64(film.seed ^ mix64(film.view_index + 0x2545F4914F6CDD1DULL));
  const float shot = static_cast<float>(film.shot_noise),
              read = static_cast<float>(film.read_noise);
  const bool filmic = film.tone == FilmOptions::Tone::Filmic;
  parallel_for(np, film.num_threads, 16384, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      float x[3];
      for (int c = 0; c < 3; ++c) {
        const float r = radiance[3 * i + c];
        x[c] = std::isfinite(r) ? std::max(0.0f, r) * gain : 0.0f;
      }
      if (noisy) {
        Rng rng(stream, i);
        float n[6];  // N1, N2 per channel (Rng::normals: no libm, same values everywhere)
        rng.normals(n, 6);
        for (int c = 0; c < 3; ++c) {
          x[c] = std::max(0.0f, x[c] + shot * std::sqrt(x[c]) * n[2 * c] + read * n[2 * c + 1]);
        }
      }
      for (int c = 0; c < 3; ++c) {
        const float y = filmic ? 1.0f - std::exp(-x[c]) : std::min(1.0f, x[c]);
        const float s = linear_to_srgb(std::min(1.0f, std::max(0.0f, y)));
        out[3 * i + c] = static_cast<std::uint8_t>(std::lround(s * 255.0f));
      }
    }
  });
  return out;
}

}  // namespace mgn
