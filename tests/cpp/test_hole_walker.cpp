// The suction hole-check shortcut (detail::HoleWalker, cpp/src/grasp/seal_model.cpp) against
// brute force: tracing every disc ray with Embree (detail::parallel_all_hit). The walker proves
// rays without tracing them, so its answer must equal the brute-force answer for every bundle,
// on meshes with holes, seams of duplicated vertices, folds, two layers, silhouettes and rays
// through vertices and along edges.
#include <gtest/gtest.h>
#include <mgn/core/rng.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/raytrace/ray_scene.hpp>

#include <cmath>
#include <vector>

#include "grasp/detail/seal_trials.hpp"
#include "raytrace/parallel_rays.hpp"

#include "vogel_disc.hpp"

namespace {

using mgn::Vec3d;

using mgn_test::vogel_disc;

/// Bumpy square plate z = f(x, y) over [-L, L]^2 on a cells x cells grid (two triangles per
/// cell, upward normals). Cells in `holes` (row-major index) are left out. With `seam`, the
/// vertices of the middle column are duplicated for the right half (same positions, other
/// indices). With `lower`, a flat plate 5 mm below is added (a second layer).
mgn::Mesh plate(int cells, double L, const std::vector<int>& holes, bool seam, bool lower) {
  const int n = cells + 1;
  auto height = [](double x, double y) {
    return 0.002 * std::sin(180.0 * x) * std::cos(150.0 * y) + 0.05 * x * y;
  };
  std::vector<Eigen::Vector3f> v;
  auto vid = [&](int i, int j) { return i * n + j; };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double x = -L + 2.0 * L * j / cells, y = -L + 2.0 * L * i / cells;
      v.emplace_back(static_cast<float>(x), static_cast<float>(y),
                     static_cast<float>(height(x, y)));
    }
  }
  const int mid = cells / 2;
  std::vector<int> dup(static_cast<std::size_t>(n), -1);
  if (seam) {
    for (int i = 0; i < n; ++i) {
      dup[static_cast<std::size_t>(i)] = static_cast<int>(v.size());
      v.push_back(v[static_cast<std::size_t>(vid(i, mid))]);
    }
  }
  auto corner = [&](int i, int j, int cell_j) {
    if (seam && j == mid && cell_j >= mid) return dup[static_cast<std::size_t>(i)];
    return vid(i, j);
  };
  std::vector<Eigen::Vector3i> f;
  for (int i = 0; i < cells; ++i) {
    for (int j = 0; j < cells; ++j) {
      bool hole = false;
      for (int h : holes) hole = hole || h == i * cells + j;
      if (hole) continue;
      const int a = corner(i, j, j), b = corner(i, j + 1, j), c = corner(i + 1, j + 1, j),
                d = corner(i + 1, j, j);
      f.emplace_back(a, b, c);
      f.emplace_back(a, c, d);
    }
  }
  if (lower) {
    const int base = static_cast<int>(v.size());
    for (double y : {-L, L}) {
      for (double x : {-L, L})
        v.emplace_back(static_cast<float>(x), static_cast<float>(y), -0.005f);
    }
    f.emplace_back(base, base + 1, base + 3);
    f.emplace_back(base, base + 3, base + 2);
  }
  mgn::Points3f V(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) V.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  mgn::Faces F(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) F.row(static_cast<Eigen::Index>(i)) = f[i].transpose();
  return mgn::Mesh(V, F);
}

struct Counts {
  int all_hit = 0, some_miss = 0;
};

/// Random bundles over `mesh`: the walker's answer equals brute force for each.
Counts compare_random(const mgn::Mesh& mesh, const Vec3d& centre, double spread, int bundles,
                      std::uint64_t seed) {
  const mgn::RayScene scene({mgn::RayGeometry{&mesh, mgn::Pose::Identity(), 0}}, false);
  const mgn::detail::HoleWalker walker(mesh);
  const auto disc = vogel_disc(1000);
  mgn::Rng rng(seed, 0);
  Counts counts;
  for (int b = 0; b < bundles; ++b) {
    const Vec3d c = centre + Vec3d(rng.uniform(-spread, spread), rng.uniform(-spread, spread),
                                   rng.uniform(-spread, spread));
    Vec3d n(rng.normal(0.0, 0.4), rng.normal(0.0, 0.4), 1.0);
    if (b % 7 == 0) n = Vec3d(rng.normal(0.0, 1.0), rng.normal(0.0, 1.0), rng.normal(0.0, 1.0));
    n.normalize();
    Vec3d u, v;
    mgn::detail::tangent_frame(n, u, v);
    const double r = rng.uniform(0.001, 0.012);
    mgn::detail::ParallelRays rays{c + 0.03 * n, u, v, -n, disc.data(), 1000, r};
    // The start face: the centre ray's first hit (as the spring model does), a random face or
    // none.
    int start = -1;
    if (b % 3 == 0) {
      const Eigen::Vector2d zero(0.0, 0.0);
      mgn::detail::ParallelRays centre_ray = rays;
      centre_ray.offsets = &zero;
      centre_ray.count = 1;
      float t;
      mgn::Vec3f normal;
      mgn::detail::parallel_first_hits(scene, centre_ray, &t, &normal, &start);
    } else if (b % 3 == 1) {
      start = static_cast<int>(rng.uniform(0.0, static_cast<double>(mesh.num_faces()) - 1e-9));
    }
    const bool brute = mgn::detail::parallel_all_hit(scene, rays);
    EXPECT_EQ(walker.all_hit(scene, rays, start), brute) << "bundle " << b;
    ++(brute ? counts.all_hit : counts.some_miss);
  }
  return counts;
}

