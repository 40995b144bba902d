#include <pybind11/stl.h>
#include <mgn/collision/collision_model.hpp>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

/// DistanceResult as numpy arrays (moved, no copies).
struct DistanceArrays {
  py::array distance, points_a, points_b, collide;
};

}  // namespace

void bind_collision(py::module_& m) {
  py::class_<DistanceArrays>(m, "DistanceResult",
                             "distance() result (mgn/collision/collision_model.hpp), one row per "
                             "pose pair.")
      .def_readonly("distance", &DistanceArrays::distance,
                    "(N,) float64 m, 0 for intersecting pairs")
      .def_readonly("points_a", &DistanceArrays::points_a,
                    "(N,3) float64 closest point on A, world frame")
      .def_readonly("points_b", &DistanceArrays::points_b,
                    "(N,3) float64 closest point on B, world frame")
      .def_readonly("collide", &DistanceArrays::collide, "(N,) bool");

  py::class_<CollisionModel, std::shared_ptr<CollisionModel>>(
      m, "CollisionModel", "Immutable FCL BVH (OBBRSS) of a mesh.")
      .def(py::init([](const Mesh& mesh) {
             py::gil_scoped_release release;
             return std::make_shared<CollisionModel>(mesh);
           }),
           py::arg("mesh"))
      .def_property_readonly("num_triangles", &CollisionModel::num_triangles)
      .def_property_readonly("num_vertices", &CollisionModel::num_vertices);

  m.def(
      "collide",
      [](const CollisionModel& a, const py::handle& X_WA, const CollisionModel& b,
         const py::handle& X_WB, int num_threads) {
        const auto xa = to_poses(X_WA, "X_WA");
        const auto xb = to_poses(X_WB, "X_WB");
        CollisionRequest req;
        req.num_threads = num_threads;
        std::vector<std::uint8_t> hit;
        {
          py::gil_scoped_release release;
          hit = collide(a, xa, b, xb, req);
        }
        return to_bool_numpy(std::move(hit));
      },
      py::arg("a"), py::arg("X_WA"), py::arg("b"), py::arg("X_WB"),
      py::arg("num_threads") = CollisionRequest{}.num_threads);

  m.def(
      "distance",
      [](const CollisionModel& a, const py::handle& X_WA, const CollisionModel& b,
         const py::handle& X_WB, double rel_err, double abs_err, int num_threads) {
        const auto xa = to_poses(X_WA, "X_WA");
        const auto xb = to_poses(X_WB, "X_WB");
        DistanceRequest req;
        req.rel_err = rel_err;
        req.abs_err = abs_err;
        req.num_threads = num_threads;
        DistanceResult r;
        {
          py::gil_scoped_release release;
          r = distance(a, xa, b, xb, req);
        }
        return DistanceArrays{to_numpy(std::move(r.distance)), to_numpy(std::move(r.points_a)),
                              to_numpy(std::move(r.points_b)), to_bool_numpy(std::move(r.collide))};
      },
      py::arg("a"), py::arg("X_WA"), py::arg("b"), py::arg("X_WB"),
      py::arg("rel_err") = DistanceRequest{}.rel_err,
      py::arg("abs_err") = DistanceRequest{}.abs_err,
      py::arg("num_threads") = DistanceRequest{}.num_threads);
}

}  // namespace mgn::py_bind
