// Bindings of mgn/render/path_tracer.hpp: PBR materials, area lights, environment, the path
// traced scene and film development. The typed façade is python/mgn/render/path.py.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <mgn/render/camera.hpp>
#include <mgn/render/path_tracer.hpp>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

template <typename T>
py::array image(std::vector<T>&& v, int h, int w, int c = 1) {
  py::array flat = to_numpy(std::move(v));
  if (c == 1) return py::array(flat.attr("reshape")(h, w));
  return py::array(flat.attr("reshape")(h, w, c));
}

/// PathTraceResult as numpy arrays (moved, no copies), top row first.
struct PathImages {
  py::array radiance, albedo, normal, depth, instance_ids;
  long long rays = 0;
};

}  // namespace

void bind_render_path_tracer(py::module_& m) {
  py::class_<PbrMaterial>(m, "PbrMaterial", "glTF 2.0 metallic-roughness material (path tracer).")
      .def(py::init<>())
      .def_readwrite("base_color", &PbrMaterial::base_color)
      .def_readwrite("metallic", &PbrMaterial::metallic)
      .def_readwrite("roughness", &PbrMaterial::roughness)
      .def_readwrite("ior", &PbrMaterial::ior)
      .def_readwrite("transmission", &PbrMaterial::transmission)
      .def_readwrite("emission", &PbrMaterial::emission)
      .def(
          "set_texture",
          [](PbrMaterial& mat, const py::handle& obj) {
            if (obj.is_none()) {
              mat.texture.clear();
              mat.texture_width = mat.texture_height = 0;
              return;
            }
            CArray<std::uint8_t> a;
            try {
              a = py::cast<CArray<std::uint8_t>>(obj);
            } catch (const py::cast_error&) {
              throw_error<InvalidArgument>(
                  "PbrMaterial.base_color_texture: expected an (H, W, 3) uint8 array");
            }
            if (a.ndim() != 3 || a.shape(2) != 3 || a.shape(0) == 0 || a.shape(1) == 0) {
              throw_error<InvalidArgument>(
                  "PbrMaterial.base_color_texture: expected an (H, W, 3) uint8 array");
            }
            mat.texture.assign(a.data(), a.data() + a.size());
            mat.texture_height = static_cast<int>(a.shape(0));
            mat.texture_width = static_cast<int>(a.shape(1));
          },
          py::arg("texture"), "(H, W, 3) uint8 sRGB, top row first, or None")
      .def("validate", [](const PbrMaterial& mat) { mat.validate("PbrMaterial"); });

  py::class_<AreaLight>(m, "AreaLight", "One-sided rect or disc area light emitting along +z_L.")
      .def(py::init<>())
      .def_property(
          "X_WL", [](const AreaLight& l) { return pose_to_numpy(l.X_WL); },
          [](AreaLight& l, const py::handle& X) {
            CArray<double> a = py::cast<CArray<double>>(X);
            if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4)
              throw_error<InvalidArgument>("AreaLight.X_WL: expected a (4, 4) pose");
            Eigen::Matrix<double, 4, 4, Eigen::RowMajor> M =
                Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(a.data());
            l.X_WL.matrix() = M;  // validated (finite, rigid) by the scene
          })
      .def_property(
          "shape",
          [](const AreaLight& l) {
            return std::string(l.shape == AreaLight::Shape::Disc ? "disc" : "rect");
          },
          [](AreaLight& l, const std::string& s) {
            if (s == "rect") {
              l.shape = AreaLight::Shape::Rect;
            } else if (s == "disc") {
              l.shape = AreaLight::Shape::Disc;
            } else {
              throw_error<InvalidArgument>("AreaLight.shape must be 'rect' or 'disc', got '", s,
                                           "'");
            }
          })
      .def_readwrite("size", &AreaLight::size)
      .def_readwrite("color", &AreaLight::color)
      .def_readwrite("intensity", &AreaLight::intensity)
      .def("validate", [](const AreaLight& l) { l.validate("AreaLight"); });

  py::class_<Environment>(m, "Environment", "Environment dome: uniform, gradient or sky.")
      .def(py::init<>())
      .def_property(
          "kind",
          [](const Environment& e) {
            switch (e.kind) {
              case Environment::Kind::Gradient:
                return std::string("gradient");
              case Environment::Kind::Sky:
                return std::string("sky");
              default:
                return std::string("uniform");
            }
          },
          [](Environment& e, const std::string& s) {
            if (s == "uniform") {
              e.kind = Environment::Kind::Uniform;
            } else if (s == "gradient") {
              e.kind = Environment::Kind::Gradient;
            } else if (s == "sky") {
              e.kind = Environment::Kind::Sky;
            } else {
              throw_error<InvalidArgument>(
                  "Environment.kind must be 'uniform', 'gradient' or 'sky', got '", s, "'");
            }
          })
      .def_readwrite("color", &Environment::color)
      .def_readwrite("zenith", &Environment::zenith)
      .def_readwrite("horizon", &Environment::horizon)
      .def_readwrite("ground", &Environment::ground)
      .def_readwrite("sun_direction", &Environment::sun_direction)
      .def_readwrite("sun_strength", &Environment::sun_strength)
      .def_readwrite("sun_angular_radius", &Environment::sun_angular_radius)
      .def_readwrite("intensity", &Environment::intensity)
      .def("validate", [](const Environment& e) { e.validate("Environment"); });

  py::class_<PathTraceOptions>(m, "PathTraceOptions", "Path tracing settings of one view.")
      .def(py::init<>())
      .def_readwrite("spp", &PathTraceOptions::spp)
      .def_readwrite("max_bounces", &PathTraceOptions::max_bounces)
      .def_readwrite("seed", &PathTraceOptions::seed)
      .def_readwrite("view_index", &PathTraceOptions::view_index)
      .def_readwrite("num_threads", &PathTraceOptions::num_threads)
      .def_readwrite("rr_depth", &PathTraceOptions::rr_depth)
      .def_readwrite("aperture_radius", &PathTraceOptions::aperture_radius)
      .def_readwrite("focus_distance", &PathTraceOptions::focus_distance)
      .def_readwrite("clamp", &PathTraceOptions::clamp)
      .def_readwrite("clamp_indirect", &PathTraceOptions::clamp_indirect)
      .def_readwrite("fresnel_split_min", &PathTraceOptions::fresnel_split_min)
      .def_readwrite("guide_split_min", &PathTraceOptions::guide_split_min)
      .def_readwrite("shadow_rays", &PathTraceOptions::shadow_rays)
      .def_readwrite("sample_sky_dome", &PathTraceOptions::sample_sky_dome)
      .def_readwrite("reduced_nee_depth", &PathTraceOptions::reduced_nee_depth)
      .def_readwrite("labels", &PathTraceOptions::labels)
      .def_readwrite("adaptive_samples", &PathTraceOptions::adaptive_samples)
      .def_readwrite("adaptive_max", &PathTraceOptions::adaptive_max)
      .def("validate", &PathTraceOptions::validate);

  py::class_<FilmOptions>(m, "FilmOptions", "Radiance to 8-bit sRGB development settings.")
      .def(py::init<>())
      .def_readwrite("exposure", &FilmOptions::exposure)
      .def_property(
          "tone",
          [](const FilmOptions& f) {
            return std::string(f.tone == FilmOptions::Tone::Linear ? "linear" : "filmic");
          },
          [](FilmOptions& f, const std::string& s) {
            if (s == "filmic") {
              f.tone = FilmOptions::Tone::Filmic;
            } else if (s == "linear") {
              f.tone = FilmOptions::Tone::Linear;
            } else {
              throw_error<InvalidArgument>("FilmOptions.tone must be 'filmic' or 'linear', got '",
                                           s, "'");
            }
          })
      .def_readwrite("shot_noise", &FilmOptions::shot_noise)
      .def_readwrite("read_noise", &FilmOptions::read_noise)
      .def_readwrite("seed", &FilmOptions::seed)
      .def_readwrite("view_index", &FilmOptions::view_index)
      .def_readwrite("num_threads", &FilmOptions::num_threads)
      .def("validate", &FilmOptions::validate);

  py::class_<PathImages>(m, "PathTraceResult",
                         "PathScene.render() result (mgn/render/path_tracer.hpp), top row first.")
      .def_readonly("radiance", &PathImages::radiance, "(H, W, 3) float32 linear RGB, sample mean")
      .def_readonly("albedo", &PathImages::albedo, "(H, W, 3) float32 first-hit base colour")
      .def_readonly("normal", &PathImages::normal,
                    "(H, W, 3) float32 first-hit shading normal, world frame")
      .def_readonly("depth", &PathImages::depth, "(H, W) float32 z-depth in m, 0 = no hit")
      .def_readonly("instance_ids", &PathImages::instance_ids, "(H, W) int32, 0 = background")
      .def_readonly("rays", &PathImages::rays, "rays cast (camera, bounce and shadow)");

  py::class_<PathScene>(m, "PathScene", "Immutable path-traced scene (Embree geometry + lights).")
      .def(py::init([](const std::vector<const Mesh*>& meshes, const py::handle& poses,
                       const std::vector<std::int32_t>& instance_ids,
                       const std::vector<std::vector<PbrMaterial>>& materials,
                       const std::vector<AreaLight>& lights, const Environment& environment) {
             std::vector<Pose> X;
             if (!meshes.empty()) X = to_poses(poses, "poses");
             if (X.size() != meshes.size() || instance_ids.size() != meshes.size() ||
                 materials.size() != meshes.size()) {
               throw_error<InvalidArgument>(
                   "PathScene: expected one pose, instance id and material list per mesh, got ",
                   meshes.size(), " meshes, ", X.size(), " poses, ", instance_ids.size(),
                   " instance ids, ", materials.size(), " material lists");
             }
             std::vector<PathGeometry> geoms(meshes.size());
             for (std::size_t i = 0; i < meshes.size(); ++i) {
               geoms[i].mesh = meshes[i];
               geoms[i].X_WO = X[i];
               geoms[i].instance_id = instance_ids[i];
               geoms[i].materials = materials[i];
             }
             py::gil_scoped_release release;
             return std::make_unique<PathScene>(geoms, lights, environment);
           }),
           py::arg("meshes"), py::arg("poses"), py::arg("instance_ids"), py::arg("materials"),
           py::arg("lights"), py::arg("environment"))
      .def(
          "with_lighting",
          [](const PathScene& s, const std::vector<AreaLight>& lights, const Environment& env) {
            return s.with_lighting(lights, env);
          },
          py::arg("lights"), py::arg("environment"))
      .def_property_readonly("num_triangles", &PathScene::num_triangles)
      .def(
          "render",
          [](const PathScene& s, const Intrinsics& K, const py::handle& X_WC,
             const PathTraceOptions& options) {
            CameraView view;
            view.K = K;
            view.X_WC = to_pose(X_WC, "X_WC");
            PathTraceOutput out;
            {
              py::gil_scoped_release release;
              out = s.render(view, options);
            }
            const int h = out.height, w = out.width;
            PathImages d;
            d.radiance = image(std::move(out.radiance), h, w, 3);
            d.albedo = image(std::move(out.albedo), h, w, 3);
            d.normal = image(std::move(out.normal), h, w, 3);
            d.depth = image(std::move(out.depth), h, w);
            d.instance_ids = image(std::move(out.instance_ids), h, w);
            d.rays = static_cast<long long>(out.rays);
            return d;
          },
          py::arg("K"), py::arg("X_WC"), py::arg("options"));

  m.def(
      "develop_radiance",
      [](const py::handle& radiance, const FilmOptions& film) {
        CArray<float> a;
        try {
          a = py::cast<CArray<float>>(radiance);
        } catch (const py::cast_error&) {
          throw_error<InvalidArgument>("develop: radiance must be an (H, W, 3) float array");
        }
        if (a.ndim() != 3 || a.shape(2) != 3) {
          throw_error<InvalidArgument>("develop: radiance must be an (H, W, 3) float array, got ",
                                       a.ndim(), " dimensions");
        }
        const int h = static_cast<int>(a.shape(0)), w = static_cast<int>(a.shape(1));
        std::vector<float> rad(a.data(), a.data() + a.size());
        std::vector<std::uint8_t> out;
        {
          py::gil_scoped_release release;
          out = develop(rad, w, h, film);
        }
        return image(std::move(out), h, w, 3);
      },
      py::arg("radiance"), py::arg("film"));

  m.def(
      "material_texture_rgb",
      [](const Material& mat) -> py::object {
        std::vector<std::uint8_t> rgb;
        int w = 0, h = 0;
        bool ok = false;
        {
          py::gil_scoped_release release;
          ok = decode_base_color_texture(mat, rgb, w, h);
        }
        if (!ok) return py::none();
        return image(std::move(rgb), h, w, 3);
      },
      py::arg("material"),
      "The material's base colour texture decoded to (H, W, 3) uint8 sRGB (top row first), or "
      "None.");
}

}  // namespace mgn::py_bind
