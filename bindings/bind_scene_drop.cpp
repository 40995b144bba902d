// Bindings of mgn/scene/drop (mgn._core.scene): numpy in/out, GIL released during the work.
#include <pybind11/stl.h>

#include <mgn/scene/drop.hpp>
#include <tuple>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

/// drop_objects()/settle_objects() result as numpy arrays (moved, no copies), one row per input
/// object; bound as DropResult.
struct DropArrays {
  py::array X_WO;            ///< (N,4,4) settled poses
  py::array X_WO_release;    ///< (N,4,4) release (or start) poses
  py::array status;          ///< (N,) int32 DropStatus
  py::array object_settled;  ///< (N,) bool, at rest when the simulation stopped
  py::array contacts;        ///< (N,) uint32 ToteContact flags
  std::int64_t steps = 0;
  double simulated_time = 0.0;
  bool settled = false;
  int resettle_rounds = 0;
  double max_penetration = 0.0;
};

DropArrays to_arrays(const DropResult& r) {
  const auto n = static_cast<Eigen::Index>(r.objects.size());
  Eigen::Matrix<double, Eigen::Dynamic, 16, Eigen::RowMajor> X(n, 16), X0(n, 16);
  std::vector<std::int32_t> status(r.objects.size());
  std::vector<std::uint8_t> settled(r.objects.size());
  std::vector<std::uint32_t> contacts(r.objects.size());
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& d = r.objects[static_cast<std::size_t>(i)];
    for (int k = 0; k < 16; ++k) {
      X(i, k) = d.X_WO.matrix()(k / 4, k % 4);
      X0(i, k) = d.X_WO_release.matrix()(k / 4, k % 4);
    }
    status[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(d.status);
    settled[static_cast<std::size_t>(i)] = d.settled ? 1 : 0;
    contacts[static_cast<std::size_t>(i)] = d.contacts;
  }
  DropArrays out;
  out.X_WO = to_numpy(std::move(X)).attr("reshape")(n, 4, 4);
  out.X_WO_release = to_numpy(std::move(X0)).attr("reshape")(n, 4, 4);
  out.status = to_numpy(std::move(status));
  out.object_settled = to_bool_numpy(std::move(settled));
  out.contacts = to_numpy(std::move(contacts));
  out.steps = r.steps;
  out.simulated_time = r.simulated_time;
  out.settled = r.settled;
  out.resettle_rounds = r.resettle_rounds;
  out.max_penetration = r.max_penetration;
  return out;
}

void bind_options(py::module_& m) {
  using Window = std::tuple<double, double, double>;
  auto window_get = [](const Vec3d& v) { return Window{v.x(), v.y(), v.z()}; };
  py::class_<DropOptions>(m, "DropOptions",
                          "Options of drop_objects (mgn/scene/drop.hpp, SI units); the defaults "
                          "are the C++ struct's, validate() checks the ranges.")
      .def(py::init<>())
      .def_property(
          "window_min", [=](const DropOptions& o) { return window_get(o.window_min); },
          [](DropOptions& o, const Window& w) {
            o.window_min = Vec3d(std::get<0>(w), std::get<1>(w), std::get<2>(w));
          })
      .def_property(
          "window_max", [=](const DropOptions& o) { return window_get(o.window_max); },
          [](DropOptions& o, const Window& w) {
            o.window_max = Vec3d(std::get<0>(w), std::get<1>(w), std::get<2>(w));
          })
      .def_readwrite("dt", &DropOptions::dt)
      .def_readwrite("solver_iterations", &DropOptions::solver_iterations)
      .def_readwrite("max_time", &DropOptions::max_time)
      .def_readwrite("linear_rest", &DropOptions::linear_rest)
      .def_readwrite("angular_rest", &DropOptions::angular_rest)
      .def_readwrite("rest_time", &DropOptions::rest_time)
      .def_readwrite("gravity", &DropOptions::gravity)
      .def_readwrite("rolling_friction", &DropOptions::rolling_friction)
      .def_readwrite("angular_damping", &DropOptions::angular_damping)
      .def_readwrite("tote_friction", &DropOptions::tote_friction)
      .def_readwrite("tote_restitution", &DropOptions::tote_restitution)
      .def_readwrite("collision_margin", &DropOptions::collision_margin)
      .def_readwrite("contact_distance", &DropOptions::contact_distance)
      .def_readwrite("remove_unsettled", &DropOptions::remove_unsettled)
      .def_readwrite("max_hull_vertices", &DropOptions::max_hull_vertices)
      .def_readwrite("hull_tolerance", &DropOptions::hull_tolerance)
      .def_readwrite("polyhedral_contacts", &DropOptions::polyhedral_contacts)
      .def_readwrite("resettle_time", &DropOptions::resettle_time)
      .def_readwrite("two_friction_directions", &DropOptions::two_friction_directions)
      .def_readwrite("guard_height", &DropOptions::guard_height)
      .def_property(
          "tote_collision",
          [](const DropOptions& o) {
            return std::string(o.tote_collision == ToteCollision::Boxes ? "boxes" : "mesh");
          },
          [](DropOptions& o, const std::string& mode) {
            if (mode == "boxes")
              o.tote_collision = ToteCollision::Boxes;
            else if (mode == "mesh")
              o.tote_collision = ToteCollision::TriangleMesh;
            else
              throw_error<InvalidArgument>(
                  "DropOptions.tote_collision must be 'boxes' or 'mesh', got '", mode, "'");
          })
      .def_readwrite("seed", &DropOptions::seed)
      .def(
          "validate", [](const DropOptions& o) { validate(o); },
          "Raises InvalidArgumentError naming the first field out of its range.");

  py::class_<DropArrays>(m, "DropResult",
                         "drop_objects() result: one row per input object, in input order.")
      .def_readonly("X_WO", &DropArrays::X_WO, "(N,4,4) float64 settled poses, m")
      .def_readonly("X_WO_release", &DropArrays::X_WO_release,
                    "(N,4,4) float64 release (or start) poses, m")
      .def_readonly("status", &DropArrays::status,
                    "(N,) int32: 0 kept, 1 left the tote, 2 not settled")
      .def_readonly("object_settled", &DropArrays::object_settled,
                    "(N,) bool: at rest when the simulation stopped")
      .def_readonly("contacts", &DropArrays::contacts,
                    "(N,) uint32 tote contact flags (bits -x, +x, -y, +y walls, floor)")
      .def_readonly("steps", &DropArrays::steps)
      .def_readonly("simulated_time", &DropArrays::simulated_time, "s")
      .def_readonly("settled", &DropArrays::settled, "every remaining object came to rest")
      .def_readonly("resettle_rounds", &DropArrays::resettle_rounds)
      .def_readonly("max_penetration", &DropArrays::max_penetration,
                    "deepest contact penetration on the simulated hulls, m");
}

}  // namespace

