// Antipodal robust sampling of parallel-jaw grasps (docs/models.md §5).
#include <mgn/collision/collision_model.hpp>
#include <mgn/collision/point_inside.hpp>
#include <mgn/core/error.hpp>
#include <mgn/core/parallel.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/geometry/sampling.hpp>
#include <mgn/grasp/antipodal.hpp>
#include <mgn/raytrace/ray_scene.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>

#include "grasp/detail/seal_trials.hpp"

namespace mgn {

void AntipodalOptions::validate() const {
  auto fail = [](const char* field, double value, const char* expected) {
    throw_error<InvalidArgument>("AntipodalOptions.", field, " must be ", expected, ", got ",
                                 value);
  };
  if (probes < 1) fail("probes", probes, "an integer >= 1");
  if (!(tilt >= 0.0) || !(tilt < M_PI / 2)) fail("tilt", tilt, "an angle in [0, pi/2) rad");
  if (!(offset >= 0.0) || !std::isfinite(offset)) fail("offset", offset, "a finite value >= 0 m");
  if (!(start_offset > 0.0) || !std::isfinite(start_offset))
    fail("start_offset", start_offset, "a finite value > 0 m");
  if (!(friction_coef > 0.0) || !std::isfinite(friction_coef))
    fail("friction_coef", friction_coef, "a finite value > 0");
  if (approaches_tried < 0) fail("approaches_tried", approaches_tried, "an integer >= 0");
  if (approaches_kept < 0) fail("approaches_kept", approaches_kept, "an integer >= 0");
  if (num_threads < 0) fail("num_threads", num_threads, "0 (all) or a positive thread count");
}

struct AntipodalSampler::Impl {
  ParallelJawGripper gripper;
  std::unique_ptr<RayScene> scene;
  std::unique_ptr<CollisionModel> object;
  std::unique_ptr<PointInsideTest> inside;  // the object's point-inside test
  // Gripper parts at opening 0 in the hand frame: palm, left finger, right finger.
  std::array<std::unique_ptr<CollisionModel>, 3> parts;
  std::array<Vec3d, 3> part_vertex;  // one vertex of each part (for the inside test), frame H
  // Points on the object surface (its vertices and even samples) for the certain-collision
  // pre-filter of box grippers: a surface point inside a gripper box means a collision.
  Points3d surface_points;
  // Bounding-sphere tree of the object's triangles for the certain-free test (see TriangleTree).
  struct TriangleTree {
    struct Node {
      Vec3d centre;
      double radius = 0;  // every vertex of the node's triangles lies within this of centre
      std::int32_t begin = 0, end = 0;     // triangles [begin, end) (tree order)
      std::int32_t left = -1, right = -1;  // children; -1: a leaf
    };
    std::vector<Node> nodes;                      // nodes[0]: the root
    std::vector<std::array<Vec3d, 3>> triangles;  // vertices (object frame, m), tree order
  } tree;
  // Spatial blocks of consecutive rows of surface_points (the rows are stored in block order; the
  // pre-filter only asks whether any row passes, so the order is free). A block whose bounding
  // sphere misses a box's region lets ProbePoints skip all its rows.
  struct Block {
    Vec3d centre;
    double radius = 0;  // max distance of a row's point from centre
    Eigen::Index begin = 0, end = 0;
  };
  std::vector<Block> point_blocks;
};

namespace {

/// Row order of `points` in which every run of at most `leaf` consecutive rows is spatially
/// compact (median splits along the longest axis), and the blocks (begin, end) of those runs.
std::vector<Eigen::Index> block_order(const Points3d& points, Eigen::Index leaf,
                                      std::vector<std::pair<Eigen::Index, Eigen::Index>>& blocks) {
  std::vector<Eigen::Index> order(static_cast<std::size_t>(points.rows()));
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<Eigen::Index>(i);
  std::vector<std::pair<Eigen::Index, Eigen::Index>> stack{{0, points.rows()}};
  while (!stack.empty()) {
    const auto [b, e] = stack.back();
    stack.pop_back();
    if (e - b <= leaf) {
      if (e > b) blocks.emplace_back(b, e);
      continue;
    }
    Eigen::RowVector3d lo = points.row(order[b]), hi = lo;
    for (Eigen::Index i = b; i < e; ++i) {
      lo = lo.cwiseMin(points.row(order[i]));
      hi = hi.cwiseMax(points.row(order[i]));
    }
    Eigen::Index axis = 0;
    (hi - lo).maxCoeff(&axis);
    const Eigen::Index mid = b + (e - b) / 2;
    std::nth_element(order.begin() + b, order.begin() + mid, order.begin() + e,
                     [&](Eigen::Index x, Eigen::Index y) {
                       const double px = points(x, axis), py = points(y, axis);
                       return px < py || (px == py && x < y);
                     });
    stack.emplace_back(mid, e);
    stack.emplace_back(b, mid);
  }
  std::sort(blocks.begin(), blocks.end());
  return order;
}

/// Whether the triangle p (coordinates relative to the box centre, in the box's axes, m) and the
/// box of half extents h are disjoint: separated along one of the 13 candidate axes (the box axes,
/// the triangle's normal, the 9 cross products of a box axis with a triangle edge). Exact up to
/// the rounding of these few products (~1e-17 m at object sizes).
bool triangle_box_separated(const std::array<Vec3d, 3>& p, const Vec3d& h) {
  for (int a = 0; a < 3; ++a) {
    const double lo = std::min({p[0][a], p[1][a], p[2][a]});
    const double hi = std::max({p[0][a], p[1][a], p[2][a]});
    if (lo > h[a] || hi < -h[a]) return true;
  }
  const auto separates = [&](const Vec3d& axis) {
    const double d0 = axis.dot(p[0]), d1 = axis.dot(p[1]), d2 = axis.dot(p[2]);
    const double r = h.dot(axis.cwiseAbs());
    return std::min({d0, d1, d2}) > r || std::max({d0, d1, d2}) < -r;
  };
  const std::array<Vec3d, 3> e = {p[1] - p[0], p[2] - p[1], p[0] - p[2]};
  if (separates(e[0].cross(e[1]))) return true;
  for (const Vec3d& edge : e) {  // unit x, y, z crossed with the edge
    if (separates(Vec3d(0, -edge.z(), edge.y()))) return true;
    if (separates(Vec3d(edge.z(), 0, -edge.x()))) return true;
    if (separates(Vec3d(-edge.y(), edge.x(), 0))) return true;
  }
  return false;
}

using TriangleTree = AntipodalSampler::Impl::TriangleTree;

/// Builds the tree over the mesh triangles: median splits of the centroids along the longest
/// axis, leaves of at most 4 triangles, each node bounded by a sphere around its vertices.
void build_triangle_tree(const Mesh& mesh, TriangleTree& tree) {
  const Points3f& V = mesh.vertices();
  const Faces& F = mesh.faces();
  const auto n = static_cast<std::size_t>(F.rows());
  std::vector<std::array<Vec3d, 3>> tris(n);
  std::vector<Vec3d> centroid(n);
  std::vector<std::int32_t> order(n);
  for (std::size_t f = 0; f < n; ++f) {
    for (int j = 0; j < 3; ++j)
      tris[f][j] = V.row(F(static_cast<Eigen::Index>(f), j)).transpose().cast<double>();
    centroid[f] = (tris[f][0] + tris[f][1] + tris[f][2]) / 3.0;
    order[f] = static_cast<std::int32_t>(f);
  }
  constexpr std::int32_t kLeaf = 4;
  tree.nodes.clear();
  tree.nodes.reserve(2 * n / kLeaf + 2);
  // (node index, begin, end) still to split
  std::vector<std::array<std::int32_t, 3>> stack;
  tree.nodes.emplace_back();
  stack.push_back({0, 0, static_cast<std::int32_t>(n)});
  while (!stack.empty()) {
    const auto [id, b, e] = stack.back();
    stack.pop_back();
    Vec3d lo = tris[order[b]][0], hi = lo;
    for (std::int32_t i = b; i < e; ++i)
      for (const Vec3d& p : tris[order[i]]) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    TriangleTree::Node node;
    node.centre = 0.5 * (lo + hi);
    for (std::int32_t i = b; i < e; ++i)
      for (const Vec3d& p : tris[order[i]])
        node.radius = std::max(node.radius, (p - node.centre).norm());
    node.radius = node.radius * (1 + 1e-9) + 1e-12;
    node.begin = b;
    node.end = e;
    if (e - b > kLeaf) {
      Vec3d clo = centroid[order[b]], chi = clo;
      for (std::int32_t i = b; i < e; ++i)
        clo = clo.cwiseMin(centroid[order[i]]), chi = chi.cwiseMax(centroid[order[i]]);
      Eigen::Index axis = 0;
      (chi - clo).maxCoeff(&axis);
      const std::int32_t mid = b + (e - b) / 2;
      std::nth_element(order.begin() + b, order.begin() + mid, order.begin() + e,
                       [&](std::int32_t x, std::int32_t y) {
                         const double px = centroid[x][axis], py = centroid[y][axis];
                         return px < py || (px == py && x < y);
                       });
      node.left = static_cast<std::int32_t>(tree.nodes.size());
      node.right = node.left + 1;
      tree.nodes.emplace_back();
      tree.nodes.emplace_back();
      stack.push_back({node.left, b, mid});
      stack.push_back({node.right, mid, e});
    }
    tree.nodes[static_cast<std::size_t>(id)] = node;
  }
  tree.triangles.resize(n);
  for (std::size_t i = 0; i < n; ++i) tree.triangles[i] = tris[static_cast<std::size_t>(order[i])];
}

/// Whether some triangle of the tree is not proven apart from the box (centre and axes R in the
/// object frame, half extents h, m): spheres that miss the box prune whole subtrees, the
/// remaining triangles get the separating-axis test.
bool tree_touches_box(const TriangleTree& tree, const Mat3d& R, const Vec3d& centre, const Vec3d& h,
                      std::vector<std::int32_t>& stack) {
  if (tree.nodes.empty()) return false;
  stack.clear();
  stack.push_back(0);
  while (!stack.empty()) {
    const TriangleTree::Node& node = tree.nodes[static_cast<std::size_t>(stack.back())];
    stack.pop_back();
    const Vec3d q = R.transpose() * (node.centre - centre);
    const Vec3d out = (q.cwiseAbs() - h).cwiseMax(0.0);
    if (out.squaredNorm() > node.radius * node.radius) continue;
    if (node.left >= 0) {
      stack.push_back(node.right);
      stack.push_back(node.left);
      continue;
    }
    for (std::int32_t i = node.begin; i < node.end; ++i) {
      const std::array<Vec3d, 3>& t = tree.triangles[static_cast<std::size_t>(i)];
      const std::array<Vec3d, 3> p = {R.transpose() * (t[0] - centre),
                                      R.transpose() * (t[1] - centre),
                                      R.transpose() * (t[2] - centre)};
      if (!triangle_box_separated(p, h)) return true;
    }
  }
  return false;
}

/// Axis-aligned box in the hand frame H: centre and half extents, m.
struct HandBox {
  Vec3d centre;
  Vec3d half;
};

/// Object surface points near one accepted probe, per gripper box, in the grasp's cylindrical
/// frame: for the approach a = cos t e1 + sin t e2 a point's hand-frame coordinates are
/// (x, cos t y0 + sin t y1, cos t z0 + sin t z1 + grasp_depth), with x along the closing axis v,
/// (z0, z1) its components along e1, e2 and (y0, y1) along e1 x v, e2 x v. The x test does not
/// depend on the approach, so each box keeps only the points of its x slab whose distance from the
/// closing axis can put them inside it.
struct ProbePoints {
  struct BoxPoints {
    double y_half = 0, z_lo = 0, z_hi = 0;  // box extent in y and in z relative to the centre
    std::vector<double> y0, y1, z0, z1;
  };
  std::array<BoxPoints, 3> lists;  // palm, left finger, right finger at the probe's opening

