// Expansion of the minimal-angle front point (paper section 5 and Figure 5): the point gets n
// triangles spanning its front angle, with n - 1 new points rotated in the tangent plane at
// the heuristic edge length and projected onto the surface; the new points replace it on the
// front. When n <= 1 the angle is closed by the single triangle (prev, point, next).
#include "tracker.h"
#include "triangle_count.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cdp::adaptive {

namespace {
// The grading (see expand): a new point may ask for edges at most this many times the length
// it was placed at. The size field then changes by at most a quarter per edge, and a triangle's
// edges can differ by about that much (Variant::Improved's mean longest/shortest edge must stay
// at most 1.25). With 1.5 the mean ratio was 1.25-1.27 on Chmutov's sextic at factors 1-3, the
// Igea VIS-4004 at 1-2 and the MPU models at 1-2, and the repair's relaxation could not bring
// it under; with 1.25 it is 1.21-1.24 there. Its cost: 1-47% more triangles at factors 1-3 (the
// most on the MPU models at factor 1, where the curvature changes fastest), a few % at 5 and
// above; Phong and depth errors at a given triangle count are the same or lower (bunny VIS-800,
// factors 1-5).
constexpr double kGrowth = 1.25;
// See expand: a new point may ask for edges down to this share of the length it was placed at
// before it is placed again closer (the grading's kGrowth the other way, with a margin).
constexpr double kAnticipate = 0.5;
// Settings::side_points: an expansion whose first or last new front edge (from the front point
// next to the expanded one to the nearest new point) would be longer than this many times the
// length the points were placed at gets points along it (add_side_points). Grading keeps
// neighbouring edges within about 1.5 times each other where sizes change smoothly; beyond 2 a
// front point's target dropped abruptly (a fillet or bump narrower than the edges before it).
constexpr double kSideEdgeRatio = 2;
// At most this many such points on either side (a front edge up to five lengths long).
constexpr int kMaxSidePoints = 4;
// Closing an angle joins prev and next by an edge; when their normals are more than 100 degrees
// apart the two lie around a bend tighter than the edges (a thin neck of the tanglecube at
// factor 1 got a triangle whose corners' normals were 155 degrees apart, folded over its
// neighbours). Such an angle is expanded with a new point between them instead. Beyond 90
// degrees with a margin: a cube's faces meet at exactly 90, and an edge across that crease
// is right.
constexpr double kFoldCosine = -0.1736;
// An expansion whose new points fold across the surface (folds_across) is tried with this many
// more points at most before a shorter length: more points turn the normal less between
// neighbours. With none, the fifty blobs of the hard-surface suite stalled at factor 1.
constexpr int kExtraPointsOnFold = 2;
}  // namespace

bool Tracker::folds_across(int vb, const std::vector<Placed>& placed, int va) const {
  // Each new point is checked against the expanded point only (place_points); two of them, or
  // one and a neighbour, can still lie on sheets facing apart, each within the turn allowed
  // from the middle: the new front edge between them then spans a fold or a gap of the
  // surface, the way a closed angle does (kFoldCosine). A random blob field at factor 1 closed
  // a tunnel so, with a membrane across the air whose corners' normals were 131-162 degrees apart.
  const Vec3* last = &mesh_.normals[vb];
  for (const Placed& x : placed) {
    if (last->dot(x.curvature.normal) < kFoldCosine) return true;
    last = &x.curvature.normal;
  }
  return last->dot(mesh_.normals[va]) < kFoldCosine;
}

void Tracker::close_angle(int node) {
  const FrontNode n = fs_.nodes[node];
  emit_triangle(fs_.nodes[n.prev].vertex, n.vertex, fs_.nodes[n.next].vertex);
  remove_node(node);
  link(n.prev, n.next);
  refresh(n.prev);
  refresh(n.next);
}

