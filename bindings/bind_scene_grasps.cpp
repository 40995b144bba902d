// Scene grasp labels (mgn/scene/scene_grasps.hpp): mgn._core.SceneGraspModel.
// The typed façade is mgn.view_labels.grasps.SceneGraspModel.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <mgn/scene/scene_grasps.hpp>

#include <string>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

std::vector<float> floats(const py::dict& d, const char* key, const std::string& what) {
  if (!d.contains(key) || d[key].is_none()) return {};
  CArray<float> a;
  try {
    a = py::cast<CArray<float>>(d[key]);
  } catch (const py::cast_error&) {
    throw_error<InvalidArgument>(what, ".", key, ": expected a numeric array of shape (M,)");
  }
  if (a.ndim() != 1) throw_error<InvalidArgument>(what, ".", key, ": expected shape (M,)");
  return std::vector<float>(a.data(), a.data() + a.shape(0));
}

py::handle item(const py::dict& d, const char* key, const std::string& what) {
  if (!d.contains(key)) throw_error<InvalidArgument>(what, ": missing key '", key, "'");
  return d[key];
}

/// PlacedGrasps as numpy arrays (copies: the model keeps its own).
struct PlacedArrays {
  py::array tool_poses, contact_poses, contacts, second_contacts, width, score_analytical;
  py::array score_simulation, score_wrench, object_index, colliding, hit, collision_part;
  py::array collision_obstacle;
};

/// ToolCollisions: colliding (M,) bool, hit (M, K) int32.
struct CollisionArrays {
  py::array colliding, hit;
};

/// ViewGrasps: row indices and camera-frame poses of the grasps kept in a view.
struct ViewGraspArrays {
  py::array pj_index, pj_tool, pj_contact, suction_index, suction_tool, suction_contact;
};

PlacedArrays placed_arrays(const PlacedGrasps& p, std::size_t num_offsets) {
  PlacedArrays out;
  out.tool_poses = poses_to_numpy(p.X_W_tool);
  out.contact_poses = poses_to_numpy(p.X_W_contact);
  out.contacts = to_numpy(Points3d(p.contacts));
  out.second_contacts = to_numpy(Points3d(p.second_contacts));
  out.width = to_numpy(std::vector<float>(p.width));
  out.score_analytical = to_numpy(std::vector<float>(p.score_analytical));
  out.score_simulation = to_numpy(std::vector<float>(p.score_simulation));
  out.score_wrench = to_numpy(std::vector<float>(p.score_wrench));
  out.object_index = to_numpy(std::vector<std::int32_t>(p.object_index));
  out.colliding = to_bool_numpy(std::vector<std::uint8_t>(p.colliding));
  py::array hit = to_numpy(std::vector<std::int32_t>(p.hit));
  out.hit = hit.attr("reshape")(static_cast<py::ssize_t>(p.size()),
                                static_cast<py::ssize_t>(num_offsets));
  out.collision_part = to_numpy(std::vector<std::uint8_t>(p.collision_part));
  out.collision_obstacle = to_numpy(std::vector<std::uint8_t>(p.collision_obstacle));
  return out;
}

void bind_results(py::module_& m) {
  py::class_<PlacedArrays>(m, "PlacedGraspArrays",
                           "SceneGraspModel.pj / .suction (mgn/scene/scene_grasps.hpp): world-"
                           "frame grasps of every object; mgn.view_labels.grasps.PlacedGrasps "
                           "documents each array.")
      .def_readonly("tool_poses", &PlacedArrays::tool_poses)
      .def_readonly("contact_poses", &PlacedArrays::contact_poses)
      .def_readonly("contacts", &PlacedArrays::contacts)
      .def_readonly("second_contacts", &PlacedArrays::second_contacts)
      .def_readonly("width", &PlacedArrays::width)
      .def_readonly("score_analytical", &PlacedArrays::score_analytical)
      .def_readonly("score_simulation", &PlacedArrays::score_simulation)
      .def_readonly("score_wrench", &PlacedArrays::score_wrench)
      .def_readonly("object_index", &PlacedArrays::object_index)
      .def_readonly("colliding", &PlacedArrays::colliding)
      .def_readonly("hit", &PlacedArrays::hit)
      .def_readonly("collision_part", &PlacedArrays::collision_part)
      .def_readonly("collision_obstacle", &PlacedArrays::collision_obstacle);
  py::class_<CollisionArrays>(m, "ToolCollisionArrays",
                              "SceneGraspModel.collides(): colliding (M,) bool, hit (M, K) "
                              "int32.")
      .def_readonly("colliding", &CollisionArrays::colliding)
      .def_readonly("hit", &CollisionArrays::hit);
  py::class_<ViewGraspArrays>(m, "ViewGraspArrays",
                              "SceneGraspModel.view_grasps(): row indices and camera-frame "
                              "(N,4,4) tool and contact poses of the grasps kept in a view.")
      .def_readonly("pj_index", &ViewGraspArrays::pj_index)
      .def_readonly("pj_tool", &ViewGraspArrays::pj_tool)
      .def_readonly("pj_contact", &ViewGraspArrays::pj_contact)
      .def_readonly("suction_index", &ViewGraspArrays::suction_index)
      .def_readonly("suction_tool", &ViewGraspArrays::suction_tool)
      .def_readonly("suction_contact", &ViewGraspArrays::suction_contact);
}