TEST(HoleWalker, PlateWithHolesSeamAndSecondLayerEqualsBruteForce) {
  const double L = 0.03;
  // Two one-cell holes (1 mm cells): a 1000-ray disc of radius >= 1 mm over one misses a few
  // rays only.
  const mgn::Mesh single = plate(60, L, {30 * 60 + 33, 12 * 60 + 40}, true, false);
  const Counts a = compare_random(single, Vec3d(0.0, 0.0, 0.0), 0.03, 1500, 11);
  // Both answers occur often (over the holes and over the plate border; elsewhere all hit).
  EXPECT_GT(a.all_hit, 300);
  EXPECT_GT(a.some_miss, 300);
  // The same plate over a second layer: rays through the holes hit the lower plate.
  const mgn::Mesh layered = plate(60, L, {30 * 60 + 33, 12 * 60 + 40}, true, true);
  const Counts b = compare_random(layered, Vec3d(0.0, 0.0, 0.0), 0.015, 800, 12);
  EXPECT_GT(b.all_hit, 200);
}

TEST(HoleWalker, SmallHoleFoundByWalkedBundle) {
  // A bundle centred on a single missing 1 mm cell: only the few rays over that cell miss, and
  // the walker (starting from the centre ray's face... which is missing: from a face nearby)
  // must not prove them.
  const double L = 0.03;
  const mgn::Mesh mesh = plate(60, L, {30 * 60 + 30}, false, false);
  const mgn::RayScene scene({mgn::RayGeometry{&mesh, mgn::Pose::Identity(), 0}}, false);
  const mgn::detail::HoleWalker walker(mesh);
  const auto disc = vogel_disc(1000);
  const Vec3d n(0.0, 0.0, 1.0);
  Vec3d u, v;
  mgn::detail::tangent_frame(n, u, v);
  for (int start = 0; start < static_cast<int>(mesh.num_faces()); start += 97) {
    mgn::detail::ParallelRays rays{Vec3d(0.0005, 0.0005, 0.03), u, v, -n, disc.data(), 1000, 0.005};
    EXPECT_FALSE(mgn::detail::parallel_all_hit(scene, rays));
    EXPECT_FALSE(walker.all_hit(scene, rays, start)) << "start face " << start;
  }
}

TEST(HoleWalker, RaysThroughVerticesAndAlongEdgesEqualBruteForce) {
  // A flat grid plate (1 mm cells) and bundles whose rays pass exactly through grid vertices
  // and along grid edges: no ray is provable by a margin, so the walker traces them all.
  const double L = 0.01;
  const int cells = 20;
  const mgn::Mesh flat = [&] {
    mgn::Mesh m = plate(cells, L, {}, true, false);
    mgn::Points3f V = m.vertices();
    V.col(2).setZero();
    return mgn::Mesh(V, m.faces());
  }();
  const mgn::RayScene scene({mgn::RayGeometry{&flat, mgn::Pose::Identity(), 0}}, false);
  const mgn::detail::HoleWalker walker(flat);
  std::vector<Eigen::Vector2d> grid;
  for (int i = -5; i <= 5; ++i) {
    for (int j = -5; j <= 5; ++j) {
      grid.emplace_back(0.001 * i, 0.001 * j);
      grid.emplace_back(0.001 * i + 0.0005, 0.001 * j);
    }
  }
  const Vec3d n(0.0, 0.0, 1.0);
  for (const Vec3d& base : {Vec3d(0.0, 0.0, 0.03), Vec3d(0.002, -0.003, 0.03)}) {
    mgn::detail::ParallelRays rays{
        base, Vec3d::UnitX(), Vec3d::UnitY(), -n, grid.data(), static_cast<int>(grid.size()), 1.0};
    const bool brute = mgn::detail::parallel_all_hit(scene, rays);
    EXPECT_TRUE(brute);
    EXPECT_EQ(walker.all_hit(scene, rays, 0), brute);
  }
  // Past the plate border: the rays beyond x = L miss.
  mgn::detail::ParallelRays off{Vec3d(L - 0.002, 0.0, 0.03),
                                Vec3d::UnitX(),
                                Vec3d::UnitY(),
                                -n,
                                grid.data(),
                                static_cast<int>(grid.size()),
                                1.0};
  EXPECT_FALSE(mgn::detail::parallel_all_hit(scene, off));
  EXPECT_FALSE(walker.all_hit(scene, off, 0));
}

TEST(HoleWalker, SphereSilhouettesAndBackFacesEqualBruteForce) {
  // A closed sphere (radius 2 cm): bundles from all around, some over the silhouette (partial
  // misses), some starting inside the sphere (back faces, faces behind the origins).
  const mgn::Mesh sphere = mgn::make_sphere(0.02, 48, 24);
  const Counts c = compare_random(sphere, Vec3d(0.0, 0.0, 0.02), 0.02, 1500, 13);
  EXPECT_GT(c.all_hit, 200);
  EXPECT_GT(c.some_miss, 200);
}

}  // namespace
