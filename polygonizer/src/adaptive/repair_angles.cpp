// The angle repair (repair_angles.h).
#include "repair_angles.h"

#include <numbers>

namespace cdp::adaptive::repair {
namespace {

// Rounds over the work list. Each round visits every triangle still under the bound once and
// every accepted operation raises the smallest angle it touches by kMinGain, so the pass ends
// on its own; the bound caps the cost (measured: the bunny VIS-800 and tanglecube settle in
// under 10 rounds).
constexpr int kQualityRounds = 24;
// A needle's shortest edge is collapsed when it is shorter than this share of the triangle's
// second-shortest edge (the other ops cannot open an angle opposite an edge that short).
constexpr double kNeedleShare = 0.5;
// A cap whose largest angle is at least this (radians; 150 degrees) on a crease edge: its apex
// lies within a sixth of the edge from it, well inside the crease probes' reach of the crease.
constexpr double kCapAngle = 5 * std::numbers::pi / 6;

// One triangle under the bound: the first operation of the list that is applied (flips, a
// needle's collapse, moves of its corners and their neighbours, a split of a cap, collapses).
bool repair_triangle(RepairContext& ctx, int t) {
  const Tri T = ctx.mesh_.triangles[t];
  const auto [len, order] = ctx.edges_longest_first(T);
  // A cap (an angle near 180 degrees) opens by flipping its longest edge; other edges may flip
  // too. Flips change nothing but connectivity, so they go first.
  for (int k : order)
    if (ctx.try_flip(t, k)) return true;
  // A needle: its shortest edge goes.
  const int shortest = order[2];
  if (len[shortest] < kNeedleShare * len[order[1]] &&
      ctx.try_collapse(t, T[shortest], T[(shortest + 1) % 3]))
    return true;
  // Otherwise move a corner: the one at the smallest angle first.
  std::array<std::pair<double, int>, 3> corners{};
  for (int k = 0; k < 3; ++k) corners[k] = {angle_at(ctx.P(T[k]), ctx.P(T[(k + 1) % 3]), ctx.P(T[(k + 2) % 3])), k};
  std::sort(corners.begin(), corners.end());
  for (const auto& [angle, k] : corners)
    if (ctx.try_move(T[k])) return true;
  // Then the neighbours of the corners (the second ring), which reshape it from outside.
  for (int v : T)
    for (int w : ctx.neighbours(v))
      if (w != T[0] && w != T[1] && w != T[2] && ctx.try_move(w)) return true;
  // A cap: a vertex inside the quad on its longest edge.
  if (ctx.try_split(t, T[order[0]], T[(order[0] + 1) % 3], true)) return true;
  // A cap on a crease edge whose apex stands next to the crease, where a patch's front placed it
  // within the patch tests' margin (fogleman/sdf's model with filleted holes at factor 2.5: an
  // apex 0.0024 past the crease where two holes' walls meet, a 2.8 degree cap): the probes flag
  // the apex as a crease vertex too, so nothing above may move or merge it. It goes onto the
  // nearer end of the crease edge.
  const int apex = (order[0] + 2) % 3;
  if (angle_at(ctx.P(T[apex]), ctx.P(T[(apex + 1) % 3]), ctx.P(T[(apex + 2) % 3])) >= kCapAngle &&
      ctx.on_crease(T[order[0]]) && ctx.on_crease(T[(order[0] + 1) % 3]) && ctx.on_crease(T[apex])) {
    // Edge k joins T[k] and T[k + 1]: edge `apex` the apex to T[order[0]], edge apex + 2 the other end to it.
    const int near = len[apex] <= len[(apex + 2) % 3] ? T[order[0]] : T[(order[0] + 1) % 3];
    if (ctx.try_collapse(t, near, T[apex], true)) return true;
  }
  // Last, removing a vertex: any edge of the triangle, shortest first, where that raises the
  // smallest angle around (a vertex squeezed between neighbours that cannot move).
  for (int i = 2; i >= 0; --i) {
    const int k = order[i];
    if (k == shortest && len[shortest] < kNeedleShare * len[order[1]]) continue;  // tried above
    if (ctx.try_collapse(t, T[k], T[(k + 1) % 3])) return true;
  }
  return false;
}

}  // namespace

void repair_angles(RepairContext& ctx) {
  std::vector<int> work;
  for (int t = 0; t < ctx.tri_count(); ++t) {
    ctx.poll(static_cast<std::size_t>(t));
    if (ctx.alive_[t] && ctx.tri_below(ctx.mesh_.triangles[t])) work.push_back(t);
  }
  ctx.report_.bad_before = std::max(ctx.report_.bad_before, work.size());
  for (int round = 0; round < kQualityRounds && !work.empty(); ++round) {
    std::vector<std::pair<double, int>> order;
    for (int t : work)
      if (ctx.alive_[t]) order.push_back({ctx.tri_min_angle(ctx.mesh_.triangles[t]), t});
    std::sort(order.begin(), order.end());
    ctx.touched_.clear();
    bool changed = false;
    for (std::size_t i = 0; i < order.size(); ++i) {
      ctx.poll(i);
      const int t = order[i].second;
      if (!ctx.alive_[t] || !(ctx.tri_min_angle(ctx.mesh_.triangles[t]) < ctx.options_.improve_below)) continue;
      changed = repair_triangle(ctx, t) || changed;
    }
    if (!changed) break;
    // Next round: what is still bad among the triangles visited or changed.
    std::vector<int> next;
    for (const auto& [angle, t] : order) next.push_back(t);
    next.insert(next.end(), ctx.touched_.begin(), ctx.touched_.end());
    std::sort(next.begin(), next.end());
    next.erase(std::unique(next.begin(), next.end()), next.end());
    work.clear();
    for (std::size_t i = 0; i < next.size(); ++i) {
      ctx.poll(i);
      const int t = next[i];
      if (ctx.alive_[t] && ctx.tri_below(ctx.mesh_.triangles[t])) work.push_back(t);
    }
  }
  // Every triangle under the bound is in the work list at a round's start (the scan above, then
  // each round's visited and changed triangles: an operation lists every triangle it changes or
  // makes in touched_), and a round that changes nothing leaves it as it is: so what is left
  // under the bound is the list, without a scan of every triangle again.
  ctx.report_.bad_after = work.size();
}

}  // namespace cdp::adaptive::repair
