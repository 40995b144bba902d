// Scene grasp labels: placement, collisions along the approach, visibility, gravity, threads.
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/scene/scene_grasps.hpp>

#include <cmath>

using namespace mgn;

namespace {

Pose at(double x, double y, double z) {
  Pose X = Pose::Identity();
  X.translation() = Vec3d(x, y, z);
  return X;
}

// A floor slab with its top face at z = 0 (the "tote" of these tests).
const Mesh& floor_mesh() {
  static const Mesh m = make_box(Vec3d(0.8, 0.8, 0.01));
  return m;
}
const Pose kFloor = at(0, 0, -0.005);

// 40 x 60 x 50 mm box lying on the floor (object frame at its centre).
const Mesh& box_mesh() {
  static const Mesh m = make_box(Vec3d(0.04, 0.06, 0.05));
  return m;
}

SceneGraspObject box_object(const Pose& X_WO) {
  SceneGraspObject o;
  o.mesh = &box_mesh();
  o.X_WO = X_WO;
  o.mass = 0.2;
  o.com = Vec3d(0.005, -0.01, 0.002);
  return o;
}

// Top-down parallel-jaw grasp across x of the box: p1 on the -x face, half-way up.
ParallelJawGrasp across_x() {
  ParallelJawGrasp g;
  g.p1 = Vec3d(-0.02, 0, 0);
  g.closing = Vec3d(1, 0, 0);
  g.approach = Vec3d(0, 0, -1);
  g.width = 0.04;
  return g;
}

void add_suction(SceneGraspObject& o, const Vec3d& p, const Vec3d& a) {
  const Eigen::Index n = o.suction_points.rows();
  o.suction_points.conservativeResize(n + 1, 3);
  o.suction_approach.conservativeResize(n + 1, 3);
  o.suction_points.row(n) = p.cast<float>().transpose();
  o.suction_approach.row(n) = a.cast<float>().transpose();
}

SceneGraspModel model_of(const std::vector<SceneGraspObject>& objects,
                         SceneGraspOptions options = {}) {
  options.num_threads = options.num_threads ? options.num_threads : 1;
  return SceneGraspModel(objects, floor_mesh(), kFloor, ParallelJawGripper(), Cup(), options);
}

CameraView top_down(double height = 1.0) {
  CameraView v;
  v.K = Intrinsics::mgn_synthetic();
  v.X_WC = look_at(Vec3d(0, 0, height), Vec3d(0, 0, 0), Vec3d(0, 1, 0));
  return v;
}

}  // namespace

TEST(SceneGrasps, SuctionOnBottomFaceHitsTheFloorTopFaceIsFree) {
  SceneGraspObject box = box_object(at(0, 0, 0.025));
  add_suction(box, Vec3d(0, 0, 0.025), Vec3d(0, 0, -1));  // top face, approach down
  add_suction(box, Vec3d(0, 0, -0.025), Vec3d(0, 0, 1));  // bottom face, approach up
  const SceneGraspModel m = model_of({box});
  const PlacedGrasps& s = m.suction();
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s.colliding[0], 0);
  EXPECT_EQ(s.colliding[1], 1);
  EXPECT_EQ(s.hit[1 * 2 + 0], 0);  // the tote (floor) at offset 0
  // Placement: contact frame z = approach, origin at the contact; tool end behind it.
  EXPECT_TRUE(s.X_W_contact[0].translation().isApprox(Vec3d(0, 0, 0.05), 1e-6));
  EXPECT_TRUE(s.X_W_contact[0].linear().col(2).isApprox(Vec3d(0, 0, -1), 1e-12));
  // MetaGraspNet's tool pose: 2 cm (cup) + 11.21 cm (tool) behind the contact.
  EXPECT_NEAR(s.X_W_tool[0].translation().z(), 0.05 + 0.02 + 0.1121, 1e-6);
  EXPECT_NEAR(kSuctionToolOffset, 0.1321, 1e-12);
  EXPECT_NEAR(s.X_W_contact[0].linear().determinant(), 1.0, 1e-12);
}

