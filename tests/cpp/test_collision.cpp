// Tests of mgn/collision against analytic answers.
#include <gtest/gtest.h>
#include <mgn/collision/collision_model.hpp>
#include <mgn/collision/point_inside.hpp>
#include <mgn/core/error.hpp>
#include <mgn/geometry/primitives.hpp>

#include <cmath>
#include <random>

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

namespace {

/// Torus about the z axis (major radius R, minor radius r), u segments around z, v around the
/// tube; closed and non-convex (the hole).
mgn::Mesh make_torus(double R, double r, int nu, int nv) {
  mgn::Points3f V(nu * nv, 3);
  mgn::Faces F(2 * nu * nv, 3);
  const double two_pi = 2.0 * std::acos(-1.0);
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const double u = two_pi * i / nu, v = two_pi * j / nv;
      V.row(i * nv + j) << static_cast<float>((R + r * std::cos(v)) * std::cos(u)),
          static_cast<float>((R + r * std::cos(v)) * std::sin(u)),
          static_cast<float>(r * std::sin(v));
      const int a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = ((i + 1) % nu) * nv + (j + 1) % nv,
                d = i * nv + (j + 1) % nv;
      F.row(2 * a) << a, b, c;
      F.row(2 * a + 1) << a, c, d;
    }
  }
  return mgn::Mesh(V, F);
}

/// Random points in [-h, h]^3 that are farther than `margin` from the surface given by the signed
/// function `f` (negative inside, ~ distance near the surface), with their analytic answers.
template <class SignedDistance>
void expect_matches_analytic(const mgn::PointInsideTest& test, double h, double margin,
                             SignedDistance f, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-h, h);
  mgn::Points3d pts(n, 3);
  std::vector<std::uint8_t> expect(static_cast<std::size_t>(n));
  int kept = 0, num_inside = 0;
  while (kept < n) {
    const mgn::Vec3d p(U(rng), U(rng), U(rng));
    const double s = f(p);
    if (std::abs(s) < margin) continue;
    pts.row(kept) = p.transpose();
    expect[static_cast<std::size_t>(kept)] = s < 0.0;
    num_inside += s < 0.0;
    ++kept;
  }
  ASSERT_GT(num_inside, n / 20);  // both answers are exercised
  ASSERT_LT(num_inside, n - n / 20);
  const std::vector<std::uint8_t> got = test.contains_each(pts);
  ASSERT_EQ(got.size(), expect.size());
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(got[static_cast<std::size_t>(i)], expect[static_cast<std::size_t>(i)])
        << "point " << pts.row(i);
    // The single-point overload agrees with the batch.
    EXPECT_EQ(test.contains(mgn::Vec3d(pts.row(i).transpose())),
              expect[static_cast<std::size_t>(i)] != 0);
  }
}

}  // namespace

TEST(Collision, PointInsideBoxMatchesAnalytic) {
  const mgn::Vec3d half(0.05, 0.1, 0.15);
  const mgn::PointInsideTest test(mgn::make_box(2.0 * half));
  // Signed distance of an axis-aligned box.
  auto f = [&](const mgn::Vec3d& p) {
    const mgn::Vec3d q = p.cwiseAbs() - half;
    return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
  };
  expect_matches_analytic(test, 0.2, 1e-4, f, 2000, 1);
  // Points on the axes and diagonals (rays from them pass near edges and vertices of the box).
  EXPECT_TRUE(test.contains(mgn::Vec3d(0.0, 0.0, 0.0)));
  EXPECT_TRUE(test.contains(mgn::Vec3d(0.0, 0.0, 0.149)));
  EXPECT_TRUE(test.contains(mgn::Vec3d(0.049, 0.099, 0.149)));
  EXPECT_FALSE(test.contains(mgn::Vec3d(-0.051, -0.101, -0.151)));
  EXPECT_FALSE(test.contains(mgn::Vec3d(0.0, 0.0, 0.151)));
  // Far outside (rejected by the bounding box without a ray).
  EXPECT_FALSE(test.contains(mgn::Vec3d(1.0, 1.0, 1.0)));
}

TEST(Collision, PointInsideSphereMatchesAnalytic) {
  const double radius = 0.1;
  const mgn::PointInsideTest test(mgn::make_sphere(radius, 64, 32));
  // The polygonal sphere lies between radius * cos(pi / 32) and radius: keep points clear of
  // that shell.
  auto f = [&](const mgn::Vec3d& p) { return p.norm() - radius; };
  expect_matches_analytic(test, 0.12, 1.5e-3, f, 2000, 2);
  EXPECT_TRUE(test.contains(mgn::Vec3d(0.0, 0.0, 0.0)));  // the ray leaves through one face
}

TEST(Collision, PointInsideTorusMatchesAnalytic) {
  const double R = 0.1, r = 0.03;
  const mgn::PointInsideTest test(make_torus(R, r, 96, 48));
  // Distance to the tube's core circle minus r; the chords of the mesh are within 1e-3 of it.
  auto f = [&](const mgn::Vec3d& p) { return std::hypot(std::hypot(p.x(), p.y()) - R, p.z()) - r; };
  expect_matches_analytic(test, 0.14, 1e-3, f, 3000, 3);
  // The hole: the centre is outside although it is inside the bounding box, and a ray from it
  // crosses the tube twice.
  EXPECT_FALSE(test.contains(mgn::Vec3d(0.0, 0.0, 0.0)));
  EXPECT_FALSE(test.contains(mgn::Vec3d(0.0, 0.0, 0.02)));
  EXPECT_TRUE(test.contains(mgn::Vec3d(R, 0.0, 0.0)));
  EXPECT_TRUE(test.contains(mgn::Vec3d(0.0, -R, 0.02)));
}

TEST(Collision, PointInsideRejectsBadInput) {
  EXPECT_THROW(mgn::PointInsideTest(mgn::Mesh()), mgn::InvalidArgument);
  const mgn::PointInsideTest test(mgn::make_box({0.1, 0.1, 0.1}));
  EXPECT_THROW(test.contains(mgn::Vec3d(std::nan(""), 0.0, 0.0)), mgn::InvalidArgument);
  EXPECT_TRUE(test.contains_each(mgn::Points3d(0, 3)).empty());
}
