#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <mgn/grasp/cup.hpp>
#include <mgn/grasp/seal_model.hpp>
#include <mgn/grasp/wrench.hpp>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

SealModelKind parse_kind(const std::string& name) {
  if (name == "spring") return SealModelKind::Spring;
  if (name == "strain") return SealModelKind::Strain;
  if (name == "smoothness") return SealModelKind::Smoothness;
  throw_error<InvalidArgument>("SealModel: model must be 'spring', 'strain' or 'smoothness', got '",
                               name, "'");
}

const char* kind_name(SealModelKind k) {
  switch (k) {
    case SealModelKind::Spring:
      return "spring";
    case SealModelKind::Strain:
      return "strain";
    case SealModelKind::Smoothness:
      return "smoothness";
  }
  return "unknown";
}

/// SealResult as numpy arrays (moved, no copies); trial arrays (count, num_trials).
struct SealArrays {
  py::array score, quality, reason, trial_sealed, trial_reason;
};

/// SealTrial with its arrays as numpy.
struct TrialArrays {
  std::string failure;
  py::array ring_points, ring_normals, elastic_force, ring_force;
  Vec3d center = Vec3d::Zero();
  double total_elastic_force = 0.0;
};

}  // namespace

void bind_grasp_seal(py::module_& m) {
  py::class_<SealArrays>(m, "SealResult",
                         "SealModel.evaluate() result (mgn/grasp/seal_model.hpp); "
                         "mgn.suction.seal.SealResult documents each array.")
      .def_readonly("score", &SealArrays::score)
      .def_readonly("quality", &SealArrays::quality)
      .def_readonly("reason", &SealArrays::reason)
      .def_readonly("trial_sealed", &SealArrays::trial_sealed)
      .def_readonly("trial_reason", &SealArrays::trial_reason);
  py::class_<TrialArrays>(m, "SealTrial",
                          "SealModel.trial() result: failure name, projected ring (object "
                          "frame, m), spring forces (N).")
      .def_readonly("failure", &TrialArrays::failure)
      .def_readonly("ring_points", &TrialArrays::ring_points, "(N,3) float32")
      .def_readonly("ring_normals", &TrialArrays::ring_normals, "(N,3) float32")
      .def_readonly("center", &TrialArrays::center, "projected centre, m")
      .def_readonly("elastic_force", &TrialArrays::elastic_force, "(N,) float64, N")
      .def_readonly("ring_force", &TrialArrays::ring_force, "(N,3) float64, N")
      .def_readonly("total_elastic_force", &TrialArrays::total_elastic_force, "N");

  py::class_<SealOptions>(m, "SealOptions",
                          "Options of SealModel.evaluate (mgn/grasp/seal_model.hpp, SI units); the "
                          "defaults are the C++ struct's, validate() checks the ranges.")
      .def(py::init<>())
      .def_readwrite("num_trials", &SealOptions::num_trials, "perturbed trials per candidate")
      .def_readwrite("angle_sigma", &SealOptions::angle_sigma,
                     "std of each Euler angle of the normal perturbation, rad")
      .def_readwrite("position_sigma", &SealOptions::position_sigma,
                     "std of the point jitter per axis, m (< 0: cup radius / 4)")
      .def_readwrite("perturb", &SealOptions::perturb,
                     "false: one deterministic trial at the nominal pose")
      .def_readwrite("on_surface_tolerance", &SealOptions::on_surface_tolerance,
                     "candidates must lie on the mesh within this distance along the normal, m")
      .def_readwrite("seed", &SealOptions::seed)
      .def_readwrite("first_index", &SealOptions::first_index,
                     "candidate i draws from the stream (seed, first_index + i)")
      .def_readwrite("num_threads", &SealOptions::num_threads, "0 = all hardware threads")
      .def("validate", &SealOptions::validate,
           "Raises InvalidArgumentError naming the first field out of its range.");

  py::class_<SuctionWrenchOptions>(
      m, "SuctionWrenchOptions",
      "Constants of suction_wrench_scores (mgn/grasp/wrench.hpp); the defaults are the C++ "
      "struct's, validate() checks the ranges.")
      .def(py::init<>())
      .def_readwrite("k", &SuctionWrenchOptions::k,
                     "tau_max = k * cup radius * pi * sqrt(2) (k in N, radius in m)")
      .def_readwrite("gravity", &SuctionWrenchOptions::gravity, "m/s^2")
      .def("validate", &SuctionWrenchOptions::validate,
           "Raises InvalidArgumentError naming the first field out of its range.");

  py::class_<Cup>(m, "Cup",
                  "Suction cup parameters for the seal models (SI units; see mgn.SuctionCup).")
      .def(py::init<>())
      .def_readwrite("name", &Cup::name)
      .def_readwrite("radius", &Cup::radius)
      .def_readwrite("num_points", &Cup::num_points)
      .def_readwrite("youngs_modulus", &Cup::youngs_modulus)
      .def_readwrite("pressure_difference", &Cup::pressure_difference)
      .def_readwrite("compensable_height", &Cup::compensable_height)
      .def_readwrite("approach_height", &Cup::approach_height)
      .def_readwrite("c1", &Cup::c1)
      .def_readwrite("c2", &Cup::c2)
      .def_readwrite("outer_radius", &Cup::outer_radius)
      .def_readwrite("body_height", &Cup::body_height)
      .def_readwrite("hole_rays", &Cup::hole_rays)
      .def("validate", &Cup::validate)
      .def("pressure_force", &Cup::pressure_force)
      .def("compression_stiffness", &Cup::compression_stiffness);

  py::list names;
  for (int f = 0; f <= static_cast<int>(SealFailure::Rough); ++f)
    names.append(failure_name(static_cast<SealFailure>(f)));
  m.attr("SEAL_FAILURE_NAMES") = py::tuple(names);

  py::class_<SealModel, std::shared_ptr<SealModel>>(
      m, "SealModel", "Immutable seal model of one object for one cup.")
      .def(py::init([](const Mesh& mesh, const Cup& cup, const std::string& model) {
             const SealModelKind kind = parse_kind(model);
             py::gil_scoped_release release;
             return std::make_shared<SealModel>(mesh, cup, kind);
           }),
           py::arg("mesh"), py::arg("cup"), py::arg("model") = "spring")
      .def_property_readonly("model", [](const SealModel& s) { return kind_name(s.kind()); })
      .def_property_readonly("cup", &SealModel::cup)
      .def(
          "evaluate",
          [](const SealModel& s, const py::handle& points, const py::handle& normals,
             const SealOptions& o) {
            const Points3f p = to_rows<float, 3>(points, "points");
            const Points3f n = to_rows<float, 3>(normals, "normals");
            SealResult r;
            {
              py::gil_scoped_release release;
              r = s.evaluate(p, n, o);
            }
            const auto count = static_cast<py::ssize_t>(r.score.size());
            const int T = r.num_trials;
            SealArrays out;
            out.score = to_numpy(std::move(r.score));
            out.quality = to_numpy(std::move(r.quality));
            out.reason = to_numpy(std::move(r.reason));
            out.trial_sealed = to_bool_numpy(std::move(r.trial_sealed)).attr("reshape")(count, T);
            out.trial_reason = to_numpy(std::move(r.trial_reason)).attr("reshape")(count, T);
            return out;
          },
          py::arg("points"), py::arg("normals"),
          py::arg_v("options", SealOptions{}, "SealOptions()"),
          "Seal scores of (N,3) candidates (object frame, m; unit outward normals).")
      .def(
          "trial",
          [](const SealModel& s, const Vec3d& point, const Vec3d& normal) {
            SealTrial t;
            {
              py::gil_scoped_release release;
              t = s.trial(point, normal);
            }
            TrialArrays out;
            out.failure = failure_name(t.failure);
            out.ring_points = to_numpy(std::move(t.ring_points));
            out.ring_normals = to_numpy(std::move(t.ring_normals));
            out.center = t.center;
            out.elastic_force = to_numpy(Eigen::VectorXd(t.elastic_force));
            out.ring_force = to_numpy(std::move(t.ring_force));
            out.total_elastic_force = t.total_elastic_force;
            return out;
          },
          py::arg("point"), py::arg("normal"))
      .def(
          "with_cup",
          [](const SealModel& s, const Cup& cup) {
            return std::const_pointer_cast<SealModel>(s.with_cup(cup));
          },
          py::arg("cup"));

  m.def(
      "suction_wrench_scores",
      [](const py::handle& contacts, const py::handle& approach, double mass, const Vec3d& com,
         const Vec3d& gravity_direction, double cup_radius, const SuctionWrenchOptions& o) {
        const Points3f c = to_rows<float, 3>(contacts, "contacts");
        const Points3f a = to_rows<float, 3>(approach, "approach");
        return to_numpy(suction_wrench_scores(c, a, mass, com, gravity_direction, cup_radius, o));
      },
      py::arg("contacts"), py::arg("approach"), py::arg("mass"), py::arg("com"),
      py::arg("gravity_direction"), py::arg("cup_radius"),
      py::arg_v("options", SuctionWrenchOptions{}, "SuctionWrenchOptions()"));
}

}  // namespace mgn::py_bind
