// Tests of mgn/render: camera rig geometry, OSMesa rendering against Embree ray casts, sensor
// models.
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/raytrace/ray_scene.hpp>
#include <mgn/render/camera.hpp>
#include <mgn/render/depth_sensor.hpp>
#include <mgn/render/renderer.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace {

constexpr double kPi = 3.14159265358979323846;

mgn::Pose translation(double x, double y, double z) {
  mgn::Pose X = mgn::Pose::Identity();
  X.translation() << x, y, z;
  return X;
}

mgn::Pose rotated(double ax, double ay, double az, const mgn::Vec3d& t) {
  mgn::Pose X = mgn::Pose::Identity();
  X.linear() =
      (Eigen::AngleAxisd(az, mgn::Vec3d::UnitZ()) * Eigen::AngleAxisd(ay, mgn::Vec3d::UnitY()) *
       Eigen::AngleAxisd(ax, mgn::Vec3d::UnitX()))
          .toRotationMatrix();
  X.translation() = t;
  return X;
}

struct Scene {
  std::vector<mgn::Mesh> meshes;
  std::vector<mgn::Instance> instances;
};

/// A floor slab (id 0, top at z = 0) and five shapes (ids 1..5) resting around the origin.
Scene test_scene() {
  Scene s;
  s.meshes.push_back(mgn::make_box({0.8, 0.6, 0.02}));
  s.meshes.push_back(mgn::make_sphere(0.05, 48, 24));
  s.meshes.push_back(mgn::make_box({0.08, 0.05, 0.12}));
  s.meshes.push_back(mgn::make_cylinder(0.03, 0.15, 48));
  s.instances.push_back({0, translation(0, 0, -0.01), 0, false});
  s.instances.push_back({1, translation(0.1, 0.05, 0.05), 1, false});
  s.instances.push_back({2, rotated(0.3, 0.2, 0.7, {-0.1, 0.02, 0.07}), 2, false});
  s.instances.push_back({3, rotated(kPi / 2, 0.0, 0.4, {0.0, -0.12, 0.03}), 3, false});
  s.instances.push_back({1, translation(-0.05, 0.12, 0.08), 4, false});
  s.instances.push_back({2, rotated(0.0, 0.0, -0.5, {0.15, -0.1, 0.06}), 5, false});
  return s;
}

mgn::Intrinsics small_camera() {
  mgn::Intrinsics K = mgn::Intrinsics::mgn_synthetic();
  K.width = K.height = 400;
  K.fx = K.fy = 2004.3 / 3.0;
  K.cx = K.cy = 200.0;
  return K;
}

/// A pinhole camera of width x height px, focal length f px, principal point at the centre.
mgn::Intrinsics centred_intrinsics(int width, int height, double f) {
  mgn::Intrinsics K;
  K.width = width;
  K.height = height;
  K.fx = K.fy = f;
  K.cx = 0.5 * width;
  K.cy = 0.5 * height;
  return K;
}

}  // namespace

TEST(Camera, IntrinsicsPresets) {
  const mgn::Intrinsics k = mgn::Intrinsics::mgn_synthetic();
  EXPECT_EQ(k.width, 1200);
  EXPECT_EQ(k.height, 1200);
  EXPECT_NEAR(k.fx, 2004.3, 0.05);
  EXPECT_DOUBLE_EQ(k.fx, k.fy);
  EXPECT_DOUBLE_EQ(k.cx, 600.0);
  const mgn::Intrinsics z = mgn::Intrinsics::zivid_two_like();
  EXPECT_EQ(z.width, 1944);
  EXPECT_EQ(z.height, 1200);
  EXPECT_NO_THROW(z.validate());
  mgn::Intrinsics bad = k;
  bad.fx = 0.0;
  EXPECT_THROW(bad.validate(), mgn::InvalidArgument);
  bad = k;
  bad.cy = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(bad.validate(), mgn::InvalidArgument);
}

