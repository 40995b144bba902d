// Tests of mgn/geometry against analytic shapes.
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/geometry/mass_properties.hpp>
#include <mgn/geometry/mesh.hpp>
#include <mgn/geometry/mesh_io.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/geometry/sampling.hpp>

#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace {
const std::string kData = MGN_TEST_DATA_DIR;
}

TEST(Mesh, ConstructorRejectsBadArrays) {
  mgn::Points3f v(3, 3);
  v << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  mgn::Faces f(1, 3);
  f << 0, 1, 2;
  EXPECT_NO_THROW(mgn::Mesh(v, f));
  mgn::Faces bad_index(1, 3);
  bad_index << 0, 1, 3;
  EXPECT_THROW(mgn::Mesh(v, bad_index), mgn::InvalidArgument);
  mgn::Points3f nan_v = v;
  nan_v(1, 1) = std::nanf("");
  EXPECT_THROW(mgn::Mesh(nan_v, f), mgn::InvalidArgument);
  mgn::Points3f collinear(3, 3);
  collinear << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  try {
    mgn::Mesh(collinear, f, {}, {}, {}, "line");
    FAIL() << "expected InvalidArgument";
  } catch (const mgn::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("'line'"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("zero area"), std::string::npos);
  }
}

TEST(Mesh, ValidatePrimitivesAndBrokenMeshes) {
  for (const auto& m : {mgn::make_box({0.1, 0.2, 0.3}), mgn::make_sphere(0.05, 32, 16),
                        mgn::make_cylinder(0.02, 0.1, 24)}) {
    const auto r = m.validate();
    EXPECT_TRUE(r.is_watertight) << m.name();
    EXPECT_TRUE(r.is_outward) << m.name();
    EXPECT_EQ(r.num_components, 1) << m.name();
  }
  const mgn::Mesh box = mgn::make_box({1, 1, 1});
  const auto flipped = box.flipped().validate();
  EXPECT_TRUE(flipped.is_watertight);
  EXPECT_TRUE(flipped.is_winding_consistent);
  EXPECT_FALSE(flipped.is_outward);
  EXPECT_NEAR(flipped.signed_volume, -1.0, 1e-6);
  // Remove one triangle: 3 boundary edges, not watertight.
  mgn::Faces f = box.faces().topRows(11);
  const auto open = mgn::Mesh(box.vertices(), f).validate();
  EXPECT_FALSE(open.is_watertight);
  EXPECT_EQ(open.num_boundary_edges, 3);
  // Flip one triangle: misoriented edges.
  mgn::Faces g = box.faces();
  std::swap(g(0, 1), g(0, 2));
  const auto mis = mgn::Mesh(box.vertices(), g).validate();
  EXPECT_FALSE(mis.is_winding_consistent);
  EXPECT_EQ(mis.num_misoriented_edges, 3);
}

