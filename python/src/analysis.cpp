// curvature, project and evaluate: the curvature program, the Newton projection and the
// evaluate program on arrays.
#include "bindings.h"

#include <cdp/core/crease_curves.h>
#include <cdp/core/curvature.h>
#include <cdp/core/errors.h>
#include <cdp/core/mesh_angles.h>
#include <cdp/core/newton_projection.h>
#include <cdp/raytrace/evaluate.h>
#include <cdp/raytrace/phong_normal.h>

#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

namespace cdp::python {

namespace {

using namespace pybind11::literals;

py::dict curvature(const Field& field, py::handle points_in) {
  const std::vector<Vec3> points = points_from(points_in, "points");
  std::vector<Curvature> c(points.size());
  {
    py::gil_scoped_release release;
    const std::size_t batch = std::min(kBindingBatch, points.size());
    std::vector<double> values(batch);
    std::vector<Vec3> gradients(batch);
    std::vector<Mat3> hessians(batch);
    for (std::size_t s = 0; s < points.size(); s += kBindingBatch) {
      const std::size_t m = std::min(kBindingBatch, points.size() - s);
      field.gradients_hessians(&points[s], values.data(), gradients.data(), hessians.data(), m);
      for (std::size_t k = 0; k < m; ++k) {
        const std::size_t i = s + k;
        try {
          c[i] = curvature_from_derivatives(gradients[k], hessians[k]);
        } catch (const NoSurfaceError& e) {
          // Which of the points, as the programs name the file.
          throw NoSurfaceError("points[" + std::to_string(i) + "] " + point_text(points[i]) + ": " + e.what());
        }
      }
    }
  }
  const std::size_t n = c.size();
  std::vector<Vec3> normal(n), dir1(n), dir2(n);
  std::vector<double> k1(n), k2(n), gaussian(n), mean(n), mac(n), min_radius(n), shape_index(n);
  py::array_t<double> C({static_cast<py::ssize_t>(n), py::ssize_t{3}, py::ssize_t{3}});
  double* Cd = C.mutable_data();
  for (std::size_t i = 0; i < n; ++i) {
    normal[i] = c[i].normal;
    dir1[i] = c[i].dir1;
    dir2[i] = c[i].dir2;
    k1[i] = c[i].k1;
    k2[i] = c[i].k2;
    gaussian[i] = c[i].gaussian;
    mean[i] = c[i].mean;
    mac[i] = c[i].mac;
    min_radius[i] = c[i].min_radius;
    shape_index[i] = c[i].shape_index;
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) Cd[9 * i + 3 * r + k] = c[i].C(r, k);
  }
  py::dict d;
  d["normal"] = to_array(normal);
  d["k1"] = to_array(k1);
  d["k2"] = to_array(k2);
  d["dir1"] = to_array(dir1);
  d["dir2"] = to_array(dir2);
  d["gaussian"] = to_array(gaussian);
  d["mean"] = to_array(mean);
  d["mac"] = to_array(mac);
  d["min_radius"] = to_array(min_radius);
  d["shape_index"] = to_array(shape_index);
  d["C"] = C;
  return d;
}

const char* status_name(ProjectionStatus s) {
  switch (s) {
    case ProjectionStatus::Converged: return "converged";
    case ProjectionStatus::MaxIterations: return "max_iterations";
    case ProjectionStatus::VanishingGradient: return "vanishing_gradient";
    case ProjectionStatus::TooFar: return "too_far";
    case ProjectionStatus::NotFinite: return "not_finite";
    case ProjectionStatus::OutOfRange: return "out_of_range";
    case ProjectionStatus::NoProgress: return "no_progress";
  }
  return "unknown";
}

py::dict project(const Field& field, py::handle points_in, std::optional<long long> max_iterations,
                 std::optional<double> tolerance, std::optional<double> max_step, std::optional<double> max_travel) {
  const std::vector<Vec3> points = points_from(points_in, "points");
  ProjectionOptions o;
  if (max_iterations) {
    if (*max_iterations < 1 || *max_iterations > 1000000)
      throw InvalidInputError("max_iterations must be an integer in [1, 1000000], not " + std::to_string(*max_iterations));
    o.max_iterations = static_cast<int>(*max_iterations);
  }
  const auto positive = [](const std::optional<double>& v, const char* name, double& slot) {
    if (!v) return;
    if (!(std::isfinite(*v) && *v > 0))
      throw InvalidInputError(std::string(name) + " must be a positive number, not " + std::string(py::str(py::float_(*v))));
    slot = *v;
  };
  positive(tolerance, "tolerance", o.tolerance);
  positive(max_step, "max_step", o.max_step);
  positive(max_travel, "max_travel", o.max_travel);
  std::vector<ProjectionResult> r(points.size());
  {
    py::gil_scoped_release release;
    const std::vector<ProjectionOptions> options(std::min(kBindingBatch, points.size()), o);
    BatchProjector projector;
    for (std::size_t s = 0; s < points.size(); s += kBindingBatch) {
      const std::size_t m = std::min(kBindingBatch, points.size() - s);
      const auto batch = projector.project(field, std::span(points).subspan(s, m), std::span(options).first(m));
      std::copy(batch.begin(), batch.end(), r.begin() + static_cast<std::ptrdiff_t>(s));
    }
  }
  const std::size_t n = r.size();
  std::vector<Vec3> projected(n);
  std::vector<double> residual(n);
  py::array_t<bool> converged(static_cast<py::ssize_t>(n));
  py::array_t<std::int32_t> iterations(static_cast<py::ssize_t>(n));
  py::list status;
  for (std::size_t i = 0; i < n; ++i) {
    projected[i] = r[i].point;
    residual[i] = r[i].residual;
    converged.mutable_data()[i] = r[i].ok();
    iterations.mutable_data()[i] = r[i].iterations;
    status.append(status_name(r[i].status));
  }
  py::dict d;
  d["points"] = to_array(projected);
  d["converged"] = converged;
  d["status"] = py::module_::import("numpy").attr("array")(status, "dtype"_a = "U");
  d["iterations"] = iterations;
  d["residual"] = to_array(residual);
  return d;
}

// Each triangle corner's normal (F, 3, 3): the field's normalized gradient at the vertex, or at a
// vertex on a crease of a CSG field the gradient of the piece the triangle lies on
// (field_corner_normals), so that a mesh whose edges follow the creases is shaded sharp there.
py::array_t<double> corner_normals(const Field& field, py::handle vertices, py::handle faces) {
  const Mesh mesh = mesh_from(vertices, faces, py::none());
  std::vector<Vec3> normals;
  std::vector<std::array<Vec3, 3>> corners;
  {
    py::gil_scoped_release release;
    normals = field_normals(field, mesh);
    corners = field_corner_normals(field, mesh, normals);
  }
  py::array_t<double> out({static_cast<py::ssize_t>(mesh.triangles.size()), py::ssize_t{3}, py::ssize_t{3}});
  auto o = out.mutable_unchecked<3>();
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Vec3& n = corners.empty() ? normals[static_cast<std::size_t>(mesh.triangles[t][k])] : corners[t][k];
      for (int c = 0; c < 3; ++c) o(t, k, c) = n[c];
    }
  return out;
}

