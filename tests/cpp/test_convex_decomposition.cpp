// Tests of mgn/geometry/convex_decomposition against analytic shapes.
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/geometry/convex_decomposition.hpp>
#include <mgn/geometry/primitives.hpp>

#include <cmath>

namespace {

/// Closed L-shaped prism: the polygon (0,0) (2,0) (2,1) (1,1) (1,2) (0,2) times `s`, extruded
/// to height h. Area 3 s^2, convex hull area 3.5 s^2 (the L's notch is a right triangle).
mgn::Mesh l_prism(double s, double h) {
  const double xy[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  mgn::Points3f v(12, 3);
  for (int i = 0; i < 6; ++i) {
    v.row(i) << float(s * xy[i][0]), float(s * xy[i][1]), 0.f;
    v.row(6 + i) << float(s * xy[i][0]), float(s * xy[i][1]), float(h);
  }
  std::vector<Eigen::Vector3i> f;
  // Caps: fan from the reflex vertex 3 (counter-clockwise from +z).
  const int fan[4][2] = {{4, 5}, {5, 0}, {0, 1}, {1, 2}};
  for (const auto& t : fan) {
    f.emplace_back(6 + 3, 6 + t[0], 6 + t[1]);  // top, +z
    f.emplace_back(3, t[1], t[0]);              // bottom, -z
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

}  // namespace

TEST(ConvexDecomposition, HullOfBoxIsTheBox) {
  const mgn::Mesh box = mgn::make_box({0.1, 0.2, 0.3});
  const mgn::Mesh hull = mgn::convex_hull(box);
  const auto r = hull.validate();
  EXPECT_TRUE(r.is_watertight);
  EXPECT_TRUE(r.is_outward);
  EXPECT_NEAR(r.signed_volume, 0.1 * 0.2 * 0.3, 1e-9);
  EXPECT_EQ(hull.num_vertices(), 8);
}

TEST(ConvexDecomposition, HullOfLPrismFillsTheNotch) {
  const mgn::Mesh l = l_prism(0.05, 0.02);
  const mgn::Mesh hull = mgn::convex_hull(l);
  EXPECT_TRUE(hull.validate().is_outward);
  EXPECT_NEAR(mgn::closed_mesh_volume(l), 3 * 0.05 * 0.05 * 0.02, 1e-10);
  EXPECT_NEAR(mgn::closed_mesh_volume(hull), 3.5 * 0.05 * 0.05 * 0.02, 1e-10);
}

TEST(ConvexDecomposition, ConvexShapesGiveTheirSingleHull) {
  for (const mgn::Mesh& m : {mgn::make_box({0.1, 0.05, 0.02}), mgn::make_sphere(0.04, 32, 16),
                             mgn::make_cylinder(0.03, 0.1, 48)}) {
    const auto parts = mgn::convex_decomposition(m);
    ASSERT_EQ(parts.size(), 1u);
    EXPECT_NEAR(mgn::closed_mesh_volume(parts[0]), mgn::closed_mesh_volume(m),
                1e-3 * mgn::closed_mesh_volume(m));  // hull merges near-coplanar facets
  }
}

TEST(ConvexDecomposition, LPrismSplitsIntoConvexPartsCoveringEveryVertex) {
  const mgn::Mesh l = l_prism(0.05, 0.02);
  const auto parts = mgn::convex_decomposition(l);
  ASSERT_GE(parts.size(), 2u);
  double sum = 0.0;
  for (const mgn::Mesh& p : parts) {
    const auto r = p.validate();
    EXPECT_TRUE(r.is_watertight && r.is_outward);
    // Each part is convex: it equals its own hull.
    EXPECT_NEAR(mgn::closed_mesh_volume(mgn::convex_hull(p)), r.signed_volume,
                1e-9 + 1e-6 * r.signed_volume);
    sum += r.signed_volume;
  }
  const double exact = 3 * 0.05 * 0.05 * 0.02;
  // The union is the L (parts may overlap a little); never the hull's 3.5/3 volume.
  EXPECT_GT(sum, 0.98 * exact);
  EXPECT_LT(sum, 1.08 * exact);
  for (Eigen::Index v = 0; v < l.num_vertices(); ++v) {
    const mgn::Vec3d p = l.vertices().row(v).cast<double>().transpose();
    double best = 1e300;
    for (const mgn::Mesh& part : parts) best = std::min(best, outside_distance(part, p));
    EXPECT_LE(best, 1e-6) << "vertex " << v << " outside every part";
  }
  // Deterministic.
  const auto again = mgn::convex_decomposition(l);
  ASSERT_EQ(again.size(), parts.size());
  for (std::size_t i = 0; i < parts.size(); ++i)
    EXPECT_EQ(again[i].vertices(), parts[i].vertices());
}

TEST(ConvexDecomposition, MaxPartsIsHonoured) {
  mgn::ConvexDecompositionOptions o;
  o.max_parts = 1;
  EXPECT_EQ(mgn::convex_decomposition(l_prism(0.05, 0.02), o).size(), 1u);
}

TEST(ConvexDecomposition, BadInputIsRejected) {
  EXPECT_THROW(mgn::convex_hull(mgn::Mesh()), mgn::InvalidArgument);
  EXPECT_THROW(mgn::convex_decomposition(mgn::Mesh()), mgn::InvalidArgument);
  mgn::Points3f flat(4, 3);
  flat << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0;
  EXPECT_THROW(mgn::convex_hull_of_points(flat), mgn::InvalidArgument);
  mgn::ConvexDecompositionOptions o;
  o.max_concavity = std::nan("");
  EXPECT_THROW(mgn::convex_decomposition(l_prism(0.05, 0.02), o), mgn::InvalidArgument);
  o = {};
  o.min_parts = 3;
  o.max_parts = 2;
  EXPECT_THROW(mgn::convex_decomposition(l_prism(0.05, 0.02), o), mgn::InvalidArgument);
}

TEST(ConvexDecomposition, GridSimplifiedInputStillCoversEveryVertex) {
  // Forced through the grid-clustering path (tiny face budget, coarse grid).
  const mgn::Mesh ring = mgn::make_cylinder(0.05, 0.02, 96);
  const mgn::Mesh l = l_prism(0.05, 0.02);
  for (const mgn::Mesh* m : {&l, &ring}) {
    mgn::ConvexDecompositionOptions o;
    o.max_hacd_faces = 4;
    o.grid_resolution = 8;
    o.convex_volume_tolerance = 0.0;
    const auto parts = mgn::convex_decomposition(*m, o);
    ASSERT_GE(parts.size(), 1u);
    for (Eigen::Index v = 0; v < m->num_vertices(); ++v) {
      const mgn::Vec3d p = m->vertices().row(v).cast<double>().transpose();
      double best = 1e300;
      for (const mgn::Mesh& part : parts) best = std::min(best, outside_distance(part, p));
      EXPECT_LE(best, 2e-5) << "vertex " << v;
    }
  }
  mgn::ConvexDecompositionOptions bad;
  bad.grid_resolution = 2;
  EXPECT_THROW(mgn::convex_decomposition(l_prism(0.05, 0.02), bad), mgn::InvalidArgument);
}
