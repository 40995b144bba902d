// Tests of mgn/scene/view_labels against boxes under a top-down pinhole camera, where masks,
// occlusion and keypoint visibility follow analytically from projected rectangles.
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/raytrace/ray_scene.hpp>
#include <mgn/scene/view_labels.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace {

constexpr double kH = 1.0;  // camera height above the floor, m

/// Camera 1 m above the world origin looking straight down: image x = world x, image down =
/// world -y.
mgn::Pose top_down() {
  mgn::Pose X = mgn::Pose::Identity();
  X.linear() << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  X.translation() << 0, 0, kH;
  return X;
}

mgn::Intrinsics intrinsics() { return mgn::Intrinsics{200, 200, 200.0, 200.0, 100.0, 100.0}; }

std::size_t pix(int u, int v) { return std::size_t(v) * 200 + u; }

mgn::Pose at(double x, double y, double z) {
  mgn::Pose X = mgn::Pose::Identity();
  X.translation() << x, y, z;
  return X;
}

/// Pixel-centre count of the projection of the world rectangle [x0,x1] x [y0,y1] at height z.
struct Rect {
  int u0, u1, v0, v1;  // inclusive
  long count() const { return long(u1 - u0 + 1) * (v1 - v0 + 1); }
};
Rect project(double x0, double x1, double y0, double y1, double z) {
  const auto K = intrinsics();
  const double depth = kH - z;
  const double ua = K.fx * x0 / depth + K.cx, ub = K.fx * x1 / depth + K.cx;
  const double va = K.fy * -y1 / depth + K.cy, vb = K.fy * -y0 / depth + K.cy;
  // Pixel u is inside when its centre u + 0.5 lies in [ua, ub].
  return Rect{int(std::ceil(ua - 0.5)), int(std::floor(ub - 0.5)), int(std::ceil(va - 0.5)),
              int(std::floor(vb - 0.5))};
}

/// Exact pinhole silhouette of a box: pixels whose centre lies in the convex hull of its 8
/// projected corners (Andrew's monotone chain), computed without ray tracing.
std::vector<std::uint8_t> silhouette(const mgn::Vec3d& extents, const mgn::Pose& X_WO) {
  const auto K = intrinsics();
  const mgn::Pose X_CO = top_down().inverse() * X_WO;
  std::vector<Eigen::Vector2d> pts;
  for (int k = 0; k < 8; ++k) {
    const mgn::Vec3d c(k & 1 ? 0.5 : -0.5, k & 2 ? 0.5 : -0.5, k & 4 ? 0.5 : -0.5);
    const mgn::Vec3d p = X_CO * c.cwiseProduct(extents);
    pts.emplace_back(K.fx * p.x() / p.z() + K.cx, K.fy * p.y() / p.z() + K.cy);
  }
  std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
  };
  std::vector<Eigen::Vector2d> hull(16);
  int k = 0;
  for (int i = 0; i < 8; ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  for (int i = 6, t = k + 1; i >= 0; --i) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  hull.resize(k - 1);  // counter-clockwise (in image coordinates), last point repeated removed
  std::vector<std::uint8_t> mask(200 * 200, 0);
  for (int v = 0; v < 200; ++v) {
    for (int u = 0; u < 200; ++u) {
      const Eigen::Vector2d c(u + 0.5, v + 0.5);
      bool inside = true;
      for (std::size_t j = 0; j < hull.size() && inside; ++j)
        inside = cross(hull[j], hull[(j + 1) % hull.size()], c) >= 0;
      mask[pix(u, v)] = inside;
    }
  }
  return mask;
}

long differing(const std::uint8_t* a, const std::vector<std::uint8_t>& b) {
  long n = 0;
  for (std::size_t i = 0; i < b.size(); ++i) n += (a[i] != 0) != (b[i] != 0);
  return n;
}

long count(const std::vector<std::uint8_t>& m) {
  long n = 0;
  for (auto x : m) n += x != 0;
  return n;
}

/// Instance image by a second, independent route: first hits of the full scene.
std::vector<std::int32_t> instance_image(const std::vector<mgn::RayGeometry>& geoms) {
  mgn::RayScene scene(geoms);
  const auto K = intrinsics();
  mgn::Points3f o, d;
  mgn::camera_rays(K.K(), K.width, K.height, top_down(), o, d);
  const auto hits = scene.intersect(o, d);
  std::vector<std::int32_t> img(hits.instance_ids.size());
  for (std::size_t i = 0; i < img.size(); ++i) img[i] = std::max(hits.instance_ids[i], 0);
  return img;
}

