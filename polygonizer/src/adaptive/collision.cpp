// The overlap tests of paper section 6 ("Self-Intersection" and "Front-Collision" in Figure 6).
// Both look for front points threatened by the expansion of a candidate point: visible from it,
// on the same side of the surface, closer than the heuristic edge length. Whether the point hit
// lies on the candidate's own front (split) or on another front (merge) is the caller's concern.
// Front points are found through a spatial hash, so a test costs a few cells, never a pass over
// all fronts.
#include "tracker.h"

#include <algorithm>
#include <limits>

namespace cdp::adaptive {

namespace {

// Keeps bridges from running almost along a front edge.
constexpr double kSectorMargin = 0.05;

// Distance between segments p0-p1 and q0-q1 (clamped closest points; Ericson, Real-Time
// Collision Detection, 5.1.9).
double segment_distance(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a <= 0 && e <= 0) return r.norm();
  if (a <= 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) t = 0, s = std::clamp(-c / a, 0.0, 1.0);
      else if (t > 1) t = 1, s = std::clamp((b - c) / a, 0.0, 1.0);
    }
  }
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

}  // namespace

std::pair<Vec3, Vec3> Tracker::front_edge_search_box(const Vec3& u, const Vec3& w, double longest) const {
  // Front edges near the segment are found from their start nodes, which lie within half the
  // segment plus the longest front edge of its midpoint.
  const Vec3 mid = 0.5 * (u + w);
  const double radius = 0.5 * (w - u).norm() + longest;
  return {mid.array() - radius, mid.array() + radius};
}

int Tracker::crossed_front_edge(int vu, int vw, const Vec3& w_point, int frame_vertex,
                                const SpatialHash::Gathered* near) const {
  // In the tangent plane at frame_vertex: does segment u-w cross a front edge that shares no
  // end point with it? (front_edge_search_box says where the candidates are.)
  const Vec3& N = mesh_.normals[frame_vertex];
  Vec3 e0 = N.unitOrthogonal();
  const Vec3 e1 = N.cross(e0);
  const auto flat = [&](const Vec3& x) { return Eigen::Vector2d(x.dot(e0), x.dot(e1)); };
  const Vec3& u_point = mesh_.positions[vu];
  const Eigen::Vector2d u = flat(u_point), w = flat(w_point);
  const auto orient = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
    const Eigen::Vector2d ab = b - a, ac = c - a;
    return ab.x() * ac.y() - ab.y() * ac.x();
  };
  const auto [lo, hi] = front_edge_search_box(u_point, w_point, longest_front_edge());
  const double uw = (w_point - u_point).norm();
  // The first front edge, in the hash's order, that passes every test. The tests are cheapest
  // first (most candidates do not cross the segment in the plane), which changes no answer:
  // they are a conjunction.
  int hit = -1;
  const auto crosses = [&](int r) {
    const int vr = fs_.nodes[r].vertex, vs = fs_.nodes[fs_.nodes[r].next].vertex;
    if (vr == vu || vr == vw || vs == vu || vs == vw) return false;
    const Vec3& ar = mesh_.positions[vr];
    const Vec3& bs = mesh_.positions[vs];
    const Eigen::Vector2d a = flat(ar), b = flat(bs);
    const double o1 = orient(u, w, a), o2 = orient(u, w, b);
    if (!((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0))) return false;
    const double o3 = orient(a, b, u), o4 = orient(a, b, w);
    if (!((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0))) return false;
    if (!same_side(N, vr) || !same_side(N, vs)) return false;
    // Only edges that pass near the segment in space count: on a thin tube or a narrow gap the
    // far side of the surface also projects across the segment in the tangent plane.
    const double reach = 0.25 * (uw + (bs - ar).norm());
    if (segment_distance(u_point, w_point, ar, bs) > reach) return false;
    hit = r;
    return true;
  };
  // A crossing edge r-s passes within `reach` of the segment, so its start r lies within
  // 1.25 |rs| + 0.25 |uw| of it: a cell farther than that from the segment's box, with its
  // longest edge for |rs| (SpatialHash::widen_reach), holds none; the margin covers rounding.
  const Vec3 seg_lo = u_point.cwiseMin(w_point), seg_hi = u_point.cwiseMax(w_point);
  const auto far = [&](const Vec3& cell_lo, const Vec3& cell_hi, double longest_there) {
    const Vec3 gap = (cell_lo - seg_hi).cwiseMax(seg_lo - cell_hi).cwiseMax(0.0);
    const double bound = 1.25 * longest_there + 0.25 * uw;
    return gap.squaredNorm() > bound * bound * (1 + 1e-9);
  };
  if (near) front_hash_.any_in(*near, lo, hi, far, crosses);
  else front_hash_.any_in(lo, hi, far, crosses);
  return hit;
}

