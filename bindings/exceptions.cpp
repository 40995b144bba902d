// The one exception registry: C++ mgn::Error hierarchy -> Python classes that also derive from
// the matching builtin, so `except ValueError` works as users expect.
#include <mgn/core/error.hpp>

#include "exceptions.hpp"

namespace py = pybind11;

namespace mgn::py_bind {

namespace {
PyObject* g_base = nullptr;
PyObject* g_invalid = nullptr;
PyObject* g_io = nullptr;
PyObject* g_unsupported = nullptr;
PyObject* g_backend = nullptr;

PyObject* make_type(py::module_& m, const char* name, const char* doc, PyObject* builtin) {
  PyObject* bases = PyTuple_Pack(2, g_base, builtin);
  const std::string qualified = m.attr("__name__").cast<std::string>() + "." + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases, nullptr);
  Py_DECREF(bases);
  if (type == nullptr) throw py::error_already_set();
  m.attr(name) = py::handle(type);  // the module keeps a reference; we keep ours forever
  return type;
}
}  // namespace

void register_exceptions(py::module_& m) {
  const std::string base_name = m.attr("__name__").cast<std::string>() + ".MgnError";
  g_base = PyErr_NewExceptionWithDoc(base_name.c_str(), "Base class of every error raised by mgn.",
                                     PyExc_Exception, nullptr);
  if (g_base == nullptr) throw py::error_already_set();
  m.attr("MgnError") = py::handle(g_base);
  g_invalid = make_type(m, "InvalidArgumentError",
                        "An argument has a wrong value, shape or range (also a ValueError).",
                        PyExc_ValueError);
  g_io = make_type(m, "IoError", "A file could not be read or written (also an OSError).",
                   PyExc_OSError);
  g_unsupported =
      make_type(m, "UnsupportedError",
                "A valid request that this build or format does not support (also a ValueError).",
                PyExc_ValueError);
  g_backend = make_type(m, "BackendError",
                        "A third-party backend reported a failure (also a RuntimeError).",
                        PyExc_RuntimeError);

  // pybind11's translator type takes the std::exception_ptr by value.
  // NOLINTNEXTLINE(performance-unnecessary-value-param)
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const mgn::InvalidArgument& e) {
      PyErr_SetString(g_invalid, e.what());
    } catch (const mgn::IoError& e) {
      PyErr_SetString(g_io, e.what());
    } catch (const mgn::Unsupported& e) {
      PyErr_SetString(g_unsupported, e.what());
    } catch (const mgn::BackendError& e) {
      PyErr_SetString(g_backend, e.what());
    } catch (const mgn::Error& e) {
      PyErr_SetString(g_base, e.what());
    }
  });
}

}  // namespace mgn::py_bind
