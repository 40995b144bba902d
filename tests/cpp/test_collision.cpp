// Tests of mgn/collision against analytic answers.
#include <gtest/gtest.h>
#include <mgn/collision/collision_model.hpp>
#include <mgn/core/error.hpp>
#include <mgn/geometry/primitives.hpp>

#include <cmath>

namespace {
mgn::Pose at(double x, double y = 0, double z = 0) {
  mgn::Pose X = mgn::Pose::Identity();
  X.translation() << x, y, z;
  return X;
}
}  // namespace

TEST(Collision, TwoBoxesMatchAnalyticDistance) {
  const mgn::CollisionModel a(mgn::make_box({0.1, 0.1, 0.1}));
  const mgn::CollisionModel b(mgn::make_box({0.2, 0.2, 0.2}));
  std::vector<mgn::Pose> xb;
  for (double x : {0.0, 0.1, 0.149, 0.151, 0.2, 0.5}) xb.push_back(at(x));
  const auto hit = mgn::collide(a, {mgn::Pose::Identity()}, b, xb);
  // At x = 0 the small box lies strictly inside the big one: surfaces do not touch (documented),
  // and the distance is the gap between the surfaces.
  const std::vector<std::uint8_t> expect_hit = {0, 1, 1, 0, 0, 0};
  EXPECT_EQ(hit, expect_hit);
  const auto d = mgn::distance(a, {mgn::Pose::Identity()}, b, xb);
  for (std::size_t i = 0; i < xb.size(); ++i) {
    const double x = xb[i].translation().x();
    const double analytic = i == 0 ? 0.05 : std::max(0.0, x - 0.15);
    EXPECT_NEAR(d.distance[i], analytic, 1e-7) << i;  // float32 vertices
    EXPECT_EQ(d.collide[i], expect_hit[i]);
  }
  // Closest points lie on the facing faces, in the world frame.
  EXPECT_NEAR(d.points_a(5, 0), 0.05, 1e-7);
  EXPECT_NEAR(d.points_b(5, 0), 0.4, 1e-7);
}

TEST(Collision, TwoSpheresMatchAnalyticDistance) {
  const double r1 = 0.05, r2 = 0.03;
  const mgn::CollisionModel a(mgn::make_sphere(r1, 256, 128));
  const mgn::CollisionModel b(mgn::make_sphere(r2, 256, 128));
  std::vector<mgn::Pose> xb;
  for (double s : {0.03, 0.07, 0.09, 0.12, 0.2})
    xb.push_back(at(s / std::sqrt(3.0), s / std::sqrt(3.0), s / std::sqrt(3.0)));
  const auto d = mgn::distance(a, {mgn::Pose::Identity()}, b, xb);
  for (std::size_t i = 0; i < xb.size(); ++i) {
    const double centre = xb[i].translation().norm();
    const double analytic = centre - r1 - r2;
    if (analytic < -1e-3) {
      EXPECT_TRUE(d.collide[i]) << i;
      EXPECT_EQ(d.distance[i], 0.0);
    } else if (analytic > 1e-3) {
      EXPECT_FALSE(d.collide[i]) << i;
      EXPECT_NEAR(d.distance[i], analytic, 2e-4) << i;  // tessellation error of inscribed spheres
    }
  }
}

TEST(Collision, BatchesBroadcastAndAreThreadIndependent) {
  const mgn::CollisionModel a(mgn::make_cylinder(0.03, 0.1, 32));
  const mgn::CollisionModel b(mgn::make_box({0.05, 0.08, 0.02}));
  std::vector<mgn::Pose> xs;
  for (int i = 0; i < 500; ++i) {
    mgn::Pose X =
        at(0.12 * std::sin(0.37 * i), 0.1 * std::cos(0.23 * i), 0.05 * std::sin(0.11 * i));
    X.rotate(Eigen::AngleAxisd(0.1 * i, mgn::Vec3d(1, 2, 3).normalized()));
    xs.push_back(X);
  }
  mgn::CollisionRequest one, two;
  one.num_threads = 1;
  two.num_threads = 2;
  const auto h1 = mgn::collide(a, {mgn::Pose::Identity()}, b, xs, one);
  const auto h2 = mgn::collide(a, {mgn::Pose::Identity()}, b, xs, two);
  EXPECT_EQ(h1, h2);
  int n_hit = 0;
  for (std::size_t i = 0; i < xs.size(); ++i) {
    EXPECT_EQ(h1[i], mgn::collide(a, mgn::Pose::Identity(), b, xs[i]));
    n_hit += h1[i];
  }
  EXPECT_GT(n_hit, 10);
  EXPECT_LT(n_hit, 490);
  EXPECT_THROW(mgn::collide(a, std::vector<mgn::Pose>(2), b, std::vector<mgn::Pose>(3)),
               mgn::InvalidArgument);
  mgn::Pose bad = mgn::Pose::Identity();
  bad.translation().y() = std::nan("");
  EXPECT_THROW(mgn::collide(a, mgn::Pose::Identity(), b, bad), mgn::InvalidArgument);
}
