// Scene grasp labels (docs/models.md §9); the model is documented in scene_grasps.hpp.
#include <mgn/collision/collision_model.hpp>
#include <mgn/collision/point_inside.hpp>
#include <mgn/core/error.hpp>
#include <mgn/core/parallel.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/raytrace/ray_scene.hpp>
#include <mgn/scene/scene_grasps.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace mgn {

void SuctionTool::validate() const {
  auto positive = [](const char* field, double v) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      throw_error<InvalidArgument>("SuctionTool.", field, ": expected a finite value > 0 m, got ",
                                   v);
    }
  };
  positive("clearance", clearance);
  positive("shaft_radius", shaft_radius);
  positive("shaft_length", shaft_length);
}

void SceneGraspOptions::validate() const {
  if (offsets.empty()) {
    throw_error<InvalidArgument>("SceneGraspOptions.offsets: expected at least one offset (m)");
  }
  for (std::size_t k = 0; k < offsets.size(); ++k) {
    if (!(offsets[k] >= 0.0) || !std::isfinite(offsets[k])) {
      throw_error<InvalidArgument>("SceneGraspOptions.offsets[", k,
                                   "]: expected a finite distance >= 0 m, got ", offsets[k]);
    }
  }
  if (!(approach_step > 0.0) || !std::isfinite(approach_step)) {
    throw_error<InvalidArgument>(
        "SceneGraspOptions.approach_step: expected a finite value > 0 m, "
        "got ",
        approach_step);
  }
  tool.validate();
  if (!gravity_world.allFinite() || !(gravity_world.norm() > 1e-12)) {
    throw_error<InvalidArgument>(
        "SceneGraspOptions.gravity_world: expected a finite non-zero direction");
  }
  if (!(visibility_tolerance >= 0.0) || !std::isfinite(visibility_tolerance)) {
    throw_error<InvalidArgument>(
        "SceneGraspOptions.visibility_tolerance: expected a finite value >= 0 m, got ",
        visibility_tolerance);
  }
  if (!(near_plane > visibility_tolerance) || !std::isfinite(near_plane)) {
    throw_error<InvalidArgument>(
        "SceneGraspOptions.near_plane: expected a finite value > "
        "visibility_tolerance (",
        visibility_tolerance, " m), got ", near_plane);
  }
  if (num_threads < 0) {
    throw_error<InvalidArgument>("SceneGraspOptions.num_threads: expected 0 (all) or > 0, got ",
                                 num_threads);
  }
}

namespace {

using Box = Eigen::AlignedBox3d;

/// Number of directions of the discrete-orientation polytope (k-DOP) bounding each mesh.
constexpr int kDopDirections = 64;

/// kDopDirections unit vectors spread evenly over the sphere (Fibonacci lattice; fixed).
const std::array<Vec3d, kDopDirections>& dop_directions() {
  static const std::array<Vec3d, kDopDirections> dirs = [] {
    std::array<Vec3d, kDopDirections> d;
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (int k = 0; k < kDopDirections; ++k) {
      const double z = 1.0 - (2.0 * k + 1.0) / kDopDirections;
      const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
      d[static_cast<std::size_t>(k)] = Vec3d(r * std::cos(golden * k), r * std::sin(golden * k), z);
    }
    return d;
  }();
  return dirs;
}

/// A closed mesh with what the tests need: FCL model, the point-inside test, its local bounding
/// box, its k-DOP and one of its vertices (all in its own frame).
struct Solid {
  std::unique_ptr<CollisionModel> model;
  std::unique_ptr<PointInsideTest> inside;
  Box box;
  /// support[k] = max over the vertices v of dop_directions()[k] . v: the mesh (the convex hull
  /// of its vertices) lies in every half-space {x : d_k . x <= support[k]}.
  std::array<double, kDopDirections> support{};
  Vec3d vertex = Vec3d::Zero();

  explicit Solid(const Mesh& mesh) {
    model = std::make_unique<CollisionModel>(mesh);
    inside = std::make_unique<PointInsideTest>(mesh);
    const auto b = mesh.bounds();
    box = Box(b.row(0).transpose(), b.row(1).transpose());
    vertex = mesh.vertices().row(0).transpose().cast<double>();
    const auto& dirs = dop_directions();
    support.fill(-std::numeric_limits<double>::infinity());
    for (Eigen::Index v = 0; v < mesh.vertices().rows(); ++v) {
      const Vec3d p = mesh.vertices().row(v).transpose().cast<double>();
      for (int k = 0; k < kDopDirections; ++k) {
        const auto i = static_cast<std::size_t>(k);
        support[i] = std::max(support[i], dirs[i].dot(p));
      }
    }
  }

