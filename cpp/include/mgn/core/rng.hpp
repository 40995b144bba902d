#pragma once
/// @file rng.hpp  Per-item random streams.
///
/// Every stochastic step in mgn draws from a stream derived from (seed, item index), so a result
/// never depends on the thread count or the order of work. The generator (SplitMix64 seeding a
/// xoshiro256** state) and the distributions are implemented here, not taken from <random>, so the
/// numbers are the same with every standard library.

#include <cmath>
#include <cstddef>
#include <cstdint>

namespace mgn {

/// A small, fast, reproducible random generator for one item of work.
class Rng {
 public:
  /// Stream for item `index` of a job seeded with `seed`.
  Rng(std::uint64_t seed, std::uint64_t index);

  /// Next raw 64-bit value.
  std::uint64_t next_u64();
  /// Uniform double in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(next_u64() >> 11) * 0x1.0p-53; }
  /// Uniform double in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Uniform integer in [0, n) (n > 0), without modulo bias.
  std::uint64_t below(std::uint64_t n);
  /// Standard normal variate (Box-Muller; one value per call, deterministic).
  double normal();
  /// Normal variate with mean `mu` and standard deviation `sigma`.
  double normal(double mu, double sigma) { return mu + sigma * normal(); }
  /// Fills out[0, n) with independent standard normal variates, many times faster per value than
  /// normal() (for per-pixel noise). Box-Muller on both outputs, one next_u64() per pair: 32 bits
  /// for the radius (u in (0, 1] with 2^-33 resolution near 0, so |z| reaches 6.7) and 32 bits
  /// for the angle; log, sin and cos are mgn's own float polynomials (relative error < 1e-6),
  /// compiled without fused multiply-adds, so the values are the same with every C library and
  /// compiler. A different stream of values than normal(): the two do not mix.
  void normals(float* out, std::size_t n);

 private:
  std::uint64_t s_[4];
};

/// SplitMix64 finaliser; mixes a 64-bit value into a well-distributed one.
std::uint64_t mix64(std::uint64_t x);

}  // namespace mgn