mgn::ViewLabelObject object(const mgn::Mesh& mesh, const mgn::Pose& X, int category) {
  mgn::ViewLabelObject o;
  o.mesh = &mesh;
  o.X_WO = X;
  o.category_id = category;
  return o;
}

}  // namespace

TEST(ViewLabels, BoxesSideBySideAreNotOccludedAndMasksMatchSilhouettes) {
  const mgn::Mesh a = mgn::make_box({0.1, 0.1, 0.05});
  const mgn::Mesh b = mgn::make_box({0.08, 0.12, 0.04});
  const mgn::Pose Xa = at(-0.1, 0.02, 0.025), Xb = at(0.1, -0.03, 0.02);
  const auto img = instance_image({{&a, Xa, 1}, {&b, Xb, 2}});
  mgn::ViewLabelModel model({object(a, Xa, 7), object(b, Xb, 9)});
  const auto L = model.label_view(intrinsics(), top_down(), img.data(), 200, 200);
  ASSERT_EQ(L.num_objects, 2);
  // A lies left of the optical axis: its +x side face is seen too, the silhouette is a hexagon.
  const auto sa = silhouette({0.1, 0.1, 0.05}, Xa), sb = silhouette({0.08, 0.12, 0.04}, Xb);
  EXPECT_LE(differing(L.amodal.data(), sa), 2);
  EXPECT_LE(differing(L.amodal.data() + 40000, sb), 2);
  EXPECT_GT(count(sa), 400);
  EXPECT_EQ(L.visible_pixels[0], L.amodal_pixels[0]);
  EXPECT_EQ(L.visible_pixels[1], L.amodal_pixels[1]);
  EXPECT_DOUBLE_EQ(L.occlusion[0], 0.0);
  EXPECT_DOUBLE_EQ(L.occlusion[1], 0.0);
  const Rect ra = project(-0.15, -0.05, -0.03, 0.07, 0.05);  // top face
  const Rect rb = project(0.06, 0.14, -0.09, 0.03, 0.04);
  EXPECT_EQ(L.bbox_loose(0, 0), ra.u0);
  EXPECT_EQ(L.bbox_loose(0, 1), ra.v0);
  EXPECT_EQ(L.bbox_loose(0, 3), ra.v1 - ra.v0 + 1);
  EXPECT_EQ(L.bbox_tight.row(0), L.bbox_loose.row(0));
  EXPECT_EQ(L.bbox_tight.row(1), L.bbox_loose.row(1));
  EXPECT_EQ(L.semantic[pix((ra.u0 + ra.u1) / 2, (ra.v0 + ra.v1) / 2)], 7);
  EXPECT_EQ(L.semantic[pix((rb.u0 + rb.u1) / 2, (rb.v0 + rb.v1) / 2)], 9);
  EXPECT_EQ(L.semantic[pix(0, 0)], 0);
  // Object pose in the camera: the centre of A lies at depth 1 - 0.025, x = -0.1, y = -0.02.
  const mgn::Vec3d t = L.X_CO[0].translation();
  EXPECT_NEAR(t.x(), -0.1, 1e-12);
  EXPECT_NEAR(t.y(), -0.02, 1e-12);
  EXPECT_NEAR(t.z(), 0.975, 1e-12);
}