  /// Whether the box `b` (a part's local box, placed at X_SB in this solid's frame) lies
  /// entirely outside the k-DOP by more than 1 nm along one direction: then the box and the
  /// mesh neither touch nor contain one another.
  bool dop_separates(const Box& b, const Pose& X_SB) const {
    const Vec3d c = X_SB * b.center();
    const Mat3d A = X_SB.linear() * (0.5 * b.sizes()).asDiagonal();
    const auto& dirs = dop_directions();
    for (int k = 0; k < kDopDirections; ++k) {
      const auto i = static_cast<std::size_t>(k);
      const Vec3d& d = dirs[i];
      const double reach = std::abs(d.dot(A.col(0))) + std::abs(d.dot(A.col(1))) +
                           std::abs(d.dot(A.col(2))) + 1e-9 + 1e-9 * std::abs(d.dot(c));
      if (d.dot(c) - reach > support[i]) return true;
    }
    return false;
  }

  /// Whether a point (own frame) is inside the closed mesh.
  bool contains(const Vec3d& p) const { return inside->contains(p); }
};

/// World bounding box of a local box under X.
Box world_box(const Box& local, const Pose& X) {
  const Vec3d c = X * local.center();
  const Vec3d h = X.linear().cwiseAbs() * (0.5 * local.sizes());
  return Box(c - h, c + h);
}

/// Whether the boxes a (local, placed at X_WA) and b (local, placed at X_WB) are disjoint: the
/// separating-axis test of two oriented boxes (15 axes). Conservative: the extents are grown by
/// 1 nm and |R| by 1e-6 (near-parallel edge axes), so touching or nearly touching boxes are never
/// called disjoint. A cheap broad phase before FCL: a part whose box misses an obstacle's box
/// cannot touch or contain it, nor lie inside it.
bool obb_disjoint(const Box& a, const Pose& X_WA, const Box& b, const Pose& X_WB) {
  const Mat3d R = X_WA.linear().transpose() * X_WB.linear();  // axes of b in the frame of a
  const Vec3d t = X_WA.linear().transpose() * (X_WB * b.center() - X_WA * a.center());
  const Vec3d ea = (0.5 * a.sizes()).array() + 1e-9;
  const Vec3d eb = (0.5 * b.sizes()).array() + 1e-9;
  const Mat3d AR = R.cwiseAbs().array() + 1e-6;
  for (int i = 0; i < 3; ++i)
    if (std::abs(t[i]) > ea[i] + AR.row(i).dot(eb)) return true;
  for (int j = 0; j < 3; ++j)
    if (std::abs(R.col(j).dot(t)) > eb[j] + AR.col(j).dot(ea)) return true;
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      // Axis a_i x b_j.
      const double ra = ea[i1] * AR(i2, j) + ea[i2] * AR(i1, j);
      const double rb = eb[j1] * AR(i, j2) + eb[j2] * AR(i, j1);
      if (std::abs(t[i2] * R(i1, j) - t[i1] * R(i2, j)) > ra + rb) return true;
    }
  }
  return false;
}

/// Branch-free orthonormal basis with z = n (Duff et al. 2017), n unit.
Mat3d frame_z_to(const Vec3d& n) {
  const double sign = std::copysign(1.0, n.z());
  const double a = -1.0 / (sign + n.z());
  const double b = n.x() * n.y() * a;
  Mat3d R;
  R.col(0) = Vec3d(1.0 + sign * n.x() * n.x() * a, sign * b, -sign * n.x());
  R.col(1) = Vec3d(b, sign + n.y() * n.y() * a, -n.y());
  R.col(2) = n;
  return R;
}

