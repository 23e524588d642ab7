// What the binding files of the `cdp` module share: numpy and JSON conversions, the callbacks
// that keep long C++ runs interruptible, and one registration function per file.
#pragma once

#include <cdp/core/field.h>
#include <cdp/core/mesh.h>
#include <cdp/core/progress.h>

#include <nlohmann/json.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace cdp::python {

namespace py = pybind11;

void bind_errors(py::module_& m);
void bind_fields(py::module_& m);
void bind_meshing(py::module_& m);
void bind_analysis(py::module_& m);
void bind_mesh_files(py::module_& m);
void bind_volume(py::module_& m);

// Points per batched field evaluation the bindings ask for (Field.gradients and .hessians,
// curvature, project): a callable field's central differences put 25 points per point into one
// numpy array for Hessians, 10 MB for this many points; larger inputs take several calls.
inline constexpr std::size_t kBindingBatch = std::size_t{1} << 14;

// --- conversions (conversions.cpp); every error is InvalidInputError, raised as ValueError ---

// An (N, 3) array of numbers (anything numpy can turn into float64). `what` names the argument.
std::vector<Vec3> points_from(py::handle object, const std::string& what);
// An (M, 3) array of integers, each in [0, vertices).
std::vector<std::array<int, 3>> faces_from(py::handle object, std::size_t vertices, const std::string& what);
// A mesh from vertex, face and optional normal arrays, checked as the mesh readers check files
// (finite coordinates and normals, indices in range, at least one triangle), so that whatever a
// Python caller hands the C++ code is something a file could have held.
Mesh mesh_from(py::handle vertices, py::handle faces, py::handle normals);
// ((xmin, ymin, zmin), (xmax, ymax, zmax)) with min < max on every axis, finite.
Box box_from(py::handle object, const std::string& what);

py::array_t<double> to_array(const std::vector<Vec3>& points);
py::array_t<double> to_array(const std::vector<double>& values);
py::array_t<std::int32_t> to_array(const std::vector<std::array<int, 3>>& faces);
py::array_t<double> to_array(const Box& box);

// Python objects (dict, list, tuple, str, numbers, bool, None, numpy arrays and scalars,
// os.PathLike) to JSON; `where` names the object in messages ("cdp.sphere: center[1]: ...").
// NaN and infinities are refused: a JSON file cannot hold them, so the readers never see them.
nlohmann::json to_json(py::handle object, const std::string& where);
py::object from_json(const nlohmann::json& j);
// "(x, y, z)" with the shortest decimals that read back as the same doubles, as Python's repr of
// a float writes them: the messages and reprs of the module.
std::string point_text(const Vec3& p);

// --- interruption (errors.cpp) ---

// The progress and phase callbacks handed to the C++ algorithms. Each takes the GIL, runs
// Python's signal handlers (PyErr_CheckSignals: Ctrl-C raises KeyboardInterrupt there) and calls
// the user's callable when one was given; a Python exception becomes py::error_already_set,
// which unwinds the algorithm and is raised again when the binding returns.
ProgressCallback interruptible_progress(py::object user);
PhaseCallback interruptible_phase(py::object user);

}  // namespace cdp::python
