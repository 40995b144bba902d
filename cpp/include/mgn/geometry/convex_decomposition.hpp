#pragma once
/// @file convex_decomposition.hpp  Convex hulls and approximate convex decomposition of a mesh.
///
/// Units: metres. Frame: every output mesh is in the frame of the input mesh (the object frame
/// O). Output hulls are closed, outward-wound convex triangle meshes. Used for rigid-body physics
/// (Bullet compound shapes) where a concave object is represented by a union of convex parts.

#include <mgn/geometry/mesh.hpp>

#include <cstdint>
#include <vector>

namespace mgn {

/// Options of convex_decomposition(). The decomposition is HACD (hierarchical approximate
/// convex decomposition, Mamou & Ghorbel 2009) as shipped with Bullet's extras.
struct ConvexDecompositionOptions {
  /// If the convex hull's volume exceeds the mesh volume by at most this fraction, the mesh is
  /// taken as convex and its single hull is returned (0.10 = 10 %: a can with a domed bottom
  /// rests like its hull). >= 0.
  double convex_volume_tolerance = 0.10;
  /// Maximum concavity allowed in a part, as a fraction of the bounding-box diagonal. > 0.
  double max_concavity = 0.02;
  /// Stop merging when this many parts are left (the decomposition may return more when the
  /// concavity bound forbids merging further; never fewer). >= 1.
  int min_parts = 1;
  /// Upper bound on the parts returned: while HACD returns more, max_concavity is doubled and
  /// the decomposition repeated. >= min_parts.
  int max_parts = 32;
  /// Weight of the compactness (perimeter^2 / area) term of HACD's merge cost. >= 0.
  double compactness_weight = 0.1;
  /// Weight of the volume term of HACD's merge cost. >= 0.
  double volume_weight = 0.0;
  /// Let HACD sample extra points (face centres, distance points) when it measures concavity:
  /// slightly better parts, much slower on meshes with thousands of faces.
  bool extra_concavity_points = true;
  /// Meshes with more faces are simplified for HACD by clustering their vertices on a grid of
  /// `grid_resolution` cells along the bounding-box diagonal (the part hulls are still built
  /// from the original vertices, so they contain every one). >= 4 each.
  std::int64_t max_hacd_faces = 1500;
  int grid_resolution = 40;
  /// After HACD, parts are merged greedily, the pair whose merged hull adds the least volume
  /// first (added volume = hull(A u B) - vol(A) - vol(B), counted as >= 0), while the total
  /// volume added stays within this fraction of the volume of the mesh's convex hull (so that
  /// thin-walled objects, whose own volume is small, are treated like solid ones of their
  /// size; a cavity larger than the budget, such as a glass's bowl, stays open). Fewer parts
  /// make the physics
  /// much cheaper (compound-compound contact pairs); the merged hull contains both parts, so
  /// every input vertex still lies in some part. 0: no merging. >= 0.
  double merge_volume_tolerance = 0.0;
  /// After the merging above, parts are merged further (cheapest first, whatever the volume
  /// added) until at most this many are left. 0: no cap; else >= 1.
  int merge_max_parts = 0;
};

/// Convex hull of the mesh's vertices (Bullet's btConvexHullComputer), as a closed,
/// outward-wound triangle mesh in the same frame. Planar hull faces are fan-triangulated.
/// Throws InvalidArgument for an empty mesh or vertices that span no volume (all coplanar).
Mesh convex_hull(const Mesh& mesh);

/// Convex hull of a point set (N >= 4, finite, not coplanar), same conventions as convex_hull().
Mesh convex_hull_of_points(const Points3f& points);

/// Approximate convex decomposition: closed convex meshes (object frame) whose union
/// approximates the object. If the mesh is (nearly) convex (hull volume within
/// options.convex_volume_tolerance of the mesh volume) the single hull is returned. Every part
/// is the exact hull of a cluster of the input's faces, so every input vertex lies in (on the
/// boundary of) at least one part. The result is deterministic. Throws InvalidArgument for an
/// empty or non-finite mesh or out-of-range options.
std::vector<Mesh> convex_decomposition(const Mesh& mesh,
                                       const ConvexDecompositionOptions& options = {});

/// Reduced convex hull for fast physics (the cost of a Bullet convex-hull support query is linear
/// in its vertex count). Chooses a subset of `points` greedily: it starts from a tetrahedron of
/// extreme points and then, in rounds, adds for each face of the hull of the points chosen so far
/// the point farthest outside it (farthest first while the budget lasts), until `max_vertices` are
/// chosen or every point lies within `tolerance` (m) of a face plane of that hull. The hull of the
/// subset lies inside the hull of all points. Returns the row indices of the chosen points (in
/// order of selection; all rows, in order, if there are at most `max_vertices` or they span no
/// volume). If `max_deviation` is given it receives the largest distance (m) of any point outside a
/// face plane of the reduced hull (0 when every point was kept). Deterministic. Throws
/// InvalidArgument for non-finite points, max_vertices < 4 or a negative / non-finite tolerance.
std::vector<Eigen::Index> reduce_convex_points(const Points3d& points, int max_vertices,
                                               double tolerance = 0.0,
                                               double* max_deviation = nullptr);

/// Enclosed volume (m^3) of a closed mesh by the divergence theorem (absolute value).
double closed_mesh_volume(const Mesh& mesh);

}  // namespace mgn