void check_pose(const Pose& X, const char* what, std::size_t index) {
  const Mat4d& M = X.matrix();
  const Mat3d R = X.linear();
  if (!M.allFinite() || (R.transpose() * R - Mat3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
      R.determinant() < 0.0 ||
      (M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-9) {
    throw_error<InvalidArgument>("SceneGraspModel: ", what, " ", index,
                                 " must be a finite rigid transform (orthonormal right-handed "
                                 "rotation)");
  }
}

Pose back_off(const Pose& X, double d) {
  Pose Y = X;
  Y.translation() -= d * X.linear().col(2);
  return Y;
}

}  // namespace

struct SceneGraspModel::Impl {
  SceneGraspOptions options;
  ParallelJawGripper gripper;
  Cup cup;
  // Objects 0..N-1, then the tote; instances of the same mesh share one Solid.
  std::vector<std::shared_ptr<const Solid>> obstacles;
  std::vector<Pose> X_W_obstacle;
  std::vector<Pose> X_obstacle_W;
  std::vector<Box> obstacle_box;               // world
  std::vector<Vec3d> obstacle_vertex;          // world
  std::array<std::unique_ptr<Solid>, 3> hand;  // palm, left finger, right finger (opening 0)
  std::array<std::unique_ptr<Solid>, 2> tool;  // cup body, shaft (contact frame)
  std::unique_ptr<RayScene> scene;             // everything, for visibility
  PlacedGrasps pj, suction;
  std::size_t num_objects = 0;
  std::unique_ptr<Solid> floor;  // tote frame slab below the inner floor surface (z < 0)
  Pose X_W_floor = Pose::Identity();

  /// Why a part at X_WP hit obstacle j (the grasped object: own).
  std::uint8_t obstacle_code(const Solid& part, const Pose& X_WP, std::size_t j,
                             std::int64_t own) const {
    if (j < num_objects) {
      return static_cast<std::uint8_t>(static_cast<std::int64_t>(j) == own
                                           ? CollisionObstacle::GraspedObject
                                           : CollisionObstacle::OtherObject);
    }
    return static_cast<std::uint8_t>(collide(*part.model, X_WP, *floor->model, X_W_floor)
                                         ? CollisionObstacle::Floor
                                         : CollisionObstacle::Wall);
  }

  /// The tool poses checked on the path of segment k: offsets[0] for k = 0, else the poses at
  /// most approach_step apart after offsets[k-1] up to offsets[k].
  std::vector<double> segment(std::size_t k) const {
    const std::vector<double>& off = options.offsets;
    if (k == 0) return {off[0]};
    const double a = off[k - 1], b = off[k];
    const auto n =
        static_cast<int>(std::max(1.0, std::ceil(std::abs(b - a) / options.approach_step)));
    std::vector<double> d(static_cast<std::size_t>(n));
    for (int i = 1; i <= n; ++i) d[static_cast<std::size_t>(i - 1)] = a + (b - a) * i / n;
    return d;
  }

  /// Collision of one part (at X_WP, world box pb) with obstacle j.
  bool part_hits(const Solid& part, const Pose& X_WP, const Box& pb, std::size_t j) const {
    const Box& ob = obstacle_box[j];
    if (!pb.intersects(ob)) return false;
    const Solid& obs = *obstacles[j];
    // Their oriented boxes: most pairs whose world boxes overlap are told apart here, without
    // a call into FCL.
    if (obb_disjoint(part.box, X_WP, obs.box, X_W_obstacle[j])) return false;
    // The part's box outside the object's k-DOP (a tighter convex bound than its box; not for
    // the tote, whose hollow lies inside its k-DOP).
    if (j < num_objects && obs.dop_separates(part.box, X_obstacle_W[j] * X_WP)) return false;
    if (collide(*part.model, X_WP, *obs.model, X_W_obstacle[j])) return true;
    // No surface contact: a part inside the obstacle or the obstacle inside the part.
    if (ob.contains(pb) && obs.contains(X_obstacle_W[j] * (X_WP * part.vertex))) return true;
    if (pb.contains(ob) && part.contains(X_WP.inverse() * obstacle_vertex[j])) return true;
    return false;
  }

  /// First obstacle hit by the parts at their poses (-1 none, 0 tote, i + 1 object i); the
  /// part index and obstacle index go to *part / *obstacle when hit.
  template <std::size_t P>
  std::int32_t first_hit(const std::array<const Solid*, P>& parts, const std::array<Pose, P>& poses,
                         std::int64_t skip, std::size_t* part = nullptr,
                         std::size_t* obstacle = nullptr) const {
    std::array<Box, P> boxes;
    for (std::size_t k = 0; k < P; ++k) boxes[k] = world_box(parts[k]->box, poses[k]);
    for (std::size_t j = 0; j < obstacles.size(); ++j) {
      if (static_cast<std::int64_t>(j) == skip) continue;
      for (std::size_t k = 0; k < P; ++k) {
        if (part_hits(*parts[k], poses[k], boxes[k], j)) {
          if (part) *part = k;
          if (obstacle) *obstacle = j;
          return j == num_objects ? 0 : static_cast<std::int32_t>(j + 1);
        }
      }
    }
    return -1;
  }

  /// Parallel-jaw hand at X_WH with the fingers at `opening`, at every offset: writes the first
  /// hit per offset into hit[0..K) and returns whether any offset collides. The object `own`
  /// (0-based, -1 none) is skipped at offset 0 exactly unless `check_own_at_grasp`.
  /// With `first_only`, the offsets after the first colliding one are not checked (their hit
  /// is kHitNotChecked).
  bool pj_hits(const Pose& X_WH, double opening, std::int64_t own, bool check_own_at_grasp,
               std::int32_t* hit, std::uint8_t* why_part = nullptr,
               std::uint8_t* why_obstacle = nullptr, bool first_only = false) const {
    const std::array<const Solid*, 3> parts = {hand[1].get(), hand[2].get(), hand[0].get()};
    bool any = false;
    for (std::size_t k = 0; k < options.offsets.size(); ++k) {
      if (any && first_only) {
        hit[k] = kHitNotChecked;
        continue;
      }
      hit[k] = -1;
      for (const double d : segment(k)) {
        const Pose X = back_off(X_WH, d);
        const std::array<Pose, 3> poses = {X * finger_offset(0, opening),
                                           X * finger_offset(1, opening), X};
        std::size_t pi = 0, oj = 0;
        hit[k] = first_hit(parts, poses, d == 0.0 && !check_own_at_grasp ? own : -1, &pi, &oj);
        if (hit[k] < 0) continue;
        if (!any && why_part) {
          *why_part =
              static_cast<std::uint8_t>(pi == 2 ? CollisionPart::Palm : CollisionPart::Finger);
          *why_obstacle = obstacle_code(*parts[pi], poses[pi], oj, own);
        }
        any = true;
        break;
      }
    }
    return any;
  }

  /// Suction tool (cup body and shaft) at the contact frame X_WS, at every offset, against
  /// every obstacle: as pj_hits.
  bool suction_hits(const Pose& X_WS, std::int32_t* hit, std::int64_t own = -1,
                    std::uint8_t* why_part = nullptr, std::uint8_t* why_obstacle = nullptr,
                    bool first_only = false) const {
    const std::array<const Solid*, 2> parts = {tool[0].get(), tool[1].get()};
    bool any = false;
    for (std::size_t k = 0; k < options.offsets.size(); ++k) {
      if (any && first_only) {
        hit[k] = kHitNotChecked;
        continue;
      }
      hit[k] = -1;
      for (const double d : segment(k)) {
        const Pose X = back_off(X_WS, d);
        std::size_t pi = 0, oj = 0;
        hit[k] = first_hit(parts, std::array<Pose, 2>{X, X}, -1, &pi, &oj);
        if (hit[k] < 0) continue;
        if (!any && why_part) {
          *why_part =
              static_cast<std::uint8_t>(pi == 0 ? CollisionPart::Cup : CollisionPart::Shaft);
          *why_obstacle = obstacle_code(*parts[pi], X, oj, own);
        }
        any = true;
        break;
      }
    }
    return any;
  }

  /// The obstacles (objects 0..N-1, then the tote) and the visibility scene. A scene often
  /// holds several instances of one object: their meshes (same vertices and faces, object
  /// frame) share one Solid, so its BVHs are built once. The distinct Solids are built in
  /// parallel (each build is independent and deterministic).
  void build_obstacles(const std::vector<SceneGraspObject>& objects, const Mesh& tote,
                       const Pose& X_WT) {
    const std::size_t N = objects.size();
    auto mesh_of = [&](std::size_t i) -> const Mesh& { return i < N ? *objects[i].mesh : tote; };
    auto same_mesh = [](const Mesh& a, const Mesh& b) {
      return &a == &b ||
             (a.vertices().rows() == b.vertices().rows() && a.faces().rows() == b.faces().rows() &&
              a.vertices() == b.vertices() && a.faces() == b.faces());
    };
    std::vector<std::size_t> first_of(N + 1);  // obstacle i uses the Solid of obstacle first_of[i]
    std::vector<std::size_t> distinct;
    for (std::size_t i = 0; i <= N; ++i) {
      first_of[i] = i;
      for (const std::size_t d : distinct) {
        if (same_mesh(mesh_of(i), mesh_of(d))) {
          first_of[i] = d;
          break;
        }
      }
      if (first_of[i] == i) distinct.push_back(i);
    }
    std::vector<std::shared_ptr<const Solid>> solids(N + 1);
    parallel_for(distinct.size(), resolve_num_threads(options.num_threads), 1,
                 [&](std::size_t begin, std::size_t end) {
                   for (std::size_t k = begin; k < end; ++k)
                     solids[distinct[k]] = std::make_shared<const Solid>(mesh_of(distinct[k]));
                 });
    std::vector<RayGeometry> geoms;
    for (std::size_t i = 0; i <= N; ++i) {
      const Mesh& mesh = mesh_of(i);
      const Pose X = i < N ? objects[i].X_WO : X_WT;
      obstacles.push_back(solids[first_of[i]]);
      X_W_obstacle.push_back(X);
      X_obstacle_W.push_back(X.inverse());
      obstacle_box.push_back(world_box(obstacles.back()->box, X));
      obstacle_vertex.push_back(X * obstacles.back()->vertex);
      geoms.push_back({&mesh, X, static_cast<std::int32_t>(i < N ? i + 1 : 0)});
    }
    scene = std::make_unique<RayScene>(geoms);
  }

  /// The floor slab: the tote's footprint below its inner floor surface (z < 0, tote frame).
  void build_floor(const Mesh& tote, const Pose& X_WT) {
    const auto b = tote.bounds();
    const double depth = std::max(0.01, -b(0, 2) + 0.01);
    const Vec3d size(b(1, 0) - b(0, 0) + 0.02, b(1, 1) - b(0, 1) + 0.02, depth);
    Pose X = Pose::Identity();
    X.translation() = Vec3d(0.5 * (b(0, 0) + b(1, 0)), 0.5 * (b(0, 1) + b(1, 1)), -0.5 * depth);
    floor = std::make_unique<Solid>(make_box(size).transformed(X));
    X_W_floor = X_WT;
  }

  /// The parallel-jaw hand (opening 0) and the suction tool (contact frame).
  void build_tools() {
    const GripperMeshes gm = gripper_meshes(gripper, 0.0);
    hand[0] = std::make_unique<Solid>(gm.palm);
    hand[1] = std::make_unique<Solid>(gm.finger_left);
    hand[2] = std::make_unique<Solid>(gm.finger_right);
    const SuctionTool& t = options.tool;
    const double body = cup.body_height - t.clearance;
    if (!(body > 0.0)) {
      throw_error<InvalidArgument>("SceneGraspModel: cup.body_height (", cup.body_height,
                                   " m) must exceed tool.clearance (", t.clearance, " m)");
    }
    // Contact frame: z into the surface, so the tool lies at z < 0.
    Pose X = Pose::Identity();
    X.translation() = Vec3d(0, 0, -(t.clearance + 0.5 * body));
    tool[0] = std::make_unique<Solid>(make_cylinder(cup.outer_radius, body, 32).transformed(X));
    X.translation() = Vec3d(0, 0, -(cup.body_height + 0.5 * t.shaft_length));
    tool[1] =
        std::make_unique<Solid>(make_cylinder(t.shaft_radius, t.shaft_length, 32).transformed(X));
  }

  /// Rows for n grasps, every score NaN, no collision.
  void allocate(PlacedGrasps& p, std::size_t n) const {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const std::size_t K = options.offsets.size();
    p.X_W_tool.resize(n);
    p.X_W_contact.resize(n);
    p.contacts.resize(static_cast<Eigen::Index>(n), 3);
    p.second_contacts.resize(static_cast<Eigen::Index>(n), 3);
    p.width.assign(n, 0.0f);
    p.score_analytical.assign(n, nan);
    p.score_simulation.assign(n, nan);
    p.score_wrench.assign(n, nan);
    p.object_index.assign(n, 0);
    p.colliding.assign(n, 0);
    p.hit.assign(n * K, -1);
    p.collision_part.assign(n, 0);
    p.collision_obstacle.assign(n, 0);
  }

  /// The parallel-jaw grasps of object i (gravity g_O in its frame) from row `row` on.
  void place_pj(const SceneGraspObject& o, std::size_t i, const Vec3d& g_O, std::size_t& row) {
    if (o.pj.empty()) return;
    const std::vector<float> wrench = pj_wrench_scores(o.pj, o.mass, o.com, g_O, options.pj_wrench);
    for (std::size_t g = 0; g < o.pj.size(); ++g, ++row) {
      const ParallelJawGrasp& gr = o.pj[g];
      const auto r = static_cast<Eigen::Index>(row);
      pj.X_W_tool[row] = o.X_WO * hand_pose(gr, gripper);
      Pose X_OG = Pose::Identity();
      X_OG.linear() = grasp_rotation(gr);
      X_OG.translation() = gr.p1;
      pj.X_W_contact[row] = o.X_WO * X_OG;
      pj.contacts.row(r) = (o.X_WO * gr.p1).transpose();
      pj.second_contacts.row(r) = (o.X_WO * (gr.p1 + gr.width * gr.closing)).transpose();
      pj.width[row] = static_cast<float>(gr.width);
      if (!o.pj_score_analytical.empty()) pj.score_analytical[row] = o.pj_score_analytical[g];
      if (!o.pj_score_simulation.empty()) pj.score_simulation[row] = o.pj_score_simulation[g];
      pj.score_wrench[row] = wrench[g];
      pj.object_index[row] = static_cast<std::int32_t>(i);
    }
  }

  /// The suction grasps of object i (gravity g_O in its frame) from row `row` on.
  void place_suction(const SceneGraspObject& o, std::size_t i, const Vec3d& g_O, std::size_t& row) {
    const auto Ks = static_cast<std::size_t>(o.suction_points.rows());
    if (Ks == 0) return;
    PlacedGrasps& su = suction;
    const std::vector<float> wrench =
        suction_wrench_scores(o.suction_points, o.suction_approach, o.mass, o.com, g_O, cup.radius,
                              options.suction_wrench);
    for (std::size_t g = 0; g < Ks; ++g, ++row) {
      const auto s = static_cast<Eigen::Index>(g);
      const auto r = static_cast<Eigen::Index>(row);
      const Vec3d c_W = o.X_WO * o.suction_points.row(s).transpose().cast<double>();
      const Vec3d a_W =
          (o.X_WO.linear() * o.suction_approach.row(s).transpose().cast<double>()).normalized();
      Pose X_WS = Pose::Identity();
      X_WS.linear() = frame_z_to(a_W);
      X_WS.translation() = c_W;
      su.X_W_contact[row] = X_WS;
      su.X_W_tool[row] = back_off(X_WS, kSuctionToolOffset);
      su.contacts.row(r) = c_W.transpose();
      su.second_contacts.row(r) = c_W.transpose();
      if (!o.suction_score_analytical.empty())
        su.score_analytical[row] = o.suction_score_analytical[g];
      if (!o.suction_score_simulation.empty())
        su.score_simulation[row] = o.suction_score_simulation[g];
      su.score_wrench[row] = wrench[g];
      su.object_index[row] = static_cast<std::int32_t>(i);
    }
  }

  /// Collisions of every placed grasp (parallel over grasps; each result depends only on its
  /// row).
  void test_collisions() {
    const std::size_t K = options.offsets.size();
    const int threads = resolve_num_threads(options.num_threads);
    PlacedGrasps& su = suction;
    parallel_for(pj.width.size(), threads, 64, [&](std::size_t begin, std::size_t end) {
      for (std::size_t r = begin; r < end; ++r) {
        const double opening = gripper.collision_opening(pj.width[r]);
        const auto own = static_cast<std::int64_t>(pj.object_index[r]);
        pj.colliding[r] =
            pj_hits(pj.X_W_tool[r], opening, own, false, &pj.hit[r * K], &pj.collision_part[r],
                    &pj.collision_obstacle[r], options.first_collision_only)
                ? 1
                : 0;
      }
    });
    parallel_for(su.width.size(), threads, 64, [&](std::size_t begin, std::size_t end) {
      for (std::size_t r = begin; r < end; ++r) {
        su.colliding[r] =
            suction_hits(su.X_W_contact[r], &su.hit[r * K],
                         static_cast<std::int64_t>(su.object_index[r]), &su.collision_part[r],
                         &su.collision_obstacle[r], options.first_collision_only)
                ? 1
                : 0;
      }
    });
  }
};

namespace {

/// Checks every object and grasp of the scene (before the parallel work); returns the numbers
/// of parallel-jaw and suction grasps.
std::pair<std::size_t, std::size_t> check_objects(const std::vector<SceneGraspObject>& objects,
                                                  const ParallelJawGripper& gripper) {
  std::size_t num_pj = 0, num_suction = 0;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const SceneGraspObject& o = objects[i];
    if (o.mesh == nullptr)
      throw_error<InvalidArgument>("SceneGraspModel: object ", i, " has no mesh");
    require_non_empty(*o.mesh, "SceneGraspModel object mesh");
    check_pose(o.X_WO, "X_WO of object", i);
    if (!(o.mass > 0.0) || !std::isfinite(o.mass)) {
      throw_error<InvalidArgument>("SceneGraspModel: object ", i,
                                   " mass must be a finite value > 0 kg, got ", o.mass);
    }
    if (!o.com.allFinite())
      throw_error<InvalidArgument>("SceneGraspModel: object ", i, " com must be finite");
    const std::size_t M = o.pj.size();
    for (std::size_t g = 0; g < M; ++g) {
      const ParallelJawGrasp& gr = o.pj[g];
      if (!gr.p1.allFinite() || !std::isfinite(gr.width) || gr.width < 0.0 ||
          gr.width > gripper.max_opening + 1e-9) {
        throw_error<InvalidArgument>("SceneGraspModel: object ", i, " parallel-jaw grasp ", g,
                                     ": p1 must be finite and width in [0, max_opening = ",
                                     gripper.max_opening, "] m, got width ", gr.width);
      }
      try {
        grasp_rotation(gr);
      } catch (const InvalidArgument& e) {
        throw_error<InvalidArgument>("SceneGraspModel: object ", i, " parallel-jaw grasp ", g, ": ",
                                     e.what());
      }
    }
    auto check_len = [&](const std::vector<float>& v, std::size_t n, const char* name) {
      if (!v.empty() && v.size() != n) {
        throw_error<InvalidArgument>("SceneGraspModel: object ", i, " ", name, " has ", v.size(),
                                     " entries; expected ", n, " (one per grasp) or none");
      }
    };
    check_len(o.pj_score_analytical, M, "pj_score_analytical");
    check_len(o.pj_score_simulation, M, "pj_score_simulation");
    const auto K = static_cast<std::size_t>(o.suction_points.rows());
    if (o.suction_approach.rows() != o.suction_points.rows()) {
      throw_error<InvalidArgument>("SceneGraspModel: object ", i, " has ", K,
                                   " suction points but ", o.suction_approach.rows(),
                                   " approach directions; expected one per point");
    }
    for (std::size_t g = 0; g < K; ++g) {
      const auto r = static_cast<Eigen::Index>(g);
      if (!o.suction_points.row(r).allFinite() || !o.suction_approach.row(r).allFinite() ||
          !(o.suction_approach.row(r).norm() > 1e-6f)) {
        throw_error<InvalidArgument>("SceneGraspModel: object ", i, " suction grasp ", g,
                                     " has a non-finite point or approach, or a zero approach");
      }
    }
    check_len(o.suction_score_analytical, K, "suction_score_analytical");
    check_len(o.suction_score_simulation, K, "suction_score_simulation");
    num_pj += M;
    num_suction += K;
  }
  return {num_pj, num_suction};
}

}  // namespace

