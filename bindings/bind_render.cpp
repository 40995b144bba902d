// Bindings of mgn/render: cameras and rigs, the OSMesa renderer, depth sensor models.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <mgn/core/parallel.hpp>
#include <mgn/render/camera.hpp>
#include <mgn/render/depth_sensor.hpp>
#include <mgn/render/half_resolution.hpp>
#include <mgn/render/renderer.hpp>

#include <limits>
#include <tuple>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

/// Renderer.render() result: images as numpy arrays (None when not requested) and the light.
struct RenderArrays {
  py::object rgb, depth, instance_ids;
  LightSample light;
};

/// apply_depth_sensor() result as (H, W) numpy arrays.
struct DepthArrays {
  py::object depth, depth_ideal, valid;
};

/// An (H, W, C) float32 argument (None: an empty view). `keep` holds the converted array while
/// the view is used.
ImageView image_arg(const py::handle& obj, const char* name, CArray<float>& keep) {
  if (obj.is_none()) return {};
  try {
    keep = py::cast<CArray<float>>(obj);
  } catch (const py::cast_error&) {
    throw_error<InvalidArgument>(name, ": expected a numeric (H, W, C) array");
  }
  if (keep.ndim() != 3 || keep.shape(0) == 0 || keep.shape(1) == 0 || keep.shape(2) == 0)
    throw_error<InvalidArgument>(name, ": expected an (H, W, C) array with H, W, C > 0, got shape ",
                                 shape_of(keep));
  return {keep.data(), static_cast<int>(keep.shape(0)), static_cast<int>(keep.shape(1)),
          static_cast<int>(keep.shape(2))};
}

/// Moves a FloatImage into an (H, W, C) float32 array (no copy).
py::array image_array(FloatImage&& img) {
  auto* heap = new std::vector<float>(std::move(img.data));
  py::capsule owner(heap, [](void* p) { delete static_cast<std::vector<float>*>(p); });
  return py::array_t<float>({img.height, img.width, img.channels}, heap->data(), owner);
}

// The depth sensor model (mgn/render/depth_sensor.hpp).
void bind_depth_sensor(py::module_& m) {
  py::enum_<DepthSensorPreset>(m, "DepthSensorPreset")
      .value("Ideal", DepthSensorPreset::Ideal)
      .value("StructuredLight", DepthSensorPreset::StructuredLight)
      .value("ToF", DepthSensorPreset::ToF);

  py::class_<DepthSensorParams>(m, "DepthSensorParams", "Depth sensor model parameters (SI).")
      .def(py::init<>())
      .def_static("preset_defaults", &DepthSensorParams::preset_defaults, py::arg("preset"))
      .def_readwrite("preset", &DepthSensorParams::preset)
      .def_readwrite("min_range", &DepthSensorParams::min_range, "m")
      .def_readwrite("max_range", &DepthSensorParams::max_range, "m")
      .def_readwrite("sigma_a", &DepthSensorParams::sigma_a, "m")
      .def_readwrite("sigma_b", &DepthSensorParams::sigma_b, "1/m")
      .def_readwrite("sigma_z0", &DepthSensorParams::sigma_z0, "m")
      .def_readwrite("baseline", &DepthSensorParams::baseline, "m, projector along camera +x")
      .def_readwrite("shadow_tolerance_px", &DepthSensorParams::shadow_tolerance_px, "px")
      .def_readwrite("edge_threshold", &DepthSensorParams::edge_threshold, "m")
      .def_readwrite("flying_pixel_probability", &DepthSensorParams::flying_pixel_probability)
      .def_readwrite("depth_step", &DepthSensorParams::depth_step,
                     "m, grid of the reported z (0 = continuous)")
      .def_readwrite("depth_step_noise_fraction", &DepthSensorParams::depth_step_noise_fraction,
                     "the grid at a pixel: the largest 2^k depth_step not above this times the "
                     "noise sigma (0 = fixed depth_step)")
      .def_readwrite("invalid_transparent", &DepthSensorParams::invalid_transparent)
      .def_readwrite("invalid_dark", &DepthSensorParams::invalid_dark)
      .def_readwrite("invalid_mirror", &DepthSensorParams::invalid_mirror)
      .def("validate", &DepthSensorParams::validate);

  m.attr("SURFACE_TRANSPARENT") = static_cast<int>(kSurfaceTransparent);
  m.attr("SURFACE_DARK") = static_cast<int>(kSurfaceDark);
  m.attr("SURFACE_MIRROR") = static_cast<int>(kSurfaceMirror);
  m.def(
      "surface_flags", [](const Material& mat) { return static_cast<int>(surface_flags(mat)); },
      py::arg("material"));
  m.def(
      "mesh_surface_flags", [](const Mesh& mesh) { return static_cast<int>(surface_flags(mesh)); },
      py::arg("mesh"));
  m.def(
      "apply_depth_sensor",
      [](const py::handle& depth, const py::handle& instance_ids,
         const std::vector<std::uint8_t>& flags_by_id, const Intrinsics& K,
         const DepthSensorParams& params, std::uint64_t seed, int num_threads) {
        CArray<float> d;
        CArray<std::int32_t> ids;
        try {
          d = py::cast<CArray<float>>(depth);
          ids = py::cast<CArray<std::int32_t>>(instance_ids);
        } catch (const py::cast_error&) {
          throw_error<InvalidArgument>(
              "apply_depth_sensor: depth and instance_ids must be "
              "numeric (H, W) arrays");
        }
        for (const auto* a : {static_cast<py::array*>(&d), static_cast<py::array*>(&ids)}) {
          if (a->ndim() != 2 || a->shape(0) != K.height || a->shape(1) != K.width) {
            throw_error<InvalidArgument>(
                "apply_depth_sensor: depth and instance_ids must have "
                "shape (",
                K.height, ", ", K.width, ") of K");
          }
        }
        std::vector<float> dv(d.data(), d.data() + d.size());
        std::vector<std::int32_t> iv(ids.data(), ids.data() + ids.size());
        DepthImage out;
        {
          py::gil_scoped_release release;
          out = apply_depth_sensor(dv, iv, flags_by_id, K, params, seed, num_threads);
        }
        const int h = out.height, w = out.width;
        return DepthArrays{to_image(std::move(out.depth), h, w),
                           to_image(std::move(out.depth_ideal), h, w),
                           to_image(std::move(out.valid), h, w).attr("astype")("bool")};
      },
      py::arg("depth"), py::arg("instance_ids"), py::arg("flags_by_id"), py::arg("K"),
      py::arg("params"), py::arg("seed"), py::arg("num_threads") = ParallelOptions{}.num_threads);
}

