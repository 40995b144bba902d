// Tests of the baseline seal models (strain, smoothness; cpp/src/grasp/seal_baselines.cpp) against
// analytic shapes, through the private trial interface.
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/grasp/cup.hpp>
#include <mgn/raytrace/ray_scene.hpp>

#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "grasp/detail/seal_trials.hpp"

#include "vogel_disc.hpp"

namespace {

using mgn::SealFailure;
using mgn::Vec3d;

using mgn_test::vogel_disc;

mgn::Mesh placed(const mgn::Mesh& mesh, const Vec3d& t) {
  mgn::Pose X = mgn::Pose::Identity();
  X.translation() = t;
  return mesh.transformed(X);
}

/// Box with corners lo and hi.
mgn::Mesh box_between(const Vec3d& lo, const Vec3d& hi) {
  return placed(mgn::make_box(hi - lo), 0.5 * (lo + hi));
}

/// One object in a ray scene plus a default cup and a 1000-point disc pattern.
struct Fixture {
  explicit Fixture(const mgn::Mesh& mesh)
      : scene(std::vector<mgn::RayGeometry>{mgn::RayGeometry{&mesh, mgn::Pose::Identity(), 0}}),
        pattern(vogel_disc(1000)),
        ctx{scene, cup, pattern} {}
  mgn::RayScene scene;
  mgn::Cup cup;
  std::vector<Eigen::Vector2d> pattern;
  mgn::detail::SealContext ctx;

  SealFailure strain(const Vec3d& c, const Vec3d& n, float* q = nullptr) const {
    return mgn::detail::strain_trial(ctx, c, n, q);
  }
  SealFailure smooth(const Vec3d& c, const Vec3d& n, float* q) const {
    return mgn::detail::smoothness_trial(ctx, c, n, q);
  }
};

const mgn::Cup kCup;           // default cup: r = 7 mm, H = 30 mm
const double r = kCup.radius;  // NOLINT
const Vec3d kUp = Vec3d::UnitZ();

}  // namespace

TEST(SealBaselines, LargeFlatBoxTopSealsInBothModels) {
  // 200 x 200 x 50 mm box, top face at z = 25 mm.
  Fixture f(mgn::make_box({0.2, 0.2, 0.05}));
  for (const Vec3d& c :
       {Vec3d(0.0, 0.0, 0.025), Vec3d(0.03, -0.05, 0.025), Vec3d(-0.08, 0.08, 0.025)}) {
    float qs = -1.0f, qm = -1.0f;
    EXPECT_EQ(f.strain(c, kUp, &qs), SealFailure::None);
    EXPECT_EQ(qs, 1.0f);
    EXPECT_EQ(f.smooth(c, kUp, &qm), SealFailure::None);
    EXPECT_GT(qm, 0.99f);
    EXPECT_LE(qm, 1.0f);
  }
}

TEST(SealBaselines, TiltedFlatFaceSealsInBothModels) {
  // The same box rotated about an oblique axis: n is not axis-aligned.
  const Eigen::AngleAxisd rot(0.7, Vec3d(1.0, 2.0, 0.5).normalized());
  mgn::Pose X = mgn::Pose::Identity();
  X.linear() = rot.toRotationMatrix();
  Fixture f(mgn::make_box({0.2, 0.2, 0.05}).transformed(X));
  const Vec3d n = rot * kUp;
  const Vec3d c = rot * Vec3d(0.01, 0.02, 0.025);
  float qs = -1.0f, qm = -1.0f;
  EXPECT_EQ(f.strain(c, n, &qs), SealFailure::None);
  EXPECT_EQ(qs, 1.0f);
  EXPECT_EQ(f.smooth(c, n, &qm), SealFailure::None);
  EXPECT_GT(qm, 0.99f);
}

TEST(SealBaselines, PointOneMillimetreFromTheEdgeMisses) {
  // Half of the ring hangs over the edge at x = 100 mm: projection rays miss in both models.
  Fixture f(mgn::make_box({0.2, 0.2, 0.05}));
  const Vec3d c(0.099, 0.0, 0.025);
  float qs = -1.0f, qm = -1.0f;
  EXPECT_EQ(f.strain(c, kUp, &qs), SealFailure::Miss);
  EXPECT_EQ(qs, 0.0f);
  EXPECT_EQ(f.smooth(c, kUp, &qm), SealFailure::Miss);
  EXPECT_EQ(qm, 0.0f);
}