SceneGraspModel::SceneGraspModel(const std::vector<SceneGraspObject>& objects, const Mesh& tote,
                                 const Pose& X_WT, const ParallelJawGripper& gripper,
                                 const Cup& cup, const SceneGraspOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  options.validate();
  gripper.validate();
  cup.validate();
  if (objects.empty()) {
    throw_error<InvalidArgument>(
        "SceneGraspModel: the scene has no objects; expected at least one");
  }
  require_non_empty(tote, "SceneGraspModel tote");
  check_pose(X_WT, "X_WT (tote)", 0);
  m.options = options;
  m.gripper = gripper;
  m.cup = cup;
  m.num_objects = objects.size();
  const auto [num_pj, num_suction] = check_objects(objects, gripper);
  m.build_obstacles(objects, tote, X_WT);
  m.build_floor(tote, X_WT);
  m.build_tools();
  // Placement and wrench scores (serial: cheap), object by object.
  m.allocate(m.pj, num_pj);
  m.allocate(m.suction, num_suction);
  const Vec3d g_W = options.gravity_world.normalized();
  std::size_t row_pj = 0, row_su = 0;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const SceneGraspObject& o = objects[i];
    const Vec3d g_O = o.X_WO.linear().transpose() * g_W;
    m.place_pj(o, i, g_O, row_pj);
    m.place_suction(o, i, g_O, row_su);
  }
  m.test_collisions();
}

