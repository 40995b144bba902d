// Tests of the part merging of mgn/geometry/convex_decomposition (merge_volume_tolerance,
// merge_max_parts) against an analytic shape: an L-shaped prism, whose two arms merge into its
// convex hull at the cost of the notch (a right triangle: 1/7 of the hull's volume).
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/geometry/convex_decomposition.hpp>

#include <cmath>

namespace {

/// Closed L-shaped prism: the polygon (0,0) (2,0) (2,1) (1,1) (1,2) (0,2) times `s`, extruded to
/// height h. Volume 3 s^2 h; its convex hull 3.5 s^2 h.
mgn::Mesh l_prism(double s, double h) {
  const double xy[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  mgn::Points3f v(12, 3);
  for (int i = 0; i < 6; ++i) {
    v.row(i) << float(s * xy[i][0]), float(s * xy[i][1]), 0.f;
    v.row(6 + i) << float(s * xy[i][0]), float(s * xy[i][1]), float(h);
  }
  std::vector<Eigen::Vector3i> f;
  const int fan[4][2] = {{4, 5}, {5, 0}, {0, 1}, {1, 2}};
  for (const auto& t : fan) {
    f.emplace_back(6 + 3, 6 + t[0], 6 + t[1]);
    f.emplace_back(3, t[1], t[0]);
  }
  for (int i = 0; i < 6; ++i) {
    const int j = (i + 1) % 6;
    f.emplace_back(i, j, 6 + j);
    f.emplace_back(i, 6 + j, 6 + i);
  }
  mgn::Faces faces(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t k = 0; k < f.size(); ++k) faces.row(static_cast<Eigen::Index>(k)) = f[k];
  return mgn::Mesh(v, faces, {}, {}, {}, "l_prism");
}

double total_volume(const std::vector<mgn::Mesh>& parts) {
  double v = 0.0;
  for (const auto& p : parts) v += mgn::closed_mesh_volume(p);
  return v;
}

/// Largest signed distance of p outside a closed convex mesh (<= 0 inside).
double outside_distance(const mgn::Mesh& hull, const mgn::Vec3d& p) {
  const auto n = hull.face_normals();
  double worst = -1e300;
  for (Eigen::Index f = 0; f < hull.num_faces(); ++f) {
    const mgn::Vec3d a = hull.vertices().row(hull.faces()(f, 0)).cast<double>().transpose();
    worst = std::max(worst, n.row(f).cast<double>().dot(p - a));
  }
  return worst;
}

void expect_covers(const mgn::Mesh& m, const std::vector<mgn::Mesh>& parts) {
  for (Eigen::Index v = 0; v < m.num_vertices(); ++v) {
    const mgn::Vec3d p = m.vertices().row(v).cast<double>().transpose();
    double best = 1e300;
    for (const auto& part : parts) best = std::min(best, outside_distance(part, p));
    EXPECT_LE(best, 1e-6) << "vertex " << v << " outside every part";
  }
}

}  // namespace

TEST(ConvexMerge, SmallToleranceKeepsTheNotchLargeToleranceFillsIt) {
  const double s = 0.05, h = 0.02;
  const mgn::Mesh l = l_prism(s, h);
  const double v_hull = 3.5 * s * s * h;
  mgn::ConvexDecompositionOptions o;
  o.convex_volume_tolerance = 0.0;
  const auto plain = mgn::convex_decomposition(l, o);
  ASSERT_GE(plain.size(), 2u);
  // Filling the notch adds 1/7 of the hull's volume: a 10 % budget must not allow it ...
  o.merge_volume_tolerance = 0.10;
  const auto tight = mgn::convex_decomposition(l, o);
  ASSERT_GE(tight.size(), 2u);
  EXPECT_LE(tight.size(), plain.size());
  // The merges add at most the budget to the parts' total volume.
  EXPECT_LE(total_volume(tight), total_volume(plain) + 0.10 * v_hull + 1e-12);
  expect_covers(l, tight);
  // ... a 20 % budget must (one part, the hull).
  o.merge_volume_tolerance = 0.20;
  const auto loose = mgn::convex_decomposition(l, o);
  ASSERT_EQ(loose.size(), 1u);
  EXPECT_NEAR(mgn::closed_mesh_volume(loose[0]), v_hull, 1e-6 * v_hull);
  expect_covers(l, loose);
}

TEST(ConvexMerge, PartCapIsHonouredAndEveryVertexStaysCovered) {
  // The L split finely (a tight concavity bound), then capped at 1, 2 and 3 parts.
  const mgn::Mesh l = l_prism(0.05, 0.02);
  mgn::ConvexDecompositionOptions o;
  o.convex_volume_tolerance = 0.0;
  o.max_concavity = 0.0005;
  const auto plain = mgn::convex_decomposition(l, o);
  for (int cap : {1, 2, 3}) {
    o.merge_max_parts = cap;
    const auto capped = mgn::convex_decomposition(l, o);
    EXPECT_LE(capped.size(), static_cast<std::size_t>(cap));
    EXPECT_GE(capped.size(), 1u);
    expect_covers(l, capped);
    for (const auto& p : capped) {
      const auto r = p.validate();
      EXPECT_TRUE(r.is_watertight && r.is_outward);
    }
    // Deterministic.
    const auto again = mgn::convex_decomposition(l, o);
    ASSERT_EQ(again.size(), capped.size());
    for (std::size_t i = 0; i < capped.size(); ++i)
      EXPECT_EQ(again[i].vertices(), capped[i].vertices());
  }
  o.merge_max_parts = -1;
  EXPECT_THROW(mgn::convex_decomposition(l, o), mgn::InvalidArgument);
  o.merge_max_parts = 0;
  o.merge_volume_tolerance = -0.1;
  EXPECT_THROW(mgn::convex_decomposition(l, o), mgn::InvalidArgument);
  o.merge_volume_tolerance = std::nan("");
  EXPECT_THROW(mgn::convex_decomposition(l, o), mgn::InvalidArgument);
}