bool Tracker::leaves_patch(int u, int w) const {
  const auto on_loop = [&](int v) {
    return static_cast<std::size_t>(v) < loop_vertex_.size() && loop_vertex_[static_cast<std::size_t>(v)];
  };
  if (!patch_test_ || !on_loop(u) || !on_loop(w) || patch_test_(mesh_.positions[u], mesh_.positions[w])) return false;
  ++patch_refusals_;
  return true;
}

bool Tracker::can_bridge(int node, int q) const {
  const FrontNode& n = fs_.nodes[node];
  const FrontNode& m = fs_.nodes[q];
  if (m.front < 0) return false;
  // The point itself, its neighbours and (as the paper requires with varying edge lengths) the
  // neighbours' neighbours are never in the way, and the same the other way round; compare
  // vertices, since after a split or merge a vertex occurs at two nodes. The other way round
  // matters there: the point's vertex can also sit at a node near q on q's front (fogleman/sdf's
  // knurling example meshed across its creases bridged to two nodes before its own vertex there,
  // cutting off a triangle of the other front that both fronts then made, again and again).
  const auto within_two = [&](const FrontNode& at, int v) {
    const FrontNode& before = fs_.nodes[at.prev];
    const FrontNode& after = fs_.nodes[at.next];
    return v == at.vertex || v == before.vertex || v == after.vertex || v == fs_.nodes[before.prev].vertex ||
           v == fs_.nodes[after.next].vertex;
  };
  const int vm = m.vertex;
  if (within_two(n, vm) || within_two(m, n.vertex)) return false;
  // A bridge is an edge like any placed one: it may not join points whose normals turned more
  // than a placement may (kMaxTurnCosine), which also keeps it off a sheet facing the other way.
  // Chmutov's sextic at factors 1 and 3 stalled behind bridges of 0.5 across its saddles, where
  // the normal turned 74-82 degrees and the edges around were 0.01-0.05 long; a front edge that
  // long is never split again.
  if (mesh_.normals[n.vertex].dot(mesh_.normals[vm]) < kMaxTurnCosine) return false;
  const Vec3& p = mesh_.positions[n.vertex];
  const Vec3& x = mesh_.positions[vm];
  // Each point must see the other inside its unmeshed sector, else the bridge would cross
  // triangles already made.
  if (!in_sector(node, x, kSectorMargin) || !in_sector(q, p, kSectorMargin)) return false;
  if (crossed_front_edge(n.vertex, vm, x, n.vertex) >= 0) return false;
  // Last, as it evaluates the field: between two loop vertices of a piece's patches, a bridge
  // may cut across what the piece does not cover (two loops passing close by each other).
  return !leaves_patch(n.vertex, vm);
}

double Tracker::bridge_quality(int node, int q) const {
  // The bridge cuts the front angles at both ends in two; the smallest part becomes the
  // smallest angle of a triangle soon after.
  const double t = sector_position(node, mesh_.positions[fs_.nodes[q].vertex]);
  const double u = sector_position(q, mesh_.positions[fs_.nodes[node].vertex]);
  return std::min({t, fs_.nodes[node].angle - t, u, fs_.nodes[q].angle - u});
}

