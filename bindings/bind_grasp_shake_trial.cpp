// Bindings of the Bullet shake test (mgn/grasp/shake_trial.hpp). The typed façade is
// python/mgn/pj/physics.py. The gripper is the bound C++ ParallelJawGripper (boxes or the three
// meshes), made by the one conversion mgn.pj.sampler.core_gripper() like every other consumer.
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/stl.h>
#include <mgn/grasp/shake_trial.hpp>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

/// (N, 10) rows [a (3), v (3), p1 (3), w] in metres (MetaGraspNet order, SI units).
std::vector<ParallelJawGrasp> grasps_from(const py::handle& obj) {
  const auto rows = to_rows<double, 10>(obj, "grasps");
  std::vector<ParallelJawGrasp> out(static_cast<std::size_t>(rows.rows()));
  for (Eigen::Index i = 0; i < rows.rows(); ++i) {
    out[i].approach = rows.row(i).segment<3>(0).transpose();
    out[i].closing = rows.row(i).segment<3>(3).transpose();
    out[i].p1 = rows.row(i).segment<3>(6).transpose();
    out[i].width = rows(i, 9);
  }
  return out;
}

PhysicsObject object_from(std::vector<Mesh> parts, double mass, const Vec3d& com,
                          const Mat3d& inertia) {
  PhysicsObject o;
  o.convex_parts = std::move(parts);
  o.mass = mass;
  o.com = com;
  o.inertia = inertia;
  return o;
}

/// ShakeResult as numpy arrays (moved, no copies); per-trial arrays shaped (G, S, S).
struct ShakeArrays {
  py::array score, trial_success, trial_ended_early, trial_steps, frictions, density_factors,
      trial_simulated, fallback;
  long long total_steps = 0;
};

/// StaircaseGrid as numpy arrays shaped (S, S).
struct StaircaseArrays {
  py::array success, simulated;
  bool fallback = false;
  int trials = 0;
};

/// ShakeTrajectory as numpy arrays, one row per recorded step.
struct TrajectoryArrays {
  py::array time, phase, X_WO, X_WH, finger_left, finger_right, contact_left, contact_right,
      force_left, force_right;
  bool success = false, ended_early = false;
  int steps = 0;
  double friction = 0.0, density_factor = 0.0;
};

}  // namespace

