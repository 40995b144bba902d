#include <mgn/core/rng.hpp>

#include <algorithm>
#include <cstring>

namespace mgn {

std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

namespace {
inline std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
}  // namespace

Rng::Rng(std::uint64_t seed, std::uint64_t index) {
  // Derive a distinct, well-mixed starting point for every (seed, index) pair.
  std::uint64_t x = mix64(seed) ^ mix64(index + 0x632BE59BD9B4E019ULL);
  for (auto& s : s_) {
    x = mix64(x);
    s = x;
  }
  if ((s_[0] | s_[1] | s_[2] | s_[3]) == 0) s_[0] = 1;  // xoshiro must not start at zero
}

std::uint64_t Rng::next_u64() {
  // xoshiro256**
  const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
  const std::uint64_t t = s_[1] << 17;
  s_[2] ^= s_[0];
  s_[3] ^= s_[1];
  s_[1] ^= s_[2];
  s_[0] ^= s_[3];
  s_[2] ^= t;
  s_[3] = rotl(s_[3], 45);
  return result;
}

std::uint64_t Rng::below(std::uint64_t n) {
  if (n <= 1) return 0;
  // Rejection sampling on the top of the range removes modulo bias.
  const std::uint64_t limit = ~std::uint64_t(0) - (~std::uint64_t(0) % n);
  std::uint64_t x;
  do {
    x = next_u64();
  } while (x >= limit);
  return x % n;
}

double Rng::normal() {
  // Box-Muller; u1 in (0,1] avoids log(0).
  const double u1 = 1.0 - uniform();
  const double u2 = uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

namespace {

// Rng::normals() works on blocks of this many Box-Muller pairs.
constexpr std::size_t kPairs = 64;

inline float float_from_bits(std::int32_t i) {
  float f;
  std::memcpy(&f, &i, sizeof f);
  return f;
}

inline std::int32_t bits_of(float f) {
  std::int32_t i;
  std::memcpy(&i, &f, sizeof i);
  return i;
}

// The two normals of each pair of 32-bit words (a[i] for the radius, b[i] for the angle), one
// branch-free loop the compiler vectorises. This file is compiled with -ffp-contract=off and
// -fno-math-errno (cpp/CMakeLists.txt): the former keeps the rounding of every operation as
// written, the latter lets sqrt vectorise (its argument is never negative here).
void box_muller_block(const std::uint32_t* a, const std::uint32_t* b, float* z0, float* z1,
                      std::size_t n) {
  constexpr float kLn2 = 0.693147180559945309f;
  constexpr float kAngle = 0.785398163397448310f * 0x1p-31f;  // pi/4 per 2^31
  for (std::size_t i = 0; i < n; ++i) {
    // Radius: u = (k + 1/2) 2^-31 in (0, 1] from 31 bits, r = sqrt(-2 ln u).
    const float u = (static_cast<float>(static_cast<std::int32_t>(a[i] >> 1)) + 0.5f) * 0x1p-31f;
    // ln u = e ln 2 + ln m with m in [sqrt(1/2), sqrt(2)); ln m = 2 atanh(s), s = (m-1)/(m+1),
    // |s| <= 0.172, by its series to s^9 (truncation < 3e-9 relative).
    // (Selects are written as integer arithmetic so that the loop stays branch-free.)
    const std::int32_t bits = bits_of(u);
    const std::int32_t mantissa = bits & 0x007fffff;
    const std::int32_t fold = ((0x003504f3 - mantissa) >> 31) & 1;  // 1 if m would be > sqrt(2)
    const std::int32_t e = ((bits >> 23) - 127) + fold;
    const float m = float_from_bits(mantissa | (0x3f800000 - (fold << 23)));
    const float s = (m - 1.0f) / (m + 1.0f);
    const float s2 = s * s;
    const float ln_m =
        2.0f * s *
        (1.0f + s2 * (1.0f / 3.0f + s2 * (1.0f / 5.0f + s2 * (1.0f / 7.0f + s2 * (1.0f / 9.0f)))));
    const float ln_u = static_cast<float>(e) * kLn2 + ln_m;
    const float r = std::sqrt(-2.0f * ln_u);
    // Angle theta = q pi/2 + phi: quadrant q from the top 2 bits, phi in [-pi/4, pi/4) from the
    // other 30; sin and cos of phi by their Taylor series to phi^9 / phi^10 (truncation < 3e-9).
    const std::uint32_t q = b[i] >> 30;
    const float phi = static_cast<float>(static_cast<std::int32_t>(b[i] << 2)) * kAngle;
    const float p = phi * phi;
    const float sin_phi =
        phi * (1.0f - p * (1.0f / 6.0f) *
                          (1.0f - p * (1.0f / 20.0f) *
                                      (1.0f - p * (1.0f / 42.0f) * (1.0f - p * (1.0f / 72.0f)))));
    const float cos_phi =
        1.0f -
        p * 0.5f *
            (1.0f - p * (1.0f / 12.0f) *
                        (1.0f - p * (1.0f / 30.0f) *
                                    (1.0f - p * (1.0f / 56.0f) * (1.0f - p * (1.0f / 90.0f)))));
    // cos theta, sin theta = (c, s), (-s, c), (-c, -s), (s, -c) for q = 0, 1, 2, 3.
    const std::int32_t odd = -static_cast<std::int32_t>(q & 1u);  // all ones if q is odd
    const std::int32_t c_bits = bits_of(cos_phi), s_bits = bits_of(sin_phi);
    const std::int32_t sign_c = static_cast<std::int32_t>(((q + 1u) & 2u) << 30);
    const std::int32_t sign_s = static_cast<std::int32_t>((q & 2u) << 30);
    z0[i] = r * float_from_bits(((c_bits & ~odd) | (s_bits & odd)) ^ sign_c);
    z1[i] = r * float_from_bits(((s_bits & ~odd) | (c_bits & odd)) ^ sign_s);
  }
}

}  // namespace

void Rng::normals(float* out, std::size_t n) {
  std::uint32_t a[kPairs], b[kPairs];
  float z0[kPairs], z1[kPairs];
  while (n > 0) {
    const std::size_t pairs = std::min(kPairs, (n + 1) / 2);
    for (std::size_t i = 0; i < pairs; ++i) {
      const std::uint64_t x = next_u64();
      a[i] = static_cast<std::uint32_t>(x >> 32);
      b[i] = static_cast<std::uint32_t>(x);
    }
    box_muller_block(a, b, z0, z1, pairs);
    // The block's cosine outputs, then its sine outputs (all independent normals).
    const std::size_t take = std::min(n, 2 * pairs);
    std::copy(z0, z0 + pairs, out);
    std::copy(z1, z1 + (take - pairs), out + pairs);
    out += take;
    n -= take;
  }
}

}  // namespace mgn
