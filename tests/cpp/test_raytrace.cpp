// Tests of mgn/raytrace against analytic shapes.
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/raytrace/ray_scene.hpp>

#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "grasp/detail/seal_trials.hpp"
#include "raytrace/parallel_rays.hpp"
#include "raytrace/ray_scene_impl.hpp"

namespace {

mgn::Points3f rows(std::initializer_list<mgn::Vec3f> list) {
  mgn::Points3f p(static_cast<Eigen::Index>(list.size()), 3);
  Eigen::Index i = 0;
  for (const auto& v : list) p.row(i++) = v.transpose();
  return p;
}

/// Random rays from a sphere of radius 0.3 towards random points in the 0.2 cube.
void random_rays(int n, std::uint64_t seed, mgn::Points3f& o, mgn::Points3f& d) {
  mgn::Rng rng(seed, 0);
  o.resize(n, 3);
  d.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    mgn::Vec3d a(rng.normal(), rng.normal(), rng.normal());
    a = 0.3 * a.normalized();
    const mgn::Vec3d t(rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1));
    o.row(i) = a.cast<float>().transpose();
    d.row(i) = (t - a).normalized().cast<float>().transpose();
  }
}

}  // namespace

TEST(RayScene, BoxHitsMatchAnalyticDistancesNormalsAndIds) {
  const mgn::Mesh box = mgn::make_box({0.2, 0.2, 0.2});
  mgn::Pose X = mgn::Pose::Identity();
  X.translation() << 0.0, 0.0, 0.1;  // box on the floor: top at z = 0.2
  mgn::RayScene scene({mgn::RayGeometry{&box, X, 5}});
  const auto o = rows({{0.05f, 0.02f, 1.0f}, {1.0f, 0.0f, 0.1f}, {0.5f, 0.5f, 1.0f}});
  const auto d = rows({{0, 0, -1}, {-1, 0, 0}, {0, 0, -1}});
  const auto h = scene.intersect(o, d);
  EXPECT_NEAR(h.distance[0], 0.8f, 1e-6f);
  EXPECT_NEAR(h.normals(0, 2), 1.0f, 1e-6f);
  EXPECT_EQ(h.instance_ids[0], 5);
  EXPECT_NEAR(h.distance[1], 0.9f, 1e-6f);
  EXPECT_NEAR(h.normals(1, 0), 1.0f, 1e-6f);
  EXPECT_TRUE(std::isinf(h.distance[2]));
  EXPECT_EQ(h.instance_ids[2], -1);
  EXPECT_EQ(h.face_ids[2], -1);
  // tfar shorter than the hit: miss; tnear past the entry: the exit (bottom) face is hit.
  mgn::CastOptions near_far;
  near_far.tfar = 0.5f;
  EXPECT_EQ(scene.intersect(o, d, near_far).instance_ids[0], -1);
  mgn::CastOptions skip;
  skip.tnear = 0.85f;
  EXPECT_NEAR(scene.intersect(o, d, skip).distance[0], 1.0f, 1e-6f);
  const auto occ = scene.occluded(o, d);
  EXPECT_EQ(occ[0], 1);
  EXPECT_EQ(occ[2], 0);
}

TEST(RayScene, SphereDistancesAndAllHits) {
  const double r = 0.1;
  const mgn::Mesh sphere = mgn::make_sphere(r, 256, 128);
  mgn::RayScene scene({mgn::RayGeometry{&sphere, mgn::Pose::Identity(), 0}});
  mgn::Points3f o, d;
  random_rays(2000, 7, o, d);
  const auto h = scene.intersect(o, d);
  const auto all = scene.intersect_all(o, d);
  int hits = 0;
  for (int i = 0; i < o.rows(); ++i) {
    // Analytic ray-sphere intersection.
    const mgn::Vec3d oo = o.row(i).transpose().cast<double>(),
                     dd = d.row(i).transpose().cast<double>();
    const double b = oo.dot(dd), c = oo.squaredNorm() - r * r, disc = b * b - c;
    const auto count = all.offsets[i + 1] - all.offsets[i];
    if (disc > 1e-3 * r * r) {  // clearly hits the true sphere (the mesh is inscribed)
      ++hits;
      EXPECT_EQ(count, 2) << i;   // in and out, edge crossings reported once
      if (disc > 0.05 * r * r) {  // away from grazing, the tessellation error is tiny
        EXPECT_NEAR(h.distance[i], -b - std::sqrt(disc), 1e-4) << i;
        EXPECT_NEAR(all.distance[all.offsets[i] + 1], -b + std::sqrt(disc), 1e-4) << i;
      }
    } else if (disc < -1e-4 * r * r) {
      EXPECT_EQ(h.instance_ids[i], -1);
      EXPECT_EQ(count, 0);
    }
  }
  EXPECT_GT(hits, 100);
}

