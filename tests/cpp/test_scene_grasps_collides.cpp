// SceneGraspModel::collides: arbitrary tool poses checked with the labels' own collision test.
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

const Mesh& floor_mesh() {
  static const Mesh m = make_box(Vec3d(0.8, 0.8, 0.01));
  return m;
}
const Pose kFloor = at(0, 0, -0.005);  // top face at z = 0

const Mesh& box_mesh() {
  static const Mesh m = make_box(Vec3d(0.04, 0.06, 0.05));
  return m;
}
const Mesh& ball_mesh() {
  static const Mesh m = make_sphere(0.03, 24, 12);
  return m;
}

SceneGraspObject object(const Mesh& mesh, const Pose& X_WO) {
  SceneGraspObject o;
  o.mesh = &mesh;
  o.X_WO = X_WO;
  o.mass = 0.2;
  o.com = Vec3d::Zero();
  return o;
}

Vec3d unit(Rng& rng) {
  Vec3d v(rng.normal(), rng.normal(), rng.normal());
  return v.normalized();
}

// Random grasps (not necessarily good ones) near each object: half of them collide somewhere.
void add_random_grasps(SceneGraspObject& o, std::uint64_t index) {
  Rng rng(7, index);
  for (int g = 0; g < 60; ++g) {
    ParallelJawGrasp pj;
    pj.closing = unit(rng);
    Vec3d a = unit(rng);
    a = (a - a.dot(pj.closing) * pj.closing).normalized();
    pj.approach = a;
    pj.width = rng.uniform(0.0, 0.08);
    pj.p1 = Vec3d(rng.uniform(-0.04, 0.04), rng.uniform(-0.04, 0.04), rng.uniform(-0.03, 0.03)) -
            0.5 * pj.width * pj.closing;
    o.pj.push_back(pj);
    o.pj_score_analytical.push_back(static_cast<float>(rng.uniform()));
  }
  const int K = 60;
  o.suction_points.resize(K, 3);
  o.suction_approach.resize(K, 3);
  for (int g = 0; g < K; ++g) {
    o.suction_points.row(g) =
        Vec3d(rng.uniform(-0.04, 0.04), rng.uniform(-0.04, 0.04), rng.uniform(-0.04, 0.04))
            .cast<float>()
            .transpose();
    o.suction_approach.row(g) = unit(rng).cast<float>().transpose();
  }
}

// Three objects close together on the floor.
std::vector<SceneGraspObject> cluttered() {
  std::vector<SceneGraspObject> objs;
  Pose X = at(0.0, 0.0, 0.025);
  objs.push_back(object(box_mesh(), X));
  X = at(0.05, 0.01, 0.03);
  X.linear() = Eigen::AngleAxisd(0.4, Vec3d(0, 0, 1)).toRotationMatrix();
  objs.push_back(object(ball_mesh(), X));
  X = at(-0.03, 0.07, 0.045);
  X.linear() = Eigen::AngleAxisd(1.1, Vec3d(1, 0.3, 0).normalized()).toRotationMatrix();
  objs.push_back(object(box_mesh(), X));
  for (std::size_t i = 0; i < objs.size(); ++i) add_random_grasps(objs[i], i);
  return objs;
}

SceneGraspModel model_of(const std::vector<SceneGraspObject>& objects, int threads = 1) {
  SceneGraspOptions options;
  options.offsets = {0.0, 0.05, 0.1};
  options.num_threads = threads;
  return SceneGraspModel(objects, floor_mesh(), kFloor, ParallelJawGripper(), Cup(), options);
}

std::vector<double> widths(const PlacedGrasps& p) {
  return std::vector<double>(p.width.begin(), p.width.end());
}

}  // namespace

TEST(SceneGraspsCollides, ReproducesTheLabelFlagsForTheLabelGrasps) {
  const std::vector<SceneGraspObject> objs = cluttered();
  const SceneGraspModel m = model_of(objs);
  for (GraspKind kind : {GraspKind::ParallelJaw, GraspKind::Suction}) {
    const PlacedGrasps& p = kind == GraspKind::ParallelJaw ? m.pj() : m.suction();
    ASSERT_EQ(p.size(), 180u);
    const ToolCollisions c = m.collides(kind, p.X_W_contact, widths(p), p.object_index);
    EXPECT_EQ(c.colliding, p.colliding);
    EXPECT_EQ(c.hit, p.hit);
    // The scene is a real test: both outcomes occur, and hits at offsets > 0 too.
    std::size_t n = 0;
    for (auto f : p.colliding) n += f;
    EXPECT_GT(n, 10u);
    EXPECT_LT(n, p.size() - 3u);  // the whole approach is checked: most grasps here collide
  }
}

TEST(SceneGraspsCollides, SameAnswerForAnyThreadCount) {
  const std::vector<SceneGraspObject> objs = cluttered();
  const SceneGraspModel m1 = model_of(objs, 1);
  const SceneGraspModel m4 = model_of(objs, 4);
  const PlacedGrasps& p = m1.pj();
  const ToolCollisions a =
      m1.collides(GraspKind::ParallelJaw, p.X_W_contact, widths(p), p.object_index, true);
  const ToolCollisions b =
      m4.collides(GraspKind::ParallelJaw, p.X_W_contact, widths(p), p.object_index, true);
  EXPECT_EQ(a.colliding, b.colliding);
  EXPECT_EQ(a.hit, b.hit);
}

