#pragma once
/// @file drop.hpp  Drop objects into the tote and let them settle (Bullet rigid-body physics).
///
/// Frames: the world frame W is the tote frame (origin at the centre of the inner floor top,
/// x along the inner length, y along the inner width, z up; see python/mgn/objects/tote.py).
/// The object frame O is the frame of each object's mesh. Poses X_WO map object coordinates to
/// world coordinates. Units: SI (m, kg, s, rad).
///
/// Objects are released all at once at random orientations and random positions in the release
/// window (MetaGraspNet: x +-60 mm, y +-30 mm, z 0.3-0.8 m above the floor); the drawn point is
/// the centre of the object's rotated bounding box, moved inwards where that box would reach
/// beyond a wall, so every object starts inside the walls (one wider than the cavity in its drawn
/// orientation starts above the guard walls instead). Initial overlaps are avoided
/// deterministically: objects are placed in order of their drawn height, and an object whose
/// bounding box would overlap one already placed is lifted just above it. While the objects fall
/// and pile up, the walls reach DropOptions::guard_height above the rim (guard walls: collision
/// only), so objects bouncing off the pile stay in. The simulation runs until every object in
/// the tote has been at rest for DropOptions::rest_time, or until DropOptions::max_time; then the
/// guard walls are lowered to the rim and the pile settles again (at most
/// DropOptions::resettle_time more), so an object piled above the rim stays only where it is
/// stable without them. Objects that left the tote (fell below the floor, or rest on or over the
/// rim) are removed, and the remaining objects are simulated again until they are at rest (at
/// most DropOptions::resettle_time more), so nothing is left leaning on a removed object. The
/// result depends only on the inputs and DropOptions::seed (object i draws from Rng(seed, i)).

#include <mgn/core/types.hpp>
#include <mgn/geometry/mesh.hpp>
#include <mgn/physics/rigid_object.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace mgn {

/// A dynamic object to drop: convex parts, mass properties, friction and restitution (one type
/// with the shake test's objects; see mgn/physics/rigid_object.hpp for the fields and defaults).
using DropObject = RigidObject;

/// The tote's inner cavity (tote frame as above). Walls are named by their outward side:
/// -x at x = -inner_length/2, +x at x = +inner_length/2, -y, +y likewise; floor at z = 0.
struct ToteBox {
  double inner_length = 0.400;     ///< m, along x
  double inner_width = 0.300;      ///< m, along y
  double inner_height = 0.150;     ///< m, floor top to rim
  double wall_thickness = 0.008;   ///< m
  double floor_thickness = 0.010;  ///< m
  /// false: a table top without walls. The "tote" is then a slab of inner_length x inner_width x
  /// floor_thickness with its top at z = 0 (the tote mesh needs not reach inner_height, which only
  /// bounds the release window); objects leave when they fall below the top (off an edge) rather
  /// than when they rest over a rim, and no object touches a wall (every bin relation is no_rel).
  bool walls = true;
};

/// How the static tote collides.
enum class ToteCollision {
  /// Five static boxes (floor and walls) fitted to the ToteBox, thickened outwards (the cavity is
  /// exact). Robust against tunnelling through thin walls; the default.
  Boxes,
  /// The tote mesh as a static BVH triangle mesh (exact outside shape, thin walls).
  TriangleMesh,
};