void Tracker::add_side_points(int v, int vb, int va, double d, std::vector<Placed>& placed) {
  // Where the front reaches a fillet or a bump narrower than its edges, a front point there asks
  // for edges far shorter than its front edges: it is expanded with short ones, and the
  // triangle between its long front edge and its first new point is a sliver whose long edge
  // is the next front edge. Each expansion next to it repeats that, a fan of slivers hinged on
  // one vertex across the fillet, which no split of the repair can mend without folding (blobs39
  // of the topology sweep at 1e-2: 7 triangles up to 10 eps from the surface, smallest angle
  // 7.7 degrees; a fresh blob field at 1e-2, 13 up to 47 eps). Points along that edge, in
  // steps of at most d, break it into edges of the new points' length instead.
  // Each is placed from v like the fan's own points: in v's tangent plane toward its place on
  // the chord, then onto the surface.
  const Vec3& p = mesh_.positions[v];
  const Vec3& N = mesh_.normals[v];
  const auto between = [&](const Vec3& from, const Vec3& to, std::vector<Placed>& out) {
    const double length = (to - from).norm();
    if (!(length > kSideEdgeRatio * d)) return true;
    const int count = std::min(kMaxSidePoints, static_cast<int>(std::ceil(length / d)) - 1);
    for (int j = 1; j <= count; ++j) {
      const Vec3 at = from + (to - from) * (static_cast<double>(j) / (count + 1));
      Vec3 dir = at - p;
      dir -= N * N.dot(dir);
      const double reach = dir.norm();
      if (!(reach > 0)) return false;
      dir /= reach;  // place_points walks unit directions
      std::vector<Placed> got = place_points(v, std::span(&dir, 1), reach);
      if (got.empty()) return false;
      out.push_back(std::move(got.front()));
    }
    return true;
  };
  std::vector<Placed> before, after;
  if (!between(mesh_.positions[vb], placed.front().point, before)) return;
  if (!between(placed.back().point, mesh_.positions[va], after)) return;
  if (before.empty() && after.empty()) return;
  std::vector<Placed> all = std::move(before);
  all.insert(all.end(), placed.begin(), placed.end());
  all.insert(all.end(), after.begin(), after.end());
  if (folds_across(vb, all, va)) return;
  placed = std::move(all);
}

Tracker::ExpandOutcome Tracker::expand(int node, double delta) {
  const FrontNode n = fs_.nodes[node];
  const int va = fs_.nodes[n.prev].vertex, vb = fs_.nodes[n.next].vertex;
  const Vec3& p = mesh_.positions[n.vertex];
  int count = triangle_count(s_.rule, n.angle, (mesh_.positions[va] - mesh_.positions[vb]).norm(), delta);
  if (count <= 1 && mesh_.normals[va].dot(mesh_.normals[vb]) < kFoldCosine) count = 2;
  if (count <= 1 && leaves_patch(va, vb)) count = 2;

  if (count <= 1) {
    const int q = find_closing_obstacle(node);
    if (q >= 0) {
      // Bridge to the best point around, which need not be the obstacle itself.
      return {false, find_bridge(node, 1.05 * (mesh_.positions[fs_.nodes[q].vertex] - p).norm())};
    }
    if (const int r = crossed_front_edge(va, vb, mesh_.positions[vb], n.vertex); r >= 0)
      return {false, bridge_around(node, r)};
    close_angle(node);
    return {true, -1};
  }
  double placed_at = 0;
  std::vector<Placed> placed = place_fan(n, count, delta, placed_at);
  if (placed.empty()) return {false, -1};
  // The fan's own first and last points, before any side points join them.
  const Fan fan{placed.front().point, placed.back().point, placed.size()};
  if (s_.side_points) add_side_points(n.vertex, vb, va, placed_at, placed);
  if (const std::optional<ExpandOutcome> refused = refuse_fan(node, placed, fan, delta)) return *refused;
  side_points_ += placed.size() - fan.size;
  emit_fan(node, placed, delta);
  return {true, -1};
}

