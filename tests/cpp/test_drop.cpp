// Tests of mgn/scene/drop: settled objects lie in the tote without interpenetrating, the result
// is deterministic, tote contacts are named, and bad input is rejected.
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/geometry/convex_decomposition.hpp>
#include <mgn/geometry/mass_properties.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/geometry/sampling.hpp>
#include <mgn/physics/rigid_object.hpp>
#include <mgn/scene/drop.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <thread>

namespace {

/// The closed tote mesh of python/mgn/objects/tote.py make_tote() for a ToteBox.
mgn::Mesh tote_mesh(const mgn::ToteBox& b) {
  const double hx = b.inner_length / 2, hy = b.inner_width / 2;
  const double ox = hx + b.wall_thickness, oy = hy + b.wall_thickness;
  const double top = b.inner_height, bottom = -b.floor_thickness;
  const double c[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  mgn::Points3f v(16, 3);
  const double rings[4][3] = {{ox, oy, bottom}, {ox, oy, top}, {hx, hy, top}, {hx, hy, 0}};
  for (int r = 0; r < 4; ++r)
    for (int i = 0; i < 4; ++i)
      v.row(4 * r + i) << float(c[i][0] * rings[r][0]), float(c[i][1] * rings[r][1]),
          float(rings[r][2]);
  std::vector<Eigen::Vector3i> f = {{0, 2, 1}, {0, 3, 2}};
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) % 4;
    f.insert(f.end(), {{i, j, 4 + j},
                       {i, 4 + j, 4 + i},
                       {4 + i, 4 + j, 8 + j},
                       {4 + i, 8 + j, 8 + i},
                       {8 + i, 8 + j, 12 + j},
                       {8 + i, 12 + j, 12 + i}});
  }
  f.insert(f.end(), {{12, 13, 14}, {12, 14, 15}});
  mgn::Faces faces(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t k = 0; k < f.size(); ++k) faces.row(static_cast<Eigen::Index>(k)) = f[k];
  return mgn::Mesh(v, faces);
}

mgn::DropObject object_of(const mgn::Mesh& mesh, double density, const std::string& name) {
  const auto mp = mgn::compute_mass_properties(mesh, {density});
  mgn::DropObject o;
  o.convex_parts = mgn::convex_decomposition(mesh);
  o.mass = mp.mass;
  o.com = mp.center_of_mass;
  o.inertia = mp.inertia;
  o.friction = 0.5;
  o.restitution = 0.1;
  o.name = name;
  return o;
}

std::vector<mgn::Mesh> mixed_meshes() {
  return {mgn::make_box({0.10, 0.06, 0.04}),   mgn::make_sphere(0.03, 32, 16),
          mgn::make_cylinder(0.025, 0.10, 32), mgn::make_box({0.05, 0.05, 0.05}),
          mgn::make_box({0.15, 0.04, 0.02}),   mgn::make_cylinder(0.04, 0.03, 32),
          mgn::make_sphere(0.025, 32, 16),     mgn::make_box({0.08, 0.08, 0.03})};
}

/// Deepest point of `a` (sampled surface, world frame) inside the convex mesh `b` (world frame).
double penetration(const mgn::Mesh& a_world, const mgn::Mesh& b_world) {
  const auto s = mgn::sample_surface(a_world, 2000, {});
  const auto n = b_world.face_normals();
  double deepest = 0.0;
  for (Eigen::Index k = 0; k < s.points.rows(); ++k) {
    const mgn::Vec3d p = s.points.row(k).cast<double>().transpose();
    double depth = 1e300;  // min over faces of the distance inside that face's plane
    for (Eigen::Index f = 0; f < b_world.num_faces(); ++f) {
      const mgn::Vec3d q = b_world.vertices().row(b_world.faces()(f, 0)).cast<double>().transpose();
      depth = std::min(depth, -n.row(f).cast<double>().dot(p - q));
    }
    deepest = std::max(deepest, depth);
  }
  return deepest;
}

}  // namespace

