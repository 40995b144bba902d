#pragma once
/// @file layout.hpp  Layout labels of one camera view: occlusion relations between objects, their
/// layers, a picking order and the view's difficulty level (MetaGraspNet, paper Table IV).
///
/// Inputs are the per-view label images of a scene with N objects (instance id i+1 = object
/// index i), all row-major, H rows by W columns, in the camera's image frame (row = v down,
/// column = u right):
///   - visible: the visible instance id of every pixel, 0 = nothing (background, tote, floor);
///   - amodal:  N binary masks, object i rendered alone (all other objects and the tote hidden);
///   - depth:   z-depth of every pixel, m (0 or NaN = invalid);
///   - categories and occlusion rates (1 - visible px / amodal px) of the objects.
///
/// Definitions (all pixel counts are of the given images):
///   - Seen-over count S[a][b] = number of pixels whose visible id is a+1 and that lie inside the
///     amodal mask of b (a hides b there).
///   - Contour of a over b: the pixel pairs (p, q), 4-adjacent, p in b's visible mask, q in a's
///     visible mask and inside b's amodal mask (a covers b at q). A pair is measured when both
///     depths are valid; on it, a is in front when depth(q) < depth(p).
///   - a's own stretch of boundary over b: the pixels p of b with at least one measured contour
///     neighbour q in front. A pair lies on the stretch of whichever object is in front there, so
///     no boundary counts for both directions of a mutual pair.
///   - Relation: a occludes b (a is a parent of b) iff both objects are visible (>= 1 visible
///     pixel), S[a][b] >= min_overlap_px, S[a][b] >= min_overlap_fraction * (S[a][b] +
///     S[b][a]), and a is seen above b where they meet: its own stretch over b is not empty, or
///     their contour has no measured pair (then the masks alone decide: edge_size 0, depth_diff
///     NaN). A parent that lies behind its child all along a measured contour is no parent. Both
///     directions can hold (mutual occlusion: interlocked or nested objects), each on its own
///     stretch.
///   - Relation matrix M (N x N, row-major): M[i][j] = -1 if j occludes i, else +1 if i occludes
///     j, else 0 (with mutual occlusion both entries are -1: the -1 convention of the files wins).
///   - edge_size of a relation = the pixel count of the parent's own stretch; depth_diff = median
///     over them of depth(p) - mean depth of p's in-front neighbours q (m; > 0 by construction).
///   - total_covered_edge of a = the sum of the edge_size of a's relations as a parent (the
///     boundary along which a covers its children), as in MetaGraspNet's sample scenes.
///   - Layers (visible objects): 0 top = no parent; 1 secondary = exactly one parent, which is a
///     top object; 2 interlock = member of a strongly connected component S (of the directed
///     parent -> child graph) of size >= 2 in which every member has at most one parent outside
///     S; 3 others. Objects that are not visible get layer 3, no relations and visible = false
///     (the dataset files leave them out of the view: mgn.view_labels.objects.seen_objects).
///   - Picking order: the visible objects' instance ids (1-based) such that every object comes
///     after all its parents (Kahn's algorithm, smallest instance id first among the ready ones).
///     When only objects in occlusion cycles remain, the cycle is broken by taking, among the
///     objects whose remaining parents all lie in their own strongly connected component, the
///     one with the smallest occlusion rate (ties: smallest instance id).
///   - Complete: the visible mask is one connected region with 8-connectivity, ignoring regions
///     smaller than max(min_region_px, min_region_fraction * visible px). An object whose
///     regions are all below that threshold counts as complete; invisible objects are not
///     complete (and are ignored by the difficulty).
///   - Classes unique: no two visible objects share a category.
///   - Difficulty (visible objects only): 1 = at most 2 distinct layers present, no occlusion
///     rate above max_occlusion_level1 (0.05), every object complete, classes unique; 2 = every
///     object complete and classes unique; 3 = classes unique, some object incomplete; 4 = every
///     object complete, some class repeated; 5 = some incomplete and some class repeated. A view
///     without visible objects is level 1.
///
/// The result depends only on the inputs and options (not on num_threads).

