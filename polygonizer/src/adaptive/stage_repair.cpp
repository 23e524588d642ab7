#include "stage_repair.h"

#include "resolve_settings.h"
#include "stage_checks.h"

#include <cdp/core/curvature.h>

#include <algorithm>
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

QualityOptions repair_options(const RunContext& run, const Settings& resolved, const CreaseLayout& creases) {
  const AdaptiveOptions& options = run.options;
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
  // Decided here, on the run's own field, for every repair of the run alike: a block's repair in
  // lockstep sees a view of it whose calls are not costly (lockstep.h).
  qo.predict_estimates = run.field.predicts_from_hessians() || run.field.costly_calls() ? QualityOptions::Predict::Always
                                                                               : QualityOptions::Predict::Never;
  return qo;
}

QualityReport repair_mesh(const RunContext& run, const Settings& resolved, const SeedGridStage& seeds,
                          const CreaseLayout& creases, const BlockMeshing& blocks, const Tracking& tracking, Mesh& mesh,
                          BandChanges& band) {
  band = {};
  if (run.options.variant != Variant::Improved) return {};
  check_overlap(run, seeds, creases, tracking, mesh);
  run.enter("quality", "repairing triangles");
  const QualityOptions qo = repair_options(run, resolved, creases);
  if (!blocks.mesh) return improve_mesh(run.field, mesh, qo);
  QualityReport report = blocks.quality;
  QualityOptions in_band = qo;
  in_band.aim_mean_edge_ratio = 0;  // as the blocks': the whole mesh's mean decides (below)
  const std::vector<char> sealed =
      run.options.check_self_intersections ? sealed_triangles(blocks, mesh) : std::vector<char>{};
  QualityReport own = repair_band(run.field, mesh, blocks.report.seam_vertices, blocks.vertices,
                                  in_band, band, sealed.empty() ? nullptr : &sealed);
  add_repair_counts(report, own);
  // The relaxation's search (QualityOptions::aim_mean_edge_ratio) aims at the whole mesh's mean
  // edge ratio, which neither a block nor the band knows: where it is over the aim, the whole
  // mesh is repaired again with the search, as a mesh tracked alone would be (rare: the blocks'
  // meshes are better shaped; a block's own mean over it made the random blobs at 1e-3 search in
  // four of their eight blocks, 1.5 times the evaluations of the whole run).
  if (qo.aim_mean_edge_ratio > 0 && mean_edge_ratio(mesh) > qo.aim_mean_edge_ratio) {
    const QualityReport whole = improve_mesh(run.field, mesh, qo);
    add_repair_counts(report, whole);
    // It measured every triangle against the tolerance: its count is the mesh's.
    report.over_tolerance = whole.over_tolerance;
    report.over_tolerance_worst = whole.over_tolerance_worst;
    report.over_tolerance_near = whole.over_tolerance_near;
    band = {};  // every vertex measured again (add_curvature_properties)
  }
  // Afresh: the blocks' counts include triangles beside a seam that the band's repair changed.
  report.bad_after = triangles_under(mesh, qo.improve_below);
  return report;
}

