// Adaptive sampling of the path tracer (cpp/src/render/detail/pt_adaptive.hpp): the allocation
// of extra samples against a brute-force search over every candidate threshold, and the noise
// estimate on constructed images (flat = no noise; a noisy patch ranks above a flat textured
// region).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "render/detail/pt_adaptive.hpp"

namespace {

/// Smallest threshold t among the candidates est_i / j whose total sum min(max_e, floor(est/t))
/// stays within the budget, by trying every candidate; returns the allocation.
std::vector<int> brute_force(const std::vector<float>& est, double budget, int max_e) {
  std::vector<double> cand;
  for (float e : est)
    for (int j = 1; j <= max_e; ++j)
      if (e > 0.0f) cand.push_back(static_cast<double>(e) / j);
  std::sort(cand.begin(), cand.end());
  auto alloc = [&](double t) {
    std::vector<int> out(est.size(), 0);
    for (std::size_t i = 0; i < est.size(); ++i)
      if (est[i] > 0.0f)
        out[i] = std::min(max_e, static_cast<int>(std::floor(static_cast<double>(est[i]) / t)));
    return out;
  };
  for (double t : cand) {
    const std::vector<int> a = alloc(t);
    double total = 0.0;
    for (int x : a) total += x;
    if (total <= budget) return a;
  }
  return alloc(cand.empty() ? 1.0 : cand.back() * 2.0);
}

TEST(PathAdaptive, AllocationMatchesBruteForceAndKeepsTheBudget) {
  std::mt19937 rng(3);
  std::lognormal_distribution<float> dist(0.0f, 1.5f);
  for (int trial = 0; trial < 6; ++trial) {
    std::vector<float> est(400);
    for (float& e : est) e = dist(rng);
    for (int k = 0; k < 40; ++k) est[static_cast<std::size_t>(k) * 10] = 0.0f;  // no noise
    const int max_e = 1 + trial % 4;
    const double mean = 0.1 + 0.3 * trial;
    const std::vector<std::uint8_t> got = mgn::pt::allocate_extra_samples(est, mean, max_e);
    const std::vector<int> want = brute_force(est, std::round(mean * 400), max_e);
    double total = 0.0;
    int diff = 0;
    for (std::size_t i = 0; i < est.size(); ++i) {
      total += got[i];
      diff += std::abs(static_cast<int>(got[i]) - want[i]);
      EXPECT_LE(got[i], max_e);
      if (est[i] == 0.0f) {
        EXPECT_EQ(got[i], 0);
      }
      for (std::size_t k = 0; k < est.size(); ++k)  // more noise, never fewer samples
        if (est[k] > est[i]) {
          EXPECT_GE(got[k], got[i]);
        }
    }
    EXPECT_LE(total, std::round(mean * 400));
    EXPECT_LE(diff, 1) << "trial " << trial;  // at most a rounding tie at the threshold
    EXPECT_GT(total, 0.0);
  }
}

TEST(PathAdaptive, BudgetBeyondMaxGivesEveryNoisyPixelTheMax) {
  const std::vector<float> est = {0.0f, 1.0f, 2.0f, 0.5f};
  const std::vector<std::uint8_t> got = mgn::pt::allocate_extra_samples(est, 10.0, 3);
  EXPECT_EQ(got, (std::vector<std::uint8_t>{0, 3, 3, 3}));
  EXPECT_EQ(mgn::pt::allocate_extra_samples(est, 0.0, 3), std::vector<std::uint8_t>(4, 0));
}

TEST(PathAdaptive, NoiseEstimateSeesNoiseNotFlatTexture) {
  // 64 x 64 image: left half a textured but noise-free region (albedo and radiance alternate
  // together in stripes, so the radiance / albedo ratio is constant), right half a constant
  // albedo with a noisy radiance (one path sample of a grey surface), a dark bottom band.
  const int w = 64, h = 64;
  std::vector<float> rad(3 * w * h), alb(3 * w * h);
  std::mt19937 rng(5);
  std::exponential_distribution<float> noise(1.0f);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * w + u;
      float a = 0.5f, r = 0.5f;
      if (u < w / 2) {
        a = (u / 2) % 2 ? 0.8f : 0.2f;
        r = a;
      } else {
        r = 0.5f * noise(rng);
      }
      for (int c = 0; c < 3; ++c) {
        rad[3 * i + c] = r;
        alb[3 * i + c] = a;
      }
    }
  }
  const std::vector<float> est = mgn::pt::noise_estimate(rad, alb, w, h);
  double left = 0.0, right = 0.0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < 24; ++u) left += est[static_cast<std::size_t>(v) * w + u];
    for (int u = 40; u < w; ++u) right += est[static_cast<std::size_t>(v) * w + u];
  }
  EXPECT_NEAR(left, 0.0, 1e-6 * right);
  EXPECT_GT(right, 0.0);
  // A flat image has no noise anywhere.
  std::vector<float> flat(3 * w * h, 0.3f);
  for (float e : mgn::pt::noise_estimate(flat, flat, w, h)) EXPECT_NEAR(e, 0.0f, 1e-6f);
}

}  // namespace