SceneGraspModel::~SceneGraspModel() = default;

std::size_t SceneGraspModel::num_objects() const { return impl_->num_objects; }
const SceneGraspOptions& SceneGraspModel::options() const { return impl_->options; }
const PlacedGrasps& SceneGraspModel::pj() const { return impl_->pj; }
const PlacedGrasps& SceneGraspModel::suction() const { return impl_->suction; }

ToolCollisions SceneGraspModel::collides(GraspKind kind, const std::vector<Pose>& X_W_contact,
                                         const std::vector<double>& width,
                                         const std::vector<std::int32_t>& target_object,
                                         bool check_target_at_grasp) const {
  const Impl& m = *impl_;
  const bool pj = kind == GraspKind::ParallelJaw;
  if (!pj && kind != GraspKind::Suction) {
    throw_error<InvalidArgument>(
        "SceneGraspModel::collides: kind must be ParallelJaw (0) or "
        "Suction (1), got ",
        static_cast<int>(kind));
  }
  const std::size_t n = X_W_contact.size();
  if (target_object.size() != n || (pj && width.size() != n) ||
      (!pj && !width.empty() && width.size() != n)) {
    throw_error<InvalidArgument>("SceneGraspModel::collides: ", n, " poses but ", width.size(),
                                 " widths and ", target_object.size(),
                                 " target objects; expected one of each per pose (widths may be "
                                 "empty for suction)");
  }
  for (std::size_t i = 0; i < n; ++i) {
    check_pose(X_W_contact[i], "collides: X_W_contact", i);
    const std::int32_t t = target_object[i];
    if (t < -1 || t >= static_cast<std::int32_t>(m.num_objects)) {
      throw_error<InvalidArgument>("SceneGraspModel::collides: target_object[", i, "] = ", t,
                                   "; expected -1 (none) or an object index in [0, ", m.num_objects,
                                   ")");
    }
    if (pj &&
        (!std::isfinite(width[i]) || width[i] < 0.0 || width[i] > m.gripper.max_opening + 1e-9)) {
      throw_error<InvalidArgument>(
          "SceneGraspModel::collides: width[", i, "] = ", width[i],
          " m; expected a finite width in [0, max_opening = ", m.gripper.max_opening, "] m");
    }
  }
  const std::size_t K = m.options.offsets.size();
  ToolCollisions out;
  out.colliding.assign(n, 0);
  out.hit.assign(n * K, -1);
  const double depth = m.gripper.grasp_depth();
  parallel_for(n, resolve_num_threads(m.options.num_threads), 16,
               [&](std::size_t begin, std::size_t end) {
                 for (std::size_t r = begin; r < end; ++r) {
                   bool c = false;
                   if (pj) {
                     // The hand of gripper.hpp: X_GH = (I, (w/2) x - grasp_depth z).
                     const double w = std::min(width[r], m.gripper.max_opening);
                     Pose X_WH = X_W_contact[r];
                     X_WH.translation() += X_W_contact[r].linear() * Vec3d(0.5 * w, 0.0, -depth);
                     c = m.pj_hits(X_WH, m.gripper.collision_opening(w), target_object[r],
                                   check_target_at_grasp, &out.hit[r * K]);
                   } else {
                     c = m.suction_hits(X_W_contact[r], &out.hit[r * K]);
                   }
                   out.colliding[r] = c ? 1 : 0;
                 }
               });
  return out;
}

