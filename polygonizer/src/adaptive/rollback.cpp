// rollback: a region where the tracker has gone wrong is undone locally and meshed again.
//
// Two triggers (tracker.cpp, step):
//  - a placement refused because it lands on finished mesh (over_finished_mesh) while the
//    point cannot expand: the front lies over finished mesh there. Left alone, such a front
//    runs on over the finished surface (the MPU stalls of bunny 3, horse 1-2 and Igea 2 all
//    began so, thousands of steps before the error: over-mesh refusals by the thousand, the
//    mesh's area up to twice the surface's, hundreds of 4-point fronts split off and waiting).
//    The hole is taken around that point alone;
//  - a front that cannot advance even at a quarter of min_edge, instead of ending the run with
//    that error: the hole is taken around all the stuck front's points.
// The triangles with a vertex within R of those points are removed (R: kRollbackRadius times
// the largest target edge length there, doubling at each further rollback at the same place);
// every front touching them joins the hole, whose boundary is traced into new fronts and
// meshed as usual at its normal edge length. The rollbacks per place and in all are bounded;
// past the bounds the old behaviour stands (the refusal, or the error).
//
// The boundary of the hole: a front edge a -> b stays when the triangle owning it (the one with
// the edge b -> a) stays (a bridge edge, with no triangle on either side, goes when one of its
// ends is in the hole's middle); a removed triangle's edge x -> y becomes a front edge when the
// triangle across it (with y -> x) stays. The edges are chained into loops; where the chain
// reaches a vertex with more than one way on, it follows the old front's link when there is
// one, and otherwise that vertex's triangles join the hole and it is traced again. So do the
// ends of a hole edge far shorter than their target (left by the retries at half length), and
// remaining triangles cut off from the rest of the component (an island inside the hole, which
// would otherwise get a front of its own and be capped into a separate closed piece).
// Vertices left without a triangle leave the vertex hash and are dropped by compact().
#include "tracker.h"

#include <algorithm>
#include <array>
#include <set>
#include <tuple>

namespace cdp::adaptive {

namespace {
// R is this many times the stuck front's largest target edge length at the first rollback.
constexpr double kRollbackRadius = 3;
// Rollbacks at one place (R doubling), and in one run.
constexpr int kRollbacksPerPlace = 3;
constexpr std::size_t kRollbacksInAll = 32;
// Attempts whose hole could not be traced, in one run. Each costs up to kGrowSteps passes over
// its hole, and a front over finished mesh asks again at nearly every step: on a shell thinner
// than min_edge (outside the promise) 255 failed attempts took 55 of a 57-second run before the
// self-intersection check named the place.
constexpr std::size_t kFailedRollbacksInAll = 16;
// Vertices whose triangles are added to the hole while tracing its boundary, at most.
constexpr int kGrowSteps = 256;
// A hole edge shorter than this share of its ends' target edge length is grown over.
constexpr double kShortEdge = 0.4;

struct BoundaryEdge {
  int from, to;
  int from_node, to_node;  // the old front's nodes for an edge kept from a front, else -1
};

// Buckets of items by key (start[key] .. start[key + 1]), in the order the pairs come.
std::array<std::vector<int>, 2> buckets(std::size_t n, const std::vector<std::pair<int, int>>& pairs) {
  std::vector<int> start(n + 1, 0), items(pairs.size());
  for (const auto& [key, item] : pairs) ++start[key + 1];
  for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (const auto& [key, item] : pairs) items[fill[key]++] = item;
  return {std::move(start), std::move(items)};
}

// The hole of one rollback, grown from the vertices `in_s` (their triangles go) until its
// boundary traces into loops (see the top of this file). Reads the tracker's state; changes nothing.
class Hole {
 public:
  // The component's triangles are those from `t0`, its vertices those from `first_vertex`; `f`
  // is the stuck front.
  Hole(const Mesh& mesh, const FrontSet& fs, const std::vector<double>& target, std::size_t first_vertex,
       std::size_t t0, std::vector<char> in_s, int f);
  // Grows the hole until its boundary is traced; false where it cannot be.
  bool trace();