TEST(RayScene, EdgeAndVertexRaysAreCountedOnce) {
  const mgn::Mesh box = mgn::make_box({0.2, 0.2, 0.2});
  mgn::RayScene scene({mgn::RayGeometry{&box, mgn::Pose::Identity(), 0}});
  // Along the diagonal of the top and bottom faces (the shared edge of their two triangles),
  // and straight through two opposite vertices' neighbourhood along z at a face-diagonal point.
  const auto o = rows({{0.0f, 0.0f, 1.0f}, {0.05f, 0.05f, 1.0f}, {-0.05f, 0.05f, 1.0f}});
  const auto d = rows({{0, 0, -1}, {0, 0, -1}, {0, 0, -1}});
  const auto all = scene.intersect_all(o, d);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(all.offsets[i + 1] - all.offsets[i], 2) << "ray " << i;
}

TEST(RayScene, ThreadsAndPacketsGiveIdenticalResults) {
  const mgn::Mesh sphere = mgn::make_sphere(0.08, 64, 32);
  const mgn::Mesh box = mgn::make_box({0.1, 0.05, 0.12});
  mgn::Pose X = mgn::Pose::Identity();
  X.translation() << 0.05, 0.0, 0.02;
  X.rotate(Eigen::AngleAxisd(0.4, mgn::Vec3d(1, 1, 0).normalized()));
  mgn::RayScene scene(
      {mgn::RayGeometry{&sphere, mgn::Pose::Identity(), 0}, mgn::RayGeometry{&box, X, 1}});
  mgn::Points3f o, d;
  random_rays(20011, 11, o, d);  // not a multiple of 16: exercises the packet tail
  mgn::CastOptions one, two, packets;
  one.num_threads = 1;
  two.num_threads = 2;
  packets.num_threads = 2;
  packets.coherent = true;
  const auto a = scene.intersect(o, d, one), b = scene.intersect(o, d, two),
             c = scene.intersect(o, d, packets);
  EXPECT_EQ(a.distance, b.distance);
  EXPECT_EQ(a.face_ids, b.face_ids);
  EXPECT_EQ(a.instance_ids, c.instance_ids);
  EXPECT_EQ(a.face_ids, c.face_ids);
  for (std::size_t i = 0; i < a.distance.size(); ++i) {
    if (a.instance_ids[i] >= 0) {
      EXPECT_NEAR(a.distance[i], c.distance[i], 1e-6f);
    }
  }
  EXPECT_EQ(scene.occluded(o, d, one), scene.occluded(o, d, packets));
  const auto all1 = scene.intersect_all(o, d, 64, one), all2 = scene.intersect_all(o, d, 64, two);
  EXPECT_EQ(all1.offsets, all2.offsets);
  EXPECT_EQ(all1.distance, all2.distance);
}

