#pragma once
/// @file scene_grasps.hpp  Scene grasp labels (docs/models.md §9): object grasps placed at the
/// settled object poses, checked for collision in the scene once, then selected per camera view.
///
/// Frames and units: world W = tote frame, metres. X_AB = pose of B in A. Camera frame C is OpenCV
/// (x right, y down, z forward).
///
/// Per scene (SceneGraspModel constructor, view-independent, run once for all views):
///  1. Placement. A parallel-jaw grasp [a, v, p1, w] of object i (object frame) becomes the hand
///     (flange) pose X_WH = X_WO * hand_pose(grasp, gripper) and the grasp (contact) frame
///     X_WG = X_WO * (grasp_rotation(grasp), p1) (x = closing, z = approach, origin at p1).
///     A suction grasp (contact c, approach a into the surface) becomes the contact frame
///     X_WS = (R, c) with R's z column = a (x, y: the branch-free orthonormal basis of Duff et al.
///     2017, deterministic) and the tool pose X_WT = X_WS * translation(0, 0, -kSuctionToolOffset)
///     (MetaGraspNet's convention, 13.21 cm behind the contact, same axes).
///  2. Collision. The tool is placed at the grasp and moved back along the approach by every offset
///     d (X * translation(0, 0, -d) in the hand/contact frame), and at poses at most
///     options.approach_step apart on the path between consecutive offsets (the whole approach). It
///     collides when any part intersects an obstacle surface (FCL) or lies entirely inside an
///     obstacle, or an obstacle lies entirely inside a part (ray-parity tests). Obstacles: every
///     object and the tote.
///     - Parallel-jaw: palm and fingers of gripper_meshes() with the fingers at the pre-grasp
///       opening gripper.collision_opening(w). The grasped object itself is skipped at offset 0
///       exactly (the object-level sampler already checked the same hand against it) and checked
///       at every other offset.
///     - Suction: the cup body, a cylinder of cup.outer_radius from tool.clearance to
///       cup.body_height behind the contact (the body the object-level labels checked), plus a
///       shaft cylinder of tool.shaft_radius and tool.shaft_length behind the cup body. Checked
///       against every obstacle, the grasped object included, at every offset.
///     hit[k] records the first obstacle on the path from offsets[k-1] to offsets[k] (k = 0: at
///     offsets[0]); collision_part / collision_obstacle say what hit what at the first colliding
///     pose.
///  3. Wrench scores recomputed with gravity of the scene: options.gravity_world expressed in the
///     object frame, R_WO^T g (pj_wrench_scores / suction_wrench_scores). Analytical and
///     simulation scores are carried over.
///
/// Per view (view_grasps(), cheap): a grasp is kept when its object is seen in the view (an input)
/// and its contact point is visible: in front of the camera (z_C > near_plane), projecting inside
/// the image, and a ray from the camera centre towards it hits nothing closer than
/// (distance - visibility_tolerance). For parallel-jaw grasps the contact is p1 or the second
/// contact p2 = p1 + w v: the grasp is kept when at least one of them is visible.

#include <mgn/core/types.hpp>
#include <mgn/geometry/mesh.hpp>
#include <mgn/grasp/cup.hpp>
#include <mgn/grasp/gripper.hpp>
#include <mgn/grasp/pj_wrench.hpp>
#include <mgn/grasp/wrench.hpp>
#include <mgn/render/camera.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace mgn {

/// Where MetaGraspNet puts the suction tool pose (`suction_poses_relative_to_camera`): the contact
/// frame moved back along the approach by its cup approach distance (2 cm) plus its suction tool
/// height (11.21 cm), m. Only the written pose uses it; the collision geometry is SuctionTool.
inline constexpr double kSuctionToolOffset = 0.02 + 0.1121;

/// PlacedGrasps::hit of an offset that was not checked (SceneGraspOptions::first_collision_only).
inline constexpr std::int32_t kHitNotChecked = -2;

/// Geometry of the suction tool behind the cup body, for the scene collision check (m).
struct SuctionTool {
  /// Gap between the contact and the bottom of the cup body cylinder: the lip touches the surface
  /// (same value as the object-level labels' CUP_BODY_CLEARANCE).
  double clearance = 0.003;
  double shaft_radius = 0.015;  ///< radius of the tool shaft (a vacuum tube / tool body), m
  double shaft_length = 0.150;  ///< length of the shaft behind the cup body, m
  /// Throws InvalidArgument naming the first field that is not finite and > 0.
  void validate() const;
};