int Tracker::find_collision(int node, double delta) const {
  return find_bridge(node, s_.collision_factor * delta);
}

int Tracker::find_bridge(int node, double radius) const {
  const Vec3& p = mesh_.positions[fs_.nodes[node].vertex];
  // Among the front points within radius, the nearest one whose bridge leaves no angle below
  // kGoodBridge; failing that, the one whose bridge leaves the largest smallest angle.
  constexpr double kGoodBridge = 0.5;
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity(), best_quality = -1;
  front_hash_.for_each_near(p, radius, [&](int q) {
    const double d = (mesh_.positions[fs_.nodes[q].vertex] - p).norm();
    if (d >= radius || !can_bridge(node, q)) return;
    const double quality = std::min(bridge_quality(node, q), kGoodBridge);
    const bool better = quality > best_quality ||
                        (quality == best_quality && (d < best_d || (d == best_d && q < best)));
    if (!better) return;
    best = q;
    best_d = d;
    best_quality = quality;
  });
  return best;
}

int Tracker::bridge_around(int node, int r) const {
  const Vec3& p = mesh_.positions[fs_.nodes[node].vertex];
  const double far = std::max((mesh_.positions[fs_.nodes[r].vertex] - p).norm(),
                              (mesh_.positions[fs_.nodes[fs_.nodes[r].next].vertex] - p).norm());
  return find_bridge(node, 1.05 * far);
}

Tracker::Ear Tracker::ear(int node) const {
  // Closing the angle adds the edge prev-next; the paper tests the triangle it closes because
  // with varying edge lengths a front point can sit inside it.
  const FrontNode& n = fs_.nodes[node];
  Ear e;
  e.node = node;
  e.va = fs_.nodes[n.prev].vertex;
  e.vb = fs_.nodes[n.next].vertex;
  const Vec3& p = mesh_.positions[n.vertex];
  const Vec3& a = mesh_.positions[e.va];
  const Vec3& b = mesh_.positions[e.vb];
  e.radius = std::max((a - p).norm(), (b - p).norm());
  // Inside test in the tangent plane of p: x is inside when it lies on p's side of the line
  // a-b (the sector test covers the two other sides).
  e.inward = mesh_.normals[n.vertex].cross(b - a);  // into the triangle when it is (a, p, b)
  e.side_p = e.inward.dot(p - a);
  return e;
}

bool Tracker::in_ear(const Ear& e, int vq) const {
  const int v = fs_.nodes[e.node].vertex;
  if (vq == v || vq == e.va || vq == e.vb) return false;
  const Vec3& x = mesh_.positions[vq];
  if ((x - mesh_.positions[v]).norm() >= e.radius || !same_side(mesh_.normals[v], vq)) return false;
  // On p's side of line a-b, with a small tolerance so points right on the new edge count.
  if (e.inward.dot(x - mesh_.positions[e.va]) * e.side_p < -0.05 * e.side_p * e.side_p) return false;
  return in_sector(e.node, x, 0);
}

int Tracker::find_closing_obstacle(int node) const {
  const Ear e = ear(node);
  const Vec3& p = mesh_.positions[fs_.nodes[node].vertex];
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  front_hash_.for_each_near(p, e.radius, [&](int q) {
    const int vq = fs_.nodes[q].vertex;
    const double d = (mesh_.positions[vq] - p).norm();
    if (d > best_d || (d == best_d && q > best) || !in_ear(e, vq)) return;
    best = q;
    best_d = d;
  });
  return best;
}

bool Tracker::ear_is_clear(int node) const {
  // find_closing_obstacle's test on the front's own points: in a small stuck front the points
  // in the ear are the front itself, folded flat (a sliver loop along a crease).
  const Ear e = ear(node);
  for (int q = fs_.nodes[fs_.nodes[node].next].next; q != fs_.nodes[node].prev; q = fs_.nodes[q].next)
    if (in_ear(e, fs_.nodes[q].vertex)) return false;
  return true;
}

}  // namespace cdp::adaptive