TEST(SceneGrasps, FingerEnteringANeighbourCollidesAndNotWithoutIt) {
  SceneGraspObject box = box_object(at(0, 0, 0.025));
  box.pj = {across_x()};
  // Finger of the +x side at opening min(0.04 + 0.03, 0.08) = 0.07: x in [0.035, 0.045].
  SceneGraspObject neighbour = box_object(at(0.032 + 0.02, 0, 0.025));
  const SceneGraspModel with = model_of({box, neighbour});
  EXPECT_EQ(with.pj().colliding[0], 1);
  EXPECT_EQ(with.pj().hit[0], 2);  // instance id of the neighbour, at offset 0
  const SceneGraspModel without = model_of({box});
  EXPECT_EQ(without.pj().colliding[0], 0);
  EXPECT_EQ(without.pj().hit[0], -1);
  EXPECT_EQ(without.pj().hit[1], -1);
  // Placement: hand at p1 + w/2 v - grasp_depth a in the world.
  const Vec3d expected(0, 0, 0.025 + ParallelJawGripper().grasp_depth());
  EXPECT_TRUE(without.pj().X_W_tool[0].translation().isApprox(expected, 1e-12));
  EXPECT_TRUE(without.pj().X_W_contact[0].translation().isApprox(Vec3d(-0.02, 0, 0.025), 1e-12));
  EXPECT_TRUE(without.pj().second_contacts.row(0).isApprox(Eigen::RowVector3d(0.02, 0, 0.025)));
}

TEST(SceneGrasps, SmallObjectInsideThePalmCollidesWithoutSurfaceContact) {
  SceneGraspObject box = box_object(at(0, 0, 0.025));
  box.pj = {across_x()};
  // The palm (200 x 60 x 60 mm) spans z in grasp centre + [grasp_depth - f - palm, grasp_depth
  // - f] above the fingers; a 1 cm cube in its middle touches none of its faces.
  const ParallelJawGripper g;
  const double palm_mid =
      0.025 + g.grasp_depth() - (g.flange_to_tip - g.finger_size.z() - 0.5 * g.palm_size.z());
  static const Mesh cube = make_box(Vec3d(0.01, 0.01, 0.01));
  SceneGraspObject small;
  small.mesh = &cube;
  small.X_WO = at(0.05, 0, palm_mid);
  small.mass = 0.01;
  const SceneGraspModel m = model_of({box, small});
  EXPECT_EQ(m.pj().hit[0], 2);
}

TEST(SceneGrasps, ApproachOffsetMattersUnderAnOverhangingPlate) {
  SceneGraspObject box = box_object(at(0, 0, 0.025));
  add_suction(box, Vec3d(0, 0, 0.025), Vec3d(0, 0, -1));
  // Tool: up to 0.05 + 0.03 + 0.15 = 0.23 m at offset 0, 0.33 m at 100 mm back.
  static const Mesh plate_mesh = make_box(Vec3d(0.2, 0.2, 0.01));
  SceneGraspObject plate;
  plate.mesh = &plate_mesh;
  plate.X_WO = at(0, 0, 0.25);
  plate.mass = 0.3;
  const SceneGraspModel m = model_of({box, plate});
  EXPECT_EQ(m.suction().hit[0], -1);
  EXPECT_EQ(m.suction().hit[1], 2);
  EXPECT_EQ(m.suction().colliding[0], 1);
  SceneGraspOptions only_at_grasp;
  only_at_grasp.offsets = {0.0};
  EXPECT_EQ(model_of({box, plate}, only_at_grasp).suction().colliding[0], 0);
}