std::vector<std::uint8_t> SceneGraspModel::visible(const CameraView& view,
                                                   const Points3d& points) const {
  view.validate("SceneGraspModel::visible view");
  const Impl& m = *impl_;
  const SceneGraspOptions& o = m.options;
  const Eigen::Index n = points.rows();
  std::vector<std::uint8_t> out(static_cast<std::size_t>(n), 0);
  const Pose X_CW = view.X_WC.inverse();
  const Vec3d eye = view.X_WC.translation();
  // Candidates in front of the camera and inside the image, ordered by 16 x 16 pixel tile
  // (counting sort: linear, deterministic) so that neighbouring rays travel in packets.
  constexpr int kTile = 16;
  const int tiles_x = (view.K.width + kTile - 1) / kTile;
  const int tiles_y = (view.K.height + kTile - 1) / kTile;
  std::vector<Eigen::Index> cand;
  std::vector<std::int32_t> tile;
  cand.reserve(static_cast<std::size_t>(n));
  tile.reserve(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    const Vec3d p = points.row(i).transpose();
    if (!p.allFinite()) {
      throw_error<InvalidArgument>("SceneGraspModel::visible: point ", i, " is not finite");
    }
    const Vec3d q = X_CW * p;
    if (!(q.z() > o.near_plane)) continue;
    const double u = view.K.fx * q.x() / q.z() + view.K.cx;
    const double v = view.K.fy * q.y() / q.z() + view.K.cy;
    if (!(u >= 0.0 && u < view.K.width && v >= 0.0 && v < view.K.height)) continue;
    cand.push_back(i);
    tile.push_back(static_cast<std::int32_t>(static_cast<int>(v) / kTile * tiles_x +
                                             static_cast<int>(u) / kTile));
  }
  std::vector<std::int64_t> start(static_cast<std::size_t>(tiles_x) * tiles_y + 1, 0);
  for (const std::int32_t t : tile) ++start[static_cast<std::size_t>(t) + 1];
  for (std::size_t t = 1; t < start.size(); ++t) start[t] += start[t - 1];
  std::vector<Eigen::Index> order(cand.size());
  for (std::size_t j = 0; j < cand.size(); ++j) order[start[tile[j]]++] = cand[j];
  // Each ray is shortened so that a hit anywhere in [0, 1] is closer than (distance - tolerance).
  const auto c = static_cast<Eigen::Index>(order.size());
  Points3f origins(c, 3), directions(c, 3);
  for (Eigen::Index j = 0; j < c; ++j) {
    const Vec3d d = points.row(order[j]).transpose() - eye;
    const double dist = d.norm();
    origins.row(j) = eye.cast<float>().transpose();
    directions.row(j) = (d * ((dist - o.visibility_tolerance) / dist)).cast<float>().transpose();
  }
  CastOptions cast;
  cast.tnear = 0.0f;
  cast.tfar = 1.0f;
  cast.coherent = true;
  cast.num_threads = o.num_threads;
  const std::vector<std::uint8_t> blocked = m.scene->occluded(origins, directions, cast);
  for (Eigen::Index j = 0; j < c; ++j) out[order[j]] = blocked[j] ? 0 : 1;
  return out;
}

