// Test helper shared by the seal tests: evenly spread ray offsets over the unit disc.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <vector>

namespace mgn_test {

/// Vogel (sunflower) spiral of n points over the unit disc.
inline std::vector<Eigen::Vector2d> vogel_disc(int n) {
  std::vector<Eigen::Vector2d> pts(static_cast<std::size_t>(n));
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double rho = std::sqrt((i + 0.5) / n);
    pts[static_cast<std::size_t>(i)] =
        Eigen::Vector2d(rho * std::cos(i * golden), rho * std::sin(i * golden));
  }
  return pts;
}

}  // namespace mgn_test