TEST(RayScene, WithoutAllHitsGivesTheSameFirstHitsAndOcclusion) {
  // The path tracer's scene (all_hits = false) against the default one: same bits for every
  // first hit and occlusion query, single rays and packets; intersect_all is refused.
  const mgn::Mesh sphere = mgn::make_sphere(0.08, 64, 32);
  const mgn::Mesh box = mgn::make_box({0.1, 0.05, 0.12});
  mgn::Pose X = mgn::Pose::Identity();
  X.translation() << 0.05, 0.0, 0.02;
  const std::vector<mgn::RayGeometry> g{mgn::RayGeometry{&sphere, mgn::Pose::Identity(), 0},
                                        mgn::RayGeometry{&box, X, 1}};
  const mgn::RayScene with(g), without(g, false);
  mgn::Points3f o, d;
  random_rays(5003, 12, o, d);
  for (const bool coherent : {false, true}) {
    mgn::CastOptions opt;
    opt.coherent = coherent;
    const auto a = with.intersect(o, d, opt), b = without.intersect(o, d, opt);
    EXPECT_EQ(a.distance, b.distance);
    EXPECT_EQ(a.face_ids, b.face_ids);
    EXPECT_EQ(a.instance_ids, b.instance_ids);
    EXPECT_EQ(with.occluded(o, d, opt), without.occluded(o, d, opt));
  }
  EXPECT_GT(with.intersect_all(o, d).distance.size(), 0u);
  EXPECT_THROW(without.intersect_all(o, d), mgn::Unsupported);
}

TEST(RayScene, RejectsBadInput) {
  const mgn::Mesh box = mgn::make_box({0.1, 0.1, 0.1});
  EXPECT_THROW(mgn::RayScene({}), mgn::InvalidArgument);
  mgn::Pose nan_pose = mgn::Pose::Identity();
  nan_pose.translation().x() = std::nan("");
  EXPECT_THROW(mgn::RayScene({mgn::RayGeometry{&box, nan_pose, 0}}), mgn::InvalidArgument);
  mgn::RayScene scene({mgn::RayGeometry{&box, mgn::Pose::Identity(), 0}});
  EXPECT_THROW(scene.intersect(rows({{0, 0, 1}}), rows({{0, 0, 0}})), mgn::InvalidArgument);
  EXPECT_THROW(scene.intersect(rows({{0, 0, 1}, {0, 0, 1}}), rows({{0, 0, -1}})),
               mgn::InvalidArgument);
  EXPECT_THROW(scene.intersect_all(rows({{0, 0, 1}}), rows({{0, 0, -1}}), 0), mgn::InvalidArgument);
}

TEST(CameraRays, CentrePixelLooksAlongTheOpticalAxis) {
  mgn::Mat3d K;
  K << 100, 0, 2, 0, 100, 1.5, 0, 0, 1;  // 4x3 image, principal point at the centre
  mgn::Pose X_WC = mgn::Pose::Identity();
  X_WC.translation() << 0, 0, 1;
  X_WC.linear() =
      Eigen::AngleAxisd(M_PI, mgn::Vec3d::UnitX()).toRotationMatrix();  // looking down -z
  mgn::Points3f o, d;
  mgn::camera_rays(K, 4, 3, X_WC, o, d);
  ASSERT_EQ(o.rows(), 12);
  // Pixel (u=1, v=1) centre is at (1.5, 1.5): x offset -0.5 px, y on axis.
  const Eigen::RowVector3f dir = d.row(1 * 4 + 1);
  EXPECT_NEAR(dir.norm(), 1.0f, 1e-6f);
  EXPECT_NEAR(dir.z(), -1.0f, 1e-4f);
  EXPECT_NEAR(dir.x(), -0.005f, 1e-4f);
  EXPECT_NEAR(dir.y(), 0.0f, 1e-6f);
}