#include <cstdint>
#include <vector>

namespace mgn {

/// Read-only views of the label images of one camera view (see the file comment). The caller
/// keeps the buffers alive during compute_layout(); sizes are height * width (visible, depth),
/// num_objects * height * width (amodal) and num_objects (categories, occlusion).
struct LayoutImages {
  int height = 0;                            ///< H, pixels, >= 1
  int width = 0;                             ///< W, pixels, >= 1
  int num_objects = 0;                       ///< N, >= 0
  const std::int32_t* visible = nullptr;     ///< (H, W) instance ids in [0, N]
  const std::uint8_t* amodal = nullptr;      ///< (N, H, W) masks, 0 = outside, else inside
  const float* depth = nullptr;              ///< (H, W) m; 0 or NaN = invalid
  const std::int32_t* categories = nullptr;  ///< (N,) category ids (any integer)
  const double* occlusion = nullptr;         ///< (N,) occlusion rates in [0, 1]
};

/// Thresholds of compute_layout().
struct LayoutOptions {
  /// Minimum seen-over pixel count for a relation, px, >= 1.
  int min_overlap_px = 10;
  /// Minimum share of the decided overlap (pixels of the two amodal masks' intersection seen as
  /// one of the two objects) for a relation, in [0, 1].
  double min_overlap_fraction = 0.1;
  /// Regions of a visible mask below max(min_region_px, min_region_fraction * visible px) are
  /// specks and do not make an object incomplete. min_region_px >= 1, fraction in [0, 1].
  int min_region_px = 10;
  double min_region_fraction = 0.005;
  /// Difficulty level 1 requires every visible object's occlusion rate <= this, in [0, 1].
  double max_occlusion_level1 = 0.05;
  /// Threads for the per-object passes, 0 = all hardware threads.
  int num_threads = 0;
};

/// One occlusion relation: parent occludes (lies on) child. Object indices are 0-based.
struct LayoutRelation {
  int parent = 0;
  int child = 0;
  /// Median depth(child) - depth(parent) on the parent's own stretch of boundary, m, > 0; NaN
  /// when their contour has no measured pixel pair (edge_size 0).
  double depth_diff = 0.0;
  int edge_size = 0;         ///< pixels of the parent's own stretch (of the child's visible mask)
  std::int64_t seen_px = 0;  ///< S[parent][child]: pixels where the parent hides the child
};

/// Layout labels of one view (object axis = the N objects in order, index i = instance id i+1).
struct Layout {
  int num_objects = 0;
  std::vector<std::int8_t> relation;             ///< (N, N) row-major matrix M (see file comment)
  std::vector<LayoutRelation> relations;         ///< sorted by (child, parent)
  std::vector<std::int64_t> visible_px;          ///< (N,) visible pixel count
  std::vector<std::uint8_t> visible;             ///< (N,) 1 if visible_px > 0
  std::vector<std::int8_t> layer;                ///< (N,) 0 top, 1 secondary, 2 interlock, 3 others
  std::vector<std::int32_t> num_regions;         ///< (N,) connected regions above the speck size
  std::vector<std::uint8_t> complete;            ///< (N,)
  std::vector<std::int64_t> total_covered_edge;  ///< (N,) px, sum of the children's edge_size
  std::vector<std::int32_t> order;               ///< picking order, 1-based instance ids
  int num_layers = 0;                            ///< distinct layers among the visible objects
  double max_occlusion = 0.0;  ///< max occlusion rate of the visible objects (0 if none)
  bool classes_unique = true;  ///< no two visible objects share a category
  int difficulty = 1;          ///< 1..5
};

/// Computes the layout labels of one view. Throws InvalidArgument on a null buffer, a
/// non-positive image size, N < 0, a visible id outside [0, N], an occlusion rate outside [0, 1]
/// or NaN, or options out of range (the message names the value and what was expected).
Layout compute_layout(const LayoutImages& images, const LayoutOptions& options = {});

}  // namespace mgn