  // The probe's geometry.
  const AntipodalSampler::Impl* model = nullptr;
  std::array<HandBox, 3> boxes;
  std::array<double, 3> r2_min{}, r2_max{}, r_min{}, r_max{};
  Vec3d c, v, w1, w2, e1, e2;
  double depth = 0;
  std::vector<std::int32_t> stack;        // tree traversal storage (reused)
  std::size_t next_point_block = 0;       // point blocks before this one are in the lists
  std::array<std::size_t, 3> hot_next{};  // next of the kHot front slots of each list to replace
  static constexpr std::size_t kHot = 8;

  /// Moves row i of list k into one of its first kHot rows (swapping), so that the next
  /// approaches test it early: a row inside a box at one angle is often inside at others. The
  /// order of the rows does not change any_inside's answer (whether any row is inside).
  void promote(int k, std::size_t i) {
    if (i < kHot) return;
    BoxPoints& l = lists[k];
    const std::size_t j = hot_next[k];
    hot_next[k] = (j + 1) % kHot;
    std::swap(l.y0[i], l.y0[j]);
    std::swap(l.y1[i], l.y1[j]);
    std::swap(l.z0[i], l.z0[j]);
    std::swap(l.z1[i], l.z1[j]);
  }

  // Slack of the block tests (m): covers the rounding of the block-level distances, so a
  // skipped block never holds a row that the per-row tests would keep.
  static constexpr double kSlack = 1e-6;
  static constexpr double kEps = 1e-7;  // boxes shrunk by this: inside means strictly inside
  // Clearance (m) that surely_clear demands between every box and every triangle: far above the
  // rounding of FCL's tests and of these (~1e-16 m at object sizes), so an approach it clears is
  // one that FCL finds free.
  static constexpr double kMargin = 1e-6;

