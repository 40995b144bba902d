#include <mgn/core/error.hpp>
#include <mgn/grasp/cup.hpp>

#include <cmath>

namespace mgn {

namespace {
void require_positive(const char* field, double value) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw_error<InvalidArgument>("Cup.", field, ": expected a finite value > 0, got ", value);
  }
}
}  // namespace

void Cup::validate() const {
  require_positive("radius", radius);
  require_positive("youngs_modulus", youngs_modulus);
  require_positive("pressure_difference", pressure_difference);
  require_positive("compensable_height", compensable_height);
  require_positive("approach_height", approach_height);
  require_positive("c1", c1);
  require_positive("c2", c2);
  require_positive("outer_radius", outer_radius);
  require_positive("body_height", body_height);
  if (num_points < 6) {
    throw_error<InvalidArgument>(
        "Cup.num_points: expected >= 6 mass points (neighbour, second-neighbour and ",
        "opposite springs must be distinct), got ", num_points);
  }
  if (hole_rays < 1) throw_error<InvalidArgument>("Cup.hole_rays: expected >= 1, got ", hole_rays);
  if (outer_radius < radius) {
    throw_error<InvalidArgument>("Cup.outer_radius (", outer_radius, ") must be >= Cup.radius (",
                                 radius, ")");
  }
}

double Cup::pressure_force() const { return pressure_difference * 1e5 * M_PI * radius * radius; }

double Cup::compression_stiffness() const { return youngs_modulus * 1e6 * M_PI * c1 / num_points; }

double Cup::ring_stiffness(double rest_length) const {
  constexpr double kCentimetre = 0.01;  // m: the length unit c2 was fitted with
  return youngs_modulus * 1e6 * M_PI * c2 * kCentimetre / (num_points * rest_length);
}

}  // namespace mgn