  const std::vector<int>& absorbed() const { return absorbed_; }    // the fronts that go, in id order
  const std::vector<char>& removed() const { return removed_; }     // by triangle - t0
  const std::vector<std::vector<int>>& loops() const { return loops_; }  // the new fronts' vertices
  // Whether vertex v had a triangle the hole removes.
  std::vector<char> had_removed_triangle() const;

 private:
  using Edges = std::vector<std::tuple<int, int, int>>;
  // The component's directed edges a -> b (a, b, triangle - t0), sorted within each a.
  std::pair<Edges::const_iterator, Edges::const_iterator> owners(int a, int b) const;
  bool remains(int a, int b) const;  // a triangle with a -> b stays
  void touch(int v);
  void set_in_s(int v) {
    in_s_[v] = 1;
    pending_.push_back(v);
  }
  void update_hole_edge(int t, int k);
  void take_pending();
  void gather_fronts();
  std::vector<BoundaryEdge> boundary();
  int trace_loops(const std::vector<BoundaryEdge>& boundary);
  bool grow_over_short_edges();
  bool grow_over_islands();

  const Mesh& mesh_;
  const FrontSet& fs_;
  const std::vector<double>& target_;
  const std::size_t first_vertex_, t0_, nt_, nv_;
  std::vector<char> in_s_;
  std::vector<int> edge_start_;
  Edges edges_;
  // Incidence, built once: the front nodes at each vertex and on each front, in increasing id order.
  std::array<std::vector<int>, 2> vnode_, fnode_;
  // The hole only grows (in_s is only ever set), so the removed triangles, the touched vertices
  // and the absorbed fronts are kept from one growing step to the next and extended by the
  // vertices added since: each step costs the hole's size and its fronts' lengths, not the
  // component's (a rollback that grew 256 times over a large component took most of a run).
  std::vector<char> removed_, touched_;
  // The removed triangles' edges (triangle, corner) whose opposite edge has a triangle that stays:
  // the hole's side of its boundary, ordered by (triangle, corner) as the full scan listed them.
  std::set<std::pair<int, int>> hole_edges_;
  std::set<int> fronts_;
  std::vector<int> front_nodes_, new_front_nodes_;  // the absorbed fronts' nodes in id order
  std::vector<int> pending_;  // in_s vertices not yet taken into removed and touched
  std::vector<int> edge_from_node_;  // set for front_nodes at each step
  std::vector<int> absorbed_;
  std::vector<std::vector<int>> loops_;
};

Hole::Hole(const Mesh& mesh, const FrontSet& fs, const std::vector<double>& target, std::size_t first_vertex,
           std::size_t t0, std::vector<char> in_s, int f)
    : mesh_(mesh), fs_(fs), target_(target), first_vertex_(first_vertex), t0_(t0), nt_(mesh.triangles.size()),
      nv_(mesh.positions.size()), in_s_(std::move(in_s)), removed_(nt_ - t0_, 0), touched_(nv_, 0), fronts_{f},
      edge_from_node_(fs.nodes.size(), -1) {
  // The component's triangles and their directed edges (a, b, triangle), sorted: bucketed by a
  // (edge_start[a] .. edge_start[a + 1]), then each vertex's few edges sorted, rather than one
  // sort of them all at each rollback. A vertex's bucket also lists its triangles.
  std::vector<std::pair<int, int>> pairs;  // (corner's vertex, corner 3 t + k)
  pairs.reserve(3 * (nt_ - t0_));
  for (std::size_t t = t0_; t < nt_; ++t)
    for (int k = 0; k < 3; ++k) pairs.emplace_back(mesh_.triangles[t][k], static_cast<int>(3 * (t - t0_)) + k);
  std::array<std::vector<int>, 2> corners = buckets(nv_, pairs);
  edges_.resize(pairs.size());
  for (std::size_t i = 0; i < edges_.size(); ++i) {
    const int t = corners[1][i] / 3, k = corners[1][i] % 3;
    const auto& tri = mesh_.triangles[t0_ + t];
    edges_[i] = {tri[k], tri[(k + 1) % 3], t};
  }
  edge_start_ = std::move(corners[0]);
  for (std::size_t v = 0; v < nv_; ++v)
    std::sort(edges_.begin() + edge_start_[v], edges_.begin() + edge_start_[v + 1]);
  pairs.clear();
  for (std::size_t n = 0; n < fs_.nodes.size(); ++n)
    if (fs_.nodes[n].front >= 0) pairs.emplace_back(fs_.nodes[n].vertex, static_cast<int>(n));
  vnode_ = buckets(nv_, pairs);
  for (auto& [key, item] : pairs) key = fs_.nodes[item].front;
  fnode_ = buckets(fs_.fronts.size(), pairs);
  new_front_nodes_.assign(fnode_[1].begin() + fnode_[0][f], fnode_[1].begin() + fnode_[0][f + 1]);
  for (std::size_t v = 0; v < nv_; ++v)
    if (in_s_[v]) pending_.push_back(static_cast<int>(v));
}

std::pair<Hole::Edges::const_iterator, Hole::Edges::const_iterator> Hole::owners(int a, int b) const {
  const auto end = edges_.begin() + edge_start_[a + 1];
  const auto lo = std::lower_bound(edges_.begin() + edge_start_[a], end, std::tuple<int, int, int>(a, b, -1));
  auto hi = lo;
  while (hi != end && std::get<1>(*hi) == b) ++hi;
  return {lo, hi};
}

bool Hole::remains(int a, int b) const {
  const auto [lo, hi] = owners(a, b);
  for (auto it = lo; it != hi; ++it)
    if (!removed_[std::get<2>(*it)]) return true;
  return false;
}

void Hole::touch(int v) {
  if (touched_[v]) return;
  touched_[v] = 1;
  // Every front with a point on a touched vertex joins the hole.
  for (int i = vnode_[0][v]; i < vnode_[0][v + 1]; ++i) {
    const int g = fs_.nodes[vnode_[1][i]].front;
    if (fronts_.insert(g).second)
      new_front_nodes_.insert(new_front_nodes_.end(), fnode_[1].begin() + fnode_[0][g], fnode_[1].begin() + fnode_[0][g + 1]);
  }
}

// The hole edge of removed triangle t at corner k, kept in hole_edges while the opposite edge
// has a triangle that stays.
void Hole::update_hole_edge(int t, int k) {
  const auto& tri = mesh_.triangles[t0_ + t];
  if (remains(tri[(k + 1) % 3], tri[k]))
    hole_edges_.emplace(t, k);
  else
    hole_edges_.erase({t, k});
}

// The pending vertices' triangles join the hole; only the new triangles' own edges and the
// removed edges opposite them change status.
void Hole::take_pending() {
  std::vector<int> newly_removed;
  for (const int v : pending_) {
    touch(v);
    for (int i = edge_start_[v]; i < edge_start_[v + 1]; ++i) {
      const int t = std::get<2>(edges_[i]);
      if (removed_[t]) continue;
      removed_[t] = 1;
      newly_removed.push_back(t);
      for (const int w : mesh_.triangles[t0_ + t]) touch(w);
    }
  }
  pending_.clear();
  for (const int t : newly_removed) {
    const auto& tri = mesh_.triangles[t0_ + t];
    for (int k = 0; k < 3; ++k) {
      update_hole_edge(t, k);
      const auto [lo, hi] = owners(tri[(k + 1) % 3], tri[k]);
      for (auto it = lo; it != hi; ++it) {
        const int u = std::get<2>(*it);
        if (!removed_[u]) continue;
        const auto& tu = mesh_.triangles[t0_ + u];
        for (int j = 0; j < 3; ++j)
          if (tu[j] == tri[(k + 1) % 3] && tu[(j + 1) % 3] == tri[k]) update_hole_edge(u, j);
      }
    }
  }
}

void Hole::gather_fronts() {
  absorbed_.assign(fronts_.begin(), fronts_.end());
  for (const int n : front_nodes_) edge_from_node_[n] = -1;
  if (new_front_nodes_.empty()) return;
  std::sort(new_front_nodes_.begin(), new_front_nodes_.end());
  const std::size_t old_size = front_nodes_.size();
  front_nodes_.insert(front_nodes_.end(), new_front_nodes_.begin(), new_front_nodes_.end());
  std::inplace_merge(front_nodes_.begin(), front_nodes_.begin() + old_size, front_nodes_.end());
  new_front_nodes_.clear();
}

// The hole's boundary: the absorbed fronts' edges that stay, then the hole edges.
std::vector<BoundaryEdge> Hole::boundary() {
  std::vector<BoundaryEdge> boundary;
  for (const int n : front_nodes_) {
    const FrontNode& fn = fs_.nodes[n];
    const int a = fn.vertex, b = fs_.nodes[fn.next].vertex;
    // A front edge stays when the triangle owning it (edge b -> a) stays; one with no triangle
    // on either side (a bridge of a split or a merge) goes when one of its ends is in the
    // hole's middle, and stays otherwise.
    const auto [lo, hi] = owners(b, a);
    if (lo == hi ? in_s_[a] || in_s_[b] : !remains(b, a)) continue;
    edge_from_node_[n] = static_cast<int>(boundary.size());
    boundary.push_back({a, b, n, fn.next});
  }
  for (const auto& [t, k] : hole_edges_) {
    const auto& tri = mesh_.triangles[t0_ + t];
    boundary.push_back({tri[k], tri[(k + 1) % 3], -1, -1});
  }
  return boundary;
}

// Chains the boundary into loops; where the chain reaches a vertex with more than one way on
// and no old front link to follow, returns that vertex (-1 when every edge is in a loop).
int Hole::trace_loops(const std::vector<BoundaryEdge>& boundary) {
  // Out-edges by vertex.
  std::vector<std::pair<int, int>> out;  // (from vertex, edge index)
  out.reserve(boundary.size());
  for (std::size_t e = 0; e < boundary.size(); ++e) out.emplace_back(boundary[e].from, static_cast<int>(e));
  std::sort(out.begin(), out.end());
  const auto out_range = [&](int v) {
    const auto lo = std::lower_bound(out.begin(), out.end(), std::pair(v, -1));
    auto hi = lo;
    while (hi != out.end() && hi->first == v) ++hi;
    return std::pair(lo, hi);
  };
  std::vector<char> used(boundary.size(), 0);
  loops_.clear();
  for (std::size_t s = 0; s < boundary.size(); ++s) {
    if (used[s]) continue;
    std::vector<int> loop;
    int e = static_cast<int>(s);
    for (;;) {
      used[e] = 1;
      loop.push_back(boundary[e].from);
      const BoundaryEdge& be = boundary[e];
      int next = -1;
      if (be.to_node >= 0) {
        const int k = edge_from_node_[be.to_node];
        if (k >= 0 && (!used[k] || k == static_cast<int>(s))) next = k;
      }
      if (next < 0) {
        const auto [lo, hi] = out_range(be.to);
        if (hi - lo == 1 && (!used[lo->second] || lo->second == static_cast<int>(s))) next = lo->second;
      }
      if (next < 0) return be.to;
      if (next == static_cast<int>(s)) break;
      e = next;
      if (loop.size() > boundary.size()) return be.to;
    }
    loops_.push_back(std::move(loop));
  }
  return -1;
}

// The hole's edges should be the older, well-sized ones: an edge far shorter than its ends'
// target (left by the retries at half length) takes its ends' triangles into the hole too.
bool Hole::grow_over_short_edges() {
  bool grew = false;
  for (const std::vector<int>& loop : loops_)
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const int a = loop[i], b = loop[(i + 1) % loop.size()];
      const double l = (mesh_.positions[a] - mesh_.positions[b]).norm();
      if (l >= kShortEdge * std::min(target_[a], target_[b])) continue;
      for (const int v : {a, b})
        if (static_cast<std::size_t>(v) >= first_vertex_ && !in_s_[v]) set_in_s(v), grew = true;
    }
  return grew;
}

// Remaining triangles cut off from the rest of the component by the hole (an island inside it)
// would be given a front of their own and capped from below: they join the hole. The component
// is the remaining triangles' largest edge-connected part.
bool Hole::grow_over_islands() {
  bool grew = false;
  std::vector<int> parent(nt_ - t0_);
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = static_cast<int>(i);
  const auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& [a, b, t] : edges_) {
    if (removed_[t] || a > b) continue;
    const auto [lo, hi] = owners(b, a);
    for (auto it = lo; it != hi; ++it)
      if (!removed_[std::get<2>(*it)]) parent[find(t)] = find(std::get<2>(*it));
  }
  std::vector<int> count(parent.size(), 0);
  int biggest = -1;
  for (std::size_t t = 0; t < parent.size(); ++t)
    if (!removed_[t]) {
      const int r = find(static_cast<int>(t));
      if (++count[r] > (biggest < 0 ? 0 : count[biggest]) || (count[r] == count[biggest] && r < biggest)) biggest = r;
    }
  for (std::size_t t = 0; t < parent.size(); ++t)
    if (!removed_[t] && find(static_cast<int>(t)) != biggest)
      for (const int v : mesh_.triangles[t0_ + t])
        if (!in_s_[v]) set_in_s(v), grew = true;
  return grew;
}

