// The force-based spring-mass seal model on canonical shapes (docs/models.md §1).
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/grasp/seal_model.hpp>
#include <mgn/grasp/wrench.hpp>

#include <cmath>

namespace {

mgn::Mesh placed(const mgn::Mesh& m, double x, double y, double z) {
  mgn::Pose X = mgn::Pose::Identity();
  X.translation() << x, y, z;
  return m.transformed(X);
}

/// A 20 x 20 cm block whose top face is the plane z = 0.
mgn::Mesh plane() { return placed(mgn::make_box({0.2, 0.2, 0.05}), 0, 0, -0.025); }

mgn::SealFailure nominal(const mgn::Mesh& mesh, const mgn::Vec3d& c, const mgn::Vec3d& n,
                         const mgn::Cup& cup = {}) {
  return mgn::SealModel(mesh, cup).trial(c, n).failure;
}

float robust_score(const mgn::Mesh& mesh, const mgn::Vec3d& c, const mgn::Vec3d& n,
                   std::uint64_t seed = 0) {
  mgn::SealModel model(mesh, mgn::Cup{});
  mgn::Points3f p(1, 3), nn(1, 3);
  p.row(0) = c.cast<float>().transpose();
  nn.row(0) = n.cast<float>().transpose();
  mgn::SealOptions o;
  o.seed = seed;
  return model.evaluate(p, nn, o).score[0];
}

const mgn::Vec3d kUp(0, 0, 1);

}  // namespace

TEST(SpringSeal, PlaneAlwaysSealsAndElasticForcesBalanceThePressure) {
  const mgn::Mesh m = plane();
  const mgn::Cup cup;
  const mgn::SealTrial t = mgn::SealModel(m, cup).trial({0.01, -0.02, 0.0}, kUp);
  EXPECT_EQ(t.failure, mgn::SealFailure::None);
  EXPECT_NEAR(t.total_elastic_force, cup.pressure_force(), 1e-9 * cup.pressure_force());
  EXPECT_LT(t.ring_force.cwiseAbs().maxCoeff(), 1e-6);  // no stretch on a plane
  EXPECT_FLOAT_EQ(robust_score(m, {0.0, 0.0, 0.0}, kUp), 1.0f);
}

TEST(SpringSeal, SpheresSealWhenLargeAndMissWhenSmallerThanTheCup) {
  const mgn::Cup cup;
  const double big = 20 * cup.radius, small = 0.5 * cup.radius;
  const mgn::Mesh large = mgn::make_sphere(big, 256, 128);
  EXPECT_EQ(nominal(large, {0, 0, big}, kUp), mgn::SealFailure::None);
  EXPECT_GE(robust_score(large, {0, 0, big}, kUp), 0.9f);
  const mgn::Mesh tiny = mgn::make_sphere(small, 64, 32);
  EXPECT_EQ(nominal(tiny, {0, 0, small}, kUp), mgn::SealFailure::Miss);
  // Elastic forces still sum to the pressure force on a curved surface.
  const mgn::SealTrial t =
      mgn::SealModel(mgn::make_sphere(4 * cup.radius, 256, 128), cup)
          .trial({0, 0, 4 * cup.radius}, mgn::Vec3d(0.1, 0.0, 1.0).normalized());
  if (t.elastic_force.size() > 0) {
    EXPECT_NEAR(t.total_elastic_force, cup.pressure_force(), 1e-9);
  }
}