// The private parallel-ray fast paths (packets, used by the suction seal trials) against one
// plain cast per ray through the public API: same hits, distances, normals and any/all answers,
// for bundles whose size is no multiple of the packet width and that straddle silhouettes.
TEST(ParallelRays, PacketPathsEqualOneCastPerRay) {
  const mgn::Mesh sphere = mgn::make_sphere(0.05, 48, 24);
  const mgn::Mesh box = mgn::make_box({0.04, 0.03, 0.02});
  mgn::Pose X = mgn::Pose::Identity();
  X.translation() << 0.06, 0.0, 0.0;
  mgn::RayScene scene(
      {mgn::RayGeometry{&sphere, mgn::Pose::Identity(), 0}, mgn::RayGeometry{&box, X, 1}});
  mgn::Rng rng(5, 0);
  int bundles_with_hits_and_misses = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const int count = std::array<int, 5>{1, 7, 37, 129, 1000}[trial % 5];
    std::vector<Eigen::Vector2d> offsets(static_cast<std::size_t>(count));
    for (auto& p : offsets) {
      const double rho = std::sqrt(rng.uniform(0.0, 1.0)), phi = rng.uniform(0.0, 2 * M_PI);
      p = Eigen::Vector2d(rho * std::cos(phi), rho * std::sin(phi));
    }
    mgn::Vec3d dir(rng.normal(), rng.normal(), rng.normal());
    dir.normalize();
    mgn::Vec3d u, v;
    mgn::detail::tangent_frame(dir, u, v);
    // Aim near the sphere's silhouette (radius 0.05) or the box, bundle radius 5-20 mm.
    const mgn::Vec3d aim = (trial % 3 == 0) ? mgn::Vec3d(0.07, rng.uniform(-0.02, 0.02), 0.0)
                                            : mgn::Vec3d(rng.uniform(0.03, 0.06) * u);
    const double scale = rng.uniform(0.005, 0.02);
    const mgn::detail::ParallelRays rays{aim - 0.3 * dir, u, v, dir, offsets.data(), count, scale};
    mgn::Points3f o(count, 3), d(count, 3);
    for (int i = 0; i < count; ++i) {
      const auto& off = offsets[static_cast<std::size_t>(i)];
      o.row(i) = (rays.base + scale * (off.x() * u + off.y() * v)).cast<float>().transpose();
      d.row(i) = dir.cast<float>().transpose();
    }
    mgn::CastOptions single;
    single.num_threads = 1;
    const mgn::RayHits ref = scene.intersect(o, d, single);
    const std::vector<std::uint8_t> occ = scene.occluded(o, d, single);
    std::vector<float> t(static_cast<std::size_t>(count));
    std::vector<mgn::Vec3f> n(static_cast<std::size_t>(count));
    mgn::detail::parallel_first_hits(scene, rays, t.data(), n.data());
    int hits = 0;
    for (int i = 0; i < count; ++i) {
      const bool hit = ref.instance_ids[static_cast<std::size_t>(i)] >= 0;
      hits += hit;
      ASSERT_EQ(std::isfinite(t[static_cast<std::size_t>(i)]), hit) << "trial " << trial;
      ASSERT_EQ(occ[static_cast<std::size_t>(i)] != 0, hit) << "trial " << trial;
      if (!hit) continue;
      EXPECT_NEAR(t[static_cast<std::size_t>(i)], ref.distance[static_cast<std::size_t>(i)], 1e-6f);
      EXPECT_EQ(n[static_cast<std::size_t>(i)], ref.normals.row(i).transpose()) << "ray " << i;
    }
    EXPECT_EQ(mgn::detail::parallel_all_hit(scene, rays), hits == count) << "trial " << trial;
    EXPECT_EQ(mgn::detail::parallel_any_hit(scene, rays), hits > 0) << "trial " << trial;
    bundles_with_hits_and_misses += hits > 0 && hits < count;
  }
  EXPECT_GE(bundles_with_hits_and_misses, 10);  // the silhouette cases are exercised
}

namespace {

/// First hit (geomID, primID, t) of one ray in an Embree scene; geomID -1 for a miss.
struct FirstHit {
  int geom = -1;
  int prim = -1;
  float t = 0.0f;
};
FirstHit first_hit(RTCScene scene, const mgn::Vec3f& o, const mgn::Vec3f& d) {
  mgn::detail::FtzDazGuard guard;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh{};
  rh.ray.org_x = o.x();
  rh.ray.org_y = o.y();
  rh.ray.org_z = o.z();
  rh.ray.dir_x = d.x();
  rh.ray.dir_y = d.y();
  rh.ray.dir_z = d.z();
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = std::numeric_limits<float>::infinity();
  rh.ray.mask = 0xFFFFFFFFu;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return {};
  return {static_cast<int>(rh.hit.geomID), static_cast<int>(rh.hit.primID), rh.ray.tfar};
}

}  // namespace