bool Hole::trace() {
  for (int grow = 0; grow <= kGrowSteps; ++grow) {
    take_pending();
    gather_fronts();
    const int grow_at = trace_loops(boundary());
    if (grow_at < 0) {
      if (!grow_over_short_edges() && !grow_over_islands()) return true;
      if (grow == kGrowSteps) return true;
      continue;
    }
    if (static_cast<std::size_t>(grow_at) < first_vertex_ || in_s_[grow_at]) return false;
    set_in_s(grow_at);
  }
  return false;
}

std::vector<char> Hole::had_removed_triangle() const {
  std::vector<char> had(nv_, 0);
  for (const auto& [a, b, t] : edges_)
    if (removed_[t]) had[a] = 1;
  return had;
}

}  // namespace

bool Tracker::rollback(int f, int node, bool at_node) {
  if (!s_.rollback || rollbacks_ >= kRollbacksInAll || failed_rollbacks_ >= kFailedRollbacksInAll) return false;
  dead_.resize(mesh_.positions.size(), 0);

  // The stuck front's vertices, its place and its largest target.
  std::vector<int> stuck;
  double longest_target = 0;
  Vec3 center = Vec3::Zero();
  {
    int x = node;
    do {
      const int v = fs_.nodes[x].vertex;
      stuck.push_back(v);
      longest_target = std::max(longest_target, target_[v]);
      center += mesh_.positions[v];
      x = fs_.nodes[x].next;
    } while (x != node && !at_node);
    center /= static_cast<double>(stuck.size());
  }
  const double r0 = kRollbackRadius * std::max(longest_target, s_.sizing.min_edge);
  int place = -1;
  for (std::size_t i = 0; i < rollback_places_.size(); ++i)
    if ((rollback_places_[i].first - center).norm() < 4 * r0) {
      place = static_cast<int>(i);
      break;
    }
  const int times = place >= 0 ? rollback_places_[place].second : 0;
  if (times >= kRollbacksPerPlace) return false;
  const double radius = r0 * std::ldexp(1.0, times);

  Hole hole(mesh_, fs_, target_, first_vertex_, first_triangle_, rollback_region(stuck, radius), f);
  if (!hole.trace()) {
    ++failed_rollbacks_;
    return false;
  }
  cut_hole(hole.absorbed(), hole.removed(), hole.had_removed_triangle(), hole.loops());
  if (place >= 0) {
    ++rollback_places_[place].second;
  } else {
    rollback_places_.emplace_back(center, 1);
    rollback_place_targets_.push_back(longest_target);
  }
  ++rollbacks_;
  // Settings::anticipate: the hole is meshed again with edges at most half as long as the stuck
  // front's longest target (a quarter at the second rollback there, ...): where the fronts went
  // wrong, the sizing asked for edges too long for how fast the surface turns there.
  if (!s_.anticipate) return true;
  // Halved from the place's first stuck front's longest target (later ones are already capped
  // by the zones made here before).
  const std::size_t at = place >= 0 ? static_cast<std::size_t>(place) : rollback_places_.size() - 1;
  const double finer =
      std::max(s_.sizing.min_edge, rollback_place_targets_[at] * std::ldexp(1.0, -(times + 1)));
  const FinerZone zone{center, radius + longest_target, finer};
  finer_zones_.push_back(zone);
  vertex_hash().for_each_near(zone.center, zone.radius, [&](int w) {
    if (static_cast<std::size_t>(w) >= first_vertex_ && !dead_[w]) target_[w] = zone_capped(mesh_.positions[w], target_[w]);
  });
  return true;
}