TEST(ViewLabels, BoxOnLargerBoxOcclusionEqualsCoveredFraction) {
  const mgn::Mesh a = mgn::make_box({0.1, 0.1, 0.05});  // on top
  const mgn::Mesh b = mgn::make_box({0.3, 0.2, 0.05});  // below
  const mgn::Pose Xa = at(0.02, 0.01, 0.075), Xb = at(0.0, 0.0, 0.025);
  const auto img = instance_image({{&a, Xa, 1}, {&b, Xb, 2}});
  mgn::ViewLabelObject oa = object(a, Xa, 1), ob = object(b, Xb, 2);
  oa.keypoints.resize(1, 4);
  oa.keypoints << 1, 0, 0, 0.025;  // top face centre of A: visible
  ob.keypoints.resize(3, 4);
  ob.keypoints << 1, 0.02, 0.01, 0.025,  // top face of B, under A: occluded
      2, 0.13, 0.0, 0.025,               // top face of B, uncovered: visible
      3, 0.13, 0.0, -0.025;              // bottom face of B: hidden by B itself
  ob.com_O = mgn::Vec3d::Zero();
  mgn::ViewLabelModel model({oa, ob});
  const auto L = model.label_view(intrinsics(), top_down(), img.data(), 200, 200);

  const Rect rb = project(-0.15, 0.15, -0.1, 0.1, 0.05);
  const Rect ra = project(-0.03, 0.07, -0.04, 0.06, 0.1);
  EXPECT_EQ(L.amodal_pixels[1], rb.count());
  EXPECT_EQ(L.amodal_pixels[0], ra.count());
  EXPECT_LE(differing(L.amodal.data() + 40000, silhouette({0.3, 0.2, 0.05}, Xb)), 2);
  // Covered fraction of B = A's projected pixels over B's (A lies inside B in the image).
  const double covered = double(ra.count()) / double(rb.count());
  EXPECT_NEAR(L.occlusion[1], covered, 1e-12);
  // Continuous areas give the same within the pixel rounding of the rectangles' perimeters.
  const double area_a = std::pow(200 * 0.1 / 0.9, 2),
               area_b = (200 * 0.3 / 0.95) * (200 * 0.2 / 0.95);
  EXPECT_NEAR(L.occlusion[1], area_a / area_b, 2.0 * (4 * 22.2) / area_b);
  EXPECT_DOUBLE_EQ(L.occlusion[0], 0.0);
  // Every amodal mask contains its visible mask; occlusion map carries the rate.
  for (int i = 0; i < 2; ++i) {
    for (std::size_t p = 0; p < 200 * 200; ++p) {
      if (L.visible[p] == i + 1) {
        ASSERT_EQ(L.amodal[i * 40000 + p], 1);
        ASSERT_FLOAT_EQ(L.occlusion_map[p], float(L.occlusion[i]));
      }
    }
  }
  // B's loose box is its full rectangle; its tight box too (the border of B stays visible).
  EXPECT_EQ(L.bbox_loose(1, 0), rb.u0);
  EXPECT_EQ(L.bbox_loose(1, 2), rb.u1 - rb.u0 + 1);
  EXPECT_EQ(L.bbox_tight.row(1), L.bbox_loose.row(1));

  // Keypoints: A's top visible; B's: 2 visible, 1 and 3 occluded.
  ASSERT_EQ(L.keypoints.rows(), 2);
  ASSERT_EQ(L.occluded_keypoints.rows(), 2);
  EXPECT_EQ(L.keypoint_object, (std::vector<std::int32_t>{0, 1}));
  EXPECT_EQ(L.keypoints(0, 0), 1);
  EXPECT_EQ(L.keypoints(1, 0), 2);
  EXPECT_EQ(L.occluded_keypoint_object, (std::vector<std::int32_t>{1, 1}));
  EXPECT_EQ(L.occluded_keypoints(0, 0), 1);
  EXPECT_EQ(L.occluded_keypoints(1, 0), 3);
  // Camera-frame coordinates: B's keypoint 2 at world (0.13, 0, 0.05) -> (0.13, 0, 0.95).
  EXPECT_NEAR(L.keypoints(1, 1), 0.13, 1e-12);
  EXPECT_NEAR(L.keypoints(1, 2), 0.0, 1e-12);
  EXPECT_NEAR(L.keypoints(1, 3), 0.95, 1e-12);

  // Heat map at a visible pixel of B: its ray hits B's top (z = 0.05) at a known point; without
  // CoM points d_min = 0 and d_max = half the diagonal of B.
  const int u = rb.u0 + 2, v = 100;
  ASSERT_EQ(L.visible[pix(u, v)], 2);
  const double depth = 0.95;
  const mgn::Vec3d p((u + 0.5 - 100.0) / 200.0 * depth, -(v + 0.5 - 100.0) / 200.0 * depth, 0.05);
  const double d = (p - mgn::Vec3d(0, 0, 0.025)).norm();
  const double d_max = std::sqrt(0.15 * 0.15 + 0.1 * 0.1 + 0.025 * 0.025);
  EXPECT_NEAR(L.com_heatmap[pix(u, v)], (d_max - d) / d_max, 1e-4);
  EXPECT_EQ(L.com_heatmap[pix(0, 0)], 0.0f);

  // With a depth image (here the analytic z of the top faces) the heat map is the same formula
  // on the back-projected pixels, and nothing else changes.
  std::vector<float> depth_image(200 * 200, 0.0f);
  for (std::size_t q = 0; q < depth_image.size(); ++q) {
    if (L.visible[q] == 1) depth_image[q] = 0.9f;
    if (L.visible[q] == 2) depth_image[q] = 0.95f;
  }
  mgn::ViewLabelOptions with_depth;
  with_depth.depth = depth_image.data();
  const auto Ld = model.label_view(intrinsics(), top_down(), img.data(), 200, 200, with_depth);
  EXPECT_NEAR(Ld.com_heatmap[pix(u, v)], (d_max - d) / d_max, 1e-6);
  EXPECT_EQ(Ld.amodal, L.amodal);
  EXPECT_EQ(Ld.occlusion, L.occlusion);
  for (std::size_t q = 0; q < depth_image.size(); ++q)
    ASSERT_NEAR(Ld.com_heatmap[q], L.com_heatmap[q], 1e-4) << q;
}