TEST(Camera, MgnRigMatchesDocumentedGeometry) {
  const mgn::Vec3d target(0.1, -0.2, 0.05);
  mgn::MgnRigParams p;
  const auto poses = mgn::mgn_rig(42, target, &p);
  ASSERT_EQ(poses.size(), 37u);
  EXPECT_GE(p.R_start, 0.70);
  EXPECT_LT(p.R_start, 0.80);
  EXPECT_GE(p.R_end, 1.00);
  EXPECT_LT(p.R_end, 1.40);
  EXPECT_GE(p.theta_start, 0.3);
  EXPECT_LT(p.theta_start, 0.8);
  EXPECT_GE(p.theta_end, 0.1);
  EXPECT_LT(p.theta_end, 0.3);
  EXPECT_GE(p.phi_end, kPi);
  EXPECT_LT(p.phi_end, 2 * kPi);
  // View 0: straight down from R_start.
  EXPECT_TRUE(poses[0].linear().col(2).isApprox(-mgn::Vec3d::UnitZ(), 1e-12));
  EXPECT_TRUE(poses[0].translation().isApprox(target + p.R_start * mgn::Vec3d::UnitZ(), 1e-12));
  for (int iR = 0; iR < 3; ++iR)
    for (int it = 0; it < 3; ++it)
      for (int ip = 0; ip < 4; ++ip) {
        const int v = 1 + 12 * iR + 4 * it + ip;
        const mgn::Pose& X = poses[v];
        const mgn::Vec3d d = X.translation() - target;
        const double R = p.R_start + iR * (p.R_end - p.R_start) / 2;
        const double th = p.theta_start + it * (p.theta_end - p.theta_start) / 2;
        const double ph = ip * p.phi_end / 4;
        EXPECT_NEAR(d.norm(), R, 1e-9) << v;
        EXPECT_NEAR(std::acos(d.z() / d.norm()), th, 1e-9) << v;
        if (ip > 0 || true) {
          const double az = std::atan2(d.y(), d.x());
          EXPECT_NEAR(std::remainder(az - ph, 2 * kPi), 0.0, 1e-9) << v;
        }
        // Optical axis through the target, rotation orthonormal, image "up" towards +z.
        EXPECT_TRUE(X.linear().col(2).isApprox(-d.normalized(), 1e-12)) << v;
        EXPECT_NEAR((X.linear().transpose() * X.linear() - mgn::Mat3d::Identity()).norm(), 0,
                    1e-12);
        EXPECT_NEAR(X.linear().determinant(), 1.0, 1e-12);
        EXPECT_LT(X.linear().col(1).z(), 0.0) << v;  // camera y (down) points down in the world
      }
  // Same seed, same rig; another seed, another rig.
  const auto again = mgn::mgn_rig(42, target);
  EXPECT_TRUE(again[20].isApprox(poses[20]));
  EXPECT_FALSE(mgn::mgn_rig(43, target)[20].isApprox(poses[20]));
}

TEST(Camera, HemisphereRigAndLookAtErrors) {
  const auto poses = mgn::hemisphere_rig({0.5, 1.0}, {0.0, 0.4}, {0.0, 1.0, 2.0}, {0, 0, 0});
  ASSERT_EQ(poses.size(), 12u);
  const mgn::Pose& X = poses[(1 * 2 + 1) * 3 + 2];  // r = 1.0, tilt 0.4, azimuth 2.0
  EXPECT_NEAR(X.translation().norm(), 1.0, 1e-12);
  EXPECT_NEAR(std::acos(X.translation().z()), 0.4, 1e-12);
  EXPECT_NEAR(std::atan2(X.translation().y(), X.translation().x()), 2.0, 1e-12);
  EXPECT_THROW(mgn::hemisphere_rig({}, {0.1}, {0.0}, {0, 0, 0}), mgn::InvalidArgument);
  EXPECT_THROW(mgn::hemisphere_rig({-1.0}, {0.1}, {0.0}, {0, 0, 0}), mgn::InvalidArgument);
  EXPECT_THROW(mgn::hemisphere_rig({1.0}, {2.0}, {0.0}, {0, 0, 0}), mgn::InvalidArgument);
  EXPECT_THROW(mgn::look_at({0, 0, 1}, {0, 0, 1}), mgn::InvalidArgument);
  EXPECT_THROW(mgn::look_at({0, 0, 1}, {0, 0, 0}), mgn::InvalidArgument);  // up parallel
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(mgn::look_at({nan, 0, 1}, {0, 0, 0}, {0, 1, 0}), mgn::InvalidArgument);
}

