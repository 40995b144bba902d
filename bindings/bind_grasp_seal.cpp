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
             int num_trials, double angle_sigma, double position_sigma, bool perturb,
             double on_surface_tolerance, std::uint64_t seed, std::uint64_t first_index,
             int num_threads) {
            const Points3f p = to_rows<float, 3>(points, "points");
            const Points3f n = to_rows<float, 3>(normals, "normals");
            SealOptions o;
            o.num_trials = num_trials;
            o.angle_sigma = angle_sigma;
            o.position_sigma = position_sigma;
            o.perturb = perturb;
            o.on_surface_tolerance = on_surface_tolerance;
            o.seed = seed;
            o.first_index = first_index;
            o.num_threads = num_threads;
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
          py::arg("points"), py::arg("normals"), py::arg("num_trials") = 10,
          py::arg("angle_sigma") = 0.1, py::arg("position_sigma") = -1.0, py::arg("perturb") = true,
          py::arg("on_surface_tolerance") = 1e-3, py::arg("seed") = 0, py::arg("first_index") = 0,
          py::arg("num_threads") = 0)
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
         const Vec3d& gravity_direction, double cup_radius, double k, double gravity) {
        const Points3f c = to_rows<float, 3>(contacts, "contacts");
        const Points3f a = to_rows<float, 3>(approach, "approach");
        SuctionWrenchOptions o;
        o.k = k;
        o.gravity = gravity;
        return to_numpy(suction_wrench_scores(c, a, mass, com, gravity_direction, cup_radius, o));
      },
      py::arg("contacts"), py::arg("approach"), py::arg("mass"), py::arg("com"),
      py::arg("gravity_direction"), py::arg("cup_radius"), py::arg("k") = 15.6,
      py::arg("gravity") = 9.81);
}

}  // namespace mgn::py_bind