TEST(ViewLabels, OneAndTwoThreadsGiveIdenticalLabels) {
  const mgn::Mesh a = mgn::make_box({0.1, 0.1, 0.05});
  const mgn::Mesh b = mgn::make_sphere(0.08, 24, 12);
  const mgn::Mesh tote = mgn::make_box({0.6, 0.6, 0.01});
  const mgn::Pose Xa = at(0.03, 0.0, 0.2), Xb = at(0.0, 0.02, 0.08), Xt = at(0, 0, -0.005);
  const auto img = instance_image({{&a, Xa, 1}, {&b, Xb, 2}, {&tote, Xt, 0}});
  mgn::ViewLabelObject oa = object(a, Xa, 1), ob = object(b, Xb, 2);
  ob.com_points.resize(50, 4);
  for (int k = 0; k < 50; ++k) {
    const double th = 0.3 * k, ph = 0.11 * k;
    ob.com_points.row(k) << 0.5, 0.08 * std::cos(th) * std::sin(ph),
        0.08 * std::sin(th) * std::sin(ph), 0.08 * std::cos(ph);
  }
  mgn::ViewLabelModel model({oa, ob}, &tote, Xt);
  EXPECT_TRUE(model.has_tote());
  mgn::ViewLabelOptions one, two;
  one.num_threads = 1;
  two.num_threads = 2;
  const auto L1 = model.label_view(intrinsics(), top_down(), img.data(), 200, 200, one);
  const auto L2 = model.label_view(intrinsics(), top_down(), img.data(), 200, 200, two);
  EXPECT_EQ(L1.amodal, L2.amodal);
  EXPECT_EQ(L1.com_heatmap, L2.com_heatmap);
  EXPECT_EQ(L1.occlusion, L2.occlusion);
  EXPECT_EQ(L1.com_visible, L2.com_visible);
  EXPECT_EQ(L1.com_points, L2.com_points);
  EXPECT_GT(L1.occlusion[1], 0.2);  // the sphere is partly under the box
  EXPECT_LT(L1.occlusion[1], 1.0);
  // Upper hemisphere points of the sphere outside A's shadow are visible, lower ones never.
  int lower_visible = 0, upper_visible = 0;
  for (int k = 0; k < 50; ++k) {
    const bool vis = L1.com_visible[k];
    if (ob.com_points(k, 3) < -0.01) lower_visible += vis;
    if (ob.com_points(k, 3) > 0.01) upper_visible += vis;
  }
  EXPECT_EQ(lower_visible, 0);
  EXPECT_GT(upper_visible, 0);
}

TEST(ViewLabels, BadInputIsRejectedWithClearErrors) {
  const mgn::Mesh a = mgn::make_box({0.1, 0.1, 0.05});
  EXPECT_THROW(mgn::ViewLabelModel({}), mgn::InvalidArgument);
  EXPECT_THROW(mgn::ViewLabelModel({object(a, at(0, 0, 0), 0)}), mgn::InvalidArgument);
  mgn::Pose skew = at(0, 0, 0);
  skew.linear()(0, 1) = 0.5;
  EXPECT_THROW(mgn::ViewLabelModel({object(a, skew, 1)}), mgn::InvalidArgument);
  mgn::ViewLabelModel model({object(a, at(0, 0, 0.025), 1)});
  std::vector<std::int32_t> img(200 * 200, 0);
  EXPECT_THROW(model.label_view(intrinsics(), top_down(), img.data(), 100, 200),
               mgn::InvalidArgument);
  EXPECT_THROW(model.label_view(intrinsics(), top_down(), nullptr, 200, 200), mgn::InvalidArgument);
  img[pix(3, 4)] = 2;  // only one object
  try {
    model.label_view(intrinsics(), top_down(), img.data(), 200, 200);
    FAIL() << "expected InvalidArgument";
  } catch (const mgn::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("(u=3, v=4) has id 2"), std::string::npos) << e.what();
  }
  img[pix(3, 4)] = -1;
  EXPECT_THROW(model.label_view(intrinsics(), top_down(), img.data(), 200, 200),
               mgn::InvalidArgument);
}