TEST(SealBaselines, SmallSphereMissesLargeSphereSeals) {
  {
    Fixture f(mgn::make_sphere(0.5 * r, 128, 64));
    float q = -1.0f;
    EXPECT_EQ(f.strain(Vec3d(0, 0, 0.5 * r), kUp, &q), SealFailure::Miss);
    EXPECT_EQ(f.smooth(Vec3d(0, 0, 0.5 * r), kUp, &q), SealFailure::Miss);
    EXPECT_EQ(q, 0.0f);
  }
  {
    const double R = 20.0 * r;
    Fixture f(mgn::make_sphere(R, 256, 128));
    // At the pole and at a point on the equator.
    for (const auto& cn :
         {std::make_pair(Vec3d(0, 0, R), kUp), std::make_pair(Vec3d(R, 0, 0), Vec3d(1, 0, 0))}) {
      float qs = -1.0f, qm = -1.0f;
      EXPECT_EQ(f.strain(cn.first, cn.second, &qs), SealFailure::None);
      EXPECT_EQ(qs, 1.0f);
      EXPECT_EQ(f.smooth(cn.first, cn.second, &qm), SealFailure::None);
      EXPECT_GT(qm, 0.9f);
    }
  }
}

TEST(SealBaselines, CylinderSideStrainAndSmoothnessMonotoneInRadius) {
  const std::vector<double> radii = {1.2 * r, 2.0 * r, 5.0 * r};
  std::vector<float> quality;
  std::vector<SealFailure> strain;
  for (double rho : radii) {
    Fixture f(mgn::make_cylinder(rho, 0.1, 512));
    // On the side, between two mesh vertices, cup axis horizontal.
    const double phi = M_PI / 512.0;
    const Vec3d n(std::cos(phi), std::sin(phi), 0.0);
    const Vec3d c = rho * std::cos(phi) * n;  // on the flat facet
    float q = -1.0f;
    f.smooth(c, n, &q);
    quality.push_back(q);
    strain.push_back(f.strain(c, n));
  }
  // r_cyl = 1.2 r: neighbouring perimeter vertices differ by ~1.5 mm in height over a 2.9 mm chord
  // (12-13 % stretch) -> strain failure; 5 r is gentle enough to seal.
  EXPECT_EQ(strain[0], SealFailure::Strain);
  EXPECT_EQ(strain[2], SealFailure::None);
  EXPECT_LT(quality[0], quality[1]);
  EXPECT_LT(quality[1], quality[2]);
  EXPECT_LT(quality[2], 0.99f);
  for (float q : quality) {
    EXPECT_GE(q, 0.0f);
    EXPECT_LE(q, 1.0f);
  }
}

TEST(SealBaselines, StepUnderTheRingFails) {
  // Floor top at z = 0 for x in [-100, 100] mm, a 10 mm step up for x >= 0 (overlapping boxes).
  const mgn::Mesh floor = box_between({-0.1, -0.1, -0.05}, {0.1, 0.1, 0.0});
  const mgn::Mesh step = box_between({0.0, -0.1, -0.05}, {0.1, 0.1, 0.01});
  Fixture f(mgn::Mesh::merge({floor, step}));
  for (const Vec3d& c : {Vec3d(0.001, 0.0, 0.01), Vec3d(-0.002, 0.0, 0.0)}) {
    float qs = -1.0f, qm = -1.0f;
    EXPECT_EQ(f.strain(c, kUp, &qs), SealFailure::Strain);
    EXPECT_EQ(qs, 0.0f);
    EXPECT_EQ(f.smooth(c, kUp, &qm), SealFailure::Rough);
    EXPECT_LT(qm, 0.05f);
    EXPECT_GE(qm, 0.0f);
  }
  // Far from the step both models seal.
  EXPECT_EQ(f.strain(Vec3d(0.05, 0.0, 0.01), kUp), SealFailure::None);
  float q = -1.0f;
  EXPECT_EQ(f.smooth(Vec3d(-0.05, 0.0, 0.0), kUp, &q), SealFailure::None);
}