ViewGrasps SceneGraspModel::view_grasps(const CameraView& view,
                                        const std::vector<std::uint8_t>& seen) const {
  const Impl& m = *impl_;
  if (seen.size() != m.num_objects) {
    throw_error<InvalidArgument>("SceneGraspModel::view_grasps: seen has ", seen.size(),
                                 " entries; expected one per object (", m.num_objects, ")");
  }
  view.validate("SceneGraspModel::view_grasps view");
  const Pose X_CW = view.X_WC.inverse();
  ViewGrasps out;
  // Parallel-jaw: the grasps of seen objects with p1 or p2 visible.
  {
    const PlacedGrasps& p = m.pj;
    std::vector<std::int64_t> cand;
    for (std::size_t r = 0; r < p.size(); ++r)
      if (seen[static_cast<std::size_t>(p.object_index[r])])
        cand.push_back(static_cast<std::int64_t>(r));
    // p1 first; p2 only where p1 is not visible.
    const auto c = static_cast<Eigen::Index>(cand.size());
    Points3d pts(c, 3);
    for (Eigen::Index j = 0; j < c; ++j) pts.row(j) = p.contacts.row(cand[j]);
    std::vector<std::uint8_t> vis = visible(view, pts);
    std::vector<Eigen::Index> second;
    for (Eigen::Index j = 0; j < c; ++j)
      if (!vis[j]) second.push_back(j);
    Points3d pts2(static_cast<Eigen::Index>(second.size()), 3);
    for (std::size_t k = 0; k < second.size(); ++k)
      pts2.row(static_cast<Eigen::Index>(k)) = p.second_contacts.row(cand[second[k]]);
    const std::vector<std::uint8_t> vis2 = visible(view, pts2);
    for (std::size_t k = 0; k < second.size(); ++k) vis[second[k]] = vis2[k];
    for (Eigen::Index j = 0; j < c; ++j) {
      if (!vis[j]) continue;
      const auto r = static_cast<std::size_t>(cand[j]);
      out.pj_index.push_back(cand[j]);
      out.pj_X_C_tool.push_back(X_CW * p.X_W_tool[r]);
      out.pj_X_C_contact.push_back(X_CW * p.X_W_contact[r]);
    }
  }
  {
    const PlacedGrasps& p = m.suction;
    std::vector<std::int64_t> cand;
    for (std::size_t r = 0; r < p.size(); ++r)
      if (seen[static_cast<std::size_t>(p.object_index[r])])
        cand.push_back(static_cast<std::int64_t>(r));
    const auto c = static_cast<Eigen::Index>(cand.size());
    Points3d pts(c, 3);
    for (Eigen::Index j = 0; j < c; ++j) pts.row(j) = p.contacts.row(cand[j]);
    const std::vector<std::uint8_t> vis = visible(view, pts);
    for (Eigen::Index j = 0; j < c; ++j) {
      if (!vis[j]) continue;
      const auto r = static_cast<std::size_t>(cand[j]);
      out.suction_index.push_back(cand[j]);
      out.suction_X_C_tool.push_back(X_CW * p.X_W_tool[r]);
      out.suction_X_C_contact.push_back(X_CW * p.X_W_contact[r]);
    }
  }
  return out;
}

}  // namespace mgn
