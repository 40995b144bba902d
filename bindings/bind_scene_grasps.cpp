// Scene grasp labels (mgn/scene/scene_grasps.hpp): mgn._core.scene.SceneGraspModel.
// The typed façade is mgn.view_labels.grasps.SceneGraspModel.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <mgn/scene/scene_grasps.hpp>

#include <string>
#include <tuple>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

/// (M,) float array -> vector; None -> empty. Names ObjectGraspLabels.<field> in errors.
std::vector<float> floats(const py::handle& obj, const char* field) {
  if (obj.is_none()) return {};
  CArray<float> a;
  try {
    a = py::cast<CArray<float>>(obj);
  } catch (const py::cast_error&) {
    throw_error<InvalidArgument>("ObjectGraspLabels.", field,
                                 " must be a numeric array of shape (M,)");
  }
  if (a.ndim() != 1)
    throw_error<InvalidArgument>("ObjectGraspLabels.", field, " must have shape (M,), got ",
                                 shape_of(a));
  return std::vector<float>(a.data(), a.data() + a.shape(0));
}

/// (M,3) array -> rows; None -> 0 rows. Names ObjectGraspLabels.<field> in errors.
template <typename Scalar>
Eigen::Matrix<Scalar, Eigen::Dynamic, 3, Eigen::RowMajor> rows3(const py::handle& obj,
                                                                const char* field) {
  if (obj.is_none()) return Eigen::Matrix<Scalar, Eigen::Dynamic, 3, Eigen::RowMajor>(0, 3);
  const std::string what = std::string("ObjectGraspLabels.") + field;
  return to_rows<Scalar, 3>(obj, what.c_str());
}

ObjectGraspLabels make_labels(const py::handle& pj_p1, const py::handle& pj_closing,
                              const py::handle& pj_approach, const py::handle& pj_width,
                              const py::handle& pj_score_analytical,
                              const py::handle& pj_score_simulation,
                              const py::handle& suction_points, const py::handle& suction_approach,
                              const py::handle& suction_score_analytical,
                              const py::handle& suction_score_simulation) {
  ObjectGraspLabels o;
  const Points3d p1 = rows3<double>(pj_p1, "pj_p1");
  const Points3d v = rows3<double>(pj_closing, "pj_closing");
  const Points3d a = rows3<double>(pj_approach, "pj_approach");
  const std::vector<float> w = floats(pj_width, "pj_width");
  const auto m = static_cast<std::size_t>(p1.rows());
  if (static_cast<std::size_t>(v.rows()) != m || static_cast<std::size_t>(a.rows()) != m ||
      w.size() != m) {
    throw_error<InvalidArgument>(
        "ObjectGraspLabels.pj_closing, pj_approach (M, 3) and pj_width (M,) must have the M of "
        "pj_p1 (",
        m, "), got ", v.rows(), ", ", a.rows(), " and ", w.size());
  }
  o.pj.resize(m);
  for (std::size_t g = 0; g < m; ++g) {
    const auto r = static_cast<Eigen::Index>(g);
    o.pj[g].p1 = p1.row(r).transpose();
    o.pj[g].closing = v.row(r).transpose();
    o.pj[g].approach = a.row(r).transpose();
    o.pj[g].width = w[g];
  }
  o.pj_score_analytical = floats(pj_score_analytical, "pj_score_analytical");
  o.pj_score_simulation = floats(pj_score_simulation, "pj_score_simulation");
  o.suction_points = rows3<float>(suction_points, "suction_points");
  o.suction_approach = rows3<float>(suction_approach, "suction_approach");
  if (o.suction_approach.rows() != o.suction_points.rows()) {
    throw_error<InvalidArgument>(
        "ObjectGraspLabels.suction_approach must have the K of "
        "suction_points (",
        o.suction_points.rows(), "), got ", o.suction_approach.rows());
  }
  o.suction_score_analytical = floats(suction_score_analytical, "suction_score_analytical");
  o.suction_score_simulation = floats(suction_score_simulation, "suction_score_simulation");
  return o;
}

/// Column `c` of the parallel-jaw grasps as (M,3) rows (0 p1, 1 closing, 2 approach).
py::array pj_rows(const ObjectGraspLabels& o, int c) {
  Points3d out(static_cast<Eigen::Index>(o.pj.size()), 3);
  for (std::size_t g = 0; g < o.pj.size(); ++g) {
    const ParallelJawGrasp& q = o.pj[g];
    out.row(static_cast<Eigen::Index>(g)) = (c == 0   ? q.p1
                                             : c == 1 ? q.closing
                                                      : q.approach)
                                                .transpose();
  }
  return to_numpy(std::move(out));
}