TEST(SpringSeal, CylinderSealsAlongItsSideOnlyAboveARadiusThreshold) {
  const mgn::Cup cup;
  // Candidates on the side of a z-axis cylinder, normal along +x (robust 10-trial score).
  auto score = [&](double R) {
    return robust_score(mgn::make_cylinder(R, 0.2, 512), {R, 0, 0}, mgn::Vec3d::UnitX());
  };
  EXPECT_EQ(nominal(mgn::make_cylinder(0.93 * cup.radius, 0.2, 512), {0.93 * cup.radius, 0, 0},
                    mgn::Vec3d::UnitX()),
            mgn::SealFailure::Miss);
  float previous = 0.0f;
  for (double R : {0.0072, 0.008, 0.009, 0.010, 0.0125, 0.015, 0.02, 0.03, 0.05, 0.1}) {
    const float s = score(R);
    EXPECT_GE(s, previous) << "radius " << R;  // same seed: perturbations are shared
    previous = s;
  }
  EXPECT_LE(score(0.0072), 0.2f);
  EXPECT_FLOAT_EQ(score(0.02), 1.0f);
}

TEST(SpringSeal, SphereScoreGrowsWithRadius) {
  auto score = [](double R) { return robust_score(mgn::make_sphere(R, 256, 128), {0, 0, R}, kUp); };
  EXPECT_LE(score(0.008), 0.2f);
  EXPECT_GE(score(0.015), 0.9f);
  EXPECT_LE(score(0.008), score(0.010));
  EXPECT_LE(score(0.010), score(0.015));
}

TEST(SpringSeal, EdgeAndCornerFail) {
  const mgn::Mesh m = plane();  // top face spans x, y in [-0.1, 0.1]
  EXPECT_EQ(nominal(m, {0.1, 0.0, 0.0}, kUp), mgn::SealFailure::Miss);
  EXPECT_EQ(nominal(m, {0.1, 0.1, 0.0}, kUp), mgn::SealFailure::Miss);
  EXPECT_EQ(robust_score(m, {0.1, 0.0, 0.0}, kUp), 0.0f);
  EXPECT_EQ(robust_score(m, {0.1, 0.1, 0.0}, kUp), 0.0f);
  // Even with the bisecting normal the ring straddling a 90 degree edge is no reliable seal.
  EXPECT_LT(robust_score(m, {0.1, 0.0, 0.0}, mgn::Vec3d(1, 0, 1).normalized()), 0.75f);
}

TEST(SpringSeal, StepHigherThanTheCompensableHeightFails) {
  const mgn::Cup cup;
  for (double step : {0.010, 0.015}) {
    const mgn::Mesh base = plane();
    const mgn::Mesh block =
        placed(mgn::make_box({0.1, 0.2, step}), 0.05, 0, step / 2);  // x in [0, 0.1]
    const mgn::Mesh m = mgn::Mesh::merge({base, block});
    const mgn::SealFailure f = nominal(m, {-0.001, 0.0, 0.0}, kUp, cup);
    EXPECT_TRUE(f == mgn::SealFailure::Hill || f == mgn::SealFailure::Force)
        << mgn::failure_name(f);
  }
  // A smooth slope is no step: a plane tilted by 10 degrees seals at any point of its face.
  mgn::Pose X = mgn::Pose::Identity();
  X.rotate(Eigen::AngleAxisd(10.0 * M_PI / 180.0, mgn::Vec3d::UnitY()));
  const mgn::Mesh tilted = plane().transformed(X);
  const mgn::Vec3d n = X.linear() * kUp;
  EXPECT_EQ(nominal(tilted, X * mgn::Vec3d(0.03, 0.01, 0.0), n, cup), mgn::SealFailure::None);
}

TEST(SpringSeal, RingStiffnessUsesMetaGraspNetsCentimetreConvention) {
  const mgn::Cup cup;
  // A 1 cm spring: k = E 1e6 pi c2 / (N * 1).
  EXPECT_NEAR(cup.ring_stiffness(0.01), 0.02e6 * M_PI * 0.06241 / 128, 1e-9);
  EXPECT_NEAR(cup.ring_stiffness(0.005), 2.0 * cup.ring_stiffness(0.01), 1e-9);
}

