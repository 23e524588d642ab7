#include <cdp/io/polygonize_stats_json.h>

#include <string>

namespace cdp {

namespace {

nlohmann::json counts_json(const EvaluationCounts& c) {
  return {{"value", c.value}, {"value_gradient", c.value_gradient}, {"gradient_hessian", c.gradient_hessian}};
}

void add_settings(nlohmann::json& j, const AdaptiveSettingsReport& s) {
  j["variant"] = to_string(s.variant);
  j["sizing"] = to_string(s.sizing);
  if (s.sizing == SizingMode::Factor) j["factor"] = s.factor;
  else j["tolerance"] = s.tolerance;
  j["edge_length"] = {{"min", s.min_edge}, {"max", s.max_edge}};
  j["triangle_count_rule"] = to_string(s.triangle_count);
  j["seed_resolution"] = s.seed_resolution;
  j["grading"] = s.grading;
  j["quality_repair"] = s.quality_repair;
  j["tolerance_refinement"] = s.tolerance_refinement;
}

void add_seeding(nlohmann::json& j, const SeedingReport& s) {
  j["seeds"] = s.seeds;
  j["failed_seeds"] = s.failed_seeds;
  j["sign_changes"] = s.sign_changes;
  j["non_finite_samples"] = s.non_finite_samples;
  j["touching_samples"] = s.touching_samples;
  j["touching_crossings"] = s.touching_crossings;
  j["covered_nearby"] = s.covered_nearby;
  j["below_resolution"] = s.below_resolution;
  j["thin_bridges"] = s.thin_bridges;
  j["seeds_first"] = s.seeds_first;
  j["uncovered_crossings"] = s.uncovered;
  j["refined_cells"] = s.refined_cells;
  j["unresolved_cells"] = s.unresolved_cells;
  j["unsearched_cells"] = s.unsearched_cells;
  j["probes"] = s.probes;
  j["probes_outside"] = s.probes_outside;
  j["band_cells"] = s.band_cells;
  j["band_components"] = s.band_components;
}

void add_tracker(nlohmann::json& j, const TrackerReport& t) {
  j["steps"] = t.steps;
  j["search_visits"] = t.search_visits;
  j["deferrals"] = t.deferrals;
  j["anticipations"] = t.anticipations;
  j["side_points"] = t.side_points;
  j["forced_closures"] = t.forced_closures;
  j["rollbacks"] = t.rollbacks;
  j["rollbacks_failed"] = t.rollbacks_failed;
  j["crease_points"] = t.crease_points;
  j["over_mesh_rejections"] = t.over_mesh_rejections;
  j["sheet_jumps"] = t.sheet_jumps;
  j["curvature_seconds"] = t.curvature_seconds;
  j["hessian_seconds"] = t.hessian_seconds;
  j["curvature"] = {{"min_radius", t.min_curvature_radius}};
}

nlohmann::json creases_json(const CreaseReport& c) {
  return {{"handling", to_string(c.handling)},
          {"followed", c.followed},
          {"curves", c.curves},
          {"corners", c.corners},
          {"vertices", c.vertices},
          {"pieces", c.pieces},
          {"components", c.components},
          {"fallback", c.fallback},
          {"steps", c.steps},
          {"tracing_resolution", c.tracing_resolution},
          {"patch_refusals", c.patch_refusals},
          {"landed_vertices", c.landed_vertices},
          {"across_black_box", c.across_black_box}};
}

nlohmann::json blocks_json(const BlocksReport& b) {
  return {{"requested", b.requested},
          {"used", b.used},
          {"blocks", b.blocks},
          {"cuts", b.cuts},
          {"meshed_blocks", b.meshed_blocks},
          {"layouts", b.layouts},
          {"estimated_triangles", b.estimated_triangles},
          {"corners", b.corners},
          {"seams", b.seams},
          {"seam_vertices", b.seam_vertices},
          {"components", b.components},
          {"steps", b.steps},
          {"threads", b.threads},
          {"layout_seconds", b.layout_seconds},
          {"task_bytes", b.task_bytes},
          {"piece_bytes", b.piece_bytes},
          {"lockstep_tasks", b.lockstep_tasks},
          {"lockstep_batches", b.lockstep_batches},
          {"seconds", b.seconds},
          {"block_seconds", b.block_seconds},
          {"pass_seconds", b.pass_seconds},
          {"pass_blocks", b.pass_blocks},
          {"fallback", b.fallback},
          {"wall_triangles", b.wall_triangles},
          {"wall_min_angle_degrees", b.wall_min_angle_degrees},
          {"wall_under_30_share", b.wall_under_30_share},
          {"wall_mean_edge_ratio", b.wall_mean_edge_ratio}};
}

nlohmann::json quality_json(const QualityReport& q) {
  nlohmann::json j{{"repair_below_degrees", q.repair_below_degrees},
                   {"bad_before", q.bad_before},
                   {"bad_after", q.bad_after},
                   {"flips", q.flips},
                   {"moves", q.moves},
                   {"relaxed", q.relaxed},
                   {"relax_flips", q.relax_flips},
                   {"refine_measured", q.refine_measured},
                   {"refine_cleared", q.refine_cleared},
                   {"relax_searched", q.relax_searched},
                   {"relax_search_sweeps", q.relax_search_sweeps},
                   {"relax_crossings", q.relax_crossings},
                   {"collapses", q.collapses},
                   {"splits", q.splits},
                   {"inserts", q.inserts},
                   {"last_resorts", q.last_resorts},
                   {"crease_vertices", q.crease_vertices},
                   {"measured_densely", q.measured_densely},
                   {"over_tolerance", q.over_tolerance}};
  if (q.over_tolerance > 0) {
    j["over_tolerance_worst"] = q.over_tolerance_worst;
    j["over_tolerance_near_x"] = q.over_tolerance_near.x();
    j["over_tolerance_near_y"] = q.over_tolerance_near.y();
    j["over_tolerance_near_z"] = q.over_tolerance_near.z();
  }
  return j;
}

void add_recoveries(nlohmann::json& j, const RecoveryReport& r) {
  j["min_edge_lowered"] = r.min_edge_lowered;
  j["turn_limited"] = r.turn_limited;
  j["thin_sheets"] = r.thin_sheets;
  j["look_ahead"] = r.look_ahead;
  j["quality_rerun"] = r.quality_rerun;
  j["quality_rerun_kept"] = r.quality_rerun_kept;
  j["tolerance_rerun"] = r.tolerance_rerun;
  j["tolerance_rerun_kept"] = r.tolerance_rerun_kept;
  j["remeshed_with_rollbacks"] = r.remeshed_with_rollbacks;
  j["remeshed_carefully"] = r.remeshed_carefully;
  j["careful_max_turn"] = r.careful_max_turn;
}

void add_adaptive(nlohmann::json& j, const AdaptiveReport& r) {
  add_settings(j, r.settings);
  add_seeding(j, r.seeding);
  add_tracker(j, r.tracker);
  j["creases"] = creases_json(r.creases);
  j["blocks"] = blocks_json(r.blocks);
  j["quality"] = quality_json(r.quality);
  j["necks"] = {{"walks", r.necks.walks},
                {"critical_points", r.necks.critical_points},
                {"tested", r.necks.tested},
                {"reruns", r.necks.reruns},
                {"unwalked", r.necks.unwalked},
                {"caps", r.necks.caps}};
  add_recoveries(j, r.recoveries);
  nlohmann::json& phases = j["phases"];
  for (std::size_t i = 0; i < kAdaptivePhases.size(); ++i) {
    nlohmann::json p = counts_json(r.phases[i].evaluations);
    p["seconds"] = r.phases[i].seconds;
    phases[std::string(kAdaptivePhases[i])] = std::move(p);
  }
  j["split_evaluations"] = r.split_evaluations;
  j["seed_grid_seconds"] = r.seed_grid_seconds;
  j["min_angle_degrees"] = r.min_angle_degrees;
}

void add_lattice(nlohmann::json& j, const LatticeReport& r) {
  j["traversal"] = r.traversal;
  if (!r.face_ambiguity.empty()) j["face_ambiguity"] = r.face_ambiguity;
  j["cell_size"] = r.cell_size;
  if (r.precision) j["precision"] = *r.precision;
  j["lattice_cells"] = r.cells;
  j["root_tolerance"] = r.root_tolerance;
  j["cubes_visited"] = r.cubes_visited;
  j["cubes_crossed"] = r.cubes_crossed;
  j["corner_evaluations"] = r.corner_evaluations;
  j["root_evaluations"] = r.root_evaluations;
  j["centre_vertices"] = r.centre_vertices;
  j["collapsed_edges"] = r.collapsed_edges;
  j["dropped_components"] = r.dropped_components;
  j["short_edges_left"] = r.short_edges_left;
  if (const auto& s = r.seeding) {
    j["seed_resolution"] = s->seed_resolution;
    j["seeds"] = s->seeds;
    j["unresolved_seeds"] = s->unresolved_seeds;
    j["starts"] = s->starts;
    j["seed_search_cubes"] = s->seed_search_cubes;
    j["sign_changes"] = s->sign_changes;
    j["completion_starts"] = s->completion_starts;
    j["unreached_sign_changes"] = s->unreached_sign_changes;
    j["completion_evaluations"] = s->completion_evaluations;
  }
  if (r.open_boundary_faces) j["open_boundary_faces"] = *r.open_boundary_faces;
}

nlohmann::json angles_json(const AngleStatistics& a) {
  return {{"min_degrees", a.min_degrees},
          {"mean_min_degrees", a.mean_min_degrees},
          {"mean_edge_ratio", a.mean_edge_ratio},
          {"share_under_10", a.share_under_10},
          {"share_under_20", a.share_under_20},
          {"share_under_30", a.share_under_30},
          {"cumulative_below_degrees", a.below},
          {"degenerate", a.degenerate}};
}

}  // namespace

nlohmann::json to_json(const PolygonizeStats& s) {
  nlohmann::json j;
  j["method"] = s.method;
  j["triangles"] = s.triangles;
  j["vertices"] = s.vertices;
  j["components"] = s.components;
  j["seconds"] = s.seconds;
  j["field_evaluations"] = counts_json(s.field_evaluations);
  j["field_evaluations"]["total"] = s.field_evaluations.total();
  j["splits"] = s.splits;
  j["merges"] = s.merges;
  if (s.adaptive) add_adaptive(j, *s.adaptive);
  if (s.lattice) add_lattice(j, *s.lattice);
  if (s.angles) j["angles"] = angles_json(*s.angles);
  if (s.topology && s.angles) {
    const MeshTopology& t = *s.topology;
    j["summary"] = {{"watertight", t.watertight()},
                    {"closed", t.closed()},
                    {"manifold", t.edge_manifold() && t.vertex_manifold()},
                    {"oriented", t.oriented()},
                    {"outward", t.signed_volume > 0},
                    {"components", t.components},
                    {"genus", t.genus},
                    {"smallest_angle_degrees", s.angles->min_degrees},
                    {"degenerate_triangles", t.degenerate_triangles}};
  }
  return j;
}

}  // namespace cdp