void bind_labels(py::module_& m) {
  py::class_<ObjectGraspLabels>(
      m, "ObjectGraspLabels",
      "Object-level grasp labels of one object, the input of SceneGraspModel "
      "(mgn/scene/scene_grasps.hpp). Object frame O, metres; every argument is optional (None: "
      "no labels of that kind, or NaN scores).")
      .def(py::init(&make_labels), py::arg("pj_p1") = py::none(),
           py::arg("pj_closing") = py::none(), py::arg("pj_approach") = py::none(),
           py::arg("pj_width") = py::none(), py::arg("pj_score_analytical") = py::none(),
           py::arg("pj_score_simulation") = py::none(), py::arg("suction_points") = py::none(),
           py::arg("suction_approach") = py::none(),
           py::arg("suction_score_analytical") = py::none(),
           py::arg("suction_score_simulation") = py::none())
      .def_property_readonly(
          "pj_p1", [](const ObjectGraspLabels& o) { return pj_rows(o, 0); },
          "(M,3) float64 first contact p1 of each parallel-jaw grasp, object frame, m")
      .def_property_readonly(
          "pj_closing", [](const ObjectGraspLabels& o) { return pj_rows(o, 1); },
          "(M,3) float64 unit closing direction v (p2 = p1 + w v), object frame")
      .def_property_readonly(
          "pj_approach", [](const ObjectGraspLabels& o) { return pj_rows(o, 2); },
          "(M,3) float64 unit approach direction, object frame")
      .def_property_readonly(
          "pj_width",
          [](const ObjectGraspLabels& o) {
            std::vector<float> w(o.pj.size());
            for (std::size_t g = 0; g < o.pj.size(); ++g) w[g] = static_cast<float>(o.pj[g].width);
            return to_numpy(std::move(w));
          },
          "(M,) float32 contact width w, m")
      .def_property_readonly(
          "pj_score_analytical",
          [](const ObjectGraspLabels& o) {
            return to_numpy(std::vector<float>(o.pj_score_analytical));
          },
          "(M,) or (0,) float32 analytical score in [0, 1]")
      .def_property_readonly(
          "pj_score_simulation",
          [](const ObjectGraspLabels& o) {
            return to_numpy(std::vector<float>(o.pj_score_simulation));
          },
          "(M,) or (0,) float32 simulation score in [0, 1]")
      .def_property_readonly(
          "suction_points",
          [](const ObjectGraspLabels& o) { return to_numpy(Points3f(o.suction_points)); },
          "(K,3) float32 suction contacts, object frame, m")
      .def_property_readonly(
          "suction_approach",
          [](const ObjectGraspLabels& o) { return to_numpy(Points3f(o.suction_approach)); },
          "(K,3) float32 approach directions into the surface, object frame")
      .def_property_readonly(
          "suction_score_analytical",
          [](const ObjectGraspLabels& o) {
            return to_numpy(std::vector<float>(o.suction_score_analytical));
          },
          "(K,) or (0,) float32 seal score in [0, 1]")
      .def_property_readonly(
          "suction_score_simulation",
          [](const ObjectGraspLabels& o) {
            return to_numpy(std::vector<float>(o.suction_score_simulation));
          },
          "(K,) or (0,) float32 simulation score in [0, 1]");
}