std::vector<Tracker::Placed> Tracker::place_fan(const FrontNode& n, int count, double delta, double& placed_at) {
  const int va = fs_.nodes[n.prev].vertex, vb = fs_.nodes[n.next].vertex;
  const Vec3& p = mesh_.positions[n.vertex];
  const double theta = n.angle;
  // Tangent frame: e0 towards next, e1 a quarter turn counter-clockwise (towards the unmeshed side).
  const Vec3& N = mesh_.normals[n.vertex];
  Vec3 e0 = mesh_.positions[vb] - p;
  e0 -= N * N.dot(e0);
  if (e0.squaredNorm() == 0) return {};
  e0.normalize();
  const Vec3 e1 = N.cross(e0);

  // Where Newton cannot place a point at full length (a nearby sheet, a vanishing gradient),
  // try shorter edges before giving up on this point for now.
  std::vector<Vec3> dirs;
  // The points at length d: count - 1 of them, or up to kExtraPointsOnFold more where those would
  // fold across the surface (folds_across; above min_edge, like place_points' own turn bound).
  // Empty when they cannot all be placed. A count that helped is kept for the shorter lengths the
  // careful run's anticipation tries next.
  int fan = count;
  const auto place_at = [&](double d) {
    for (int c = fan; c <= count + kExtraPointsOnFold; ++c) {
      dirs.resize(c - 1);
      for (int k = 1; k < c; ++k) {
        const double t = k * theta / c;
        dirs[k - 1] = std::cos(t) * e0 + std::sin(t) * e1;
      }
      std::vector<Placed> got = place_points(n.vertex, dirs, d);
      if (got.size() < dirs.size()) {
        if (c == fan) return std::vector<Placed>{};
        continue;
      }
      if (d <= s_.sizing.min_edge || !folds_across(vb, got, va)) {
        fan = c;
        return got;
      }
    }
    fan = count;
    return std::vector<Placed>{};
  };
  std::vector<Placed> placed, complete;
  double complete_at = 0;  // the lengths they were placed at (and placed_at)
  for (double d = delta; d >= kShortestEdgeLoop * s_.sizing.min_edge; d *= 0.5) {
    placed = place_at(d);
    placed_at = d;
    if (placed.empty()) {
      // A placement again at half the length that fails keeps the one it was to replace.
      if (!complete.empty()) {
        placed = std::move(complete);
        placed_at = complete_at;
        break;
      }
      continue;
    }
    // Settings::anticipate: a new point whose own target is below kAnticipate times the length
    // it was placed at lies where the surface turns much faster than at the front (a neck
    // ahead, a small blob): its edges would be too long for it, and an edge longer than a neck
    // is wide jumps it. Placed again at half the length, down to min_edge.
    if (!s_.anticipate || 0.5 * d < s_.sizing.min_edge) break;
    const bool too_long = std::any_of(placed.begin(), placed.end(), [&](const Placed& x) {
      return placed_target(x) < kAnticipate * d;
    });
    if (!too_long) break;
    ++anticipations_;
    complete = placed;
    complete_at = d;
  }
  return placed;
}

