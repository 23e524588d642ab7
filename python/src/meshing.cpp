// polygonize, marching_cubes, marching_tetrahedra: the options of build/bin/polygonize as
// keywords, the same library calls, so that the same field and options give the same arrays as
// the program's mesh file. The GIL is released while the C++ code runs; the progress callback
// takes it back to look for Ctrl-C.
#include "bindings.h"

#include <cdp/baselines/marching_cubes.h>
#include <cdp/baselines/marching_tetrahedra.h>
#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/cancel.h>
#include <cdp/core/errors.h>
#include <cdp/core/mesh_angles.h>
#include <cdp/core/models/level_shift.h>
#include <cdp/io/polygonize_options.h>
#include <cdp/io/polygonize_stats_json.h>

#include <pybind11/stl.h>

#include <atomic>
#include <csignal>
#include <optional>

namespace cdp::python {

namespace {

// Ctrl-C during a run on the main thread: for the run's length SIGINT cancels its token (an
// atomic store, safe in a signal handler), so the run stops at its next poll wherever it is (the
// progress callback, which also looks for Ctrl-C, is not called during the repair or the
// checks); the binding then raises KeyboardInterrupt through Python's own handler. Python's
// handler is put back when the run ends. Elsewhere (another thread, a run inside a callback of
// a run) nothing is installed.
std::atomic<const CancelToken*> g_sigint_token{nullptr};
std::atomic<bool> g_sigint_fired{false};

extern "C" void cancel_on_sigint(int) {
  if (const CancelToken* t = g_sigint_token.load()) t->cancel();
  g_sigint_fired.store(true);
}

class SigintCancels {
 public:
  explicit SigintCancels(const CancelToken& token) {
    const py::module_ threading = py::module_::import("threading");
    if (!threading.attr("current_thread")().is(threading.attr("main_thread")())) return;
    const CancelToken* none = nullptr;
    if (!g_sigint_token.compare_exchange_strong(none, &token)) return;
    g_sigint_fired.store(false);
    struct sigaction sa {};
    sa.sa_handler = cancel_on_sigint;
    sigemptyset(&sa.sa_mask);
    installed_ = sigaction(SIGINT, &sa, &previous_) == 0;
    if (!installed_) g_sigint_token.store(nullptr);
  }
  // Puts Python's handler back; true if SIGINT came during the run.
  bool restore() {
    if (!installed_) return false;
    sigaction(SIGINT, &previous_, nullptr);
    installed_ = false;
    g_sigint_token.store(nullptr);
    return g_sigint_fired.exchange(false);
  }
  ~SigintCancels() { restore(); }
  SigintCancels(const SigintCancels&) = delete;
  SigintCancels& operator=(const SigintCancels&) = delete;

 private:
  bool installed_ = false;
  struct sigaction previous_ {};
};

// After a run: Python's handler back, and if SIGINT came during the run, handed to it as if it
// had come now (KeyboardInterrupt by default), whatever the run ended with (CancelledError at its
// next poll, or a result or another error when the signal came after its last one).
void reraise_sigint(SigintCancels& sigint) {
  if (!sigint.restore()) return;
  PyErr_SetInterrupt();
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();
}

// A keyword's value as the options table takes it (cdp/io/polygonize_options.h): a bool, an
// integer, a float (numpy's too) or a str; None for the default.
nlohmann::json option_value(const std::string& name, py::handle v) {
  if (v.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(v)) return v.cast<bool>();
  if (py::isinstance<py::str>(v)) return v.cast<std::string>();
  if (PyIndex_Check(v.ptr())) {
    try {
      return py::int_(py::reinterpret_borrow<py::object>(v)).cast<long long>();
    } catch (const py::cast_error&) {
      return py::float_(py::reinterpret_borrow<py::object>(v)).cast<double>();  // beyond long long: out of every range
    }
  }
  if (py::hasattr(v, "__float__")) return py::float_(py::reinterpret_borrow<py::object>(v)).cast<double>();
  throw InvalidInputError(name + " must be a number, a string or a bool, not a " +
                          py::str(py::type::of(v).attr("__name__")).cast<std::string>());
}

// The keywords as the options table takes them; a keyword the table does not know is a
// TypeError, as Python's own for a function's keywords, with the nearest known name.
nlohmann::json options_json(const char* function, const py::kwargs& kwargs) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [key, value] : kwargs) {
    const std::string name = py::str(key);
    if (!find_polygonize_option(name)) {
      const auto near = nearest_polygonize_option(name);
      throw py::type_error(std::string(function) + "() got an unexpected keyword argument '" + name + "'" +
                           (near ? " (did you mean '" + std::string(*near) + "'?)" : std::string()));
    }
    j[name] = option_value(name, value);
  }
  return j;
}