/// Options of the scene grasp model.
struct SceneGraspOptions {
  /// Distances back along the approach at which the tool is checked, m (finite, >= 0, at least
  /// one; default: at the grasp and 100 mm back).
  std::vector<double> offsets = {0.0, 0.1};
  /// Largest spacing of the poses checked along the path between consecutive offsets, m (> 0).
  /// The whole approach is checked: between offsets[k-1] and offsets[k] the tool is placed every
  /// approach_step (at most). A part whose extent along the approach is at least the step (every
  /// default part: palm 60 mm, fingers 50 mm, cup body 27 mm, shaft 150 mm) sweeps through every
  /// point between two checked poses, so nothing is missed for box- and cylinder-shaped parts;
  /// for other shapes only an obstacle thinner than the step along the approach can slip through.
  double approach_step = 0.005;
  SuctionTool tool;
  Vec3d gravity_world = Vec3d(0.0, 0.0, -1.0);  ///< direction of gravity in W (normalised here)
  PjWrenchOptions pj_wrench;                    ///< constants of the parallel-jaw wrench score
  SuctionWrenchOptions suction_wrench;          ///< constants of the suction wrench score
  /// A contact is visible when nothing is hit closer than (distance - tolerance), m.
  double visibility_tolerance = 0.002;
  double near_plane = 0.01;  ///< a contact must lie at z_C > near_plane in the camera frame, m
  int num_threads = 0;       ///< 0 = all hardware threads; results do not depend on it
  /// Stop checking a label grasp at its first colliding pose: `colliding`, `collision_part` and
  /// `collision_obstacle` are the same as without it, but PlacedGrasps::hit of the offsets after
  /// the first colliding one holds kHitNotChecked instead of their first obstacle. What the
  /// dataset files store does not depend on it (they hold no per-offset hits); about half the
  /// collision tests of a cluttered scene, where nearly every grasp collides at the grasp pose.
  /// collides() always checks every offset.
  bool first_collision_only = false;
  /// Throws InvalidArgument naming the first bad field.
  void validate() const;
};

/// The object-level grasp labels of one object (object frame O, metres), as the scene model
/// reads them. Empty vectors: no labels of that kind.
struct ObjectGraspLabels {
  std::vector<ParallelJawGrasp> pj;  ///< parallel-jaw grasps (object frame)
  /// Per grasp scores in [0, 1], the same length as pj, or empty (then NaN).
  std::vector<float> pj_score_analytical, pj_score_simulation;
  Points3f suction_points;    ///< (K,3) suction contacts, object frame, m
  Points3f suction_approach;  ///< (K,3) approach directions into the surface (normalised here)
  /// Per suction grasp scores in [0, 1], length K or empty (then NaN).
  std::vector<float> suction_score_analytical, suction_score_simulation;
};

/// One object of the scene: its geometry and settled pose, with its object-level labels.
struct SceneGraspObject : ObjectGraspLabels {
  const Mesh* mesh = nullptr;    ///< closed mesh in the object frame (copied at build time)
  Pose X_WO = Pose::Identity();  ///< settled pose of the object in the world
  double mass = 0.0;             ///< kg (> 0)
  Vec3d com = Vec3d::Zero();     ///< centre of mass, object frame, m
};

/// All grasps of one kind placed in the world, objects concatenated in scene order (M rows).
struct PlacedGrasps {
  std::vector<Pose> X_W_tool;     ///< parallel-jaw: hand (flange) X_WH; suction: tool end X_WT
  std::vector<Pose> X_W_contact;  ///< parallel-jaw: grasp frame at p1; suction: contact frame
  Points3d contacts;              ///< (M,3) world: p1 (parallel-jaw) or the suction contact, m
  Points3d second_contacts;       ///< (M,3) world: p1 + w v (parallel-jaw); = contacts (suction)
  std::vector<float> width;       ///< (M) contact width w, m (suction: 0)
  std::vector<float> score_analytical, score_simulation, score_wrench;  ///< (M) [0,1] or NaN
  std::vector<std::int32_t> object_index;  ///< (M) 0-based scene index (= instance id - 1)
  std::vector<std::uint8_t> colliding;     ///< (M) 1 when the tool collides at any offset
  /// (M x K) row-major, K = number of offsets: first obstacle hit at offset k: -1 none, 0 the
  /// tote, i + 1 object i (its instance id). Obstacles are tried in the order objects 0..N-1,
  /// then the tote. With SceneGraspOptions::first_collision_only, kHitNotChecked at the offsets
  /// after the first colliding one.
  std::vector<std::int32_t> hit;
  /// (M) why the grasp collides, at the first colliding pose along the approach (the grasp
  /// first): the gripper part (CollisionPart) and the obstacle (CollisionObstacle); 0 = none.
  std::vector<std::uint8_t> collision_part, collision_obstacle;
  std::size_t size() const { return object_index.size(); }
};

/// Gripper part of a collision (PlacedGrasps::collision_part).
enum class CollisionPart : std::uint8_t { None = 0, Palm = 1, Finger = 2, Cup = 3, Shaft = 4 };
/// Obstacle of a collision (PlacedGrasps::collision_obstacle). Floor: the tote where the part
/// reaches below the inner floor surface (z < 0 in the tote frame); wall: the rest of the tote.
enum class CollisionObstacle : std::uint8_t {
  None = 0,
  Floor = 1,
  Wall = 2,
  OtherObject = 3,
  GraspedObject = 4
};

