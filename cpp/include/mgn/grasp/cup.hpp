#pragma once
/// @file cup.hpp  Vacuum suction cup parameters (docs/models.md §1; MetaGraspNet defaults).

#include <string>

namespace mgn {

/// A suction cup as seen by the seal models. Lengths in metres.
struct Cup {
  std::string name = "bellows_14mm";
  double radius = 0.007;              ///< contact-ring radius r, m
  int num_points = 128;               ///< mass points N on the ring (>= 6)
  double youngs_modulus = 0.02;       ///< E as in the paper; stiffness uses E * 1e6
  double pressure_difference = 0.7;   ///< vacuum pressure difference, bar (1 bar = 1e5 Pa)
  double compensable_height = 0.007;  ///< h: largest centre-above-ring height (hill check), m
  double approach_height = 0.030;     ///< start height of the projection rays above c, m
  double c1 = 0.03768;                ///< fitted compression-spring constant
  double c2 = 0.06241;                ///< fitted ring-spring constant
  double outer_radius = 0.010;        ///< cup body radius for collision checks, m
  double body_height = 0.030;         ///< cup body (bellows) height for collision checks, m
  int hole_rays = 1000;               ///< rays of the hole check spread over the disc (>= 1)

  /// Throws InvalidArgument naming the first field that is not finite/positive/in range.
  void validate() const;

  /// Pressure force F_p = dp * 1e5 * pi * r^2, N.
  double pressure_force() const;
  /// Compression spring stiffness k_c = E * 1e6 * pi * c1 / N, N/m.
  double compression_stiffness() const;
  /// Ring spring stiffness for a spring of rest length L (m), N/m:
  /// k = E * 1e6 * pi * c2 / (N * L[cm]) = E * 1e6 * pi * c2 * 0.01 / (N * L[m]).
  /// MetaGraspNet fitted c2 with rest lengths in centimetres (its forces are otherwise SI); this
  /// keeps the published c2 — and any c2 fitted against it — meaning the same stiffness.
  double ring_stiffness(double rest_length) const;
};

}  // namespace mgn
