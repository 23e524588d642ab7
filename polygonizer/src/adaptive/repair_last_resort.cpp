// The dense measurement and the last resort (repair_last_resort.h).
#include "repair_last_resort.h"

namespace cdp::adaptive::repair {
namespace {

// Splits triangle t in three at the surface point a projection landed on (its corners at least
// last_resort_edge from it), with the checks of every split (repair_context.h).
bool try_insert_inside(RepairContext& ctx, int t, const ProjectionResult& landed) {
  const Tri T = ctx.mesh_.triangles[t];
  const Vec3& x = landed.point;
  const Vec3& g = landed.gradient;  // at x
  if (!landed.ok() || !(g.squaredNorm() > 0)) return false;
  const Vec3 ng = g.normalized();
  for (int v : T)
    if (!((x - ctx.P(v)).norm() >= ctx.last_resort_edge())) return false;
  const int m = static_cast<int>(ctx.mesh_.positions.size());
  ctx.add_vertex(x, ng);
  const std::vector<Tri> added{{T[0], T[1], m}, {T[1], T[2], m}, {T[2], T[0], m}};
  const double floor = ctx.facing_floor({t});
  bool ok = true;
  for (const Tri& s : added) ok = ok && ctx.faces_surface(s, floor);
  if (ok) ok = !ctx.intersects(added, {t});
  if (!ok) {
    ctx.drop_last_vertex();
    return false;
  }
  ctx.make_room_for_triangles(2);
  const int t2 = ctx.tri_count(), t3 = t2 + 1;
  ctx.mesh_.triangles[t] = added[0];
  ctx.mesh_.triangles.push_back(added[1]);
  ctx.mesh_.triangles.push_back(added[2]);
  ctx.alive_.push_back(1);
  ctx.alive_.push_back(1);
  ctx.stamp_.push_back(0);
  ctx.stamp_.push_back(0);
  // T[0]: t, t3 (was t); T[1]: t, t2; T[2]: t2, t3; m: all three.
  ctx.vt_[T[0]].push_back(t3);
  ctx.vt_[T[2]].push_back(t2);
  ctx.vt_[T[2]].push_back(t3);
  ctx.erase_value(ctx.vt_[T[2]], t);
  ctx.vt_[T[1]].push_back(t2);
  ctx.vt_[m] = {t, t2, t3};
  for (int s : {t, t2, t3}) {
    ctx.hash_box(s);
    ctx.touch(s);
  }
  ++ctx.report_.splits;
  return true;
}

}  // namespace

std::vector<Beyond> measure_densely(RepairContext& ctx, const std::vector<int>& work) {
  std::vector<Beyond> out;
  for (int t : work) {
    if (!ctx.alive_[t]) continue;
    const Tri& T = ctx.mesh_.triangles[t];
    const double estimate = ctx.estimate_distance(T);
    if (!(estimate > kToleranceMargin * ctx.options_.tolerance)) continue;
    ++ctx.report_.measured_densely;
    ProjectionResult worst;
    const double d = ctx.sampled_distance(T, estimate, &worst);
    if (d > ctx.options_.tolerance) out.push_back({t, T, d, worst});
  }
  return out;
}

bool last_resort(RepairContext& ctx, const Beyond& b) {
  if (!ctx.alive_[b.t] || ctx.mesh_.triangles[b.t] != b.T) return true;  // changed since it was measured
  const std::array<int, 3> order = ctx.edges_longest_first(b.T).second;
  for (const int k : order)
    if (ctx.try_split(b.t, b.T[k], b.T[(k + 1) % 3], false, ctx.last_resort_edge())) {
      ++ctx.report_.last_resorts;
      return true;
    }
  if (try_insert_inside(ctx, b.t, b.worst)) {
    ++ctx.report_.last_resorts;
    return true;
  }
  return false;
}

}  // namespace cdp::adaptive::repair
