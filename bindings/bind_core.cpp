#include <pybind11/stl.h>
#include <mgn/core/build_info.hpp>
#include <mgn/core/parallel.hpp>

#include "exceptions.hpp"

namespace py = pybind11;

namespace mgn::py_bind {

void bind_core(py::module_& m) {
  m.def("build_info", &mgn::build_info,
        "(library, version) pairs for mgn and every library the core was built against.");
  m.def("resolve_num_threads", &mgn::resolve_num_threads, py::arg("requested"),
        "Thread count used for `requested` (0 = all hardware threads).");
}

}  // namespace mgn::py_bind