  /// Whether a block (every row within `reach` of its centre) may hold a row that reaches a box.
  bool block_may_reach(const AntipodalSampler::Impl::Block& blk, double reach) const {
    const Vec3d q = blk.centre - c;
    const double xq = q.dot(v);
    const double rho = std::sqrt(std::max(0.0, q.squaredNorm() - xq * xq));
    for (int k = 0; k < 3; ++k) {
      const HandBox& b = boxes[k];
      if (std::abs(xq - b.centre.x()) - reach > b.half.x() + kSlack) continue;
      if (rho + reach < r_min[k] - kSlack || rho - reach > r_max[k] + kSlack) continue;
      return true;
    }
    return false;
  }

  /// Fills the point lists for one accepted probe (reusing their storage) and clears the sphere
  /// lists. `m` holds the object's surface points and triangle spheres in spatial blocks; blocks
  /// that cannot reach a box's region are skipped whole, the rows of the others pass the same
  /// per-row tests.
  void build(const AntipodalSampler::Impl& m, const ParallelJawGripper& g,
             const ParallelJawGrasp& grasp, const Vec3d& e1_in, const Vec3d& e2_in,
             double opening) {
    const Vec3d& f = g.finger_size;
    const Vec3d& pb = g.palm_size;
    depth = g.grasp_depth();
    model = &m;
    e1 = e1_in;
    e2 = e2_in;
    boxes = {HandBox{Vec3d(0, 0, g.flange_to_tip - f.z() - 0.5 * pb.z()), 0.5 * pb},
             HandBox{Vec3d(-0.5 * (opening + f.x()), 0, g.flange_to_tip - 0.5 * f.z()), 0.5 * f},
             HandBox{Vec3d(0.5 * (opening + f.x()), 0, g.flange_to_tip - 0.5 * f.z()), 0.5 * f}};
    for (int k = 0; k < 3; ++k) {
      const HandBox& b = boxes[k];
      BoxPoints& l = lists[k];
      l.y0.clear(), l.y1.clear(), l.z0.clear(), l.z1.clear();
      l.y_half = b.half.y() - kEps;
      l.z_lo = b.centre.z() - b.half.z() + kEps - depth;
      l.z_hi = b.centre.z() + b.half.z() - kEps - depth;
      const double z_near = (l.z_lo > 0) ? l.z_lo : (l.z_hi < 0 ? -l.z_hi : 0.0);
      const double z_far = std::max(std::abs(l.z_lo), std::abs(l.z_hi));
      r2_min[k] = z_near * z_near;  // the box's nearest and farthest distance from the axis
      r2_max[k] = z_far * z_far + l.y_half * l.y_half;
      r_min[k] = std::sqrt(r2_min[k]);
      r_max[k] = std::sqrt(r2_max[k]);
    }
    c = grasp.p1 + 0.5 * grasp.width * grasp.closing;
    v = grasp.closing;
    w1 = e1.cross(v), w2 = e2.cross(v);
    next_point_block = 0;
    hot_next = {0, 0, 0};
  }