std::vector<char> Tracker::rollback_region(const std::vector<int>& stuck, double radius) const {
  // The vertices whose triangles go: within radius of a stuck point, on the same side, of the
  // component being meshed (earlier components are finished and indexed by the seeding).
  std::vector<char> in_s(mesh_.positions.size(), 0);
  for (const int u : stuck) {
    const Vec3& pu = mesh_.positions[u];
    in_s[u] = 1;
    vertex_hash().for_each_near(pu, radius, [&](int w) {
      if (static_cast<std::size_t>(w) >= first_vertex_ && (mesh_.positions[w] - pu).norm() < radius &&
          same_side(mesh_.normals[u], w))
        in_s[w] = 1;
    });
  }
  return in_s;
}

void Tracker::cut_hole(const std::vector<int>& absorbed, const std::vector<char>& removed, const std::vector<char>& had,
                       const std::vector<std::vector<int>>& loops) {
  // The absorbed fronts go, then the triangles, then the vertices left without one.
  for (const int g : absorbed) {
    Front& fr = fs_.fronts[g];
    fr.alive = false;
    fr.release_heap();
  }
  for (std::size_t n = 0; n < fs_.nodes.size(); ++n) {
    const FrontNode& fn = fs_.nodes[n];
    if (fn.front >= 0 && std::binary_search(absorbed.begin(), absorbed.end(), fn.front)) remove_node(static_cast<int>(n));
  }
  for (const int g : absorbed) fs_.fronts[g].size = 0;
  const std::size_t nv = mesh_.positions.size(), t0 = first_triangle_, nt = mesh_.triangles.size();
  std::vector<int> uses(nv, 0);
  std::size_t kept = t0;
  for (std::size_t t = t0; t < nt; ++t) {
    const auto tri = mesh_.triangles[t];
    if (removed[t - t0]) {
      const Vec3& pa = mesh_.positions[tri[0]];
      area_ -= 0.5 * (mesh_.positions[tri[1]] - pa).cross(mesh_.positions[tri[2]] - pa).norm();
      continue;
    }
    for (const int v : tri) ++uses[v];
    mesh_.triangles[kept++] = tri;
  }
  mesh_.triangles.resize(kept);
  // Vertices of removed triangles that no remaining triangle uses.
  for (std::size_t v = first_vertex_; v < nv; ++v)
    if (had[v] && uses[v] == 0 && !dead_[v]) {
      dead_[v] = 1;
      vertex_hash().remove(static_cast<int>(v), mesh_.positions[v]);
    }
  // The hole's loops as new fronts (two-point loops enclose nothing).
  for (const std::vector<int>& loop : loops) {
    if (loop.size() < 3) continue;
    const int g = fs_.new_front();
    std::vector<int> nodes;
    nodes.reserve(loop.size());
    for (const int v : loop) nodes.push_back(insert_node(v, g));
    for (std::size_t i = 0; i < nodes.size(); ++i) link(nodes[i], nodes[(i + 1) % nodes.size()]);
    for (const int n : nodes) refresh(n);
    stack_.push_back(g);
  }
}

void Tracker::compact() {
  if (std::find(dead_.begin(), dead_.end(), 1) == dead_.end()) return;
  const std::size_t nv = mesh_.positions.size();
  dead_.resize(nv, 0);
  std::vector<int> remap(nv, -1);
  int m = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    if (dead_[v]) continue;
    remap[v] = m;
    mesh_.positions[m] = mesh_.positions[v];
    mesh_.normals[m] = mesh_.normals[v];
    target_[m] = target_[v];
    mac_[m] = mac_[v];
    shape_index_[m] = shape_index_[v];
    front_refs_[m] = front_refs_[v];
    ++m;
  }
  mesh_.positions.resize(m);
  mesh_.normals.resize(m);
  target_.resize(m);
  mac_.resize(m);
  shape_index_.resize(m);
  front_refs_.resize(m);
  for (auto& tri : mesh_.triangles)
    for (int& v : tri) v = remap[v];
  dead_.assign(m, 0);
  vertex_hash_ = SpatialHash(s_.hash_cell, Crowding::split);
  vertex_hash_.set_cancel(s_.cancel);
  unhashed_ = static_cast<std::size_t>(m);  // hashed when first asked for (vertex_hash)
}

}  // namespace cdp::adaptive