TEST(SceneGrasps, HiddenContactIsNotKeptInATopDownView) {
  SceneGraspObject box = box_object(at(0, 0, 0.025));
  add_suction(box, Vec3d(0, 0, 0.025), Vec3d(0, 0, -1));      // top face centre
  add_suction(box, Vec3d(0.015, 0, 0.025), Vec3d(0, 0, -1));  // top face, off centre
  box.pj = {across_x()};                                      // side contacts
  static const Mesh cover_mesh = make_box(Vec3d(0.02, 0.1, 0.01));
  SceneGraspObject cover;  // a bar lying over the middle of the box top, x in [-0.01, 0.01]
  cover.mesh = &cover_mesh;
  cover.X_WO = at(0, 0, 0.056);
  cover.mass = 0.05;
  const CameraView view = top_down(1.0);
  const SceneGraspModel covered = model_of({box, cover});
  const ViewGrasps v = covered.view_grasps(view, {1, 1});
  ASSERT_EQ(v.suction_index.size(), 1u);
  EXPECT_EQ(v.suction_index[0], 1);  // the centre one is hidden under the bar
  // Side faces are seen edge-on from straight above: the top edge hides p1 and p2.
  EXPECT_TRUE(v.pj_index.empty());
  // Object not seen: nothing kept.
  EXPECT_TRUE(covered.view_grasps(view, {0, 1}).suction_index.empty());
  // Without the cover both suction grasps are visible; camera-frame poses are X_CW X_W.
  const SceneGraspModel open = model_of({box});
  const ViewGrasps w = open.view_grasps(view, {1});
  ASSERT_EQ(w.suction_index.size(), 2u);
  const Pose expected = view.X_WC.inverse() * open.suction().X_W_contact[0];
  EXPECT_TRUE(w.suction_X_C_contact[0].isApprox(expected, 1e-12));
  EXPECT_NEAR(w.suction_X_C_contact[0].translation().z(), 1.0 - 0.05, 1e-9);
  // An oblique camera sees the -x side face: the parallel-jaw grasp (p1 there) is kept.
  CameraView side = view;
  side.X_WC = look_at(Vec3d(-0.8, 0, 0.4), Vec3d(0, 0, 0.025), Vec3d(0, 0, 1));
  EXPECT_EQ(open.view_grasps(side, {1}).pj_index.size(), 1u);
  // A camera looking away sees nothing.
  side.X_WC = look_at(Vec3d(0, 0, 1), Vec3d(0, 0, 2), Vec3d(0, 1, 0));
  EXPECT_TRUE(open.view_grasps(side, {1}).suction_index.empty());
}

TEST(SceneGrasps, WrenchUsesTheSceneGravityInTheObjectFrame) {
  SceneGraspObject box = box_object(Pose::Identity());
  ParallelJawGrasp g = across_x();
  g.closing = Vec3d(1, 0, 0);
  g.approach = Vec3d(0, 1, 0);
  box.pj = {g};
  add_suction(box, Vec3d(0, 0, 0.025), Vec3d(0, 0, -1));
  add_suction(box, Vec3d(0.02, 0.01, 0), Vec3d(-1, 0, 0));
  for (const Vec3d& axis : {Vec3d(1, 0, 0), Vec3d(0.3, 1, 0.2)}) {
    for (double angle : {M_PI, M_PI / 2, 0.7}) {
      Pose X = at(0, 0, 0.2);
      X.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
      box.X_WO = X;
      SceneGraspOptions o;
      o.offsets = {0.0};
      const SceneGraspModel m = model_of({box}, o);
      const Vec3d g_O = X.linear().transpose() * Vec3d(0, 0, -1);
      const std::vector<float> pj = pj_wrench_scores(box.pj, box.mass, box.com, g_O);
      const std::vector<float> su = suction_wrench_scores(box.suction_points, box.suction_approach,
                                                          box.mass, box.com, g_O, Cup().radius);
      EXPECT_FLOAT_EQ(m.pj().score_wrench[0], pj[0]);
      EXPECT_FLOAT_EQ(m.suction().score_wrench[0], su[0]);
      EXPECT_FLOAT_EQ(m.suction().score_wrench[1], su[1]);
    }
  }
  // Upside down: gravity +z in the object frame.
  Pose X = at(0, 0, 0.2);
  X.linear() = Eigen::AngleAxisd(M_PI, Vec3d::UnitX()).toRotationMatrix();
  box.X_WO = X;
  const SceneGraspModel m = model_of({box});
  EXPECT_FLOAT_EQ(m.pj().score_wrench[0],
                  pj_wrench_scores(box.pj, box.mass, box.com, Vec3d(0, 0, 1))[0]);
  // A side pose changes the suction score of the side contact (a real dependence on the pose).
  X.linear() = Eigen::AngleAxisd(M_PI / 2, Vec3d::UnitY()).toRotationMatrix();
  box.X_WO = X;
  const std::vector<float> upright = suction_wrench_scores(
      box.suction_points, box.suction_approach, box.mass, box.com, Vec3d(0, 0, -1), Cup().radius);
  EXPECT_NE(model_of({box}).suction().score_wrench[1], upright[1]);
}