TEST(Drop, SettledObjectsLieInTheToteWithoutInterpenetrating) {
  const mgn::ToteBox box;
  const mgn::Mesh tote = tote_mesh(box);
  const auto meshes = mixed_meshes();
  std::vector<mgn::DropObject> objects;
  for (std::size_t i = 0; i < meshes.size(); ++i)
    objects.push_back(object_of(meshes[i], 500, "obj" + std::to_string(i)));
  mgn::DropOptions o;
  o.seed = 7;
  const mgn::DropResult r = mgn::drop_objects(objects, tote, box, o);
  EXPECT_TRUE(r.settled);
  EXPECT_LT(r.simulated_time, o.max_time);
  EXPECT_LT(r.max_penetration, 0.003);
  std::vector<mgn::Mesh> world;
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    const auto& d = r.objects[i];
    ASSERT_TRUE(d.kept()) << "object " << i << " " << mgn::to_string(d.status);
    EXPECT_TRUE(d.settled);
    world.push_back(meshes[i].transformed(d.X_WO));
    const auto b = world.back().bounds();
    constexpr double tol = 0.002;
    EXPECT_GE(b(0, 2), -tol);
    EXPECT_GE(b(0, 0), -box.inner_length / 2 - tol);
    EXPECT_LE(b(1, 0), box.inner_length / 2 + tol);
    EXPECT_GE(b(0, 1), -box.inner_width / 2 - tol);
    EXPECT_LE(b(1, 1), box.inner_width / 2 + tol);
    // Released above the floor, at rest below where it was released.
    EXPECT_LT(d.X_WO.translation().z(), d.X_WO_release.translation().z());
    // Something holds it up: the floor, or (for a stacked object) not the floor.
    if (b(0, 2) < 0.002) {
      EXPECT_TRUE(d.contacts & mgn::ContactFloor) << i;
    }
  }
  for (std::size_t i = 0; i < world.size(); ++i)
    for (std::size_t j = 0; j < world.size(); ++j)
      if (i != j) {
        EXPECT_LT(penetration(world[i], world[j]), 0.003) << i << " in " << j;
      }
}

TEST(Drop, SameSeedSamePosesOtherSeedOtherPoses) {
  const mgn::ToteBox box;
  const mgn::Mesh tote = tote_mesh(box);
  std::vector<mgn::DropObject> objects;
  for (const auto& m : mixed_meshes()) objects.push_back(object_of(m, 700, "o"));
  mgn::DropOptions o;
  o.seed = 3;
  o.max_time = 1.0;
  const auto a = mgn::drop_objects(objects, tote, box, o);
  const auto b = mgn::drop_objects(objects, tote, box, o);
  o.seed = 4;
  const auto c = mgn::drop_objects(objects, tote, box, o);
  ASSERT_EQ(a.steps, b.steps);
  double diff_c = 0.0;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    EXPECT_EQ(a.objects[i].X_WO.matrix(), b.objects[i].X_WO.matrix());
    EXPECT_EQ(a.objects[i].contacts, b.objects[i].contacts);
    diff_c += (a.objects[i].X_WO_release.matrix() - c.objects[i].X_WO_release.matrix()).norm();
  }
  EXPECT_GT(diff_c, 0.1);
}

TEST(Drop, BallInANarrowChannelTouchesBothSideWallsAndTheFloor) {
  // Inner width 80.8 mm, ball diameter 80 mm released on the centre line: it must touch -y, +y and
  // the floor (each wall within contact_distance), and the floor. Every hull
  // vertex is kept and the margin is small: a reduced hull contains the ball and is wider, and
  // the margin widens it too, which would jam it between the rims.
  mgn::ToteBox box;
  box.inner_length = 0.3;
  box.inner_width = 0.0808;
  for (auto mode : {mgn::ToteCollision::Boxes, mgn::ToteCollision::TriangleMesh}) {
    mgn::DropOptions o;
    o.window_min = {0.0, 0.0, 0.2};
    o.window_max = {0.0, 0.0, 0.2};
    o.tote_collision = mode;
    o.max_hull_vertices = 0;
    o.collision_margin = 0.0002;
    const auto r = mgn::drop_objects({object_of(mgn::make_sphere(0.04, 64, 32), 300, "ball")},
                                     tote_mesh(box), box, o);
    ASSERT_TRUE(r.objects[0].kept());
    // (With exact geometry the ball may roll along the channel to an x wall; against the
    // triangle mesh, Bullet reports only the wall it leans on, 0.8 mm from the other.)
    const std::uint32_t c = r.objects[0].contacts;
    EXPECT_TRUE(c & mgn::ContactFloor) << "mode " << int(mode);
    if (mode == mgn::ToteCollision::Boxes) {
      EXPECT_TRUE((c & mgn::ContactWallMinusY) && (c & mgn::ContactWallPlusY));
    } else {
      EXPECT_TRUE((c & mgn::ContactWallMinusY) || (c & mgn::ContactWallPlusY));
    }
    EXPECT_NEAR(r.objects[0].X_WO.translation().z(), 0.04, 0.002);
  }
}

