#pragma once
/// @file wrench.hpp  Wrench resistance scores of grasps under gravity (docs/models.md §3).

#include <mgn/core/types.hpp>

#include <vector>

namespace mgn {

/// Parameters of the suction wrench score.
struct SuctionWrenchOptions {
  /// tau_max = k * r * pi * sqrt(2) with r the cup radius (SuctionNet-1Billion uses k = 15.6 and
  /// r = 0.01 m, i.e. 0.693 N m). mgn scales by the actual cup radius so that larger cups resist
  /// more torque.
  double k = 15.6;
  double gravity = 9.81;  ///< m/s^2 (>= 0)
  /// Throws InvalidArgument "SuctionWrenchOptions.<field> must be ..." (k finite and > 0, gravity
  /// finite and >= 0).
  void validate() const;
};

/// Suction wrench score of each contact in [0, 1]: 1 - min(1, tau / tau_max), where tau is the
/// bending (torsion-free) part of the gravity torque about the contact, expressed in the contact
/// frame (z = approach direction into the surface).
///
/// @param contacts  (N,3) contact points, m (object frame or world, consistently with com)
/// @param approach  (N,3) unit approach directions, pointing into the surface
/// @param mass      object mass, kg (> 0)
/// @param com       centre of mass, m (same frame as contacts)
/// @param gravity_direction  unit direction of gravity in that frame (e.g. -z of the world)
/// @param cup_radius  m (> 0)
/// Throws InvalidArgument for mismatched shapes, non-finite input, non-positive mass/radius.
std::vector<float> suction_wrench_scores(const Points3f& contacts, const Points3f& approach,
                                         double mass, const Vec3d& com,
                                         const Vec3d& gravity_direction, double cup_radius,
                                         const SuctionWrenchOptions& options = {});

}  // namespace mgn
