// Cup calibration (mgn/grasp/calibration.hpp): calibrate_cup, predict_experiments,
// classification_metrics. Experiments cross the boundary as parallel arrays; cups as
// mgn._core.grasp.Cup (bound in bind_grasp_seal.cpp; mgn.suction.core_cup converts a SuctionCup).
#include <pybind11/stl.h>
#include <mgn/grasp/calibration.hpp>

#include <string>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

/// (N,) integer array; names `arg` in errors.
std::vector<std::int64_t> to_int_vector(const py::handle& obj, const char* arg, Eigen::Index n) {
  CArray<std::int64_t> a;
  try {
    a = py::cast<CArray<std::int64_t>>(obj);
  } catch (const py::cast_error&) {
    throw_error<InvalidArgument>(arg, ": expected an integer array of shape (", n, ",)");
  }
  if (a.ndim() != 1 || a.shape(0) != n) {
    throw_error<InvalidArgument>(arg, ": expected shape (", n,
                                 ",) (one entry per experiment), got ", a.ndim(), "-D array of ",
                                 a.size(), " entries");
  }
  return {a.data(), a.data() + a.size()};
}

std::vector<CalibrationExperiment> to_experiments(const py::handle& surface_index,
                                                  const py::handle& points,
                                                  const py::handle& normals,
                                                  const py::handle* sealed) {
  const Points3d p = to_rows<double, 3>(points, "points");
  const Points3d n = to_rows<double, 3>(normals, "normals");
  if (n.rows() != p.rows()) {
    throw_error<InvalidArgument>("normals: expected shape (", p.rows(), ", 3) like points, got (",
                                 n.rows(), ", 3)");
  }
  const std::vector<std::int64_t> s = to_int_vector(surface_index, "surface_index", p.rows());
  std::vector<std::int64_t> y;
  if (sealed) y = to_int_vector(*sealed, "sealed", p.rows());
  std::vector<CalibrationExperiment> out(static_cast<std::size_t>(p.rows()));
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (s[i] < 0) throw_error<InvalidArgument>("surface_index[", i, "]: expected >= 0, got ", s[i]);
    out[i].surface = static_cast<std::size_t>(s[i]);
    out[i].point = p.row(static_cast<Eigen::Index>(i)).transpose();
    out[i].normal = n.row(static_cast<Eigen::Index>(i)).transpose();
    if (sealed) {
      if (y[i] != 0 && y[i] != 1)
        throw_error<InvalidArgument>("sealed[", i, "]: expected 0 or 1, got ", y[i]);
      out[i].sealed = y[i] == 1;
    }
  }
  return out;
}

/// CalibrationResult with its arrays as numpy (moved, no copies).
struct CalibrationArrays {
  Cup cup;
  double objective = 0.0;
  int evaluations = 0;
  ClassificationMetrics train, test;
  py::array train_indices, test_indices, predicted;
};

py::array indices_to_numpy(const std::vector<std::size_t>& idx) {
  std::vector<std::int64_t> v(idx.begin(), idx.end());
  return to_numpy(std::move(v));
}

}  // namespace

