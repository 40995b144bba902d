#include <mgn/core/error.hpp>
#include <mgn/core/parallel.hpp>
#include <mgn/raytrace/ray_scene.hpp>
#include <mgn/scene/view_labels.hpp>

#include "raytrace/ray_scene_impl.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace mgn {

namespace {

constexpr const char* kModel = "ViewLabelModel";
constexpr const char* kLabel = "ViewLabelModel::label_view";
/// Rays per tile of the amodal pass (one tile = one object, a band of rows of its box).
constexpr long kTileRays = 2048;

void check_rigid(const Pose& X, const std::string& what) {
  if (!X.matrix().allFinite()) throw_error<InvalidArgument>(what, ": pose has non-finite entries");
  const Mat3d R = X.linear();
  const double orth = (R.transpose() * R - Mat3d::Identity()).cwiseAbs().maxCoeff();
  const Eigen::RowVector4d last = X.matrix().row(3);
  if (orth > 1e-6 || R.determinant() < 0.0 || (last - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 0) {
    throw_error<InvalidArgument>(what,
                                 ": pose must be rigid (orthonormal right-handed rotation, last "
                                 "row 0 0 0 1); rotation error ",
                                 orth, ", det ", R.determinant());
  }
}

/// Inclusive pixel rectangle.
struct PixelBox {
  int u0 = 0, v0 = 0, u1 = -1, v1 = -1;
  bool empty() const { return u1 < u0 || v1 < v0; }
};

/// Direction of the ray through the centre of pixel (u, v), world frame, exactly as camera_rays.
inline Eigen::RowVector3f pixel_direction(const Mat3d& R, const Intrinsics& K, int u, int v) {
  const Vec3d d_C((u + 0.5 - K.cx) / K.fx, (v + 0.5 - K.cy) / K.fy, 1.0);
  return (R * d_C.normalized()).cast<float>().transpose();
}

/// COCO [x, y, w, h] of an inclusive pixel rectangle (zeros when empty).
Eigen::Matrix<std::int32_t, 1, 4> coco_box(const PixelBox& b) {
  Eigen::Matrix<std::int32_t, 1, 4> out;
  if (b.empty()) {
    out.setZero();
  } else {
    out << b.u0, b.v0, b.u1 - b.u0 + 1, b.v1 - b.v0 + 1;
  }
  return out;
}

/// Convex hull of 2-D points, counter-clockwise (Andrew's monotone chain); the points if < 3.
std::vector<Eigen::Vector2d> convex_hull(std::vector<Eigen::Vector2d> pts) {
  std::sort(pts.begin(), pts.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return pts;
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2d> h(2 * pts.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
    h[k++] = pts[i];
  }
  for (std::size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
    h[k++] = pts[i];
  }
  h.resize(k - 1);
  return h;
}

/// Widens [xl, xr] by where the horizontal line at height y crosses the convex polygon `hull`.
void hull_row(const std::vector<Eigen::Vector2d>& hull, double y, double& xl, double& xr) {
  for (std::size_t j = 0; j < hull.size(); ++j) {
    const Eigen::Vector2d& a = hull[j];
    const Eigen::Vector2d& b = hull[(j + 1) % hull.size()];
    if (y < std::min(a.y(), b.y()) || y > std::max(a.y(), b.y())) continue;
    if (a.y() == b.y()) {
      xl = std::min({xl, a.x(), b.x()});
      xr = std::max({xr, a.x(), b.x()});
    } else {
      const double x = a.x() + (y - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      xl = std::min(xl, x);
      xr = std::max(xr, x);
    }
  }
}

}  // namespace

struct ViewLabelModel::Impl {
  struct Object {
    std::unique_ptr<RayScene> alone;  // this object only (amodal pass)
    Points3d vertices_W;              // for the projected box
    Pose X_WO;
    std::int32_t category_id = 0;
    Keypoints4d keypoints_W;   // [id, x, y, z] world
    Keypoints4d com_points_W;  // [score, x, y, z] world
    Vec3d com_W;
    double d_min = 0.0, d_max = 0.0;
  };
  std::vector<Object> objects;
  std::unique_ptr<RayScene> all;  // all objects (ids 1..N) and the tote (id 0)
  bool tote = false;
};

ViewLabelModel::ViewLabelModel(const std::vector<ViewLabelObject>& objects, const Mesh* tote,
                               const Pose& X_W_tote)
    : impl_(std::make_unique<Impl>()) {
  if (objects.empty()) {
    throw_error<InvalidArgument>(kModel, ": no objects given; expected at least one object");
  }
  std::vector<RayGeometry> all;
  impl_->objects.resize(objects.size());
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const ViewLabelObject& in = objects[i];
    const std::string what = std::string(kModel) + ": object " + std::to_string(i);
    if (in.mesh == nullptr) throw_error<InvalidArgument>(what, " has no mesh");
    require_non_empty(*in.mesh, what);
    check_rigid(in.X_WO, what + " X_WO");
    if (in.category_id < 1) {
      throw_error<InvalidArgument>(what, " has category id ", in.category_id, "; expected >= 1");
    }
    if (!in.keypoints.allFinite() || !in.com_points.allFinite() || !in.com_O.allFinite()) {
      throw_error<InvalidArgument>(what, " has non-finite keypoints, CoM points or CoM");
    }
    Impl::Object& o = impl_->objects[i];
    o.X_WO = in.X_WO;
    o.category_id = in.category_id;
    RayGeometry g;
    g.mesh = in.mesh;
    g.X_WO = in.X_WO;
    g.instance_id = static_cast<std::int32_t>(i + 1);
    o.alone = std::make_unique<RayScene>(std::vector<RayGeometry>{g});
    all.push_back(g);
    const Mat3d R = in.X_WO.linear();
    const Vec3d t = in.X_WO.translation();
    o.vertices_W = (in.mesh->vertices().cast<double>() * R.transpose()).rowwise() + t.transpose();
    auto to_world = [&](const Keypoints4d& k) {
      Keypoints4d w(k.rows(), 4);
      w.col(0) = k.col(0);
      w.rightCols<3>() = (k.rightCols<3>() * R.transpose()).rowwise() + t.transpose();
      return w;
    };
    o.keypoints_W = to_world(in.keypoints);
    o.com_points_W = to_world(in.com_points);
    o.com_W = in.X_WO * in.com_O;
    if (o.com_points_W.rows() > 0) {
      const Eigen::VectorXd d =
          (o.com_points_W.rightCols<3>().rowwise() - o.com_W.transpose()).rowwise().norm();
      o.d_min = d.minCoeff();
      o.d_max = d.maxCoeff();
    } else {
      o.d_min = 0.0;
      o.d_max = (o.vertices_W.rowwise() - o.com_W.transpose()).rowwise().norm().maxCoeff();
    }
  }
  if (tote != nullptr) {
    check_rigid(X_W_tote, std::string(kModel) + ": X_W_tote");
    RayGeometry g;
    g.mesh = tote;
    g.X_WO = X_W_tote;
    g.instance_id = 0;
    all.push_back(g);
    impl_->tote = true;
  }
  impl_->all = std::make_unique<RayScene>(all);
}

ViewLabelModel::~ViewLabelModel() = default;
ViewLabelModel::ViewLabelModel(ViewLabelModel&&) noexcept = default;
ViewLabelModel& ViewLabelModel::operator=(ViewLabelModel&&) noexcept = default;

int ViewLabelModel::num_objects() const { return static_cast<int>(impl_->objects.size()); }
bool ViewLabelModel::has_tote() const { return impl_->tote; }

namespace {

using Object = ViewLabelModel::Impl::Object;

/// What the stages of label_view share: the camera, the instance image and the options.
struct ViewInput {
  ViewInput(const Intrinsics& K_, const Pose& X_WC_, const std::int32_t* ids_,
            const ViewLabelOptions& options_, int num_objects)
      : K(K_),
        X_WC(X_WC_),
        ids(ids_),
        options(options_),
        W(K_.width),
        H(K_.height),
        N(num_objects),
        P(static_cast<std::size_t>(W) * static_cast<std::size_t>(H)),
        X_CW(X_WC_.inverse()),
        R_WC(X_WC_.linear()),
        origin(X_WC_.translation().cast<float>().transpose()) {}
  const Intrinsics& K;
  const Pose& X_WC;
  const std::int32_t* ids;  // instance image, row-major (H, W)
  const ViewLabelOptions& options;
  int W, H, N;
  std::size_t P;  // pixels
  Pose X_CW;
  Mat3d R_WC;
  Eigen::RowVector3f origin;  // camera centre, world frame
};

/// The pixels to cast for one object: a span of columns [u_lo, u_hi] per row of its box.
struct CastRegion {
  PixelBox box;
  std::vector<std::pair<int, int>> spans;
};

/// One tile of the amodal pass: rows [v0, v1) of an object's cast region.
struct Tile {
  int object, v0, v1;
};

void check_view_input(const Intrinsics& K, const Pose& X_WC, const std::int32_t* instance_image,
                      int image_width, int image_height, const ViewLabelOptions& options,
                      int num_objects) {
  CameraView cam;
  cam.K = K;
  cam.X_WC = X_WC;
  cam.validate(kLabel);
  if (instance_image == nullptr) throw_error<InvalidArgument>(kLabel, ": instance image is null");
  if (image_width != K.width || image_height != K.height) {
    throw_error<InvalidArgument>(kLabel, ": instance image is ", image_width, "x", image_height,
                                 " (width x height); expected the camera size ", K.width, "x",
                                 K.height);
  }
  if (options.num_threads < 0) {
    throw_error<InvalidArgument>(kLabel, ": num_threads must be >= 0, got ", options.num_threads);
  }
  if (!(options.keypoint_tolerance >= 0.0) || !std::isfinite(options.keypoint_tolerance)) {
    throw_error<InvalidArgument>(kLabel, ": keypoint_tolerance must be finite and >= 0, got ",
                                 options.keypoint_tolerance);
  }
  const int W = K.width;
  const std::size_t P = static_cast<std::size_t>(W) * static_cast<std::size_t>(K.height);
  for (std::size_t p = 0; p < P; ++p) {
    const std::int32_t id = instance_image[p];
    if (id < 0 || id > num_objects) {
      throw_error<InvalidArgument>(kLabel, ": instance image pixel (u=", p % W, ", v=", p / W,
                                   ") has id ", id, "; expected 0 (background) .. ", num_objects,
                                   " (the number of objects)");
    }
  }
}

/// The semantic image and the visible pixel counts of `out`; returns the tight (visible) boxes.
std::vector<PixelBox> visible_pass(const ViewInput& in, const std::vector<Object>& objects,
                                   ViewLabels& out) {
  const int W = in.W, H = in.H, N = in.N;
  out.visible.assign(in.ids, in.ids + in.P);
  out.semantic.assign(in.P, 0);
  out.visible_pixels.assign(N, 0);
  std::vector<PixelBox> tight(N, PixelBox{W, H, -1, -1});
  std::vector<std::int32_t> category(N + 1, 0);
  for (int i = 0; i < N; ++i) category[i + 1] = objects[i].category_id;
  for (int v = 0; v < H; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * W;
    for (int u = 0; u < W; ++u) {
      const std::int32_t id = in.ids[row + u];
      out.semantic[row + u] = category[id];
      if (id == 0) continue;
      const int i = id - 1;
      ++out.visible_pixels[i];
      PixelBox& b = tight[i];
      b.u0 = std::min(b.u0, u);
      b.u1 = std::max(b.u1, u);
      b.v0 = std::min(b.v0, v);
      b.v1 = std::max(b.v1, v);
    }
  }
  return tight;
}

/// The pixels to cast for an object with world vertices V: a span of columns per row of its
/// projected box. The silhouette of a mesh lies inside the convex hull of its projected
/// vertices, so a row's span is where the row's centre line crosses that hull (widened by a
/// pixel for rounding). If a vertex is not in front of the camera, every pixel is cast.
CastRegion cast_region(const ViewInput& in, const Points3d& V) {
  const Intrinsics& K = in.K;
  const int W = in.W, H = in.H;
  const Points3d p_C =
      (V * in.X_CW.linear().transpose()).rowwise() + in.X_CW.translation().transpose();
  PixelBox b{0, 0, W - 1, H - 1};
  std::vector<Eigen::Vector2d> hull;
  if (p_C.col(2).minCoeff() > 1e-9) {
    std::vector<Eigen::Vector2d> pts(static_cast<std::size_t>(p_C.rows()));
    for (Eigen::Index k = 0; k < p_C.rows(); ++k) {
      pts[k] = {K.fx * p_C(k, 0) / p_C(k, 2) + K.cx, K.fy * p_C(k, 1) / p_C(k, 2) + K.cy};
    }
    hull = convex_hull(std::move(pts));
    double x0 = hull[0].x(), x1 = x0, y0 = hull[0].y(), y1 = y0;
    for (const auto& q : hull) {
      x0 = std::min(x0, q.x());
      x1 = std::max(x1, q.x());
      y0 = std::min(y0, q.y());
      y1 = std::max(y1, q.y());
    }
    // Pixel u's centre is u + 0.5: u in [ceil(xmin - 0.5), floor(xmax - 0.5)], plus 1 px slack.
    auto lo = [](double m, int size) {
      return static_cast<int>(std::clamp(std::ceil(m - 0.5) - 1.0, 0.0, double(size)));
    };
    auto hi = [](double m, int size) {
      return static_cast<int>(std::clamp(std::floor(m - 0.5) + 1.0, -1.0, double(size - 1)));
    };
    b = PixelBox{lo(x0, W), lo(y0, H), hi(x1, W), hi(y1, H)};
  }
  CastRegion region;
  region.box = b;
  if (b.empty()) return region;
  auto& rows = region.spans;
  const int num_rows = b.v1 - b.v0 + 1;
  rows.assign(static_cast<std::size_t>(num_rows), {b.u0, b.u1});
  if (hull.size() < 3) return region;
  for (int v = b.v0; v <= b.v1; ++v) {
    double xl = std::numeric_limits<double>::infinity(), xr = -xl;
    for (const double dy : {-0.05, 0.0, 0.05}) hull_row(hull, v + 0.5 + dy, xl, xr);
    auto& span = rows[static_cast<std::size_t>(v - b.v0)];
    if (xl > xr) {
      span = {b.u0, b.u0 - 1};
    } else {
      span = {std::max(b.u0, static_cast<int>(std::ceil(xl - 0.5)) - 1),
              std::min(b.u1, static_cast<int>(std::floor(xr - 0.5)) + 1)};
    }
  }
  return region;
}

/// Tiles: (object, band of rows), about kTileRays rays each, in a fixed order.
std::vector<Tile> make_tiles(const std::vector<CastRegion>& regions) {
  std::vector<Tile> tiles;
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const PixelBox& b = regions[i].box;
    if (b.empty()) continue;
    long rays = 0;
    int start = b.v0;
    for (int v = b.v0; v <= b.v1; ++v) {
      const auto& span = regions[i].spans[static_cast<std::size_t>(v - b.v0)];
      rays += std::max(0, span.second - span.first + 1);
      if (rays >= kTileRays || v == b.v1) {
        tiles.push_back({static_cast<int>(i), start, v + 1});
        start = v + 1;
        rays = 0;
      }
    }
  }
  return tiles;
}

/// Heat of a point at distance d from the centre of mass of `obj`, in [0, 1].
float com_heat(const Object& obj, double d) {
  const double span = std::max(obj.d_max - obj.d_min, 1e-12);
  return static_cast<float>(std::clamp((obj.d_max - d) / span, 0.0, 1.0));
}

/// Rays of the pixels `ps` (origin: the camera centre, direction: through each pixel centre).
void pixel_rays(const ViewInput& in, const std::vector<std::size_t>& ps, Points3f& o, Points3f& d) {
  const auto n = static_cast<Eigen::Index>(ps.size());
  const auto W = static_cast<std::size_t>(in.W);
  o.resize(n, 3);
  d.resize(n, 3);
  for (Eigen::Index k = 0; k < n; ++k) {
    o.row(k) = in.origin;
    d.row(k) =
        pixel_direction(in.R_WC, in.K, static_cast<int>(ps[k] % W), static_cast<int>(ps[k] / W));
  }
}

/// Per-thread buffers of the amodal pass.
struct TileScratch {
  Points3f o_vis, d_vis, o_hid, d_hid;
  std::vector<std::size_t> p_vis, p_hid;
};

/// Casts one tile against its object alone: the hidden pixels' rays set the amodal mask; the
/// visible ones (without a depth image) also give the heat map at their first hit.
void cast_tile(const ViewInput& in, const Object& obj, const CastRegion& region, const Tile& tile,
               TileScratch& s, ViewLabels& out) {
  CastOptions co;
  co.coherent = true;
  co.num_threads = 1;
  const int i = tile.object;
  const std::int32_t id = i + 1;
  s.p_vis.clear();
  s.p_hid.clear();
  for (int v = tile.v0; v < tile.v1; ++v) {
    const auto& span = region.spans[static_cast<std::size_t>(v - region.box.v0)];
    for (int u = span.first; u <= span.second; ++u) {
      const std::size_t p = static_cast<std::size_t>(v) * in.W + u;
      if (in.ids[p] != id) {
        s.p_hid.push_back(p);
      } else if (in.options.depth == nullptr) {
        s.p_vis.push_back(p);
      }
    }
  }
  std::uint8_t* mask = out.amodal.data() + static_cast<std::size_t>(i) * in.P;
  if (!s.p_hid.empty()) {
    pixel_rays(in, s.p_hid, s.o_hid, s.d_hid);
    const std::vector<std::uint8_t> hit = obj.alone->occluded(s.o_hid, s.d_hid, co);
    for (std::size_t k = 0; k < s.p_hid.size(); ++k) mask[s.p_hid[k]] = hit[k];
  }
  if (!s.p_vis.empty()) {
    pixel_rays(in, s.p_vis, s.o_vis, s.d_vis);
    const RayHits hits = obj.alone->intersect(s.o_vis, s.d_vis, co);
    for (std::size_t k = 0; k < s.p_vis.size(); ++k) {
      mask[s.p_vis[k]] = 1;  // visible => amodal, even if the ray grazes past the edge
      if (hits.instance_ids[k] < 0) continue;
      const double d = (hits.points.row(k).cast<double>().transpose() - obj.com_W).norm();
      out.com_heatmap[s.p_vis[k]] = com_heat(obj, d);
    }
  }
}

/// Every visible pixel is amodal (also outside the cast box, should rasteriser and box
/// disagree); with a depth image the heat map comes from the back-projected pixels.
void visible_amodal_rows(const ViewInput& in, const std::vector<Object>& objects, std::size_t begin,
                         std::size_t end, ViewLabels& out) {
  const Intrinsics& K = in.K;
  for (std::size_t v = begin; v < end; ++v) {
    for (int u = 0; u < in.W; ++u) {
      const std::size_t p = v * static_cast<std::size_t>(in.W) + u;
      const std::int32_t id = in.ids[p];
      if (id <= 0) continue;
      out.amodal[static_cast<std::size_t>(id - 1) * in.P + p] = 1;
      if (in.options.depth == nullptr) continue;
      const double z = in.options.depth[p];
      if (!(z > 0.0) || !std::isfinite(z)) continue;
      const Object& obj = objects[id - 1];
      const Vec3d p_C(z * (u + 0.5 - K.cx) / K.fx, z * (v + 0.5 - K.cy) / K.fy, z);
      const double d = (in.X_WC * p_C - obj.com_W).norm();
      out.com_heatmap[p] = com_heat(obj, d);
    }
  }
}

/// The box of an amodal mask (searched in the cast box united with the tight box) and its pixel
/// count.
PixelBox amodal_box(const ViewInput& in, const std::uint8_t* mask, const PixelBox& b,
                    const PixelBox& tight, std::int64_t& count) {
  PixelBox loose{in.W, in.H, -1, -1};
  count = 0;
  if (b.empty() && tight.empty()) return loose;
  const int u0 = tight.empty() ? b.u0 : std::min(b.u0, tight.u0);
  const int u1 = tight.empty() ? b.u1 : std::max(b.u1, tight.u1);
  const int v0 = tight.empty() ? b.v0 : std::min(b.v0, tight.v0);
  const int v1 = tight.empty() ? b.v1 : std::max(b.v1, tight.v1);
  for (int v = std::max(v0, 0); v <= std::min(v1, in.H - 1); ++v) {
    for (int u = std::max(u0, 0); u <= std::min(u1, in.W - 1); ++u) {
      if (!mask[static_cast<std::size_t>(v) * in.W + u]) continue;
      ++count;
      loose.u0 = std::min(loose.u0, u);
      loose.u1 = std::max(loose.u1, u);
      loose.v0 = std::min(loose.v0, v);
      loose.v1 = std::max(loose.v1, v);
    }
  }
  return loose;
}

/// Amodal pixel counts, occlusion rates, boxes and camera-frame poses of the objects.
void object_summaries(const ViewInput& in, const std::vector<Object>& objects,
                      const std::vector<CastRegion>& regions, const std::vector<PixelBox>& tight,
                      ViewLabels& out) {
  const int N = in.N;
  out.amodal_pixels.assign(N, 0);
  out.occlusion.assign(N, 1.0);
  out.bbox_tight.resize(N, 4);
  out.bbox_loose.resize(N, 4);
  out.X_CO.resize(N);
  for (int i = 0; i < N; ++i) {
    const std::uint8_t* mask = out.amodal.data() + static_cast<std::size_t>(i) * in.P;
    std::int64_t count = 0;
    const PixelBox loose = amodal_box(in, mask, regions[i].box, tight[i], count);
    out.amodal_pixels[i] = count;
    if (count > 0) {
      out.occlusion[i] =
          1.0 - static_cast<double>(out.visible_pixels[i]) / static_cast<double>(count);
    }
    out.bbox_tight.row(i) = coco_box(tight[i]);
    out.bbox_loose.row(i) = coco_box(loose);
    out.X_CO[i] = in.X_CW * objects[i].X_WO;
  }
  out.occlusion_map.assign(in.P, 0.0f);
  for (std::size_t p = 0; p < in.P; ++p) {
    const std::int32_t id = in.ids[p];
    if (id > 0) out.occlusion_map[p] = static_cast<float>(out.occlusion[id - 1]);
  }
}

/// Every keypoint and CoM point of every object: camera-frame rows [a, x, y, z], world points
/// and owners, keypoints of all objects first, then CoM points.
struct ScenePoints {
  Keypoints4d all_C;
  Points3d p_W;
  std::vector<std::int32_t> owner;
  Eigen::Index n_kp = 0, n_com = 0;
};

ScenePoints scene_points(const ViewInput& in, const std::vector<Object>& objects) {
  ScenePoints sp;
  for (const auto& o : objects) {
    sp.n_kp += o.keypoints_W.rows();
    sp.n_com += o.com_points_W.rows();
  }
  const Eigen::Index n = sp.n_kp + sp.n_com;
  sp.all_C.resize(n, 4);
  sp.owner.resize(static_cast<std::size_t>(n));
  sp.p_W.resize(n, 3);
  Eigen::Index r = 0;
  for (int pass = 0; pass < 2; ++pass) {
    for (int i = 0; i < in.N; ++i) {
      const Keypoints4d& k = pass == 0 ? objects[i].keypoints_W : objects[i].com_points_W;
      for (Eigen::Index j = 0; j < k.rows(); ++j, ++r) {
        sp.p_W.row(r) = k.row(j).rightCols<3>();
        sp.all_C(r, 0) = k(j, 0);
        sp.all_C.row(r).rightCols<3>() = (in.X_CW * sp.p_W.row(r).transpose()).transpose();
        sp.owner[r] = i;
      }
    }
  }
  return sp;
}

/// For each ray k (origin o, unit direction d_k): whether its first hit in the scene lies at a
/// distance t with lo_k <= t <= lo_k + width (the float sum) and belongs to instance
/// owner_id[k]. The same answer as testing RayScene::intersect's first hit (tnear 0, tfar +inf),
/// from two cheaper queries: an any-hit query over [0, lo_k (1 - 1e-4)] (a hit there is closer
/// than lo_k: the test fails), then, where nothing is there, a first-hit query over
/// [lo_k (1 - 2e-4), (lo_k + width) (1 + 1e-4)], whose first hit is the ray's first hit
/// whenever that one can pass the test. A triangle's t does not depend on the query's bounds,
/// and the overlaps (1e-4 of the distance) are far wider than Embree's rounding of its bound
/// tests, so the answers are the same bits.
std::vector<std::uint8_t> first_hit_in_window(const RayScene& scene, const Eigen::RowVector3f& o,
                                              const Points3f& d, const std::vector<float>& lo,
                                              float width,
                                              const std::vector<std::int32_t>& owner_id,
                                              int num_threads) {
  constexpr float kGap = 1e-4f;
  const RayScene::Impl& impl = scene.impl();
  std::vector<std::uint8_t> out(lo.size(), 0);
  parallel_for(lo.size(), num_threads, 1024, [&](std::size_t begin, std::size_t end) {
    detail::FtzDazGuard guard;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (std::size_t k = begin; k < end; ++k) {
      const float* dk = &d(static_cast<Eigen::Index>(k), 0);
      RTCRayHit rh;
      RTCRay& r = rh.ray;
      r.org_x = o[0];
      r.org_y = o[1];
      r.org_z = o[2];
      r.dir_x = dk[0];
      r.dir_y = dk[1];
      r.dir_z = dk[2];
      r.time = 0.0f;
      r.mask = 0xFFFFFFFFu;
      r.id = 0;
      r.flags = 0;
      float tnear = 0.0f;
      const float front = lo[k] * (1.0f - kGap);
      if (front > 0.0f) {
        r.tnear = 0.0f;
        r.tfar = front;
        rtcOccluded1(impl.scene, &ctx, &r);
        if (r.tfar == -std::numeric_limits<float>::infinity()) continue;
        tnear = lo[k] * (1.0f - 2.0f * kGap);
      }
      const float hi = lo[k] + width;
      r.tnear = tnear;
      r.tfar = hi * (1.0f + kGap);
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(impl.scene, &ctx, &rh);
      if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
      const float t = r.tfar;
      out[k] = static_cast<std::uint8_t>(std::isfinite(t) && t >= lo[k] && t <= hi &&
                                         impl.instance_ids[rh.hit.geomID] == owner_id[k]);
    }
  });
  return out;
}

/// Which points are visible: the first hit along the ray from the camera centre towards the
/// point, through the whole scene, is the point's own object, within the tolerance of the point
/// (|hit - distance| <= tolerance): nothing in front of it, and the point lies on the surface
/// the camera sees (a keypoint floating in a hole or above the object is not visible, even if
/// whatever lies behind it is). Points behind the camera or outside the image are not visible.
std::vector<std::uint8_t> visible_points(const ViewInput& in, const RayScene& scene,
                                         const ScenePoints& sp) {
  const Intrinsics& K = in.K;
  const Eigen::Index n = sp.all_C.rows();
  // Candidates: in front of the camera and projecting inside the image.
  std::vector<Eigen::Index> cand;
  for (Eigen::Index r = 0; r < n; ++r) {
    const double z = sp.all_C(r, 3);
    if (!(z > 1e-9)) continue;
    const double x = K.fx * sp.all_C(r, 1) / z + K.cx, y = K.fy * sp.all_C(r, 2) / z + K.cy;
    if (!(x >= 0.0 && x < in.W && y >= 0.0 && y < in.H)) continue;
    cand.push_back(r);
  }
  std::vector<float> tfar(cand.size());
  std::vector<std::int32_t> owner_id(cand.size());
  const Vec3d c = in.X_WC.translation();
  Points3f d(static_cast<Eigen::Index>(cand.size()), 3);
  for (std::size_t k = 0; k < cand.size(); ++k) {
    const Vec3d dir = sp.p_W.row(cand[k]).transpose() - c;
    const double dist = dir.norm();
    d.row(static_cast<Eigen::Index>(k)) = (dir / dist).cast<float>().transpose();
    tfar[k] = static_cast<float>(std::max(dist - in.options.keypoint_tolerance, 0.0));
    owner_id[k] = sp.owner[cand[k]] + 1;
  }
  std::vector<std::uint8_t> visible(static_cast<std::size_t>(n), 0);
  if (cand.empty()) return visible;
  const float tol2 = 2.0f * static_cast<float>(in.options.keypoint_tolerance);
  const std::vector<std::uint8_t> seen =
      first_hit_in_window(scene, in.origin, d, tfar, tol2, owner_id, in.options.num_threads);
  for (std::size_t k = 0; k < cand.size(); ++k) visible[cand[k]] = seen[k];
  return visible;
}

/// Keypoints: visible and occluded semantic keypoints, CoM points with their visibility.
void label_keypoints(const ViewInput& in, const std::vector<Object>& objects, const RayScene& scene,
                     ViewLabels& out) {
  const ScenePoints sp = scene_points(in, objects);
  const std::vector<std::uint8_t> visible = visible_points(in, scene, sp);
  const Eigen::Index n_kp = sp.n_kp;
  Eigen::Index nv = 0;
  for (Eigen::Index r = 0; r < n_kp; ++r) nv += visible[r];
  out.keypoints.resize(nv, 4);
  out.occluded_keypoints.resize(n_kp - nv, 4);
  for (Eigen::Index r = 0, a = 0, b = 0; r < n_kp; ++r) {
    if (visible[r]) {
      out.keypoints.row(a++) = sp.all_C.row(r);
      out.keypoint_object.push_back(sp.owner[r]);
    } else {
      out.occluded_keypoints.row(b++) = sp.all_C.row(r);
      out.occluded_keypoint_object.push_back(sp.owner[r]);
    }
  }
  out.com_points = sp.all_C.bottomRows(sp.n_com);
  out.com_object.assign(sp.owner.begin() + n_kp, sp.owner.end());
  out.com_visible.assign(visible.begin() + n_kp, visible.end());
}

}  // namespace

ViewLabels ViewLabelModel::label_view(const Intrinsics& K, const Pose& X_WC,
                                      const std::int32_t* instance_image, int image_width,
                                      int image_height, const ViewLabelOptions& options) const {
  const int N = num_objects();
  check_view_input(K, X_WC, instance_image, image_width, image_height, options, N);
  const ViewInput in(K, X_WC, instance_image, options, N);
  const std::vector<Object>& objects = impl_->objects;

  ViewLabels out;
  out.width = in.W;
  out.height = in.H;
  out.num_objects = N;
  const std::vector<PixelBox> tight = visible_pass(in, objects, out);

  // Amodal masks and the heat map: each tile cast against its object alone, then every visible
  // pixel.
  std::vector<CastRegion> regions(N);
  for (int i = 0; i < N; ++i) regions[i] = cast_region(in, objects[i].vertices_W);
  const std::vector<Tile> tiles = make_tiles(regions);
  out.amodal.assign(static_cast<std::size_t>(N) * in.P, 0);
  out.com_heatmap.assign(in.P, 0.0f);
  parallel_for(tiles.size(), options.num_threads, 1, [&](std::size_t begin, std::size_t end) {
    TileScratch scratch;
    for (std::size_t t = begin; t < end; ++t) {
      const Tile& tile = tiles[t];
      cast_tile(in, objects[tile.object], regions[tile.object], tile, scratch, out);
    }
  });
  parallel_for(static_cast<std::size_t>(in.H), options.num_threads, 64,
               [&](std::size_t begin, std::size_t end) {
                 visible_amodal_rows(in, objects, begin, end, out);
               });

  object_summaries(in, objects, regions, tight, out);
  if (options.keypoints) label_keypoints(in, objects, *impl_->all, out);
  return out;
}

}  // namespace mgn