// Half-resolution denoise arithmetic (mgn/render/half_resolution.hpp).
void bind_half_resolution(py::module_& m) {
  m.def(
      "block_means_2x2",
      [](const py::handle& image, int num_threads) {
        CArray<float> keep;
        const ImageView img = image_arg(image, "block_means_2x2: image", keep);
        if (img.empty()) throw_error<InvalidArgument>("block_means_2x2: image must not be None");
        FloatImage out;
        {
          py::gil_scoped_release release;
          out = block_means_2x2(img, num_threads);
        }
        return image_array(std::move(out));
      },
      py::arg("image"), py::arg("num_threads") = ParallelOptions{}.num_threads,
      "Means of the 2 x 2 pixel blocks of an (H, W, C) float32 image (an odd last row or column "
      "repeated): (ceil(H/2), ceil(W/2), C).");
  m.def(
      "double_blocks",
      [](const py::handle& blocks, int height, int width, int num_threads) {
        CArray<float> keep;
        const ImageView img = image_arg(blocks, "double_blocks: blocks", keep);
        if (img.empty()) throw_error<InvalidArgument>("double_blocks: blocks must not be None");
        FloatImage out;
        {
          py::gil_scoped_release release;
          out = double_blocks(img, height, width, num_threads);
        }
        return image_array(std::move(out));
      },
      py::arg("blocks"), py::arg("height"), py::arg("width"),
      py::arg("num_threads") = ParallelOptions{}.num_threads,
      "Bilinear doubling of a 2 x 2 block image to (height, width), block centres at the centres "
      "of their pixels, border blocks repeated.");
  m.def(
      "gaussian_3x3",
      [](const py::handle& image, double sigma, int num_threads) {
        CArray<float> keep;
        const ImageView img = image_arg(image, "gaussian_3x3: image", keep);
        if (img.empty()) throw_error<InvalidArgument>("gaussian_3x3: image must not be None");
        FloatImage out;
        {
          py::gil_scoped_release release;
          out = gaussian_3x3(img, sigma, num_threads);
        }
        return image_array(std::move(out));
      },
      py::arg("image"), py::arg("sigma") = 0.5,
      py::arg("num_threads") = ParallelOptions{}.num_threads,
      "Separable 3 x 3 Gaussian (sigma in pixels) of an (H, W, C) float32 image, border pixels "
      "repeated.");
  m.def(
      "restore_half_resolution",
      [](const py::handle& denoised, int height, int width, const py::handle& albedo,
         const py::handle& albedo_blocks, const py::handle& normal, const py::handle& normal_blocks,
         float albedo_floor, double edge_cos_lo, double edge_cos_hi, int num_threads) {
        CArray<float> k0, k1, k2, k3, k4;
        const ImageView den = image_arg(denoised, "restore_half_resolution: denoised", k0);
        if (den.empty())
          throw_error<InvalidArgument>("restore_half_resolution: denoised must not be None");
        const ImageView a = image_arg(albedo, "restore_half_resolution: albedo", k1);
        const ImageView ab = image_arg(albedo_blocks, "restore_half_resolution: albedo_blocks", k2);
        const ImageView n = image_arg(normal, "restore_half_resolution: normal", k3);
        const ImageView nb = image_arg(normal_blocks, "restore_half_resolution: normal_blocks", k4);
        HalfRestoreOptions opt;
        opt.albedo_floor = albedo_floor;
        opt.edge_cos_lo = edge_cos_lo;
        opt.edge_cos_hi = edge_cos_hi;
        opt.num_threads = num_threads;
        FloatImage out;
        {
          py::gil_scoped_release release;
          out = restore_half_resolution(den, height, width, a, ab, n, nb, opt);
        }
        return image_array(std::move(out));
      },
      py::arg("denoised"), py::arg("height"), py::arg("width"), py::arg("albedo") = py::none(),
      py::arg("albedo_blocks") = py::none(), py::arg("normal") = py::none(),
      py::arg("normal_blocks") = py::none(),
      py::arg("albedo_floor") = HalfRestoreOptions{}.albedo_floor,
      py::arg("edge_cos_lo") = HalfRestoreOptions{}.edge_cos_lo,
      py::arg("edge_cos_hi") = HalfRestoreOptions{}.edge_cos_hi,
      py::arg("num_threads") = HalfRestoreOptions{}.num_threads,
      "Full-size image of a half-resolution denoise: the denoised blocks doubled, times the "
      "albedo ratio max(a, floor) / max(double(albedo_blocks), floor) faded to 1 where the "
      "normal turns away from double(normal_blocks) (cosine edge_cos_lo..edge_cos_hi); clamped "
      "to >= 0.");
}

}  // namespace

