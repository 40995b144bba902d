#pragma once
/// @file view_labels.hpp  Per-view object labels (docs/models.md §7): visible / semantic / amodal
/// masks, occlusion, 2-D boxes, object poses in the camera frame, keypoint visibility and a
/// centre-of-mass heat map.
///
/// Frames and units: the world W is the tote frame (metres); the camera frame C is OpenCV (x
/// right, y down, z forward); X_AB is the pose of B in A. Pixel (u, v) is the ray through the
/// continuous image point (u + 0.5, v + 0.5), exactly as mgn::camera_rays and the renderer, so a
/// ray-traced mask and a rendered mask agree pixel for pixel up to edge rounding.
///
/// Objects are numbered in scene order: object index i (0-based) has instance id i + 1. Every
/// per-object array has one row per object, including objects not seen in a view.
///
/// A ViewLabelModel is built once per scene (one Embree scene per object for the amodal masks,
/// one Embree scene of all objects and the tote for keypoint visibility) and is then immutable:
/// it is reused for every view and may be used by several threads at once.

#include <mgn/core/types.hpp>
#include <mgn/geometry/mesh.hpp>
#include <mgn/render/camera.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace mgn {

/// [a, x, y, z] rows: a = keypoint id or CoM score, x, y, z in metres.
using Keypoints4d = Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>;
/// COCO boxes [x, y, w, h] in pixels, one row per object.
using Boxes4i = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 4, Eigen::RowMajor>;

/// One object of the scene, as given to ViewLabelModel.
struct ViewLabelObject {
  const Mesh* mesh = nullptr;    ///< object-frame mesh; copied at build time
  Pose X_WO = Pose::Identity();  ///< pose of the object in the world (rigid)
  std::int32_t category_id = 0;  ///< written to the semantic mask (>= 1)
  /// Semantic keypoints in the object frame: [id, x, y, z] (m). May be empty.
  Keypoints4d keypoints;
  /// CoM-scored surface points in the object frame: [score, x, y, z] (m), as
  /// mgn.io.model_folder.com_keypoints makes them. May be empty.
  Keypoints4d com_points;
  /// Centre of mass in the object frame (m).
  Vec3d com_O = Vec3d::Zero();
};

/// Options of one labelling call.
struct ViewLabelOptions {
  /// A keypoint (or CoM point) is visible when the first hit along the ray from the camera
  /// centre is on its own object and within keypoint_tolerance of the point (m): unoccluded and
  /// on the surface the camera sees. A point floating off its surface (a hole centre, say) is
  /// occluded. 2 mm absorbs the float32 geometry and points sampled on the surface.
  double keypoint_tolerance = 0.002;
  /// Compute the keypoint sets (false leaves them empty).
  bool keypoints = true;
  /// Optional (H*W) row-major z-depth image of the same view (m; <= 0 or NaN where nothing is
  /// seen), e.g. the renderer's ideal depth. When given, the heat map takes the 3-D point of
  /// each visible pixel from it (p_C = z ((u + 0.5 - cx) / fx, (v + 0.5 - cy) / fy, 1)) instead
  /// of casting a ray per visible pixel, which roughly halves the ray count. Not owned.
  const float* depth = nullptr;
  int num_threads = 0;  ///< 0 = all hardware threads; results do not depend on it
};

