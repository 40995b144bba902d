// Antipodal sampler and parallel-jaw wrench score (MODELS.md §5) on analytic shapes.
#include <gtest/gtest.h>
#include <mgn/collision/collision_model.hpp>
#include <mgn/core/error.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/geometry/sampling.hpp>
#include <mgn/grasp/antipodal.hpp>
#include <mgn/grasp/pj_wrench.hpp>

#include <Eigen/Geometry>
#include <cmath>

namespace mgn {
namespace {

Points3d rows(std::initializer_list<Vec3d> vs) {
  Points3d out(static_cast<Eigen::Index>(vs.size()), 3);
  Eigen::Index i = 0;
  for (const Vec3d& v : vs) out.row(i++) = v.transpose();
  return out;
}

// Independent collision check: the whole gripper merged into one mesh at the collision opening.
bool gripper_collides(const Mesh& object, const ParallelJawGripper& g,
                      const ParallelJawGrasp& grasp) {
  const GripperMeshes m = gripper_meshes(g, g.collision_opening(grasp.width));
  const CollisionModel hand(Mesh::merge({m.palm, m.finger_left, m.finger_right}));
  const CollisionModel obj(object);
  return collide(hand, hand_pose(grasp, g), obj, Pose::Identity());
}

// Box 40 x 60 x 120 mm: faces x (40 mm) and y (60 mm) are graspable, z (120 mm) is not.
TEST(Antipodal, BoxFacesNarrowerThanTheOpeningScoreOneLongSideZero) {
  const Mesh box = make_box(Vec3d(0.04, 0.06, 0.12));
  const Points3d p = rows({{0.02, 0.0, 0.0},
                           {-0.02, 0.01, 0.02},
                           {0.0, 0.03, 0.0},
                           {0.0, 0.0, 0.06},
                           {0.005, 0.0, -0.06}});
  const Points3d n = rows({{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, -1}});
  ParallelJawGripper g;
  AntipodalOptions o;
  o.seed = 7;
  const AntipodalResult r = sample_antipodal_grasps(box, p, n, g, o);
  ASSERT_EQ(r.point_score.size(), 5u);
  EXPECT_FLOAT_EQ(r.point_score[0], 1.0f);
  EXPECT_FLOAT_EQ(r.point_score[1], 1.0f);
  EXPECT_FLOAT_EQ(r.point_score[2], 1.0f);
  EXPECT_FLOAT_EQ(r.point_score[3], 0.0f);
  EXPECT_FLOAT_EQ(r.point_score[4], 0.0f);
  EXPECT_EQ(r.num_accepted_probes, 15);
  EXPECT_EQ(r.num_kept[3], 0);
  EXPECT_EQ(r.num_kept[4], 0);
  // The last accepted probe is used too: every one of the 5 probes of point 0 yields grasps.
  std::array<int, 5> per_probe{};
  for (const AntipodalGrasp& a : r.grasps) {
    if (a.point_index == 0) ++per_probe[a.probe];
  }
  for (int k = 0; k < 5; ++k) EXPECT_GT(per_probe[k], 0) << "probe " << k;
  for (const AntipodalGrasp& a : r.grasps) {
    const ParallelJawGrasp& gr = a.grasp;
    EXPECT_NEAR(gr.closing.norm(), 1.0, 1e-9);
    EXPECT_NEAR(gr.approach.norm(), 1.0, 1e-9);
    EXPECT_NEAR(gr.closing.dot(gr.approach), 0.0, 1e-9);
    EXPECT_LE(gr.width, g.max_opening);
    EXPECT_FLOAT_EQ(a.score, r.point_score[a.point_index]);
    // Width across x is 40 mm (up to the tilt: 40 / cos(tilt) <= 42 mm), across y 60 mm.
    const double across = a.point_index == 2 ? 0.06 : 0.04;
    EXPECT_GE(gr.width, across - 1e-5);
    EXPECT_LE(gr.width, across / std::cos(std::sqrt(2.0) * o.tilt) + 1e-5);
    // Both contacts on the box surface: p1 on the start face.
    EXPECT_NEAR(std::abs(gr.p1[a.point_index == 2 ? 1 : 0]), across / 2, 1e-5);
    EXPECT_LE(static_cast<int>(r.num_kept[a.point_index]), 5 * o.approaches_kept);
    EXPECT_FALSE(gripper_collides(box, g, gr));
  }
  EXPECT_GT(r.num_colliding, 0);  // approaches along z into the long box hit the palm
}

TEST(Antipodal, CollisionFilterRemovesExactlyTheCollidingApproaches) {
  const Mesh box = make_box(Vec3d(0.04, 0.06, 0.12));
  const Points3d p = rows({{0.02, 0.0, 0.0}, {0.0, -0.03, 0.01}});
  const Points3d n = rows({{1, 0, 0}, {0, -1, 0}});
  ParallelJawGripper g;
  AntipodalOptions o;
  o.check_collision = false;
  o.approaches_kept = o.approaches_tried;  // keep every approach
  const AntipodalResult all = sample_antipodal_grasps(box, p, n, g, o);
  o.check_collision = true;
  const AntipodalResult free = sample_antipodal_grasps(box, p, n, g, o);
  ASSERT_EQ(all.grasps.size(), 2u * 5u * static_cast<std::size_t>(o.approaches_tried));
  std::size_t expected_free = 0;
  for (const AntipodalGrasp& a : all.grasps) expected_free += !gripper_collides(box, g, a.grasp);
  EXPECT_EQ(free.grasps.size(), expected_free);
  EXPECT_EQ(free.num_colliding, static_cast<std::int64_t>(all.grasps.size() - expected_free));
  EXPECT_GT(free.num_colliding, 0);
  EXPECT_GT(free.grasps.size(), 0u);
}

TEST(Antipodal, SphereGraspsPassThroughTheCentre) {
  const double R = 0.03;
  const Mesh sphere = make_sphere(R, 96, 48);
  const SurfaceSamples s = sample_surface(sphere, 40, {SampleMethod::Even, 3, 6});
  const Points3d p = s.points.cast<double>();
  const Points3d n = p.rowwise().normalized();  // radial: the probes aim at the centre
  ParallelJawGripper g;
  AntipodalOptions exact;
  exact.tilt = 0.0;
  exact.offset = 0.0;
  exact.approaches_kept = 2;
  const AntipodalResult r = sample_antipodal_grasps(sphere, p, n, g, exact);
  ASSERT_GT(r.grasps.size(), 0u);
  for (float sc : r.point_score) EXPECT_FLOAT_EQ(sc, 1.0f);
  for (const AntipodalGrasp& a : r.grasps) {
    const Vec3d c = a.grasp.p1 + 0.5 * a.grasp.width * a.grasp.closing;
    const Vec3d& p1 = a.grasp.p1;
    const Vec3d& v = a.grasp.closing;
    EXPECT_LT((p1 - p1.dot(v) * v).norm(), 1e-5);  // the closing line passes through the centre
    EXPECT_LT(c.norm(), 1e-4);                     // midway up to the facet sag
    EXPECT_NEAR(a.grasp.width, 2 * R, 1e-4);
  }
  // Perturbed probes: accepted chords lie within the friction cone, so they pass within
  // R sin(atan mu) of the centre (plus the facet error).
  AntipodalOptions o;
  const AntipodalResult rp = sample_antipodal_grasps(sphere, p, n, g, o);
  const double bound = R * std::sin(std::atan(o.friction_coef)) + 1e-3;
  for (const AntipodalGrasp& a : rp.grasps) {
    const Vec3d& p1 = a.grasp.p1;
    const Vec3d& v = a.grasp.closing;
    const double dist = (p1 - p1.dot(v) * v).norm();  // distance of the line to the origin
    EXPECT_LT(dist, bound);
  }
}

TEST(Antipodal, DeterministicForAnyThreadCountAndBatchSplit) {
  const Mesh cyl = make_cylinder(0.025, 0.1, 48);
  const SurfaceSamples s = sample_surface(cyl, 120, {SampleMethod::Even, 11, 6});
  const Points3d p = s.points.cast<double>();
  const Points3d n = s.normals.cast<double>();
  const AntipodalSampler sampler(cyl, ParallelJawGripper{});
  AntipodalOptions o;
  o.seed = 42;
  o.num_threads = 1;
  const AntipodalResult a = sampler.sample(p, n, o);
  o.num_threads = 2;
  const AntipodalResult b = sampler.sample(p, n, o);
  // Second half alone, with first_index = 60.
  o.first_index = 60;
  const AntipodalResult c = sampler.sample(p.bottomRows(60), n.bottomRows(60), o);
  ASSERT_EQ(a.grasps.size(), b.grasps.size());
  ASSERT_GT(a.grasps.size(), 0u);
  EXPECT_EQ(a.point_score, b.point_score);
  for (std::size_t i = 0; i < a.grasps.size(); ++i) {
    EXPECT_EQ(a.grasps[i].grasp.p1, b.grasps[i].grasp.p1);
    EXPECT_EQ(a.grasps[i].grasp.approach, b.grasps[i].grasp.approach);
  }
  std::size_t first_second_half = 0;
  while (a.grasps[first_second_half].point_index < 60) ++first_second_half;
  ASSERT_EQ(a.grasps.size() - first_second_half, c.grasps.size());
  for (std::size_t i = 0; i < c.grasps.size(); ++i) {
    EXPECT_EQ(a.grasps[first_second_half + i].grasp.approach, c.grasps[i].grasp.approach);
    EXPECT_EQ(a.grasps[first_second_half + i].point_index, c.grasps[i].point_index + 60);
  }
  // A different seed gives different approaches.
  o.first_index = 0;
  o.seed = 43;
  const AntipodalResult d = sampler.sample(p, n, o);
  ASSERT_GT(d.grasps.size(), 0u);
  EXPECT_NE(a.grasps[0].grasp.approach, d.grasps[0].grasp.approach);
}

TEST(Antipodal, GripperInsideTheObjectCollides) {
  const AntipodalSampler sampler(make_box(Vec3d(1, 1, 1)), ParallelJawGripper{});
  EXPECT_TRUE(sampler.collides(Pose::Identity(), 0.05));  // all parts inside, no surface contact
  Pose far = Pose::Identity();
  far.translation() = Vec3d(0, 0, 2);
  EXPECT_FALSE(sampler.collides(far, 0.05));
  Pose straddle = Pose::Identity();
  straddle.translation() = Vec3d(0, 0, 0.45);  // fingers cross the top face
  EXPECT_TRUE(sampler.collides(straddle, 0.05));
}

TEST(Antipodal, BadInputIsRejected) {
  const Mesh box = make_box(Vec3d(0.04, 0.04, 0.04));
  const Points3d p = rows({{0.02, 0, 0}});
  const Points3d n = rows({{1, 0, 0}});
  ParallelJawGripper g;
  g.max_opening = -0.01;  // open gripper narrower than 0
  EXPECT_THROW(sample_antipodal_grasps(box, p, n, g), InvalidArgument);
  g = ParallelJawGripper{};
  // No closed volume: the box without its last two triangles.
  Faces open_faces = box.faces().topRows(box.num_faces() - 2);
  const Mesh open(box.vertices(), open_faces);
  EXPECT_THROW(AntipodalSampler(open, g), InvalidArgument);
  EXPECT_THROW(sample_antipodal_grasps(box, p, rows({{0, 0, 0}}), g), InvalidArgument);
  EXPECT_THROW(sample_antipodal_grasps(box, p, Points3d(2, 3), g), InvalidArgument);
  AntipodalOptions o;
  o.probes = 0;
  EXPECT_THROW(sample_antipodal_grasps(box, p, n, g, o), InvalidArgument);
  o = AntipodalOptions{};
  o.friction_coef = -1;
  EXPECT_THROW(sample_antipodal_grasps(box, p, n, g, o), InvalidArgument);
  // Half the faces of a mesh gripper.
  g.palm_mesh = box;
  EXPECT_THROW(g.validate(), InvalidArgument);
}

TEST(PjWrench, MatchesTheEllipticSoftFingerLimitInClosedForm) {
  PjWrenchOptions o;
  o.grip_force = 10.0;
  o.friction = 0.5;
  o.contact_radius = 0.006;
  ParallelJawGrasp g;
  g.p1 = Vec3d(-0.02, 0, 0);
  g.closing = Vec3d(1, 0, 0);
  g.approach = Vec3d(0, 0, -1);
  g.width = 0.04;
  const Vec3d down(0, 0, -1);
  // CoM on the closing axis: no torque; 0.2 kg -> f_t = 0.981 N per finger < mu f = 5 N.
  EXPECT_FLOAT_EQ(pj_wrench_scores({g}, 0.2, Vec3d(0.01, 0, 0), down, o)[0], 1.0f);
  // CoM 5 cm off the axis along y: tau about x = m g d.
  const double m = 0.2, d = 0.05;
  const double f_t = 0.5 * m * 9.81, tau_n = 0.5 * m * 9.81 * d;
  const double u = std::hypot(f_t / (0.5 * 10), tau_n / (2.0 / 3.0 * 0.5 * 0.006 * 10));
  ASSERT_GT(u, 1.0);
  const float s = pj_wrench_scores({g}, m, Vec3d(0, d, 0), down, o)[0];
  EXPECT_NEAR(s, 1.0 / u, 1e-6);
  // Symmetry: the same grasp seen from the other finger scores the same.
  ParallelJawGrasp flipped = g;
  flipped.p1 = g.p1 + g.width * g.closing;
  flipped.closing = -g.closing;
  EXPECT_FLOAT_EQ(pj_wrench_scores({flipped}, m, Vec3d(0, d, 0), down, o)[0], s);
  // Gravity along the closing axis: no tangential load, no torsion -> 1 even for a heavy object.
  EXPECT_FLOAT_EQ(pj_wrench_scores({g}, 50.0, Vec3d(0, d, 0), Vec3d(1, 0, 0), o)[0], 1.0f);
  // Heavier is never better.
  EXPECT_LT(pj_wrench_scores({g}, 2 * m, Vec3d(0, d, 0), down, o)[0], s);
  EXPECT_THROW(pj_wrench_scores({g}, 0.0, Vec3d::Zero(), down, o), InvalidArgument);
  EXPECT_THROW(pj_wrench_scores({g}, 1.0, Vec3d::Zero(), Vec3d::Zero(), o), InvalidArgument);
}

}  // namespace
}  // namespace mgn