TEST(SpringSeal, LowRidgeUnderTheLipSealsAndHighStepFailsByForce) {
  // A ridge 2 mm wide across the whole ring: the bellows lip bends over a 0.2 mm ridge (as a real
  // 14 mm bellows cup does) but not over a 3 mm one (below the compensable height of 7 mm, so it
  // is the force balance that decides).
  const mgn::Cup cup;
  auto ridge = [](double h) {
    return mgn::Mesh::merge({plane(), placed(mgn::make_box({0.002, 0.2, h}), 0.0, 0, h / 2)});
  };
  EXPECT_EQ(nominal(ridge(0.0002), {0.004, 0.0, 0.0}, kUp, cup), mgn::SealFailure::None);
  EXPECT_EQ(nominal(ridge(0.003), {0.004, 0.0, 0.0}, kUp, cup), mgn::SealFailure::Force);
}

TEST(SpringSeal, HoleInsideTheRingFailsByHole) {
  const mgn::Cup cup;
  const double hole = 0.5 * cup.radius, t = 0.01;
  // A plate with a square through-hole of half-width `hole`, made of four boxes around it.
  const double W = 0.1;
  const mgn::Mesh left = placed(mgn::make_box({W - hole, 2 * W, t}), -(W + hole) / 2, 0, -t / 2);
  const mgn::Mesh right = placed(mgn::make_box({W - hole, 2 * W, t}), (W + hole) / 2, 0, -t / 2);
  const mgn::Mesh front =
      placed(mgn::make_box({2 * hole, W - hole, t}), 0, -(W + hole) / 2, -t / 2);
  const mgn::Mesh back = placed(mgn::make_box({2 * hole, W - hole, t}), 0, (W + hole) / 2, -t / 2);
  const mgn::Mesh plate = mgn::Mesh::merge({left, right, front, back});
  EXPECT_EQ(nominal(plate, {0.0, 0.0, 0.0}, kUp, cup), mgn::SealFailure::Hole);
  EXPECT_EQ(nominal(plate, {0.03, 0.03, 0.0}, kUp, cup), mgn::SealFailure::None);
}

TEST(SpringSeal, RoofAboveTheCupFailsByObstruction) {
  const mgn::Mesh roof = placed(mgn::make_box({0.05, 0.05, 0.005}), 0, 0, 0.05);
  const mgn::Mesh m = mgn::Mesh::merge({plane(), roof});
  EXPECT_EQ(nominal(m, {0.0, 0.0, 0.0}, kUp), mgn::SealFailure::Obstruction);
  const mgn::Mesh low_roof =
      mgn::Mesh::merge({plane(), placed(mgn::make_box({0.05, 0.05, 0.005}), 0, 0, 0.02)});
  EXPECT_EQ(nominal(low_roof, {0.0, 0.0, 0.0}, kUp), mgn::SealFailure::Obstruction);
  EXPECT_EQ(nominal(m, {0.07, 0.07, 0.0}, kUp), mgn::SealFailure::None);  // away from the roof
}

TEST(SpringSeal, JitteredTrialsOnALargePlaneAllSealAwayFromItsEdge) {
  // The jitter moves the cup, not the surface: a trial whose point is jittered more than the
  // compensable height below a plane must not see a "roof" above its contact. A 4 mm jitter per
  // axis puts ~4 % of the trials more than h = 7 mm below the plane; every trial must still seal.
  const mgn::Mesh m = placed(mgn::make_box({0.6, 0.6, 0.05}), 0, 0, -0.025);
  mgn::SealModel model(m, mgn::Cup{});
  const int side = 15;
  mgn::Points3f p(side * side, 3), nn(side * side, 3);
  for (int i = 0; i < side * side; ++i) {
    p.row(i) << -0.1f + 0.2f * static_cast<float>(i % side) / (side - 1),
        -0.1f + 0.2f * static_cast<float>(i / side) / (side - 1), 0.0f;
    nn.row(i) << 0.0f, 0.0f, 1.0f;
  }
  mgn::SealOptions o;
  o.position_sigma = 0.004;
  o.seed = 3;
  const mgn::SealResult r = model.evaluate(p, nn, o);
  for (int i = 0; i < side * side; ++i) EXPECT_EQ(r.score[i], 1.0f) << "point " << i;
  mgn::SealOptions d;  // the default jitter (r / 4)
  d.seed = 4;
  for (float s : model.evaluate(p, nn, d).score) EXPECT_EQ(s, 1.0f);
}

