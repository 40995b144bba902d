// The path tracer's sampler (cpp/src/render/detail/pt_math.hpp): the samples of neighbouring
// pixels are one stratified (0, m, 2)-net per dimension pair, each pixel's own samples too, and
// no two samples of a block repeat. Truth: the definition of a (0, m, 2)-net in base 2 (every
// elementary box of area 2^-m holds exactly one point).
#include <gtest/gtest.h>

#include <cstdint>
#include <set>
#include <utility>
#include <vector>

#include "render/detail/pt_math.hpp"

namespace {

using mgn::pt::PixelSampler;
using mgn::pt::PixelStream;
using mgn::pt::Sample2;

/// True when the 2^m points are a (0, m, 2)-net: for every split a + b = m, each of the 2^a x 2^b
/// boxes holds exactly one point.
bool is_net(const std::vector<Sample2>& pts, int m) {
  if (pts.size() != (std::size_t{1} << m)) return false;
  for (int a = 0; a <= m; ++a) {
    const int b = m - a;
    std::vector<int> count(std::size_t{1} << m, 0);
    for (const Sample2& p : pts) {
      const int ix = static_cast<int>(p.x * static_cast<float>(1 << a));
      const int iy = static_cast<int>(p.y * static_cast<float>(1 << b));
      if (ix < 0 || ix >= (1 << a) || iy < 0 || iy >= (1 << b)) return false;
      if (++count[static_cast<std::size_t>(iy) * (1u << a) + ix] != 1) return false;
    }
  }
  return true;
}

/// Sample pair `pair` of the spp samples of every pixel in the n x n pixels at (u0, v0).
std::vector<Sample2> group(std::uint64_t stream, int u0, int v0, int n, int spp, int pair) {
  const int l = mgn::pt::ceil_log2(static_cast<std::uint32_t>(spp));
  std::vector<Sample2> pts;
  for (int v = v0; v < v0 + n; ++v)
    for (int u = u0; u < u0 + n; ++u) {
      const PixelStream ps = mgn::pt::pixel_stream(stream, u, v, l);
      for (int k = 0; k < spp; ++k)
        pts.push_back(PixelSampler(ps.seed, ps.base | static_cast<std::uint32_t>(k)).get(pair));
    }
  return pts;
}

TEST(PathSampler, NeighbouringPixelsAtOneSampleAreOneNet) {
  // 1 spp: every aligned 2x2, 4x4 and 8x8 group of pixels holds one point per elementary box,
  // in every dimension pair (pixel jitter, light point, BSDF direction, ...).
  const std::uint64_t stream = 0x1234567887654321ULL;
  for (int pair = 0; pair < 12; ++pair)
    for (int n : {2, 4, 8})
      for (int g = 0; g < 3; ++g) {
        const int u0 = 8 * (3 * g + 1), v0 = 8 * (5 * g + 2);
        const int m = 2 * (n == 2 ? 1 : n == 4 ? 2 : 3);
        EXPECT_TRUE(is_net(group(stream, u0, v0, n, 1, pair), m))
            << "pair " << pair << ", " << n << "x" << n << " pixels at (" << u0 << ", " << v0
            << ")";
      }
}

TEST(PathSampler, EachPixelAndEachPixelGroupAtFourSamplesAreNets) {
  const std::uint64_t stream = 99;
  for (int pair = 0; pair < 8; ++pair) {
    for (int p = 0; p < 20; ++p)  // one pixel's 4 samples: one per quadrant (and 1x4, 4x1)
      EXPECT_TRUE(is_net(group(stream, 3 * p, 7 * p, 1, 4, pair), 2)) << "pixel " << p;
    EXPECT_TRUE(is_net(group(stream, 64, 32, 2, 4, pair), 4));  // 2x2 pixels, 16 points
    EXPECT_TRUE(is_net(group(stream, 16, 48, 4, 4, pair), 6));  // 4x4 pixels, 64 points
  }
}

TEST(PathSampler, NoSampleRepeatsAndBlocksDiffer) {
  // Indices of one block are distinct for any spp (no overflow of the 32-bit index), and two
  // blocks (or two streams) do not share their scramble.
  for (int spp : {1, 3, 16, 1000, 1 << 20}) {
    const int l = mgn::pt::ceil_log2(static_cast<std::uint32_t>(spp));
    const std::set<int> ks = {0, spp / 2, spp - 1};
    std::set<std::pair<std::uint32_t, std::uint32_t>> seen;
    std::size_t inserted = 0;
    for (int v = 0; v < 64; ++v)
      for (int u = 0; u < 64; ++u) {
        const PixelStream ps = mgn::pt::pixel_stream(7, u, v, l);
        for (int k : ks) {
          seen.insert({ps.seed, ps.base | static_cast<std::uint32_t>(k)});
          ++inserted;
        }
      }
    EXPECT_EQ(seen.size(), inserted) << "spp " << spp;
  }
  EXPECT_NE(mgn::pt::pixel_stream(7, 0, 0, 0).seed, mgn::pt::pixel_stream(7, 64, 0, 0).seed);
  EXPECT_NE(mgn::pt::pixel_stream(7, 0, 0, 0).seed, mgn::pt::pixel_stream(7, 0, 64, 0).seed);
  EXPECT_NE(mgn::pt::pixel_stream(7, 0, 0, 0).seed, mgn::pt::pixel_stream(8, 0, 0, 0).seed);
}

TEST(PathSampler, SamplesAreUniformOverManyPixels) {
  // Each sample alone is uniform in [0,1)^2: the mean over 256 x 256 pixels at 1 spp is 1/2
  // and the variance 1/12 per coordinate, to within the sampling error.
  double sx = 0, sy = 0, sxx = 0, n = 0;
  for (int v = 0; v < 256; ++v)
    for (int u = 0; u < 256; ++u) {
      const PixelStream ps = mgn::pt::pixel_stream(5, u, v, 0);
      const Sample2 s = PixelSampler(ps.seed, ps.base).get(3);
      sx += s.x;
      sy += s.y;
      sxx += double(s.x) * s.x;
      n += 1;
    }
  EXPECT_NEAR(sx / n, 0.5, 0.005);
  EXPECT_NEAR(sy / n, 0.5, 0.005);
  EXPECT_NEAR(sxx / n - (sx / n) * (sx / n), 1.0 / 12.0, 0.002);
}

TEST(PathSampler, CachedPairSeedsGiveTheSameSamples) {
  // The path tracer passes a PairSeeds cache; a second implementation (the seeds hashed at
  // every call) must give the same bits, also when the pixel seed changes back and forth and
  // pairs are asked out of order.
  mgn::pt::PairSeeds cache;
  const std::uint64_t stream = 0x0DDC0FFEEULL;
  int checked = 0;
  for (int round = 0; round < 2; ++round)
    for (int u : {0, 70, 5, 130})
      for (int v : {3, 64}) {
        const PixelStream ps = mgn::pt::pixel_stream(stream, u, v, 2);
        for (std::uint32_t k = 0; k < 4; ++k)
          for (std::uint32_t pair : {7u, 0u, 31u, 2u, 12u}) {
            const Sample2 a = PixelSampler(ps.seed, ps.base | k, &cache).get(pair);
            const Sample2 b = PixelSampler(ps.seed, ps.base | k).get(pair);
            EXPECT_EQ(a.x, b.x) << "pixel (" << u << ", " << v << ") sample " << k << " pair "
                                << pair;
            EXPECT_EQ(a.y, b.y) << "pixel (" << u << ", " << v << ") sample " << k << " pair "
                                << pair;
            ++checked;
          }
      }
  EXPECT_EQ(checked, 2 * 4 * 2 * 4 * 5);
}

}  // namespace