/// Options of drop_objects().
struct DropOptions {
  /// Release window in the tote frame, m: x, y, z ranges (min <= max, inside the cavity
  /// horizontally, z min >= 0). MetaGraspNet: x +-0.06, y +-0.03, z 0.3-0.8.
  Vec3d window_min = Vec3d(-0.06, -0.03, 0.30);
  Vec3d window_max = Vec3d(0.06, 0.03, 0.80);
  double dt = 1.0 / 240.0;     ///< s, fixed time step, in (0, 0.02]
  int solver_iterations = 20;  ///< Bullet sequential-impulse iterations, >= 1
  double max_time = 7.0;       ///< s of simulated time at most (MetaGraspNet: 7 s), > dt
  /// An object is at rest when it is slower than linear_rest (m/s) and angular_rest (rad/s) and
  /// over the last rest_time (s) has moved less than linear_rest * rest_time and turned less than
  /// angular_rest * rest_time (so a momentary speed spike of a resting object, solver jitter,
  /// does not restart the count, but real motion does). All > 0.
  double linear_rest = 0.01;
  double angular_rest = 0.1;        ///< rad/s, see linear_rest
  double rest_time = 0.2;           ///< s, see linear_rest
  double gravity = 9.81;            ///< m/s^2, > 0, along -z
  double rolling_friction = 0.002;  ///< Bullet rolling-friction coefficient of the objects, >= 0
  double angular_damping = 0.05;    ///< fraction of angular velocity lost per second, [0, 1)
  double tote_friction = 0.5;       ///< Coulomb coefficient of the tote, >= 0
  double tote_restitution = 0.1;    ///< in [0, 1]
  /// Bullet collision margin, m (> 0). Convex parts are shrunk by it so the effective surface is
  /// the part's (with rounded edges).
  double collision_margin = 0.001;
  /// An object touches a wall or the floor if a contact point lies within this distance, m (> 0).
  double contact_distance = 0.002;
  /// Remove objects that are still moving at max_time (else keep them with settled = false).
  bool remove_unsettled = false;
  /// Each convex part's Bullet hull is reduced to at most this many vertices (0: keep all; else
  /// >= 8) by outer_hull_vertices(): a support query costs time linear in the vertex count and
  /// dominates the drop. The reduced hull CONTAINS the part (it is cut from the part's own face
  /// planes), so resting objects do not sink into the floor or into each other; it protrudes
  /// beyond the part by at most hull_tolerance where the vertex budget allows.
  int max_hull_vertices = 384;
  /// Stop reducing a hull once no vertex of the reduced hull lies farther than this distance
  /// (m, >= 0) outside the part.
  double hull_tolerance = 0.0002;
  /// Contacts between convex parts (and with the tote boxes) from Bullet's polyhedral clipping
  /// (a whole face-on-face contact patch in one step: piles come to rest much sooner) instead of
  /// one GJK point per step. The hulls are then not shrunk by the margin (the clipping ignores
  /// margins), so the contact surface is the part itself.
  bool polyhedral_contacts = true;
  /// An object that comes to rest not entirely inside the walls (on or over the rim) is removed
  /// at once (and so is any such object at max_time); the others are then simulated again until
  /// they are at rest, with this much simulated time (s, >= 0) allowed beyond max_time.
  double resettle_time = 2.0;
  /// Friction along two tangent directions per contact (kept from step to step; the default)
  /// instead of one. With one, Bullet resists sliding only along the current slip direction, so
  /// a resting object can creep along the other tangent: large piles creep for seconds and
  /// often never pass the rest test before max_time (20-object scenes: ~2x more steps, ~2.5x
  /// more CPU; docs/decisions/0014-drop-two-friction-directions.md). With two, a symmetric
  /// resting contact can drift to one side.
  bool two_friction_directions = true;
  /// Guard walls: while the objects fall and pile up, the walls reach this far (m, >= 0) above
  /// the rim (collision only), so objects bouncing off the pile stay in the tote; once the pile
  /// rests (or at max_time) they are lowered to the rim and the pile settles again with
  /// resettle_time (s) allowed. 0: no guard walls. Not used without walls (a table top) or by
  /// settle_objects().
  double guard_height = 0.6;
  ToteCollision tote_collision = ToteCollision::Boxes;
  std::uint64_t seed = 0;
};

/// Checks every DropOptions field against its documented range (the release window only for
/// min <= max: whether it lies above the cavity depends on the ToteBox and is checked by
/// drop_objects()). Throws InvalidArgument "DropOptions.<field> must be <range>, got <value>".
void validate(const DropOptions& options);

/// Why an object is not kept.
enum class DropStatus {
  Kept = 0,        ///< at rest inside the tote
  LeftTote = 1,    ///< fell out, or rests on/over the rim (not entirely inside the walls)
  NotSettled = 2,  ///< still moving at max_time (only with remove_unsettled)
};

/// Tote surfaces, as bit flags of DroppedObject::contacts.
enum ToteContact : std::uint32_t {
  ContactWallMinusX = 1u << 0,
  ContactWallPlusX = 1u << 1,
  ContactWallMinusY = 1u << 2,
  ContactWallPlusY = 1u << 3,
  ContactFloor = 1u << 4,
};