TEST(Drop, ObjectOverTheRimIsRemoved) {
  // A 160 mm rod dropped off-centre into a shallow 120 mm tray may end inside (along the
  // diagonal) or over the rim; either way `kept` must agree with "entirely inside the walls".
  mgn::ToteBox box;
  box.inner_length = 0.12;
  box.inner_width = 0.12;
  box.inner_height = 0.02;
  mgn::DropOptions o;
  o.window_min = {0.03, 0.0, 0.3};
  o.window_max = {0.03, 0.0, 0.3};
  o.seed = 1;
  // 160 mm rod: second-largest extent 20 mm fits; largest 160 <= diagonal 170 mm.
  const auto r = mgn::drop_objects({object_of(mgn::make_box({0.16, 0.02, 0.02}), 500, "rod")},
                                   tote_mesh(box), box, o);
  const auto b = mgn::make_box({0.16, 0.02, 0.02}).transformed(r.objects[0].X_WO).bounds();
  const bool inside = b(0, 0) > -0.064 && b(1, 0) < 0.064 && b(0, 1) > -0.064 && b(1, 1) < 0.064;
  EXPECT_EQ(r.objects[0].kept(), inside);
}

TEST(Drop, BadInputIsRejected) {
  const mgn::ToteBox box;
  const mgn::Mesh tote = tote_mesh(box);
  const auto good = object_of(mgn::make_box({0.05, 0.05, 0.05}), 500, "cube");
  EXPECT_THROW(mgn::drop_objects({}, tote, box, {}), mgn::InvalidArgument);
  auto bad = good;
  bad.mass = std::nan("");
  EXPECT_THROW(mgn::drop_objects({bad}, tote, box, {}), mgn::InvalidArgument);
  bad = good;
  bad.convex_parts.clear();
  EXPECT_THROW(mgn::drop_objects({bad}, tote, box, {}), mgn::InvalidArgument);
  bad = good;
  bad.inertia = -bad.inertia;
  EXPECT_THROW(mgn::drop_objects({bad}, tote, box, {}), mgn::InvalidArgument);
  // Larger than the tote.
  const auto huge = object_of(mgn::make_box({0.6, 0.5, 0.05}), 500, "huge");
  EXPECT_THROW(mgn::drop_objects({huge}, tote, box, {}), mgn::InvalidArgument);
  mgn::DropOptions o;
  o.dt = 0;
  EXPECT_THROW(mgn::drop_objects({good}, tote, box, o), mgn::InvalidArgument);
  o = {};
  o.window_min.x() = 0.5;  // min > max and outside the cavity
  EXPECT_THROW(mgn::drop_objects({good}, tote, box, o), mgn::InvalidArgument);
  o = {};
  o.window_max.x() = 0.3;  // beyond the inner wall at 0.2
  EXPECT_THROW(mgn::drop_objects({good}, tote, box, o), mgn::InvalidArgument);
  o = {};
  o.max_time = std::nan("");
  EXPECT_THROW(mgn::drop_objects({good}, tote, box, o), mgn::InvalidArgument);
  mgn::ToteBox bad_box;
  bad_box.inner_height = -1;
  EXPECT_THROW(mgn::drop_objects({good}, tote, bad_box, {}), mgn::InvalidArgument);
  EXPECT_THROW(mgn::drop_objects({good}, mgn::Mesh(), box, {}), mgn::InvalidArgument);
  // A tote mesh that does not match the box.
  mgn::ToteBox bigger = box;
  bigger.inner_length = 0.8;
  EXPECT_THROW(mgn::drop_objects({good}, tote, bigger, {}), mgn::InvalidArgument);
}