/// Labels of one view. Images are row-major (H, W), top row first; N = number of objects.
struct ViewLabels {
  int width = 0, height = 0, num_objects = 0;
  /// (H*W) visible instance ids 0..N (0 = background, tote, floor): the instance image checked.
  std::vector<std::int32_t> visible;
  /// (H*W) category id of the visible object, 0 for background.
  std::vector<std::int32_t> semantic;
  /// (N*H*W) amodal masks (1 = object i covers the pixel when it is alone in the scene): the
  /// pixels whose centre ray hits object i, united with its visible pixels (so the amodal mask
  /// always contains the visible one, even where the rasteriser and the ray tracer disagree on
  /// an edge pixel).
  std::vector<std::uint8_t> amodal;
  std::vector<std::int64_t> visible_pixels;  ///< (N)
  std::vector<std::int64_t> amodal_pixels;   ///< (N)
  /// (N) occlusion rate 1 - visible / amodal in [0, 1]; 1 when the amodal mask is empty. Every
  /// occluder counts: other objects, the tote, anything drawn in the instance image.
  std::vector<double> occlusion;
  /// (H*W) each visible pixel carries its object's occlusion rate; 0 on background.
  std::vector<float> occlusion_map;
  Boxes4i bbox_tight;      ///< (N,4) COCO [x, y, w, h] px of the visible mask; zeros if empty
  Boxes4i bbox_loose;      ///< (N,4) COCO [x, y, w, h] px of the amodal mask; zeros if empty
  std::vector<Pose> X_CO;  ///< (N) object poses in the camera frame, X_WC^-1 X_WO
  Keypoints4d keypoints;   ///< visible semantic keypoints [id, x, y, z], camera frame, m
  std::vector<std::int32_t> keypoint_object;  ///< object index (0-based) of each row
  Keypoints4d occluded_keypoints;             ///< the other semantic keypoints, same layout
  std::vector<std::int32_t> occluded_keypoint_object;
  /// All CoM-scored points of all objects [score, x, y, z], camera frame, m, object by object.
  Keypoints4d com_points;
  std::vector<std::int32_t> com_object;   ///< object index of each CoM point
  std::vector<std::uint8_t> com_visible;  ///< 1 if the CoM point is visible
  /// (H*W) centre-of-mass heat map in [0, 1]. For a visible pixel of object i whose centre ray
  /// first hits object i at the world point x (or, with ViewLabelOptions::depth, the pixel's
  /// back-projected depth point): heat = clamp((d_max - |x - c|) / (d_max - d_min),
  /// 0, 1), with c the object's centre of mass and d_min, d_max the smallest and largest distance
  /// of its CoM-scored points to c (the same score as the CoM keypoints); without CoM points
  /// d_min = 0 and d_max = the largest vertex distance. 0 on background, on visible pixels whose
  /// ray misses the object (edge pixels where rasteriser and ray tracer disagree) and on visible
  /// pixels without a valid depth.
  std::vector<float> com_heatmap;
};

/// Ray-tracing model of one scene for per-view labels. Immutable after construction.
class ViewLabelModel {
 public:
  /// Builds the Embree scenes. `tote` (may be null) is placed at X_W_tote and only occludes
  /// keypoints (it never appears in amodal masks). Throws InvalidArgument for an empty object
  /// list, a null or empty mesh, a non-finite or non-rigid pose, a category id < 1 or
  /// non-finite keypoints.
  ViewLabelModel(const std::vector<ViewLabelObject>& objects, const Mesh* tote = nullptr,
                 const Pose& X_W_tote = Pose::Identity());
  ~ViewLabelModel();
  ViewLabelModel(const ViewLabelModel&) = delete;
  ViewLabelModel& operator=(const ViewLabelModel&) = delete;
  ViewLabelModel(ViewLabelModel&&) noexcept;
  ViewLabelModel& operator=(ViewLabelModel&&) noexcept;

  int num_objects() const;
  bool has_tote() const;

  /// Labels of one view seen by a camera with intrinsics K at pose X_WC (world). `instance_image`
  /// points to the row-major (image_height, image_width) instance image of the view (0 =
  /// background, else instance id 1..N), e.g. the renderer's instance pass. Throws
  /// InvalidArgument for an invalid camera, a null image, an image size other than K.width x
  /// K.height, an id outside 0..N or a negative thread count.
  ViewLabels label_view(const Intrinsics& K, const Pose& X_WC, const std::int32_t* instance_image,
                        int image_width, int image_height,
                        const ViewLabelOptions& options = {}) const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// The centre-of-mass heat map of a view predicted from its noise-free depth, as label_view
/// computes it (docs/format.md, "`{v}_mgn.hdf5`": the scene writer stores the heat map as its
/// difference from this prediction). At each pixel (u, v) of instance id i >= 1 whose depth
/// z = depth_m (metres) is finite and > 0, the point p_C = (z (u + 0.5 - cx) / fx,
/// z (v + 0.5 - cy) / fy, z) (camera frame, OpenCV; [fx, fy, cx, cy] = intrinsics) moved to the
/// world by X_WC scores
/// clamp((d_max - |p_W - c_W|) / max(d_max - d_min, 1e-12), 0, 1), where [c_W (3, world frame, m),
/// d_min, d_max (m)] is row i - 1 of com_parameters (num_objects x 5, row-major); 0 elsewhere.
/// Only IEEE-exact operations in a fixed order and no fused multiply-adds, so every machine gives
/// the same bits. depth_m, instances and out: width x height, row-major; X_WC: 4 x 4 row-major,
/// m; intrinsics: fx, fy, cx, cy, px. Throws InvalidArgument for an instance id above
/// num_objects.
void com_heatmap_prediction(const float* depth_m, const std::int32_t* instances, int width,
                            int height, const double X_WC[16], const double intrinsics[4],
                            const double* com_parameters, int num_objects, float* out);

}  // namespace mgn
