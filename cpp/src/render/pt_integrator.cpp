#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <new>

#include "render/detail/pt_integrator.hpp"
#include "render/detail/pt_math.hpp"
#include "render/detail/pt_scene.hpp"

namespace mgn::pt {

namespace {

float srgb_to_linear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

struct SrgbLut {
  float v[256];
  SrgbLut() {
    for (int i = 0; i < 256; ++i) v[i] = srgb_to_linear(static_cast<float>(i) / 255.0f);
  }
};
const SrgbLut& srgb_lut() {
  static const SrgbLut lut;
  return lut;
}

F3 texture_lookup(const MaterialData& m, float u, float v) {
  const float x = u * static_cast<float>(m.tw) - 0.5f;
  const float y = (1.0f - v) * static_cast<float>(m.th) - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float ax = x - fx, ay = y - fy;
  auto wrap = [](long i, int n) {
    if (i >= 0 && i < n) return static_cast<int>(i);  // the usual case: no division
    long r = i % n;
    return static_cast<int>(r < 0 ? r + n : r);
  };
  const long ix = static_cast<long>(fx), iy = static_cast<long>(fy);
  const int x0 = wrap(ix, m.tw), x1 = wrap(ix + 1, m.tw);
  const int y0 = wrap(iy, m.th), y1 = wrap(iy + 1, m.th);
  const float* lut = srgb_lut().v;
  auto texel = [&](int xx, int yy) {
    const std::uint8_t* t = m.tex + 3 * (static_cast<std::size_t>(yy) * m.tw + xx);
    return F3(lut[t[0]], lut[t[1]], lut[t[2]]);
  };
  return pt::lerp(pt::lerp(texel(x0, y0), texel(x1, y0), ax),
                  pt::lerp(texel(x0, y1), texel(x1, y1), ax), ay);
}

/// The denoiser's albedo guide where a path sees an emitter: its radiance clamped to [0, 1]
/// (per channel for the environment, grey for a lamp).
F3 emitter_guide(F3 Le) {
  return F3(std::min(1.0f, Le.x), std::min(1.0f, Le.y), std::min(1.0f, Le.z));
}
F3 lamp_guide(F3 Le) { return F3(std::min(1.0f, max_comp(Le))); }

/// Smooth, mostly transmissive glass: the denoiser's guides are taken behind it (trace()).
bool see_through(const MaterialData& m) {
  return m.transmission * (1.0f - m.metallic) >= 0.5f &&
         m.alpha <= pt::ShadingMaterial::kRoughAlpha;
}

void make_hit(const Geometry& G, const RTCRayHit& rh, F3 dir, Hit& h) {
  const GeometryData& g = G.geoms[rh.hit.geomID];
  const unsigned f = rh.hit.primID;
  const float b1 = rh.hit.u, b2 = rh.hit.v, b0 = 1.0f - b1 - b2;
  const TriShade& t = g.tri[f];
  h.p = t.p[0] * b0 + t.p[1] * b1 + t.p[2] * b2;
  F3 ng = t.ng;
  F3 ns = normalize(t.cn[0] * b0 + t.cn[1] * b1 + t.cn[2] * b2);
  h.front = dot(dir, ng) < 0.0f;
  if (!h.front) {
    ng = -ng;
    ns = -ns;
  }
  if (dot(ns, ng) <= 0.0f || dot(ns, -dir) <= 1e-4f) ns = ng;  // fall back at flips
  h.ng = ng;
  h.ns = ns;
  h.mat = &G.mats[t.material];
  h.base = h.mat->base;
  if (h.mat->tex != nullptr && g.uvs.rows() > 0) {
    const std::int32_t i0 = g.faces(f, 0), i1 = g.faces(f, 1), i2 = g.faces(f, 2);
    const float u = g.uvs(i0, 0) * b0 + g.uvs(i1, 0) * b1 + g.uvs(i2, 0) * b2;
    const float v = g.uvs(i0, 1) * b0 + g.uvs(i1, 1) * b1 + g.uvs(i2, 1) * b2;
    h.base = h.base * texture_lookup(*h.mat, u, v);
  }
  h.instance_id = g.instance_id;
}

/// Ray origin moved off the surface to the side of direction d.
F3 offset_origin(const Hit& h, F3 d) {
  const float scale =
      2e-5f * (1.0f + std::max(std::abs(h.p.x), std::max(std::abs(h.p.y), std::abs(h.p.z))));
  return h.p + h.ng * (dot(d, h.ng) >= 0.0f ? scale : -scale);
}

/// Nearest front-facing area light along the ray within (0, tmax). Returns its index or -1.
int hit_light(const Lighting& L, F3 o, F3 d, float tmax, float& t_out) {
  int best = -1;
  for (std::size_t i = 0; i < L.light_data.size(); ++i) {
    const LightData& l = L.light_data[i];
    const float dn = dot(d, l.n);
    if (dn >= 0.0f) continue;  // back side or parallel: one-sided emitter
    const float t = dot(l.centre - o, l.n) / dn;
    if (!(t > 0.0f && t < tmax)) continue;
    const F3 q = o + d * t - l.centre;
    const float x = dot(q, l.ex), y = dot(q, l.ey);
    const bool inside =
        l.disc ? (x * x + y * y <= l.hx * l.hx) : (std::abs(x) <= l.hx && std::abs(y) <= l.hy);
    if (!inside) continue;
    tmax = t;
    best = static_cast<int>(i);
  }
  t_out = tmax;
  return best;
}

/// Pdf (solid angle, at the shading point with normal n) of environment sampling: the sun's
/// cone with probability p_sun, the dome (cosine-weighted) with probability p_dome.
float env_pdf(const Lighting& L, float p_sun, float p_dome, F3 n, F3 w) {
  float p = p_dome * std::max(0.0f, dot(n, w)) * pt::kInvPi;
  if (p_sun > 0.0f && dot(w, L.sun_dir) >= L.sun_cos)
    p += p_sun / (2.0f * pt::kPi * (1.0f - L.sun_cos));
  return p;
}

inline float power_heuristic(float a, float b) {
  const float a2 = a * a, b2 = b * b;
  return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

}  // namespace

// The path of one camera sample. At a smooth dielectric both the reflected and the refracted
// ray are traced to the light they meet first (Fresnel splitting: each weighted by its expected
// share F or 1 - F instead of the random choice of one; the lamps and the sky seen in and
// through glass are the noisiest part of a glass object otherwise) and only the chosen ray
// continues the path (it carries the indirect light of both, unbiased); at the first
// kMaxBranches such vertices the other ray is traced in full as a branch (take_split).
// The albedo and normal for the denoiser are those of the first surface that is not smooth
// glass: through (or in) a smooth dielectric they are taken at the next hit, so that the
// denoiser keeps what is seen through glass instead of smoothing it into a flat surface.
// At a split smooth dielectric both branches contribute, weighted by their Fresnel shares:
// the other branch's first hit goes into the sample's guides now, the continuing one's guide
// (PathState::aov_a, aov_n, what it shows so far) is weighted aov_w at the end. About the
// expectation of following the randomly chosen branch only (the other branch is followed
// through further glass by refraction alone), without its noise: a pixel no longer shows the
// reflection's guide or the transmission's at random.
F3 Integrator::trace(F3 o, F3 d, const pt::PixelSampler& s, F3& aov_albedo, F3& aov_normal,
                     const RTCRayHit* first) {
  // The stack of waiting branches, left uninitialised (a camera sample rarely uses it):
  // take_split constructs each entry it pushes.
  union Stack {
    Stack() {}  // no initialisation of the items
    PathState items[kMaxBranches];
  } stack;
  SampleSum sum;
  sum.pending = stack.items;
  PathState p;
  p.o = o;
  p.d = d;
  for (;;) {
    trace_path(p, s, first, sum);
    sum.aov_a += p.aov_a * p.aov_w;
    sum.aov_n += p.aov_n * p.aov_w;
    if (sum.n_pending == 0) break;
    p = sum.pending[--sum.n_pending];
  }
  aov_albedo = sum.aov_a;
  aov_normal = sum.aov_n;
  return sum.L;
}

inline void Integrator::trace_path(PathState& p, const pt::PixelSampler& s, const RTCRayHit* first,
                                   SampleSum& sum) {
  RTCRayHit rh;
  Hit h;
  for (;; ++p.depth) {
    if (!find_surface(p, first, rh, sum.L)) return;
    make_hit(G_, rh, p.d, h);
    add_surface_emission(p, rh, h, sum.L);
    if (p.depth >= opt_.max_bounces) return;
    if (!scatter(p, h, s, sum)) return;
  }
}

inline bool Integrator::find_surface(PathState& p, const RTCRayHit* first, RTCRayHit& rh, F3& L) {
  bool hit;
  if (p.depth == 0 && first != nullptr) {
    rh = *first;
    hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
  } else if (p.depth == 0) {
    hit = intersect_primary(p.o, p.d, std::numeric_limits<float>::infinity(), rh);
  } else {
    hit = intersect(p.o, p.d, std::numeric_limits<float>::infinity(), rh);
  }
  const float t_geom = hit ? rh.ray.tfar : std::numeric_limits<float>::infinity();
  float t_light;
  const int li = L_.light_data.empty() ? -1 : hit_light(L_, p.o, p.d, t_geom, t_light);
  if (li >= 0) {
    const LightData& l = L_.light_data[li];
    float w = 1.0f;
    if (!p.prev_delta) {
      const float cos_l = -dot(p.d, l.n);
      const float pl =
          L_.pmf[li] * nee(p.depth - 1).area_sel * t_light * t_light / (l.area * cos_l);
      w = power_heuristic(p.prev_pdf, pl);
    }
    add(L, p.beta_e * l.radiance * w, p.depth >= 2);
    if (p.aov_open) p.aov_a = lamp_guide(l.radiance);
    return false;
  }
  if (hit) return true;
  if (L_.env_on || p.aov_open) {
    const F3 Le = L_.env(p.d);
    float w = 1.0f;
    if (!p.prev_delta && L_.env_on) {
      const NeeMode& m = nee(p.depth - 1);
      w = power_heuristic(
          p.prev_pdf, L_.pmf.back() * m.env_sel * env_pdf(L_, m.p_sun, m.p_dome, p.prev_n, p.d));
    }
    add(L, p.beta_e * Le * w, p.depth >= 2);
    if (p.aov_open) p.aov_a = emitter_guide(Le);
  }
  return false;
}

inline void Integrator::add_surface_emission(PathState& p, const RTCRayHit& rh, const Hit& h,
                                             F3& L) {
  const MaterialData& m = *h.mat;
  if (m.emissive && h.front) {
    // An emissive triangle found by BSDF sampling: MIS against its next-event estimation.
    float w = 1.0f;
    if (!p.prev_delta) {
      const auto& fe = G_.geoms[rh.hit.geomID].face_emitter;
      const std::int32_t e = fe.empty() ? -1 : fe[rh.hit.primID];
      if (e >= 0) {
        const float cos_l = std::abs(dot(p.d, h.ng));
        const float t = rh.ray.tfar;
        const float pl = L_.pmf[L_.light_data.size() + e] * nee(p.depth - 1).area_sel * t * t /
                         (L_.tris[e].area * std::max(cos_l, 1e-7f));
        w = power_heuristic(p.prev_pdf, pl);
      }
    }
    add(L, p.beta_e * m.emission * w, p.depth >= 2);
  }
  if (p.aov_open) {
    p.aov_a = h.base;
    p.aov_n = h.ns;
    p.aov_open = see_through(m);
  }
}

inline bool Integrator::scatter(PathState& p, const Hit& h, const pt::PixelSampler& s,
                                SampleSum& sum) {
  const MaterialData& m = *h.mat;
  const pt::Frame frame(h.ns);
  const F3 wo = frame.to_local(-p.d);
  pt::ShadingMaterial sm{h.base, m.metallic, m.alpha, m.ior, m.transmission, m.ms};
  sm.prepare(wo.z, h.front);
  const std::uint32_t base_pair = 2 + 5 * static_cast<std::uint32_t>(p.depth);
  // Dimension pairs of this vertex: light point, BSDF direction, (light choice, lobe),
  // (roulette, Fresnel choice), environment direction.
  const pt::Sample2 u_bsdf = s.get(base_pair + 1);
  const pt::Sample2 u_sel = s.get(base_pair + 2);
  const pt::Sample2 u_rr = s.get(base_pair + 3);
  if (sm.has_nondelta) next_event(p, h, frame, wo, sm, s, base_pair, u_sel.x, sum.L);

  BsdfSample bs;
  Split split;
  // Fresnel splitting (and the branches) only while the throughput is worth the other
  // direction's ray: deeper, dim paths take the random direction alone (unbiased; the
  // choice does not depend on the Fresnel draw).
  const bool may_split = sum.branches_left > 0 || max_comp(p.beta) >= split_min_;
  if (!sample_bsdf(h, frame, wo, sm, u_sel.y, u_rr.y, u_bsdf, bs, may_split ? &split : nullptr))
    return false;
  if (split.on) {
    p.beta *= take_split(p, h, sm, bs, split, sum);
  } else {
    p.beta *= bs.weight;
    p.beta_e = p.beta;
  }
  p.eta_scale *= bs.eta2;
  if (!all_finite(p.beta) || max_comp(p.beta) <= 0.0f) return false;
  if (!roulette(p, bs.delta && !sm.rough, u_rr.x)) return false;
  p.prev_delta = bs.delta;
  p.prev_pdf = bs.pdf;
  p.prev_n = h.ns;
  p.o = offset_origin(h, bs.wi_w);
  p.d = bs.wi_w;
  return true;
}

inline void Integrator::next_event(const PathState& p, const Hit& h, const pt::Frame& frame, F3 wo,
                                   const pt::ShadingMaterial& sm, const pt::PixelSampler& s,
                                   std::uint32_t base_pair, float u_light, F3& L) {
  const NeeMode& m = nee(p.depth);
  bool do_area = L_.area_on, do_env = m.env_nee;
  if (m.one_shadow) {
    // One shadow ray: the environment with probability env_sel, else a light.
    if (u_light < m.env_sel) {
      do_area = false;
    } else {
      do_env = false;
      u_light = std::min((u_light - m.env_sel) / (1.0f - m.env_sel), 0.99999994f);
    }
  }
  if (do_area) {
    const std::size_t n = L_.n_local;
    const auto k = static_cast<std::size_t>(
        std::upper_bound(L_.cdf.begin(), L_.cdf.begin() + (n - 1), u_light) - L_.cdf.begin());
    add(L, p.beta * direct(h, frame, wo, sm, k, s.get(base_pair), m), p.depth >= 1);
  }
  if (do_env)
    add(L, p.beta * direct(h, frame, wo, sm, L_.n_local, s.get(base_pair + 4), m), p.depth >= 1);
}

inline F3 Integrator::take_split(PathState& p, const Hit& h, const pt::ShadingMaterial& sm,
                                 const BsdfSample& bs, const Split& split, SampleSum& sum) {
  if (sum.branches_left > 0) {
    // Both branches traced in full (the first kMaxBranches smooth-dielectric vertices of a
    // camera sample): the other one waits in `pending`; each carries its expected weight
    // (F or 1 - F times its lobe weight) instead of the random choice's, so nothing seen in
    // or through the first walls of a glass object depends on the reflect/refract draw
    // (a lamp reflected by the far wall of a bottle and seen through the near one was found
    // by a path only with probability F: a bright speckle, now a clean highlight).
    --sum.branches_left;
    const float eta_v = h.front ? sm.ior : 1.0f / sm.ior;
    PathState& b = *::new (static_cast<void*>(&sum.pending[sum.n_pending++])) PathState;
    b.o = offset_origin(h, split.other_dir);
    b.d = split.other_dir;
    b.beta = p.beta * split.other_weight;
    b.beta_e = b.beta;
    b.prev_delta = true;
    b.prev_pdf = 0.0f;
    b.prev_n = h.ns;
    b.eta_scale = p.eta_scale * (bs.eta2 == 1.0f ? eta_v * eta_v : 1.0f);
    b.aov_a = p.aov_a;
    b.aov_n = p.aov_n;
    b.aov_w = p.aov_w * split.other_share;
    b.aov_open = p.aov_open;
    b.depth = p.depth + 1;
    b.rr_vertices = p.rr_vertices;
    p.aov_w *= 1.0f - split.other_share;
    if (max_comp(b.beta) <= 0.0f || !all_finite(b.beta)) --sum.n_pending;
    p.beta_e = p.beta * split.weight;
    return split.weight;
  }
  if (p.aov_open && p.aov_w * split.other_share >= guide_split_min_) {
    // The other branch's guide (followed through further smooth glass by refraction),
    // weighted by its share; the continuing branch keeps the rest.
    F3 oa = p.aov_a, on = p.aov_n;
    const F3 Le = emitted(h, split.other_dir, &oa, &on);
    if (max_comp(split.other_weight) > 0.0f)
      add(sum.L, p.beta * split.other_weight * Le, p.depth >= 1);
    sum.aov_a += oa * (p.aov_w * split.other_share);
    sum.aov_n += on * (p.aov_w * split.other_share);
    p.aov_w *= 1.0f - split.other_share;
  } else if (max_comp(split.other_weight) > 0.0f) {
    add(sum.L, p.beta * split.other_weight * emitted(h, split.other_dir), p.depth >= 1);
  }
  p.beta_e = p.beta * split.weight;
  return bs.weight;
}

inline bool Integrator::roulette(PathState& p, bool smooth, float u) {
  // Roulette counts the vertices where the path did not pass a smooth dielectric: behind a
  // glass wall (two such vertices, each keeping nearly all the throughput) the first rough
  // surface is rouletted as if seen directly. Those paths (what is seen in and through
  // glass) carry most of a glass object's noise and few of them are long.
  if (!smooth) ++p.rr_vertices;
  if (p.rr_vertices < opt_.rr_depth) return true;
  // Roulette on the throughput without the 1/eta^2 radiance scaling of refractions, so
  // that paths inside glass are not killed more often than outside.
  const float q = std::min(1.0f, max_comp(p.beta) * p.eta_scale);
  if (u >= q) return false;
  p.beta *= 1.0f / q;
  p.beta_e *= 1.0f / q;
  return true;
}

F3 Integrator::direct(const Hit& h, const pt::Frame& frame, F3 wo, const pt::ShadingMaterial& sm,
                      std::size_t k, pt::Sample2 u, const NeeMode& mode) {
  const std::size_t n = L_.pmf.size();
  const float p_sel = L_.pmf[k] * (k + 1 == n ? mode.env_sel : mode.area_sel);
  if (p_sel <= 0.0f) return F3(0.0f);
  F3 wi_w, Le;
  float pdf_light, dist;
  if (k + 1 == n) {  // environment
    float pu = u.x;
    if (mode.p_sun > 0.0f && pu < mode.p_sun) {
      pu /= mode.p_sun;
      const pt::Frame sf(L_.sun_dir);
      wi_w = sf.to_world(pt::uniform_cone(pu, u.y, L_.sun_cos));
    } else {
      if (mode.p_sun > 0.0f) pu = (pu - mode.p_sun) / (1.0f - mode.p_sun);
      wi_w = frame.to_world(pt::cosine_hemisphere(std::min(pu, 0.99999994f), u.y));
    }
    pdf_light = env_pdf(L_, mode.p_sun, mode.p_dome, h.ns, wi_w);
    if (pdf_light <= 0.0f) return F3(0.0f);
    dist = std::numeric_limits<float>::infinity();
    Le = L_.env(wi_w);
  } else {
    // A point q on an emissive triangle or an area light (normal n, area), uniform in area.
    F3 q, n;
    float area;
    if (k >= L_.light_data.size()) {
      const TriEmitter& t = L_.tris[k - L_.light_data.size()];
      const float su = std::sqrt(u.x);
      q = t.p0 + t.e1 * (1.0f - su) + t.e2 * (u.y * su);
      n = t.n;
      area = t.area;
      Le = t.radiance;
    } else {
      const LightData& l = L_.light_data[k];
      if (l.disc) {
        const pt::Sample2 dd = pt::concentric_disc(u.x, u.y);
        q = l.centre + l.ex * (dd.x * l.hx) + l.ey * (dd.y * l.hx);
      } else {
        q = l.centre + l.ex * ((2.0f * u.x - 1.0f) * l.hx) + l.ey * ((2.0f * u.y - 1.0f) * l.hy);
      }
      n = l.n;
      area = l.area;
      Le = l.radiance;
    }
    const F3 v = q - h.p;
    const float d2 = dot(v, v);
    if (!(d2 > 0.0f)) return F3(0.0f);
    dist = std::sqrt(d2);
    wi_w = v / dist;
    const float cos_l = -dot(wi_w, n);
    if (cos_l <= 0.0f) return F3(0.0f);
    pdf_light = d2 / (area * cos_l);
  }
  if (dot(wi_w, h.ng) <= 0.0f) return F3(0.0f);
  const F3 wi = frame.to_local(wi_w);
  F3 f;
  float pdf_bsdf;
  sm.eval(wo, wi, f, pdf_bsdf);
  if (max_comp(f) <= 0.0f || max_comp(Le) <= 0.0f) return F3(0.0f);
  const F3 o = offset_origin(h, wi_w);
  const float tfar = std::isinf(dist) ? dist : dist * (1.0f - 1e-4f);
  if (occluded(o, wi_w, tfar)) return F3(0.0f);
  const float pl = p_sel * pdf_light;
  const float w = power_heuristic(pl, pdf_bsdf);
  return f * Le * (wi.z * w / pl);
}

F3 Integrator::emitted(const Hit& h, F3 d, F3* aux_albedo, F3* aux_normal) {
  const F3 o = offset_origin(h, d);
  RTCRayHit rh;
  const bool hit = intersect(o, d, std::numeric_limits<float>::infinity(), rh);
  const float t_geom = hit ? rh.ray.tfar : std::numeric_limits<float>::infinity();
  float t_light;
  const int li = L_.light_data.empty() ? -1 : hit_light(L_, o, d, t_geom, t_light);
  if (li >= 0) {
    if (aux_albedo) *aux_albedo = lamp_guide(L_.light_data[li].radiance);
    return L_.light_data[li].radiance;
  }
  if (!hit) {
    const F3 Le = L_.env(d);
    if (aux_albedo) *aux_albedo = emitter_guide(Le);
    return L_.env_on ? Le : F3(0.0f);
  }
  if (aux_albedo) aux_behind_glass(rh, d, *aux_albedo, *aux_normal);
  const TriShade& t = G_.geoms[rh.hit.geomID].tri[rh.hit.primID];
  const MaterialData& m = G_.mats[t.material];
  if (!m.emissive) return F3(0.0f);
  return dot(d, t.ng) < 0.0f ? m.emission : F3(0.0f);
}

void Integrator::aux_behind_glass(RTCRayHit rh, F3 d, F3& albedo, F3& normal) {
  Hit g;
  for (int k = 0;; ++k) {
    make_hit(G_, rh, d, g);
    if (!see_through(*g.mat) || k == 8) {
      albedo = g.base;
      normal = g.ns;
      return;
    }
    // ns faces the side d came from; eta = n_incident / n_transmitted.
    const float eta = g.front ? 1.0f / g.mat->ior : g.mat->ior;
    const float ci = std::min(1.0f, std::max(0.0f, -dot(d, g.ns)));
    const float sin2_t = eta * eta * (1.0f - ci * ci);
    d = sin2_t >= 1.0f ? normalize(d + g.ns * (2.0f * ci))
                       : normalize(d * eta + g.ns * (eta * ci - std::sqrt(1.0f - sin2_t)));
    const F3 o = offset_origin(g, d);
    const bool hit = intersect(o, d, std::numeric_limits<float>::infinity(), rh);
    float t_light;
    const float t_geom = hit ? rh.ray.tfar : std::numeric_limits<float>::infinity();
    const int li = L_.light_data.empty() ? -1 : hit_light(L_, o, d, t_geom, t_light);
    if (li >= 0 || !hit) {
      albedo = li >= 0 ? lamp_guide(L_.light_data[li].radiance) : emitter_guide(L_.env(d));
      return;
    }
  }
}

bool Integrator::sample_bsdf(const Hit& h, const pt::Frame& frame, F3 wo,
                             const pt::ShadingMaterial& sm, float u_lobe, float u_fresnel,
                             pt::Sample2 u, BsdfSample& out, Split* split) {
  F3& wi_w = out.wi_w;
  F3& weight = out.weight;
  float& pdf = out.pdf;
  bool& delta = out.delta;
  float& eta2 = out.eta2;
  eta2 = 1.0f;
  if (split != nullptr) split->on = false;
  if (u_lobe < sm.p_delta && sm.rough) {
    // Rough dielectric: refraction (no light is sampled below the surface, so the light this
    // ray finds is weighted 1, as after a delta lobe) or reflection (weighed by the whole
    // non-delta BSDF and its pdf, as the other lobes' samples).
    F3 wi;
    if (sm.sample_rough(wo, u_fresnel, u.x, u.y, wi, weight)) {
      if (wi.z >= 0.0f) return false;
      wi_w = frame.to_world(wi);
      if (dot(wi_w, h.ng) >= 0.0f) return false;
      delta = true;
      pdf = 0.0f;
      eta2 = sm.eta * sm.eta;
      return true;
    }
    delta = false;
    if (wi.z <= 0.0f) return false;
    wi_w = frame.to_world(wi);
    if (dot(wi_w, h.ng) <= 0.0f) return false;
    F3 f;
    sm.eval(wo, wi, f, pdf);
    if (!(pdf > 0.0f)) return false;
    weight = f * (wi.z / pdf);
    return true;
  }
  if (u_lobe < sm.p_delta) {
    // Smooth dielectric: reflect with probability F, otherwise refract.
    delta = true;
    pdf = 0.0f;
    const float eta = h.front ? sm.ior : 1.0f / sm.ior;  // n_t / n_i
    // The interface normal is the shading normal (smooth curved glass); where it would send
    // the reflected or refracted ray to the wrong side of the surface, the geometric normal.
    const F3 wo_w = frame.to_world(wo);
    F3 n = h.ns;
    float ci = std::max(0.0f, dot(wo_w, n));
    const float F = pt::fresnel_dielectric(ci, eta);
    const float scale = sm.w_trans / sm.p_delta;
    auto refract = [&](F3 nn, float c) {
      const float sin2_t = (1.0f - c * c) / (eta * eta);
      const float ct = std::sqrt(std::max(0.0f, 1.0f - sin2_t));
      return normalize(-wo_w * (1.0f / eta) + nn * (c / eta - ct));
    };
    auto reflected = [&] {
      const F3 r = pt::reflect(wo_w, n);
      return dot(r, h.ng) <= 0.0f ? pt::reflect(wo_w, h.ng) : r;
    };
    auto refracted = [&] {
      const F3 t = refract(n, ci);
      return dot(t, h.ng) >= 0.0f ? refract(h.ng, std::max(0.0f, dot(wo_w, h.ng))) : t;
    };
    // Tint sqrt(base) at each interface: a pass through a closed wall (in and out) is
    // tinted by the base colour once, as in Blender's Principled BSDF. Radiance is scaled
    // by 1/eta^2 on refraction (the solid angle compresses); it cancels on a closed shell.
    const F3 w_refract = sm.sqrt_base() * (scale / (eta * eta));
    const bool split_on = split != nullptr && F > 0.0f && F < 1.0f;
    if (u_fresnel < F) {
      wi_w = reflected();
      weight = F3(scale);
      if (split_on) *split = {true, F3(F * scale), refracted(), w_refract * (1.0f - F), 1.0f - F};
    } else {
      wi_w = refracted();
      weight = w_refract;
      eta2 = eta * eta;
      if (split_on) *split = {true, w_refract * (1.0f - F), reflected(), F3(F * scale), F};
    }
    return true;
  }
  delta = false;
  if (!sm.has_other) return false;
  const float ul = (u_lobe - sm.p_delta) / (1.0f - sm.p_delta);
  F3 wi;
  if (ul < sm.p_spec) {
    const F3 m = pt::ggx_sample_vndf(wo, sm.alpha, u.x, u.y);
    wi = pt::reflect(wo, m);
  } else {
    wi = pt::cosine_hemisphere(u.x, u.y);
  }
  if (wi.z <= 0.0f) return false;
  wi_w = frame.to_world(wi);
  if (dot(wi_w, h.ng) <= 0.0f) return false;
  F3 f;
  sm.eval(wo, wi, f, pdf);
  if (!(pdf > 0.0f)) return false;
  weight = f * (wi.z / pdf);
  return true;
}

}  // namespace mgn::pt