TEST(Renderer, DepthAndIdsAgreeWithEmbree) {
  const Scene s = test_scene();
  mgn::Renderer r(400, 400);
  for (const auto& m : s.meshes) r.add_mesh(m);
  r.set_instances(s.instances);
  std::vector<mgn::RayGeometry> geoms;
  for (const auto& in : s.instances)
    geoms.push_back({&s.meshes[in.mesh_id], in.X_WO, in.instance_id});
  const mgn::RayScene rays(geoms);
  const mgn::Intrinsics K = small_camera();
  const auto rig = mgn::mgn_rig(7, {0, 0, 0.05});
  for (int v : {0, 5, 30}) {
    const mgn::CameraView view{K, rig[v]};
    mgn::RenderOptions opt;
    opt.background = mgn::Vec3f(0.5f, 0.0f, 1.0f);  // sRGB (188, 0, 255)
    const mgn::RenderOutput out = r.render(view, opt);
    ASSERT_EQ(out.depth.size(), 400u * 400u);
    ASSERT_EQ(out.rgb.size(), 400u * 400u * 3);
    mgn::Points3f o, d;
    mgn::camera_rays(K.K(), K.width, K.height, view.X_WC, o, d);
    mgn::CastOptions co;
    co.coherent = true;
    const mgn::RayHits hits = rays.intersect(o, d, co);
    const mgn::Vec3d axis = view.X_WC.linear().col(2);
    int object_px = 0, depth_ok = 0, id_ok = 0, hit_px = 0, bg_px = 0, bg_ok = 0, shaded_ok = 0;
    for (std::size_t i = 0; i < out.depth.size(); ++i) {
      const bool hit = hits.instance_ids[i] >= 0;
      const int truth_id = hit ? hits.instance_ids[i] : 0;
      id_ok += out.instance_ids[i] == truth_id;
      const std::uint8_t* px = &out.rgb[3 * i];
      const bool is_bg = px[0] == 188 && px[1] == 0 && px[2] == 255;
      if (!hit) {
        bg_px += 1;
        bg_ok += is_bg;
        continue;
      }
      shaded_ok += !is_bg;
      ++hit_px;
      if (truth_id == 0) continue;
      ++object_px;
      const double z = hits.distance[i] * d.row(i).cast<double>().dot(axis);
      depth_ok += std::abs(out.depth[i] - z) < 1e-3;
    }
    EXPECT_GT(object_px, 2000) << v;
    EXPECT_GE(depth_ok, 0.99 * object_px) << v;
    EXPECT_GE(id_ok, 0.99 * out.depth.size()) << v;
    EXPECT_GT(hit_px, object_px);  // the floor is seen too
    // Every surface pixel is shaded (no hole from the depth pre-pass), empty ones keep the
    // background colour (linear 0.5 stored as sRGB 188).
    EXPECT_GE(shaded_ok, 0.999 * hit_px) << v;
    EXPECT_GE(bg_ok, 0.99 * bg_px) << v;
  }
}

