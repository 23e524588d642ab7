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
#include <cdp/io/polygonize_stats_json.h>

#include <pybind11/stl.h>

#include <atomic>
#include <climits>
#include <cmath>
#include <csignal>
#include <optional>

namespace cdp::python {

namespace {

struct Options {
  std::string method = "adaptive";
  std::optional<double> factor, tolerance, chord, min_edge, max_edge, cell;
  std::optional<long long> precision, seed_resolution, max_triangles;
  std::optional<std::string> triangle_count, traversal, face_ambiguity;
  std::optional<bool> check_self_intersections;
  std::optional<long long> threads;
  std::optional<std::string> creases;
  std::optional<CancelToken> cancel;
};

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

std::string number_text(double v) { return py::str(py::float_(v)); }

double positive(const std::optional<double>& v, const char* name) {
  if (!(std::isfinite(*v) && *v > 0)) throw InvalidInputError(std::string(name) + " must be a positive number, not " + number_text(*v));
  return *v;
}

long long integer_in(const std::optional<long long>& v, const char* name, long long lo, long long hi) {
  if (*v < lo || *v > hi)
    throw InvalidInputError(std::string(name) + " must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                            "], not " + std::to_string(*v));
  return *v;
}

// A keyword the chosen method would ignore is an error, as the program's flags are.
void check_applies(const Options& o) {
  const bool adaptive = o.method == "adaptive";
  const auto refuse = [&](bool given, const char* name) {
    if (given) throw InvalidInputError(std::string(name) + " does not apply to method \"" + o.method + "\"");
  };
  if (adaptive) {
    refuse(o.cell.has_value(), "cell");
    refuse(o.precision.has_value(), "precision");
    refuse(o.traversal.has_value(), "traversal");
    refuse(o.face_ambiguity.has_value(), "face_ambiguity");
  } else {
    refuse(o.factor.has_value(), "factor");
    refuse(o.tolerance.has_value(), "tolerance");
    refuse(o.chord.has_value(), "chord");
    refuse(o.min_edge.has_value(), "min_edge");
    refuse(o.max_edge.has_value(), "max_edge");
    refuse(o.triangle_count.has_value(), "triangle_count");
    refuse(o.creases.has_value(), "creases");
    refuse(o.check_self_intersections.has_value(), "check_self_intersections");
    if (o.method == "mt") refuse(o.face_ambiguity.has_value(), "face_ambiguity");
  }
}

AdaptiveOptions adaptive_options(const Options& o) {
  AdaptiveOptions a;
  if (int(o.factor.has_value()) + int(o.tolerance.has_value()) + int(o.chord.has_value()) > 1)
    throw InvalidInputError("give one of factor, tolerance and chord, not several");
  // The Python default is the paper's bunny example, factor 3 (the library's and the program's
  // is 2): pass factor explicitly to compare with a program run without --factor.
  a.factor = o.factor ? positive(o.factor, "factor") : 3.0;
  if (o.tolerance) {
    a.sizing = SizingMode::Tolerance;
    a.tolerance = positive(o.tolerance, "tolerance");
  }
  if (o.chord) {
    a.sizing = SizingMode::Chord;
    a.tolerance = positive(o.chord, "chord");
  }
  if (o.min_edge) a.min_edge = positive(o.min_edge, "min_edge");
  if (o.max_edge) a.max_edge = positive(o.max_edge, "max_edge");
  if (o.triangle_count) {
    if (*o.triangle_count == "hartmann") a.triangle_count = TriangleCountRule::Hartmann;
    else if (*o.triangle_count == "paper") a.triangle_count = TriangleCountRule::PaperFloor;
    else throw InvalidInputError("triangle_count must be \"hartmann\" or \"paper\", not \"" + *o.triangle_count + "\"");
  }
  if (o.creases) {
    if (*o.creases == "follow") a.creases = CreaseHandling::Follow;
    else if (*o.creases == "ignore") a.creases = CreaseHandling::Ignore;
    else throw InvalidInputError("creases must be \"follow\" or \"ignore\", not \"" + *o.creases + "\"");
  }
  if (o.seed_resolution) a.seed_resolution = static_cast<int>(integer_in(o.seed_resolution, "seed_resolution", 2, INT_MAX));
  if (o.max_triangles) a.max_triangles = static_cast<std::size_t>(integer_in(o.max_triangles, "max_triangles", 1, INT_MAX));
  if (o.check_self_intersections) a.check_self_intersections = *o.check_self_intersections;
  if (o.threads) a.threads = static_cast<int>(integer_in(o.threads, "threads", 0, INT_MAX));
  return a;
}

MarchingOptions marching_options(const Options& o) {
  MarchingOptions m;
  // 0 means "the default" inside the library; given here it is a mistake.
  if (o.cell) m.cell_size = positive(o.cell, "cell");
  if (o.precision) m.precision = static_cast<int>(integer_in(o.precision, "precision", 0, 5));
  if (o.traversal) {
    if (*o.traversal == "continuation") m.traversal = Traversal::Continuation;
    else if (*o.traversal == "grid") m.traversal = Traversal::Grid;
    else throw InvalidInputError("traversal must be \"continuation\" or \"grid\", not \"" + *o.traversal + "\"");
  }
  if (o.face_ambiguity) {
    if (*o.face_ambiguity == "asymptotic_decider") m.face_ambiguity = FaceAmbiguity::AsymptoticDecider;
    else if (*o.face_ambiguity == "join_inside") m.face_ambiguity = FaceAmbiguity::JoinInside;
    else if (*o.face_ambiguity == "separate_inside") m.face_ambiguity = FaceAmbiguity::SeparateInside;
    else
      throw InvalidInputError("face_ambiguity must be \"asymptotic_decider\", \"join_inside\" or \"separate_inside\", not \"" +
                              *o.face_ambiguity + "\"");
  }
  if (o.seed_resolution) m.seed_resolution = static_cast<int>(integer_in(o.seed_resolution, "seed_resolution", 2, INT_MAX));
  if (o.max_triangles) m.max_triangles = static_cast<std::size_t>(integer_in(o.max_triangles, "max_triangles", 1, INT_MAX));
  if (o.threads) m.threads = static_cast<int>(integer_in(o.threads, "threads", 0, INT_MAX));
  return m;
}

py::tuple run(const Field& field, const Options& o, bool return_normals, py::object progress, py::object phase) {
  if (o.method != "adaptive" && o.method != "mc" && o.method != "mt")
    throw InvalidInputError("method must be \"adaptive\", \"mc\" or \"mt\", not \"" + o.method + "\"");
  check_applies(o);
  PolygonizeResult result;
  const CancelToken token = o.cancel ? *o.cancel : CancelToken();
  SigintCancels sigint(token);
  try {
    if (o.method == "adaptive") {
      AdaptiveOptions a = adaptive_options(o);
      a.progress = interruptible_progress(progress);
      a.phase = interruptible_phase(phase);
      a.cancel = token;
      py::gil_scoped_release release;
      result = polygonize_adaptive(field, a);
    } else {
      MarchingOptions m = marching_options(o);
      m.progress = interruptible_progress(progress);
      m.cancel = token;
      // The marching methods have one phase; it is announced as the program announces it.
      interruptible_phase(phase)("meshing");
      py::gil_scoped_release release;
      result = o.method == "mc" ? marching_cubes(field, m) : marching_tetrahedra(field, m);
    }
  } catch (...) {
    reraise_sigint(sigint);
    throw;
  }
  reraise_sigint(sigint);
  // The program's STATS.json entries (apps/polygonize.cpp), so that the dicts stay equal.
  add_angle_statistics(result.mesh, result.stats);
  py::object stats = from_json(to_json(result.stats));
  py::array_t<double> vertices = to_array(result.mesh.positions);
  py::array_t<std::int32_t> faces = to_array(result.mesh.triangles);
  if (!return_normals) return py::make_tuple(vertices, faces, stats);
  py::object normals = result.mesh.normals.size() == result.mesh.positions.size() ? py::object(to_array(result.mesh.normals))
                                                                                 : py::object(py::none());
  return py::make_tuple(vertices, faces, normals, stats);
}

constexpr const char* kPolygonizeDoc = R"(Meshes the zero set of a field.

Returns (vertices (N, 3) float64, faces (M, 3) int32, stats dict), or with return_normals=True
(vertices, faces, normals (N, 3) float64, stats). Faces are counter-clockwise seen from outside.
stats is build/bin/polygonize's STATS.json as a dict (without "field").

method "adaptive" (the paper's tracker): factor (default 3: edge = minimum radius of curvature /
factor), tolerance (chord deviation, and every triangle measured and split until it lies within
it of the surface where it can) or chord (the same sizing without the bound: nothing measured),
min_edge, max_edge, triangle_count ("hartmann" or "paper"), creases ("follow", the default: mesh edges along the creases of a min/max/abs field, or
"ignore"), seed_resolution, max_triangles, check_self_intersections.
Both: threads (0, the default, all cores, at most 8; 1 the calling thread only) for the seed grid of
a thread-safe field and the adaptive method's final check; the mesh is the same on any number.
method "mc" or "mt" (Marching Cubes / Tetrahedra): cell or precision (0..5, data-driven models),
traversal ("continuation" or "grid"), face_ambiguity (mc: "asymptotic_decider", "join_inside",
"separate_inside"), seed_resolution, max_triangles.
A keyword the method does not use is a ValueError. progress(fraction) and phase(name) are called
from the run with the GIL held; Ctrl-C interrupts it with KeyboardInterrupt. cancel (a
cdp.CancelToken): its cancel(), from another thread, ends the run with cdp.CancelledError.)";

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
  m.def(
      "polygonize",
      [](const Field& field, std::string method, std::optional<double> factor, std::optional<double> tolerance,
         std::optional<double> chord, std::optional<double> min_edge, std::optional<double> max_edge, std::optional<double> cell,
         std::optional<long long> precision, std::optional<std::string> traversal, std::optional<std::string> face_ambiguity,
         std::optional<std::string> triangle_count, std::optional<long long> seed_resolution,
         std::optional<long long> max_triangles, std::optional<bool> check_self_intersections,
         std::optional<long long> threads, std::optional<std::string> creases, bool return_normals, py::object progress,
         py::object phase, std::optional<CancelToken> cancel) {
        Options o{method,        factor,         tolerance,      chord,          min_edge,       max_edge,
                  cell,          precision,      seed_resolution, max_triangles, triangle_count,
                  traversal,     face_ambiguity, check_self_intersections, threads, creases, cancel};
        return run(field, o, return_normals, progress, phase);
      },
      py::arg("field"), py::arg("method") = "adaptive", py::kw_only(), py::arg("factor") = py::none(),
      py::arg("tolerance") = py::none(), py::arg("chord") = py::none(), py::arg("min_edge") = py::none(), py::arg("max_edge") = py::none(),
      py::arg("cell") = py::none(), py::arg("precision") = py::none(), py::arg("traversal") = py::none(),
      py::arg("face_ambiguity") = py::none(), py::arg("triangle_count") = py::none(),
      py::arg("seed_resolution") = py::none(), py::arg("max_triangles") = py::none(),
      py::arg("check_self_intersections") = py::none(), py::arg("threads") = py::none(),
      py::arg("creases") = py::none(), py::arg("return_normals") = false,
      py::arg("progress") = py::none(), py::arg("phase") = py::none(), py::arg("cancel") = py::none(), kPolygonizeDoc);