py::dict crease_angles_py(const Field& field, py::handle vertices, py::handle faces, std::optional<double> near) {
  const Mesh mesh = mesh_from(vertices, faces, py::none());
  if (near && !(*near > 0 && std::isfinite(*near))) throw InvalidInputError("near must be positive and finite");
  CreaseAngles a;
  {
    py::gil_scoped_release release;
    a = crease_angles(field, mesh, near.value_or(0));
  }
  return py::dict("crease_vertices"_a = a.crease_vertices, "triangles_at_creases"_a = a.triangles_at_creases,
                  "triangles_away"_a = a.triangles_away, "min_degrees_at_creases"_a = a.min_degrees_at_creases,
                  "min_degrees_away"_a = a.min_degrees_away,
                  "worst_away"_a = to_array(std::vector<double>{a.worst_away.x(), a.worst_away.y(), a.worst_away.z()}));
}

py::dict evaluate(const Field& field, py::handle vertices, py::handle faces, py::handle normals, long long views,
                  long long resolution, const std::string& projection, long long samples) {
  // normals: an (N, 3) array, "field" (the field's, each side's at creases, as `evaluate
  // --normals field`), "mesh" or None (area-weighted).
  std::string choice;
  if (py::isinstance<py::str>(normals)) {
    choice = normals.cast<std::string>();
    if (choice != "field" && choice != "mesh")
      throw InvalidInputError("normals: expected an (N, 3) array, \"field\", \"mesh\" or None, not \"" + choice + "\"");
  }
  Mesh mesh = mesh_from(vertices, faces, choice.empty() ? normals : py::none());
  std::string normals_source = "given";
  if (choice == "field") {
    py::gil_scoped_release release;
    mesh.normals = field_normals(field, mesh);
    mesh.corner_normals = field_corner_normals(field, mesh, mesh.normals);
    normals_source = mesh.corner_normals.empty() ? "field (normalized gradient at the vertices)"
                                                 : "field (normalized gradient at the vertices, each side's at creases)";
  } else if (mesh.normals.empty()) {
    mesh.normals = area_weighted_normals(mesh);
    normals_source = choice == "mesh" ? "mesh (area-weighted face normals)" : "area_weighted (no normals given)";
  }
  // The program's ranges (build/bin/evaluate --views, --rays, --samples).
  const auto range = [](long long v, const char* name, long long lo, long long hi) {
    if (v < lo || v > hi)
      throw InvalidInputError(std::string(name) + " must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                              "], not " + std::to_string(v));
  };
  range(views, "views", 1, 10000);
  range(resolution, "resolution", 1, 8192);
  range(samples, "samples", 1, 100000000);
  EvaluateOptions options;
  options.camera.views = static_cast<int>(views);
  options.camera.resolution = static_cast<int>(resolution);
  options.camera.projection = parse_projection(projection);
  options.sampling.samples = static_cast<std::size_t>(samples);

  nlohmann::json metrics;
  double gt_seconds = 0;
  {
    py::gil_scoped_release release;
    const auto start = std::chrono::steady_clock::now();
    std::vector<Ray> rays = make_camera_rays(field.bounds(), options.camera);
    // As build/bin/evaluate computes it when it has no cache; the cache key needs the field's
    // JSON text, which a field made in Python need not have, so none is recorded.
    const GroundTruth truth = compute_ground_truth(field, std::move(rays), options.raycast);
    gt_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    metrics = evaluate_mesh(field, mesh, truth, options, normals_source, "");
  }
  metrics["rays"]["ground_truth_cached"] = false;
  metrics["rays"]["ground_truth_seconds"] = gt_seconds;
  return from_json(metrics);
}

