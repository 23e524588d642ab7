// The angle repair (repair_angles.h).
#include "repair_angles.h"

#include <cstddef>
#include <numbers>
#include <vector>

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


// What each visit of repair_triangle found, so that a triangle it failed on is not tried again
// while nothing around it has changed. Its operations read the mesh within two rings of its
// corners (a corner's neighbours' stars, their valences and links) and the field there, so where
// no triangle with a corner in those rings has changed since a visit failed, the next visit
// would fail the same way and is skipped: the repair makes the same operations in the same
// order, with fewer visits. (Triangles whose corners all lie on creases cannot be mended by
// moves and were tried every round: 9,837 visits for 204 operations on the table of the SDF
// sweep, a third of its run.) Not quite: an operation is also refused where it would cross a
// triangle near it in space (RepairContext::intersects), which may lie beyond the two rings (a
// triangle at a moved neighbour's outer corners is three rings out; one near in space only, any
// number), and a change there could free it; such a refusal stands until a change nears the
// triangle. The SDF and topology sweeps made the same meshes, bit for bit, with and without.
class Visits {
 public:
  explicit Visits(std::size_t vertices) : changed_at_(vertices, -1) {}
  // Whether t was visited, failed, and no triangle within two rings of its corners changed since.
  bool unchanged_since_failure(const RepairContext& ctx, int t) const {
    const auto ti = static_cast<std::size_t>(t);
    if (ti >= failed_at_.size() || failed_at_[ti] < 0) return false;
    const long since = failed_at_[ti];
    const auto changed = [&](int v) {
      const auto vi = static_cast<std::size_t>(v);
      return vi >= changed_at_.size() || changed_at_[vi] >= since;
    };
    // The corners of the stars of the corners of t's corners' stars (no sorted neighbour lists:
    // this runs on every triangle still failing, every round).
    for (const int v : ctx.mesh_.triangles[ti])
      for (const int u : ctx.vt_[static_cast<std::size_t>(v)])
        for (const int w : ctx.mesh_.triangles[static_cast<std::size_t>(u)]) {
          if (changed(w)) return false;
          for (const int y : ctx.vt_[static_cast<std::size_t>(w)])
            for (const int x : ctx.mesh_.triangles[static_cast<std::size_t>(y)])
              if (changed(x)) return false;
        }
    return true;
  }
  // After a visit of t: the corners of the triangles it changed or made (touched_ from `stamped`
  // on) stamped with this visit, and t's failure.
  void record(const RepairContext& ctx, int t, bool applied, std::size_t& stamped) {
    for (; stamped < ctx.touched_.size(); ++stamped)
      for (const int v : ctx.mesh_.triangles[static_cast<std::size_t>(ctx.touched_[stamped])]) {
        const auto vi = static_cast<std::size_t>(v);
        if (vi >= changed_at_.size()) changed_at_.resize(vi + 1, -1);
        changed_at_[vi] = visit_;
      }
    const auto ti = static_cast<std::size_t>(t);
    if (ti >= failed_at_.size()) failed_at_.resize(ti + 1, -1);
    failed_at_[ti] = applied ? -1 : visit_;
    ++visit_;
  }

 private:
  long visit_ = 0;
  std::vector<long> failed_at_, changed_at_;  // per triangle, per vertex; -1 none
};
}  // namespace

void repair_angles(RepairContext& ctx) {
  std::vector<int> work;
  for (int t = 0; t < ctx.tri_count(); ++t) {
    ctx.poll(static_cast<std::size_t>(t));
    if (ctx.alive_[t] && ctx.tri_below(ctx.mesh_.triangles[t])) work.push_back(t);
  }
  ctx.report_.bad_before = std::max(ctx.report_.bad_before, work.size());
  Visits visits(ctx.mesh_.positions.size());
  for (int round = 0; round < kQualityRounds && !work.empty(); ++round) {
    std::vector<std::pair<double, int>> order;
    for (int t : work)
      if (ctx.alive_[t]) order.push_back({ctx.tri_min_angle(ctx.mesh_.triangles[t]), t});
    std::sort(order.begin(), order.end());
    ctx.touched_.clear();
    std::size_t stamped = 0;
    bool changed = false;
    for (std::size_t i = 0; i < order.size(); ++i) {
      ctx.poll(i);
      const int t = order[i].second;
      if (!ctx.alive_[t] || !(ctx.tri_min_angle(ctx.mesh_.triangles[t]) < ctx.options_.improve_below)) continue;
      if (visits.unchanged_since_failure(ctx, t)) continue;
      const bool applied = repair_triangle(ctx, t);
      visits.record(ctx, t, applied, stamped);
      changed = applied || changed;
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
