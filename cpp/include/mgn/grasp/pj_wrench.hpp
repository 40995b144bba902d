#pragma once
/// @file pj_wrench.hpp  Soft-finger wrench score of parallel-jaw grasps (docs/models.md §5).
///
/// Variant implemented (mgn): the object (mass m at centre of mass c) hangs under gravity
/// F = m g ĝ in the two fingers, each pressing with the normal force f = grip_force. Each contact
/// is a soft finger (Murray, Li, Sastry 1994) with an elliptic limit surface:
///     (f_t / (mu f))^2 + (tau_n / (gamma f))^2 <= 1,   gamma = (2/3) mu r
/// (gamma: the torsional friction of a disc of radius r = contact_radius under uniform pressure).
/// The load is shared equally by the two contacts: f_t = |F_t| / 2 with F_t the part of F
/// perpendicular to the closing axis v (the part along v is taken by the normal forces), and
/// tau_n = |tau . v| / 2 with tau = (c - g) x F the gravity torque about the grasp centre
/// g = p1 + (w/2) v. With the utilisation u = sqrt((f_t/(mu f))^2 + (tau_n/(gamma f))^2), the
/// score is min(1, 1/u): the ratio of the limit to the demand along the load direction, clipped
/// (1 when the grasp holds, lower the more the demand exceeds the limit; 1 for u = 0). For a
/// light object it reduces to min(1, 2 gamma f / |tau . v|), the ratio of the torsional limit of
/// both fingers to the torque about the closing axis. Bending torques (perpendicular to v) are
/// resisted by the couple of the two contacts and are not scored, as in the paper's s_pj,soft.

#include <mgn/core/types.hpp>
#include <mgn/grasp/gripper.hpp>

#include <vector>

namespace mgn {

/// Constants of the parallel-jaw wrench score.
struct PjWrenchOptions {
  double friction = 0.5;          ///< mu between finger pads and object (> 0)
  double grip_force = 70.0;       ///< N, normal force of each finger (Franka Hand: 70 N continuous)
  double contact_radius = 0.005;  ///< m, radius of the soft contact patch (> 0)
  double gravity = 9.81;          ///< m/s^2 (> 0)
  /// Throws InvalidArgument "PjWrenchOptions.<field> must be ..." for a field that is not finite
  /// and > 0.
  void validate() const;
};

/// Score in [0, 1] of each grasp (object frame; only p1, closing and width are used).
/// @param mass  kg (> 0)
/// @param com   centre of mass, m, same frame as the grasps
/// @param gravity_direction  direction of gravity in that frame (normalised here; e.g. -z)
/// Throws InvalidArgument for a non-positive or non-finite mass, option or gravity direction, or
/// a grasp with a non-finite point or a zero closing direction.
std::vector<float> pj_wrench_scores(const std::vector<ParallelJawGrasp>& grasps, double mass,
                                    const Vec3d& com, const Vec3d& gravity_direction,
                                    const PjWrenchOptions& options = {});

}  // namespace mgn