TEST(SealBaselines, ThroughHoleFailsWithHole) {
  // 100 x 100 x 5 mm plate (top at z = 0) with a square through hole of half-width 0.5 r, built
  // from four boxes; the ring (radius r > 0.5 r sqrt 2) lies on material, the disc does not.
  const double h = 0.5 * r, e = 0.05, t = 0.005;
  const mgn::Mesh plate = mgn::Mesh::merge(
      {box_between({-e, -e, -t}, {-h, e, 0.0}), box_between({h, -e, -t}, {e, e, 0.0}),
       box_between({-h, -e, -t}, {h, -h, 0.0}), box_between({-h, h, -t}, {h, e, 0.0})});
  Fixture f(plate);
  float qs = -1.0f, qm = -1.0f;
  EXPECT_EQ(f.strain(Vec3d::Zero(), kUp, &qs), SealFailure::Hole);
  EXPECT_EQ(qs, 0.0f);
  EXPECT_EQ(f.smooth(Vec3d::Zero(), kUp, &qm), SealFailure::Hole);
  EXPECT_EQ(qm, 0.0f);
  // Next to the hole (ring and disc on material) both seal.
  EXPECT_EQ(f.strain(Vec3d(0.02, 0.02, 0.0), kUp), SealFailure::None);
  EXPECT_EQ(f.smooth(Vec3d(0.02, 0.02, 0.0), kUp, &qm), SealFailure::None);
}

TEST(SealBaselines, DeterministicResults) {
  Fixture f(mgn::make_cylinder(2.0 * r, 0.1, 128));
  const std::vector<std::pair<Vec3d, Vec3d>> cases = {
      {Vec3d(2.0 * r, 0, 0), Vec3d(1, 0, 0)},
      {Vec3d(0.0, 0.0, 0.05), kUp},
      {Vec3d(0.9 * 2.0 * r, 0.2 * r, 0.01), Vec3d(0.9, 0.3, 0.1).normalized()},
      {Vec3d(2.0 * r, 0.0, 0.045), Vec3d(1, 0, 1).normalized()}};
  for (const auto& cn : cases) {
    float q1 = -1.0f, q2 = -2.0f, s1 = -1.0f, s2 = -2.0f;
    const SealFailure a1 = f.smooth(cn.first, cn.second, &q1);
    const SealFailure a2 = f.smooth(cn.first, cn.second, &q2);
    const SealFailure b1 = f.strain(cn.first, cn.second, &s1);
    const SealFailure b2 = f.strain(cn.first, cn.second, &s2);
    EXPECT_EQ(a1, a2);
    EXPECT_EQ(q1, q2);  // bit-identical
    EXPECT_EQ(b1, b2);
    EXPECT_EQ(s1, s2);
    EXPECT_EQ(a1 == SealFailure::None, q1 >= mgn::detail::smoothness_threshold);
  }
}

TEST(SealBaselines, NullQualityPointerAndUnnormalisedNormal) {
  Fixture f(mgn::make_box({0.2, 0.2, 0.05}));
  const Vec3d c(0.0, 0.0, 0.025);
  EXPECT_EQ(f.strain(c, 3.0 * kUp, nullptr), SealFailure::None);
  EXPECT_EQ(mgn::detail::smoothness_trial(f.ctx, c, 0.5 * kUp, nullptr), SealFailure::None);
}

TEST(SealBaselines, ImpossibleInputsThrowInvalidArgument) {
  Fixture f(mgn::make_box({0.2, 0.2, 0.05}));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  float q = 0.0f;
  EXPECT_THROW(f.strain(Vec3d(nan, 0, 0), kUp, &q), mgn::InvalidArgument);
  EXPECT_THROW(f.strain(Vec3d::Zero(), Vec3d::Zero(), &q), mgn::InvalidArgument);
  EXPECT_THROW(f.smooth(Vec3d::Zero(), Vec3d(0, nan, 1), &q), mgn::InvalidArgument);
  try {
    f.smooth(Vec3d(0, 0, std::numeric_limits<double>::infinity()), kUp, &q);
    FAIL() << "expected InvalidArgument";
  } catch (const mgn::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("smoothness_trial"), std::string::npos) << e.what();
  }
}
