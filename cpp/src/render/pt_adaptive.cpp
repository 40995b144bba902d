#include <algorithm>
#include <cmath>
#include <cstddef>

#include "render/detail/pt_adaptive.hpp"

namespace mgn::pt {

namespace {

constexpr int kRadius = 4;  // 9x9 neighbourhood

/// Means over the (2r+1)^2 neighbourhood cut at the image border, from a summed-area table.
class BoxMean {
 public:
  BoxMean(int w, int h) : w_(w), h_(h), s_(static_cast<std::size_t>(w + 1) * (h + 1), 0.0) {}
  std::vector<float> operator()(const std::vector<float>& x) {
    for (int v = 0; v < h_; ++v) {
      double row = 0.0;
      for (int u = 0; u < w_; ++u) {
        row += x[static_cast<std::size_t>(v) * w_ + u];
        at(u + 1, v + 1) = at(u + 1, v) + row;
      }
    }
    std::vector<float> out(x.size());
    for (int v = 0; v < h_; ++v) {
      const int v0 = std::max(0, v - kRadius), v1 = std::min(h_, v + kRadius + 1);
      for (int u = 0; u < w_; ++u) {
        const int u0 = std::max(0, u - kRadius), u1 = std::min(w_, u + kRadius + 1);
        const double sum = at(u1, v1) - at(u0, v1) - at(u1, v0) + at(u0, v0);
        out[static_cast<std::size_t>(v) * w_ + u] =
            static_cast<float>(sum / (static_cast<double>(u1 - u0) * (v1 - v0)));
      }
    }
    return out;
  }

 private:
  double& at(int u, int v) { return s_[static_cast<std::size_t>(v) * (w_ + 1) + u]; }
  int w_, h_;
  std::vector<double> s_;
};

float lum(const float* c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

}  // namespace

std::vector<float> noise_estimate(const std::vector<float>& radiance,
                                  const std::vector<float>& albedo, int width, int height) {
  const std::size_t np = static_cast<std::size_t>(width) * height;
  std::vector<float> l(np), a(np), d(np);
  for (std::size_t i = 0; i < np; ++i) {
    l[i] = std::max(0.0f, lum(&radiance[3 * i]));
    a[i] = std::max(0.05f, lum(&albedo[3 * i]));
    d[i] = l[i] / a[i];
  }
  std::vector<float> sorted(l);
  const std::size_t k = std::min(np - 1, static_cast<std::size_t>(0.995 * static_cast<double>(np)));
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(k), sorted.end());
  const float exposure = 1.0f / std::max(sorted[k], 1e-6f);
  BoxMean box(width, height);
  const std::vector<float> md = box(d), ml = box(l);
  std::vector<float> dc(np), dc2(np), lc(np);
  for (std::size_t i = 0; i < np; ++i) {
    dc[i] = std::min(d[i], 4.0f * md[i] + 1e-3f);
    dc2[i] = dc[i] * dc[i];
    lc[i] = std::min(l[i], 4.0f * ml[i] + 1e-3f);
  }
  const std::vector<float> m1 = box(dc), m2 = box(dc2), mt = box(lc);
  std::vector<float> est(np);
  for (std::size_t i = 0; i < np; ++i) {
    const float var = std::max(0.0f, m2[i] - m1[i] * m1[i]);
    est[i] = var * a[i] * a[i] * std::pow(std::max(exposure * mt[i], 1e-3f), -1.1f);
    if (!std::isfinite(est[i])) est[i] = 0.0f;
  }
  return est;
}

std::vector<std::uint8_t> allocate_extra_samples(const std::vector<float>& estimate,
                                                 double mean_extra, int max_extra) {
  const std::size_t np = estimate.size();
  std::vector<std::uint8_t> extra(np, 0);
  if (np == 0 || max_extra <= 0 || !(mean_extra > 0.0)) return extra;
  std::vector<float> pos;
  pos.reserve(np);
  for (float e : estimate)
    if (e > 0.0f) pos.push_back(e);
  if (pos.empty()) return extra;
  std::sort(pos.begin(), pos.end());
  const double budget = std::round(mean_extra * static_cast<double>(np));
  // Samples given at threshold t: sum over j = 1..max_extra of #{est >= j t}.
  auto total = [&](double t) {
    double n = 0.0;
    for (int j = 1; j <= max_extra; ++j) {
      const float x = static_cast<float>(j * t);
      n += static_cast<double>(pos.end() - std::lower_bound(pos.begin(), pos.end(), x));
    }
    return n;
  };
  double lo = 0.0, hi = static_cast<double>(pos.back()) * 2.0;  // total(hi) = 0
  if (total(static_cast<double>(pos.front()) / max_extra) <= budget) {
    hi = static_cast<double>(pos.front()) / max_extra;  // every positive pixel gets max_extra
  } else {
    for (int it = 0; it < 200 && hi - lo > 1e-12 * hi; ++it) {
      const double mid = 0.5 * (lo + hi);
      (total(mid) <= budget ? hi : lo) = mid;
    }
  }
  for (std::size_t i = 0; i < np; ++i) {
    const float x = estimate[i];
    if (!(x > 0.0f)) continue;
    int e = 0;
    while (e < max_extra && x >= static_cast<float>((e + 1) * hi)) ++e;
    extra[i] = static_cast<std::uint8_t>(e);
  }
  return extra;
}

}  // namespace mgn::pt