py::dict trace_creases_py(const Field& field, std::optional<int> resolution, std::optional<double> max_spacing,
                          std::optional<double> min_spacing, std::optional<double> max_turn) {
  CreaseTracingOptions o;
  if (resolution) o.resolution = *resolution;
  if (max_spacing) o.max_spacing = *max_spacing;
  if (min_spacing) o.min_spacing = *min_spacing;
  if (max_turn) o.max_turn = *max_turn;
  if (o.resolution < 2) throw InvalidInputError("resolution must be at least 2");
  if (!(o.max_turn > 0) || !std::isfinite(o.max_spacing) || !std::isfinite(o.min_spacing))
    throw InvalidInputError("max_turn must be positive, spacings finite");
  CreaseTracingResult r;
  {
    py::gil_scoped_release release;
    r = trace_creases(field, o);
  }
  py::list curves;
  for (const CreaseCurve& c : r.curves)
    curves.append(py::dict("points"_a = to_array(c.points), "closed"_a = c.closed,
                           "starts_at_corner"_a = c.starts_at_corner, "ends_at_corner"_a = c.ends_at_corner));
  py::dict d;
  d["curves"] = curves;
  d["corners"] = to_array(r.corners);
  d["stops"] = r.stops;
  d["duplicates"] = r.duplicates;
  return d;
}

}  // namespace

