// C++ errors as Python exceptions, with the C++ message unchanged:
//   InvalidInputError             -> ValueError
//   FileError (an InvalidInputError about a file that cannot be opened, read or written)
//                                 -> OSError, the subclass its errno names (FileNotFoundError,
//                                    IsADirectoryError, PermissionError), errno set
//   NoSurfaceError                -> cdp.NoSurfaceError(RuntimeError)
//   LimitExceededError            -> cdp.LimitExceededError(RuntimeError)
//   CancelledError                -> cdp.CancelledError(RuntimeError) (cdp.CancelToken.cancel();
//                                    Ctrl-C during a run raises KeyboardInterrupt instead)
// Python exceptions raised inside callbacks (a callable field, a progress callable, Ctrl-C)
// travel through the C++ code as py::error_already_set and come out as themselves.
#include "bindings.h"

#include <cdp/core/cancel.h>
#include <cdp/core/errors.h>

#include <cerrno>

namespace cdp::python {

namespace {

PyObject* os_error_type(int error_number) {
  switch (error_number) {
    case ENOENT: return PyExc_FileNotFoundError;
    case EISDIR: return PyExc_IsADirectoryError;
    case ENOTDIR: return PyExc_NotADirectoryError;
    case EACCES:
    case EPERM: return PyExc_PermissionError;
    default: return PyExc_OSError;
  }
}

// Owned by the module: created once at import, never freed (the interpreter may be gone by the
// time static destructors run).
PyObject* g_no_surface = nullptr;
PyObject* g_limit_exceeded = nullptr;
PyObject* g_cancelled = nullptr;

// A Python object shared by copies of a std::function: the C++ algorithms copy their callbacks
// while the GIL is released, and copying a py::object would touch its reference count without
// it. The last copy to go takes the GIL to let go of the object.
std::shared_ptr<py::object> hold(py::object object) {
  return std::shared_ptr<py::object>(new py::object(std::move(object)), [](py::object* p) {
    py::gil_scoped_acquire gil;
    delete p;
  });
}

}  // namespace

ProgressCallback interruptible_progress(py::object user) {
  return [user = hold(std::move(user))](double fraction) {
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    if (!user->is_none()) (*user)(fraction);
  };
}

PhaseCallback interruptible_phase(py::object user) {
  return [user = hold(std::move(user))](const std::string& phase) {
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    if (!user->is_none()) (*user)(phase);
  };
}

void bind_errors(py::module_& m) {
  g_no_surface = PyErr_NewExceptionWithDoc(
      "cdp.NoSurfaceError",
      "The field has no usable surface: no zero crossing in its box, a surface leaving the box, NaN "
      "values, a vanishing gradient where a surface point was expected, or a finished mesh that fails its "
      "checks (cdp::NoSurfaceError).",
      PyExc_RuntimeError, nullptr);
  g_limit_exceeded = PyErr_NewExceptionWithDoc(
      "cdp.LimitExceededError",
      "An algorithm hit one of its bounds (steps, triangles, cubes, area) before finishing "
      "(cdp::LimitExceededError).",
      PyExc_RuntimeError, nullptr);
  g_cancelled = PyErr_NewExceptionWithDoc(
      "cdp.CancelledError", "The run was cancelled through its cdp.CancelToken (cdp::CancelledError).",
      PyExc_RuntimeError, nullptr);
  if (!g_no_surface || !g_limit_exceeded || !g_cancelled) throw py::error_already_set();
  m.add_object("CancelledError", py::handle(g_cancelled));
  m.add_object("NoSurfaceError", py::handle(g_no_surface));
  m.add_object("LimitExceededError", py::handle(g_limit_exceeded));

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const FileError& e) {
      const py::object type = py::reinterpret_borrow<py::object>(os_error_type(e.error_number()));
      // One argument, so that str(error) is the C++ message; errno is set on its own.
      const py::object error = type(e.what());
      if (e.error_number() != 0) error.attr("errno") = e.error_number();
      PyErr_SetObject(type.ptr(), error.ptr());
    } catch (const InvalidInputError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const NoSurfaceError& e) {
      PyErr_SetString(g_no_surface, e.what());
    } catch (const LimitExceededError& e) {
      PyErr_SetString(g_limit_exceeded, e.what());
    } catch (const CancelledError& e) {
      PyErr_SetString(g_cancelled, e.what());
    }
  });
}

}  // namespace cdp::python
