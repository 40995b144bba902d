// mgn._core: registration only. Each C++ module is bound in its own bind_<module>.cpp.
#include <pybind11/pybind11.h>

#include "exceptions.hpp"

PYBIND11_MODULE(_core, m) {
  m.doc() = "mgn compiled core (private): use the typed API of the `mgn` package instead.";
  mgn::py_bind::register_exceptions(m);
  mgn::py_bind::bind_core(m);
  mgn::py_bind::bind_geometry(m);
  mgn::py_bind::bind_raytrace(m);
  mgn::py_bind::bind_collision(m);
  mgn::py_bind::bind_grasp(m);
  mgn::py_bind::bind_calibration(m);
  mgn::py_bind::bind_render(m);
  mgn::py_bind::bind_path_tracer(m);
  mgn::py_bind::bind_scene(m);
  mgn::py_bind::bind_pj(m);
  mgn::py_bind::bind_shake(m);
  mgn::py_bind::bind_layout(m);
  mgn::py_bind::bind_scene_grasps(m);
  mgn::py_bind::bind_view_labels(m);
}