TEST(ViewLabels, UnseenObjectHasEmptyMasksAndFullOcclusion) {
  const mgn::Mesh a = mgn::make_box({0.1, 0.1, 0.05});
  // Behind the camera: nothing projects; the amodal pass must still be empty.
  mgn::ViewLabelModel model({object(a, at(0, 0, 0.025), 1), object(a, at(0, 0, 2.0), 2)});
  const auto img = instance_image({{&a, at(0, 0, 0.025), 1}});
  const auto L = model.label_view(intrinsics(), top_down(), img.data(), 200, 200);
  EXPECT_EQ(L.amodal_pixels[1], 0);
  EXPECT_EQ(L.visible_pixels[1], 0);
  EXPECT_DOUBLE_EQ(L.occlusion[1], 1.0);
  EXPECT_EQ(L.bbox_loose.row(1), (Eigen::Matrix<std::int32_t, 1, 4>::Zero()));
  EXPECT_EQ(L.bbox_tight.row(1), (Eigen::Matrix<std::int32_t, 1, 4>::Zero()));
}

// com_heatmap_prediction on points placed by hand: an identity camera pose, fx = fy = 1 and
// cx = cy = 0, so pixel (u, v) at depth z is the point ((u + 0.5) z, (v + 0.5) z, z).
TEST(ViewLabels, ComHeatmapPredictionScoresPointsPlacedByHand) {
  const int W = 3, H = 2;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  // Row 0: instance 1 at z 2, 2, 2; row 1: instance 2 at z 2, background, NaN depth.
  const std::vector<float> depth = {2.0f, 2.0f, 2.0f, 2.0f, 2.0f, nan};
  const std::vector<std::int32_t> ids = {1, 1, 1, 2, 0, 2};
  double X[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const double K4[4] = {1.0, 1.0, 0.0, 0.0};  // fx, fy, cx, cy
  // Pixel (0, 0) is (1, 1, 2): instance 1's centre there (d = 0 -> 1.5 / 1, clamped to 1);
  // (1, 0) is (3, 1, 2): d = 2 -> (1.5 - 2) / 1 < 0 -> 0; (2, 0) is (5, 1, 2): d = 4 -> 0.
  // Instance 2's centre 1 m from (1, 3, 2) along x: d = 1 -> (1.5 - 1) / (1.5 - 0.5) = 0.5.
  const std::vector<double> params = {1, 1, 2, 0.5, 1.5, 0, 3, 2, 0.5, 1.5};
  std::vector<float> out(W * H, -1.0f);
  mgn::com_heatmap_prediction(depth.data(), ids.data(), W, H, X, K4, params.data(), 2, out.data());
  EXPECT_EQ(out[0], 1.0f);
  EXPECT_EQ(out[1], 0.0f);
  EXPECT_EQ(out[2], 0.0f);
  EXPECT_EQ(out[3], 0.5f);
  EXPECT_EQ(out[4], 0.0f);  // background
  EXPECT_EQ(out[5], 0.0f);  // no depth
  // Moving the camera 1 m along x moves every world point: pixel (1, 0) is then (4, 1, 2).
  X[3] = 1.0;
  const std::vector<double> far = {4, 1, 2, 0.5, 1.5, 0, 3, 2, 0.5, 1.5};
  mgn::com_heatmap_prediction(depth.data(), ids.data(), W, H, X, K4, far.data(), 2, out.data());
  EXPECT_EQ(out[1], 1.0f);
  EXPECT_EQ(out[3], 0.0f);  // (2, 3, 2) is 2 m from (0, 3, 2)
  // An instance id above the rows of com_parameters is refused.
  EXPECT_THROW(mgn::com_heatmap_prediction(depth.data(), ids.data(), W, H, X, K4, params.data(), 1,
                                           out.data()),
               mgn::InvalidArgument);
}
