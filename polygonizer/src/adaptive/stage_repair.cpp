#include "stage_repair.h"

#include "resolve_settings.h"
#include "stage_checks.h"

#include <cdp/core/curvature.h>

#include <numbers>
#include <utility>
#include <vector>

namespace cdp::adaptive {
namespace {

// A mesh that covers more than kOverlapArea times the area the seed grid measures has a front
// that ran over finished mesh: it is checked before the repair, which cannot take doubled
// surface away and would spend its rounds on the triangles where the sheets cross (blobs31 of
// the topology sweep at tolerance 3e-2: 45 s on a mesh of 469k triangles and 112k intersecting
// pairs, area 1.83 times the estimate, that the checks then refused). Each triangle is counted
// with its own crossing weight (|nx| + |ny| + |nz|, against the estimate's mean
// kMeanCrossings), so that a cube's faces (weight 1) do not pass for doubled surface. Meshes the
// checks pass measure 0.90-1.01 times the estimate on the topology sweep's fields; the failed
// ones, 1.13-1.94. Not for the crease-aware meshes, whose intersections are checked after the
// repair (it removes some that chords on an acute crease's two faces make).
constexpr double kOverlapArea = 1.25;

// Where the distance bound needs it, the repair's last resort (quality.h) may halve edges down
// to this share of the default min_edge: an edge between one and two min_edge long on a bend a
// little tighter than min_edge follows (blobs37 of the topology sweep at 1e-3: radius of
// curvature 0.0062, edges of 0.009 where 0.0077 keeps the bound, min_edge 0.0063) cannot be
// split into halves of min_edge.
constexpr double kLastResortEdgeShare = 0.5;

void check_overlap(const RunContext& run, const SeedGridStage& seeds, const CreaseLayout& creases,
                   const Tracking& tracking, const Mesh& mesh) {
  if (creases.mesh || !(seeds.estimated_area > 0) || !(tracking.tracker->area() > kOverlapArea * seeds.estimated_area))
    return;
  double seen = 0;  // the area as the grid sees it
  for (const auto& t : mesh.triangles) {
    const Vec3& a = mesh.positions[t[0]];
    const Vec3 n = (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a);  // twice the area
    seen += 0.5 * n.cwiseAbs().sum() / kMeanCrossings;
  }
  if (seen > kOverlapArea * seeds.estimated_area) {
    run.enter("checks");
    check_mesh(mesh, tracking.seeding.seeds + creases.components, run.options.check_self_intersections,
               run.options.threads, run.options.cancel);
  }
}

}  // namespace

QualityReport repair_mesh(const RunContext& run, const Settings& resolved, const SeedGridStage& seeds,
                          const CreaseLayout& creases, const Tracking& tracking, Mesh& mesh) {
  const AdaptiveOptions& options = run.options;
  if (options.variant != Variant::Improved) return {};
  check_overlap(run, seeds, creases, tracking, mesh);
  run.enter("quality", "repairing triangles");
  QualityOptions qo;
  qo.improve_below = kRepairBelowDegrees * std::numbers::pi / 180;
  qo.tolerance = resolved.sizing.mode == SizingMode::Tolerance ? requested_tolerance(options, resolved) : 0;
  qo.diagonal = resolved.diagonal;
  qo.min_edge = resolved.sizing.min_edge;
  // The default min_edge is the sizing's floor, not the caller's: where the distance bound
  // needs it, the last resort may halve edges down to kLastResortEdgeShare of it. A min_edge
  // the caller set holds for every split.
  qo.last_resort_min_edge =
      options.min_edge > 0 ? resolved.sizing.min_edge : kLastResortEdgeShare * resolved.sizing.min_edge;
  qo.threads = options.threads;
  qo.cancel = options.cancel;
  // Neither the search nor the dense measurement before a split where a field with branch
  // points (min, max, abs) is meshed without following its creases (CreaseHandling::Ignore,
  // or a crease layout that failed; see QualityOptions): the triangles across a crease stay
  // stretched, so the mean is no aim. Meshed so, the creased shapes of
  // results/creases came out as often further from it as nearer, and the two spheres at
  // 5e-4 fell from 19.7 to 13.6 degrees; meshed along their creases they all came nearer.
  // A field with branch points whose crease tracing ran and found no crease (the hollow
  // sphere: its two sheets meet nowhere) is a smooth surface; one meshed without its layout
  // may have creases the mesh crosses.
  const bool no_crease =
      options.creases == CreaseHandling::Follow && creases.fallback.empty() && creases.traced.curves.empty();
  const bool across_creases = run.field.has_pieces() && !creases.mesh && !no_crease;
  qo.aim_mean_edge_ratio = across_creases ? 0 : kBoundMeanEdgeRatio;
  qo.measure_near_bound = !across_creases;
  return improve_mesh(run.field, mesh, qo);
}

void add_curvature_properties(const Field& field, const Tracker& tracker, const QualityReport& quality, Mesh& mesh) {
  if (quality.moves + quality.relaxed + quality.collapses + quality.splits + quality.inserts == 0) {
    mesh.vertex_scalars["mac"] = tracker.vertex_mac();
    mesh.vertex_scalars["shape_index"] = tracker.vertex_shape_index();
    return;
  }
  // The repair moved, removed or added vertices: measure them all where they are now.
  std::vector<double> mac(mesh.positions.size()), shape(mesh.positions.size());
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const Curvature c = curvature_at(field, mesh.positions[v]);
    mac[v] = c.mac;
    shape[v] = c.shape_index;
  }
  mesh.vertex_scalars["mac"] = std::move(mac);
  mesh.vertex_scalars["shape_index"] = std::move(shape);
}

}  // namespace cdp::adaptive
