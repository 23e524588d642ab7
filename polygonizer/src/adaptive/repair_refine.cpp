// The tolerance's refinement (repair_refine.h).
#include "repair_refine.h"

namespace cdp::adaptive::repair {
namespace {

// The refinement measures densely (as the tolerance is defined) a triangle whose estimate is
// over kToleranceMargin of the tolerance but not over the tolerance, and leaves it unsplit when
// it measures at most this share of the tolerance (a margin for the surface between the dense
// grid's samples). The estimate's margin is for its own error, under 4 %, but rings of nearly
// equilateral triangles at the target length estimate at 0.87-0.93 of the tolerance (a
// triangle's sagitta is 4/3 of its edges'), and splitting them all left bands of triangles of
// edge ratio 1.6: a sphere capped by a plane at 1e-3, 7036 triangles (1009 splits) and a mean
// ratio of 1.239 -> 5286 (132 splits) and 1.131 with this (5298 at 0.945, 5222 at 0.99, 7016
// at 0.9: the estimate's own margin clears almost nothing).
constexpr double kDenseClearShare = 0.95;
// Rounds of splitting triangles beyond the tolerance; each round halves the longest edge of
// every offending triangle, and 24 halvings take any edge below min_edge.
constexpr int kRefineRounds = 24;

// The estimates of a round's triangles, made before the round splits any: each edge's midpoint
// once (two triangles share it), then each triangle into its slot (a triangle a split changes
// before its turn is measured again there). A thread-safe field's on all cores (the same on any
// number of threads); another's (a Python function) in batched calls, midpoints and centroids,
// where one at a time took a call a point: a black-box tanglecube at tolerance 1e-3, 1.06
// million calls for 96,588 triangles.
void estimate_ahead(RepairContext& ctx, const std::vector<int>& work) {
  if (ctx.estimates_.size() < ctx.mesh_.triangles.size()) ctx.estimates_.resize(ctx.mesh_.triangles.size());
  std::vector<int> todo;
  RepairContext::EdgeTable table;
  for (std::size_t w = 0; w < work.size(); ++w) {
    ctx.poll(w);
    const int t = work[w];
    if (ctx.alive_[t] && !ctx.remembered(t)) {
      todo.push_back(t);
      const Tri& T = ctx.mesh_.triangles[t];
      for (int i = 0; i < 3; ++i) table.add(T[i], T[(i + 1) % 3]);
    }
  }
  ctx.poll();
  table.d.resize(table.size());
  const auto midpoint = [&](std::size_t i) {
    const auto [x, y] = table.ends(i);
    return Vec3(0.5 * (ctx.P(x) + ctx.P(y)));
  };
  if (ctx.predict_) {
    // Every corner's jet first, so that the passes below only read them.
    std::vector<int> corners;
    corners.reserve(3 * todo.size());
    for (const int t : todo) corners.insert(corners.end(), ctx.mesh_.triangles[t].begin(), ctx.mesh_.triangles[t].end());
    ctx.fill_jets(corners);
  }
  if (ctx.field_.thread_safe()) {
    detail::parallel_blocks(table.size(), kRepairBlock, ctx.workers_, [&](std::size_t begin, std::size_t end, unsigned) {
      ctx.poll();
      for (std::size_t i = begin; i < end; ++i) {
        const auto [x, y] = table.ends(i);
        table.d[i] = ctx.midpoint_sample(x, y);
      }
    });
    detail::parallel_blocks(todo.size(), kRepairBlock, ctx.workers_, [&](std::size_t begin, std::size_t end, unsigned) {
      ctx.poll();
      RepairContext::MidpointMemo memo;
      memo.table = &table;
      for (std::size_t i = begin; i < end; ++i) ctx.estimate_distance(ctx.mesh_.triangles[todo[i]], todo[i], &memo);
    });
  } else {
    // The same samples as above: the predicted ones, then the rest measured in one batch.
    std::vector<Vec3> points;
    std::vector<std::size_t> which;
    for (std::size_t i = 0; i < table.size(); ++i) {
      const auto [x, y] = table.ends(i);
      const std::optional<RepairContext::Mid> m = ctx.predict_ ? ctx.predicted_midpoint(x, y) : std::nullopt;
      if (m) {
        table.d[i] = *m;
      } else {
        which.push_back(i);
        points.push_back(midpoint(i));
      }
    }
    std::vector<double> measured;
    ctx.signed_distances(points, measured);
    for (std::size_t k = 0; k < which.size(); ++k) table.d[which[k]] = {measured[k], -1};
    // The centroids predicted where estimate_from would predict them.
    RepairContext::MidpointMemo lookup;
    lookup.table = &table;
    std::vector<RepairContext::Mid> centroids(todo.size());
    points.clear(), which.clear();
    for (std::size_t i = 0; i < todo.size(); ++i) {
      const Tri& T = ctx.mesh_.triangles[todo[i]];
      const auto mid = [&](int k) { return ctx.midpoint_distance(T[k], T[(k + 1) % 3], &lookup); };
      const std::optional<RepairContext::Mid> c =
          ctx.predict_ ? ctx.predicted_centroid(T, {mid(0), mid(1), mid(2)}) : std::nullopt;
      if (c) {
        centroids[i] = *c;
      } else {
        which.push_back(i);
        points.push_back((ctx.P(T[0]) + ctx.P(T[1]) + ctx.P(T[2])) / 3);
      }
    }
    ctx.signed_distances(points, measured);
    for (std::size_t k = 0; k < which.size(); ++k) centroids[which[k]] = {measured[k], -1};
    for (std::size_t begin = 0; begin < todo.size(); begin += kRepairBlock) {
      ctx.poll();
      RepairContext::MidpointMemo memo;  // as a block of the threads' (its list searched linearly)
      memo.table = &table;
      for (std::size_t i = begin; i < std::min(todo.size(), begin + kRepairBlock); ++i)
        ctx.estimate_distance(ctx.mesh_.triangles[todo[i]], todo[i], &memo, &centroids[i]);
    }
  }
}

}  // namespace

std::vector<int> refine(RepairContext& ctx, std::vector<int> work) {
  // A triangle whose longest edge cannot be split may have its other edges split when its
  // estimate is within this many times the bound: a ridge a little narrower than the edges
  // is resolved by a few such splits (the bunny VIS-2000 at 1.035e-3: 4 triangles up to 1.45
  // eps, none after), but a crease the sizing does not see never is, and splitting across it
  // without bound made the cube meshed as smooth at 5e-4 (creases ignored) take 162 s for
  // 11,780 triangles with a smallest angle of 0.06 degrees, against 0.3 s and 566 triangles.
  constexpr double kFallbackShare = 4;
  const double bound = kToleranceMargin * ctx.options_.tolerance;
  std::vector<int> left;
  for (int round = 0; round < kRefineRounds && !work.empty(); ++round) {
    ctx.touched_.clear();
    estimate_ahead(ctx, work);
    for (std::size_t i = 0; i < work.size(); ++i) {
      ctx.poll(i);
      const int t = work[i];
      if (!ctx.alive_[t]) continue;
      const Tri T = ctx.mesh_.triangles[t];
      const double estimate = ctx.estimate_distance(T, t);
      if (!(estimate > bound)) continue;
      if (ctx.options_.measure_near_bound && estimate <= ctx.options_.tolerance) {
        ++ctx.report_.refine_measured;
        if (ctx.sampled_distance(T, estimate) <= kDenseClearShare * ctx.options_.tolerance) {
          ++ctx.report_.refine_cleared;
          continue;
        }
      }
      // Halve the longest edge; after a split the edge is gone, so a neighbour visited later
      // in this round sees the new triangles. When the longest edge cannot be split (its
      // midpoint's normal or the new triangles would fold: a ridge narrower than the edges, as
      // on the bunny VIS-2000 where normals 110 degrees apart share a triangle), the next
      // longest is tried, then the shortest, on a triangle near the bound (kFallbackShare).
      const std::array<int, 3> order = ctx.edges_longest_first(T).second;
      bool split = false;
      for (const int k : order)
        if ((k == order[0] || estimate <= kFallbackShare * bound) && (split = ctx.try_split(t, T[k], T[(k + 1) % 3]))) break;
      if (!split) left.push_back(t);
    }
    std::sort(ctx.touched_.begin(), ctx.touched_.end());
    ctx.touched_.erase(std::unique(ctx.touched_.begin(), ctx.touched_.end()), ctx.touched_.end());
    work = ctx.touched_;
  }
  return ctx.merged(left, work);
}

}  // namespace cdp::adaptive::repair