  /// Adds the rows of the next point block that may reach a box to the point lists; false when
  /// every block has been added.
  bool extend_points() {
    const AntipodalSampler::Impl& m = *model;
    const Points3d& surface = m.surface_points;
    while (next_point_block < m.point_blocks.size()) {
      const auto& blk = m.point_blocks[next_point_block++];
      if (!block_may_reach(blk, blk.radius)) continue;
      for (Eigen::Index i = blk.begin; i < blk.end; ++i) {
        const Vec3d q = surface.row(i).transpose() - c;
        const double xq = q.dot(v);
        const double r2 = q.squaredNorm() - xq * xq;
        for (int k = 0; k < 3; ++k) {
          const HandBox& b = boxes[k];
          if (std::abs(xq - b.centre.x()) >= b.half.x() - kEps) continue;
          if (r2 < r2_min[k] || r2 > r2_max[k]) continue;
          BoxPoints& l = lists[k];
          l.y0.push_back(q.dot(w1));
          l.y1.push_back(q.dot(w2));
          l.z0.push_back(q.dot(e1));
          l.z1.push_back(q.dot(e2));
        }
      }
      return true;
    }
    return false;
  }

  /// True when every object triangle is more than kMargin from every gripper box for the approach
  /// a (the unit vector cos t e1 + sin t e2, as the caller computes it): then the gripper surface
  /// cannot touch the object surface.
  bool surely_clear(const Vec3d& a) {
    Mat3d R;
    R.col(0) = v;
    R.col(1) = a.cross(v);
    R.col(2) = a;
    const Vec3d origin = c - depth * a;  // the hand frame's origin (see hand_pose)
    for (int k : {1, 2, 0}) {
      const HandBox& b = boxes[k];
      const Vec3d half = b.half + Vec3d::Constant(kMargin);
      if (tree_touches_box(model->tree, R, origin + R * b.centre, half, stack)) return false;
    }
    return true;
  }