TEST(NonRobustScene, SameFirstHitsAsTheRobustSceneWithinFloatPrecision) {
  // The path tracer's bounce and shadow BVH (no RTC_SCENE_FLAG_ROBUST) over the geometries of
  // a RayScene: the same surfaces at the same distances (to float precision) for random rays.
  const mgn::Mesh sphere = mgn::make_sphere(0.08, 64, 32);
  const mgn::Mesh box = mgn::make_box({0.1, 0.05, 0.12});
  mgn::Pose X = mgn::Pose::Identity();
  X.translation() << 0.05, 0.0, 0.02;
  X.rotate(Eigen::AngleAxisd(0.4, mgn::Vec3d(1, 1, 0).normalized()));
  const mgn::RayScene scene(
      {mgn::RayGeometry{&sphere, mgn::Pose::Identity(), 0}, mgn::RayGeometry{&box, X, 1}}, false);
  const mgn::detail::OwnedScene fast = mgn::detail::non_robust_scene(scene);
  ASSERT_NE(fast.get(), nullptr);
  mgn::Points3f o, d;
  random_rays(20000, 13, o, d);
  int hits = 0, same_face = 0;
  for (Eigen::Index i = 0; i < o.rows(); ++i) {
    const mgn::Vec3f oi = o.row(i).transpose(), di = d.row(i).transpose();
    const FirstHit a = first_hit(scene.impl().scene, oi, di), b = first_hit(fast.get(), oi, di);
    ASSERT_EQ(a.geom, b.geom) << "ray " << i;  // the same object, hit or miss
    if (a.geom < 0) continue;
    ++hits;
    same_face += a.prim == b.prim;
    EXPECT_NEAR(a.t, b.t, 1e-6f * (1.0f + a.t)) << "ray " << i;
  }
  EXPECT_GT(hits, 10000);
  EXPECT_GE(same_face, hits - 10);  // a different face only through a shared edge
}

TEST(NonRobustScene, RandomRaysFromInsideClosedMeshesDoNotEscape) {
  // Light leaks: Embree's non-robust triangle test is not watertight (rays aimed exactly at the
  // vertices and edge midpoints of a closed UV sphere escape it: ~8 % of them, measured), so the
  // labels and camera rays stay on the robust scene. The path tracer's bounce and shadow rays
  // have random directions, for which the slits have (nearly) zero measure: none of these rays
  // from random points inside a closed sphere and a closed box escapes, robust or not.
  for (int which = 0; which < 2; ++which) {
    const mgn::Mesh mesh =
        which == 0 ? mgn::make_sphere(0.5, 96, 48) : mgn::make_box({0.6, 0.4, 0.5});
    const mgn::RayScene scene({mgn::RayGeometry{&mesh, mgn::Pose::Identity(), 0}}, false);
    const mgn::detail::OwnedScene fast = mgn::detail::non_robust_scene(scene);
    mgn::Rng rng(5, static_cast<std::uint64_t>(which));
    int escaped_robust = 0, escaped_fast = 0;
    for (int i = 0; i < 300000; ++i) {
      const mgn::Vec3f o(static_cast<float>(rng.uniform(-0.19, 0.19)),
                         static_cast<float>(rng.uniform(-0.19, 0.19)),
                         static_cast<float>(rng.uniform(-0.19, 0.19)));
      const mgn::Vec3f d =
          mgn::Vec3d(rng.normal(), rng.normal(), rng.normal()).normalized().cast<float>();
      escaped_robust += first_hit(scene.impl().scene, o, d).geom < 0;
      escaped_fast += first_hit(fast.get(), o, d).geom < 0;
    }
    EXPECT_EQ(escaped_robust, 0) << "mesh " << which;
    EXPECT_EQ(escaped_fast, 0) << "mesh " << which;
  }
}
