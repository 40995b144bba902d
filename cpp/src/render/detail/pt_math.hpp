#pragma once
// Private building blocks of the path tracer (path_tracer.cpp): a small float vector type, the
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
  x = ((x >> 8) & 0x00FF00FFu) | ((x & 0x00FF00FFu) << 8);
  return (x >> 16) | (x << 16);
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

/// Stream of one pixel: sample `index` of dimension pair `pair` is a point in [0,1)^2.
///
/// Point: i = owen_scramble(index, s) (a scrambled sample order), then dimension 0 (the
/// van der Corput radical inverse, reverse_bits(i)) and dimension 1 (Sobol) of point i, each
/// Owen-scrambled with its own seed. Written with owen_scramble(x) = rev(lk(rev(x))) and
/// rev(rev(x)) = x so that only the needed bit reversals are done.
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

class PixelSampler {
 public:
  /// `cache`, when given, supplies the pair seeds (same values, computed once per pixel seed).
  PixelSampler(std::uint32_t pixel_seed, std::uint32_t index, PairSeeds* cache = nullptr)
      : seed_(pixel_seed), rev_index_(reverse_bits(index)), table_(&sobol_table()), cache_(cache) {}
  Sample2 get(std::uint32_t pair) const {
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
// The material at one shading point and its BSDF (local shading frame, wo.z > 0).

struct ShadingMaterial {
  F3 base;  ///< base colour (textured), linear
  float metallic;
  float alpha;  ///< GGX alpha = max(roughness^2, min)
  float ior;
  float transmission;
  // Derived at the shading point for wo:
  float w_diel = 0, w_trans = 0;  ///< lobe weights (1-m)(1-t), (1-m)t
  float fd_o = 0;                 ///< dielectric Fresnel at cos_o (specular layer)
  float p_spec = 0, p_diff = 0;   ///< strategy probabilities of the other lobes (sum 1 if any)
  float p_delta = 0;              ///< probability of the transmission (dielectric) lobe
  float eta = 1.0f;               ///< n_t / n_i of the dielectric seen from wo's side
  bool rough = false;             ///< the dielectric is rough (GGX), not a delta lobe
  bool has_other = false;         ///< has the specular / diffuse lobes
  bool has_nondelta = false;      ///< has any non-delta lobe (next-event estimation applies)
  float lambda_o = 0;             ///< ggx_lambda(wo, alpha) (depends on cos_o only)

  /// Transmission tint of one interface: the square root of the base colour.
  F3 sqrt_base() const { return {std::sqrt(base.x), std::sqrt(base.y), std::sqrt(base.z)}; }

  /// Alpha above which the transmission lobe is a rough dielectric (roughness >= ~0.055).
  static constexpr float kRoughAlpha = 3e-3f;

  /// `cos_o`: wo.z of the wo later given to eval and sample_rough. `front`: wo is on the
  /// outward side of the surface (the dielectric is entered).
  void prepare(float cos_o, bool front = true) {
    w_trans = (1.0f - metallic) * transmission;
    eta = front ? ior : 1.0f / ior;
    rough = w_trans > 0.0f && alpha > kRoughAlpha && ior > 1.0f;
    w_diel = (1.0f - metallic) * (1.0f - transmission);
    fd_o = ior > 1.0f ? fresnel_dielectric(cos_o, ior) : 0.0f;
    lambda_o = ggx_lambda(F3(0.0f, 0.0f, cos_o), alpha);
    const float s_spec =
        (ior > 1.0f ? w_diel * fd_o : 0.0f) + metallic * luminance(fresnel_schlick(base, cos_o));
    const float s_diff = w_diel * (1.0f - fd_o) * std::max(luminance(base), 1e-3f);
    const float s_nd = s_spec + s_diff;
    has_other = s_nd > 0.0f;
    has_nondelta = has_other || rough;
    p_spec = has_other ? s_spec / s_nd : 0.0f;
    p_diff = has_other ? 1.0f - p_spec : 0.0f;
    const float s_delta = w_trans;
    p_delta = (s_delta + s_nd) > 0.0f ? s_delta / (s_delta + s_nd) : 0.0f;
  }

  /// Non-delta BSDF value f(wo, wi) (without the cosine) and its sampling pdf (solid angle:
  /// (1 - p_delta) times that of the other lobes, plus p_delta times that of the reflection of
  /// a rough dielectric). Both zero unless wi.z > 0: the refraction of a rough dielectric is
  /// only sampled, never evaluated here (no light is sampled below the surface).
  void eval(F3 wo, F3 wi, F3& f, float& pdf) const {
    f = F3(0.0f);
    pdf = 0.0f;
    if (!has_nondelta || wi.z <= 0.0f || wo.z <= 0.0f) return;
    const F3 h = normalize(wo + wi);
    const float d = ggx_d(h, alpha);
    const float lo = lambda_o, li = ggx_lambda(wi, alpha);
    const float g2 = 1.0f / (1.0f + lo + li);
    const float g1o = 1.0f / (1.0f + lo);
    const float wh = std::max(dot(wo, h), 0.0f);
    const float spec = d * g2 / (4.0f * wo.z * wi.z);
    const float pdf_spec = g1o * d / (4.0f * wo.z);
    if (has_other) {
      F3 spec_color(0.0f);
      if (ior > 1.0f && w_diel > 0.0f) spec_color += F3(w_diel * fresnel_dielectric(wh, ior));
      if (metallic > 0.0f) spec_color += fresnel_schlick(base, wh) * metallic;
      f = spec_color * spec + base * (w_diel * (1.0f - fd_o) * kInvPi);
      const float pdf_diff = wi.z * kInvPi;
      pdf = (1.0f - p_delta) * (p_spec * pdf_spec + p_diff * pdf_diff);
    }
    if (rough) {
      const float fr = fresnel_dielectric(wh, eta);
      f += F3(w_trans * fr * spec);
      pdf += p_delta * fr * pdf_spec;
    }
  }

  /// Samples the rough dielectric (Walter et al. 2007, visible normals): reflection with the
  /// probability of the microfacet's Fresnel reflectance, otherwise refraction. On refraction
  /// returns true with wi (local, wi.z < 0) and the weight f |cos| / pdf of this lobe, i.e.
  /// sqrt(base) G2 / G1 / eta^2 (radiance scaling) times w_trans / p_delta. On reflection
  /// returns false with wi set (wi.z may be <= 0: no sample); the caller weighs it with eval.
  bool sample_rough(F3 wo, float u_fresnel, float u1, float u2, F3& wi, F3& weight) const {
    const F3 m = ggx_sample_vndf(wo, alpha, u1, u2);
    const float c = dot(wo, m);
    const float fr = fresnel_dielectric(c, eta);
    if (u_fresnel < fr) {
      wi = reflect(wo, m);
      return false;
    }
    const float sin2_t = (1.0f - c * c) / (eta * eta);
    const float ct = std::sqrt(std::max(0.0f, 1.0f - sin2_t));
    wi = normalize(-wo * (1.0f / eta) + m * (c / eta - ct));
    const float lo = lambda_o, li = ggx_lambda(wi, alpha);
    const F3 tint(std::sqrt(base.x), std::sqrt(base.y), std::sqrt(base.z));
    weight = tint * ((1.0f + lo) / (1.0f + lo + li) * (w_trans / p_delta) / (eta * eta));
    return true;
  }
};

}  // namespace mgn::pt