TEST(SceneGraspsCollides, SuctionToolInsideAnotherObjectCollidesWithIt) {
  const std::vector<SceneGraspObject> objs = cluttered();
  const SceneGraspModel m = model_of(objs);
  // Contact at the centre of the ball (object 1), approach straight down: the cup body and shaft
  // start inside the ball; on the top of the box (object 0) the tool is free.
  std::vector<Pose> X = {objs[1].X_WO, at(0.0, 0.0, 0.05)};
  X[0].linear() = Eigen::AngleAxisd(M_PI, Vec3d(1, 0, 0)).toRotationMatrix();  // z down
  X[1].linear() = X[0].linear();
  const ToolCollisions c = m.collides(GraspKind::Suction, X, {}, {0, 0});
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.colliding[0], 1);
  EXPECT_EQ(c.hit[0], 2);  // instance id of object 1, found at offset 0
  EXPECT_EQ(c.colliding[1], 0);
  EXPECT_EQ(c.hit[3], -1);
}

TEST(SceneGraspsCollides, ParallelJawTargetIsSkippedAtTheGraspUnlessAsked) {
  // One box alone on the floor: a top-down grasp across x (width 40 mm) is free. The same hand
  // shifted 30 mm along x puts the right finger into the box at offset 0 only.
  std::vector<SceneGraspObject> objs = {object(box_mesh(), at(0, 0, 0.025))};
  const SceneGraspModel m = model_of(objs);
  Pose G = at(-0.02, 0.0, 0.03);        // p1 on the -x face, 20 mm below the top
  G.linear().col(0) = Vec3d(1, 0, 0);   // closing
  G.linear().col(1) = Vec3d(0, -1, 0);  // a x v
  G.linear().col(2) = Vec3d(0, 0, -1);  // approach, down
  Pose shifted = G;
  shifted.translation().x() += 0.03;
  const std::vector<Pose> X = {G, shifted};
  const ToolCollisions skip = m.collides(GraspKind::ParallelJaw, X, {0.04, 0.04}, {0, 0});
  const ToolCollisions full = m.collides(GraspKind::ParallelJaw, X, {0.04, 0.04}, {0, 0}, true);
  const ToolCollisions none = m.collides(GraspKind::ParallelJaw, X, {0.04, 0.04}, {-1, -1});
  // The target is skipped at the grasp itself; the shifted hand's finger is still inside the
  // box 5 mm back along the approach, where the target is checked (the whole path is).
  EXPECT_EQ(skip.colliding, (std::vector<std::uint8_t>{0, 1}));
  EXPECT_EQ(skip.hit[3], -1);  // offset 0 of the second pose: target skipped
  EXPECT_EQ(skip.hit[4], 1);   // the path to 50 mm: the box (instance 1)
  EXPECT_EQ(full.colliding, (std::vector<std::uint8_t>{0, 1}));
  EXPECT_EQ(full.hit[3], 1);  // offset 0 of the second pose: the box (instance 1)
  EXPECT_EQ(none.colliding, full.colliding);
  // Lowered 50 mm: the fingertips enter the floor (the tote) at offset 0; the palm then also
  // touches the top of the box, which is skipped there as the target.
  Pose low = G;
  low.translation().z() -= 0.05;
  const ToolCollisions f = m.collides(GraspKind::ParallelJaw, {low}, {0.04}, {0});
  EXPECT_EQ(f.colliding[0], 1);
  EXPECT_EQ(f.hit[0], 0);
}

TEST(SceneGraspsCollides, BadInputThrowsInvalidArgument) {
  const std::vector<SceneGraspObject> objs = cluttered();
  const SceneGraspModel m = model_of(objs);
  const Pose I = at(0, 0, 0.3);
  EXPECT_THROW(m.collides(GraspKind::ParallelJaw, {I}, {}, {0}), InvalidArgument);
  EXPECT_THROW(m.collides(GraspKind::ParallelJaw, {I}, {0.2}, {0}), InvalidArgument);
  EXPECT_THROW(m.collides(GraspKind::ParallelJaw, {I}, {NAN}, {0}), InvalidArgument);
  EXPECT_THROW(m.collides(GraspKind::Suction, {I}, {}, {3}), InvalidArgument);
  EXPECT_THROW(m.collides(GraspKind::Suction, {I}, {}, {-2}), InvalidArgument);
  EXPECT_THROW(m.collides(GraspKind::Suction, {I, I}, {}, {0}), InvalidArgument);
  Pose scaled = I;
  scaled.linear() *= 1.1;
  EXPECT_THROW(m.collides(GraspKind::Suction, {scaled}, {}, {0}), InvalidArgument);
  Pose nan = I;
  nan.translation().x() = NAN;
  EXPECT_THROW(m.collides(GraspKind::Suction, {nan}, {}, {0}), InvalidArgument);
  EXPECT_TRUE(m.collides(GraspKind::Suction, {}, {}, {}).colliding.empty());
}
