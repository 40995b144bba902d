#pragma once
/// @file rigid_object.hpp  The rigid object that mgn's Bullet simulations move (the drop into the
/// tote, mgn/scene/drop.hpp, and the shake test of grasps, mgn/grasp/shake_trial.hpp), its
/// principal frame and the reduction of its convex hulls (docs/models.md §5 and §6).
///
/// Frames: O = the object (mesh) frame; B = its principal (body) frame, origin at the centre of
/// mass, axes along the principal axes of inertia (right-handed). Units SI (m, kg, kg m^2).

#include <mgn/core/types.hpp>
#include <mgn/geometry/mesh.hpp>

#include <string>
#include <vector>

namespace mgn {

/// A rigid body for the physics simulations. Both the drop and the shake test take this type
/// (DropObject and PhysicsObject are its names there). Defaults: mass and inertia have none that
/// makes sense (0: rejected until set); friction and restitution are the drop's contact
/// properties (the shake test takes its friction from its friction grid and ignores both).
struct RigidObject {
  /// Closed convex meshes in the object frame O whose union is the collision shape (e.g. the
  /// output of convex_decomposition(), or the object itself when it is convex); each part is
  /// used as the convex hull of its vertices. At least one, each with >= 4 non-coplanar vertices.
  std::vector<Mesh> convex_parts;
  double mass = 0.0;              ///< kg (shake test: at density factor 1), finite and > 0
  Vec3d com = Vec3d::Zero();      ///< centre of mass p_OCm, m, object frame
  Mat3d inertia = Mat3d::Zero();  ///< kg m^2 about the centre of mass, axes of O; symmetric PD
  double friction = 0.5;          ///< Coulomb coefficient against the tote and other objects
  double restitution = 0.1;       ///< in [0, 1], drop only
  std::string name;               ///< used in error messages only
};

/// Principal frame of a rigid object.
struct PrincipalFrame {
  Pose X_OB = Pose::Identity();   ///< principal frame B in O (origin at the centre of mass)
  Vec3d moments = Vec3d::Zero();  ///< principal moments of inertia (ascending), kg m^2
};

/// Principal frame of `object` (eigen-decomposition of its symmetrised inertia; the third axis is
/// flipped if needed so that B is right-handed). Throws InvalidArgument, prefixed with `context`,
/// if the inertia is not finite, not symmetric (relative 1e-6) or not positive definite.
PrincipalFrame principal_frame(const RigidObject& object, const std::string& context);

/// How a convex part's hull is reduced to few vertices for Bullet (a support query costs time
/// linear in the vertex count).
enum class HullReduction {
  /// Greedy farthest-point subset of the hull's vertices (reduce_convex_points()): the reduced
  /// hull lies INSIDE the part, short of it by up to the reported deviation.
  InnerGreedy,
  /// Support points of the hull along well-spread directions (spread_support_points()): also
  /// inside the part.
  InnerSupportDirections,
  /// A subset of the hull's face planes chosen greedily (outer_hull_vertices()): the reduced
  /// hull CONTAINS the part, and every part face it keeps is a face of it.
  Outer,
};

/// Support points of a point set along n well-spread unit directions (a Fibonacci sphere),
/// each point at most once: an inner approximation of the set's hull with at most n vertices.
/// Deterministic; the result depends on the units of the points only through their order.
std::vector<Vec3d> spread_support_points(const std::vector<Vec3d>& points, int n);

/// Vertices of a convex polytope that contains every point of `points` (a finite point set
/// spanning a volume, m) with at most `max_vertices` (>= 8) vertices: the intersection of a
/// subset of the face planes of the points' convex hull, chosen greedily (each round adds the
/// hull face whose plane cuts off most of the current polytope's farthest protruding vertex)
/// until the polytope protrudes at most `tolerance` (m, >= 0) beyond the hull or one more
/// plane would exceed the vertex budget. The vertices of the hull itself are returned if it has
/// at most `max_vertices`. If `max_excess` is given it receives the largest distance (m) of a
/// returned vertex outside the hull (0 for the hull itself). Deterministic. Throws
/// InvalidArgument for fewer than 4 points, non-finite points, points spanning no volume,
/// max_vertices < 8 or a negative tolerance.
std::vector<Vec3d> outer_hull_vertices(const std::vector<Vec3d>& points, int max_vertices,
                                       double tolerance = 0.0, double* max_excess = nullptr);

}  // namespace mgn
