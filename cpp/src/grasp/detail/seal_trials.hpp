#pragma once
// Private: one deterministic seal trial per model, shared by SealModel and the calibration.
// Every trial gets the contact point c (object frame, m) and the unit outward normal n; the cup
// approaches along -n. The ray scene holds the object mesh only.
#include <mgn/grasp/seal_model.hpp>
#include <mgn/raytrace/ray_scene.hpp>

namespace mgn::detail {

/// Orthonormal u, v with (u, v, n) right-handed (deterministic for a given n).
void tangent_frame(const Vec3d& n, Vec3d& u, Vec3d& v);

/// Everything a trial needs; immutable, shared across threads.
struct SealContext {
  const RayScene& scene;
  const Cup& cup;
  /// Hole-check pattern: unit-disc points (x, y) in [-1, 1]^2 scaled by the cup radius at use.
  const std::vector<Eigen::Vector2d>& disc_pattern;
  /// Unit ring of cup.num_points points at angles (k + 1/2) 2 pi / N, then the centre (0, 0);
  /// built by SealModel (null: spring_trial builds its own).
  const std::vector<Eigen::Vector2d>* ring_pattern = nullptr;
};

/// The unit ring pattern described in SealContext::ring_pattern.
std::vector<Eigen::Vector2d> unit_ring(int num_points);

/// Force-based spring-mass model (docs/models.md §1). Fills `detail` when not null.
/// `nominal` (may be null: c itself) is the unperturbed contact point of a jittered trial; the
/// roof check measures from it, because the jitter moves the cup, not the surface (a trial
/// jittered below a flat surface must not find a "roof" above its contact).
SealFailure spring_trial(const SealContext& ctx, const Vec3d& c, const Vec3d& n, SealTrial* detail,
                         const Vec3d* nominal = nullptr);

/// Dex-Net 3.0 style strain model (docs/models.md §2). `quality` (may be null) gets 1 or 0.
SealFailure strain_trial(const SealContext& ctx, const Vec3d& c, const Vec3d& n, float* quality);

/// SuctionNet style smoothness model (docs/models.md §2). `quality` gets deform x fit in [0, 1];
/// the trial seals when quality >= smoothness_threshold.
SealFailure smoothness_trial(const SealContext& ctx, const Vec3d& c, const Vec3d& n,
                             float* quality);

/// Quality at or above which the smoothness model counts a trial as sealed.
constexpr float smoothness_threshold = 0.5f;

}  // namespace mgn::detail
