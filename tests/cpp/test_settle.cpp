// Tests of mgn::settle_objects (mgn/scene/drop): objects start at rest at given poses and settle
// under gravity. Truth: a resting pile does not move, a box above the floor comes to rest at
// half its height (analytic), a box loses its support when the one below is taken away.
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/geometry/convex_decomposition.hpp>
#include <mgn/geometry/mass_properties.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/scene/drop.hpp>

#include <cmath>
#include <string>

namespace {

/// A closed mesh spanning the tote's outer bounds (the Boxes collision mode only checks that the
/// mesh encloses the cavity).
mgn::Mesh outer_tote(const mgn::ToteBox& b) {
  const mgn::Vec3d ext(b.inner_length + 2 * b.wall_thickness, b.inner_width + 2 * b.wall_thickness,
                       b.inner_height + b.floor_thickness);
  mgn::Pose X = mgn::Pose::Identity();
  X.translation() = mgn::Vec3d(0, 0, 0.5 * (b.inner_height - b.floor_thickness));
  return mgn::make_box(ext).transformed(X);
}

mgn::DropObject box_object(const mgn::Vec3d& extents, const std::string& name) {
  const mgn::Mesh mesh = mgn::make_box(extents);
  const auto mp = mgn::compute_mass_properties(mesh, {500.0});
  mgn::DropObject o;
  o.convex_parts = {mesh};
  o.mass = mp.mass;
  o.com = mp.center_of_mass;
  o.inertia = mp.inertia;
  o.name = name;
  return o;
}

mgn::Pose at(double x, double y, double z, double yaw = 0.0) {
  mgn::Pose X = mgn::Pose::Identity();
  X.linear() = Eigen::AngleAxisd(yaw, mgn::Vec3d::UnitZ()).toRotationMatrix();
  X.translation() = mgn::Vec3d(x, y, z);
  return X;
}

double shift(const mgn::Pose& a, const mgn::Pose& b) {
  return (a.translation() - b.translation()).norm();
}

}  // namespace

TEST(Settle, BoxAboveTheFloorFallsAndRestsAtHalfItsHeight) {
  const mgn::ToteBox box;
  const auto cube = box_object({0.10, 0.06, 0.04}, "box");
  const mgn::Pose start = at(0.03, -0.02, 0.02 + 0.05, 0.3);  // bottom face 5 cm above the floor
  const mgn::DropResult r = mgn::settle_objects({cube}, {start}, outer_tote(box), box);
  ASSERT_EQ(r.objects.size(), 1u);
  const auto& d = r.objects[0];
  EXPECT_TRUE(d.kept());
  EXPECT_TRUE(d.settled);
  EXPECT_TRUE(r.settled);
  EXPECT_TRUE(d.contacts & mgn::ContactFloor);
  EXPECT_NEAR(d.X_WO.translation().z(), 0.02, 0.0015);  // half of the 4 cm height
  // It fell straight down: no horizontal drift, no turn, start pose reported as release pose.
  EXPECT_NEAR(d.X_WO.translation().x(), 0.03, 0.002);
  EXPECT_NEAR(d.X_WO.translation().y(), -0.02, 0.002);
  EXPECT_LT(Eigen::AngleAxisd(d.X_WO.linear().transpose() * start.linear()).angle(), 0.02);
  EXPECT_LT(shift(d.X_WO_release, start), 1e-12);
}