  /// Whether an object point lies strictly inside a gripper box for the approach angle t. The
  /// point lists are built block by block only as far as needed: a colliding approach usually
  /// finds an inside point early, and every later call first scans the rows already built. The
  /// answer ("any row inside") is that of a scan of every row. A row found inside is moved to
  /// the front of its list (promote), so the probe's next approaches test it first.
  bool any_inside(double t) {
    const double ct = std::cos(t), st = std::sin(t);
    std::array<std::size_t, 3> from{};
    while (true) {
      for (int k = 0; k < 3; ++k) {
        BoxPoints& l = lists[k];
        const std::size_t n = l.y0.size();
        for (std::size_t i = from[k]; i < n; ++i) {
          const double z = ct * l.z0[i] + st * l.z1[i];
          const double y = ct * l.y0[i] + st * l.y1[i];
          if (z > l.z_lo && z < l.z_hi && std::abs(y) < l.y_half) {
            promote(k, i);
            return true;
          }
        }
        from[k] = n;
      }
      if (!extend_points()) return false;
    }
  }
};

}  // namespace

AntipodalSampler::AntipodalSampler(const Mesh& object, const ParallelJawGripper& gripper)
    : impl_(std::make_unique<Impl>()) {
  require_non_empty(object, "AntipodalSampler");
  const MeshReport report = object.validate();
  if (!report.is_watertight) {
    throw_error<InvalidArgument>(
        "AntipodalSampler: the object mesh '", object.name(), "' has no closed volume (",
        report.num_boundary_edges, " boundary and ", report.num_nonmanifold_edges,
        " non-manifold edges); expected a watertight mesh (antipodal probes need an inside)");
  }
  gripper.validate();
  impl_->gripper = gripper;
  impl_->scene =
      std::make_unique<RayScene>(std::vector<RayGeometry>{{&object, Pose::Identity(), 0}});
  impl_->object = std::make_unique<CollisionModel>(object);
  impl_->inside = std::make_unique<PointInsideTest>(object);
  const GripperMeshes meshes = gripper_meshes(gripper, 0.0);
  const std::array<const Mesh*, 3> parts = {&meshes.palm, &meshes.finger_left,
                                            &meshes.finger_right};
  for (int k = 0; k < 3; ++k) {
    impl_->parts[k] = std::make_unique<CollisionModel>(*parts[k]);
    impl_->part_vertex[k] = parts[k]->vertices().row(0).transpose().cast<double>();
  }
  if (!gripper.has_meshes()) {
    SampleOptions so;
    so.method = SampleMethod::Even;
    const SurfaceSamples samples = sample_surface(object, 2048, so);
    Points3d& sp = impl_->surface_points;
    sp.resize(object.num_vertices() + samples.points.rows(), 3);
    sp.topRows(object.num_vertices()) = object.vertices().cast<double>();
    sp.bottomRows(samples.points.rows()) = samples.points.cast<double>();
    build_triangle_tree(object, impl_->tree);
    // Store the rows in spatial block order (see Impl::Block).
    constexpr Eigen::Index kLeaf = 16;
    const auto make_blocks = [&](Points3d& rows, std::vector<Impl::Block>& out) {
      std::vector<std::pair<Eigen::Index, Eigen::Index>> ranges;
      const std::vector<Eigen::Index> order = block_order(rows, kLeaf, ranges);
      Points3d sorted(rows.rows(), 3);
      for (std::size_t i = 0; i < order.size(); ++i)
        sorted.row(static_cast<Eigen::Index>(i)) = rows.row(order[i]);
      rows = std::move(sorted);
      for (const auto& [b, e] : ranges) {
        Impl::Block blk;
        blk.begin = b;
        blk.end = e;
        Eigen::RowVector3d lo = rows.row(b), hi = lo;
        for (Eigen::Index i = b; i < e; ++i) {
          lo = lo.cwiseMin(rows.row(i));
          hi = hi.cwiseMax(rows.row(i));
        }
        blk.centre = (0.5 * (lo + hi)).transpose();
        for (Eigen::Index i = b; i < e; ++i)
          blk.radius = std::max(blk.radius, (rows.row(i).transpose() - blk.centre).norm());
        blk.radius *= 1 + 1e-9;
        out.push_back(blk);
      }
    };
    make_blocks(impl_->surface_points, impl_->point_blocks);
  }
}

AntipodalSampler::~AntipodalSampler() = default;

const ParallelJawGripper& AntipodalSampler::gripper() const { return impl_->gripper; }

namespace {

/// Rotation by Euler angles about x, then y, then z (fixed axes): Rz * Ry * Rx.
Mat3d euler_xyz(double ax, double ay, double az) {
  return (Eigen::AngleAxisd(az, Vec3d::UnitZ()) * Eigen::AngleAxisd(ay, Vec3d::UnitY()) *
          Eigen::AngleAxisd(ax, Vec3d::UnitX()))
      .toRotationMatrix();
}

/// Whether a gripper part at hand pose X_OH (fingers at `opening`) lies inside the closed
/// object. Without surface contact a part is either fully outside or fully inside it.
bool parts_inside(const AntipodalSampler::Impl& m, const Pose& X_OH, double opening) {
  const std::array<Pose, 3> X = {X_OH, X_OH * finger_offset(0, opening),
                                 X_OH * finger_offset(1, opening)};
  Points3d points(3, 3);
  for (int k = 0; k < 3; ++k) points.row(k) = (X[k] * m.part_vertex[k]).transpose();
  return m.inside->contains_any(points);
}

void check_sample_input(const Points3d& points, const Points3d& normals) {
  const Eigen::Index n = points.rows();
  if (normals.rows() != n) {
    throw_error<InvalidArgument>("sample_antipodal_grasps: points has ", n,
                                 " rows but normals has ", normals.rows(),
                                 "; expected the same count");
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!points.row(i).allFinite() || !normals.row(i).allFinite() ||
        !(normals.row(i).norm() > 1e-12)) {
      throw_error<InvalidArgument>("sample_antipodal_grasps: point/normal ", i,
                                   " is not finite or the normal is zero; expected finite points "
                                   "and non-zero normals");
    }
  }
}

/// The probes of a chunk of points: row (i - begin) * probes + k is probe k of point i.
struct ChunkProbes {
  Points3f origins, directions;
  RayAllHits hits;  // the first two surface crossings of each probe
};

/// Draws the probes of points [begin, end), each point from its own stream (appended to rngs,
/// left after its probes), and casts them in one batch.
ChunkProbes cast_probes(const AntipodalSampler::Impl& m, const AntipodalOptions& o,
                        const Points3d& points, const Points3d& normals, std::size_t begin,
                        std::size_t end, std::vector<Rng>& rngs) {
  const int P = o.probes;
  const auto count = static_cast<Eigen::Index>(end - begin);
  rngs.reserve(end - begin);
  ChunkProbes c;
  c.origins.resize(count * P, 3);
  c.directions.resize(count * P, 3);
  Points3d origins_d(count * P, 3), directions_d(count * P, 3);
  for (std::size_t i = begin; i < end; ++i) {
    rngs.emplace_back(o.seed, o.first_index + i);
    Rng& rng = rngs.back();
    const Vec3d p = points.row(i).transpose();
    const Vec3d nrm = normals.row(i).transpose().normalized();
    for (int k = 0; k < P; ++k) {
      const double ax = rng.uniform(-o.tilt, o.tilt);
      const double ay = rng.uniform(-o.tilt, o.tilt);
      const double az = rng.uniform(-o.tilt, o.tilt);
      Vec3d shift;
      for (int axis = 0; axis < 3; ++axis) shift[axis] = rng.uniform(-o.offset, o.offset);
      const Vec3d d = (euler_xyz(ax, ay, az) * -nrm).normalized();
      const Vec3d start = p + shift - o.start_offset * d;
      const Eigen::Index r = static_cast<Eigen::Index>(i - begin) * P + k;
      origins_d.row(r) = start.transpose();
      directions_d.row(r) = d.transpose();
    }
  }
  c.origins = origins_d.cast<float>();
  c.directions = directions_d.cast<float>();
  CastOptions cast;
  cast.num_threads = 1;
  c.hits = m.scene->intersect_all(c.origins, c.directions, 2, cast);
  return c;
}

/// The antipodal test of the P probes from row r0 on: the grasps of the probes whose two
/// crossings lie within the opening and inside each other's friction cone, with their probe
/// indices.
void accept_probes(const ChunkProbes& c, Eigen::Index r0, int P, const ParallelJawGripper& g,
                   double cos_cone, std::vector<ParallelJawGrasp>& accepted,
                   std::vector<int>& accepted_probe) {
  const RayAllHits& hits = c.hits;
  for (int k = 0; k < P; ++k) {
    const Eigen::Index r = r0 + k;
    const std::int64_t h0 = hits.offsets[r];
    if (hits.offsets[r + 1] - h0 < 2) continue;
    const Vec3d start = c.origins.row(r).transpose().cast<double>();
    const Vec3d d = c.directions.row(r).transpose().cast<double>();
    const Vec3d q1 = start + static_cast<double>(hits.distance[h0]) * d;
    const Vec3d q2 = start + static_cast<double>(hits.distance[h0 + 1]) * d;
    const double w = (q2 - q1).norm();
    if (!(w > 1e-9) || !(w < g.max_opening)) continue;
    const Vec3d v = (q2 - q1) / w;
    const Vec3d n1 = hits.normals.row(h0).transpose().cast<double>().normalized();
    const Vec3d n2 = hits.normals.row(h0 + 1).transpose().cast<double>().normalized();
    if (-n1.dot(v) < cos_cone || n2.dot(v) < cos_cone) continue;
    ParallelJawGrasp grasp;
    grasp.p1 = q1;
    grasp.closing = v;
    grasp.width = w;
    accepted.push_back(grasp);
    accepted_probe.push_back(k);
  }
}

/// Whether the hand of `grasp` (fingers at `opening`) collides with the object: FCL per part
/// (fingers first), unless the pre-filter's spheres prove the surfaces apart; then the parity
/// test for a part lying entirely inside the object.
bool hand_collides(const AntipodalSampler::Impl& m, const ParallelJawGrasp& grasp, double opening,
                   bool prefilter, ProbePoints& near) {
  const Pose X_OH = hand_pose(grasp, m.gripper);
  bool hit = false;
  if (!(prefilter && near.surely_clear(grasp.approach))) {
    for (int k : {1, 2, 0}) {
      const Pose X = k == 0 ? X_OH : X_OH * finger_offset(k - 1, opening);
      if ((hit = collide(*m.parts[k], X, *m.object, Pose::Identity()))) break;
    }
  }
  return hit || parts_inside(m, X_OH, opening);
}

/// The approaches of one accepted grasp `cand` (its approach is drawn here): appends the
/// collision-free ones to `kept` (at most approaches_kept) and counts the colliding ones.
void try_approaches(const AntipodalSampler::Impl& m, const AntipodalOptions& o, AntipodalGrasp cand,
                    Rng& rng, ProbePoints& near, std::vector<AntipodalGrasp>& kept,
                    std::int64_t& colliding) {
  const ParallelJawGripper& g = m.gripper;
  ParallelJawGrasp& grasp = cand.grasp;
  Vec3d e1, e2;
  detail::tangent_frame(grasp.closing, e1, e2);
  const double opening = g.collision_opening(grasp.width);
  // Box grippers: certain-collision (object point inside a box) and certain-free (every
  // triangle more than 1 um from every box) pre-filters; FCL decides the rest.
  const bool prefilter = o.check_collision && m.surface_points.rows() > 0 &&
                         o.approaches_tried > 0 && o.approaches_kept > 0;
  if (prefilter) near.build(m, g, grasp, e1, e2, opening);
  int num_kept = 0;
  // All angles are drawn even when the loop stops early, so the stream of the next probe
  // does not depend on collision outcomes.
  std::vector<double> angles(static_cast<std::size_t>(o.approaches_tried));
  for (double& t : angles) t = rng.uniform(0.0, 2.0 * M_PI);
  for (double t : angles) {
    if (num_kept >= o.approaches_kept) break;
    grasp.approach = (std::cos(t) * e1 + std::sin(t) * e2).normalized();
    if (prefilter && near.any_inside(t)) {
      ++colliding;
      continue;
    }
    if (o.check_collision && hand_collides(m, grasp, opening, prefilter, near)) {
      ++colliding;
      continue;
    }
    kept.push_back(cand);
    ++num_kept;
  }
}

}  // namespace