TEST(Drop, ObjectsReleasedFromOnePointAreStackedWithoutOverlap) {
  // Twenty copies drawn at the same point: the release placement must lift each one above the
  // others (this once looped forever on a floating-point tie) and the release boxes must not
  // overlap.
  const mgn::ToteBox box;
  const mgn::Mesh cube = mgn::make_box({0.05, 0.05, 0.05});
  std::vector<mgn::DropObject> objects(20, object_of(cube, 500, "cube"));
  mgn::DropOptions o;
  o.window_min = {0.01, 0.01, 0.3};
  o.window_max = {0.01, 0.01, 0.3};
  o.max_time = 0.3;
  const auto r = mgn::drop_objects(objects, tote_mesh(box), box, o);
  std::vector<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> b;
  for (const auto& d : r.objects) b.push_back(cube.transformed(d.X_WO_release).bounds());
  for (std::size_t i = 0; i < b.size(); ++i)
    for (std::size_t j = i + 1; j < b.size(); ++j) {
      const bool overlap = (b[i].row(0).array() < b[j].row(1).array()).all() &&
                           (b[j].row(0).array() < b[i].row(1).array()).all();
      EXPECT_FALSE(overlap) << i << " and " << j;
    }
}

TEST(ReduceConvexPoints, KeepsFewPointsInsideTheHullCloseToIt) {
  // A 64-gon cylinder (128 points): the reduced hull must use at most 24 of the points, lie inside
  // the full hull (its points are a subset) and keep every point within the reported deviation,
  // checked here independently against the face planes of the reduced hull.
  const mgn::Mesh cyl = mgn::make_cylinder(0.04, 0.10, 64);
  const mgn::Points3d P = cyl.vertices().cast<double>();
  double dev = -1.0;
  const auto idx = mgn::reduce_convex_points(P, 24, 0.0, &dev);
  ASSERT_EQ(idx.size(), 24u);
  std::vector<Eigen::Index> sorted = idx;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(std::unique(sorted.begin(), sorted.end()), sorted.end()) << "indices repeat";
  mgn::Points3f sub(static_cast<Eigen::Index>(idx.size()), 3);
  for (std::size_t k = 0; k < idx.size(); ++k)
    sub.row(static_cast<Eigen::Index>(k)) = P.row(idx[k]).cast<float>();
  const mgn::Mesh hull = mgn::convex_hull_of_points(sub);
  const auto n = hull.face_normals();
  double worst = 0.0;
  for (Eigen::Index v = 0; v < P.rows(); ++v) {
    double out = -1e300;
    for (Eigen::Index f = 0; f < hull.num_faces(); ++f) {
      const mgn::Vec3d q = hull.vertices().row(hull.faces()(f, 0)).cast<double>().transpose();
      out = std::max(out, n.row(f).cast<double>().dot(P.row(v).transpose() - q));
    }
    worst = std::max(worst, out);
  }
  EXPECT_NEAR(worst, dev, 1e-6);
  // The best 24 points (a 12-gon per rim) deviate by r (1 - cos(pi / 12)) = 1.4 mm; the greedy
  // choice must come within 2.5x of that and keep 95 % of the volume (12-gon: 95.5 %).
  EXPECT_LT(dev, 2.5 * 0.04 * (1 - std::cos(M_PI / 12)));
  EXPECT_GT(mgn::closed_mesh_volume(hull), 0.95 * mgn::closed_mesh_volume(cyl));
  // A tolerance stops early; few points come back unchanged; bad arguments are rejected.
  double dev_tol = 0.0;
  const auto coarse = mgn::reduce_convex_points(P, 128, 0.002, &dev_tol);
  EXPECT_LT(coarse.size(), 40u);
  EXPECT_LE(dev_tol, 0.002);
  EXPECT_EQ(mgn::reduce_convex_points(P.topRows(8), 24).size(), 8u);
  EXPECT_THROW(mgn::reduce_convex_points(P, 3), mgn::InvalidArgument);
  EXPECT_THROW(mgn::reduce_convex_points(P, 24, -1.0), mgn::InvalidArgument);
}

