#pragma once
/// @file gripper.hpp  Parallel-jaw gripper geometry and the grasp frame (docs/models.md §5).
///
/// Hand frame H: origin at the flange, z = approach direction (towards the object), x = closing
/// direction (from finger 1 towards finger 2 at the object), y = z × x. Lengths in metres.
///
/// Grasp (MetaGraspNet): first contact p1, unit closing direction v (from p1 towards the second
/// contact), unit approach a ⟂ v, width w = |p2 − p1|. Grasp frame R = [v | a×v | a] at p1.
/// The hand pose in the object frame is X_OH = (R, p1 + (w/2)·v − grasp_depth()·a).

#include <mgn/core/types.hpp>
#include <mgn/geometry/mesh.hpp>

#include <string>

namespace mgn {

/// A parametric two-finger gripper (defaults: Franka-hand-like, the MetaGraspNet gripper).
/// Collision geometry (FCL) and rigid bodies (Bullet) are both built from gripper_meshes().
struct ParallelJawGripper {
  std::string name = "franka_like";
  double max_opening = 0.080;       ///< largest finger separation (inner faces), m
  double flange_to_tip = 0.1121;    ///< flange to fingertip along z, m
  double contact_from_tip = 0.008;  ///< contact-pad centre measured back from the tip, m
  double collision_margin = 0.030;  ///< opening used for collision = min(w + margin, max), m
  /// Finger box: thickness along x (closing), width along y, length along z, m.
  Vec3d finger_size = Vec3d(0.010, 0.020, 0.050);
  /// Palm box (x, y, z), m; it sits directly above the fingers, between them and the flange.
  /// Franka-hand-like: the housing is long along the closing axis x (about 200 x 60 mm).
  Vec3d palm_size = Vec3d(0.200, 0.060, 0.060);
  double friction = 1.0;  ///< finger pad Coulomb friction coefficient

  /// User gripper from meshes (all three set, or none: then the parametric boxes are used).
  /// Meshes are closed, in the hand frame H, with the fingers at opening 0 (closed): at an opening
  /// o the left finger moves by -o/2 and the right one by +o/2 along x (finger_offset()). The
  /// grasp geometry (max_opening, flange_to_tip, contact_from_tip) still comes from the fields
  /// above; finger_size and palm_size are then ignored.
  Mesh palm_mesh;
  Mesh finger_left_mesh;   ///< the p1 side (x < 0)
  Mesh finger_right_mesh;  ///< x > 0

  /// True when the gripper is defined by the three meshes above.
  bool has_meshes() const { return !palm_mesh.empty(); }

  /// Throws InvalidArgument naming the first field that is not finite/positive/consistent.
  void validate() const;

  /// Flange to grasp centre (contact-pad centre) along z: flange_to_tip − contact_from_tip, m.
  double grasp_depth() const { return flange_to_tip - contact_from_tip; }

  /// Opening used for the collision check of a grasp of width w: min(w + margin, max_opening).
  double collision_opening(double width) const;
};

/// Closed box meshes of the gripper in the hand frame H at a given opening (inner-face
/// separation, m, in [0, max_opening]; InvalidArgument otherwise).
struct GripperMeshes {
  Mesh palm;
  Mesh finger_left;   ///< at x < 0 (the p1 side)
  Mesh finger_right;  ///< at x > 0
};
GripperMeshes gripper_meshes(const ParallelJawGripper& gripper, double opening);

/// Translation of a finger along x of H at an opening, relative to its closed placement
/// (gripper_meshes(g, 0)): -opening/2 for the left finger (side = 0), +opening/2 for the right one
/// (side = 1). Lets callers build collision models or rigid bodies once and move them.
Pose finger_offset(int side, double opening);

/// One parallel-jaw grasp in the object frame (MetaGraspNet's [a, v, p1, w]).
struct ParallelJawGrasp {
  Vec3d p1 = Vec3d::Zero();         ///< first contact point, m
  Vec3d closing = Vec3d::UnitX();   ///< v: unit, from p1 towards the second contact
  Vec3d approach = Vec3d::UnitZ();  ///< a: unit, perpendicular to v, pointing into the object
  double width = 0.0;               ///< w = |p2 − p1|, m
};

/// Grasp frame R = [v | a×v | a] (columns) as a rotation; InvalidArgument if v or a is not unit
/// (tolerance 1e-6) or they are not perpendicular (|v·a| > 1e-6).
Mat3d grasp_rotation(const ParallelJawGrasp& grasp);

/// Pose of the hand (flange) frame H in the object frame O for a grasp: X_OH.
Pose hand_pose(const ParallelJawGrasp& grasp, const ParallelJawGripper& gripper);

}  // namespace mgn
