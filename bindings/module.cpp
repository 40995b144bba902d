// mgn._core: registration only. bind_<module>.cpp binds a C++ module (cpp/include/mgn/<module>/);
// a module bound in several files has bind_<module>_<header>.cpp (docs/architecture.md).
#include <pybind11/pybind11.h>

#include "exceptions.hpp"

PYBIND11_MODULE(_core, m) {
  m.doc() = "mgn compiled core (private): use the typed API of the `mgn` package instead.";
  mgn::py_bind::register_exceptions(m);
  mgn::py_bind::bind_core(m);
  mgn::py_bind::bind_geometry(m);
  mgn::py_bind::bind_raytrace(m);
  mgn::py_bind::bind_collision(m);
  mgn::py_bind::bind_grasp_seal(m);
  mgn::py_bind::bind_grasp_calibration(m);
  mgn::py_bind::bind_render(m);
  mgn::py_bind::bind_scene_drop(m);
  mgn::py_bind::bind_grasp_antipodal(m);
  mgn::py_bind::bind_grasp_shake_trial(m);
  mgn::py_bind::bind_scene_layout(m);
  mgn::py_bind::bind_render_path_tracer(m);
  mgn::py_bind::bind_scene_grasps(m);
  mgn::py_bind::bind_scene_view_labels(m);
}