TEST(SceneGrasps, OneAndTwoThreadsGiveIdenticalResults) {
  std::vector<SceneGraspObject> objects;
  Rng rng(7, 0);
  for (int i = 0; i < 6; ++i) {
    Pose X = at(rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), 0.03 + 0.04 * i);
    X.linear() =
        Eigen::AngleAxisd(rng.uniform(0, 6.28), Vec3d(rng.uniform(-1, 1), 0.3, 1).normalized())
            .toRotationMatrix();
    SceneGraspObject o = box_object(X);
    for (int k = 0; k < 60; ++k) {
      ParallelJawGrasp g = across_x();
      g.p1 = Vec3d(-0.02, rng.uniform(-0.03, 0.03), rng.uniform(-0.025, 0.025));
      const double t = rng.uniform(0, 6.28);
      g.approach = Vec3d(0, std::cos(t), std::sin(t));
      o.pj.push_back(g);
      add_suction(o, Vec3d(rng.uniform(-0.02, 0.02), rng.uniform(-0.03, 0.03), 0.025),
                  Vec3d(0, 0, -1));
    }
    objects.push_back(o);
  }
  SceneGraspOptions one, two;
  one.num_threads = 1;
  two.num_threads = 2;
  const SceneGraspModel a = model_of(objects, one), b = model_of(objects, two);
  EXPECT_EQ(a.pj().hit, b.pj().hit);
  EXPECT_EQ(a.suction().hit, b.suction().hit);
  EXPECT_EQ(a.pj().score_wrench, b.pj().score_wrench);
  // Some collide and some do not: the comparison means something.
  int n = 0;
  for (auto c : a.pj().colliding) n += c;
  EXPECT_GT(n, 0);
  EXPECT_LT(n, static_cast<int>(a.pj().size()));
}

TEST(SceneGrasps, BadInputIsAClearError) {
  SceneGraspObject box = box_object(at(0, 0, 0.025));
  EXPECT_THROW(model_of({}), InvalidArgument);
  SceneGraspObject bad = box;
  bad.X_WO.matrix()(0, 3) = std::nan("");
  EXPECT_THROW(model_of({bad}), InvalidArgument);
  bad = box;
  bad.pj = {across_x()};
  bad.pj[0].p1.x() = std::nan("");
  EXPECT_THROW(model_of({bad}), InvalidArgument);
  bad = box;
  bad.pj = {across_x()};
  bad.pj_score_analytical = {0.5f, 0.5f};
  EXPECT_THROW(model_of({bad}), InvalidArgument);
  bad = box;
  bad.mass = 0;
  EXPECT_THROW(model_of({bad}), InvalidArgument);
  SceneGraspOptions o;
  o.offsets = {-0.1};
  EXPECT_THROW(model_of({box}, o), InvalidArgument);
  const SceneGraspModel m = model_of({box});
  EXPECT_THROW(m.view_grasps(top_down(), {1, 1}), InvalidArgument);
  try {
    m.view_grasps(top_down(), {});
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("expected one per object (1)"), std::string::npos);
  }
}