/// Outcome for one input object (same order as the input).
struct DroppedObject {
  Pose X_WO = Pose::Identity();          ///< settled pose (or the pose where it was removed)
  Pose X_WO_release = Pose::Identity();  ///< release pose
  DropStatus status = DropStatus::Kept;
  bool settled = false;        ///< at rest when the simulation stopped
  std::uint32_t contacts = 0;  ///< ToteContact flags after settling (kept objects)
  bool kept() const { return status == DropStatus::Kept; }
};

/// Outcome of drop_objects().
struct DropResult {
  std::vector<DroppedObject> objects;
  std::int64_t steps = 0;       ///< simulation steps taken
  double simulated_time = 0.0;  ///< s
  /// Every remaining object was at rest before the time ran out (max_time, plus resettle_time
  /// after removals).
  bool settled = false;
  int resettle_rounds = 0;  ///< how often objects were removed and the rest simulated again
  /// Deepest penetration between any two bodies (objects or tote) at the end, from Bullet's
  /// contact points, m (>= 0).
  double max_penetration = 0.0;
};

/// Drops `objects` into the tote and simulates until they settle (see the file comment).
/// `tote` is the tote's closed triangle mesh in the world frame (python make_tote()); it is used
/// for collisions with ToteCollision::TriangleMesh and otherwise checked for consistency with
/// `box`. Throws InvalidArgument naming the input for: no objects, an object without parts,
/// non-finite or non-positive mass / inertia, an object that cannot lie in the tote (its
/// second-largest extent exceeds the inner width, or its largest the inner diagonal), an empty
/// tote mesh, non-positive tote dimensions, or options out of range.
DropResult drop_objects(const std::vector<DropObject>& objects, const Mesh& tote,
                        const ToteBox& box, const DropOptions& options = {});

/// Simulates `objects` from the poses `X_WO_start` (object frames in the tote frame, one per
/// object, m), all starting at rest (zero velocity), until every object in the tote is at rest:
/// the same simulation, rest test and removal of objects that left the tote (or rest on the rim)
/// as drop_objects(), without the random release (DropOptions::window_min/max and seed are not
/// used). Used to let a pile settle again after objects were taken out of it: pass the remaining
/// objects at their current poses. An already resting pile stays where it is (up to solver
/// creep, well below a millimetre). DroppedObject::X_WO_release is the start pose. Throws
/// InvalidArgument for a pose count different from the object count, a non-finite or non-rigid
/// pose, and everything drop_objects() rejects (naming settle_objects).
DropResult settle_objects(const std::vector<DropObject>& objects,
                          const std::vector<Pose>& X_WO_start, const Mesh& tote, const ToteBox& box,
                          const DropOptions& options = {});

/// Name of a status ("kept", "left_tote", "not_settled").
const char* to_string(DropStatus status);

/// drop_objects() and settle_objects() keep each object's prepared collision hulls (the hull of
/// every convex part, its reduction to DropOptions::max_hull_vertices, Bullet's hull shape with
/// its support-search arrays and polyhedral features) in a process-wide cache, so a dataset that
/// drops the same objects scene after scene prepares each object once. An entry is keyed by
/// every input of the preparation, compared bit for bit: the vertices of every convex part, the
/// principal frame (from com and inertia), collision_margin, max_hull_vertices, hull_tolerance
/// and polyhedral_contacts; a changed mesh, scale or option is a new entry. Results are the same
/// bit for bit with or without the cache. Entries are read-only and shared by concurrent drops
/// (thread-safe); the least recently used are evicted beyond the capacity (estimated bytes,
/// default 64 MiB; the 30 built-in objects at the default options take about 5 MB).
struct DropHullCacheInfo {
  std::size_t entries = 0;
  std::size_t bytes = 0;       ///< estimated memory of the entries
  std::size_t capacity = 0;    ///< bytes; 0: nothing is cached
  std::int64_t hits = 0;       ///< objects whose hulls came from the cache (since the last clear)
  std::int64_t misses = 0;     ///< objects whose hulls were prepared (since the last clear)
  std::int64_t evictions = 0;  ///< entries evicted for the capacity (since the last clear)
};
DropHullCacheInfo drop_hull_cache_info();
/// Drops every entry of the hull cache and resets its counters (the capacity stays).
void clear_drop_hull_cache();
/// Sets the hull cache's capacity (estimated bytes; 0: cache nothing) and evicts down to it.
void set_drop_hull_cache_capacity(std::size_t bytes);

}  // namespace mgn
