// Parallel-jaw grasps: gripper, antipodal sampler and soft-finger wrench score
// (docs/models.md §5).
#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <mgn/grasp/antipodal.hpp>
#include <mgn/grasp/gripper.hpp>
#include <mgn/grasp/pj_wrench.hpp>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

/// Grasps from (N,3) p1, closing, approach and (N,) width arrays.
std::vector<ParallelJawGrasp> to_grasps(const py::handle& p1, const py::handle& closing,
                                        const py::handle& approach, const py::handle& width) {
  const Points3d p = to_rows<double, 3>(p1, "p1");
  const Points3d v = to_rows<double, 3>(closing, "closing");
  const Points3d a = approach.is_none() ? Points3d() : to_rows<double, 3>(approach, "approach");
  CArray<double> w;
  try {
    w = py::cast<CArray<double>>(width);
  } catch (const py::cast_error&) {
    throw_error<InvalidArgument>("width: expected a numeric array of shape (N,)");
  }
  if (w.ndim() != 1 || v.rows() != p.rows() || w.shape(0) != p.rows() ||
      (!approach.is_none() && a.rows() != p.rows())) {
    throw_error<InvalidArgument>("grasps: p1 has ", p.rows(),
                                 " rows; expected closing, approach (N, 3) and width (N,) with the "
                                 "same N");
  }
  std::vector<ParallelJawGrasp> out(static_cast<std::size_t>(p.rows()));
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    out[i].p1 = p.row(i).transpose();
    out[i].closing = v.row(i).transpose();
    if (!approach.is_none()) out[i].approach = a.row(i).transpose();
    out[i].width = w.at(i);
  }
  return out;
}

/// AntipodalResult as numpy arrays (moved, no copies), one row per kept grasp.
struct AntipodalArrays {
  py::array point_score, num_kept, p1, closing, approach, width, point_index, probe, score;
  std::int64_t num_accepted_probes = 0, num_colliding = 0;
};

}  // namespace