std::optional<Tracker::ExpandOutcome> Tracker::refuse_fan(int node, const std::vector<Placed>& placed, const Fan& fan,
                                                          double delta) {
  const FrontNode n = fs_.nodes[node];
  const int va = fs_.nodes[n.prev].vertex, vb = fs_.nodes[n.next].vertex;
  const Vec3& p = mesh_.positions[n.vertex];
  const Vec3& N = mesh_.normals[n.vertex];
  // The front cells around the checks below, looked up once: they ask the front hash about
  // boxes close together (each new point, and each new edge with the longest front edge
  // around it), and nothing changes the front before they are done.
  {
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    const auto cover = [&](const std::pair<Vec3, Vec3>& box) {
      lo = lo.cwiseMin(box.first);
      hi = hi.cwiseMax(box.second);
    };
    const double near_point = 0.5 * delta, longest = longest_front_edge();
    for (const Placed& x : placed) {
      cover({x.point.array() - near_point, x.point.array() + near_point});
      cover(front_edge_search_box(p, x.point, longest));
    }
    cover(front_edge_search_box(mesh_.positions[vb], placed.front().point, longest));
    cover(front_edge_search_box(mesh_.positions[va], placed.back().point, longest));
    cover(front_edge_search_box(mesh_.positions[vb], fan.first, longest));
    cover(front_edge_search_box(mesh_.positions[va], fan.last, longest));
    front_hash_.gather(lo, hi, near_front_);
  }
  // A new point landing close to a front point the collision test did not see (beyond
  // collision_factor * delta of the candidate) would make a sliver or an overlap: bridge to
  // that front point instead.
  for (const Placed& x : placed) {
    int hit = -1;
    double hit_d = 0.5 * delta;
    front_hash_.for_each_near(near_front_, x.point, hit_d, [&](int q) {
      const int vq = fs_.nodes[q].vertex;
      if (vq == n.vertex || vq == va || vq == vb) return;
      if (!same_side(N, vq)) return;
      const double d = (mesh_.positions[vq] - x.point).norm();
      if (d < hit_d || (d == hit_d && q < hit)) hit = q, hit_d = d;
    });
    if (hit >= 0) return ExpandOutcome{false, find_bridge(node, 1.05 * (mesh_.positions[fs_.nodes[hit].vertex] - p).norm())};
    if (const int r = crossed_front_edge(n.vertex, -1, x.point, n.vertex, &near_front_); r >= 0)
      return ExpandOutcome{false, bridge_around(node, r)};
  }
  // The new front edges next -> x1 and x_last -> prev must leave next and prev into their own
  // unmeshed sectors. The points were rotated in the tangent plane of the expanded point; where
  // the surface bends between it and its neighbours, a point can land behind a neighbour, on
  // triangles already made around it, and no front edge is crossed there (the ones bounding
  // those triangles all end at the neighbour). A random blob field at factor 1 folded over so.
  // The point waits instead; the neighbour's own expansion usually closes the gap first.
  if (!in_sector(n.next, placed.front().point, 0) || !in_sector(n.prev, placed.back().point, 0)) return ExpandOutcome{false, -1};
  // The new front edges must not cross the front either. With side points, the chords they
  // stand in for too (next -> the fan's first point, its last -> prev): the side points lie
  // along them, and only the first piece of each chain is a segment tested here.
  for (const auto& [from, to] : {std::pair{vb, placed.front().point}, std::pair{va, placed.back().point}})
    if (const int r = crossed_front_edge(from, -1, to, n.vertex, &near_front_); r >= 0)
      return ExpandOutcome{false, bridge_around(node, r)};
  if (placed.size() != fan.size)
    for (const auto& [from, to] : {std::pair{vb, fan.first}, std::pair{va, fan.last}})
      if (const int r = crossed_front_edge(from, -1, to, n.vertex, &near_front_); r >= 0)
        return ExpandOutcome{false, bridge_around(node, r)};
  return std::nullopt;
}

void Tracker::emit_fan(int node, const std::vector<Placed>& placed, double delta) {
  const FrontNode n = fs_.nodes[node];
  const int va = fs_.nodes[n.prev].vertex, vb = fs_.nodes[n.next].vertex;
  // Triangles (p, next, x1), (p, x1, x2), ..., (p, x_{n-1}, prev): counter-clockwise from
  // outside; the new points run from prev's side to next's side on the front.
  std::vector<int> vs;
  vs.reserve(placed.size());
  for (const Placed& x : placed) {
    const int v = add_vertex(x);
    // Grading: a new point may ask for at most kGrowth times the length it was placed at, so
    // that a curvature estimate that drops abruptly (MPU's Hessian is only piecewise smooth)
    // cannot put long edges right beside short ones.
    if (s_.grading) target_[v] = std::min(target_[v], kGrowth * delta);
    vs.push_back(v);
  }
  emit_triangle(n.vertex, vb, vs.front());
  for (std::size_t k = 0; k + 1 < vs.size(); ++k) emit_triangle(n.vertex, vs[k], vs[k + 1]);
  emit_triangle(n.vertex, vs.back(), va);

  remove_node(node);
  const int f = n.front;
  int after = n.next;
  std::vector<int> fresh;
  for (int v : vs) {
    const int m = insert_node(v, f);
    link(m, after);
    after = m;
    fresh.push_back(m);
  }
  link(n.prev, after);
  refresh(n.prev);
  refresh(n.next);
  for (int m : fresh) refresh(m);
}

}  // namespace cdp::adaptive