TEST(OuterHullVertices, ContainsEveryPointWithinTheBudgetAndReportsItsExcess) {
  // A fine sphere (hundreds of hull vertices): the outer polytope must keep at most 64 vertices,
  // contain every point (checked against the face planes of the hull of the returned vertices),
  // and protrude beyond the sphere's hull by the reported excess, checked by brute force.
  const double r = 0.04;
  const mgn::Mesh ball = mgn::make_sphere(r, 48, 24);
  std::vector<mgn::Vec3d> P;
  for (Eigen::Index v = 0; v < ball.num_vertices(); ++v)
    P.push_back(ball.vertices().row(v).cast<double>().transpose());
  double excess = -1.0;
  const std::vector<mgn::Vec3d> V = mgn::outer_hull_vertices(P, 64, 0.0, &excess);
  ASSERT_LE(V.size(), 64u);
  ASSERT_GE(V.size(), 8u);
  // Containment of convex hulls: along every direction u the support of V reaches at least as
  // far as that of P (checked on 4000 well-spread directions).
  const int K = 4000;
  for (int k = 0; k < K; ++k) {
    const double z = 1.0 - 2.0 * (k + 0.5) / K, rho = std::sqrt(1.0 - z * z);
    const double phi = k * M_PI * (3.0 - std::sqrt(5.0));
    const mgn::Vec3d u(rho * std::cos(phi), rho * std::sin(phi), z);
    double hp = -1e300, hv = -1e300;
    for (const mgn::Vec3d& p : P) hp = std::max(hp, u.dot(p));
    for (const mgn::Vec3d& v : V) hv = std::max(hv, u.dot(v));
    ASSERT_GE(hv, hp - 1e-9) << "a point lies outside along direction " << k;
  }
  // Excess: distance of each returned vertex outside the sphere's hull (its face planes).
  const mgn::Mesh hull = mgn::convex_hull(ball);
  const auto hn = hull.face_normals();
  double worst = 0.0;
  for (const mgn::Vec3d& v : V) {
    double out = -1e300;
    for (Eigen::Index f = 0; f < hull.num_faces(); ++f) {
      const mgn::Vec3d q = hull.vertices().row(hull.faces()(f, 0)).cast<double>().transpose();
      out = std::max(out, hn.row(f).cast<double>().dot(v - q));
    }
    worst = std::max(worst, out);
  }
  EXPECT_NEAR(worst, excess, 1e-6);
  // A polytope with 64 vertices has ~34 faces; circumscribed about a sphere its vertices lie
  // ~9 % of r outside it at best (faces of ~0.4 rad circumradius): the greedy choice must come
  // within 1.7x of that.
  EXPECT_LT(excess, 0.15 * r);
  // A tolerance stops early; a small hull comes back as it is; bad arguments are rejected.
  double coarse_excess = 0.0;
  const auto coarse = mgn::outer_hull_vertices(P, 200, 0.008, &coarse_excess);
  EXPECT_LE(coarse_excess, 0.008);
  EXPECT_LT(coarse.size(), V.size());
  EXPECT_EQ(mgn::outer_hull_vertices(P, 100000).size(),
            static_cast<std::size_t>(hull.num_vertices()));
  EXPECT_THROW(mgn::outer_hull_vertices(P, 7), mgn::InvalidArgument);
  EXPECT_THROW(mgn::outer_hull_vertices(P, 64, -1.0), mgn::InvalidArgument);
}

