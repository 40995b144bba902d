// Parallel-jaw gripper geometry and the grasp frame (MODELS.md §5).
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/grasp/gripper.hpp>

#include <Eigen/Geometry>

namespace mgn {
namespace {

TEST(Gripper, DefaultGraspDepthIsMetaGraspNets) {
  ParallelJawGripper g;
  EXPECT_NO_THROW(g.validate());
  EXPECT_NEAR(g.grasp_depth(), 0.1041, 1e-12);
  EXPECT_NEAR(g.collision_opening(0.02), 0.05, 1e-12);
  EXPECT_NEAR(g.collision_opening(0.07), 0.08, 1e-12);  // clipped at max_opening
}

TEST(Gripper, FingerInnerFacesAreOpeningApartAndTipsAtFlangeToTip) {
  ParallelJawGripper g;
  const double opening = 0.05;
  GripperMeshes m = gripper_meshes(g, opening);
  auto bl = m.finger_left.bounds();
  auto br = m.finger_right.bounds();
  EXPECT_NEAR(br(0, 0) - bl(1, 0), opening, 1e-6);  // inner faces
  EXPECT_NEAR(bl(1, 2), g.flange_to_tip, 1e-6);
  EXPECT_NEAR(br(1, 2), g.flange_to_tip, 1e-6);
  auto bp = m.palm.bounds();
  EXPECT_NEAR(bp(1, 2), g.flange_to_tip - g.finger_size.z(), 1e-6);  // palm touches fingers
  EXPECT_GE(bp(0, 2), -1e-6);                                        // and stays below the flange
  EXPECT_TRUE(m.palm.validate().is_watertight);
}

TEST(Gripper, HandPoseBringsPadCentresOntoTheContacts) {
  ParallelJawGripper g;
  ParallelJawGrasp grasp;
  grasp.p1 = Vec3d(0.1, -0.2, 0.3);
  grasp.closing = Vec3d(1, 1, 0).normalized();
  grasp.approach = Vec3d(0, 0, -1);
  grasp.width = 0.04;
  Pose X_OH = hand_pose(grasp, g);
  EXPECT_NEAR((X_OH.linear().transpose() * X_OH.linear() - Mat3d::Identity()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(X_OH.linear().determinant(), 1.0, 1e-12);
  // In H, the contacts are at (∓w/2, 0, grasp_depth).
  Vec3d p1_H = X_OH.inverse() * grasp.p1;
  Vec3d p2_H = X_OH.inverse() * (grasp.p1 + grasp.width * grasp.closing);
  EXPECT_NEAR((p1_H - Vec3d(-0.02, 0, g.grasp_depth())).norm(), 0.0, 1e-12);
  EXPECT_NEAR((p2_H - Vec3d(0.02, 0, g.grasp_depth())).norm(), 0.0, 1e-12);
}

TEST(Gripper, MeshGripperFromTheBoxMeshesMatchesTheParametricOne) {
  ParallelJawGripper boxes;
  const GripperMeshes closed = gripper_meshes(boxes, 0.0);
  ParallelJawGripper meshes = boxes;
  meshes.palm_mesh = closed.palm;
  meshes.finger_left_mesh = closed.finger_left;
  meshes.finger_right_mesh = closed.finger_right;
  meshes.finger_size = Vec3d(1, 1, 1);  // ignored by a mesh gripper
  ASSERT_TRUE(meshes.has_meshes());
  EXPECT_NO_THROW(meshes.validate());
  for (double opening : {0.0, 0.037, 0.08}) {
    const GripperMeshes a = gripper_meshes(boxes, opening);
    const GripperMeshes b = gripper_meshes(meshes, opening);
    EXPECT_LT((a.finger_left.vertices() - b.finger_left.vertices()).cwiseAbs().maxCoeff(), 1e-7);
    EXPECT_LT((a.finger_right.vertices() - b.finger_right.vertices()).cwiseAbs().maxCoeff(), 1e-7);
    EXPECT_LT((a.palm.vertices() - b.palm.vertices()).cwiseAbs().maxCoeff(), 1e-7);
  }
  EXPECT_NEAR(finger_offset(0, 0.05).translation().x(), -0.025, 1e-15);
  EXPECT_NEAR(finger_offset(1, 0.05).translation().x(), 0.025, 1e-15);
  EXPECT_THROW(finger_offset(2, 0.05), InvalidArgument);
}

TEST(Gripper, BadInputIsRejected) {
  ParallelJawGripper g;
  EXPECT_THROW(gripper_meshes(g, -0.001), InvalidArgument);
  EXPECT_THROW(gripper_meshes(g, 0.081), InvalidArgument);
  g.max_opening = 0.0;
  EXPECT_THROW(g.validate(), InvalidArgument);
  g = ParallelJawGripper{};
  g.palm_size.z() = 0.1;  // palm + finger longer than flange_to_tip
  EXPECT_THROW(g.validate(), InvalidArgument);
  ParallelJawGrasp bad;
  bad.approach = Vec3d(1, 0, 0);  // parallel to closing
  EXPECT_THROW(grasp_rotation(bad), InvalidArgument);
  bad.approach = Vec3d(0, 0, 2);  // not unit
  EXPECT_THROW(grasp_rotation(bad), InvalidArgument);
}

}  // namespace
}  // namespace mgn