TEST(SceneGrasps, CopiesOfOneMeshCollideEachAtItsOwnPose) {
  // Three instances of one box: the shared mesh, a separate copy with the same vertices and
  // faces (they share one collision model), and the copy again turned 45 degrees about z. A
  // suction tool pushed 5 mm into the top of each hits that instance; one placed at the corner
  // of the turned box's world bounding box (inside that box, 30 mm outside the box itself, more
  // than the 10 mm cup radius) hits nothing.
  const Mesh copy(box_mesh().vertices(), box_mesh().faces());
  std::vector<SceneGraspObject> objects = {
      box_object(at(-0.15, 0, 0.025)), box_object(at(0, 0, 0.025)), box_object(at(0.15, 0, 0.025))};
  objects[1].mesh = &copy;
  objects[2].mesh = &copy;
  objects[2].X_WO.linear() = Eigen::AngleAxisd(M_PI / 4, Vec3d::UnitZ()).toRotationMatrix();
  const SceneGraspModel m = model_of(objects);
  Pose down = Pose::Identity();
  down.linear() = Eigen::AngleAxisd(M_PI, Vec3d::UnitX()).toRotationMatrix();  // z = -z_W
  std::vector<Pose> poses;
  for (const double x : {-0.15, 0.0, 0.15}) {
    poses.push_back(down);
    poses.back().translation() = Vec3d(x, 0, 0.045);
  }
  const double corner = 0.05 / std::sqrt(2.0);  // half the turned box's world extent in x, y
  poses.push_back(down);
  poses.back().translation() = Vec3d(0.15 + corner - 0.001, corner - 0.001, 0.045);
  const ToolCollisions c = m.collides(GraspKind::Suction, poses, {}, {-1, -1, -1, -1});
  const std::size_t K = m.options().offsets.size();
  EXPECT_EQ(c.hit[0 * K], 1);
  EXPECT_EQ(c.hit[1 * K], 2);
  EXPECT_EQ(c.hit[2 * K], 3);
  EXPECT_EQ(c.colliding[3], 0);
  EXPECT_EQ(c.hit[3 * K], -1);
}

TEST(SceneGrasps, FirstCollisionOnlyKeepsTheLabelsAndSkipsTheLaterOffsets) {
  // The grasp of FingerEnteringANeighbourCollidesAndNotWithoutIt (its finger in the neighbour
  // at offset 0) and a free one (the box alone): with first_collision_only the colliding grasp
  // is not checked at 100 mm, the free one is.
  SceneGraspObject box = box_object(at(0, 0, 0.025));
  box.pj = {across_x()};
  SceneGraspObject free_box = box_object(at(0.3, 0, 0.025));
  free_box.pj = {across_x()};
  SceneGraspObject neighbour = box_object(at(0.032 + 0.02, 0, 0.025));
  SceneGraspOptions first;
  first.first_collision_only = true;
  const SceneGraspModel a = model_of({box, free_box, neighbour});
  const SceneGraspModel b = model_of({box, free_box, neighbour}, first);
  ASSERT_EQ(b.pj().size(), 2u);
  EXPECT_EQ(a.pj().colliding, b.pj().colliding);
  EXPECT_EQ(a.pj().collision_part, b.pj().collision_part);
  EXPECT_EQ(a.pj().collision_obstacle, b.pj().collision_obstacle);
  EXPECT_EQ(b.pj().colliding[0], 1);
  EXPECT_EQ(b.pj().collision_obstacle[0],
            static_cast<std::uint8_t>(CollisionObstacle::OtherObject));
  EXPECT_EQ(b.pj().hit[0], 3);  // the neighbour, at offset 0
  EXPECT_EQ(b.pj().hit[1], kHitNotChecked);
  EXPECT_GE(a.pj().hit[1], -1);
  EXPECT_EQ(b.pj().colliding[1], 0);
  EXPECT_EQ(b.pj().hit[2], -1);
  EXPECT_EQ(b.pj().hit[3], -1);
  // collides() checks every offset whatever the option.
  const ToolCollisions c =
      b.collides(GraspKind::ParallelJaw, {b.pj().X_W_contact[0]}, {b.pj().width[0]}, {0});
  EXPECT_EQ(c.hit[1], a.pj().hit[1]);
}
