#include <mgn/core/error.hpp>
#include <mgn/grasp/wrench.hpp>

#include <cmath>

namespace mgn {

void SuctionWrenchOptions::validate() const {
  if (!(k > 0.0) || !std::isfinite(k))
    throw_error<InvalidArgument>("SuctionWrenchOptions.k must be finite and > 0, got ", k);
  if (!(gravity >= 0.0) || !std::isfinite(gravity)) {
    throw_error<InvalidArgument>(
        "SuctionWrenchOptions.gravity must be finite and >= 0 (m/s^2), got ", gravity);
  }
}

std::vector<float> suction_wrench_scores(const Points3f& contacts, const Points3f& approach,
                                         double mass, const Vec3d& com,
                                         const Vec3d& gravity_direction, double cup_radius,
                                         const SuctionWrenchOptions& options) {
  const char* fn = "suction_wrench_scores";
  if (contacts.rows() != approach.rows()) {
    throw_error<InvalidArgument>(fn, ": ", contacts.rows(), " contacts but ", approach.rows(),
                                 " approach directions; expected one per contact");
  }
  if (!(mass > 0.0) || !std::isfinite(mass))
    throw_error<InvalidArgument>(fn, ": mass must be > 0 kg, got ", mass);
  if (!(cup_radius > 0.0) || !std::isfinite(cup_radius)) {
    throw_error<InvalidArgument>(fn, ": cup_radius must be > 0 m, got ", cup_radius);
  }
  if (!com.allFinite()) throw_error<InvalidArgument>(fn, ": com must be finite");
  const double g_norm = gravity_direction.norm();
  if (!(g_norm > 0.0) || !std::isfinite(g_norm)) {
    throw_error<InvalidArgument>(fn, ": gravity_direction must be a finite non-zero vector");
  }
  options.validate();
  const Vec3d weight = mass * options.gravity * gravity_direction / g_norm;  // N
  const double tau_max = options.k * cup_radius * M_PI * std::sqrt(2.0);
  std::vector<float> score(static_cast<std::size_t>(contacts.rows()));
  for (Eigen::Index i = 0; i < contacts.rows(); ++i) {
    const Vec3d c = contacts.row(i).transpose().cast<double>();
    Vec3d z = approach.row(i).transpose().cast<double>();
    if (!c.allFinite() || !z.allFinite() || z.norm() == 0.0) {
      throw_error<InvalidArgument>(fn, ": contact ", i,
                                   " has a non-finite point or a zero approach direction");
    }
    z.normalize();
    const Vec3d tau = (com - c).cross(weight);
    // Torsion (about z) is resisted by friction, not by the seal: keep the bending part.
    const double bending = (tau - tau.dot(z) * z).norm();
    score[i] = static_cast<float>(1.0 - std::min(1.0, bending / tau_max));
  }
  return score;
}

}  // namespace mgn