// A Python callable as the run's block runner (block_tasks.h): called with the tasks as a list of
// bytes and a function that says whether the run was cancelled (its token, which Ctrl-C cancels
// while the run is on), it returns the pieces as a sequence of bytes. It holds the callable by
// pointer (the caller's reference keeps it alive for the run), since the run copies its options
// with the GIL released.
BlockRunner python_block_runner(py::handle runner, const CancelToken& token) {
  PyObject* callable = runner.ptr();
  return [callable, token](const std::vector<std::string>& tasks) {
    py::gil_scoped_acquire gil;
    py::list list;
    for (const std::string& t : tasks) list.append(py::bytes(t));
    const py::cpp_function cancelled([token] { return token.cancelled(); });
    const py::object pieces = py::reinterpret_borrow<py::object>(callable)(list, cancelled);
    token.check("adaptive");
    std::vector<std::string> out;
    for (const py::handle piece : pieces) {
      if (!py::isinstance<py::bytes>(piece))
        throw py::type_error("block_runner must return bytes for each task, not " +
                             py::str(py::type::of(piece).attr("__name__")).cast<std::string>());
      out.push_back(piece.cast<std::string>());
    }
    return out;
  };
}

py::tuple run(const Field& unshifted, const std::string& method, const nlohmann::json& options, py::object progress,
              py::object phase, const std::optional<CancelToken>& cancel, py::object block_runner = py::none()) {
  PolygonizeRequest request = polygonize_request(method, options);
  if (!block_runner.is_none() && (method != "adaptive" || !request.adaptive.blocks.value_or(false)))
    throw InvalidInputError("polygonize: block_runner needs method \"adaptive\" with blocks=True");
  std::optional<LevelShift> shifted;
  const Field& field = request.level != 0 ? shifted.emplace(unshifted, request.level) : unshifted;
  PolygonizeResult result;
  const CancelToken token = cancel ? *cancel : CancelToken();
  SigintCancels sigint(token);
  try {
    if (method == "adaptive") {
      AdaptiveOptions& a = request.adaptive;
      a.progress = interruptible_progress(progress);
      a.phase = interruptible_phase(phase);
      a.cancel = token;
      if (!block_runner.is_none()) a.block_runner = python_block_runner(block_runner, token);
      py::gil_scoped_release release;
      result = polygonize_adaptive(field, a);
    } else {
      MarchingOptions& m = request.marching;
      m.progress = interruptible_progress(progress);
      m.cancel = token;
      // The marching methods have one phase; it is announced as the program announces it.
      interruptible_phase(phase)("meshing");
      py::gil_scoped_release release;
      result = method == "mc" ? marching_cubes(field, m) : marching_tetrahedra(field, m);
    }
  } catch (...) {
    reraise_sigint(sigint);
    throw;
  }
  reraise_sigint(sigint);
  // The program's STATS.json entries (apps/polygonize.cpp), so that the dicts stay equal.
  add_mesh_summary(result.mesh, result.stats);
  py::object stats = from_json(to_json(result.stats));
  py::array_t<double> vertices = to_array(result.mesh.positions);
  py::array_t<std::int32_t> faces = to_array(result.mesh.triangles);
  py::object normals = result.mesh.normals.size() == result.mesh.positions.size() ? py::object(to_array(result.mesh.normals))
                                                                                 : py::object(py::none());
  return py::make_tuple(vertices, faces, normals, stats);
}

constexpr const char* kPolygonizeDoc = R"(Meshes the zero set of a field (the set F = level with level=).

Returns a cdp.Mesh, a named tuple (vertices (N, 3) float64, faces (M, 3) int32, normals (N, 3)
float64 or None where the method has none, stats dict): mesh.vertices or V, F, N, stats = mesh.
Faces are counter-clockwise seen from outside. stats is build/bin/polygonize's STATS.json as a
dict (without "field"); stats["summary"], the entry to read first, says whether the mesh is watertight (closed,
manifold, oriented, outward, no degenerate triangle), its components, genus and smallest angle.

method: "adaptive" (the paper's tracker, the default), "mc" or "mt" (Marching Cubes / Tetrahedra).
The options are the polygonize program's (the same names, defaults and choices: --min-edge is
min_edge; cdp.polygonize_options() lists them); None means the default. An option the method
does not use, or a bad value, is a ValueError; an unknown keyword a TypeError naming the nearest
option. progress(fraction) and phase(name) are called from the run with the GIL held; Ctrl-C
interrupts it with KeyboardInterrupt. cancel (a cdp.CancelToken): its cancel(), from another
thread, ends the run with cdp.CancelledError. client (a dask.distributed.Client, python/cdp/distributed.py):
the blocks are meshed as tasks on its workers, the same mesh bit for bit (method "adaptive", blocks
on). block_runner: the hook it uses, a callable taking the blocks' tasks (a list of bytes) and a
function cancelled() (true once cancel or Ctrl-C asked the run to stop: it should then raise), and
returning cdp._run_block_task(field, task, level) of each, in order.

Options:
)";