TEST(Renderer, IdOnlySubsetPassAndTransparency) {
  Scene s = test_scene();
  mgn::Mesh glass = mgn::make_box({0.1, 0.1, 0.1});
  mgn::Material m;
  m.opacity = 0.15f;
  glass = mgn::Mesh(glass.vertices(), glass.faces(), {}, {m}, {}, "glass");
  s.meshes.push_back(glass);
  s.instances.push_back({4, translation(0.0, 0.0, 0.3), 9, false});
  mgn::Renderer r(400, 400);
  for (const auto& mesh : s.meshes) r.add_mesh(mesh);
  r.set_instances(s.instances);
  const mgn::CameraView view{small_camera(), mgn::mgn_rig(1, {0, 0, 0})[0]};
  const mgn::RenderOutput full = r.render(view);
  // The glass box hides what is below it in the depth and id passes: at the image centre.
  const std::size_t c = 200 * 400 + 200;
  EXPECT_EQ(full.instance_ids[c], 9);
  const double cam_z = view.X_WC.translation().z();
  EXPECT_NEAR(full.depth[c], cam_z - 0.35, 1e-4);
  // ... but not in the colour: the floor shows through (differs from the glass-free render).
  mgn::RenderOptions only_sphere;
  only_sphere.rgb = only_sphere.depth = false;
  only_sphere.visible_instances = {4};
  const mgn::RenderOutput alone = r.render(view, only_sphere);
  EXPECT_TRUE(alone.rgb.empty());
  EXPECT_TRUE(alone.depth.empty());
  std::size_t n4 = 0, n_other = 0, n4_full = 0;
  for (std::size_t i = 0; i < alone.instance_ids.size(); ++i) {
    n4 += alone.instance_ids[i] == 4;
    n_other += alone.instance_ids[i] != 4 && alone.instance_ids[i] != 0;
    n4_full += full.instance_ids[i] == 4;
  }
  EXPECT_EQ(n_other, 0u);
  EXPECT_GE(n4, n4_full);  // amodal >= visible
  // Projected disc area of the sphere (radius 5 cm at depth ~ cam_z - 0.08): pi r^2 f^2 / z^2.
  const double zc = cam_z - 0.08, f = small_camera().fx;
  const double expected = kPi * 0.05 * 0.05 * f * f / (zc * zc);
  EXPECT_NEAR(static_cast<double>(n4), expected, 0.05 * expected);
}

TEST(Renderer, RandomisedLightingIsDeterministic) {
  Scene s = test_scene();
  s.instances[0].randomize_color = true;
  mgn::Renderer r(200, 200);
  for (const auto& mesh : s.meshes) r.add_mesh(mesh);
  r.set_instances(s.instances);
  mgn::Intrinsics K = small_camera();
  K.width = K.height = 200;
  K.cx = K.cy = 100;
  K.fx = K.fy = 300;
  const mgn::CameraView view{K, mgn::mgn_rig(3, {0, 0, 0})[10]};
  mgn::RenderOptions o;
  o.randomize = true;
  o.seed = 11;
  o.view_index = 10;
  const auto a = r.render(view, o);
  const auto b = r.render(view, o);
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_EQ(a.light.position_W, b.light.position_W);
  o.view_index = 11;
  const auto c = r.render(view, o);
  EXPECT_NE(a.rgb, c.rgb);
  EXPECT_EQ(a.instance_ids, c.instance_ids);  // geometry does not change
  EXPECT_EQ(a.depth, c.depth);
}