CameraView camera(const Intrinsics& K, const py::handle& X_WC) {
  CameraView v;
  v.K = K;
  v.X_WC = to_pose(X_WC, "X_WC");
  return v;
}

}  // namespace

void bind_scene_grasps(py::module_& m) {
  bind_results(m);
  m.attr("SUCTION_TOOL_OFFSET") = kSuctionToolOffset;
  py::class_<SceneGraspModel, std::shared_ptr<SceneGraspModel>>(
      m, "SceneGraspModel",
      "Per-scene grasp model: placement, collisions and wrench scores at construction; "
      "view_grasps per camera (see mgn/scene/scene_grasps.hpp).")
      .def(py::init([](const std::vector<const Mesh*>& meshes, const py::handle& poses,
                       const std::vector<double>& masses, const py::handle& coms,
                       const std::vector<py::object>& pj, const std::vector<py::object>& suction,
                       const Mesh& tote, const py::handle& X_WT, const ParallelJawGripper& gripper,
                       const Cup& cup, const std::vector<double>& offsets, double clearance,
                       double shaft_radius, double shaft_length, const Vec3d& gravity_world,
                       double pj_friction, double grip_force, double contact_radius,
                       double suction_k, double visibility_tolerance, double near_plane,
                       int num_threads, double approach_step) {
             const std::size_t n = meshes.size();
             const std::vector<Pose> X = n ? to_poses(poses, "poses") : std::vector<Pose>{};
             const Points3d com = n ? to_rows<double, 3>(coms, "coms") : Points3d();
             if (X.size() != n || masses.size() != n || static_cast<std::size_t>(com.rows()) != n ||
                 pj.size() != n || suction.size() != n) {
               throw_error<InvalidArgument>(
                   "SceneGraspModel: ", n, " meshes but ", X.size(), " poses, ", masses.size(),
                   " masses, ", com.rows(), " coms, ", pj.size(), " parallel-jaw and ",
                   suction.size(), " suction label entries; expected one of each per object");
             }
             std::vector<SceneGraspObject> objects(n);
             for (std::size_t i = 0; i < n; ++i) {
               SceneGraspObject& o = objects[i];
               if (meshes[i] == nullptr)
                 throw_error<InvalidArgument>("SceneGraspModel: mesh ", i, " is None");
               o.mesh = meshes[i];
               o.X_WO = X[i];
               o.mass = masses[i];
               o.com = com.row(static_cast<Eigen::Index>(i)).transpose();
               if (!pj[i].is_none()) {
                 const std::string what = "pj[" + std::to_string(i) + "]";
                 const py::dict d = pj[i].cast<py::dict>();
                 const Points3d p1 = to_rows<double, 3>(item(d, "p1", what), "p1");
                 const Points3d v = to_rows<double, 3>(item(d, "closing", what), "closing");
                 const Points3d a = to_rows<double, 3>(item(d, "approach", what), "approach");
                 const std::vector<float> w = floats(d, "width", what);
                 if (v.rows() != p1.rows() || a.rows() != p1.rows() ||
                     w.size() != static_cast<std::size_t>(p1.rows())) {
                   throw_error<InvalidArgument>(what, ": p1 has ", p1.rows(),
                                                " rows; expected closing, approach (M, 3) and "
                                                "width (M,) with the same M");
                 }
                 o.pj.resize(static_cast<std::size_t>(p1.rows()));
                 for (Eigen::Index g = 0; g < p1.rows(); ++g) {
                   o.pj[g].p1 = p1.row(g).transpose();
                   o.pj[g].closing = v.row(g).transpose();
                   o.pj[g].approach = a.row(g).transpose();
                   o.pj[g].width = w[g];
                 }
                 o.pj_score_analytical = floats(d, "score_analytical", what);
                 o.pj_score_simulation = floats(d, "score_simulation", what);
               }
               if (!suction[i].is_none()) {
                 const std::string what = "suction[" + std::to_string(i) + "]";
                 const py::dict d = suction[i].cast<py::dict>();
                 o.suction_points = to_rows<float, 3>(item(d, "points", what), "points");
                 o.suction_approach = to_rows<float, 3>(item(d, "approach", what), "approach");
                 o.suction_score_analytical = floats(d, "score_analytical", what);
                 o.suction_score_simulation = floats(d, "score_simulation", what);
               }
             }
             const Pose X_tote = to_pose(X_WT, "X_WT");
             SceneGraspOptions opt;
             opt.offsets = offsets;
             opt.approach_step = approach_step;
             opt.tool.clearance = clearance;
             opt.tool.shaft_radius = shaft_radius;
             opt.tool.shaft_length = shaft_length;
             opt.gravity_world = gravity_world;
             opt.pj_wrench.friction = pj_friction;
             opt.pj_wrench.grip_force = grip_force;
             opt.pj_wrench.contact_radius = contact_radius;
             opt.suction_wrench.k = suction_k;
             opt.visibility_tolerance = visibility_tolerance;
             opt.near_plane = near_plane;
             opt.num_threads = num_threads;
             py::gil_scoped_release release;
             return std::make_shared<SceneGraspModel>(objects, tote, X_tote, gripper, cup, opt);
           }),
           py::arg("meshes"), py::arg("poses"), py::arg("masses"), py::arg("coms"), py::arg("pj"),
           py::arg("suction"), py::arg("tote"), py::arg("X_WT"), py::arg("gripper"), py::arg("cup"),
           py::arg("offsets"), py::arg("clearance"), py::arg("shaft_radius"),
           py::arg("shaft_length"), py::arg("gravity_world"), py::arg("pj_friction"),
           py::arg("grip_force"), py::arg("contact_radius"), py::arg("suction_k"),
           py::arg("visibility_tolerance"), py::arg("near_plane"), py::arg("num_threads"),
           py::arg("approach_step") = SceneGraspOptions{}.approach_step)
      .def_property_readonly("num_objects", &SceneGraspModel::num_objects)
      .def_property_readonly("offsets",
                             [](const SceneGraspModel& s) { return s.options().offsets; })
      .def(
          "pj",
          [](const SceneGraspModel& s) {
            return placed_arrays(s.pj(), s.options().offsets.size());
          },
          "Parallel-jaw grasps in the world: dict of arrays.")
      .def(
          "suction",
          [](const SceneGraspModel& s) {
            return placed_arrays(s.suction(), s.options().offsets.size());
          },
          "Suction grasps in the world: dict of arrays.")
      .def(
          "collides",
          [](const SceneGraspModel& s, const std::string& kind, const py::handle& poses,
             const std::vector<double>& width, const std::vector<std::int32_t>& target_object,
             bool check_target_at_grasp) {
            GraspKind k = GraspKind::Suction;
            if (kind == "pj") {
              k = GraspKind::ParallelJaw;
            } else if (kind != "suction") {
              throw_error<InvalidArgument>("collides: kind must be 'pj' or 'suction', got '", kind,
                                           "'");
            }
            const std::vector<Pose> X = to_poses(poses, "X_W_contact");
            ToolCollisions r;
            {
              py::gil_scoped_release release;
              r = s.collides(k, X, width, target_object, check_target_at_grasp);
            }
            CollisionArrays out;
            const auto n = static_cast<py::ssize_t>(r.size());
            out.colliding = to_bool_numpy(std::move(r.colliding));
            py::array hit = to_numpy(std::move(r.hit));
            out.hit = hit.attr("reshape")(n, static_cast<py::ssize_t>(s.options().offsets.size()));
            return out;
          },
          py::arg("kind"), py::arg("X_W_contact"), py::arg("width"), py::arg("target_object"),
          py::arg("check_target_at_grasp") = false,
          "Collision of arbitrary grasp (contact-frame) poses with the labels' test: "
          "colliding (M,) bool and hit (M, K) int32.")
      .def(
          "visible",
          [](const SceneGraspModel& s, const Intrinsics& K, const py::handle& X_WC,
             const py::handle& points) {
            const CameraView v = camera(K, X_WC);
            const Points3d p = to_rows<double, 3>(points, "points");
            std::vector<std::uint8_t> out;
            {
              py::gil_scoped_release release;
              out = s.visible(v, p);
            }
            return to_bool_numpy(std::move(out));
          },
          py::arg("K"), py::arg("X_WC"), py::arg("points"),
          "(N,) bool: whether each world point is visible from the camera.")
      .def(
          "view_grasps",
          [](const SceneGraspModel& s, const Intrinsics& K, const py::handle& X_WC,
             const py::handle& seen) {
            const CameraView v = camera(K, X_WC);
            CArray<bool> a;
            try {
              a = py::cast<CArray<bool>>(seen);
            } catch (const py::cast_error&) {
              throw_error<InvalidArgument>("seen: expected a bool array of shape (N,)");
            }
            if (a.ndim() != 1) throw_error<InvalidArgument>("seen: expected shape (N,)");
            std::vector<std::uint8_t> flags(a.data(), a.data() + a.shape(0));
            ViewGrasps r;
            {
              py::gil_scoped_release release;
              r = s.view_grasps(v, flags);
            }
            ViewGraspArrays out;
            out.pj_index = to_numpy(std::move(r.pj_index));
            out.pj_tool = poses_to_numpy(r.pj_X_C_tool);
            out.pj_contact = poses_to_numpy(r.pj_X_C_contact);
            out.suction_index = to_numpy(std::move(r.suction_index));
            out.suction_tool = poses_to_numpy(r.suction_X_C_tool);
            out.suction_contact = poses_to_numpy(r.suction_X_C_contact);
            return out;
          },
          py::arg("K"), py::arg("X_WC"), py::arg("seen"),
          "Grasps kept in a view: row indices and camera-frame poses.");
}

}  // namespace mgn::py_bind