// The docstring: `head` and a line for each option of the table that applies to `method` (all
// of them for none).
std::string polygonize_doc(const std::string& head, const char* method = nullptr) {
  std::string doc = head;
  for (const OptionSpec& spec : polygonize_options()) {
    if (method && !applies_to(spec, method)) continue;
    const char* methods = spec.methods == OptionMethods::All        ? "all methods"
                          : spec.methods == OptionMethods::Adaptive ? "adaptive"
                          : spec.methods == OptionMethods::Marching ? "mc, mt"
                                                                    : "mc";
    doc += "  " + std::string(spec.name) + " (" + methods;
    if (!spec.default_text.empty()) doc += "; default " + std::string(spec.default_text);
    doc += "): " + std::string(spec.help) + "\n";
  }
  return doc;
}

py::list options_list() {
  static const char* const kinds[] = {"number", "integer", "choice", "flag", "boolean", "real"};
  py::list out;
  for (const OptionSpec& spec : polygonize_options()) {
    py::dict d;
    d["name"] = std::string(spec.name);
    d["kind"] = kinds[static_cast<int>(spec.kind)];
    py::list methods;
    for (const char* m : {"adaptive", "mc", "mt"})
      if (applies_to(spec, m)) methods.append(m);
    d["methods"] = methods;
    d["default"] = spec.default_text.empty() ? py::object(py::none()) : py::object(py::str(std::string(spec.default_text)));
    py::list choices;
    for (const auto& c : spec.choices) choices.append(std::string(c));
    d["choices"] = choices;
    d["flag"] = option_flag(spec);
    d["help"] = std::string(spec.help);
    out.append(d);
  }
  return out;
}

}  // namespace

void bind_meshing(py::module_& m) {
  py::class_<CancelToken>(m, "CancelToken", R"(Cancels a run from another thread (cdp::CancelToken).

Pass it as cancel= to polygonize, marching_cubes or marching_tetrahedra (which release the GIL while
they run) and call cancel() from another thread: the run ends with cdp.CancelledError at its next
poll. reset() makes the token usable again. Ctrl-C needs no token: it raises KeyboardInterrupt.)")
      .def(py::init<>())
      .def("cancel", &CancelToken::cancel, "Ends every run holding this token with cdp.CancelledError.")
      .def("reset", &CancelToken::reset, "Makes the token usable for another run.")
      .def_property_readonly("cancelled", &CancelToken::cancelled);
  static const std::string doc = polygonize_doc(kPolygonizeDoc);
  static const std::string mc_doc = polygonize_doc(
      "polygonize(field, \"mc\", ...): Marching Cubes, returning a cdp.Mesh; see polygonize. progress(fraction) is "
      "called from the run; cancel (a cdp.CancelToken) ends it with cdp.CancelledError.\n\nOptions:\n",
      "mc");
  static const std::string mt_doc = polygonize_doc(
      "polygonize(field, \"mt\", ...): Marching Tetrahedra, the paper's baseline, returning a cdp.Mesh; see "
      "polygonize. progress(fraction) is called from the run; cancel (a cdp.CancelToken) ends it with "
      "cdp.CancelledError.\n\nOptions:\n",
      "mt");
  m.def(
      "polygonize",
      [](const Field& field, const std::string& method, py::object progress, py::object phase,
         std::optional<CancelToken> cancel, py::object block_runner, const py::kwargs& options) {
        return run(field, method, options_json("polygonize", options), progress, phase, cancel, block_runner);
      },
      py::arg("field"), py::arg("method") = "adaptive", py::kw_only(), py::arg("progress") = py::none(),
      py::arg("phase") = py::none(), py::arg("cancel") = py::none(), py::arg("block_runner") = py::none(), doc.c_str());
  // One block's task (cdp/core/block_tasks.h) on the field of the run, shifted by the run's level:
  // what a cluster's workers run (python/cdp/distributed.py). The GIL is released while it runs.
  m.def(
      "_run_block_task",
      [](const Field& field, const py::bytes& task, double level) {
        const std::string bytes = task;
        std::string piece;
        {
          py::gil_scoped_release release;
          std::optional<LevelShift> shifted;  // as run() shifts the run's field
          piece = run_block_task(level != 0 ? shifted.emplace(field, level) : field, bytes);
        }
        return py::bytes(piece);
      },
      py::arg("field"), py::arg("task"), py::arg("level") = 0.0);
  const auto marching = [](const char* method, const char* name) {
    return [method, name](const Field& field, py::object progress, std::optional<CancelToken> cancel,
                          const py::kwargs& options) {
      return run(field, method, options_json(name, options), progress, py::none(), cancel);
    };
  };
  m.def("marching_cubes", marching("mc", "marching_cubes"), py::arg("field"), py::kw_only(),
        py::arg("progress") = py::none(), py::arg("cancel") = py::none(), mc_doc.c_str());
  m.def("marching_tetrahedra", marching("mt", "marching_tetrahedra"), py::arg("field"), py::kw_only(),
        py::arg("progress") = py::none(), py::arg("cancel") = py::none(), mt_doc.c_str());
  m.def("polygonize_options", &options_list,
        "The options of polygonize, marching_cubes and marching_tetrahedra: one dict each (name, kind, methods, "
        "default, choices, the program's flag, help), the table the polygonize program and experiment files share.");
}

}  // namespace cdp::python
