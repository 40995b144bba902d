#pragma once
/// @file antipodal.hpp  Antipodal robust sampling of parallel-jaw grasps (docs/models.md §5).
///
/// For every contact point p (object frame O, metres) with unit outward normal n, `probes` probes
/// are cast: the inward direction -n is tilted by Euler angles (x, y, z) ~ U(-tilt, tilt) and the
/// start point moved by U(-offset, offset) per axis, then placed `start_offset` outside the surface
/// along the tilted direction d. The ray from there along d collects its hits: q1 = the first hit
/// (entry), q2 = the second hit (where the ray leaves the material entered at q1). A probe is
/// accepted if 0 < |q2 - q1| < max_opening and both outward hit normals lie inside the friction
/// cone (half-angle atan(friction_coef)) of the closing line: angle(-n1, v) and angle(n2, v) at
/// most atan(mu), v = (q2 - q1)/|q2 - q1|. The analytic score of the point is accepted / probes.
///
/// For every accepted probe (all of them: the reference implementation skips the last one, mgn
/// does not) up to `approaches_tried` approach directions a = cos(t) e1 + sin(t) e2, t ~ U(0, 2pi)
/// (e1, e2 an orthonormal basis of the plane perpendicular to v) are tried in order and the first
/// `approaches_kept` collision-free ones are kept. Collision: the gripper meshes (palm, fingers at
/// the opening collision_opening(w)) posed by hand_pose() against the object with FCL, plus a
/// ray-parity test that catches a gripper part lying entirely inside the object. For box grippers
/// two exact pre-filters skip most FCL queries: an object surface point (vertex or one of 2048 even
/// samples) strictly inside a gripper box is a collision (this also rejects an object entirely
/// inside a box), and a hand whose boxes touch no bounding sphere of an object triangle cannot
/// touch the surface. Both are decided per approach in the grasp's cylindrical frame.
///
/// Determinism: point i draws from Rng(seed, first_index + i) only; results are identical for
/// any thread count and any split of the points into batches.

#include <mgn/core/types.hpp>
#include <mgn/geometry/mesh.hpp>
#include <mgn/grasp/gripper.hpp>

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

namespace mgn {

/// Parameters of the antipodal sampler (defaults: MetaGraspNet).
struct AntipodalOptions {
  int probes = 5;               ///< perturbed probes per contact point (>= 1)
  double tilt = M_PI / 16.0;    ///< rad, bound of each Euler angle of the tilt, in [0, pi/2)
  double offset = 0.005;        ///< m, bound of the start offset per axis (>= 0)
  double start_offset = 0.010;  ///< m, the ray starts this far outside the surface (> 0)
  double friction_coef = 0.41421356237309503;  ///< mu; cone half-angle atan(mu) (MGN: pi/8)
  int approaches_tried = 50;    ///< random approach directions tried per accepted probe (>= 0)
  int approaches_kept = 20;     ///< collision-free approaches kept per accepted probe (>= 0)
  bool check_collision = true;  ///< false: keep the first approaches_kept approaches unchecked
  std::uint64_t seed = 0;
  std::uint64_t first_index = 0;  ///< point i uses the random stream (seed, first_index + i)
  int num_threads = 0;            ///< 0 = all hardware threads

  /// Throws InvalidArgument "AntipodalOptions.<field> must be ..." naming the first field out of
  /// range.
  void validate() const;
};

/// One collision-free grasp and where it came from.
struct AntipodalGrasp {
  ParallelJawGrasp grasp;        ///< object frame, metres
  std::int64_t point_index = 0;  ///< row of the source contact point in the input
  int probe = 0;                 ///< which probe of that point produced it
  float score = 0.0f;            ///< analytic score of the source point (accepted / probes)
};

/// Output of a batch.
struct AntipodalResult {
  std::vector<float> point_score;        ///< (N) accepted probes / probes
  std::vector<std::int32_t> num_kept;    ///< (N) grasps kept for each point
  std::vector<AntipodalGrasp> grasps;    ///< ordered by point, then probe, then approach
  std::int64_t num_accepted_probes = 0;  ///< over all points
  std::int64_t num_colliding = 0;        ///< approaches rejected by the collision check
};

/// Immutable sampler of one object for one gripper: builds the ray scene and the collision
/// models once; sample() may be called from many threads.
class AntipodalSampler {
 public:
  /// Throws InvalidArgument if the mesh is empty or not watertight (no closed volume: the probes
  /// and the inside test need one), or if the gripper is invalid.
  AntipodalSampler(const Mesh& object, const ParallelJawGripper& gripper);
  ~AntipodalSampler();
  AntipodalSampler(const AntipodalSampler&) = delete;
  AntipodalSampler& operator=(const AntipodalSampler&) = delete;

  const ParallelJawGripper& gripper() const;

  /// Samples grasps at N contact points. points (N,3) m on the surface, normals (N,3) outward
  /// (normalised here; InvalidArgument if zero or not finite, or if the shapes differ).
  AntipodalResult sample(const Points3d& points, const Points3d& normals,
                         const AntipodalOptions& options = {}) const;

  /// Whether the gripper, opened at `opening` (m) and posed at X_OH (hand in the object frame),
  /// intersects the object (FCL surface contact of palm or fingers, or a part entirely inside it).
  /// The query of sample(), which adds the exact pre-filters above.
  bool collides(const Pose& X_OH, double opening) const;

  struct Impl;

 private:
  static bool part_inside_object(const Impl& m, const Pose& X_OH, double opening);
  std::unique_ptr<Impl> impl_;
};

/// One-shot convenience: AntipodalSampler(object, gripper).sample(points, normals, options).
AntipodalResult sample_antipodal_grasps(const Mesh& object, const Points3d& points,
                                        const Points3d& normals, const ParallelJawGripper& gripper,
                                        const AntipodalOptions& options = {});

}  // namespace mgn