void bind_render(py::module_& m) {
  using Triple = std::tuple<double, double, double>;
  py::class_<LightSample>(m, "LightSample",
                          "The main point light (mgn/render/renderer.hpp): input of "
                          "RenderOptions.light, and the light a view was rendered with. The "
                          "defaults are the C++ struct's.")
      .def(py::init<>())
      .def_property(
          "position_W",
          [](const LightSample& l) {
            return Triple(l.position_W.x(), l.position_W.y(), l.position_W.z());
          },
          [](LightSample& l, const Triple& p) {
            l.position_W = Vec3d(std::get<0>(p), std::get<1>(p), std::get<2>(p));
          },
          "point light position, world frame, m (NaN: 1.5 m above the centre of the scene)")
      .def_readwrite("intensity", &LightSample::intensity, "radiance scale (1 = nominal)")
      .def_readwrite("color_temperature", &LightSample::color_temperature, "K")
      .def_readwrite("ambient", &LightSample::ambient, "relative to white");
  py::class_<RenderOptions>(m, "RenderOptions",
                            "What Renderer.render draws and how (mgn/render/renderer.hpp); the "
                            "defaults are the C++ struct's, validate() checks the ranges.")
      .def(py::init<>())
      .def_readwrite("rgb", &RenderOptions::rgb, "produce the colour image")
      .def_readwrite("depth", &RenderOptions::depth, "produce the z-depth image")
      .def_readwrite("instances", &RenderOptions::instances, "produce the instance-id image")
      .def_readwrite("visible_instances", &RenderOptions::visible_instances,
                     "draw only instances with these ids (empty: all)")
      .def_readwrite("shadows", &RenderOptions::shadows, "shadow mapping from the main light")
      .def_readwrite("randomize", &RenderOptions::randomize,
                     "draw the light and the randomize_color colours from (seed, view_index)")
      .def_readwrite("seed", &RenderOptions::seed)
      .def_readwrite("view_index", &RenderOptions::view_index)
      .def_readwrite("light", &RenderOptions::light, "the light used when randomize is false")
      .def_property(
          "background",
          [](const RenderOptions& o) {
            return Triple(o.background.x(), o.background.y(), o.background.z());
          },
          [](RenderOptions& o, const Triple& c) {
            o.background =
                Vec3f(static_cast<float>(std::get<0>(c)), static_cast<float>(std::get<1>(c)),
                      static_cast<float>(std::get<2>(c)));
          },
          "linear RGB of empty pixels")
      .def_readwrite("check_camera_inside", &RenderOptions::check_camera_inside,
                     "raise if the camera centre is inside a closed mesh")
      .def("validate", &RenderOptions::validate,
           "Raises InvalidArgumentError naming the first field out of its range.");
  py::class_<RenderArrays>(m, "RenderResult",
                           "Renderer.render() result: (H,W,3) uint8 rgb, (H,W) float32 depth "
                           "(m), (H,W) int32 instance_ids (None when not requested), light.")
      .def_readonly("rgb", &RenderArrays::rgb)
      .def_readonly("depth", &RenderArrays::depth)
      .def_readonly("instance_ids", &RenderArrays::instance_ids)
      .def_readonly("light", &RenderArrays::light);
  py::class_<DepthArrays>(m, "DepthSensorResult",
                          "apply_depth_sensor() result: (H,W) float32 depth and depth_ideal (m), "
                          "(H,W) bool valid.")
      .def_readonly("depth", &DepthArrays::depth)
      .def_readonly("depth_ideal", &DepthArrays::depth_ideal)
      .def_readonly("valid", &DepthArrays::valid);
  py::class_<MgnRigParams>(m, "MgnRigParams",
                           "Drawn parameters of the MetaGraspNet rig (mgn/render/camera.hpp): "
                           "radii m, angles rad.")
      .def_readonly("R_start", &MgnRigParams::R_start)
      .def_readonly("R_end", &MgnRigParams::R_end)
      .def_readonly("theta_start", &MgnRigParams::theta_start)
      .def_readonly("theta_end", &MgnRigParams::theta_end)
      .def_readonly("phi_end", &MgnRigParams::phi_end);
  py::class_<Intrinsics>(m, "Intrinsics", "Pinhole intrinsics in pixels (OpenCV model).")
      .def(py::init([](int width, int height, double fx, double fy, double cx, double cy) {
             Intrinsics k{width, height, fx, fy, cx, cy};
             k.validate("Intrinsics");
             return k;
           }),
           py::arg("width"), py::arg("height"), py::arg("fx"), py::arg("fy"), py::arg("cx"),
           py::arg("cy"))
      .def_readonly("width", &Intrinsics::width)
      .def_readonly("height", &Intrinsics::height)
      .def_readonly("fx", &Intrinsics::fx)
      .def_readonly("fy", &Intrinsics::fy)
      .def_readonly("cx", &Intrinsics::cx)
      .def_readonly("cy", &Intrinsics::cy)
      .def_static("mgn_synthetic", &Intrinsics::mgn_synthetic)
      .def_static("zivid_two_like", &Intrinsics::zivid_two_like)
      .def_property_readonly("K", &Intrinsics::K, "(3, 3) intrinsic matrix")
      .def("__repr__", [](const Intrinsics& k) {
        return "Intrinsics(width=" + std::to_string(k.width) +
               ", height=" + std::to_string(k.height) + ", fx=" + std::to_string(k.fx) +
               ", fy=" + std::to_string(k.fy) + ", cx=" + std::to_string(k.cx) +
               ", cy=" + std::to_string(k.cy) + ")";
      });

  m.def(
      "look_at",
      [](const py::handle& eye, const py::handle& target, const py::handle& up) {
        return pose_to_numpy(
            look_at(to_vec3(eye, "eye"), to_vec3(target, "target"), to_vec3(up, "up")));
      },
      py::arg("eye"), py::arg("target"), py::arg("up"));
  m.def(
      "mgn_rig",
      [](std::uint64_t seed, const py::handle& target) {
        MgnRigParams p;
        const auto poses = mgn_rig(seed, to_vec3(target, "target"), &p);
        return py::make_tuple(poses_to_numpy(poses), p);
      },
      py::arg("seed"), py::arg("target"));
  m.def(
      "mgn_rig_from_params",
      [](double R_start, double R_end, double theta_start, double theta_end, double phi_end,
         const py::handle& target) {
        const MgnRigParams p{R_start, R_end, theta_start, theta_end, phi_end};
        return poses_to_numpy(mgn_rig_from_params(p, to_vec3(target, "target")));
      },
      py::arg("R_start"), py::arg("R_end"), py::arg("theta_start"), py::arg("theta_end"),
      py::arg("phi_end"), py::arg("target"));
  m.def(
      "hemisphere_rig",
      [](const std::vector<double>& radii, const std::vector<double>& tilts,
         const std::vector<double>& azimuths, const py::handle& target) {
        return poses_to_numpy(hemisphere_rig(radii, tilts, azimuths, to_vec3(target, "target")));
      },
      py::arg("radii"), py::arg("tilts"), py::arg("azimuths"), py::arg("target"));
  m.def("color_temperature_rgb", &color_temperature_rgb, py::arg("kelvin"));

  py::class_<Renderer>(m, "Renderer", "Off-screen OSMesa renderer (one GL context, reused).")
      .def(py::init([](int w, int h) {
             py::gil_scoped_release release;
             return std::make_unique<Renderer>(w, h);
           }),
           py::arg("max_width"), py::arg("max_height"))
      .def_property_readonly("max_width", &Renderer::max_width)
      .def_property_readonly("max_height", &Renderer::max_height)
      .def_property_readonly("num_meshes", &Renderer::num_meshes)
      .def(
          "add_mesh",
          [](Renderer& r, const Mesh& mesh) {
            py::gil_scoped_release release;
            return r.add_mesh(mesh);
          },
          py::arg("mesh"))
      .def(
          "set_instances",
          [](Renderer& r, const std::vector<int>& mesh_ids, const py::handle& poses,
             const std::vector<std::int32_t>& instance_ids,
             const std::vector<bool>& randomize_color) {
            std::vector<Pose> X;
            if (!mesh_ids.empty()) X = to_poses(poses, "poses");
            if (X.size() != mesh_ids.size() || instance_ids.size() != mesh_ids.size() ||
                (!randomize_color.empty() && randomize_color.size() != mesh_ids.size())) {
              throw_error<InvalidArgument>(
                  "Renderer.set_instances: expected one pose, instance id (and randomize flag) "
                  "per mesh id, got ",
                  mesh_ids.size(), " mesh ids, ", X.size(), " poses, ", instance_ids.size(),
                  " ids, ", randomize_color.size(), " flags");
            }
            std::vector<Instance> in(mesh_ids.size());
            for (std::size_t i = 0; i < in.size(); ++i) {
              in[i].mesh_id = mesh_ids[i];
              in[i].X_WO = X[i];
              in[i].instance_id = instance_ids[i];
              in[i].randomize_color = !randomize_color.empty() && randomize_color[i];
            }
            r.set_instances(std::move(in));
          },
          py::arg("mesh_ids"), py::arg("poses"), py::arg("instance_ids"),
          py::arg("randomize_color") = std::vector<bool>{})
      .def_property_readonly("num_instances",
                             [](const Renderer& r) { return r.instances().size(); })
      .def(
          "render",
          [](Renderer& r, const Intrinsics& K, const py::handle& X_WC, const RenderOptions& o) {
            CameraView view;
            view.K = K;
            view.X_WC = to_pose(X_WC, "X_WC");
            RenderOutput out;
            {
              py::gil_scoped_release release;
              out = r.render(view, o);
            }
            const int h = out.height, w = out.width;
            return RenderArrays{to_image(std::move(out.rgb), h, w, 3),
                                to_image(std::move(out.depth), h, w),
                                to_image(std::move(out.instance_ids), h, w), out.light};
          },
          py::arg("K"), py::arg("X_WC"), py::arg_v("options", RenderOptions{}, "RenderOptions()"),
          "Renders one view (camera frame OpenCV, X_WC in m): rgb, depth, instance_ids and the "
          "light used.");

  bind_depth_sensor(m);
  bind_half_resolution(m);
}

}  // namespace mgn::py_bind