void bind_grasp_calibration(py::module_& m) {
  py::class_<ClassificationMetrics>(m, "ClassificationMetrics",
                                    "Confusion counts and rates (mgn/grasp/calibration.hpp); "
                                    "NaN for a zero denominator.")
      .def_readonly("tp", &ClassificationMetrics::tp)
      .def_readonly("fp", &ClassificationMetrics::fp)
      .def_readonly("tn", &ClassificationMetrics::tn)
      .def_readonly("fn", &ClassificationMetrics::fn)
      .def_readonly("ppv", &ClassificationMetrics::ppv, "tp / (tp + fp), precision")
      .def_readonly("npv", &ClassificationMetrics::npv, "tn / (tn + fn)")
      .def_readonly("sensitivity", &ClassificationMetrics::sensitivity, "tp / (tp + fn)")
      .def_readonly("specificity", &ClassificationMetrics::specificity, "tn / (tn + fp)")
      .def_readonly("accuracy", &ClassificationMetrics::accuracy, "(tp + tn) / count")
      .def(
          "to_dict",
          [](const ClassificationMetrics& c) {
            py::dict d;  // the JSON form (mgn calibrate writes it)
            d["tp"] = c.tp;
            d["fp"] = c.fp;
            d["tn"] = c.tn;
            d["fn"] = c.fn;
            d["ppv"] = c.ppv;
            d["npv"] = c.npv;
            d["sensitivity"] = c.sensitivity;
            d["specificity"] = c.specificity;
            d["accuracy"] = c.accuracy;
            return d;
          },
          "{name: value} of the fields above, for JSON.");

  py::class_<CalibrationArrays>(m, "CalibrationResult",
                                "calibrate_cup() result (mgn/grasp/calibration.hpp).")
      .def_readonly("cup", &CalibrationArrays::cup, "the initial cup with the fitted c1, c2")
      .def_readonly("objective", &CalibrationArrays::objective,
                    "training accuracy of the fitted cup")
      .def_readonly("evaluations", &CalibrationArrays::evaluations)
      .def_readonly("train", &CalibrationArrays::train)
      .def_readonly("test", &CalibrationArrays::test)
      .def_readonly("train_indices", &CalibrationArrays::train_indices, "(T,) int64 ascending")
      .def_readonly("test_indices", &CalibrationArrays::test_indices, "(H,) int64 ascending")
      .def_readonly("predicted", &CalibrationArrays::predicted,
                    "(N,) bool nominal prediction of the fitted cup");

  const CalibrationOptions defaults;
  m.def(
      "calibrate_cup",
      [](const std::vector<const Mesh*>& surfaces, const py::handle& surface_index,
         const py::handle& points, const py::handle& normals, const py::handle& sealed,
         const Cup& initial, double c1_min, double c1_max, double c2_min, double c2_max,
         int global_evaluations, int local_evaluations, double xtol_rel, double ftol_abs,
         double holdout_fraction, std::uint64_t seed, int num_threads) {
        const auto experiments = to_experiments(surface_index, points, normals, &sealed);
        CalibrationOptions o;
        o.c1_min = c1_min;
        o.c1_max = c1_max;
        o.c2_min = c2_min;
        o.c2_max = c2_max;
        o.global_evaluations = global_evaluations;
        o.local_evaluations = local_evaluations;
        o.xtol_rel = xtol_rel;
        o.ftol_abs = ftol_abs;
        o.holdout_fraction = holdout_fraction;
        o.seed = seed;
        o.num_threads = num_threads;
        CalibrationResult r;
        {
          py::gil_scoped_release release;
          r = calibrate_cup(surfaces, experiments, initial, o);
        }
        return CalibrationArrays{r.cup,
                                 r.objective,
                                 r.evaluations,
                                 r.train,
                                 r.test,
                                 indices_to_numpy(r.train_indices),
                                 indices_to_numpy(r.test_indices),
                                 to_bool_numpy(std::move(r.predicted))};
      },
      "Fit c1, c2 of the cup to measured outcomes (see mgn.calibration.fit).", py::arg("surfaces"),
      py::arg("surface_index"), py::arg("points"), py::arg("normals"), py::arg("sealed"),
      py::arg("cup"), py::arg("c1_min") = defaults.c1_min, py::arg("c1_max") = defaults.c1_max,
      py::arg("c2_min") = defaults.c2_min, py::arg("c2_max") = defaults.c2_max,
      py::arg("global_evaluations") = defaults.global_evaluations,
      py::arg("local_evaluations") = defaults.local_evaluations,
      py::arg("xtol_rel") = defaults.xtol_rel, py::arg("ftol_abs") = defaults.ftol_abs,
      py::arg("holdout_fraction") = defaults.holdout_fraction, py::arg("seed") = defaults.seed,
      py::arg("num_threads") = defaults.num_threads);

  m.def(
      "predict_experiments",
      [](const std::vector<const Mesh*>& surfaces, const py::handle& surface_index,
         const py::handle& points, const py::handle& normals, const Cup& c, int num_threads) {
        const auto experiments = to_experiments(surface_index, points, normals, nullptr);
        std::vector<std::uint8_t> pred;
        {
          py::gil_scoped_release release;
          pred = predict_experiments(surfaces, experiments, c, num_threads);
        }
        return to_bool_numpy(std::move(pred));
      },
      "Nominal spring-model seal prediction (bool per experiment) for a cup.", py::arg("surfaces"),
      py::arg("surface_index"), py::arg("points"), py::arg("normals"), py::arg("cup"),
      py::arg("num_threads") = 0);

  m.def(
      "classification_metrics",
      [](const std::vector<bool>& predicted, const std::vector<bool>& measured) {
        const std::vector<std::uint8_t> p(predicted.begin(), predicted.end());
        const std::vector<std::uint8_t> y(measured.begin(), measured.end());
        return classification_metrics(p, y);
      },
      "Confusion counts and PPV, NPV, sensitivity, specificity, accuracy (NaN for a zero "
      "denominator).",
      py::arg("predicted"), py::arg("measured"));
}

}  // namespace mgn::py_bind