TEST(Drop, FullAndReducedHullsBothSettleTheSamePile) {
  // Fine spheres and cylinders (hundreds of hull vertices): with reduced hulls (the default) the
  // pile must settle as well as with every vertex kept, and without more interpenetration.
  const mgn::ToteBox box;
  const mgn::Mesh tote = tote_mesh(box);
  std::vector<mgn::Mesh> meshes = {
      mgn::make_sphere(0.03, 48, 24), mgn::make_cylinder(0.03, 0.1, 96),
      mgn::make_sphere(0.025, 48, 24), mgn::make_cylinder(0.04, 0.05, 96),
      mgn::make_box({0.08, 0.05, 0.04})};
  std::vector<mgn::DropObject> objects;
  for (const auto& m : meshes) objects.push_back(object_of(m, 600, "o"));
  for (int full = 0; full < 2; ++full) {
    mgn::DropOptions o;
    o.seed = 21;
    o.max_hull_vertices = full ? 0 : 48;
    const auto r = mgn::drop_objects(objects, tote, box, o);
    EXPECT_TRUE(r.settled) << "full " << full;
    for (std::size_t i = 0; i < meshes.size(); ++i) {
      ASSERT_TRUE(r.objects[i].kept()) << i;
      EXPECT_TRUE(r.objects[i].settled) << i;
      EXPECT_GE(meshes[i].transformed(r.objects[i].X_WO).bounds()(0, 2), -0.002) << i;
    }
    for (std::size_t i = 0; i < meshes.size(); ++i)
      for (std::size_t j = 0; j < meshes.size(); ++j)
        if (i != j) {
          EXPECT_LT(penetration(meshes[i].transformed(r.objects[i].X_WO),
                                meshes[j].transformed(r.objects[j].X_WO)),
                    0.003)
              << i << " in " << j << " full " << full;
        }
  }
}

TEST(Drop, ObjectsOverTheRimAreRemovedAndTheRestSettlesAgain) {
  // Rods into a shallow 120 mm tray: some end over the rim. They are removed, and what stays
  // must have settled again afterwards: at rest, inside, and held up by the floor or by another
  // kept object (never by a removed one, i.e. floating).
  mgn::ToteBox box;
  box.inner_length = 0.12;
  box.inner_width = 0.12;
  box.inner_height = 0.02;
  const mgn::Mesh rod = mgn::make_box({0.15, 0.02, 0.02});
  std::vector<mgn::DropObject> objects(6, object_of(rod, 500, "rod"));
  int rounds = 0;
  for (std::uint64_t seed = 0; seed < 4; ++seed) {
    mgn::DropOptions o;
    o.window_min = {-0.03, -0.03, 0.1};
    o.window_max = {0.03, 0.03, 0.3};
    o.seed = seed;
    const auto r = mgn::drop_objects(objects, tote_mesh(box), box, o);
    rounds += r.resettle_rounds;
    EXPECT_TRUE(r.settled) << "seed " << seed;
    std::vector<mgn::Mesh> kept;
    for (const auto& d : r.objects)
      if (d.kept()) {
        EXPECT_TRUE(d.settled);
        kept.push_back(rod.transformed(d.X_WO));
      }
    for (std::size_t i = 0; i < kept.size(); ++i) {
      const auto b = kept[i].bounds();
      EXPECT_TRUE(b(0, 0) > -0.063 && b(1, 0) < 0.063 && b(0, 1) > -0.063 && b(1, 1) < 0.063);
      if (b(0, 2) < 0.003) continue;  // on the floor
      bool held = false;
      for (std::size_t j = 0; j < kept.size(); ++j) {
        if (j == i) continue;
        const auto c = kept[j].bounds();
        held |= (b.row(0).array() < c.row(1).array() + 0.003).all() &&
                (c.row(0).array() < b.row(1).array() + 0.003).all() && c(1, 2) < b(1, 2);
      }
      EXPECT_TRUE(held) << "seed " << seed << ": kept rod " << i << " floats at z " << b(0, 2);
    }
  }
  EXPECT_GT(rounds, 0) << "no seed put a rod over the rim: the test tests nothing";
}