TEST(Settle, AnAlreadySettledPileStaysWhereItIs) {
  const mgn::ToteBox box;
  const mgn::Mesh tote = outer_tote(box);
  std::vector<mgn::DropObject> objects = {
      box_object({0.10, 0.06, 0.04}, "a"), box_object({0.05, 0.05, 0.05}, "b"),
      box_object({0.08, 0.08, 0.03}, "c"), box_object({0.15, 0.04, 0.02}, "d")};
  mgn::DropOptions o;
  o.seed = 3;
  const mgn::DropResult dropped = mgn::drop_objects(objects, tote, box, o);
  ASSERT_TRUE(dropped.settled);
  std::vector<mgn::DropObject> kept;
  std::vector<mgn::Pose> poses;
  for (std::size_t i = 0; i < objects.size(); ++i)
    if (dropped.objects[i].kept()) {
      kept.push_back(objects[i]);
      poses.push_back(dropped.objects[i].X_WO);
    }
  ASSERT_GE(kept.size(), 3u);
  const mgn::DropResult r = mgn::settle_objects(kept, poses, tote, box, o);
  EXPECT_TRUE(r.settled);
  // With two friction directions cube "b" rests tilted against a neighbour, held by static
  // friction (centre 36 mm up, not 25). Settling restarts from rest with new contacts, and it
  // slips 1.5 mm and turns 0.037 rad before friction holds it again (continuing the drop's own
  // simulation instead moves it < 0.1 mm); objects lying flat move < 0.2 mm.
  for (std::size_t i = 0; i < kept.size(); ++i) {
    EXPECT_TRUE(r.objects[i].kept()) << i;
    EXPECT_LT(shift(r.objects[i].X_WO, poses[i]), 0.002) << kept[i].name;
    EXPECT_LT(Eigen::AngleAxisd(r.objects[i].X_WO.linear().transpose() * poses[i].linear()).angle(),
              0.05)
        << kept[i].name;
  }
  // Only the rest time had to pass (no falling).
  EXPECT_LT(r.simulated_time, 1.0);
}

TEST(Settle, BoxOnAnotherFallsToTheFloorWhenTheLowerOneIsRemoved) {
  const mgn::ToteBox box;
  const mgn::Mesh tote = outer_tote(box);
  const auto lower = box_object({0.12, 0.10, 0.04}, "lower");
  const auto upper = box_object({0.06, 0.06, 0.03}, "upper");
  const mgn::Pose X_lower = at(0, 0, 0.02), X_upper = at(0.01, 0, 0.04 + 0.015, 0.5);
  // Both: the stack stays.
  const mgn::DropResult both = mgn::settle_objects({lower, upper}, {X_lower, X_upper}, tote, box);
  EXPECT_LT(shift(both.objects[0].X_WO, X_lower), 0.001);
  EXPECT_LT(shift(both.objects[1].X_WO, X_upper), 0.001);
  EXPECT_FALSE(both.objects[1].contacts & mgn::ContactFloor);
  // Without the lower box: the upper one falls by the lower one's height onto the floor.
  const mgn::DropResult alone = mgn::settle_objects({upper}, {X_upper}, tote, box);
  const auto& d = alone.objects[0];
  EXPECT_TRUE(d.kept());
  EXPECT_NEAR(d.X_WO.translation().z(), 0.015, 0.0015);
  EXPECT_NEAR(shift(d.X_WO, X_upper), 0.04, 0.003);
  EXPECT_TRUE(d.contacts & mgn::ContactFloor);
}

TEST(Settle, BadInputIsRejectedNamingSettleObjects) {
  const mgn::ToteBox box;
  const mgn::Mesh tote = outer_tote(box);
  const auto cube = box_object({0.05, 0.05, 0.05}, "cube");
  auto expect_invalid = [&](const std::vector<mgn::DropObject>& objects,
                            const std::vector<mgn::Pose>& poses, const std::string& needle) {
    try {
      mgn::settle_objects(objects, poses, tote, box);
      ADD_FAILURE() << "expected InvalidArgument containing '" << needle << "'";
    } catch (const mgn::InvalidArgument& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("settle_objects", 0), 0u) << what;
      EXPECT_NE(what.find(needle), std::string::npos) << what;
    }
  };
  expect_invalid({cube}, {}, "X_WO_start has 0 poses");
  expect_invalid({cube, cube}, {at(0, 0, 0.1)}, "one per object (2)");
  mgn::Pose nan_pose = at(0, 0, 0.1);
  nan_pose.translation().x() = std::nan("");
  expect_invalid({cube}, {nan_pose}, "X_WO_start[0]");
  mgn::Pose scaled = at(0, 0, 0.1);
  scaled.linear() *= 2.0;
  expect_invalid({cube}, {scaled}, "rigid");
  expect_invalid({}, {}, "at least one object");
  auto heavy = cube;
  heavy.mass = -1;
  expect_invalid({heavy}, {at(0, 0, 0.1)}, "mass");
}
