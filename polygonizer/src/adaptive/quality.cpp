// improve_mesh (quality.h): the repair's algorithms in order over one context.
#include "repair_angles.h"
#include "repair_context.h"
#include "repair_last_resort.h"
#include "repair_refine.h"
#include "repair_relax.h"

#include <numeric>
#include <stdexcept>

namespace cdp::adaptive {
namespace repair {
namespace {

QualityReport run_repair(RepairContext& ctx) {
  if (!(ctx.options_.tolerance > 0)) {
    repair_angles(ctx);
    relax(ctx);
    ctx.compact();
    return ctx.report_;
  }
  // Every triangle is checked once; after that only what an operation made or changed (the
  // operations keep the bound they were tested against, so only triangles that were beyond it
  // already can be beyond it after them).
  std::vector<int> all(ctx.tri_count());
  std::iota(all.begin(), all.end(), 0);
  std::vector<int> over = refine(ctx, all);
  ctx.since_check_.clear();
  repair_angles(ctx);
  relax(ctx);
  over = refine(ctx, ctx.merged(over, ctx.since_check_));
  ctx.since_check_.clear();
  repair_angles(ctx);
  // What the estimate cannot clear (it keeps kToleranceMargin for its own error) is measured
  // as the tolerance is defined, densely over the triangle; a triangle farther than the
  // tolerance there gets the last resort (last_resort) on a smooth field, and whatever that
  // cannot clear is reported, with its distance. Not on a field with creases: a triangle
  // across a crease meshed as smooth stays beyond the tolerance however it is split (the
  // capped cylinder with its creases ignored at 1e-3: 3.6 times the time and 19% more
  // triangles, with the same triangles reported).
  std::vector<Beyond> beyond = measure_densely(ctx, ctx.merged(over, ctx.since_check_));
  for (int round = 0; round < kLastResortRounds && ctx.smooth_ && !beyond.empty(); ++round) {
    ctx.since_check_.clear();
    std::vector<int> left;
    for (const Beyond& b : beyond)
      if (!last_resort(ctx, b)) left.push_back(b.t);
    if (ctx.since_check_.empty()) break;  // nothing could be split: what is left is reported
    left = ctx.merged(left, refine(ctx, ctx.since_check_));
    repair_angles(ctx);
    beyond = measure_densely(ctx, ctx.merged(left, ctx.since_check_));
  }
  for (const Beyond& b : beyond) {
    if (ctx.near_measured_again(b.T)) continue;  // the caller measures it again
    ++ctx.report_.over_tolerance;
    if (!(b.d <= ctx.report_.over_tolerance_worst)) {
      ctx.report_.over_tolerance_worst = b.d;
      ctx.report_.over_tolerance_near = (ctx.P(b.T[0]) + ctx.P(b.T[1]) + ctx.P(b.T[2])) / 3;
    }
  }
  ctx.compact();
  return ctx.report_;
}

}  // namespace
}  // namespace repair

QualityReport improve_mesh(const Field& field, Mesh& mesh, const QualityOptions& options,
                           std::vector<int>* renumbered, const std::vector<char>* measured_again) {
  if (mesh.normals.size() != mesh.positions.size())
    throw std::logic_error("improve_mesh: the mesh needs one normal per vertex");
  if (renumbered) {
    renumbered->resize(mesh.positions.size());
    std::iota(renumbered->begin(), renumbered->end(), 0);
  }
  if (mesh.triangles.empty()) return {};
  repair::RepairContext ctx(field, mesh, options);
  if (measured_again && options.keep_boundary) ctx.mark_measured_again(*measured_again);
  QualityReport report = repair::run_repair(ctx);
  if (renumbered) *renumbered = std::move(ctx.renumbered_);
  ctx.release();
  return report;
}

void add_repair_counts(QualityReport& sum, const QualityReport& r) {
  sum.repair_below_degrees = r.repair_below_degrees;
  sum.bad_before += r.bad_before;
  sum.bad_after += r.bad_after;
  sum.flips += r.flips;
  sum.moves += r.moves;
  sum.collapses += r.collapses;
  sum.relaxed += r.relaxed;
  sum.relax_flips += r.relax_flips;
  sum.relax_searched += r.relax_searched;
  sum.relax_search_sweeps = std::max(sum.relax_search_sweeps, r.relax_search_sweeps);
  sum.relax_crossings += r.relax_crossings;
  sum.splits += r.splits;
  sum.inserts += r.inserts;
  sum.last_resorts += r.last_resorts;
  sum.crease_vertices += r.crease_vertices;
  sum.measured_densely += r.measured_densely;
  sum.refine_measured += r.refine_measured;
  sum.refine_cleared += r.refine_cleared;
  sum.over_tolerance += r.over_tolerance;
  if (!(r.over_tolerance_worst <= sum.over_tolerance_worst)) {
    sum.over_tolerance_worst = r.over_tolerance_worst;
    sum.over_tolerance_near = r.over_tolerance_near;
  }
}

}  // namespace cdp::adaptive