QualityReport repair_band(const Field& field, Mesh& mesh, std::size_t seams, std::size_t finished, QualityOptions qo,
                          BandChanges& band, const std::vector<char>* sealed) {
  const std::size_t nv = mesh.positions.size();
  // The seams and their neighbours.
  std::vector<char> near(nv, 0);
  for (std::size_t v = 0; v < std::min(seams, nv); ++v) near[v] = 1;
  for (const auto& t : mesh.triangles)
    if (static_cast<std::size_t>(std::min({t[0], t[1], t[2]})) < seams)
      for (int v : t) near[static_cast<std::size_t>(v)] = 1;
  // The band: its triangles in mesh order, its vertices numbered in mesh order.
  std::vector<char> in_band(mesh.triangles.size(), 0);
  std::vector<int> local(nv, -1);
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const auto& t = mesh.triangles[i];
    for (int v : t)
      if (near[static_cast<std::size_t>(v)] || static_cast<std::size_t>(v) >= finished) in_band[i] = 1;
    if (in_band[i])
      for (int v : t) local[static_cast<std::size_t>(v)] = 0;
  }
  Mesh part;
  std::vector<int> global;  // part's vertex -> mesh's
  for (std::size_t v = 0; v < nv; ++v)
    if (local[v] == 0) {
      local[v] = static_cast<int>(global.size());
      global.push_back(static_cast<int>(v));
      part.positions.push_back(mesh.positions[v]);
      part.normals.push_back(mesh.normals[v]);
    }
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    if (in_band[i]) {
      const auto& t = mesh.triangles[i];
      part.triangles.push_back({local[t[0]], local[t[1]], local[t[2]]});
    }
  qo.keep_boundary = true;
  qo.count_near_boundary = true;
  std::vector<int> renumbered;
  const QualityReport report = improve_mesh(field, part, qo, &renumbered);

  // Back into the mesh: its vertices in their order without those removed, then those added.
  std::vector<int> part_to_mesh(part.positions.size(), -1);
  std::vector<char> removed(nv, 0);
  for (std::size_t l = 0; l < global.size(); ++l) {
    if (renumbered[l] < 0)
      removed[static_cast<std::size_t>(global[l])] = 1;
    else
      part_to_mesh[static_cast<std::size_t>(renumbered[l])] = global[l];
  }
  // In place, without a second copy of the mesh (at 1.85M triangles the copy was most of the
  // repair's memory, then the run's peak): a kept vertex or triangle moves down, never up, so
  // each is read before anything is written over it.
  band.renumbered.assign(nv, -1);
  std::size_t kept = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    if (removed[v]) continue;
    band.renumbered[v] = static_cast<int>(kept);
    mesh.positions[kept] = mesh.positions[v];
    mesh.normals[kept] = mesh.normals[v];
    ++kept;
  }
  mesh.positions.resize(kept);
  mesh.normals.resize(kept);
  // Room for what the part adds made once (a doubling would hold the old array beside the new).
  mesh.positions.reserve(kept + part.positions.size());
  mesh.normals.reserve(kept + part.positions.size());
  for (std::size_t p = 0; p < part.positions.size(); ++p) {
    int at;
    if (part_to_mesh[p] >= 0) {
      at = band.renumbered[static_cast<std::size_t>(part_to_mesh[p])];
      if (mesh.positions[static_cast<std::size_t>(at)] == part.positions[p]) continue;
    } else {
      at = static_cast<int>(mesh.positions.size());
      mesh.positions.emplace_back();
      mesh.normals.emplace_back();
    }
    part_to_mesh[p] = -2 - at;  // placed
    mesh.positions[static_cast<std::size_t>(at)] = part.positions[p];
    mesh.normals[static_cast<std::size_t>(at)] = part.normals[p];
    band.moved.push_back(at);
  }
  // The part's vertex p is the output's vertex out_of(p).
  const auto out_of = [&](int p) {
    const int m = part_to_mesh[static_cast<std::size_t>(p)];
    return m <= -2 ? -2 - m : band.renumbered[static_cast<std::size_t>(m)];
  };
  std::size_t outside = 0;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    if (!in_band[i]) {
      const auto t = mesh.triangles[i];
      mesh.triangles[outside++] = {band.renumbered[t[0]], band.renumbered[t[1]], band.renumbered[t[2]]};
      if (sealed) band.sealed.push_back((*sealed)[i]);
    }
  mesh.triangles.resize(outside);
  mesh.triangles.reserve(outside + part.triangles.size());
  for (const auto& t : part.triangles) mesh.triangles.push_back({out_of(t[0]), out_of(t[1]), out_of(t[2])});
  if (sealed) band.sealed.resize(mesh.triangles.size(), 0);
  std::sort(band.moved.begin(), band.moved.end());
  return report;
}

void add_curvature_properties(const Field& field, const Tracker& tracker, const QualityReport& quality,
                              const BandChanges& band, Mesh& mesh) {
  if (!band.renumbered.empty()) {
    // The tracker's (the blocks' measured again where their repairs moved vertices), renumbered,
    // and measured where the band's repair moved or added a vertex.
    const std::vector<double>& tmac = tracker.vertex_mac();
    const std::vector<double>& tshape = tracker.vertex_shape_index();
    std::vector<double> mac(mesh.positions.size()), shape(mesh.positions.size());
    for (std::size_t v = 0; v < band.renumbered.size(); ++v)
      if (band.renumbered[v] >= 0) {
        mac[static_cast<std::size_t>(band.renumbered[v])] = tmac[v];
        shape[static_cast<std::size_t>(band.renumbered[v])] = tshape[v];
      }
    std::vector<Vec3> at;
    for (int v : band.moved) at.push_back(mesh.positions[static_cast<std::size_t>(v)]);
    const std::vector<Curvature> c = curvatures_at(field, at);
    for (std::size_t i = 0; i < band.moved.size(); ++i) {
      mac[static_cast<std::size_t>(band.moved[i])] = c[i].mac;
      shape[static_cast<std::size_t>(band.moved[i])] = c[i].shape_index;
    }
    mesh.vertex_scalars["mac"] = std::move(mac);
    mesh.vertex_scalars["shape_index"] = std::move(shape);
    return;
  }
  if (quality.moves + quality.relaxed + quality.collapses + quality.splits + quality.inserts == 0) {
    mesh.vertex_scalars["mac"] = tracker.vertex_mac();
    mesh.vertex_scalars["shape_index"] = tracker.vertex_shape_index();
    return;
  }
  // The repair moved, removed or added vertices: measure them all where they are now.
  std::vector<double> mac(mesh.positions.size()), shape(mesh.positions.size());
  const std::vector<Curvature> c = curvatures_at(field, mesh.positions);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    mac[v] = c[v].mac;
    shape[v] = c[v].shape_index;
  }
  mesh.vertex_scalars["mac"] = std::move(mac);
  mesh.vertex_scalars["shape_index"] = std::move(shape);
}

}  // namespace cdp::adaptive
