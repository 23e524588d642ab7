// polygonize_adaptive: resolves the options, finds seeds on every component, runs the tracker
// from each seed not yet covered, and fills in the common statistics.
#include "tracker.h"

#include <polygonizer/adaptive_polygonizer.h>
#include <polygonizer/curvature.h>
#include <polygonizer/errors.h>
#include <polygonizer/mesh_topology.h>
#include <polygonizer/surface_seeds.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

namespace cdp {

const char* to_string(SizingMode mode) { return mode == SizingMode::Factor ? "factor" : "tolerance"; }

const char* to_string(TriangleCountRule rule) {
  return rule == TriangleCountRule::PaperFloor ? "paper_floor" : "hartmann";
}

namespace {

adaptive::Settings resolve(const Field& field, const AdaptiveOptions& o) {
  const Box& box = field.bounds();
  if (!box.valid()) throw NoSurfaceError("adaptive: the field has no valid bounding box");
  const double diag = box.diagonal();
  const auto positive_or_default = [](double v, double fallback) { return v > 0 ? v : fallback; };
  adaptive::Settings s;
  s.diagonal = diag;
  s.sizing.mode = o.sizing;
  s.sizing.factor = o.factor;
  s.sizing.tolerance = positive_or_default(o.tolerance, 1e-3 * diag);
  s.sizing.min_edge = positive_or_default(o.min_edge, 2e-3 * diag);
  s.sizing.max_edge = positive_or_default(o.max_edge, 0.1 * diag);
  s.hash_cell = s.sizing.max_edge;  // refined from the seed crossings once they are known
  if (o.sizing == SizingMode::Factor && !(std::isfinite(o.factor) && o.factor > 0))
    throw InvalidInputError("adaptive: the factor must be a positive number, not " + std::to_string(o.factor));
  if (!std::isfinite(s.sizing.tolerance) || !std::isfinite(s.sizing.min_edge) || !std::isfinite(s.sizing.max_edge))
    throw InvalidInputError("adaptive: tolerance and edge lengths must be finite");
  if (s.sizing.min_edge > s.sizing.max_edge)
    throw InvalidInputError("adaptive: min_edge (" + std::to_string(s.sizing.min_edge) + ") exceeds max_edge (" +
                            std::to_string(s.sizing.max_edge) + ")");
  if (!(o.collision_factor >= 0.5 && o.collision_factor <= 3))
    throw InvalidInputError("adaptive: collision_factor must lie in [0.5, 3]");
  if (o.seed_resolution < 2) throw InvalidInputError("adaptive: seed_resolution must be at least 2");
  s.rule = o.triangle_count;
  s.collision_factor = o.collision_factor;
  s.curvature_properties = o.curvature_properties;
  const Vec3 e = box.size();
  const double box_area = 2 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
  const double tri_area = std::sqrt(3.0) / 4 * s.sizing.min_edge * s.sizing.min_edge;
  const double derived = std::min(5e7, std::max(1e4, 20 * box_area / tri_area));
  s.max_triangles = o.max_triangles > 0 ? o.max_triangles : static_cast<std::size_t>(derived);
  s.max_steps = o.max_steps > 0 ? o.max_steps : 4 * s.max_triangles + 10000;
  return s;
}

double min_angle_degrees(const Mesh& mesh) {
  double best = 180;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = mesh.positions[t[k]];
      const Vec3 u = mesh.positions[t[(k + 1) % 3]] - p, v = mesh.positions[t[(k + 2) % 3]] - p;
      best = std::min(best, std::atan2(u.cross(v).norm(), u.dot(v)) * 180 / std::numbers::pi);
    }
  return best;
}

}  // namespace

PolygonizeResult polygonize_adaptive(const Field& field, const AdaptiveOptions& options) {
  const adaptive::Settings s = resolve(field, options);
  const auto start = std::chrono::steady_clock::now();
  const EvaluationCounts before = field.counts();

  SeedOptions seed_options;
  seed_options.resolution = options.seed_resolution;
  // Grid crossings (not just one seed per cluster): two components closer than a grid cell
  // share a cluster, and the check "is this crossing meshed yet" catches the second one.
  const std::vector<SurfaceSeed> crossings = find_surface_crossings(field, seed_options);
  const double h = seed_grid_spacing(field, seed_options);

  // The hash cell follows the edge length the sizing asks for at up to 64 of the crossings
  // (their median), a deterministic sample spread over the surface.
  adaptive::Settings settings = s;
  {
    std::vector<double> lengths;
    const std::size_t stride = std::max<std::size_t>(1, crossings.size() / 64);
    for (std::size_t i = 0; i < crossings.size(); i += stride) {
      try {
        lengths.push_back(adaptive::edge_length(s.sizing, curvature_at(field, crossings[i].point).min_radius));
      } catch (const NoSurfaceError&) {
      }
    }
    if (!lengths.empty()) {
      std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
      settings.hash_cell = 2 * lengths[lengths.size() / 2];
    }
  }

  PolygonizeResult result;
  Mesh& mesh = result.mesh;
  adaptive::Tracker tracker(field, settings, mesh);
  // Crossed grid edges per unit area average 1.5 / h^2 over all orientations.
  if (options.progress) tracker.set_progress(options.progress, crossings.size() * h * h / 1.5);

  ProjectionOptions seed_projection;
  seed_projection.max_travel = 2 * h;
  std::size_t seeds = 0, failed_seeds = 0;
  for (const SurfaceSeed& c : crossings) {
    if (tracker.covered(c.point)) continue;
    const ProjectionResult r = project_to_surface(field, c.point, seed_projection);
    if (!r.ok() || tracker.covered(r.point)) continue;
    if (tracker.mesh_from_seed(r.point)) ++seeds;
    else ++failed_seeds;
  }
  if (mesh.triangles.empty())
    throw NoSurfaceError("adaptive: the field changes sign but no seed could be meshed (vanishing gradient)");

  if (s.curvature_properties) {
    mesh.vertex_scalars["mac"] = tracker.vertex_mac();
    mesh.vertex_scalars["shape_index"] = tracker.vertex_shape_index();
  }

  PolygonizeStats& st = result.stats;
  st.method = "adaptive";
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  st.field_evaluations = field.counts() - before;
  st.triangles = mesh.num_triangles();
  st.vertices = mesh.num_vertices();
  st.components = analyze_topology(mesh).components;
  st.splits = tracker.splits();
  st.merges = tracker.merges();
  st.extra["seeds"] = seeds;
  st.extra["curvature_seconds"] = tracker.curvature_seconds();
  st.extra["failed_seeds"] = failed_seeds;
  st.extra["steps"] = tracker.steps();
  st.extra["deferrals"] = tracker.deferrals();
  st.extra["forced_closures"] = tracker.forced_closures();
  st.extra["min_angle_degrees"] = min_angle_degrees(mesh);
  st.extra["edge_length"] = {{"min", s.sizing.min_edge}, {"max", s.sizing.max_edge}};
  st.extra["sizing"] = to_string(s.sizing.mode);
  if (s.sizing.mode == SizingMode::Factor) st.extra["factor"] = s.sizing.factor;
  else st.extra["tolerance"] = s.sizing.tolerance;
  st.extra["triangle_count_rule"] = to_string(s.rule);
  st.extra["seed_resolution"] = options.seed_resolution;
  if (options.progress) options.progress(1.0);
  return result;
}

}  // namespace cdp
