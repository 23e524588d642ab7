// The typed report of a run (PolygonizeStats::adaptive, adaptive_report.h).
#include "failure_message.h"
#include "resolve_settings.h"
#include "run_state.h"
#include "stage_checks.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

namespace cdp::adaptive {

namespace {

// The triangles a cut plane passes through, and their quality (BlocksReport).
void add_wall_quality(const Mesh& mesh, BlocksReport& b) {
  double min_angle = 180, ratio_sum = 0;
  std::size_t count = 0, under = 0;
  for (const auto& t : mesh.triangles) {
    const Vec3& p = mesh.positions[static_cast<std::size_t>(t[0])];
    const Vec3& q = mesh.positions[static_cast<std::size_t>(t[1])];
    const Vec3& s = mesh.positions[static_cast<std::size_t>(t[2])];
    bool crossed = false;
    for (int a = 0; a < 3 && !crossed; ++a)
      for (const double c : b.cuts[a])
        if (std::min({p[a], q[a], s[a]}) <= c && std::max({p[a], q[a], s[a]}) >= c) {
          crossed = true;
          break;
        }
    if (!crossed) continue;
    const double e0 = (q - p).norm(), e1 = (s - q).norm(), e2 = (p - s).norm();
    // The smallest angle is opposite the shortest edge.
    const auto corner = [](const Vec3& at, const Vec3& u, const Vec3& w) {
      const Vec3 x = u - at, y = w - at;
      return std::atan2(x.cross(y).norm(), x.dot(y)) * 180 / std::numbers::pi;
    };
    const double angle = std::min({corner(p, q, s), corner(q, s, p), corner(s, p, q)});
    ++count;
    min_angle = std::min(min_angle, angle);
    if (angle < 30) ++under;
    ratio_sum += std::max({e0, e1, e2}) / std::min({e0, e1, e2});
  }
  b.wall_triangles = count;
  if (count == 0) return;
  b.wall_min_angle_degrees = min_angle;
  b.wall_under_30_share = static_cast<double>(under) / static_cast<double>(count);
  b.wall_mean_edge_ratio = ratio_sum / static_cast<double>(count);
}

}  // namespace

void Run::write_stats() {
  PolygonizeStats& st = result.stats;
  st.components = components;
  st.method = "adaptive";
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  st.field_evaluations = ctx.field.counts() - before;
  st.triangles = result.mesh.num_triangles();
  st.vertices = result.mesh.num_vertices();
  const CreaseMesh* adopted = finished();  // the crease patches' or the blocks' mesh
  st.splits = tracking.tracker->splits() + (adopted ? adopted->splits : 0);
  st.merges = tracking.tracker->merges() + (adopted ? adopted->merges : 0);

  AdaptiveReport& r = st.adaptive.emplace();
  AdaptiveSettingsReport& s = r.settings;
  const bool repair = ctx.options.variant == Variant::Improved;
  s.variant = ctx.options.variant;
  s.sizing = resolved.sizing.mode;
  if (s.sizing == SizingMode::Factor) s.factor = resolved.sizing.factor;
  else s.tolerance = requested_tolerance(ctx.options, resolved);
  s.min_edge = resolved.sizing.min_edge;
  s.max_edge = resolved.sizing.max_edge;
  s.triangle_count = resolved.rule;
  s.seed_resolution = ctx.options.seed_resolution;
  s.grading = resolved.grading;
  s.quality_repair = repair;
  s.tolerance_refinement = repair && resolved.sizing.mode == SizingMode::Tolerance;

  r.seeding = tracking.seeding;
  r.seeding.non_finite_samples = seeds.grid.non_finite;
  r.seeding.touching_samples = seeds.grid.touching;
  r.seed_grid_seconds = seed_grid_seconds;

  // The seeding tracker's counters, and the blocks' trackers' for a mesh made of blocks (their
  // steps apart: blocks.steps); the crease patches' forced closures.
  TrackerReport& tr = r.tracker;
  tr = tracking.tracker->report();
  if (blocks.mesh) {
    const std::size_t steps = tr.steps;
    add_tracker_counts(tr, blocks.tracker);
    tr.steps = steps;
  }
  if (creases.mesh) tr.forced_closures += creases.mesh->forced_closures;
  tracking.note_tightest();
  tr.min_curvature_radius = std::isfinite(tracking.tightest.first) ? tracking.tightest.first : -1.0;

  CreaseReport& c = r.creases;
  c.handling = repair ? ctx.options.creases : CreaseHandling::Ignore;
  c.followed = creases.mesh.has_value();
  c.curves = creases.traced.curves.size();
  c.corners = creases.traced.corners.size();
  if (creases.mesh) {
    c.vertices = creases.mesh->crease_vertices;
    c.pieces = creases.mesh->pieces;
    c.steps = creases.mesh->steps;
    c.patch_refusals = creases.mesh->patch_refusals;
    c.landed_vertices = creases.mesh->landed;
  }
  c.components = creases.components;
  c.fallback = creases.fallback;
  c.tracing_resolution = creases.tracing_resolution;
  // A mesh made across a crease of a black box (see kink_in_black_box) that held together: the
  // crease is cut across by chords, not followed.
  c.across_black_box = kink_in_black_box(ctx.field, tracking.tightest);

  BlocksReport& b = r.blocks;
  b = blocks.report;
  b.requested = uses_blocks(ctx.options);
  b.used = blocks.mesh.has_value();
  b.components = blocks.components;
  b.steps = blocks.mesh ? blocks.mesh->steps : 0;
  add_wall_quality(result.mesh, b);
  b.pass_seconds = passes.seconds;
  b.pass_blocks = passes.blocks;

  r.quality = quality;
  r.quality.repair_below_degrees = kRepairBelowDegrees;
  r.necks = {.walks = necks.walks, .critical_points = necks.critical_points, .tested = necks.tested,
             .reruns = neck_reruns, .unwalked = necks.unwalked, .caps = necks.caps};
  r.recoveries.turn_limited = request.max_turn > 0;
  r.recoveries.look_ahead = request.look_ahead;
  r.recoveries.remeshed_with_rollbacks = tracking.remeshed;
  r.recoveries.remeshed_carefully = careful;
  r.recoveries.careful_max_turn = careful ? settings.sizing.max_turn : 0.0;
  r.min_angle_degrees = min_angle_degrees(result.mesh);
}

}  // namespace cdp::adaptive