void bind_grasp_antipodal(py::module_& m) {
  py::class_<AntipodalArrays>(m, "AntipodalResult",
                              "AntipodalSampler.sample() result (mgn/grasp/antipodal.hpp); "
                              "mgn.pj.sampler.AntipodalResult documents each array.")
      .def_readonly("point_score", &AntipodalArrays::point_score)
      .def_readonly("num_kept", &AntipodalArrays::num_kept)
      .def_readonly("p1", &AntipodalArrays::p1)
      .def_readonly("closing", &AntipodalArrays::closing)
      .def_readonly("approach", &AntipodalArrays::approach)
      .def_readonly("width", &AntipodalArrays::width)
      .def_readonly("point_index", &AntipodalArrays::point_index)
      .def_readonly("probe", &AntipodalArrays::probe)
      .def_readonly("score", &AntipodalArrays::score)
      .def_readonly("num_accepted_probes", &AntipodalArrays::num_accepted_probes)
      .def_readonly("num_colliding", &AntipodalArrays::num_colliding);

  py::class_<AntipodalOptions>(m, "AntipodalOptions",
                               "Options of AntipodalSampler.sample (mgn/grasp/antipodal.hpp, SI "
                               "units); the defaults are the C++ struct's (MetaGraspNet), "
                               "validate() checks the ranges.")
      .def(py::init<>())
      .def_readwrite("probes", &AntipodalOptions::probes, "perturbed probes per contact point")
      .def_readwrite("tilt", &AntipodalOptions::tilt,
                     "bound of each Euler angle of the probe tilt, rad")
      .def_readwrite("offset", &AntipodalOptions::offset, "bound of the start offset per axis, m")
      .def_readwrite("start_offset", &AntipodalOptions::start_offset,
                     "the probe ray starts this far outside the surface, m")
      .def_readwrite("friction_coef", &AntipodalOptions::friction_coef,
                     "mu; friction cone half-angle atan(mu)")
      .def_readwrite("approaches_tried", &AntipodalOptions::approaches_tried,
                     "random approach directions tried per accepted probe")
      .def_readwrite("approaches_kept", &AntipodalOptions::approaches_kept,
                     "collision-free approaches kept per accepted probe")
      .def_readwrite("check_collision", &AntipodalOptions::check_collision,
                     "false: keep the first approaches_kept approaches unchecked")
      .def_readwrite("seed", &AntipodalOptions::seed)
      .def_readwrite("first_index", &AntipodalOptions::first_index,
                     "point i uses the random stream (seed, first_index + i)")
      .def_readwrite("num_threads", &AntipodalOptions::num_threads, "0 = all hardware threads")
      .def("validate", &AntipodalOptions::validate,
           "Raises InvalidArgumentError naming the first field out of its range.");

  py::class_<PjWrenchOptions>(m, "PjWrenchOptions",
                              "Constants of pj_wrench_scores (mgn/grasp/pj_wrench.hpp, SI units); "
                              "the defaults are the C++ struct's, validate() checks the ranges.")
      .def(py::init<>())
      .def_readwrite("friction", &PjWrenchOptions::friction, "mu between finger pads and object")
      .def_readwrite("grip_force", &PjWrenchOptions::grip_force, "normal force per finger, N")
      .def_readwrite("contact_radius", &PjWrenchOptions::contact_radius,
                     "radius of the soft contact patch, m")
      .def_readwrite("gravity", &PjWrenchOptions::gravity, "m/s^2")
      .def("validate", &PjWrenchOptions::validate,
           "Raises InvalidArgumentError naming the first field out of its range.");

  py::class_<ParallelJawGripper>(
      m, "ParallelJawGripper",
      "Parallel-jaw gripper (SI units; see mgn.hardware.ParallelJawGripper). Box gripper unless "
      "palm_mesh, finger_left_mesh and finger_right_mesh are all set (closed, hand frame, fingers "
      "at opening 0).")
      .def(py::init<>())
      .def_readwrite("name", &ParallelJawGripper::name)
      .def_readwrite("max_opening", &ParallelJawGripper::max_opening)
      .def_readwrite("flange_to_tip", &ParallelJawGripper::flange_to_tip)
      .def_readwrite("contact_from_tip", &ParallelJawGripper::contact_from_tip)
      .def_readwrite("collision_margin", &ParallelJawGripper::collision_margin)
      .def_readwrite("finger_size", &ParallelJawGripper::finger_size)
      .def_readwrite("palm_size", &ParallelJawGripper::palm_size)
      .def_readwrite("friction", &ParallelJawGripper::friction)
      .def_readwrite("palm_mesh", &ParallelJawGripper::palm_mesh)
      .def_readwrite("finger_left_mesh", &ParallelJawGripper::finger_left_mesh)
      .def_readwrite("finger_right_mesh", &ParallelJawGripper::finger_right_mesh)
      .def("has_meshes", &ParallelJawGripper::has_meshes)
      .def("validate", &ParallelJawGripper::validate)
      .def("grasp_depth", &ParallelJawGripper::grasp_depth)
      .def("collision_opening", &ParallelJawGripper::collision_opening, py::arg("width"));

  m.def(
      "gripper_meshes",
      [](const ParallelJawGripper& g, double opening) {
        GripperMeshes out = gripper_meshes(g, opening);
        return py::make_tuple(std::move(out.palm), std::move(out.finger_left),
                              std::move(out.finger_right));
      },
      py::arg("gripper"), py::arg("opening"),
      "(palm, finger_left, finger_right) closed meshes in the hand frame at an opening (m).");

  m.def(
      "hand_poses",
      [](const py::handle& p1, const py::handle& closing, const py::handle& approach,
         const py::handle& width, const ParallelJawGripper& g) {
        const std::vector<ParallelJawGrasp> grasps = to_grasps(p1, closing, approach, width);
        std::vector<Pose> X_OH;
        X_OH.reserve(grasps.size());
        for (const ParallelJawGrasp& grasp : grasps) X_OH.push_back(hand_pose(grasp, g));
        return poses_to_numpy(X_OH);
      },
      py::arg("p1"), py::arg("closing"), py::arg("approach"), py::arg("width"), py::arg("gripper"),
      "(N,4,4) hand (flange) poses X_OH of grasps in the object frame.");

  py::class_<AntipodalSampler, std::shared_ptr<AntipodalSampler>>(
      m, "AntipodalSampler", "Immutable antipodal grasp sampler of one object for one gripper.")
      .def(py::init([](const Mesh& mesh, const ParallelJawGripper& g) {
             py::gil_scoped_release release;
             return std::make_shared<AntipodalSampler>(mesh, g);
           }),
           py::arg("mesh"), py::arg("gripper"))
      .def_property_readonly("gripper", &AntipodalSampler::gripper)
      .def(
          "sample",
          [](const AntipodalSampler& s, const py::handle& points, const py::handle& normals,
             const AntipodalOptions& o) {
            const Points3d p = to_rows<double, 3>(points, "points");
            const Points3d n = to_rows<double, 3>(normals, "normals");
            AntipodalResult r;
            {
              py::gil_scoped_release release;
              r = s.sample(p, n, o);
            }
            const auto M = static_cast<Eigen::Index>(r.grasps.size());
            Points3d p1(M, 3), v(M, 3), a(M, 3);
            std::vector<double> width(r.grasps.size());
            std::vector<std::int64_t> point_index(r.grasps.size());
            std::vector<std::int32_t> probe(r.grasps.size());
            std::vector<float> score(r.grasps.size());
            for (Eigen::Index i = 0; i < M; ++i) {
              const AntipodalGrasp& g = r.grasps[i];
              p1.row(i) = g.grasp.p1.transpose();
              v.row(i) = g.grasp.closing.transpose();
              a.row(i) = g.grasp.approach.transpose();
              width[i] = g.grasp.width;
              point_index[i] = g.point_index;
              probe[i] = g.probe;
              score[i] = g.score;
            }
            AntipodalArrays out;
            out.point_score = to_numpy(std::move(r.point_score));
            out.num_kept = to_numpy(std::move(r.num_kept));
            out.p1 = to_numpy(std::move(p1));
            out.closing = to_numpy(std::move(v));
            out.approach = to_numpy(std::move(a));
            out.width = to_numpy(std::move(width));
            out.point_index = to_numpy(std::move(point_index));
            out.probe = to_numpy(std::move(probe));
            out.score = to_numpy(std::move(score));
            out.num_accepted_probes = r.num_accepted_probes;
            out.num_colliding = r.num_colliding;
            return out;
          },
          py::arg("points"), py::arg("normals"),
          py::arg_v("options", AntipodalOptions{}, "AntipodalOptions()"),
          "Antipodal grasps from (N,3) contact points and unit outward normals (object frame, "
          "m).")
      .def(
          "collides",
          [](const AntipodalSampler& s, const py::handle& X_OH, double opening) {
            const Pose X = to_pose(X_OH, "X_OH");
            py::gil_scoped_release release;
            return s.collides(X, opening);
          },
          py::arg("X_OH"), py::arg("opening"));

  m.def(
      "pj_wrench_scores",
      [](const py::handle& p1, const py::handle& closing, const py::handle& width, double mass,
         const Vec3d& com, const Vec3d& gravity_direction, const PjWrenchOptions& o) {
        const std::vector<ParallelJawGrasp> grasps = to_grasps(p1, closing, py::none(), width);
        return to_numpy(pj_wrench_scores(grasps, mass, com, gravity_direction, o));
      },
      py::arg("p1"), py::arg("closing"), py::arg("width"), py::arg("mass"), py::arg("com"),
      py::arg("gravity_direction"), py::arg_v("options", PjWrenchOptions{}, "PjWrenchOptions()"));
}

}  // namespace mgn::py_bind
