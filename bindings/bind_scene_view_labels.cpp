#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <mgn/scene/view_labels.hpp>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

/// ViewLabels as numpy arrays (moved, no copies; images reshaped to (H, W)).
struct ViewLabelArrays {
  py::array visible, semantic, amodal, visible_pixels, amodal_pixels, occlusion, occlusion_map,
      bbox_tight, bbox_loose;
  py::array X_CO, keypoints, keypoint_object, occluded_keypoints, occluded_keypoint_object,
      com_points, com_object, com_visible, com_heatmap;
};

}  // namespace

void bind_scene_view_labels(py::module_& m) {
  py::class_<ViewLabelArrays>(m, "ViewLabelArrays",
                              "ViewLabelModel.label_view() result (mgn/scene/view_labels.hpp); "
                              "mgn.view_labels.objects.ViewObjectLabels documents each array.")
      .def_readonly("visible", &ViewLabelArrays::visible)
      .def_readonly("semantic", &ViewLabelArrays::semantic)
      .def_readonly("amodal", &ViewLabelArrays::amodal)
      .def_readonly("visible_pixels", &ViewLabelArrays::visible_pixels)
      .def_readonly("amodal_pixels", &ViewLabelArrays::amodal_pixels)
      .def_readonly("occlusion", &ViewLabelArrays::occlusion)
      .def_readonly("occlusion_map", &ViewLabelArrays::occlusion_map)
      .def_readonly("bbox_tight", &ViewLabelArrays::bbox_tight)
      .def_readonly("bbox_loose", &ViewLabelArrays::bbox_loose)
      .def_readonly("X_CO", &ViewLabelArrays::X_CO)
      .def_readonly("keypoints", &ViewLabelArrays::keypoints)
      .def_readonly("keypoint_object", &ViewLabelArrays::keypoint_object)
      .def_readonly("occluded_keypoints", &ViewLabelArrays::occluded_keypoints)
      .def_readonly("occluded_keypoint_object", &ViewLabelArrays::occluded_keypoint_object)
      .def_readonly("com_points", &ViewLabelArrays::com_points)
      .def_readonly("com_object", &ViewLabelArrays::com_object)
      .def_readonly("com_visible", &ViewLabelArrays::com_visible)
      .def_readonly("com_heatmap", &ViewLabelArrays::com_heatmap);

  py::class_<ViewLabelModel>(m, "ViewLabelModel",
                             "Ray-tracing model of one scene for per-view object labels.")
      .def(py::init([](const std::vector<const Mesh*>& meshes, const py::handle& poses,
                       const std::vector<std::int32_t>& category_ids,
                       const std::vector<py::handle>& keypoints,
                       const std::vector<py::handle>& com_points, const py::handle& coms,
                       const Mesh* tote, const py::handle& X_W_tote) {
             const std::size_t n = meshes.size();
             const std::vector<Pose> X = n == 0 ? std::vector<Pose>{} : to_poses(poses, "poses");
             const Points3d c = to_rows<double, 3>(coms, "coms");
             if (X.size() != n || category_ids.size() != n || keypoints.size() != n ||
                 com_points.size() != n || static_cast<std::size_t>(c.rows()) != n) {
               throw_error<InvalidArgument>("ViewLabelModel: got ", n, " meshes, ", X.size(),
                                            " poses, ", category_ids.size(), " category ids, ",
                                            keypoints.size(), " keypoint arrays, ",
                                            com_points.size(), " CoM point arrays and ", c.rows(),
                                            " centres of mass; expected one of each per object");
             }
             std::vector<ViewLabelObject> objects(n);
             for (std::size_t i = 0; i < n; ++i) {
               objects[i].mesh = meshes[i];
               objects[i].X_WO = X[i];
               objects[i].category_id = category_ids[i];
               objects[i].keypoints = to_rows<double, 4>(keypoints[i], "keypoints");
               objects[i].com_points = to_rows<double, 4>(com_points[i], "com_points");
               objects[i].com_O = c.row(static_cast<Eigen::Index>(i)).transpose();
             }
             const Pose X_tote =
                 X_W_tote.is_none() ? Pose::Identity() : to_pose(X_W_tote, "X_W_tote");
             py::gil_scoped_release release;
             return std::make_unique<ViewLabelModel>(objects, tote, X_tote);
           }),
           py::arg("meshes"), py::arg("poses"), py::arg("category_ids"), py::arg("keypoints"),
           py::arg("com_points"), py::arg("coms"), py::arg("tote") = nullptr,
           py::arg("X_W_tote") = py::none())
      .def_property_readonly("num_objects", &ViewLabelModel::num_objects)
      .def_property_readonly("has_tote", &ViewLabelModel::has_tote)
      .def(
          "label_view",
          [](const ViewLabelModel& model, const Intrinsics& K, const py::handle& X_WC,
             const py::handle& instance_image, double keypoint_tolerance, bool keypoints,
             int num_threads, const py::handle& depth) {
            const Pose X = to_pose(X_WC, "X_WC");
            CArray<std::int32_t> img;
            try {
              img = py::cast<CArray<std::int32_t>>(instance_image);
            } catch (const py::cast_error&) {
              throw_error<InvalidArgument>("instance_image: expected an integer (H, W) array");
            }
            if (img.ndim() != 2) {
              throw_error<InvalidArgument>("instance_image: expected a 2-D (H, W) array, got ",
                                           img.ndim(), " dimensions");
            }
            ViewLabelOptions o;
            o.keypoint_tolerance = keypoint_tolerance;
            o.keypoints = keypoints;
            o.num_threads = num_threads;
            const int h = static_cast<int>(img.shape(0)), w = static_cast<int>(img.shape(1));
            CArray<float> z;
            if (!depth.is_none()) {
              try {
                z = py::cast<CArray<float>>(depth);
              } catch (const py::cast_error&) {
                throw_error<InvalidArgument>("depth: expected a float (H, W) array");
              }
              if (z.ndim() != 2 || z.shape(0) != h || z.shape(1) != w) {
                throw_error<InvalidArgument>("depth: expected the shape of instance_image (", h,
                                             ", ", w, ")");
              }
              o.depth = z.data();
            }
            ViewLabels L;
            {
              py::gil_scoped_release release;
              L = model.label_view(K, X, img.data(), w, h, o);
            }
            const int n = L.num_objects;
            ViewLabelArrays out;
            out.visible = as_image(to_numpy(std::move(L.visible)), h, w);
            out.semantic = as_image(to_numpy(std::move(L.semantic)), h, w);
            out.amodal =
                to_bool_numpy(std::move(L.amodal)).attr("reshape")(py::make_tuple(n, h, w));
            out.visible_pixels = to_numpy(std::move(L.visible_pixels));
            out.amodal_pixels = to_numpy(std::move(L.amodal_pixels));
            out.occlusion = to_numpy(std::move(L.occlusion));
            out.occlusion_map = as_image(to_numpy(std::move(L.occlusion_map)), h, w);
            out.bbox_tight = to_numpy(std::move(L.bbox_tight));
            out.bbox_loose = to_numpy(std::move(L.bbox_loose));
            out.X_CO = poses_to_numpy(L.X_CO);
            out.keypoints = to_numpy(std::move(L.keypoints));
            out.keypoint_object = to_numpy(std::move(L.keypoint_object));
            out.occluded_keypoints = to_numpy(std::move(L.occluded_keypoints));
            out.occluded_keypoint_object = to_numpy(std::move(L.occluded_keypoint_object));
            out.com_points = to_numpy(std::move(L.com_points));
            out.com_object = to_numpy(std::move(L.com_object));
            out.com_visible = to_bool_numpy(std::move(L.com_visible));
            out.com_heatmap = as_image(to_numpy(std::move(L.com_heatmap)), h, w);
            return out;
          },
          py::arg("K"), py::arg("X_WC"), py::arg("instance_image"),
          py::arg("keypoint_tolerance") = ViewLabelOptions{}.keypoint_tolerance,
          py::arg("keypoints") = ViewLabelOptions{}.keypoints,
          py::arg("num_threads") = ViewLabelOptions{}.num_threads, py::arg("depth") = py::none());

  m.def(
      "com_heatmap_prediction",
      [](const py::handle& depth_m, const py::handle& instances, const py::handle& X_WC, double fx,
         double fy, double cx, double cy, const py::handle& com_parameters) {
        CArray<float> z;
        CArray<std::int32_t> ids;
        CArray<double> X, params;
        try {
          z = py::cast<CArray<float>>(depth_m);
          ids = py::cast<CArray<std::int32_t>>(instances);
          X = py::cast<CArray<double>>(X_WC);
          params = py::cast<CArray<double>>(com_parameters);
        } catch (const py::cast_error&) {
          throw_error<InvalidArgument>(
              "com_heatmap_prediction: expected float32 depth (H, W), int32 instances (H, W), "
              "X_WC (4, 4) and com_parameters (N, 5)");
        }
        if (z.ndim() != 2 || ids.ndim() != 2 || z.shape(0) != ids.shape(0) ||
            z.shape(1) != ids.shape(1) || X.size() != 16 || params.ndim() != 2 ||
            params.shape(1) != 5) {
          throw_error<InvalidArgument>(
              "com_heatmap_prediction: expected depth and instances of one (H, W) shape, X_WC "
              "(4, 4) and com_parameters (N, 5)");
        }
        const int h = static_cast<int>(z.shape(0)), w = static_cast<int>(z.shape(1));
        py::array_t<float> out({z.shape(0), z.shape(1)});
        float* o = out.mutable_data();
        {
          py::gil_scoped_release release;
          const double intrinsics[4] = {fx, fy, cx, cy};
          com_heatmap_prediction(z.data(), ids.data(), w, h, X.data(), intrinsics, params.data(),
                                 static_cast<int>(params.shape(0)), o);
        }
        return out;
      },
      py::arg("depth_m"), py::arg("instances"), py::arg("X_WC"), py::arg("fx"), py::arg("fy"),
      py::arg("cx"), py::arg("cy"), py::arg("com_parameters"),
      "(H, W) float32 CoM heat map predicted from the noise-free depth (m), see "
      "mgn/scene/view_labels.hpp and docs/format.md.");
}

}  // namespace mgn::py_bind
