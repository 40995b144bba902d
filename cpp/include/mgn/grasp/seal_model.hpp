#pragma once
/// @file seal_model.hpp  Will a suction cup seal at a surface point? Batch evaluation.
///
/// A SealModel is built once from an object mesh (object frame O, metres) and a cup, and is then
/// immutable and thread-safe. evaluate() scores N candidates, each a contact point c on the
/// surface with its unit outward surface normal n (the cup approaches along -n). The robust score
/// of a candidate is the fraction of `num_trials` perturbed trials that seal (docs/models.md §1):
/// each trial rotates n by Euler angles ~ N(0, angle_sigma) and moves c by ~ N(0, (r/4)^2) per
/// axis. Trial perturbations come from the random stream (seed, candidate index), so results do
/// not depend on the thread count.
///
/// Three models share this interface:
///   - SealModelKind::Spring     the force-based spring-mass model of MetaGraspNet (default)
///   - SealModelKind::Strain     the Dex-Net 3.0 style cone-of-springs strain model
///   - SealModelKind::Smoothness the SuctionNet-1Billion style ring smoothness model
///
// clang-format off
/// Where the spring model differs from the public MetaGraspNet reference, and why:
///
/// | item | reference | mgn | why |
/// |---|---|---|---|
/// | units | cm lengths; forces in N, but the ring-spring stiffness takes its rest length in cm | SI, with Cup::ring_stiffness keeping the cm rest length | the published c2 was fitted that way; read in pure SI the ring is 100x stiffer than the calibrated cup and fails on 0.2 mm ridges |
/// | ring springs | forces paired with neighbouring indices in an ad-hoc order | each unordered pair once, equal and opposite forces on both ends | Newton's third law; symmetric rings give zero net force |
/// | projected points | float hit points | rebuilt in double from ray origin and distance | a plane gives exactly zero stretch |
/// | lip reach | not checked | a mass point whose compression k_c (delta - d_k) is negative fails ("force") | the lip cannot touch there |
/// | roof below the cup | seals on the roof | the centre ray stopped more than h above c fails ("obstruction") | the cup cannot reach c |
/// | centre ray misses, ring hits | "miss" | "hole" | the contact disc is open |
/// | hole check | 1000 random points | 1000-point Vogel spiral, Z-ordered | deterministic, denser near the centre, coherent packets |
// clang-format on
///
/// Behaviour pinned by tests (tests/cpp/test_seal_model.cpp): the ring tension on a convex surface
/// presses the lip onto it, so convex shapes are limited by geometry and reach (robust scores rise
/// monotonically with the radius of spheres and cylinders; below the cup radius the ring misses),
/// while sharp steps crossing the lip, edges and corners fail.

#include <mgn/core/types.hpp>
#include <mgn/geometry/mesh.hpp>
#include <mgn/grasp/cup.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace mgn {

class RayScene;

enum class SealModelKind : std::uint8_t { Spring = 0, Strain = 1, Smoothness = 2 };

/// Why a trial did not seal. The order is the order of the checks.
enum class SealFailure : std::uint8_t {
  None = 0,         ///< sealed
  Miss = 1,         ///< a projection ray missed the object (off an edge, or too small)
  Obstruction = 2,  ///< material above the cup (a ray from the ring upwards hits the mesh)
  Hill = 3,         ///< the centre sticks up more than the compensable height above the ring
  Hole = 4,         ///< a ray inside the ring disc went through the object
  Force = 5,        ///< force balance: the ring forces lift the lip off (or the lip cannot reach)
  Strain = 6,       ///< strain model: a spring stretched or compressed beyond its limit
  Rough = 7,        ///< smoothness model: score below the seal threshold
};

/// Human-readable name of a failure ("none", "miss", "obstruction", ...).
const char* failure_name(SealFailure f);

/// Options of a batch evaluation.
struct SealOptions {
  int num_trials = 10;           ///< perturbed trials per candidate (>= 1)
  double angle_sigma = 0.1;      ///< std of each Euler angle of the normal perturbation, rad
  double position_sigma = -1.0;  ///< std of the point jitter per axis, m (< 0: radius / 4)
  bool perturb = true;           ///< false: one deterministic trial at the nominal (c, n)
  /// Candidates must lie on the mesh: a ray along the normal within +-tolerance must hit it, m.
  double on_surface_tolerance = 1e-3;
  std::uint64_t seed = 0;
  /// Index of the first candidate in the whole job: candidate i uses stream (seed, first_index
  /// + i), so a job evaluated in chunks gives the same scores as in one call.
  std::uint64_t first_index = 0;
  int num_threads = 0;  ///< 0 = all hardware threads
  /// Throws InvalidArgument "SealOptions.<field> must be ..." naming the first field out of range.
  void validate() const;
};

/// Per-candidate results of evaluate().
struct SealResult {
  std::vector<float> score;                ///< (N) fraction of sealed trials in [0, 1]
  std::vector<std::uint8_t> trial_sealed;  ///< (N * T) 1 if trial t of candidate i sealed
  std::vector<std::uint8_t> trial_reason;  ///< (N * T) SealFailure of each trial
  std::vector<std::uint8_t>
      reason;  ///< (N) most frequent failure of the failed trials, None if all sealed
  /// Mean per-trial quality in [0, 1]: the smoothness model's continuous deform x fit; for the
  /// other models a trial's quality is 1 if sealed else 0 (so quality == score).
  std::vector<float> quality;
  int num_trials = 0;
};

/// Detailed outcome of one deterministic trial (for tests, plots and debugging).
struct SealTrial {
  SealFailure failure = SealFailure::None;
  Points3f ring_points;           ///< (N,3) projected ring points x_k (object frame), if projected
  Points3f ring_normals;          ///< (N,3) surface normals m_k at x_k
  Vec3d center = Vec3d::Zero();   ///< projected centre x_c
  Eigen::VectorXd elastic_force;  ///< (N) k_c (delta - d_k), N (spring model)
  Points3d ring_force;            ///< (N,3) summed ring-spring force F_k, N (spring model)
  double total_elastic_force = 0.0;  ///< sum of elastic_force, N (equals the pressure force)
};

/// Immutable seal model of one object for one cup.
class SealModel {
 public:
  /// Builds the model (copies the mesh into an Embree scene). Throws InvalidArgument for an empty
  /// mesh or an invalid cup.
  SealModel(const Mesh& mesh, const Cup& cup, SealModelKind kind = SealModelKind::Spring);
  ~SealModel();
  SealModel(const SealModel&) = delete;
  SealModel& operator=(const SealModel&) = delete;

  SealModelKind kind() const { return kind_; }
  const Cup& cup() const { return cup_; }

  /// Scores N candidates: points (N,3) on the surface and unit outward normals (N,3), object
  /// frame. Throws InvalidArgument for mismatched shapes, non-finite values, zero normals, or
  /// invalid options. Candidates whose ring misses the mesh simply fail ("miss").
  SealResult evaluate(const Points3f& points, const Points3f& normals,
                      const SealOptions& options = {}) const;

  /// One deterministic trial at (c, n) with every intermediate quantity (spring model details
  /// are filled only for SealModelKind::Spring).
  SealTrial trial(const Vec3d& point, const Vec3d& normal) const;

  /// Same model with another cup (e.g. during calibration); shares the ray scene.
  std::shared_ptr<const SealModel> with_cup(const Cup& cup) const;

  struct Impl;

 private:
  SealModel(std::shared_ptr<const Impl> impl, const Cup& cup, SealModelKind kind);
  std::shared_ptr<const Impl> impl_;
  Cup cup_;
  SealModelKind kind_;
};

}  // namespace mgn
