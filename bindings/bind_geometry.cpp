#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <mgn/geometry/convex_decomposition.hpp>
#include <mgn/geometry/mass_properties.hpp>
#include <mgn/geometry/mesh.hpp>
#include <mgn/geometry/mesh_io.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/geometry/sampling.hpp>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

/// SurfaceSamples as numpy arrays (moved, no copies).
struct SampleArrays {
  py::array points, normals, face_ids;
};

}  // namespace

void bind_geometry(py::module_& m) {
  py::class_<SampleArrays>(m, "SurfaceSamples",
                           "sample_surface() result (mgn/geometry/sampling.hpp), mesh frame.")
      .def_readonly("points", &SampleArrays::points, "(N,3) float32 points on the surface, m")
      .def_readonly("normals", &SampleArrays::normals, "(N,3) float32 unit outward face normals")
      .def_readonly("face_ids", &SampleArrays::face_ids,
                    "(N,) int32 index of the face each point lies on");

  py::class_<Material>(m, "Material",
                       "Surface appearance of a mesh (colours linear RGBA in [0,1]).")
      .def(py::init<>())
      .def_readwrite("name", &Material::name)
      .def_readwrite("base_color", &Material::base_color, "RGBA in [0,1]")
      .def_readwrite("specular", &Material::specular, "RGB in [0,1]")
      .def_readwrite("shininess", &Material::shininess, "Phong exponent")
      .def_readwrite("opacity", &Material::opacity, "1 opaque .. 0 invisible")
      .def_readwrite("texture_path", &Material::texture_path,
                     "absolute path of the diffuse texture or ''")
      .def_property(
          "texture_data",
          [](const Material& mat) {
            return py::bytes(reinterpret_cast<const char*>(mat.texture_data.data()),
                             mat.texture_data.size());
          },
          [](Material& mat, const py::bytes& b) {
            const std::string s = b;
            mat.texture_data.assign(s.begin(), s.end());
          },
          "compressed bytes of an embedded texture, or b''")
      .def_readwrite("has_pbr", &Material::has_pbr,
                     "True when metallic/roughness/ior/transmission are given (glTF, built-in)")
      .def_readwrite("metallic", &Material::metallic, "[0,1] (glTF metallicFactor)")
      .def_readwrite("roughness", &Material::roughness,
                     "perceptual roughness [0,1] (glTF roughnessFactor)")
      .def_readwrite("ior", &Material::ior, "index of refraction >= 1 (KHR_materials_ior)")
      .def_readwrite("transmission", &Material::transmission,
                     "[0,1], 1 = clear dielectric (KHR_materials_transmission)")
      .def("__repr__", [](const Material& mat) {
        return "Material(name='" + mat.name + "', opacity=" + std::to_string(mat.opacity) +
               (mat.texture_path.empty() ? "" : ", texture='" + mat.texture_path + "'") + ")";
      });

  py::class_<MeshReport>(m, "MeshReport",
                         "Validation report of a mesh (topology after welding by position and "
                         "splitting where closed pieces touch along an edge or at a vertex).")
      .def_readonly("num_vertices", &MeshReport::num_vertices)
      .def_readonly("num_faces", &MeshReport::num_faces)
      .def_readonly("num_boundary_edges", &MeshReport::num_boundary_edges)
      .def_readonly("num_nonmanifold_edges", &MeshReport::num_nonmanifold_edges)
      .def_readonly("num_misoriented_edges", &MeshReport::num_misoriented_edges)
      .def_readonly("num_components", &MeshReport::num_components,
                    "connected components (by vertex, after splits)")
      .def_readonly("num_split_edges", &MeshReport::num_split_edges,
                    "welded edges of more than two faces split between closed pieces that touch "
                    "there (each piece then a closed 2-manifold)")
      .def_readonly("num_split_vertices", &MeshReport::num_split_vertices,
                    "welded vertices split between closed pieces that touch there")
      .def_readonly("is_watertight", &MeshReport::is_watertight)
      .def_readonly("is_winding_consistent", &MeshReport::is_winding_consistent)
      .def_readonly("is_outward", &MeshReport::is_outward)
      .def_readonly("signed_volume", &MeshReport::signed_volume, "m^3")
      .def_readonly("area", &MeshReport::area, "m^2")
      .def("__repr__", [](const MeshReport& r) {
        return "MeshReport(faces=" + std::to_string(r.num_faces) +
               ", watertight=" + (r.is_watertight ? "True" : "False") +
               ", winding_consistent=" + (r.is_winding_consistent ? "True" : "False") +
               ", outward=" + (r.is_outward ? "True" : "False") +
               ", boundary_edges=" + std::to_string(r.num_boundary_edges) +
               (r.num_split_edges + r.num_split_vertices > 0
                    ? ", split_edges=" + std::to_string(r.num_split_edges) +
                          ", split_vertices=" + std::to_string(r.num_split_vertices)
                    : std::string()) +
               ")";
      });

  py::class_<MassProperties>(m, "MassProperties", "Mass properties in the mesh frame (SI units).")
      .def_readonly("volume", &MassProperties::volume, "m^3")
      .def_readonly("mass", &MassProperties::mass, "kg")
      .def_readonly("center_of_mass", &MassProperties::center_of_mass, "(3,) m, mesh frame")
      .def_readonly("inertia", &MassProperties::inertia, "(3,3) kg m^2 about the centre of mass")
      .def_readonly("is_exact", &MassProperties::is_exact,
                    "False when the open-mesh shell fallback was used");

  py::class_<Mesh>(m, "Mesh", "Indexed triangle mesh in metres (see mgn.Mesh).")
      .def(py::init([](const py::handle& vertices, const py::handle& faces, const py::object& uvs,
                       std::vector<Material> materials, std::vector<std::int32_t> face_materials,
                       std::string name) {
             Points3f v = to_rows<float, 3>(vertices, "vertices");
             Faces f = to_rows<std::int32_t, 3>(faces, "faces");
             Points2f uv;
             if (!uvs.is_none()) uv = to_rows<float, 2>(uvs, "uvs");
             return Mesh(std::move(v), std::move(f), std::move(uv), std::move(materials),
                         std::move(face_materials), std::move(name));
           }),
           py::arg("vertices"), py::arg("faces"), py::arg("uvs") = py::none(),
           py::arg("materials") = std::vector<Material>{},
           py::arg("face_materials") = std::vector<std::int32_t>{}, py::arg("name") = "")
      .def_property_readonly(
          "vertices",
          [](const py::object& self) { return view_of(self.cast<const Mesh&>().vertices(), self); })
      .def_property_readonly(
          "faces",
          [](const py::object& self) { return view_of(self.cast<const Mesh&>().faces(), self); })
      .def_property_readonly("uvs",
                             [](const py::object& self) -> py::object {
                               const Mesh& mesh = self.cast<const Mesh&>();
                               if (mesh.uvs().rows() == 0) return py::none();
                               return view_of(mesh.uvs(), self);
                             })
      .def_property_readonly("materials", &Mesh::materials)
      .def_property_readonly("face_materials",
                             [](const Mesh& mesh) { return mesh.face_materials(); })
      .def_property("name", &Mesh::name, &Mesh::set_name)
      .def_property_readonly("num_vertices", &Mesh::num_vertices)
      .def_property_readonly("num_faces", &Mesh::num_faces)
      .def("face_normals", [](const Mesh& mesh) { return to_numpy(mesh.face_normals()); })
      .def("face_areas",
           [](const Mesh& mesh) { return to_numpy(Eigen::VectorXd(mesh.face_areas())); })
      .def_property_readonly("area", &Mesh::area)
      .def_property_readonly("bounds",
                             [](const Mesh& mesh) {
                               Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> b =
                                   mesh.bounds();
                               return to_numpy(std::move(b));
                             })
      .def("validate", &Mesh::validate, py::call_guard<py::gil_scoped_release>())
      .def(
          "transformed",
          [](const Mesh& mesh, const py::handle& X) { return mesh.transformed(to_pose(X, "X")); },
          py::arg("X"))
      .def("scaled", &Mesh::scaled, py::arg("factor"))
      .def("flipped", &Mesh::flipped)
      .def_static("merge", &Mesh::merge, py::arg("meshes"), py::arg("name") = "")
      .def("__repr__", [](const Mesh& mesh) {
        return "Mesh(name='" + mesh.name() + "', vertices=" + std::to_string(mesh.num_vertices()) +
               ", faces=" + std::to_string(mesh.num_faces()) + ")";
      });

  m.def(
      "load_mesh",
      [](const std::string& path, double scale, bool merge, bool drop_degenerate) {
        LoadOptions o;
        o.scale = scale;
        o.merge = merge;
        o.drop_degenerate = drop_degenerate;
        py::gil_scoped_release release;
        return load_mesh(path, o);
      },
      py::arg("path"), py::arg("scale") = LoadOptions{}.scale,
      py::arg("merge") = LoadOptions{}.merge,
      py::arg("drop_degenerate") = LoadOptions{}.drop_degenerate);

  m.def(
      "compute_mass_properties",
      [](const Mesh& mesh, double density, const std::string& open_mesh, double shell_thickness) {
        MassOptions o;
        o.density = density;
        o.shell_thickness = shell_thickness;
        if (open_mesh == "shell") {
          o.open_mesh = OpenMeshPolicy::Shell;
        } else if (open_mesh == "error") {
          o.open_mesh = OpenMeshPolicy::Error;
        } else {
          throw_error<InvalidArgument>(
              "compute_mass_properties: open_mesh must be 'shell' or 'error', got '", open_mesh,
              "'");
        }
        py::gil_scoped_release release;
        return compute_mass_properties(mesh, o);
      },
      py::arg("mesh"), py::arg("density") = MassOptions{}.density, py::arg("open_mesh") = "shell",
      py::arg("shell_thickness") = MassOptions{}.shell_thickness);

  m.def(
      "sample_surface",
      [](const Mesh& mesh, std::int64_t count, const std::string& method, std::uint64_t seed,
         int oversampling) {
        SampleOptions o;
        if (method == "random") {
          o.method = SampleMethod::Random;
        } else if (method == "even") {
          o.method = SampleMethod::Even;
        } else {
          throw_error<InvalidArgument>("sample_surface: method must be 'random' or 'even', got '",
                                       method, "'");
        }
        o.seed = seed;
        o.oversampling = oversampling;
        SurfaceSamples s;
        {
          py::gil_scoped_release release;
          s = sample_surface(mesh, count, o);
        }
        return SampleArrays{to_numpy(std::move(s.points)), to_numpy(std::move(s.normals)),
                            to_numpy(std::move(s.face_ids))};
      },
      py::arg("mesh"), py::arg("count"), py::arg("method") = "random",
      py::arg("seed") = SampleOptions{}.seed,
      py::arg("oversampling") = SampleOptions{}.oversampling);

  m.def(
      "make_box", [](const Vec3d& extents) { return make_box(extents); }, py::arg("extents"));
  m.def("make_sphere", &make_sphere, py::arg("radius"), py::arg("segments") = 64,
        py::arg("rings") = 32);
  m.def("make_cylinder", &make_cylinder, py::arg("radius"), py::arg("height"),
        py::arg("segments") = 64);

  m.def(
      "convex_hull",
      [](const Mesh& mesh) {
        py::gil_scoped_release release;
        return convex_hull(mesh);
      },
      py::arg("mesh"));

  py::class_<ConvexDecompositionOptions>(
      m, "ConvexDecompositionOptions",
      "Options of convex_decomposition (mgn/geometry/convex_decomposition.hpp); the defaults "
      "are the C++ struct's.")
      .def(py::init<>())
      .def_readwrite("convex_volume_tolerance",
                     &ConvexDecompositionOptions::convex_volume_tolerance)
      .def_readwrite("max_concavity", &ConvexDecompositionOptions::max_concavity)
      .def_readwrite("min_parts", &ConvexDecompositionOptions::min_parts)
      .def_readwrite("max_parts", &ConvexDecompositionOptions::max_parts)
      .def_readwrite("compactness_weight", &ConvexDecompositionOptions::compactness_weight)
      .def_readwrite("volume_weight", &ConvexDecompositionOptions::volume_weight)
      .def_readwrite("extra_concavity_points", &ConvexDecompositionOptions::extra_concavity_points)
      .def_readwrite("max_hacd_faces", &ConvexDecompositionOptions::max_hacd_faces)
      .def_readwrite("grid_resolution", &ConvexDecompositionOptions::grid_resolution)
      .def_readwrite("merge_volume_tolerance", &ConvexDecompositionOptions::merge_volume_tolerance)
      .def_readwrite("merge_max_parts", &ConvexDecompositionOptions::merge_max_parts);

  m.def(
      "convex_decomposition",
      [](const Mesh& mesh, const ConvexDecompositionOptions& options) {
        py::gil_scoped_release release;
        return convex_decomposition(mesh, options);
      },
      py::arg("mesh"),
      py::arg_v("options", ConvexDecompositionOptions{}, "ConvexDecompositionOptions()"));
}

}  // namespace mgn::py_bind