void bind_options(py::module_& m) {
  using Triple = std::tuple<double, double, double>;
  py::class_<SuctionTool>(m, "SuctionTool",
                          "Suction tool geometry behind the cup body for the scene collision "
                          "check (mgn/scene/scene_grasps.hpp, m); defaults are the C++ struct's.")
      .def(py::init<>())
      .def_readwrite("clearance", &SuctionTool::clearance,
                     "gap between the contact and the bottom of the cup body, m")
      .def_readwrite("shaft_radius", &SuctionTool::shaft_radius, "m")
      .def_readwrite("shaft_length", &SuctionTool::shaft_length, "m")
      .def("validate", &SuctionTool::validate,
           "Raises InvalidArgumentError naming the first field out of its range.");
  py::class_<SceneGraspOptions>(m, "SceneGraspOptions",
                                "Options of SceneGraspModel (mgn/scene/scene_grasps.hpp, SI "
                                "units); the defaults are the C++ struct's, validate() checks "
                                "the ranges.")
      .def(py::init<>())
      .def_readwrite("offsets", &SceneGraspOptions::offsets,
                     "distances back along the approach where the tool is checked, m")
      .def_readwrite("approach_step", &SceneGraspOptions::approach_step,
                     "largest spacing of the poses checked between offsets, m")
      .def_readwrite("tool", &SceneGraspOptions::tool)
      .def_property(
          "gravity_world",
          [](const SceneGraspOptions& o) {
            return Triple(o.gravity_world.x(), o.gravity_world.y(), o.gravity_world.z());
          },
          [](SceneGraspOptions& o, const Triple& g) {
            o.gravity_world = Vec3d(std::get<0>(g), std::get<1>(g), std::get<2>(g));
          },
          "direction of gravity in the world (tote frame), normalised by the model")
      .def_readwrite("pj_wrench", &SceneGraspOptions::pj_wrench)
      .def_readwrite("suction_wrench", &SceneGraspOptions::suction_wrench)
      .def_readwrite("visibility_tolerance", &SceneGraspOptions::visibility_tolerance, "m")
      .def_readwrite("near_plane", &SceneGraspOptions::near_plane, "m")
      .def_readwrite("num_threads", &SceneGraspOptions::num_threads, "0 = all hardware threads")
      .def_readwrite("first_collision_only", &SceneGraspOptions::first_collision_only,
                     "stop at each label grasp's first colliding pose (hit of the later offsets "
                     "= -2, not checked)")
      .def("validate", &SceneGraspOptions::validate,
           "Raises InvalidArgumentError naming the first field out of its range.");
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
  bind_labels(m);
  bind_options(m);
  bind_results(m);
  m.attr("SUCTION_TOOL_OFFSET") = kSuctionToolOffset;
  py::class_<SceneGraspModel, std::shared_ptr<SceneGraspModel>>(
      m, "SceneGraspModel",
      "Per-scene grasp model: placement, collisions and wrench scores at construction; "
      "view_grasps per camera (see mgn/scene/scene_grasps.hpp).")
      .def(py::init([](const std::vector<const Mesh*>& meshes, const py::handle& poses,
                       const std::vector<double>& masses, const py::handle& coms,
                       const std::vector<ObjectGraspLabels>& labels, const Mesh& tote,
                       const py::handle& X_WT, const ParallelJawGripper& gripper, const Cup& cup,
                       const SceneGraspOptions& options) {
             const std::size_t n = meshes.size();
             const std::vector<Pose> X = n ? to_poses(poses, "poses") : std::vector<Pose>{};
             const Points3d com = n ? to_rows<double, 3>(coms, "coms") : Points3d();
             if (X.size() != n || masses.size() != n || static_cast<std::size_t>(com.rows()) != n ||
                 labels.size() != n) {
               throw_error<InvalidArgument>("SceneGraspModel: ", n, " meshes but ", X.size(),
                                            " poses, ", masses.size(), " masses, ", com.rows(),
                                            " coms and ", labels.size(),
                                            " label entries; expected one of each per object");
             }
             std::vector<SceneGraspObject> objects(n);
             for (std::size_t i = 0; i < n; ++i) {
               SceneGraspObject& o = objects[i];
               if (meshes[i] == nullptr)
                 throw_error<InvalidArgument>("SceneGraspModel: mesh ", i, " is None");
               static_cast<ObjectGraspLabels&>(o) = labels[i];
               o.mesh = meshes[i];
               o.X_WO = X[i];
               o.mass = masses[i];
               o.com = com.row(static_cast<Eigen::Index>(i)).transpose();
             }
             const Pose X_tote = to_pose(X_WT, "X_WT");
             py::gil_scoped_release release;
             return std::make_shared<SceneGraspModel>(objects, tote, X_tote, gripper, cup, options);
           }),
           py::arg("meshes"), py::arg("poses"), py::arg("masses"), py::arg("coms"),
           py::arg("labels"), py::arg("tote"), py::arg("X_WT"), py::arg("gripper"), py::arg("cup"),
           py::arg_v("options", SceneGraspOptions{}, "SceneGraspOptions()"))
      .def_property_readonly("num_objects", &SceneGraspModel::num_objects)
      .def_property_readonly("offsets",
                             [](const SceneGraspModel& s) { return s.options().offsets; })
      .def(
          "pj",
          [](const SceneGraspModel& s) {
            return placed_arrays(s.pj(), s.options().offsets.size());
          },
          "Parallel-jaw grasps in the world (PlacedGraspArrays).")
      .def(
          "suction",
          [](const SceneGraspModel& s) {
            return placed_arrays(s.suction(), s.options().offsets.size());
          },
          "Suction grasps in the world (PlacedGraspArrays).")
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
