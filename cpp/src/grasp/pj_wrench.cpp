// Soft-finger wrench score of parallel-jaw grasps (docs/models.md §5); the model is documented in
// pj_wrench.hpp.
#include <mgn/core/error.hpp>
#include <mgn/grasp/pj_wrench.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace mgn {

void PjWrenchOptions::validate() const {
  auto positive = [](const char* field, double v, const char* unit) {
    if (!(v > 0.0) || !std::isfinite(v))
      throw_error<InvalidArgument>("PjWrenchOptions.", field, " must be finite and > 0", unit,
                                   ", got ", v);
  };
  positive("friction", friction, "");
  positive("grip_force", grip_force, " (N)");
  positive("contact_radius", contact_radius, " (m)");
  positive("gravity", gravity, " (m/s^2)");
}

std::vector<float> pj_wrench_scores(const std::vector<ParallelJawGrasp>& grasps, double mass,
                                    const Vec3d& com, const Vec3d& gravity_direction,
                                    const PjWrenchOptions& o) {
  const char* fn = "pj_wrench_scores";
  if (!(mass > 0.0) || !std::isfinite(mass)) {
    throw_error<InvalidArgument>(fn, ": mass must be a finite value > 0 kg, got ", mass);
  }
  if (!com.allFinite()) throw_error<InvalidArgument>(fn, ": com must be finite");
  if (!gravity_direction.allFinite() || !(gravity_direction.norm() > 1e-12)) {
    throw_error<InvalidArgument>(fn, ": gravity_direction must be finite and non-zero");
  }
  o.validate();

  const Vec3d F = mass * o.gravity * gravity_direction.normalized();
  const double f = o.grip_force;
  const double force_limit = o.friction * f;                                     // per contact, N
  const double torsion_limit = (2.0 / 3.0) * o.friction * o.contact_radius * f;  // per contact, N m
  std::vector<float> out(grasps.size());
  for (std::size_t i = 0; i < grasps.size(); ++i) {
    const ParallelJawGrasp& gr = grasps[i];
    if (!gr.p1.allFinite() || !gr.closing.allFinite() || !(gr.closing.norm() > 1e-12) ||
        !std::isfinite(gr.width)) {
      throw_error<InvalidArgument>(fn, ": grasp ", i,
                                   " has a non-finite point or width or a zero closing direction");
    }
    const Vec3d v = gr.closing.normalized();
    const Vec3d centre = gr.p1 + 0.5 * gr.width * v;
    const Vec3d tau = (com - centre).cross(F);
    const double f_t = 0.5 * (F - F.dot(v) * v).norm();
    const double tau_n = 0.5 * std::abs(tau.dot(v));
    const double u = std::hypot(f_t / force_limit, tau_n / torsion_limit);
    out[i] = u <= 1.0 ? 1.0f : static_cast<float>(1.0 / u);
  }
  return out;
}

}  // namespace mgn