TEST(Renderer, BadInputGivesClearErrors) {
  EXPECT_THROW(mgn::Renderer(0, 10), mgn::InvalidArgument);
  mgn::Renderer r(100, 100);
  EXPECT_THROW(r.add_mesh(mgn::Mesh()), mgn::InvalidArgument);
  const mgn::Intrinsics K = centred_intrinsics(100, 100, 100);
  const mgn::CameraView view{K, mgn::look_at({0, 0, 1}, {0, 0, 0}, {0, 1, 0})};
  EXPECT_THROW(r.render(view), mgn::InvalidArgument);  // empty scene
  const int box = r.add_mesh(mgn::make_box({0.2, 0.2, 0.2}));
  EXPECT_THROW(r.set_instances({{box + 1, mgn::Pose::Identity(), 1, false}}), mgn::InvalidArgument);
  mgn::Pose nan_pose = mgn::Pose::Identity();
  nan_pose(0, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(r.set_instances({{box, nan_pose, 1, false}}), mgn::InvalidArgument);
  r.set_instances({{box, mgn::Pose::Identity(), 1, false}});
  EXPECT_NO_THROW(r.render(view));
  mgn::CameraView bad = view;
  bad.K.fx = 0;
  EXPECT_THROW(r.render(bad), mgn::InvalidArgument);
  bad = view;
  bad.X_WC(1, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(r.render(bad), mgn::InvalidArgument);
  bad = view;
  bad.X_WC.translation() << 0.05, 0.0, 0.0;  // inside the box
  EXPECT_THROW(r.render(bad), mgn::InvalidArgument);
  bad = view;
  bad.K.width = 200;  // larger than the framebuffer
  EXPECT_THROW(r.render(bad), mgn::InvalidArgument);
  mgn::RenderOptions none;
  none.visible_instances = {77};
  EXPECT_THROW(r.render(view, none), mgn::InvalidArgument);
}

TEST(DepthSensor, ProjectorShadowWidthMatchesTriangulation) {
  // A step: background at 1.0 m, foreground at 0.5 m on the right half. The projector 0.1 m to
  // the right cannot see fx * b * (1/0.5 - 1/1.0) = fx * 0.1 px of background left of the step.
  const mgn::Intrinsics K = centred_intrinsics(300, 4, 400);
  std::vector<float> depth(1200, 1.0f);
  std::vector<std::int32_t> ids(1200, 1);
  for (int v = 0; v < 4; ++v)
    for (int u = 200; u < 300; ++u) depth[v * 300 + u] = 0.5f, ids[v * 300 + u] = 2;
  auto p = mgn::DepthSensorParams::preset_defaults(mgn::DepthSensorPreset::StructuredLight);
  p.sigma_a = p.sigma_b = 0.0;
  const auto out = mgn::apply_depth_sensor(depth, ids, {}, K, p, 1);
  for (int v = 0; v < 4; ++v) {
    int invalid = 0;
    for (int u = 0; u < 300; ++u) invalid += !out.valid[v * 300 + u];
    EXPECT_NEAR(invalid, 40, 1);
    for (int u = 0; u < 159; ++u) EXPECT_TRUE(out.valid[v * 300 + u]);
    for (int u = 161; u < 200; ++u) EXPECT_FALSE(out.valid[v * 300 + u]);
    EXPECT_TRUE(std::isnan(out.depth[v * 300 + 170]));
  }
  // Projector on the other side: the shadow falls right of the foreground, which here is the
  // image border, so nothing is shadowed.
  p.baseline = -0.1;
  const auto other = mgn::apply_depth_sensor(depth, ids, {}, K, p, 1);
  for (auto v : other.valid) EXPECT_EQ(v, 1);
}

TEST(DepthSensor, NoiseMaterialsAndDeterminism) {
  const mgn::Intrinsics K = centred_intrinsics(200, 200, 300);
  std::vector<float> depth(40000, 1.0f);
  std::vector<std::int32_t> ids(40000, 1);
  for (int i = 0; i < 100; ++i) ids[i] = 2, depth[i] = 1.0f;  // first half row: transparent
  mgn::Material glass;
  glass.opacity = 0.1f;
  mgn::Material black;
  black.base_color << 0.01f, 0.01f, 0.01f, 1.0f;
  mgn::Material mirror;
  mirror.specular << 1, 1, 1;
  mirror.shininess = 500;
  EXPECT_EQ(mgn::surface_flags(glass), mgn::kSurfaceTransparent);
  EXPECT_EQ(mgn::surface_flags(black), mgn::kSurfaceDark);
  EXPECT_EQ(mgn::surface_flags(mirror), mgn::kSurfaceMirror);
  EXPECT_EQ(mgn::surface_flags(mgn::Material{}), 0);
  const std::vector<std::uint8_t> flags = {0, 0, mgn::kSurfaceTransparent};
  for (auto preset : {mgn::DepthSensorPreset::StructuredLight, mgn::DepthSensorPreset::ToF}) {
    const auto p = mgn::DepthSensorParams::preset_defaults(preset);
    const auto a = mgn::apply_depth_sensor(depth, ids, flags, K, p, 5);
    const auto b = mgn::apply_depth_sensor(depth, ids, flags, K, p, 5);
    EXPECT_EQ(a.valid, b.valid);
    for (std::size_t i = 0; i < a.depth.size(); ++i)
      if (a.valid[i]) {
        ASSERT_EQ(a.depth[i], b.depth[i]);
      }
    for (int i = 0; i < 100; ++i) EXPECT_FALSE(a.valid[i]);
    double s = 0, s2 = 0;
    int n = 0;
    for (std::size_t i = 100; i < a.depth.size(); ++i) {
      ASSERT_TRUE(a.valid[i]);
      const double e = a.depth[i] - 1.0;
      s += e, s2 += e * e, ++n;
    }
    const double sigma = p.sigma_a + p.sigma_b * (1.0 - p.sigma_z0) * (1.0 - p.sigma_z0);
    EXPECT_NEAR(std::sqrt(s2 / n), sigma, 0.03 * sigma);
    EXPECT_NEAR(s / n, 0.0, 0.03 * sigma);
    EXPECT_EQ(a.depth_ideal, depth);
    // The sensor reports z on its grid: each value is the float nearest a multiple of the step.
    ASSERT_GT(p.depth_step, 0.0);
    std::size_t distinct_off_grid = 0;
    for (std::size_t i = 100; i < a.depth.size(); ++i) {
      const double k = std::round(a.depth[i] / p.depth_step);
      distinct_off_grid += a.depth[i] != static_cast<float>(k * p.depth_step);
    }
    EXPECT_EQ(distinct_off_grid, 0u);
    // The grid grows with the noise: the largest 2^k depth_step not above half of sigma(1 m)
    // (structured light 0.15 mm -> 2 steps of 0.039 mm; ToF 0.94 mm -> 4 steps of 0.156 mm).
    ASSERT_EQ(p.depth_step_noise_fraction, 0.5);
    const double coarse =
        p.depth_step * std::exp2(std::floor(std::log2(0.5 * sigma / p.depth_step) + 1e-12));
    EXPECT_GE(coarse, 2.0 * p.depth_step);
    std::size_t off_coarse = 0, odd = 0;
    for (std::size_t i = 100; i < a.depth.size(); ++i) {
      const double k = std::round(a.depth[i] / coarse);
      off_coarse += a.depth[i] != static_cast<float>(k * coarse);
      odd += std::fmod(k, 2.0) != 0.0;  // not on the next coarser grid
    }
    EXPECT_EQ(off_coarse, 0u);
    EXPECT_GT(odd, (a.depth.size() - 100) / 4);
    // Without the noise fraction the grid is the fixed step: values between the coarse ones.
    auto fixed = p;
    fixed.depth_step_noise_fraction = 0.0;
    const auto c = mgn::apply_depth_sensor(depth, ids, flags, K, fixed, 5);
    std::size_t between = 0;
    for (std::size_t i = 100; i < c.depth.size(); ++i) {
      const double k = std::round(c.depth[i] / p.depth_step);
      ASSERT_EQ(c.depth[i], static_cast<float>(k * p.depth_step));
      between += c.depth[i] != static_cast<float>(std::round(c.depth[i] / coarse) * coarse);
    }
    EXPECT_GT(between, (c.depth.size() - 100) / 4);
  }
  auto fraction = mgn::DepthSensorParams::preset_defaults(mgn::DepthSensorPreset::StructuredLight);
  fraction.depth_step_noise_fraction = -0.5;
  EXPECT_THROW(mgn::apply_depth_sensor(depth, ids, flags, K, fraction, 0), mgn::InvalidArgument);
  auto step = mgn::DepthSensorParams::preset_defaults(mgn::DepthSensorPreset::StructuredLight);
  step.depth_step = -1e-5;
  EXPECT_THROW(mgn::apply_depth_sensor(depth, ids, flags, K, step, 0), mgn::InvalidArgument);
  const auto ideal = mgn::apply_depth_sensor(
      depth, ids, flags, K, mgn::DepthSensorParams::preset_defaults(mgn::DepthSensorPreset::Ideal),
      5);
  for (std::size_t i = 0; i < ideal.depth.size(); ++i) ASSERT_EQ(ideal.depth[i], depth[i]);
  EXPECT_THROW(mgn::apply_depth_sensor(std::vector<float>(10, 1.0f), ids, flags, K,
                                       mgn::DepthSensorParams{}, 0),
               mgn::InvalidArgument);
  auto bad = mgn::DepthSensorParams::preset_defaults(mgn::DepthSensorPreset::ToF);
  bad.flying_pixel_probability = 2.0;
  EXPECT_THROW(mgn::apply_depth_sensor(depth, ids, flags, K, bad, 0), mgn::InvalidArgument);
}

TEST(DepthSensor, TofFlyingPixelsLieBetweenSurfaces) {
  const mgn::Intrinsics K = centred_intrinsics(100, 100, 100);
  std::vector<float> depth(10000, 1.5f);
  std::vector<std::int32_t> ids(10000, 1);
  for (int v = 0; v < 100; ++v)
    for (int u = 50; u < 100; ++u) depth[v * 100 + u] = 1.0f;
  auto p = mgn::DepthSensorParams::preset_defaults(mgn::DepthSensorPreset::ToF);
  p.sigma_a = p.sigma_b = 0.0;
  p.flying_pixel_probability = 1.0;
  const auto out = mgn::apply_depth_sensor(depth, ids, {}, K, p, 3);
  int between = 0;
  for (int v = 0; v < 100; ++v) {
    for (int u : {49, 50}) {
      const float z = out.depth[v * 100 + u];
      EXPECT_GE(z, 1.0f);
      EXPECT_LE(z, 1.5f);
      between += z > 1.001f && z < 1.499f;
    }
    EXPECT_EQ(out.depth[v * 100 + 10], 1.5f);
    EXPECT_EQ(out.depth[v * 100 + 90], 1.0f);
  }
  EXPECT_GT(between, 190);
}

TEST(DepthSensor, NoiseFollowsSigmaOfDepthOnATiltedPlane) {
  // A plane whose depth grows down the image (constant along each row) through each preset's
  // range, on the continuous grid: the residuals divided by the analytic sigma(z) = a + b (z -
  // z0)^2 are standard normal in every band of rows and over the whole image.
  const mgn::Intrinsics K = centred_intrinsics(400, 600, 500);
  const std::size_t n = 400 * 600;
  std::vector<std::int32_t> ids(n, 1);
  for (auto preset : {mgn::DepthSensorPreset::StructuredLight, mgn::DepthSensorPreset::ToF}) {
    auto p = mgn::DepthSensorParams::preset_defaults(preset);
    p.depth_step = 0.0;
    p.flying_pixel_probability = 0.0;
    const double z_lo = p.min_range + 0.01, z_hi = p.max_range - 0.01;
    std::vector<float> depth(n);
    for (int v = 0; v < K.height; ++v)
      for (int u = 0; u < K.width; ++u)
        depth[v * K.width + u] = static_cast<float>(z_lo + (z_hi - z_lo) * v / (K.height - 1));
    const auto out = mgn::apply_depth_sensor(depth, ids, {}, K, p, 21);
    std::vector<double> all;
    for (int band = 0; band < 20; ++band) {
      double s = 0, s2 = 0;
      int m = 0;
      for (int v = band * 30; v < band * 30 + 30; ++v)
        for (int u = 0; u < K.width; ++u) {
          const std::size_t i = v * K.width + u;
          ASSERT_TRUE(out.valid[i]) << i;
          const double z = depth[i];
          const double sigma = p.sigma_a + p.sigma_b * (z - p.sigma_z0) * (z - p.sigma_z0);
          const double r = (static_cast<double>(out.depth[i]) - z) / sigma;
          s += r, s2 += r * r, ++m;
          all.push_back(r);
        }
      EXPECT_NEAR(s / m, 0.0, 5.0 / std::sqrt(m)) << band;
      EXPECT_NEAR(s2 / m, 1.0, 5.0 * std::sqrt(2.0 / m)) << band;
    }
    std::sort(all.begin(), all.end());
    double d = 0;
    const double m = static_cast<double>(all.size());
    for (std::size_t i = 0; i < all.size(); ++i) {
      const double F = 0.5 * std::erfc(-all[i] / std::sqrt(2.0));
      d = std::max({d, F - i / m, (i + 1) / m - F});
    }
    EXPECT_LT(std::sqrt(m) * d, 1.95);
  }
}

TEST(DepthSensor, SameBytesForAnyThreadCount) {
  // Boxes on a floor: shadows, edges and flying pixels (ToF) as well as the noise.
  const mgn::Intrinsics K = centred_intrinsics(320, 240, 300);
  std::vector<float> depth(320 * 240, 1.2f);
  std::vector<std::int32_t> ids(320 * 240, 0);
  for (int b = 0; b < 6; ++b)
    for (int v = 20 + 30 * b; v < 60 + 30 * b; ++v)
      for (int u = 15 + 45 * b; u < 70 + 45 * b; ++u)
        depth[v * 320 + u] = 1.2f - 0.03f * (b + 1), ids[v * 320 + u] = b + 1;
  for (auto preset : {mgn::DepthSensorPreset::StructuredLight, mgn::DepthSensorPreset::ToF}) {
    const auto p = mgn::DepthSensorParams::preset_defaults(preset);
    const auto one = mgn::apply_depth_sensor(depth, ids, {}, K, p, 8, 1);
    for (int threads : {2, 3, 0}) {
      const auto other = mgn::apply_depth_sensor(depth, ids, {}, K, p, 8, threads);
      EXPECT_EQ(other.valid, one.valid) << threads;
      EXPECT_EQ(std::memcmp(other.depth.data(), one.depth.data(), one.depth.size() * 4), 0)
          << threads;
    }
    const auto reseeded = mgn::apply_depth_sensor(depth, ids, {}, K, p, 9, 1);
    EXPECT_NE(std::memcmp(reseeded.depth.data(), one.depth.data(), one.depth.size() * 4), 0);
  }
}

TEST(Renderer, ColorTemperatureFollowsPlanck) {
  const mgn::Vec3d white = mgn::color_temperature_rgb(6500.0);
  EXPECT_NEAR(white.minCoeff(), 1.0, 1e-12);
  const mgn::Vec3d warm = mgn::color_temperature_rgb(3000.0);
  const mgn::Vec3d cold = mgn::color_temperature_rgb(10000.0);
  EXPECT_DOUBLE_EQ(warm.x(), 1.0);  // red dominates a warm light
  EXPECT_GT(warm.x(), warm.y());
  EXPECT_GT(warm.y(), warm.z());
  EXPECT_DOUBLE_EQ(cold.z(), 1.0);  // blue dominates a cold one
  EXPECT_LT(cold.x(), cold.y());
  EXPECT_THROW(mgn::color_temperature_rgb(0.0), mgn::InvalidArgument);
}

TEST(Renderer, BackFaceCullingOfClosedMeshesChangesNoPixel) {
  // Closed outward meshes are drawn with back faces culled; the same meshes wound inwards are
  // not culled (culling them would show their insides). Both must give the same depth and ids,
  // and the same colours except on a few silhouette pixels (rasterisation ties).
  const Scene s = test_scene();
  mgn::Renderer culled(400, 400), plain(400, 400);
  for (const auto& m : s.meshes) {
    culled.add_mesh(m);
    plain.add_mesh(m.flipped());
  }
  culled.set_instances(s.instances);
  plain.set_instances(s.instances);
  const auto rig = mgn::mgn_rig(3, {0, 0, 0.05});
  for (int v : {0, 12, 30}) {
    const mgn::CameraView view{small_camera(), rig[v]};
    const auto a = culled.render(view);
    const auto b = plain.render(view);
    std::size_t same_z = 0, same_id = 0, close_rgb = 0;
    for (std::size_t i = 0; i < a.depth.size(); ++i) {
      same_z += std::abs(a.depth[i] - b.depth[i]) < 1e-5f;
      same_id += a.instance_ids[i] == b.instance_ids[i];
      int diff = 0;
      for (int c = 0; c < 3; ++c)
        diff = std::max(diff, std::abs(a.rgb[3 * i + c] - b.rgb[3 * i + c]));
      close_rgb += diff <= 2;
    }
    const double n = static_cast<double>(a.depth.size());
    EXPECT_GE(same_z, 0.999 * n) << v;
    EXPECT_GE(same_id, 0.999 * n) << v;
    EXPECT_GE(close_rgb, 0.995 * n) << v;
  }
}