void bind_grasp_shake_trial(py::module_& m) {
  py::class_<ShakeOptions>(m, "ShakeOptions",
                           "Options of the Bullet shake test (SI units; see mgn.pj.physics).")
      .def(py::init<>())
      .def_readwrite("grid", &ShakeOptions::grid)
      .def_readwrite("friction_min", &ShakeOptions::friction_min)
      .def_readwrite("friction_max", &ShakeOptions::friction_max)
      .def_readwrite("density_min", &ShakeOptions::density_min)
      .def_readwrite("density_max", &ShakeOptions::density_max)
      .def_readwrite("dt", &ShakeOptions::dt)
      .def_readwrite("close_steps", &ShakeOptions::close_steps)
      .def_readwrite("shake_steps", &ShakeOptions::shake_steps)
      .def_readwrite("rotate_steps", &ShakeOptions::rotate_steps)
      .def_readwrite("gravity", &ShakeOptions::gravity)
      .def_readwrite("shake_speed", &ShakeOptions::shake_speed)
      .def_readwrite("shake_cycles", &ShakeOptions::shake_cycles)
      .def_readwrite("angle_min", &ShakeOptions::angle_min)
      .def_readwrite("angle_max", &ShakeOptions::angle_max)
      .def_readwrite("rotate_cycles", &ShakeOptions::rotate_cycles)
      .def_readwrite("grip_force", &ShakeOptions::grip_force)
      .def_readwrite("close_speed", &ShakeOptions::close_speed)
      .def_readwrite("pad_stiffness", &ShakeOptions::pad_stiffness)
      .def_readwrite("pad_damping", &ShakeOptions::pad_damping)
      .def_readwrite("controller_stiffness", &ShakeOptions::controller_stiffness)
      .def_readwrite("inertia_floor", &ShakeOptions::inertia_floor)
      .def_readwrite("contact_distance", &ShakeOptions::contact_distance)
      .def_readwrite("settle_steps", &ShakeOptions::settle_steps)
      .def_readwrite("limit_controller_gain", &ShakeOptions::limit_controller_gain)
      .def_readwrite("adapt_controller_gain", &ShakeOptions::adapt_controller_gain)
      .def_readwrite("controller_net_force", &ShakeOptions::controller_net_force)
      .def_readwrite("lost_contact_steps", &ShakeOptions::lost_contact_steps)
      .def_readwrite("hold_tolerance", &ShakeOptions::hold_tolerance)
      .def_readwrite("smooth_shake", &ShakeOptions::smooth_shake)
      .def_readwrite("margin", &ShakeOptions::margin)
      .def_readwrite("polyhedral_contacts", &ShakeOptions::polyhedral_contacts)
      .def_readwrite("max_hull_vertices", &ShakeOptions::max_hull_vertices)
      .def_readwrite("solver_iterations", &ShakeOptions::solver_iterations)
      .def_readwrite("compound_solver_iterations", &ShakeOptions::compound_solver_iterations)
      .def_readwrite("compound_iteration_points", &ShakeOptions::compound_iteration_points)
      .def_readwrite("iterations_per_hull_contact", &ShakeOptions::iterations_per_hull_contact)
      .def_readwrite("staircase", &ShakeOptions::staircase)
      .def_readwrite("staircase_checks", &ShakeOptions::staircase_checks)
      .def_readwrite("staircase_verify_share", &ShakeOptions::staircase_verify_share)
      .def("staircase_verified_rows", &ShakeOptions::staircase_verified_rows,
           "Rows whose boundary the staircase verifies: ceil(staircase_verify_share * grid).")
      .def_readwrite("num_threads", &ShakeOptions::num_threads)
      .def_readwrite("seed", &ShakeOptions::seed)
      .def_readwrite("first_grasp_index", &ShakeOptions::first_grasp_index)
      .def("validate", &ShakeOptions::validate)
      .def("frictions", &ShakeOptions::frictions)
      .def("density_factors", &ShakeOptions::density_factors);

  py::class_<ShakeArrays>(m, "ShakeResult",
                          "shake_test() result (mgn/grasp/shake_trial.hpp): G grasps on an S x S "
                          "friction x density grid.")
      .def_readonly("score", &ShakeArrays::score, "(G,) float64 success fraction over the grid")
      .def_readonly("trial_success", &ShakeArrays::trial_success,
                    "(G, S, S) bool [grasp][friction i][density j]")
      .def_readonly("trial_ended_early", &ShakeArrays::trial_ended_early, "(G, S, S) bool")
      .def_readonly("trial_steps", &ShakeArrays::trial_steps, "(G, S, S) int steps simulated")
      .def_readonly("frictions", &ShakeArrays::frictions, "(S,) friction coefficients")
      .def_readonly("density_factors", &ShakeArrays::density_factors, "(S,) density factors")
      .def_readonly("trial_simulated", &ShakeArrays::trial_simulated,
                    "(G, S, S) bool: simulated (else inferred by the staircase search)")
      .def_readonly("fallback", &ShakeArrays::fallback,
                    "(G,) bool: a staircase check failed and the full grid was simulated")
      .def_readonly("total_steps", &ShakeArrays::total_steps, "simulation steps of all trials");

  py::class_<StaircaseArrays>(m, "StaircaseGridResult",
                              "staircase_grid() result: success and simulated (S, S) bool "
                              "[friction i][density j], fallback, trials.")
      .def_readonly("success", &StaircaseArrays::success, "(S, S) bool")
      .def_readonly("simulated", &StaircaseArrays::simulated, "(S, S) bool: trial() was called")
      .def_readonly("fallback", &StaircaseArrays::fallback,
                    "a check contradicted its inference: every cell was simulated")
      .def_readonly("trials", &StaircaseArrays::trials, "calls of trial()");

  py::class_<TrajectoryArrays>(m, "ShakeTrajectoryResult",
                               "shake_trajectory() result, one row per recorded step (world W: "
                               "z up; poses (K, 4, 4) m).")
      .def_readonly("time", &TrajectoryArrays::time, "(K,) s since the start")
      .def_readonly("phase", &TrajectoryArrays::phase, "(K,) int8 ShakePhase")
      .def_readonly("X_WO", &TrajectoryArrays::X_WO, "(K, 4, 4) object pose")
      .def_readonly("X_WH", &TrajectoryArrays::X_WH, "(K, 4, 4) hand pose")
      .def_readonly("finger_left", &TrajectoryArrays::finger_left, "(K,) finger opening, m")
      .def_readonly("finger_right", &TrajectoryArrays::finger_right, "(K,) finger opening, m")
      .def_readonly("contact_left", &TrajectoryArrays::contact_left, "(K,) bool")
      .def_readonly("contact_right", &TrajectoryArrays::contact_right, "(K,) bool")
      .def_readonly("force_left", &TrajectoryArrays::force_left,
                    "(K,) normal force of the -x pad over the last step, N")
      .def_readonly("force_right", &TrajectoryArrays::force_right,
                    "(K,) normal force of the +x pad over the last step, N")
      .def_readonly("success", &TrajectoryArrays::success)
      .def_readonly("ended_early", &TrajectoryArrays::ended_early)
      .def_readonly("steps", &TrajectoryArrays::steps)
      .def_readonly("friction", &TrajectoryArrays::friction)
      .def_readonly("density_factor", &TrajectoryArrays::density_factor);

  m.def(
      "shake_test",
      [](std::vector<Mesh> parts, double mass, const Vec3d& com, const Mat3d& inertia,
         const py::handle& grasps, const ParallelJawGripper& grip, const ShakeOptions& options) {
        const PhysicsObject object = object_from(std::move(parts), mass, com, inertia);
        const std::vector<ParallelJawGrasp> g = grasps_from(grasps);
        ShakeResult r;
        {
          py::gil_scoped_release release;
          r = shake_test(object, grip, g, options);
        }
        const auto G = static_cast<py::ssize_t>(r.score.size());
        const py::ssize_t S = r.grid;
        ShakeArrays out;
        out.score = to_numpy(std::move(r.score));
        out.trial_success = to_bool_numpy(std::move(r.trial_success)).attr("reshape")(G, S, S);
        out.trial_ended_early =
            to_bool_numpy(std::move(r.trial_ended_early)).attr("reshape")(G, S, S);
        out.trial_steps = to_numpy(std::move(r.trial_steps)).attr("reshape")(G, S, S);
        out.frictions = to_numpy(std::move(r.frictions));
        out.density_factors = to_numpy(std::move(r.density_factors));
        out.total_steps = static_cast<long long>(r.total_steps);
        out.trial_simulated = to_bool_numpy(std::move(r.trial_simulated)).attr("reshape")(G, S, S);
        out.fallback = to_bool_numpy(std::move(r.fallback));
        return out;
      },
      py::arg("parts"), py::arg("mass"), py::arg("com"), py::arg("inertia"), py::arg("grasps"),
      py::arg("gripper"), py::arg("options"),
      "Shake test of (N, 10) grasps [a, v, p1, w] (m); a ShakeResult (GIL released).");

  m.def(
      "staircase_grid",
      [](int S, const std::function<bool(int, int)>& trial, int checks, int verified_rows) {
        const StaircaseGrid g = staircase_grid(S, trial, checks, verified_rows);
        StaircaseArrays out;
        out.success = to_bool_numpy(std::vector<std::uint8_t>(g.success)).attr("reshape")(S, S);
        out.simulated = to_bool_numpy(std::vector<std::uint8_t>(g.simulated)).attr("reshape")(S, S);
        out.fallback = g.fallback;
        out.trials = g.trials;
        return out;
      },
      py::arg("S"), py::arg("trial"), py::arg("checks"), py::arg("verified_rows") = -1,
      "The staircase search of shake_test on an S x S grid: trial(i, j) -> bool is called for "
      "the cells it simulates (friction index i, density index j); the boundary is verified in "
      "rows i < verified_rows (-1: every row); a StaircaseGridResult.");

  m.def(
      "shake_trajectory",
      [](std::vector<Mesh> parts, double mass, const Vec3d& com, const Mat3d& inertia,
         const py::handle& grasp, const ParallelJawGripper& grip, double friction,
         double density_factor, const ShakeOptions& options, int record_every,
         std::uint64_t trial_index) {
        const PhysicsObject object = object_from(std::move(parts), mass, com, inertia);
        const py::object row =
            py::module_::import("numpy").attr("asarray")(grasp).attr("reshape")(-1, 10);
        const std::vector<ParallelJawGrasp> g = grasps_from(row);
        if (g.size() != 1) {
          throw_error<InvalidArgument>("grasp: expected one row of 10 values, got ", g.size());
        }
        ShakeTrajectory t;
        {
          py::gil_scoped_release release;
          t = shake_trajectory(object, grip, g[0], friction, density_factor, options, record_every,
                               trial_index);
        }
        TrajectoryArrays out;
        out.time = to_numpy(std::move(t.time));
        out.phase = to_numpy(std::move(t.phase));
        out.X_WO = poses_to_numpy(t.X_WO);
        out.X_WH = poses_to_numpy(t.X_WH);
        out.finger_left = to_numpy(std::move(t.finger_left));
        out.finger_right = to_numpy(std::move(t.finger_right));
        out.contact_left = to_bool_numpy(std::move(t.contact_left));
        out.contact_right = to_bool_numpy(std::move(t.contact_right));
        out.force_left = to_numpy(std::move(t.force_left));
        out.force_right = to_numpy(std::move(t.force_right));
        out.success = t.success;
        out.ended_early = t.ended_early;
        out.steps = t.steps;
        out.friction = t.friction;
        out.density_factor = t.density_factor;
        return out;
      },
      py::arg("parts"), py::arg("mass"), py::arg("com"), py::arg("inertia"), py::arg("grasp"),
      py::arg("gripper"), py::arg("friction"), py::arg("density_factor"), py::arg("options"),
      py::arg("record_every") = 5, py::arg("trial_index") = 0,
      "One recorded shake trial (poses in the world W: z up, gravity -z).");
}

}  // namespace mgn::py_bind