/// Kind of a grasp (tool) for SceneGraspModel::collides().
enum class GraspKind : std::uint8_t { ParallelJaw = 0, Suction = 1 };

/// Per-pose result of SceneGraspModel::collides() (the same fields as PlacedGrasps).
struct ToolCollisions {
  std::vector<std::uint8_t> colliding;  ///< (M) 1 when the tool collides at any offset
  /// (M x K) row-major first obstacle hit at offset k: -1 none, 0 the tote, i + 1 object i.
  std::vector<std::int32_t> hit;
  std::size_t size() const { return colliding.size(); }
};

/// The grasps kept in one view (rows of SceneGraspModel::pj() / suction(), ascending), with their
/// poses in the camera frame.
struct ViewGrasps {
  std::vector<std::int64_t> pj_index;
  std::vector<Pose> pj_X_C_tool;     ///< hand (flange) poses X_CH
  std::vector<Pose> pj_X_C_contact;  ///< grasp frames at p1, X_CG
  std::vector<std::int64_t> suction_index;
  std::vector<Pose> suction_X_C_tool;     ///< tool end poses X_CT
  std::vector<Pose> suction_X_C_contact;  ///< contact frames X_CS
};

/// Immutable per-scene model: placement, collisions and wrench scores are computed by the
/// constructor; view_grasps() is then cheap and thread-safe.
class SceneGraspModel {
 public:
  /// Builds the model (see the file comment). The tote mesh is closed, placed at X_WT.
  /// Throws InvalidArgument for no objects, a null/empty mesh, a non-finite or non-rigid pose,
  /// a non-positive mass, a non-finite grasp, score vectors of a wrong length, invalid options,
  /// gripper or cup.
  SceneGraspModel(const std::vector<SceneGraspObject>& objects, const Mesh& tote, const Pose& X_WT,
                  const ParallelJawGripper& gripper, const Cup& cup,
                  const SceneGraspOptions& options = {});
  ~SceneGraspModel();
  SceneGraspModel(const SceneGraspModel&) = delete;
  SceneGraspModel& operator=(const SceneGraspModel&) = delete;

  std::size_t num_objects() const;
  const SceneGraspOptions& options() const;
  const PlacedGrasps& pj() const;       ///< parallel-jaw grasps in the world
  const PlacedGrasps& suction() const;  ///< suction grasps in the world

  /// Whether each world point (N,3) is visible from the camera (see the file comment).
  std::vector<std::uint8_t> visible(const CameraView& view, const Points3d& points) const;

  /// Grasps kept in a view. `seen` has one entry per object (non-zero: the object has visible
  /// pixels in the view). Throws InvalidArgument for a wrong length or an invalid view.
  ViewGrasps view_grasps(const CameraView& view, const std::vector<std::uint8_t>& seen) const;

  /// Collision of arbitrary tool poses with exactly the test that made the labels' `colliding`
  /// flags (same tool geometry, same offsets, same obstacles: every object and the tote).
  ///
  /// @param kind          ParallelJaw or Suction.
  /// @param X_W_contact   (M) grasp poses in the world, the contact frames of PlacedGrasps:
  ///                      parallel-jaw: the grasp frame at the first contact p1 (x = closing,
  ///                      z = approach); the hand is at X_W_contact * (I, ((w/2), 0, -grasp_depth))
  ///                      (gripper.hpp). Suction: the contact frame (z = approach into the
  ///                      surface, origin at the contact); the cup body and shaft lie at z < 0.
  /// @param width         (M) contact width w of each parallel-jaw grasp, m, in [0, max_opening]
  ///                      (the fingers are checked at gripper.collision_opening(w)); ignored and
  ///                      may be empty for suction.
  /// @param target_object (M) 0-based scene index of the object being grasped, or -1 (none).
  ///                      Parallel-jaw: as for the labels, the target is skipped at offset 0
  ///                      exactly (the object-level sampler checked the hand against it there)
  ///                      and checked at every other offset; with `check_target_at_grasp` the
  ///                      hand is tested against the target at offset 0 too, with the same
  ///                      test (surface contact or a part inside it): the fingers, open at the
  ///                      collision opening around the grasp, must not touch it. Suction: the
  ///                      target is checked like every other obstacle at every offset (as for
  ///                      the labels); the argument is only validated.
  /// @return per pose: colliding flag and the first obstacle hit per offset.
  ///
  /// For the label grasps, collides(kind, placed.X_W_contact, placed.width, placed.object_index)
  /// reproduces placed.colliding and placed.hit. Thread-safe (the model is immutable); runs with
  /// options().num_threads, results do not depend on it. Throws InvalidArgument for lengths that
  /// differ, a non-finite or non-rigid pose, a width outside [0, max_opening] or a target outside
  /// [-1, num_objects).
  ToolCollisions collides(GraspKind kind, const std::vector<Pose>& X_W_contact,
                          const std::vector<double>& width,
                          const std::vector<std::int32_t>& target_object,
                          bool check_target_at_grasp = false) const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace mgn