TEST(SpringSeal, BatchIsDeterministicForSeedsAndThreads) {
  const double R = 0.01;  // borderline: trials differ
  const mgn::Mesh sphere = mgn::make_sphere(R, 128, 64);
  mgn::SealModel model(sphere, mgn::Cup{});
  const int n = 64;
  mgn::Points3f p(n, 3), nn(n, 3);
  for (int i = 0; i < n; ++i) {
    const double th = 0.2 + 2.5 * i / n, ph = 0.7 * i;
    const mgn::Vec3d d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
    p.row(i) = (R * d).cast<float>().transpose();
    nn.row(i) = d.cast<float>().transpose();
  }
  mgn::SealOptions one, two;
  one.num_threads = 1;
  two.num_threads = 2;
  one.seed = two.seed = 5;
  const auto a = model.evaluate(p, nn, one), b = model.evaluate(p, nn, two);
  EXPECT_EQ(a.score, b.score);
  EXPECT_EQ(a.trial_reason, b.trial_reason);
  EXPECT_EQ(a.reason, b.reason);
  EXPECT_EQ(a.trial_sealed.size(), static_cast<std::size_t>(n * 10));
  mgn::SealOptions other = one;
  other.seed = 6;
  EXPECT_NE(model.evaluate(p, nn, other).trial_reason, a.trial_reason);
}

TEST(SpringSeal, BadInputIsRejectedWithAClearError) {
  const mgn::Mesh m = plane();
  mgn::Cup zero;
  zero.radius = 0.0;
  EXPECT_THROW(mgn::SealModel(m, zero), mgn::InvalidArgument);
  mgn::Cup few;
  few.num_points = 3;
  EXPECT_THROW(mgn::SealModel(m, few), mgn::InvalidArgument);
  mgn::SealModel model(m, mgn::Cup{});
  mgn::Points3f p(1, 3), n(1, 3);
  p << 0, 0, 0;
  n << std::nanf(""), 0, 1;
  EXPECT_THROW(model.evaluate(p, n), mgn::InvalidArgument);
  n << 0, 0, 1;
  p << 0, 0, 0.05;  // 5 cm above the surface
  try {
    model.evaluate(p, n);
    FAIL() << "expected InvalidArgument";
  } catch (const mgn::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("not on the mesh"), std::string::npos);
  }
}

TEST(SuctionWrench, ScoresFollowTheBendingTorque) {
  // Unit mass, CoM 5 cm to the side of a contact on top: torque 0.4905 N m about a horizontal axis.
  mgn::Points3f c(3, 3), a(3, 3);
  c << 0, 0, 0.1, 0.05, 0, 0.1, 0, 0, 0.1;
  a << 0, 0, -1, 0, 0, -1, 1, 0, 0;  // from above (twice), and from the side
  const mgn::Vec3d com(0.05, 0, 0.1), g(0, 0, -1);
  const double r = 0.01, tau_max = 15.6 * r * M_PI * std::sqrt(2.0);
  const auto s = mgn::suction_wrench_scores(c, a, 1.0, com, g, r);
  EXPECT_NEAR(s[0], 1.0 - 9.81 * 0.05 / tau_max, 1e-6);
  EXPECT_FLOAT_EQ(s[1], 1.0f);  // directly above the CoM: no torque
  // From the side the same torque is about the approach axis's normal plane: still bending.
  EXPECT_NEAR(s[2], s[0], 1e-6);
  // Heavier objects score lower; the score saturates at 0.
  EXPECT_FLOAT_EQ(mgn::suction_wrench_scores(c, a, 100.0, com, g, r)[0], 0.0f);
  EXPECT_THROW(mgn::suction_wrench_scores(c, a, -1.0, com, g, r), mgn::InvalidArgument);
}
