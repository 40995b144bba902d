#pragma once
// Private building blocks of the path tracer (pt_*.cpp): a small float vector type, the
// per-pixel low-discrepancy sampler, and the glTF metallic-roughness BSDF (GGX + Lambert +
// smooth dielectric). Everything here is inline and in float; only PairSeeds allocates (as it
// grows, once per thread).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace mgn::pt {

constexpr float kPi = 3.14159265358979f;
constexpr float kInvPi = 0.318309886183791f;

struct F3 {
  float x = 0.0f, y = 0.0f, z = 0.0f;
  F3() = default;
  constexpr F3(float a, float b, float c) : x(a), y(b), z(c) {}
  explicit constexpr F3(float a) : x(a), y(a), z(a) {}
  float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};
inline F3 operator+(F3 a, F3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline F3 operator-(F3 a, F3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline F3 operator-(F3 a) { return {-a.x, -a.y, -a.z}; }
inline F3 operator*(F3 a, F3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
inline F3 operator*(F3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline F3 operator*(float s, F3 a) { return {a.x * s, a.y * s, a.z * s}; }
inline F3 operator/(F3 a, float s) { return a * (1.0f / s); }
inline F3& operator+=(F3& a, F3 b) { return a = a + b; }
inline F3& operator*=(F3& a, F3 b) { return a = a * b; }
inline F3& operator*=(F3& a, float s) { return a = a * s; }
inline float dot(F3 a, F3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline F3 cross(F3 a, F3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(F3 a) { return std::sqrt(dot(a, a)); }
inline F3 normalize(F3 a) {
  const float l2 = dot(a, a);
  return l2 > 0.0f ? a * (1.0f / std::sqrt(l2)) : a;
}
inline float max_comp(F3 a) { return std::max(a.x, std::max(a.y, a.z)); }
inline float luminance(F3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }
inline bool all_finite(F3 a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
inline F3 lerp(F3 a, F3 b, float t) { return a + (b - a) * t; }

/// Orthonormal basis (t, b, n) around unit n (branch-free construction after Duff et al. 2017).
struct Frame {
  F3 t, b, n;
  explicit Frame(F3 nn) : n(nn) {
    const float s = std::copysign(1.0f, nn.z);
    const float a = -1.0f / (s + nn.z);
    const float c = nn.x * nn.y * a;
    t = F3(1.0f + s * nn.x * nn.x * a, s * c, -s * nn.x);
    b = F3(c, s + nn.y * nn.y * a, -nn.y);
  }
  F3 to_local(F3 v) const { return {dot(v, t), dot(v, b), dot(v, n)}; }
  F3 to_world(F3 v) const { return t * v.x + b * v.y + n * v.z; }
};

// ---------------------------------------------------------------------------------------------
// Sampler: 2-D Sobol points (dimensions 0 and 1 of Sobol's sequence) with hash-based nested
// uniform (Owen) scrambling and a scrambled sample order, an independent scramble per pixel and
// per pair of dimensions (after Burley, "Practical Hash-based Owen Scrambling", JCGT 2020).

inline std::uint32_t reverse_bits(std::uint32_t x) {
  x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  x = ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);
  return __builtin_bswap32(x);  // the bytes in reverse order (one instruction)
}

/// A permutation of 32-bit words in which bit k of the result depends only on bits <= k of the
/// input (so applied to bit-reversed values it is a nested uniform scramble).
inline std::uint32_t lk_permute(std::uint32_t x, std::uint32_t seed) {
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return x;
}

inline std::uint32_t owen_scramble(std::uint32_t x, std::uint32_t seed) {
  return reverse_bits(lk_permute(reverse_bits(x), seed));
}

inline std::uint32_t hash32(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}
inline std::uint32_t hash_combine(std::uint32_t seed, std::uint32_t v) {
  return hash32(seed ^ (v + 0x9e3779b9u + (seed << 6) + (seed >> 2)));
}

/// Second Sobol dimension as a 32-bit fraction, by byte tables (generator matrix columns XORed).
/// The table holds it bit-reversed (`rev`): reverse_bits is linear over XOR, so the reversed
/// value is the XOR of the reversed columns.
struct SobolTable {
  std::uint32_t t[4][256];
  SobolTable() {
    std::uint32_t col[32];
    std::uint32_t v = 1u << 31;
    for (int k = 0; k < 32; ++k) {
      col[k] = reverse_bits(v);
      v ^= v >> 1;
    }
    for (int byte = 0; byte < 4; ++byte) {
      for (int b = 0; b < 256; ++b) {
        std::uint32_t r = 0;
        for (int k = 0; k < 8; ++k)
          if (b & (1 << k)) r ^= col[8 * byte + k];
        t[byte][b] = r;
      }
    }
  }
  /// reverse_bits(second Sobol dimension of point i).
  std::uint32_t rev(std::uint32_t i) const {
    return t[0][i & 255u] ^ t[1][(i >> 8) & 255u] ^ t[2][(i >> 16) & 255u] ^ t[3][i >> 24];
  }
};
inline const SobolTable& sobol_table() {
  static const SobolTable table;
  return table;
}

inline float to_unit(std::uint32_t x) { return static_cast<float>(x >> 8) * 0x1.0p-24f; }

struct Sample2 {
  float x, y;
};

/// The three scramble seeds of dimension pair `pair` of a pixel stream with seed `pixel_seed`:
/// of the sample order and of dimensions 0 and 1. They depend on neither the pixel inside a
/// block nor the sample index, so PairSeeds keeps them.
struct PairSeed {
  std::uint32_t order, dim0, dim1;
};
inline PairSeed pair_seed(std::uint32_t pixel_seed, std::uint32_t pair) {
  const std::uint32_t s = hash_combine(pixel_seed, pair);
  return {s, hash32(s ^ 0xa511e9b3u), hash32(s ^ 0x63d83595u)};
}

/// The pair seeds of the last pixel seed asked for, computed once per (seed, pair) instead of
/// at every sample (the pixels of a block share one seed). One per thread; not thread-safe.
class PairSeeds {
 public:
  const PairSeed& get(std::uint32_t pixel_seed, std::uint32_t pair) {
    if (pixel_seed != seed_ || seeds_.empty()) {
      seed_ = pixel_seed;
      seeds_.clear();
    }
    while (seeds_.size() <= pair)
      seeds_.push_back(pair_seed(seed_, static_cast<std::uint32_t>(seeds_.size())));
    return seeds_[pair];
  }

 private:
  std::uint32_t seed_ = 0;
  std::vector<PairSeed> seeds_;
};

/// Stream of one pixel: sample `index` of dimension pair `pair` is a point in [0,1)^2.
///
/// Point: i = owen_scramble(index, s) (a scrambled sample order), then dimension 0 (the
/// van der Corput radical inverse, reverse_bits(i)) and dimension 1 (Sobol) of point i, each
/// Owen-scrambled with its own seed. Written with owen_scramble(x) = rev(lk(rev(x))) and
/// rev(rev(x)) = x so that only the needed bit reversals are done.
class PixelSampler {
 public:
  /// `cache`, when given, supplies the pair seeds (same values, computed once per pixel seed).
  PixelSampler(std::uint32_t pixel_seed, std::uint32_t index, PairSeeds* cache = nullptr)
      : seed_(pixel_seed), rev_index_(reverse_bits(index)), table_(&sobol_table()), cache_(cache) {}
  __attribute__((always_inline)) Sample2 get(std::uint32_t pair) const {
    const PairSeed ps = cache_ != nullptr ? cache_->get(seed_, pair) : pair_seed(seed_, pair);
    const std::uint32_t i = reverse_bits(lk_permute(rev_index_, ps.order));
    const std::uint32_t a = reverse_bits(lk_permute(i, ps.dim0));
    const std::uint32_t b = reverse_bits(lk_permute(table_->rev(i), ps.dim1));
    return {to_unit(a), to_unit(b)};
  }

 private:
  std::uint32_t seed_, rev_index_;
  const SobolTable* table_;
  PairSeeds* cache_;
};

/// Bits per axis of the 2-D Morton (Z-order) index of (x, y) < 2^bits (bit k of x goes to bit 2k,
/// of y to bit 2k + 1).
inline std::uint32_t morton2(std::uint32_t x, std::uint32_t y, int bits) {
  std::uint32_t m = 0;
  for (int k = 0; k < bits; ++k)
    m |= (((x >> k) & 1u) << (2 * k)) | (((y >> k) & 1u) << (2 * k + 1));
  return m;
}

/// ceil(log2(n)) for n >= 1.
inline int ceil_log2(std::uint32_t n) {
  int l = 0;
  while (l < 32 && (std::uint64_t{1} << l) < n) ++l;
  return l;
}

/// Where the samples of one pixel sit in the image-wide sample sequence: sample k of pixel
/// (u, v) is PixelSampler(seed, base | k).
///
/// The image is cut into blocks of 2^b x 2^b pixels (b <= 6, fewer when spp needs the bits);
/// each block has one seed (from `stream` and the block), and inside it the pixels take
/// consecutive ranges of 2^ceil(log2(spp)) indices in Morton order. PixelSampler scrambles the
/// index with a nested uniform permutation per dimension pair, which maps every aligned range
/// of indices to an aligned range: the samples of any aligned 2^j x 2^j group of pixels are then
/// one Owen-scrambled Sobol net of 4^j * spp points in every dimension pair, i.e. stratified
/// across neighbouring pixels, while each single sample stays uniformly distributed (unbiased).
/// The error is thereby pushed to high spatial frequencies ("blue"), which a denoiser removes
/// best (after Ahmed and Wonka, "Screen-space blue-noise diffusion of Monte Carlo sampling
/// error via hierarchical ordering of pixels", SIGGRAPH Asia 2020).
struct PixelStream {
  std::uint32_t seed, base;
};
inline PixelStream pixel_stream(std::uint64_t stream, std::uint32_t u, std::uint32_t v,
                                int spp_log2) {
  const int b = std::max(0, std::min(6, (32 - spp_log2) / 2));
  const std::uint32_t mask = (1u << b) - 1u;
  const std::uint64_t block = (static_cast<std::uint64_t>(v >> b) << 32) | (u >> b);
  std::uint64_t z = stream ^ (block + 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  const std::uint32_t m = morton2(u & mask, v & mask, b);
  return {static_cast<std::uint32_t>(z), spp_log2 >= 32 ? 0u : (m << spp_log2)};
}

// ---------------------------------------------------------------------------------------------
// Warps.

inline Sample2 concentric_disc(float u1, float u2) {
  const float a = 2.0f * u1 - 1.0f, b = 2.0f * u2 - 1.0f;
  if (a == 0.0f && b == 0.0f) return {0.0f, 0.0f};
  float r, phi;
  if (std::abs(a) > std::abs(b)) {
    r = a;
    phi = (kPi / 4.0f) * (b / a);
  } else {
    r = b;
    phi = (kPi / 2.0f) - (kPi / 4.0f) * (a / b);
  }
  return {r * std::cos(phi), r * std::sin(phi)};
}

inline F3 cosine_hemisphere(float u1, float u2) {
  const Sample2 d = concentric_disc(u1, u2);
  const float z = std::sqrt(std::max(0.0f, 1.0f - d.x * d.x - d.y * d.y));
  return {d.x, d.y, z};
}

/// Uniform direction in the cone of half-angle acos(cos_max) around +z.
inline F3 uniform_cone(float u1, float u2, float cos_max) {
  const float c = 1.0f - u1 * (1.0f - cos_max);
  const float s = std::sqrt(std::max(0.0f, 1.0f - c * c));
  const float phi = 2.0f * kPi * u2;
  return {s * std::cos(phi), s * std::sin(phi), c};
}

// ---------------------------------------------------------------------------------------------
// Fresnel and GGX.

/// Unpolarised Fresnel reflectance of a dielectric interface, cos_i >= 0 on the incident side,
/// eta = n_transmitted / n_incident. Returns 1 for total internal reflection.
inline float fresnel_dielectric(float cos_i, float eta) {
  cos_i = std::min(std::max(cos_i, 0.0f), 1.0f);
  const float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0f) return 1.0f;
  const float cos_t = std::sqrt(1.0f - sin2_t);
  const float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  const float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  return 0.5f * (rs * rs + rp * rp);
}

inline F3 fresnel_schlick(F3 f0, float cos_i) {
  const float m = std::min(std::max(1.0f - cos_i, 0.0f), 1.0f);
  const float m2 = m * m;
  const float m5 = m2 * m2 * m;
  return f0 + (F3(1.0f) - f0) * m5;
}

/// GGX normal distribution (local frame, h unit, h.z = cos theta_h).
inline float ggx_d(F3 h, float alpha) {
  if (h.z <= 0.0f) return 0.0f;
  const float a2 = alpha * alpha;
  const float c2 = h.z * h.z;
  const float d = c2 * (a2 - 1.0f) + 1.0f;
  return a2 / (kPi * d * d);
}

/// Smith Lambda of GGX for direction w (local).
inline float ggx_lambda(F3 w, float alpha) {
  const float c2 = w.z * w.z;
  if (c2 <= 0.0f) return 1e30f;
  const float t2 = std::max(0.0f, 1.0f - c2) / c2;
  return 0.5f * (-1.0f + std::sqrt(1.0f + alpha * alpha * t2));
}

/// Visible-normal sample of GGX for view direction wo (local, wo.z > 0) (Heitz 2018).
inline F3 ggx_sample_vndf(F3 wo, float alpha, float u1, float u2) {
  const F3 vh = normalize(F3(alpha * wo.x, alpha * wo.y, wo.z));
  const float len2 = vh.x * vh.x + vh.y * vh.y;
  const F3 t1 = len2 > 0.0f ? F3(-vh.y, vh.x, 0.0f) * (1.0f / std::sqrt(len2)) : F3(1, 0, 0);
  const F3 t2 = cross(vh, t1);
  const float r = std::sqrt(u1);
  const float phi = 2.0f * kPi * u2;
  const float p1 = r * std::cos(phi);
  float p2 = r * std::sin(phi);
  const float s = 0.5f * (1.0f + vh.z);
  p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * p2;
  const F3 nh = t1 * p1 + t2 * p2 + vh * std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2));
  return normalize(F3(alpha * nh.x, alpha * nh.y, std::max(1e-6f, nh.z)));
}

inline F3 reflect(F3 w, F3 n) { return n * (2.0f * dot(w, n)) - w; }

// ---------------------------------------------------------------------------------------------
// Multiple scattering between microfacets: energy compensation after Kulla and Conty,
// "Revisiting Physically Based Shading at Imageworks" (SIGGRAPH 2017 course). A single-scattering
// GGX lobe of directional albedo E(mu) < 1 gets a second, diffuse-like lobe
//   f_ms(wo, wi) = c (1 - E(mu_o)) (1 - E(mu_i)) / pi,
// symmetric in wo and wi, whose albedo is c (1 - E(mu_o)) (1 - E_avg), E_avg = 2 int E(mu) mu dmu:
// with c = 1 / (1 - E_avg) the lobes together reflect everything a white lobe receives. The
// tables are computed by the tracer itself, per material (its alpha and ior), when the scene is
// built: E(mu) by a fixed midpoint quadrature of the visible-normal distribution (below), so
// the result is the same on every run and machine.

/// A directional albedo E(mu), mu = cos theta in [0, 1], tabulated at mu_k = (k / (kN - 1))^2
/// (denser near grazing, where E changes fastest) and linearly interpolated in sqrt(mu). `avg`
/// is 2 int_0^1 E(mu) mu dmu of the interpolated function (exact: the compensation lobes built
/// from it then conserve energy to float precision, whatever the table's own quadrature error).
struct AlbedoTable {
  static constexpr int kN = 32;
  float e[kN] = {};
  float avg = 1.0f;
  float operator()(float mu) const {
    const float x = std::sqrt(std::min(std::max(mu, 0.0f), 1.0f)) * static_cast<float>(kN - 1);
    const int i = std::min(static_cast<int>(x), kN - 2);
    const float t = x - static_cast<float>(i);
    return e[i] + (e[i + 1] - e[i]) * t;
  }
  /// Fills e[k] = albedo(mu_k) (mu_0 = 0 is evaluated at 1e-4) and avg.
  template <class Fn>
  void fill(Fn&& albedo) {
    for (int k = 0; k < kN; ++k) {
      const double x = static_cast<double>(k) / (kN - 1);
      e[k] = static_cast<float>(albedo(std::max(x * x, 1e-4)));
    }
    // 2 int E mu dmu = 4 int_0^1 E(x) x^3 dx, E linear on [a, b]: closed form per segment.
    double s = 0.0;
    for (int k = 0; k + 1 < kN; ++k) {
      const double a = static_cast<double>(k) / (kN - 1), b = static_cast<double>(k + 1) / (kN - 1);
      const double h = b - a, a4 = a * a * a * a, b4 = b * b * b * b;
      const double i3 = (b4 - a4) / 4.0;                   // int x^3
      const double i4 = (b4 * b - a4 * a) / 5.0 - a * i3;  // int (x - a) x^3
      s += e[k] * i3 + (static_cast<double>(e[k + 1]) - e[k]) / h * i4;
    }
    avg = static_cast<float>(4.0 * s);
  }
};

/// Mean of w(wo, m) over the visible normals m of GGX for wo at cos theta = mu: a midpoint rule
/// on an n x n grid of the visible-normal sampler's unit square (ggx_sample_vndf maps it onto
/// the visible normals with their density, so this is int D_wo(m) w(m) dm), with the radial
/// coordinate u1 = 1 - (1 - v)^2 (weight 2 (1 - v)): the grid is denser where u1 -> 1, the
/// steep microfacets of GGX's long tail (uniform in u1, n = 64 misses 0.6 % of the albedo at
/// alpha = 0.09; with the substitution the error is below 1e-4 for alpha in [0.003, 1]).
template <class W>
double vndf_mean(double mu, float alpha, W&& w, int n = 64) {
  const float c = static_cast<float>(mu);
  const F3 wo(std::sqrt(std::max(0.0f, 1.0f - c * c)), 0.0f, c);
  double s = 0.0;
  for (int i = 0; i < n; ++i) {
    const double v = (i + 0.5) / n;
    const float u1 = static_cast<float>(1.0 - (1.0 - v) * (1.0 - v));
    double row = 0.0;
    for (int j = 0; j < n; ++j) {
      const F3 m = ggx_sample_vndf(wo, alpha, u1, (static_cast<float>(j) + 0.5f) / n);
      row += w(wo, m);
    }
    s += row * 2.0 * (1.0 - v);
  }
  return s / (static_cast<double>(n) * n);
}

/// Refraction of wo (unit, dot(wo, m) = c > 0) through the microfacet m, eta = n_t / n_i
/// (no total internal reflection: (1 - c^2) < eta^2).
inline F3 refract_m(F3 wo, F3 m, float c, float eta) {
  const float sin2_t = (1.0f - c * c) / (eta * eta);
  const float ct = std::sqrt(std::max(0.0f, 1.0f - sin2_t));
  return normalize(-wo * (1.0f / eta) + m * (c / eta - ct));
}

/// Single-scattering GGX albedo of the lobes, for wo at cos theta = mu:
/// conductor (Fresnel 1): the mean of G2 / G1 over the visible normals whose mirror direction
/// is above the surface; `fresnel_ior` > 1 weighs each by the dielectric Fresnel of the
/// microfacet (the specular layer over the diffuse lobe).
inline double ggx_reflection_albedo(double mu, float alpha, float fresnel_ior = 0.0f) {
  return vndf_mean(mu, alpha, [&](F3 wo, F3 m) {
    const F3 wi = reflect(wo, m);
    if (wi.z <= 0.0f) return 0.0;
    const float lo = ggx_lambda(wo, alpha), li = ggx_lambda(wi, alpha);
    const double g = (1.0 + lo) / (1.0 + lo + li);
    return fresnel_ior > 1.0f ? g * fresnel_dielectric(dot(wo, m), fresnel_ior) : g;
  });
}

/// Single-scattering albedo of the rough dielectric seen from the side where n_t / n_i = eta:
/// reflected plus transmitted energy (the transmitted radiance times eta^2, i.e. without the
/// 1 / eta^2 radiance scaling), what the sampler of ShadingMaterial::sample_rough keeps.
inline double ggx_dielectric_albedo(double mu, float alpha, float eta) {
  return vndf_mean(mu, alpha, [&](F3 wo, F3 m) {
    const float c = dot(wo, m);
    const float fr = fresnel_dielectric(c, eta);
    const float lo = ggx_lambda(wo, alpha);
    double s = 0.0;
    const F3 wr = reflect(wo, m);
    if (wr.z > 0.0f) s += fr * (1.0 + lo) / (1.0 + lo + ggx_lambda(wr, alpha));
    if (fr < 1.0f) {
      const F3 wt = refract_m(wo, m, c, eta);
      if (wt.z < 0.0f) s += (1.0 - fr) * (1.0 + lo) / (1.0 + lo + ggx_lambda(wt, alpha));
    }
    return s;
  });
}

/// The compensation tables of one material (alpha, ior).
///
/// Conductor: f_ms = F_ms (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)), coloured by Kulla and
/// Conty's F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg)) (the light that leaves after 2, 3, ...
/// bounces, each reflecting F_avg, relative to the white case) with the hemispherical average
/// of Schlick's Fresnel F_avg = 2 int F mu dmu = (20 F0 + 1) / 21.
///
/// Specular layer over the diffuse lobe: the diffuse lobe is weighted by 1 - E_spec(mu_o), the
/// energy the (single-scattering, Fresnel-weighted) specular layer does not reflect, instead of
/// 1 - F(mu_o): both are the same for a smooth layer, and with E_spec a white material reflects
/// exactly what it receives (albedo scaling, as Blender's Principled BSDF does).
///
/// Rough dielectric, sides s = 0 (outside, eta_0 = ior) and 1 (inside, eta_1 = 1 / ior), E_s its
/// single-scattering albedo from side s: a compensation reflection lobe per side,
///   f_r,s = cr_s (1 - E_s(mu_o)) (1 - E_s(mu_i)) / pi,
/// and a transmission lobe (radiance convention: transmitted radiance scaled by 1 / eta^2)
///   f_t,s = ct_s (1 - E_s(mu_o)) (1 - E_s'(mu_i)) / pi,  s' the other side,
/// of which the fraction t_s of the missing energy 1 - E_s(mu_o) is transmitted. Constraints:
/// energy conservation per side, (1 - t_s) = cr_s (1 - E_s,avg) and t_s = eta_s^2 ct_s
/// (1 - E_s',avg); generalised reciprocity f_t,0 / n_0^2 = f_t,1 / n_1^2, i.e. ct_1 = ior^2 ct_0.
/// The free parameter is t_0 = 1 - F_avg(ior) (what a smooth interface transmits on average from
/// outside); t_1 follows (and if it would exceed 1, t_1 = 1 and t_0 follows).
struct MsTables {
  bool conductor = false, coat = false, dielectric = false;
  AlbedoTable cond;            ///< GGX reflection, Fresnel 1
  AlbedoTable spec;            ///< GGX reflection with the dielectric Fresnel of ior
  AlbedoTable diel[2];         ///< rough dielectric, reflection + transmission, from side 0 / 1
  float t[2] = {0.0f, 0.0f};   ///< transmitted fraction of the compensation lobe, per side
  float cr[2] = {0.0f, 0.0f};  ///< reflection coefficient, per side
  float ct[2] = {0.0f, 0.0f};  ///< transmission coefficient, per side
};

/// Hemispherical average of the dielectric Fresnel reflectance, 2 int F(mu, eta) mu dmu.
inline double fresnel_dielectric_avg(float eta, int n = 4096) {
  double s = 0.0;
  for (int i = 0; i < n; ++i) {
    const double mu = (i + 0.5) / n;
    s += fresnel_dielectric(static_cast<float>(mu), eta) * mu;
  }
  return 2.0 * s / n;
}

/// Builds the tables for the lobes asked for; a lobe whose single scattering already keeps all
/// but 1e-5 of the energy (a nearly smooth surface) is left uncompensated.
inline MsTables make_ms_tables(float alpha, float ior, bool conductor, bool coat, bool dielectric) {
  MsTables t;
  if (conductor) {
    t.cond.fill([&](double mu) { return ggx_reflection_albedo(mu, alpha); });
    t.conductor = 1.0f - t.cond.avg > 1e-5f;
  }
  if (coat && ior > 1.0f) {
    t.spec.fill([&](double mu) { return ggx_reflection_albedo(mu, alpha, ior); });
    t.coat = true;
  }
  if (dielectric && ior > 1.0f) {
    t.diel[0].fill([&](double mu) { return ggx_dielectric_albedo(mu, alpha, ior); });
    t.diel[1].fill([&](double mu) { return ggx_dielectric_albedo(mu, alpha, 1.0f / ior); });
    const double m0 = 1.0 - t.diel[0].avg, m1 = 1.0 - t.diel[1].avg;
    if (m0 > 1e-5 && m1 > 1e-5) {
      const double e2 = static_cast<double>(ior) * ior;
      double t0 = 1.0 - fresnel_dielectric_avg(ior);
      double ct0 = t0 / (e2 * m1);
      double t1 = ct0 * m0;
      if (t1 > 1.0) {
        t1 = 1.0;
        ct0 = 1.0 / m0;
        t0 = e2 * ct0 * m1;
      }
      t.t[0] = static_cast<float>(t0);
      t.t[1] = static_cast<float>(t1);
      t.cr[0] = static_cast<float>((1.0 - t0) / m0);
      t.cr[1] = static_cast<float>((1.0 - t1) / m1);
      t.ct[0] = static_cast<float>(ct0);
      t.ct[1] = static_cast<float>(ct0 * e2);
      t.dielectric = true;
    }
  }
  return t;
}

// ---------------------------------------------------------------------------------------------
// The material at one shading point and its BSDF (local shading frame, wo.z > 0).

struct ShadingMaterial {
  F3 base;  ///< base colour (textured), linear
  float metallic;
  float alpha;  ///< GGX alpha = max(roughness^2, min)
  float ior;
  float transmission;
  const MsTables* ms = nullptr;  ///< multiple-scattering compensation (none: single scattering)
  // Derived at the shading point for wo:
  float w_diel = 0, w_trans = 0;  ///< lobe weights (1-m)(1-t), (1-m)t
  float fd_o = 0;                 ///< dielectric Fresnel at cos_o (specular layer)
  float diff_o = 0;               ///< weight of the diffuse lobe: 1 - albedo of the layer above
  float p_spec = 0, p_diff = 0;   ///< strategy probabilities of the other lobes (sum 1 if any)
  float p_delta = 0;              ///< probability of the transmission (dielectric) lobe
  float eta = 1.0f;               ///< n_t / n_i of the dielectric seen from wo's side
  bool rough = false;             ///< the dielectric is rough (GGX), not a delta lobe
  bool has_other = false;         ///< has the specular / diffuse lobes
  bool has_nondelta = false;      ///< has any non-delta lobe (next-event estimation applies)
  F3 ms_c = F3(0.0f);             ///< conductor compensation: f_ms = ms_c (1 - E(mu_i))
  int side = 0;                   ///< side of the dielectric wo is on (0 outside, 1 inside)
  float q_ms = 0.0f;              ///< probability that sample_rough samples the compensation lobes
  float ms_o = 0.0f;      ///< 1 - E_side(mu_o) of the rough dielectric (0 without compensation)
  float lambda_o = 0.0f;  ///< Smith Lambda of wo (ggx_lambda depends on cos_o only)

  /// Transmission tint of one interface: the square root of the base colour.
  F3 sqrt_base() const { return {std::sqrt(base.x), std::sqrt(base.y), std::sqrt(base.z)}; }

  /// Alpha above which the transmission lobe is a rough dielectric (roughness >= ~0.055); also
  /// the alpha above which the multiple-scattering compensation tables are built.
  static constexpr float kRoughAlpha = 3e-3f;

  /// `front`: wo is on the outward side of the surface (the dielectric is entered). The eval and
  /// sample functions below must be given a wo with wo.z = cos_o.
  void prepare(float cos_o, bool front = true) {
    lambda_o = ggx_lambda(F3(0.0f, 0.0f, cos_o), alpha);
    w_trans = (1.0f - metallic) * transmission;
    eta = front ? ior : 1.0f / ior;
    rough = w_trans > 0.0f && alpha > kRoughAlpha && ior > 1.0f;
    w_diel = (1.0f - metallic) * (1.0f - transmission);
    fd_o = ior > 1.0f ? fresnel_dielectric(cos_o, ior) : 0.0f;
    diff_o = ms != nullptr && ms->coat ? 1.0f - ms->spec(cos_o) : 1.0f - fd_o;
    float s_ms = 0.0f;
    if (ms != nullptr && ms->conductor && metallic > 0.0f) {
      const float ea = ms->cond.avg, lost = 1.0f - ms->cond(cos_o);
      const F3 fa = base * (20.0f / 21.0f) + F3(1.0f / 21.0f);
      const F3 fms = fa * fa * ea *
                     F3(1.0f / (1.0f - fa.x * (1.0f - ea)), 1.0f / (1.0f - fa.y * (1.0f - ea)),
                        1.0f / (1.0f - fa.z * (1.0f - ea)));
      ms_c = fms * (metallic * lost * kInvPi / (1.0f - ea));
      s_ms = metallic * luminance(fms) * lost;
    }
    const float s_spec =
        (ior > 1.0f ? w_diel * fd_o : 0.0f) + metallic * luminance(fresnel_schlick(base, cos_o));
    const float s_diff = w_diel * diff_o * std::max(luminance(base), 1e-3f) + s_ms;
    const float s_nd = s_spec + s_diff;
    has_other = s_nd > 0.0f;
    has_nondelta = has_other || rough;
    p_spec = has_other ? s_spec / s_nd : 0.0f;
    p_diff = has_other ? 1.0f - p_spec : 0.0f;
    const float s_delta = w_trans;
    p_delta = (s_delta + s_nd) > 0.0f ? s_delta / (s_delta + s_nd) : 0.0f;
    if (rough && ms != nullptr && ms->dielectric) {
      side = front ? 0 : 1;
      ms_o = std::max(0.0f, 1.0f - ms->diel[side](cos_o));
      q_ms = std::min(ms_o, 0.95f);  // the single-scattering lobe is always sampled sometimes
    }
  }

  /// The rough dielectric lobe alone (without w_trans): f(wo, wi) (without the cosine; the
  /// transmission tinted by sqrt(base) and in the radiance convention, scaled by 1 / eta^2) and
  /// the solid-angle density with which sample_rough draws wi (reflection or transmission).
  /// Single scattering after Walter et al. 2007 (height-correlated G2) plus the compensation
  /// lobes of MsTables when `ms` has them.
  void eval_rough_dielectric(F3 wo, F3 wi, F3& f, float& pdf) const {
    f = F3(0.0f);
    pdf = 0.0f;
    if (wo.z <= 0.0f || wi.z == 0.0f) return;
    const float lo = lambda_o, li = ggx_lambda(wi, alpha);
    const float g2 = 1.0f / (1.0f + lo + li), g1o = 1.0f / (1.0f + lo);
    const float p_ss = 1.0f - q_ms;
    const bool comp = ms != nullptr && ms->dielectric && q_ms > 0.0f;
    if (wi.z > 0.0f) {
      const F3 h = normalize(wo + wi);
      const float d = ggx_d(h, alpha);
      const float fr = fresnel_dielectric(std::max(dot(wo, h), 0.0f), eta);
      float fv = fr * d * g2 / (4.0f * wo.z * wi.z);
      pdf = p_ss * fr * g1o * d / (4.0f * wo.z);
      if (comp) {
        fv += ms->cr[side] * ms_o * (1.0f - ms->diel[side](wi.z)) * kInvPi;
        pdf += q_ms * (1.0f - ms->t[side]) * wi.z * kInvPi;
      }
      f = F3(fv);
      return;
    }
    // Transmission: the microfacet normal is -(wo + eta wi), turned to wo's side.
    F3 h = normalize(-(wo + wi * eta));
    if (h.z < 0.0f) h = -h;
    const float co = dot(wo, h), ci = dot(wi, h);
    float fv = 0.0f;
    if (co > 0.0f && ci < 0.0f) {
      const float d = ggx_d(h, alpha);
      const float fr = fresnel_dielectric(co, eta);
      const float den = co + eta * ci;
      const float den2 = den * den;
      if (fr < 1.0f && den2 > 0.0f) {
        fv = (1.0f - fr) * d * g2 * co * -ci / (wo.z * -wi.z * den2);
        pdf = p_ss * (1.0f - fr) * g1o * co * d / wo.z * eta * eta * -ci / den2;
      }
    }
    if (comp) {
      fv += ms->ct[side] * ms_o * (1.0f - ms->diel[1 - side](-wi.z)) * kInvPi;
      pdf += q_ms * ms->t[side] * -wi.z * kInvPi;
    }
    f = sqrt_base() * fv;
  }

  /// Non-delta BSDF value f(wo, wi) (without the cosine) and its sampling pdf (solid angle:
  /// (1 - p_delta) times that of the other lobes, plus p_delta times that of the reflection of
  /// a rough dielectric). Both zero unless wi.z > 0: the refraction of a rough dielectric is
  /// only sampled, never evaluated here (no light is sampled below the surface).
  void eval(F3 wo, F3 wi, F3& f, float& pdf) const {
    f = F3(0.0f);
    pdf = 0.0f;
    if (!has_nondelta || wi.z <= 0.0f || wo.z <= 0.0f) return;
    if (has_other) {
      const F3 h = normalize(wo + wi);
      const float d = ggx_d(h, alpha);
      const float lo = lambda_o, li = ggx_lambda(wi, alpha);
      const float g2 = 1.0f / (1.0f + lo + li);
      const float g1o = 1.0f / (1.0f + lo);
      const float wh = std::max(dot(wo, h), 0.0f);
      const float spec = d * g2 / (4.0f * wo.z * wi.z);
      const float pdf_spec = g1o * d / (4.0f * wo.z);
      F3 spec_color(0.0f);
      if (ior > 1.0f && w_diel > 0.0f) spec_color += F3(w_diel * fresnel_dielectric(wh, ior));
      if (metallic > 0.0f) spec_color += fresnel_schlick(base, wh) * metallic;
      f = spec_color * spec + base * (w_diel * diff_o * kInvPi);
      if (ms != nullptr && ms->conductor && metallic > 0.0f) f += ms_c * (1.0f - ms->cond(wi.z));
      const float pdf_diff = wi.z * kInvPi;
      pdf = (1.0f - p_delta) * (p_spec * pdf_spec + p_diff * pdf_diff);
    }
    if (rough) {
      F3 fd;
      float pd;
      eval_rough_dielectric(wo, wi, fd, pd);
      f += fd * w_trans;
      pdf += p_delta * pd;
    }
  }

  /// Samples the rough dielectric (Walter et al. 2007, visible normals): with probability q_ms
  /// the compensation lobes (cosine-distributed, transmitted with probability t_side), otherwise
  /// a visible microfacet normal, then reflection with the probability of its Fresnel
  /// reflectance, otherwise refraction. On transmission returns true with wi (local, wi.z < 0
  /// unless the refraction failed) and the weight f |cos| / pdf of the whole lobe (both from
  /// eval_rough_dielectric, the radiance scaled by 1 / eta^2) times w_trans / p_delta. On
  /// reflection returns false with wi set (wi.z may be <= 0: no sample); the caller weighs it
  /// with eval.
  bool sample_rough(F3 wo, float u_fresnel, float u1, float u2, F3& wi, F3& weight) const {
    float u = u_fresnel;
    if (u < q_ms) {
      const F3 d = cosine_hemisphere(u1, u2);
      if (u / q_ms >= ms->t[side]) {
        wi = d;
        return false;
      }
      wi = F3(d.x, d.y, -d.z);
    } else {
      u = (u - q_ms) / (1.0f - q_ms);
      const F3 m = ggx_sample_vndf(wo, alpha, u1, u2);
      const float c = dot(wo, m);
      const float fr = fresnel_dielectric(c, eta);
      if (u < fr) {
        wi = reflect(wo, m);
        return false;
      }
      wi = refract_m(wo, m, c, eta);
    }
    weight = F3(0.0f);
    if (wi.z >= 0.0f) return true;
    F3 f;
    float pdf;
    eval_rough_dielectric(wo, wi, f, pdf);
    if (pdf > 0.0f) weight = f * (-wi.z / pdf * (w_trans / p_delta));
    return true;
  }
};

}  // namespace mgn::pt
