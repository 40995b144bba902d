#pragma once
#include <pybind11/pybind11.h>

namespace mgn::py_bind {
/// Creates mgn._core.core.MgnError and its subclasses (each also derived from the matching builtin)
/// and installs the translator from the C++ hierarchy.
void register_exceptions(pybind11::module_& m);
void bind_core(pybind11::module_& m);
void bind_geometry(pybind11::module_& m);
void bind_raytrace(pybind11::module_& m);
void bind_collision(pybind11::module_& m);
void bind_grasp_seal(pybind11::module_& m);
void bind_grasp_calibration(pybind11::module_& m);
void bind_render(pybind11::module_& m);
void bind_scene_drop(pybind11::module_& m);
void bind_grasp_antipodal(pybind11::module_& m);
void bind_grasp_shake_trial(pybind11::module_& m);
void bind_scene_layout(pybind11::module_& m);
void bind_render_path_tracer(pybind11::module_& m);
void bind_scene_grasps(pybind11::module_& m);
void bind_scene_view_labels(pybind11::module_& m);
}  // namespace mgn::py_bind
