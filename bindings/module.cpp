// mgn._core: registration only. One submodule per C++ module (cpp/include/mgn/<module>/):
// mgn._core.<module> holds what bind_<module>.cpp binds; a module bound in several files has
// bind_<module>_<header>.cpp (docs/architecture.md).
#include <pybind11/pybind11.h>

#include <mgn/core/build_info.hpp>

#include "exceptions.hpp"

namespace py = pybind11;

namespace {

/// mgn._core.<name>, also entered in sys.modules so that `import mgn._core.<name>` and
/// `from mgn._core.<name> import X` work (and pickle finds the classes by their __module__).
py::module_ submodule(py::module_& parent, const char* name, const char* doc) {
  py::module_ sub = parent.def_submodule(name, doc);
  py::module_::import("sys").attr("modules")[sub.attr("__name__")] = sub;
  return sub;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "mgn compiled core (private): use the typed API of the `mgn` package instead.";
  m.attr("__version__") = mgn::version();
  py::module_ core = submodule(m, "core", "mgn/core: errors, build information, threads.");
  py::module_ geometry =
      submodule(m, "geometry", "mgn/geometry: meshes, primitives, sampling, convex hulls.");
  py::module_ raytrace = submodule(m, "raytrace", "mgn/raytrace: Embree ray casting.");
  py::module_ collision = submodule(m, "collision", "mgn/collision: FCL collision and distance.");
  py::module_ grasp =
      submodule(m, "grasp", "mgn/grasp: suction seal, antipodal grasps, shake trials.");
  py::module_ render =
      submodule(m, "render", "mgn/render: cameras, rasteriser, depth sensors, path tracer.");
  py::module_ scene =
      submodule(m, "scene", "mgn/scene: drop, layout, scene grasps, per-view labels.");

  mgn::py_bind::register_exceptions(core);
  mgn::py_bind::bind_core(core);
  mgn::py_bind::bind_geometry(geometry);
  mgn::py_bind::bind_raytrace(raytrace);
  mgn::py_bind::bind_collision(collision);
  mgn::py_bind::bind_grasp_seal(grasp);
  mgn::py_bind::bind_grasp_calibration(grasp);
  mgn::py_bind::bind_render(render);
  mgn::py_bind::bind_scene_drop(scene);
  mgn::py_bind::bind_grasp_antipodal(grasp);
  mgn::py_bind::bind_grasp_shake_trial(grasp);
  mgn::py_bind::bind_scene_layout(scene);
  mgn::py_bind::bind_render_path_tracer(render);
  mgn::py_bind::bind_scene_grasps(scene);
  mgn::py_bind::bind_scene_view_labels(scene);
}