TEST(Drop, TableTopKeepsOverhangsAndLosesWhatFallsOff) {
  // A 300 x 200 mm board without walls, 10 mm thick, top at z = 0 (python make_tote with
  // walls=False). Three 50 mm cubes start at rest just above it: one in the middle, one
  // overhanging the +x edge by 10 mm (centre on the board: it stays, though in a tote of the
  // same size it would be over the rim) and one with its centre 20 mm beyond the edge (it falls).
  mgn::ToteBox box;
  box.inner_length = 0.3;
  box.inner_width = 0.2;
  box.walls = false;
  mgn::Pose X_board = mgn::Pose::Identity();
  X_board.translation() = mgn::Vec3d(0, 0, -0.005);
  const mgn::Mesh board = mgn::make_box({0.3, 0.2, 0.01}).transformed(X_board);
  const mgn::Mesh cube = mgn::make_box({0.05, 0.05, 0.05});
  std::vector<mgn::DropObject> objects(3, object_of(cube, 500, "cube"));
  std::vector<mgn::Pose> start(3, mgn::Pose::Identity());
  start[0].translation() = mgn::Vec3d(0.0, 0.0, 0.0255);
  start[1].translation() = mgn::Vec3d(0.135, 0.0, 0.0255);
  start[2].translation() = mgn::Vec3d(0.17, 0.07, 0.0255);
  mgn::DropOptions o;
  o.window_min = {-0.1, -0.05, 0.1};
  o.window_max = {0.1, 0.05, 0.2};
  const auto r = mgn::settle_objects(objects, start, board, box, o);
  ASSERT_TRUE(r.objects[0].kept());
  ASSERT_TRUE(r.objects[1].kept());
  EXPECT_EQ(r.objects[2].status, mgn::DropStatus::LeftTote);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(r.objects[i].contacts, mgn::ContactFloor) << i;  // the edge is no wall
    EXPECT_NEAR(r.objects[i].X_WO.translation().z(), 0.025, 0.002) << i;
  }
  EXPECT_NEAR(r.objects[1].X_WO.translation().x(), 0.135, 0.005);
  // The same board with walls is rejected as a tote (its mesh has no rim at inner_height).
  box.walls = true;
  EXPECT_THROW(mgn::settle_objects(objects, start, board, box, o), mgn::InvalidArgument);
}

namespace {

/// Every output of two drops, compared bit for bit.
void expect_same_drop(const mgn::DropResult& a, const mgn::DropResult& b, const char* what) {
  ASSERT_EQ(a.objects.size(), b.objects.size()) << what;
  for (std::size_t i = 0; i < a.objects.size(); ++i) {
    const auto& p = a.objects[i];
    const auto& q = b.objects[i];
    EXPECT_EQ(std::memcmp(p.X_WO.matrix().data(), q.X_WO.matrix().data(), 16 * sizeof(double)), 0)
        << what << " object " << i;
    EXPECT_EQ(std::memcmp(p.X_WO_release.matrix().data(), q.X_WO_release.matrix().data(),
                          16 * sizeof(double)),
              0)
        << what << " object " << i;
    EXPECT_EQ(p.status, q.status) << what << " object " << i;
    EXPECT_EQ(p.settled, q.settled) << what << " object " << i;
    EXPECT_EQ(p.contacts, q.contacts) << what << " object " << i;
  }
  EXPECT_EQ(a.steps, b.steps) << what;
  EXPECT_EQ(a.settled, b.settled) << what;
  EXPECT_EQ(a.resettle_rounds, b.resettle_rounds) << what;
  EXPECT_EQ(std::memcmp(&a.max_penetration, &b.max_penetration, sizeof(double)), 0) << what;
}

}  // namespace