void bind_scene_drop(py::module_& m) {
  bind_options(m);

  m.def(
      "drop_objects",
      [](const std::vector<std::vector<Mesh>>& parts, const std::vector<double>& mass,
         const py::handle& coms, const py::handle& inertias, const std::vector<double>& mu,
         const std::vector<double>& e, const std::vector<std::string>& names, const Mesh& tote,
         const std::vector<double>& tote_box, const DropOptions& options,
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
          r = X_WO_start.is_none() ? drop_objects(objects, tote, box, options)
                                   : settle_objects(objects, start, tote, box, options);
        }
        return to_arrays(r);
      },
      py::arg("parts"), py::arg("masses"), py::arg("coms"), py::arg("inertias"),
      py::arg("frictions"), py::arg("restitutions"), py::arg("names"), py::arg("tote"),
      py::arg("tote_box"), py::arg("options"), py::arg("X_WO_start") = py::none());

  py::class_<DropHullCacheInfo>(m, "DropHullCacheInfo",
                                "State of the drop's cache of prepared object hulls "
                                "(mgn/scene/drop.hpp).")
      .def_readonly("entries", &DropHullCacheInfo::entries)
      .def_readonly("bytes", &DropHullCacheInfo::bytes, "estimated memory of the entries")
      .def_readonly("capacity", &DropHullCacheInfo::capacity, "bytes; 0: nothing is cached")
      .def_readonly("hits", &DropHullCacheInfo::hits,
                    "objects whose hulls came from the cache (since the last clear)")
      .def_readonly("misses", &DropHullCacheInfo::misses,
                    "objects whose hulls were prepared (since the last clear)")
      .def_readonly("evictions", &DropHullCacheInfo::evictions,
                    "entries evicted for the capacity (since the last clear)");
  m.def("drop_hull_cache_info", &drop_hull_cache_info,
        "The state of the drop's cache of prepared object hulls (mgn/scene/drop.hpp).");
  m.def("clear_drop_hull_cache", &clear_drop_hull_cache,
        "Drops every entry of the drop's hull cache and resets its counters.");
  m.def(
      "set_drop_hull_cache_capacity",
      [](std::int64_t bytes) {
        if (bytes < 0)
          throw_error<InvalidArgument>(
              "set_drop_hull_cache_capacity: bytes must be >= 0 (0: cache nothing), got ", bytes);
        set_drop_hull_cache_capacity(static_cast<std::size_t>(bytes));
      },
      py::arg("bytes"),
      "Sets the capacity of the drop's hull cache (estimated bytes; 0: cache nothing) and evicts "
      "the least recently used entries down to it.");
}

}  // namespace mgn::py_bind
