// The compiled part of the Python package softhd (softhd._core). softhd/__init__.py wraps it.

#include <chrono>
#include <filesystem>

#include "common.hpp"
#include "softhd/error.hpp"
#include "softhd/interrupt.hpp"

namespace softhd::python {

namespace {

// Python exception types, created once at import (kept for the process's lifetime).
PyObject* g_error = nullptr;
PyObject* g_invalid = nullptr;
PyObject* g_file = nullptr;
PyObject* g_resource = nullptr;
PyObject* g_numerical = nullptr;

PyObject* new_exception(py::module_& m, const char* name, PyObject* bases, const char* doc) {
  const std::string qualified = std::string("softhd.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases, nullptr);
  if (!type) throw py::error_already_set();
  m.attr(name) = py::handle(type);
  return type;
}

// The exception a Python signal handler raised during a softhd call (KeyboardInterrupt for
// Ctrl-C), held from the interrupt check until the call's Interrupted reaches Python. Only the
// main thread runs signal handlers; guarded by the GIL. Plain references, never destroyed.
struct PendingError {
  PyObject* type = nullptr;
  PyObject* value = nullptr;
  PyObject* traceback = nullptr;
};
PendingError g_pending;

// The interrupt check of every softhd call made from Python (softhd/interrupt.hpp): runs the
// signal handlers under the GIL, which the long calls release. At most every 20 ms per thread.
bool python_interrupt_check() {
  using Clock = std::chrono::steady_clock;
  thread_local Clock::time_point last;
  const Clock::time_point now = Clock::now();
  if (now - last < std::chrono::milliseconds(20) || !Py_IsInitialized()) return false;
  last = now;
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() == 0) return false;
  Py_XDECREF(g_pending.type);  // an earlier one never raised (not expected)
  Py_XDECREF(g_pending.value);
  Py_XDECREF(g_pending.traceback);
  PyErr_Fetch(&g_pending.type, &g_pending.value, &g_pending.traceback);
  return true;
}

// Sets the Python error for an Interrupted: the signal handler's exception, else
// KeyboardInterrupt with the C++ message.
void raise_interrupted(const Interrupted& e) {
  if (g_pending.type) {
    PyErr_Restore(g_pending.type, g_pending.value, g_pending.traceback);
    g_pending = {};
  } else {
    PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
  }
}

}  // namespace

void bind_interrupts() { set_interrupt_check(&python_interrupt_check); }

void bind_errors(py::module_& m) {
  g_error = new_exception(m, "Error", PyExc_Exception,
                          "Base of every error softhd raises (softhd::Error in C++).");
  const py::tuple value_bases = py::make_tuple(py::handle(g_error), py::handle(PyExc_ValueError));
  g_invalid = new_exception(m, "InvalidArgument", value_bases.ptr(),
                            "An argument outside its valid range (a ValueError).");
  const py::tuple os_bases = py::make_tuple(py::handle(g_error), py::handle(PyExc_OSError));
  g_file = new_exception(m, "FileError", os_bases.ptr(),
                         "A file that cannot be opened, read, parsed or written (an OSError).");
  g_resource = new_exception(m, "ResourceError", g_error,
                             "A problem larger than the configured limits (memory estimate).");
  g_numerical = new_exception(m, "NumericalError", g_error,
                              "A numerical operation that cannot be carried out on valid input.");
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Interrupted& e) {
      raise_interrupted(e);
    } catch (const InvalidArgument& e) {
      PyErr_SetString(g_invalid, e.what());
    } catch (const FileError& e) {
      PyErr_SetString(g_file, e.what());
    } catch (const ResourceError& e) {
      PyErr_SetString(g_resource, e.what());
    } catch (const NumericalError& e) {
      PyErr_SetString(g_numerical, e.what());
    } catch (const Error& e) {
      PyErr_SetString(g_error, e.what());
    } catch (const std::filesystem::filesystem_error& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    }
  });
}

}  // namespace softhd::python

PYBIND11_MODULE(_core, m) {
  m.doc() = "The compiled core of softhd; use the package softhd, which wraps it.";
  softhd::python::bind_errors(m);
  softhd::python::bind_interrupts();
  softhd::python::bind_hausdorff(m);
  softhd::python::bind_scan(m);
  softhd::python::bind_io(m);
  softhd::python::bind_align(m);
  softhd::python::bind_mesh(m);
  softhd::python::bind_fe(m);
  softhd::python::bind_optimise(m);
}
