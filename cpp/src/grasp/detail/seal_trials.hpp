#pragma once
// Private: one deterministic seal trial per model, shared by SealModel and the calibration.
// Every trial gets the contact point c (object frame, m) and the unit outward normal n; the cup
// approaches along -n. The ray scene holds the object mesh only.
#include <mgn/grasp/seal_model.hpp>
#include <mgn/raytrace/ray_scene.hpp>

#include <cstdint>
#include <vector>

#include "raytrace/parallel_rays.hpp"

namespace mgn::detail {

/// Shortcut for the hole check "every disc ray hits the object" (parallel_all_hit): proves most
/// rays hit without tracing them and traces only the rest, so the answer is the one
/// parallel_all_hit gives for the whole bundle.
///
/// The disc rays are parallel and Z-ordered, so consecutive rays usually cross the same
/// triangle. Projected along the ray direction, each ray's origin is located by walking from
/// triangle to neighbouring triangle across the edge the point lies beyond (point location by
/// walking, starting at the triangle the centre ray hit). A ray is proven to hit when its
/// origin lies inside a triangle by more than `margin` from every edge and every vertex of that
/// triangle lies more than `margin` in front of the origin along the ray. The margin is 1e-5 of
/// the coordinate scale (object size plus the distance of the origins from the object frame
/// origin), ~80 float ulps: far above the float rounding of the ray origins and direction and of
/// Embree's triangle test, so Embree reports every proven ray occluded (every triangle is tested
/// the same way whatever the traversal finds first). Rays the walk cannot prove (near an edge,
/// at a mesh boundary or a non-manifold edge, too many steps) are traced with Embree.
class HoleWalker {
 public:
  explicit HoleWalker(const Mesh& mesh);

  /// Same answer as parallel_all_hit(scene, rays) for a scene holding only this mesh (identity
  /// pose); `start_face` (< 0: none) is a face near the disc centre (the centre ray's hit).
  /// `rays.tfar` must be infinite.
  bool all_hit(const RayScene& scene, const ParallelRays& rays, int start_face) const;

 private:
  Points3d vertices_;
  Faces faces_;
  /// neighbour_(f, k): the face across edge (k, k + 1) of face f; -1 at a boundary or a
  /// non-manifold edge.
  Faces neighbour_;
  Points3d edge_length_;  ///< (faces, 3): length of edge (k, k + 1), m
  double max_abs_coord_ = 0.0;
};

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
  /// Hole-check shortcut for the scene's mesh (null: every disc ray is traced).
  const HoleWalker* hole_walker = nullptr;
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