TEST(Drop, TheHullCacheGivesTheSameDropsBitForBit) {
  // Objects repeated within a drop and from drop to drop, the way a dataset drops them.
  const mgn::ToteBox box;
  const mgn::Mesh tote = tote_mesh(box);
  const auto meshes = mixed_meshes();
  std::vector<mgn::DropObject> objects;
  for (int k : {0, 1, 2, 0, 3, 1, 2, 0}) objects.push_back(object_of(meshes[k], 600, "o"));
  mgn::DropOptions o;
  o.seed = 5;
  o.max_time = 2.0;
  o.resettle_time = 0.5;
  o.max_hull_vertices = 48;
  // Without the cache: every drop prepares every object.
  mgn::set_drop_hull_cache_capacity(0);
  const auto fresh = mgn::drop_objects(objects, tote, box, o);
  EXPECT_EQ(mgn::drop_hull_cache_info().entries, 0u);
  // With it: the first drop prepares the four distinct objects once, the second none.
  mgn::set_drop_hull_cache_capacity(std::size_t(64) << 20);
  mgn::clear_drop_hull_cache();
  const auto first = mgn::drop_objects(objects, tote, box, o);
  auto info = mgn::drop_hull_cache_info();
  EXPECT_EQ(info.misses, 4);
  EXPECT_EQ(info.hits, 4);
  EXPECT_EQ(info.entries, 4u);
  const auto second = mgn::drop_objects(objects, tote, box, o);
  info = mgn::drop_hull_cache_info();
  EXPECT_EQ(info.misses, 4);
  EXPECT_EQ(info.hits, 12);
  expect_same_drop(fresh, first, "first drop with the cache");
  expect_same_drop(fresh, second, "second drop with the cache");
  // A settle from the dropped poses, with and without the cache.
  std::vector<mgn::Pose> start;
  for (const auto& r : fresh.objects) start.push_back(r.X_WO);
  const auto settled_cached = mgn::settle_objects(objects, start, tote, box, o);
  mgn::set_drop_hull_cache_capacity(0);
  expect_same_drop(mgn::settle_objects(objects, start, tote, box, o), settled_cached, "settle");

  // Scaled objects (the same vertex count, other coordinates, mass properties) and another
  // hull budget are new entries: each drop equals its drop without the cache.
  std::vector<mgn::DropObject> scaled;
  for (int k : {0, 1, 2, 0}) scaled.push_back(object_of(meshes[k].scaled(1.2), 600, "o"));
  const auto scaled_fresh = mgn::drop_objects(scaled, tote, box, o);
  mgn::DropOptions fewer = o;
  fewer.max_hull_vertices = 16;
  const auto fewer_fresh = mgn::drop_objects(objects, tote, box, fewer);
  mgn::set_drop_hull_cache_capacity(std::size_t(64) << 20);
  const auto before = mgn::drop_hull_cache_info();
  expect_same_drop(scaled_fresh, mgn::drop_objects(scaled, tote, box, o), "scaled");
  expect_same_drop(fewer_fresh, mgn::drop_objects(objects, tote, box, fewer), "max_hull_vertices");
  info = mgn::drop_hull_cache_info();
  EXPECT_EQ(info.misses - before.misses, 3 + 4);  // 3 scaled objects, 4 with the other budget
  EXPECT_EQ(info.hits - before.hits, 1 + 4);
  EXPECT_FALSE(std::memcmp(scaled_fresh.objects[0].X_WO.matrix().data(),
                           fresh.objects[0].X_WO.matrix().data(), 16 * sizeof(double)) == 0);

  // Errors are those without the cache: an object whose vertices have an entry but whose
  // inertia is invalid is rejected, naming it.
  auto bad = objects;
  bad[3].inertia = -bad[3].inertia;
  bad[3].name = "negative";
  try {
    mgn::drop_objects(bad, tote, box, o);
    ADD_FAILURE() << "expected InvalidArgument";
  } catch (const mgn::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("objects[3] ('negative')"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("positive definite"), std::string::npos) << e.what();
  }
  mgn::clear_drop_hull_cache();
}

TEST(Drop, TwoThreadsDroppingTheSameObjectsGetTheSerialResults) {
  const mgn::ToteBox box;
  const mgn::Mesh tote = tote_mesh(box);
  const auto meshes = mixed_meshes();
  std::vector<mgn::DropObject> objects;
  for (int k : {4, 5, 6, 4, 5}) objects.push_back(object_of(meshes[k], 600, "o"));
  mgn::DropOptions o;
  o.max_time = 1.5;
  o.resettle_time = 0.5;
  o.max_hull_vertices = 48;
  mgn::set_drop_hull_cache_capacity(0);
  std::vector<mgn::DropResult> serial;
  for (std::uint64_t seed : {1, 2}) {
    o.seed = seed;
    serial.push_back(mgn::drop_objects(objects, tote, box, o));
  }
  mgn::set_drop_hull_cache_capacity(std::size_t(64) << 20);
  mgn::clear_drop_hull_cache();
  std::vector<mgn::DropResult> parallel(2);
  auto work = [&](std::size_t t) {
    mgn::DropOptions mine = o;
    mine.seed = t + 1;
    parallel[t] = mgn::drop_objects(objects, tote, box, mine);
  };
  std::thread other(work, std::size_t(1));
  work(0);
  other.join();
  expect_same_drop(serial[0], parallel[0], "thread 0");
  expect_same_drop(serial[1], parallel[1], "thread 1");
  EXPECT_EQ(mgn::drop_hull_cache_info().entries, 3u);
  mgn::clear_drop_hull_cache();
}