bool AntipodalSampler::collides(const Pose& X_OH, double opening) const {
  const Impl& m = *impl_;
  if (!X_OH.matrix().allFinite()) {
    throw_error<InvalidArgument>("AntipodalSampler::collides: X_OH must be finite");
  }
  if (!std::isfinite(opening) || opening < 0.0 || opening > m.gripper.max_opening + 1e-12) {
    throw_error<InvalidArgument>("AntipodalSampler::collides: opening must be in [0, ",
                                 m.gripper.max_opening, "] m, got ", opening);
  }
  // Fingers first: they are the parts nearest to the object.
  const std::array<Pose, 3> X = {X_OH, X_OH * finger_offset(0, opening),
                                 X_OH * finger_offset(1, opening)};
  for (int k : {1, 2, 0}) {
    if (collide(*m.parts[k], X[k], *m.object, Pose::Identity())) return true;
  }
  return part_inside_object(m, X_OH, opening);
}

bool AntipodalSampler::part_inside_object(const Impl& m, const Pose& X_OH, double opening) {
  return parts_inside(m, X_OH, opening);
}

AntipodalResult AntipodalSampler::sample(const Points3d& points, const Points3d& normals,
                                         const AntipodalOptions& o) const {
  o.validate();
  const Impl& m = *impl_;
  const Eigen::Index n = points.rows();
  check_sample_input(points, normals);
  const double cos_cone = std::cos(std::atan(o.friction_coef));
  const int P = o.probes;

  AntipodalResult out;
  out.point_score.assign(static_cast<std::size_t>(n), 0.0f);
  out.num_kept.assign(static_cast<std::size_t>(n), 0);
  std::vector<std::vector<AntipodalGrasp>> per_point(static_cast<std::size_t>(n));
  std::vector<std::int32_t> accepted_count(static_cast<std::size_t>(n), 0);
  std::vector<std::int64_t> colliding(static_cast<std::size_t>(n), 0);

  const auto process = [&](std::size_t begin, std::size_t end) {
    ProbePoints near;  // the pre-filter lists of the current probe (storage reused)
    // 1. Probes of the whole chunk, drawn per point from its own stream, cast in one batch.
    std::vector<Rng> rngs;
    const ChunkProbes probes = cast_probes(m, o, points, normals, begin, end, rngs);
    // 2. Per point: antipodal test of each probe, then approaches and collision.
    for (std::size_t i = begin; i < end; ++i) {
      std::vector<ParallelJawGrasp> accepted;
      std::vector<int> accepted_probe;
      accept_probes(probes, static_cast<Eigen::Index>(i - begin) * P, P, m.gripper, cos_cone,
                    accepted, accepted_probe);
      const float score = static_cast<float>(accepted.size()) / static_cast<float>(P);
      out.point_score[i] = score;
      accepted_count[i] = static_cast<std::int32_t>(accepted.size());
      std::vector<AntipodalGrasp>& kept = per_point[i];
      for (std::size_t j = 0; j < accepted.size(); ++j) {
        try_approaches(m, o, {accepted[j], static_cast<std::int64_t>(i), accepted_probe[j], score},
                       rngs[i - begin], near, kept, colliding[i]);
      }
      out.num_kept[i] = static_cast<std::int32_t>(kept.size());
    }
  };
  // Dynamic scheduling over blocks of points (the cost per point varies a lot with the number of
  // colliding approaches); every point's result depends only on its index.
  parallel_for_dynamic(static_cast<std::size_t>(n), o.num_threads, 32, process);

  std::size_t total = 0;
  for (const auto& v : per_point) total += v.size();
  out.grasps.reserve(total);
  for (std::size_t i = 0; i < per_point.size(); ++i) {
    out.grasps.insert(out.grasps.end(), per_point[i].begin(), per_point[i].end());
    out.num_accepted_probes += accepted_count[i];
    out.num_colliding += colliding[i];
  }
  return out;
}

AntipodalResult sample_antipodal_grasps(const Mesh& object, const Points3d& points,
                                        const Points3d& normals, const ParallelJawGripper& gripper,
                                        const AntipodalOptions& options) {
  options.validate();
  return AntipodalSampler(object, gripper).sample(points, normals, options);
}

}  // namespace mgn
