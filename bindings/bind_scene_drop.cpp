// Bindings of mgn/scene/drop and of the convex decomposition it uses (geometry/
// convex_decomposition): numpy in/out, GIL released during the work.
#include <pybind11/stl.h>
#include <mgn/geometry/convex_decomposition.hpp>
#include <mgn/scene/drop.hpp>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

Vec3d vec3(const py::handle& obj, const char* arg) {
  const auto rows = to_rows<double, 3>(
      py::module_::import("numpy").attr("reshape")(obj, py::make_tuple(-1, 3)), arg);
  if (rows.rows() != 1)
    throw_error<InvalidArgument>(arg, ": expected 3 numbers, got ", 3 * rows.rows());
  return rows.row(0).transpose();
}

}  // namespace

void bind_scene_drop(py::module_& m) {
  m.def(
      "convex_hull",
      [](const Mesh& mesh) {
        py::gil_scoped_release release;
        return convex_hull(mesh);
      },
      py::arg("mesh"));

  m.def(
      "convex_decomposition",
      [](const Mesh& mesh, double convex_volume_tolerance, double max_concavity, int min_parts,
         int max_parts, double compactness_weight, double volume_weight,
         bool extra_concavity_points, std::int64_t max_hacd_faces, int grid_resolution,
         double merge_volume_tolerance, int merge_max_parts) {
        ConvexDecompositionOptions o;
        o.convex_volume_tolerance = convex_volume_tolerance;
        o.max_concavity = max_concavity;
        o.min_parts = min_parts;
        o.max_parts = max_parts;
        o.compactness_weight = compactness_weight;
        o.volume_weight = volume_weight;
        o.extra_concavity_points = extra_concavity_points;
        o.max_hacd_faces = max_hacd_faces;
        o.grid_resolution = grid_resolution;
        o.merge_volume_tolerance = merge_volume_tolerance;
        o.merge_max_parts = merge_max_parts;
        py::gil_scoped_release release;
        return convex_decomposition(mesh, o);
      },
      py::arg("mesh"), py::arg("convex_volume_tolerance") = 0.10, py::arg("max_concavity") = 0.02,
      py::arg("min_parts") = 1, py::arg("max_parts") = 32, py::arg("compactness_weight") = 0.1,
      py::arg("volume_weight") = 0.0, py::arg("extra_concavity_points") = true,
      py::arg("max_hacd_faces") = 1500, py::arg("grid_resolution") = 40,
      py::arg("merge_volume_tolerance") = ConvexDecompositionOptions{}.merge_volume_tolerance,
      py::arg("merge_max_parts") = ConvexDecompositionOptions{}.merge_max_parts);

  m.def(
      "drop_objects",
      [](const std::vector<std::vector<Mesh>>& parts, const std::vector<double>& mass,
         const py::handle& coms, const py::handle& inertias, const std::vector<double>& mu,
         const std::vector<double>& e, const std::vector<std::string>& names, const Mesh& tote,
         const std::vector<double>& tote_box, const py::dict& options,
         const py::object& X_WO_start) {
        const std::size_t n = parts.size();
        const auto com = to_rows<double, 3>(coms, "coms");
        const auto inertia = to_rows<double, 9>(inertias, "inertias");
        auto check_len = [n](Eigen::Index rows, const char* arg) {
          if (static_cast<std::size_t>(rows) != n)
            throw_error<InvalidArgument>("drop_objects: ", arg, " has ", rows,
                                         " entries, expected one per object (", n, ")");
        };
        check_len(static_cast<Eigen::Index>(mass.size()), "masses");
        check_len(com.rows(), "coms");
        check_len(inertia.rows(), "inertias");
        check_len(static_cast<Eigen::Index>(mu.size()), "frictions");
        check_len(static_cast<Eigen::Index>(e.size()), "restitutions");
        check_len(static_cast<Eigen::Index>(names.size()), "names");
        std::vector<DropObject> objects(n);
        for (std::size_t i = 0; i < n; ++i) {
          const auto r = static_cast<Eigen::Index>(i);
          objects[i].convex_parts = parts[i];
          objects[i].mass = mass[i];
          objects[i].com = com.row(r).transpose();
          for (int k = 0; k < 9; ++k) objects[i].inertia(k / 3, k % 3) = inertia(r, k);
          objects[i].friction = mu[i];
          objects[i].restitution = e[i];
          objects[i].name = names[i];
        }
        if (tote_box.size() != 5 && tote_box.size() != 6)
          throw_error<InvalidArgument>(
              "drop_objects: tote_box must be (inner_length, inner_width, inner_height, "
              "wall_thickness, floor_thickness[, walls 1 or 0]), got ",
              tote_box.size(), " values");
        ToteBox box{tote_box[0], tote_box[1], tote_box[2], tote_box[3], tote_box[4]};
        if (tote_box.size() == 6) box.walls = tote_box[5] != 0.0;
        DropOptions o;
        for (const auto& [key_h, value] : options) {
          const std::string key = py::str(key_h);
          if (key == "window_min")
            o.window_min = vec3(value, "window_min");
          else if (key == "window_max")
            o.window_max = vec3(value, "window_max");
          else if (key == "dt")
            o.dt = value.cast<double>();
          else if (key == "solver_iterations")
            o.solver_iterations = value.cast<int>();
          else if (key == "max_time")
            o.max_time = value.cast<double>();
          else if (key == "linear_rest")
            o.linear_rest = value.cast<double>();
          else if (key == "angular_rest")
            o.angular_rest = value.cast<double>();
          else if (key == "rest_time")
            o.rest_time = value.cast<double>();
          else if (key == "gravity")
            o.gravity = value.cast<double>();
          else if (key == "rolling_friction")
            o.rolling_friction = value.cast<double>();
          else if (key == "angular_damping")
            o.angular_damping = value.cast<double>();
          else if (key == "tote_friction")
            o.tote_friction = value.cast<double>();
          else if (key == "tote_restitution")
            o.tote_restitution = value.cast<double>();
          else if (key == "collision_margin")
            o.collision_margin = value.cast<double>();
          else if (key == "contact_distance")
            o.contact_distance = value.cast<double>();
          else if (key == "remove_unsettled")
            o.remove_unsettled = value.cast<bool>();
          else if (key == "max_hull_vertices")
            o.max_hull_vertices = value.cast<int>();
          else if (key == "hull_tolerance")
            o.hull_tolerance = value.cast<double>();
          else if (key == "polyhedral_contacts")
            o.polyhedral_contacts = value.cast<bool>();
          else if (key == "resettle_time")
            o.resettle_time = value.cast<double>();
          else if (key == "two_friction_directions")
            o.two_friction_directions = value.cast<bool>();
          else if (key == "seed")
            o.seed = value.cast<std::uint64_t>();
          else if (key == "tote_collision") {
            const std::string mode = value.cast<std::string>();
            if (mode == "boxes")
              o.tote_collision = ToteCollision::Boxes;
            else if (mode == "mesh")
              o.tote_collision = ToteCollision::TriangleMesh;
            else
              throw_error<InvalidArgument>(
                  "drop_objects: tote_collision must be 'boxes' or 'mesh', got '", mode, "'");
          } else {
            throw_error<InvalidArgument>("drop_objects: unknown option '", key, "'");
          }
        }
        std::vector<Pose> start;  // settle_objects(): start at rest at these poses
        if (!X_WO_start.is_none()) {
          const auto rows = to_rows<double, 16>(X_WO_start, "X_WO_start");
          for (Eigen::Index i = 0; i < rows.rows(); ++i) {
            Pose X = Pose::Identity();
            for (int k = 0; k < 16; ++k) X.matrix()(k / 4, k % 4) = rows(i, k);
            start.push_back(X);
          }
        }
        DropResult r;
        {
          py::gil_scoped_release release;
          r = X_WO_start.is_none() ? drop_objects(objects, tote, box, o)
                                   : settle_objects(objects, start, tote, box, o);
        }
        Eigen::Matrix<double, Eigen::Dynamic, 16, Eigen::RowMajor> X(n, 16), X0(n, 16);
        std::vector<std::int32_t> status(n);
        std::vector<std::uint8_t> settled(n);
        std::vector<std::uint32_t> contacts(n);
        for (std::size_t i = 0; i < n; ++i) {
          const auto& d = r.objects[i];
          const auto ri = static_cast<Eigen::Index>(i);
          for (int k = 0; k < 16; ++k) {
            X(ri, k) = d.X_WO.matrix()(k / 4, k % 4);
            X0(ri, k) = d.X_WO_release.matrix()(k / 4, k % 4);
          }
          status[i] = static_cast<std::int32_t>(d.status);
          settled[i] = d.settled ? 1 : 0;
          contacts[i] = d.contacts;
        }
        py::dict out;
        out["X_WO"] = to_numpy(std::move(X)).attr("reshape")(n, 4, 4);
        out["X_WO_release"] = to_numpy(std::move(X0)).attr("reshape")(n, 4, 4);
        out["status"] = to_numpy(std::move(status));
        out["settled"] = to_bool_numpy(std::move(settled));
        out["contacts"] = to_numpy(std::move(contacts));
        out["steps"] = r.steps;
        out["simulated_time"] = r.simulated_time;
        out["all_settled"] = r.settled;
        out["max_penetration"] = r.max_penetration;
        return out;
      },
      py::arg("parts"), py::arg("masses"), py::arg("coms"), py::arg("inertias"),
      py::arg("frictions"), py::arg("restitutions"), py::arg("names"), py::arg("tote"),
      py::arg("tote_box"), py::arg("options"), py::arg("X_WO_start") = py::none());
}

}  // namespace mgn::py_bind
