// Tests of mgn/geometry against analytic shapes.
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/geometry/mass_properties.hpp>
#include <mgn/geometry/mesh.hpp>
#include <mgn/geometry/mesh_io.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/geometry/sampling.hpp>

#include <cmath>
#include <string>

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