  const auto marching = [](const char* method) {
    return [method](const Field& field, std::optional<double> cell, std::optional<long long> precision,
                    std::optional<std::string> traversal, std::optional<std::string> face_ambiguity,
                    std::optional<long long> seed_resolution, std::optional<long long> max_triangles, bool return_normals,
                    py::object progress, std::optional<CancelToken> cancel) {
      Options o;
      o.method = method;
      o.cell = cell;
      o.precision = precision;
      o.traversal = traversal;
      o.face_ambiguity = face_ambiguity;
      o.seed_resolution = seed_resolution;
      o.max_triangles = max_triangles;
      o.cancel = cancel;
      return run(field, o, return_normals, progress, py::none());
    };
  };
  m.def("marching_cubes", marching("mc"), py::arg("field"), py::kw_only(), py::arg("cell") = py::none(),
        py::arg("precision") = py::none(), py::arg("traversal") = py::none(), py::arg("face_ambiguity") = py::none(),
        py::arg("seed_resolution") = py::none(), py::arg("max_triangles") = py::none(), py::arg("return_normals") = false,
        py::arg("progress") = py::none(), py::arg("cancel") = py::none(), "polygonize(field, \"mc\", ...): Marching Cubes; see polygonize.");
  m.def("marching_tetrahedra", marching("mt"), py::arg("field"), py::kw_only(), py::arg("cell") = py::none(),
        py::arg("precision") = py::none(), py::arg("traversal") = py::none(), py::arg("face_ambiguity") = py::none(),
        py::arg("seed_resolution") = py::none(), py::arg("max_triangles") = py::none(), py::arg("return_normals") = false,
        py::arg("progress") = py::none(), py::arg("cancel") = py::none(),
        "polygonize(field, \"mt\", ...): Marching Tetrahedra, the paper's baseline; see polygonize.");
}

}  // namespace cdp::python