namespace {

/// Unit cube centred at (x, y, z) (make_box's faces, outward).
mgn::Mesh unit_cube(double x, double y, double z) {
  mgn::Pose X = mgn::Pose::Identity();
  X.translation() << x, y, z;
  return mgn::make_box({1, 1, 1}).transformed(X);
}

/// The faces, wound outward, of the tetrahedron on vertices (a, b, c, d) with
/// det(b - a, c - a, d - a) > 0, appended to `f`.
void add_tetrahedron(std::vector<std::array<int, 3>>& f, const std::array<int, 4>& id) {
  const auto [a, b, c, d] = id;
  f.insert(f.end(), {{a, c, b}, {a, b, d}, {a, d, c}, {b, c, d}});
}

mgn::Mesh from_rows(const std::vector<mgn::Vec3d>& v, const std::vector<std::array<int, 3>>& f) {
  mgn::Points3f pv(static_cast<std::int64_t>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) pv.row(i) = v[i].cast<float>().transpose();
  mgn::Faces pf(static_cast<std::int64_t>(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) pf.row(i) << f[i][0], f[i][1], f[i][2];
  return mgn::Mesh(pv, pf);
}

}  // namespace

TEST(Mesh, ClosedSolidsSharingAnEdgeAreSplitIntoClosedPieces) {
  // Two unit cubes that share the edge x = y = 0.5: four faces on that edge.
  const mgn::Mesh pair = mgn::Mesh::merge({unit_cube(0, 0, 0), unit_cube(1, 1, 0)});
  const auto r = pair.validate();
  EXPECT_TRUE(r.is_watertight);
  EXPECT_TRUE(r.is_winding_consistent);
  EXPECT_TRUE(r.is_outward);
  EXPECT_EQ(r.num_nonmanifold_edges, 0);
  EXPECT_EQ(r.num_split_edges, 1);
  EXPECT_EQ(r.num_split_vertices, 2);  // the edge's two ends
  EXPECT_EQ(r.num_components, 2);
  EXPECT_EQ(r.signed_volume, 2.0);  // every coordinate a multiple of 1/2: exact
  mgn::MassOptions o;
  o.open_mesh = mgn::OpenMeshPolicy::Error;
  const auto p = mgn::compute_mass_properties(pair, o);
  EXPECT_TRUE(p.is_exact);
  EXPECT_EQ(p.volume, 2.0);
  EXPECT_NEAR(p.center_of_mass.x(), 0.5, 1e-12);
  EXPECT_NEAR(p.center_of_mass.y(), 0.5, 1e-12);

  // The same pair with the shared edge's two vertices as one index each (as an OBJ writes it).
  const auto& v0 = pair.vertices();
  mgn::Faces f = pair.faces();
  for (std::int64_t i = 0; i < f.size(); ++i) {
    const auto k = f.data()[i];
    for (std::int64_t j = 0; j < k; ++j)
      if (v0.row(j) == v0.row(k)) {
        f.data()[i] = static_cast<std::int32_t>(j);
        break;
      }
  }
  const auto shared = mgn::Mesh(v0, f).validate();
  EXPECT_TRUE(shared.is_watertight);
  EXPECT_TRUE(shared.is_outward);
  EXPECT_EQ(shared.num_split_edges, 1);
  EXPECT_EQ(shared.num_split_vertices, 2);
  EXPECT_EQ(shared.signed_volume, 2.0);

  // A chain of three cubes, each touching the next along an edge.
  const auto three =
      mgn::Mesh::merge({unit_cube(0, 0, 0), unit_cube(1, 1, 0), unit_cube(2, 2, 0)}).validate();
  EXPECT_TRUE(three.is_watertight);
  EXPECT_EQ(three.num_components, 3);
  EXPECT_EQ(three.num_split_edges, 2);
  EXPECT_EQ(three.num_split_vertices, 4);
  EXPECT_EQ(three.signed_volume, 3.0);
}

TEST(Mesh, ClosedSolidsSharingAVertexAreSplitIntoClosedPieces) {
  // Tetrahedra (0, e_x, e_y, e_z) and (0, -e_x, -e_z, -2 e_y) share the origin (one index):
  // volumes 1/6 and 2/6.
  std::vector<mgn::Vec3d> v = {{0, 0, 0},  {1, 0, 0},  {0, 1, 0}, {0, 0, 1},
                               {-1, 0, 0}, {0, 0, -1}, {0, -2, 0}};
  std::vector<std::array<int, 3>> f;
  add_tetrahedron(f, {0, 1, 2, 3});
  add_tetrahedron(f, {0, 4, 5, 6});
  const auto r = from_rows(v, f).validate();
  EXPECT_TRUE(r.is_watertight);
  EXPECT_TRUE(r.is_outward);
  EXPECT_EQ(r.num_split_edges, 0);
  EXPECT_EQ(r.num_split_vertices, 1);
  EXPECT_EQ(r.num_components, 2);
  EXPECT_NEAR(r.signed_volume, 1.0 / 6.0 + 2.0 / 6.0, 1e-15);
  // Each alone: no split, one component.
  std::vector<std::array<int, 3>> one;
  add_tetrahedron(one, {0, 1, 2, 3});
  const auto single = from_rows(v, one).validate();
  EXPECT_EQ(single.num_split_vertices, 0);
  EXPECT_EQ(single.num_components, 1);
  EXPECT_NEAR(single.signed_volume, 1.0 / 6.0, 1e-15);
}

TEST(Mesh, OpenPiecesAndSharedWallsAreNotSplit) {
  // A cube with one missing face (the -z face) stays open, alone ...
  const mgn::Mesh cube = unit_cube(0, 0, 0);
  const mgn::Mesh open(cube.vertices(), cube.faces().bottomRows(10));
  const auto alone = open.validate();
  EXPECT_FALSE(alone.is_watertight);
  EXPECT_EQ(alone.num_boundary_edges, 4);
  EXPECT_EQ(alone.num_split_edges + alone.num_split_vertices, 0);
  // ... and touching a closed cube along its edge x = y = 0.5 (the edge keeps four faces).
  const auto touching = mgn::Mesh::merge({open, unit_cube(1, 1, 0)}).validate();
  EXPECT_FALSE(touching.is_watertight);
  EXPECT_EQ(touching.num_boundary_edges, 4);
  EXPECT_EQ(touching.num_nonmanifold_edges, 1);
  EXPECT_EQ(touching.num_split_edges + touching.num_split_vertices, 0);
  // A fin: a closed cube with one triangle on its edge (0, 1): three faces there.
  mgn::Points3f fv(9, 3);
  fv.topRows(8) = cube.vertices();
  fv.row(8) << 0.0f, -2.0f, -2.0f;
  mgn::Faces ff(13, 3);
  ff.topRows(12) = cube.faces();
  ff.row(12) << 0, 1, 8;
  const auto fin = mgn::Mesh(fv, ff).validate();
  EXPECT_FALSE(fin.is_watertight);
  EXPECT_EQ(fin.num_nonmanifold_edges, 1);
  EXPECT_EQ(fin.num_boundary_edges, 2);
  EXPECT_EQ(fin.num_split_edges + fin.num_split_vertices, 0);
  // Two cubes sharing a whole face (the same two triangles, wound both ways): a shared wall,
  // not a touch; its five edges keep four faces each.
  const auto wall = mgn::Mesh::merge({cube, unit_cube(1, 0, 0)}).validate();
  EXPECT_FALSE(wall.is_watertight);
  EXPECT_EQ(wall.num_nonmanifold_edges, 5);
  EXPECT_EQ(wall.num_split_edges + wall.num_split_vertices, 0);
}

TEST(MeshIo, LoadsEveryFormatWithMaterials) {
  for (const char* name : {"cube.obj", "cube.stl", "cube.ply", "cube.glb", "cube.dae"}) {
    const mgn::Mesh m = mgn::load_mesh(kData + "/" + name);
    const auto r = m.validate();
    EXPECT_TRUE(r.is_outward) << name;  // the OBJ has uv seams: welding by position must close it
    EXPECT_NEAR(r.signed_volume, 8e-6, 1e-10) << name;
  }
  const mgn::Mesh obj = mgn::load_mesh(kData + "/cube.obj");
  ASSERT_EQ(obj.materials().size(), 1u);
  EXPECT_NEAR(obj.materials()[0].base_color[0], 0.8f, 1e-6f);
  EXPECT_NEAR(obj.materials()[0].opacity, 0.5f, 1e-6f);
  EXPECT_NE(obj.materials()[0].texture_path.find("cube_texture.png"), std::string::npos);
  EXPECT_EQ(obj.uvs().rows(), obj.num_vertices());
  const mgn::Mesh glb = mgn::load_mesh(kData + "/cube.glb");
  EXPECT_NEAR(glb.materials()[0].base_color[1], 200.0f / 255.0f, 1e-3f);
  mgn::LoadOptions mm;
  mm.scale = 0.001;
  EXPECT_NEAR(mgn::load_mesh(kData + "/cube.stl", mm).validate().signed_volume, 8e-15, 1e-18);
}

TEST(MeshIo, BadFilesGiveErrorsNamingThePath) {
  auto expect_error = [](const std::string& path, auto tag) {
    using E = decltype(tag);
    try {
      mgn::load_mesh(path);
      FAIL() << "no error for " << path;
    } catch (const E& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  };
  expect_error(kData + "/missing.obj", mgn::IoError("x"));
  expect_error(kData + "/not_a_mesh.obj", mgn::IoError("x"));
  expect_error(kData + "/empty.stl", mgn::IoError("x"));
  expect_error(kData + "/nan_vertex.obj", mgn::InvalidArgument("x"));
  mgn::LoadOptions strict;
  strict.drop_degenerate = false;
  EXPECT_THROW(mgn::load_mesh(kData + "/zero_area.obj", strict), mgn::InvalidArgument);
  EXPECT_EQ(mgn::load_mesh(kData + "/zero_area.obj").num_faces(), 4);
}

TEST(MassProperties, BoxCylinderSphereMatchAnalyticValues) {
  const double rho = 800.0;
  mgn::MassOptions o;
  o.density = rho;
  {
    const double a = 0.1, b = 0.2, c = 0.3, m = rho * a * b * c;
    mgn::Pose X = mgn::Pose::Identity();
    X.translation() << 1.0, -2.0, 0.5;
    X.rotate(Eigen::AngleAxisd(0.0, mgn::Vec3d::UnitZ()));
    const auto p = mgn::compute_mass_properties(mgn::make_box({a, b, c}).transformed(X), o);
    EXPECT_TRUE(p.is_exact);
    // Vertices are float32: relative accuracy ~1e-7 per coordinate.
    EXPECT_NEAR(p.volume, a * b * c, 2e-6 * a * b * c);
    EXPECT_NEAR(p.mass, m, 2e-6 * m);
    EXPECT_LT((p.center_of_mass - mgn::Vec3d(1.0, -2.0, 0.5)).norm(), 1e-6);
    EXPECT_NEAR(p.inertia(0, 0), m / 12 * (b * b + c * c), 1e-5 * m / 12 * (b * b + c * c));
    EXPECT_NEAR(p.inertia(1, 1), m / 12 * (a * a + c * c), 1e-5 * m / 12 * (a * a + c * c));
    EXPECT_NEAR(p.inertia(2, 2), m / 12 * (a * a + b * b), 1e-5 * m / 12 * (a * a + b * b));
    EXPECT_NEAR(p.inertia(0, 1), 0.0, 1e-7 * m);
  }
  {
    const double r = 0.04, h = 0.1;
    const auto p = mgn::compute_mass_properties(mgn::make_cylinder(r, h, 512), o);
    const double v = M_PI * r * r * h, m = rho * v;
    EXPECT_NEAR(p.volume, v, 1e-4 * v);
    EXPECT_NEAR(p.inertia(2, 2), m * r * r / 2, 2e-4 * m * r * r);
    EXPECT_NEAR(p.inertia(0, 0), m * (3 * r * r + h * h) / 12, 2e-4 * m * h * h);
  }
  {
    const double r = 0.05;
    const auto p = mgn::compute_mass_properties(mgn::make_sphere(r, 512, 256), o);
    const double v = 4.0 / 3.0 * M_PI * r * r * r, m = rho * v;
    EXPECT_NEAR(p.volume, v, 2e-4 * v);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(p.inertia(k, k), 0.4 * m * r * r, 5e-4 * m * r * r);
    EXPECT_LT(p.center_of_mass.norm(), 1e-6);
  }
}

TEST(MassProperties, OpenMeshFallbackAndBadDensity) {
  const mgn::Mesh box = mgn::make_box({1, 1, 1});
  const mgn::Mesh open(box.vertices(), box.faces().topRows(10));  // the +x face removed
  mgn::MassOptions o;
  o.open_mesh = mgn::OpenMeshPolicy::Error;
  EXPECT_THROW(mgn::compute_mass_properties(open, o), mgn::InvalidArgument);
  o.open_mesh = mgn::OpenMeshPolicy::Shell;
  o.shell_thickness = 0.001;
  o.density = 1000;
  const auto p = mgn::compute_mass_properties(open, o);
  EXPECT_FALSE(p.is_exact);
  EXPECT_NEAR(p.mass, 5.0 * 1.0 * 0.001 * 1000, 1e-9);  // five unit faces
  EXPECT_NEAR(p.center_of_mass.x(), -0.1, 1e-9);        // (4 faces at x=0, one at -0.5) / 5
  EXPECT_NEAR(p.center_of_mass.z(), 0.0, 1e-9);
  o.density = -1;
  EXPECT_THROW(mgn::compute_mass_properties(box, o), mgn::InvalidArgument);
}

TEST(Sampling, PointsLieOnTheSurfaceAndAreDeterministic) {
  const double r = 0.05;
  const mgn::Mesh sphere = mgn::make_sphere(r, 128, 64);
  for (auto method : {mgn::SampleMethod::Random, mgn::SampleMethod::Even}) {
    mgn::SampleOptions o;
    o.method = method;
    o.seed = 3;
    const auto s = mgn::sample_surface(sphere, 500, o);
    ASSERT_EQ(s.points.rows(), 500);
    for (int i = 0; i < 500; ++i) {
      EXPECT_NEAR(s.points.row(i).norm(), r, 1e-3 * r);
      EXPECT_NEAR(s.normals.row(i).norm(), 1.0f, 1e-5f);
      EXPECT_GT(s.normals.row(i).dot(s.points.row(i)), 0.0f);  // outward
    }
    const auto again = mgn::sample_surface(sphere, 500, o);
    EXPECT_TRUE(s.points == again.points);
  }
}

TEST(Sampling, EvenSamplingIsMoreEvenThanRandom) {
  const mgn::Mesh box = mgn::make_box({0.1, 0.1, 0.1});
  auto min_spacing = [&](mgn::SampleMethod m) {
    mgn::SampleOptions o;
    o.method = m;
    const auto s = mgn::sample_surface(box, 400, o);
    float best = 1e9f;
    for (int i = 0; i < 400; ++i)
      for (int j = i + 1; j < 400; ++j)
        best = std::min(best, (s.points.row(i) - s.points.row(j)).norm());
    return best;
  };
  EXPECT_GT(min_spacing(mgn::SampleMethod::Even), 3.0f * min_spacing(mgn::SampleMethod::Random));
}