void bind_analysis(py::module_& m) {
  m.def("curvature", &curvature, py::arg("field"), py::arg("points"),
        "Curvature of the level set through each row of points (N, 3), evaluated where the points are (no "
        "projection: call project first for points off the surface). A dict of arrays: normal, dir1, dir2 (N, 3); "
        "k1 >= k2, gaussian, mean, mac, min_radius, shape_index (N,); C (N, 3, 3), the derivative of the unit normal. "
        "A point where the gradient vanishes raises NoSurfaceError naming it.");
  m.def("project", &project, py::arg("field"), py::arg("points"), py::kw_only(), py::arg("max_iterations") = py::none(),
        py::arg("tolerance") = py::none(), py::arg("max_step") = py::none(), py::arg("max_travel") = py::none(),
        "The paper's bounded Newton projection of each row of points (N, 3) onto F = 0. A dict: points (N, 3), converged "
        "(N,) bool, status (N,) str (converged, max_iterations, vanishing_gradient, too_far, not_finite, out_of_range, "
        "no_progress), iterations (N,) int32, residual (N,) = |F| / |grad F| at the point. Defaults: 40 iterations, "
        "tolerance 1e-10, max_step 0.1 and max_travel 0.5 of the box diagonal.");
  m.def("trace_creases", &trace_creases_py, py::arg("field"), py::kw_only(), py::arg("resolution") = py::none(),
        py::arg("max_spacing") = py::none(), py::arg("min_spacing") = py::none(), py::arg("max_turn") = py::none(),
        "The creases of a CSG field (an expression or a compiled model with min, max or abs) as polylines on both pieces: a dict with "
        "curves (a list of dicts: points (N, 3), closed, starts_at_corner, ends_at_corner), corners (K, 3) and stops "
        "(curve ends that are not corners). Found from the crossed edges of a grid of `resolution` cells (32); steps "
        "of at most max_spacing (0.02 of the box diagonal), shortened down to min_spacing (0.0005) so that the "
        "tangent turns at most max_turn (0.1 rad) a step. Fields that do not report pieces (the other models, "
        "Python callables) have none.");
  m.def("evaluate", &evaluate, py::arg("field"), py::arg("vertices"), py::arg("faces"), py::kw_only(),
        py::arg("normals") = py::none(), py::arg("views") = 8, py::arg("resolution") = 64,
        py::arg("projection") = "perspective", py::arg("samples") = 20000,
        "build/bin/evaluate on arrays: the metrics dict (schema cdp-metrics/1, raytrace/README.md) of a mesh against "
        "the exact ray-cast surface of its field, without cache and without the \"files\" entry. normals: an (N, 3) "
        "array, \"field\" (the field's normalized gradient, and at vertices on a crease of a CSG field each side's "
        "normal, as evaluate --normals field) or \"mesh\"/None (the default: area-weighted vertex normals). As the "
        "program's options: views (default 8) camera directions, each casting resolution x resolution rays (default "
        "64), projection \"perspective\" (the default) or \"orthographic\"; samples (default 20000) points of the mesh "
        "measured against the surface.");
  m.def("crease_angles", &crease_angles_py, py::arg("field"), py::arg("vertices"), py::arg("faces"), py::kw_only(),
        py::arg("near") = py::none(),
        "The smallest triangle angles (degrees) at the field's creases and away from them, judged from the field: a "
        "vertex is on a crease where two pieces of a CSG field (min, max, abs) meet within `near` of it (default 1e-6 "
        "of the box diagonal), a triangle at a crease when a corner is. A dict: crease_vertices, "
        "triangles_at_creases, triangles_away, min_degrees_at_creases, min_degrees_away (180 where there is no such "
        "triangle) and worst_away (the centroid of the triangle of min_degrees_away). The adaptive method's bounds "
        "are 20 degrees away from creases and 5 at them.");
  m.def("corner_normals", &corner_normals, py::arg("field"), py::arg("vertices"), py::arg("faces"),
        "The normal at each triangle corner, (F, 3, 3): the field's normalized gradient at the vertex, or, at a "
        "vertex on a crease of a CSG field (min, max, abs), the normal of the piece the triangle lies on, so that a "
        "mesh whose edges follow the creases (the adaptive method's) is shaded sharp there. For rendering and for "
        "Phong errors.");
}

}  // namespace cdp::python
