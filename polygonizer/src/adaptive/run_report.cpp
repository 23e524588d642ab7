// The stats of a run (PolygonizeStats::extra's keys as STATS.json writes them).
#include "failure_message.h"
#include "resolve_settings.h"
#include "run_state.h"
#include "stage_checks.h"

#include <chrono>
#include <cmath>

namespace cdp::adaptive {

void Run::write_stats() {
  const bool repair = ctx.options.variant == Variant::Improved;
  const double tolerance = requested_tolerance(ctx.options, resolved);
  PolygonizeStats& st = result.stats;
  st.components = components;
  st.method = "adaptive";
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  st.field_evaluations = ctx.field.counts() - before;
  st.triangles = result.mesh.num_triangles();
  st.vertices = result.mesh.num_vertices();
  st.splits = tracking.tracker->splits() + (creases.mesh ? creases.mesh->splits : 0);
  st.merges = tracking.tracker->merges() + (creases.mesh ? creases.mesh->merges : 0);
  st.extra["seeds"] = tracking.seeding.seeds;
  st.extra["creases.handling"] = to_string(ctx.options.variant == Variant::Improved ? ctx.options.creases : CreaseHandling::Ignore);
  st.extra["creases.followed"] = creases.mesh.has_value();
  st.extra["creases.curves"] = creases.traced.curves.size();
  st.extra["creases.corners"] = creases.traced.corners.size();
  st.extra["creases.vertices"] = creases.mesh ? creases.mesh->crease_vertices : 0;
  st.extra["creases.pieces"] = creases.mesh ? creases.mesh->pieces : 0;
  st.extra["creases.components"] = creases.components;
  st.extra["creases.fallback"] = creases.fallback;
  st.extra["creases.steps"] = creases.mesh ? creases.mesh->steps : 0;
  st.extra["creases.tracing_resolution"] = creases.tracing_resolution;
  st.extra["creases.patch_refusals"] = creases.mesh ? creases.mesh->patch_refusals : 0;
  st.extra["seed_grid_seconds"] = seed_grid_seconds;
  st.extra["curvature_seconds"] = tracking.tracker->curvature_seconds();
  st.extra["hessian_seconds"] = tracking.tracker->hessian_seconds();
  st.extra["failed_seeds"] = tracking.seeding.failed_seeds;
  st.extra["sign_changes"] = tracking.seeding.sign_changes;
  st.extra["non_finite_samples"] = seeds.grid.non_finite;
  st.extra["covered_nearby"] = tracking.seeding.covered_nearby;
  st.extra["below_resolution"] = tracking.seeding.below_resolution;
  st.extra["uncovered_crossings"] = tracking.seeding.uncovered;
  st.extra["refined_cells"] = tracking.seeding.refined_cells;
  st.extra["unresolved_cells"] = tracking.seeding.unresolved_cells;
  st.extra["probes"] = tracking.seeding.probes;
  st.extra["steps"] = tracking.tracker->steps();
  st.extra["search_visits"] = tracking.tracker->search_visits();
  st.extra["deferrals"] = tracking.tracker->deferrals();
  st.extra["anticipations"] = tracking.tracker->anticipations();
  st.extra["side_points"] = tracking.tracker->side_points();
  st.extra["forced_closures"] = tracking.tracker->forced_closures() + (creases.mesh ? creases.mesh->forced_closures : 0);
  st.extra["rollbacks"] = tracking.tracker->rollbacks();
  st.extra["rollbacks_failed"] = tracking.tracker->failed_rollbacks();
  st.extra["remeshed_with_rollbacks"] = tracking.remeshed;
  st.extra["remeshed_carefully"] = careful;
  st.extra["turn_limited"] = request.max_turn > 0;
  st.extra["careful_max_turn"] = careful ? settings.sizing.max_turn : 0.0;
  st.extra["crease_points"] = tracking.tracker->crease_points();
  st.extra["over_mesh_rejections"] = tracking.tracker->over_mesh();
  st.extra["necks.walks"] = necks.walks;
  st.extra["necks.critical_points"] = necks.critical_points;
  st.extra["necks.tested"] = necks.tested;
  st.extra["necks.reruns"] = neck_reruns;
  tracking.note_tightest();
  st.extra["curvature.min_radius"] = std::isfinite(tracking.tightest.first) ? tracking.tightest.first : -1.0;
  // A mesh made across a crease of a black box (see kink_in_black_box) that held together: the
  // crease is cut across by chords, not followed.
  st.extra["creases.across_black_box"] = kink_in_black_box(ctx.field, tracking.tightest);
  st.extra["min_angle_degrees"] = min_angle_degrees(result.mesh);
  st.extra["edge_length.min"] = resolved.sizing.min_edge;
  st.extra["edge_length.max"] = resolved.sizing.max_edge;
  st.extra["sizing"] = to_string(resolved.sizing.mode);
  if (resolved.sizing.mode == SizingMode::Factor) st.extra["factor"] = resolved.sizing.factor;
  else st.extra["tolerance"] = tolerance;
  st.extra["variant"] = to_string(ctx.options.variant);
  st.extra["grading"] = resolved.grading;
  st.extra["quality_repair"] = repair;
  st.extra["tolerance_refinement"] = repair && resolved.sizing.mode == SizingMode::Tolerance;
  st.extra["quality.repair_below_degrees"] = kRepairBelowDegrees;
  st.extra["quality.bad_before"] = quality.bad_before;
  st.extra["quality.bad_after"] = quality.bad_after;
  st.extra["quality.flips"] = quality.flips;
  st.extra["quality.moves"] = quality.moves;
  st.extra["quality.relaxed"] = quality.relaxed;
  st.extra["quality.relax_flips"] = quality.relax_flips;
  st.extra["quality.refine_measured"] = quality.refine_measured;
  st.extra["quality.refine_cleared"] = quality.refine_cleared;
  st.extra["quality.relax_searched"] = quality.relax_searched;
  st.extra["quality.relax_search_sweeps"] = quality.relax_search_sweeps;
  st.extra["quality.relax_crossings"] = quality.relax_crossings;
  st.extra["quality.collapses"] = quality.collapses;
  st.extra["quality.splits"] = quality.splits;
  st.extra["quality.inserts"] = quality.inserts;
  st.extra["quality.last_resorts"] = quality.last_resorts;
  st.extra["quality.crease_vertices"] = quality.crease_vertices;
  st.extra["quality.measured_densely"] = quality.measured_densely;
  st.extra["quality.over_tolerance"] = quality.over_tolerance;
  if (quality.over_tolerance > 0) {
    st.extra["quality.over_tolerance_worst"] = quality.over_tolerance_worst;
    const Vec3& c = quality.over_tolerance_near;
    st.extra["quality.over_tolerance_near_x"] = c.x();
    st.extra["quality.over_tolerance_near_y"] = c.y();
    st.extra["quality.over_tolerance_near_z"] = c.z();
  }
  st.extra["triangle_count_rule"] = to_string(resolved.rule);
  st.extra["seed_resolution"] = ctx.options.seed_resolution;
  st.extra["min_edge_lowered"] = false;
  st.extra["look_ahead"] = request.look_ahead;
  st.extra["quality_rerun"] = false;
  st.extra["quality_rerun_kept"] = false;
}

}  // namespace cdp::adaptive
