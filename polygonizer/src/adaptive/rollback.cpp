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
}  // namespace

bool Tracker::rollback(int f, int node, bool at_node) {
  if (!s_.rollback || rollbacks_ >= kRollbacksInAll || failed_rollbacks_ >= kFailedRollbacksInAll) return false;
  const std::size_t nv = mesh_.positions.size();
  dead_.resize(nv, 0);

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

  // The vertices whose triangles go: within radius of a stuck point, on the same side, of the
  // component being meshed (earlier components are finished and indexed by the seeding).
  std::vector<char> in_s(nv, 0);
  for (const int u : stuck) {
    const Vec3& pu = mesh_.positions[u];
    in_s[u] = 1;
    vertex_hash_.for_each_near(pu, radius, [&](int w) {
      if (static_cast<std::size_t>(w) >= first_vertex_ && (mesh_.positions[w] - pu).norm() < radius &&
          same_side(mesh_.normals[u], w))
        in_s[w] = 1;
    });
  }

  // Buckets of items by key (start[key] .. start[key + 1]), in the order the pairs come.
  const auto csr = [](std::size_t n, const std::vector<std::pair<int, int>>& pairs) {
    std::vector<int> start(n + 1, 0), items(pairs.size());
    for (const auto& [key, item] : pairs) ++start[key + 1];
    for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (const auto& [key, item] : pairs) items[fill[key]++] = item;
    return std::array<std::vector<int>, 2>{std::move(start), std::move(items)};
  };

  // The component's triangles and their directed edges (a, b, triangle), sorted: bucketed by a
  // (edge_start[a] .. edge_start[a + 1]), then each vertex's few edges sorted, rather than one
  // sort of them all at each rollback. A vertex's bucket also lists its triangles.
  const std::size_t t0 = first_triangle_, nt = mesh_.triangles.size();
  std::vector<std::pair<int, int>> pairs;  // (corner's vertex, corner 3 t + k)
  pairs.reserve(3 * (nt - t0));
  for (std::size_t t = t0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) pairs.emplace_back(mesh_.triangles[t][k], static_cast<int>(3 * (t - t0)) + k);
  const std::array<std::vector<int>, 2> corner_csr = csr(nv, pairs);
  const std::vector<int>& edge_start = corner_csr[0];
  std::vector<std::tuple<int, int, int>> edges(pairs.size());
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const int t = corner_csr[1][i] / 3, k = corner_csr[1][i] % 3;
    const auto& tri = mesh_.triangles[t0 + t];
    edges[i] = {tri[k], tri[(k + 1) % 3], t};
  }
  for (std::size_t v = 0; v < nv; ++v) std::sort(edges.begin() + edge_start[v], edges.begin() + edge_start[v + 1]);
  const auto owners = [&](int a, int b) {
    const auto end = edges.begin() + edge_start[a + 1];
    const auto lo = std::lower_bound(edges.begin() + edge_start[a], end, std::tuple<int, int, int>(a, b, -1));
    auto hi = lo;
    while (hi != end && std::get<1>(*hi) == b) ++hi;
    return std::pair(lo, hi);
  };

  // The hole only grows (in_s is only ever set), so the removed triangles, the touched vertices
  // and the absorbed fronts are kept from one growing step to the next and extended by the
  // vertices added since: each step costs the hole's size and its fronts' lengths, not the
  // component's (a rollback that grew 256 times over a large component took most of a run).
  // Incidence, built once: the front nodes at each vertex and on each front, in increasing id
  // order.
  pairs.clear();
  for (std::size_t n = 0; n < fs_.nodes.size(); ++n)
    if (fs_.nodes[n].front >= 0) pairs.emplace_back(fs_.nodes[n].vertex, static_cast<int>(n));
  const std::array<std::vector<int>, 2> vnode_csr = csr(nv, pairs);
  const std::vector<int>& vnode_start = vnode_csr[0];
  const std::vector<int>& vnode_items = vnode_csr[1];
  for (auto& [key, item] : pairs) key = fs_.nodes[item].front;
  const std::array<std::vector<int>, 2> fnode_csr = csr(fs_.fronts.size(), pairs);
  const std::vector<int>& fnode_start = fnode_csr[0];
  const std::vector<int>& fnode_items = fnode_csr[1];
  pairs = {};

  const auto remains = [&](const std::vector<char>& removed, int a, int b) {  // a triangle with a -> b stays
    const auto [lo, hi] = owners(a, b);
    for (auto it = lo; it != hi; ++it)
      if (!removed[std::get<2>(*it)]) return true;
    return false;
  };
  std::vector<char> removed(nt - t0, 0), touched(nv, 0);
  // The removed triangles' edges (triangle, corner) whose opposite edge has a triangle that stays:
  // the hole's side of its boundary, ordered by (triangle, corner) as the full scan listed them.
  std::set<std::pair<int, int>> hole_edges;
  std::set<int> fronts{f};
  std::vector<int> front_nodes, new_front_nodes;  // the absorbed fronts' nodes in id order
  const auto touch = [&](int v) {
    if (touched[v]) return;
    touched[v] = 1;
    // Every front with a point on a touched vertex joins the hole.
    for (int i = vnode_start[v]; i < vnode_start[v + 1]; ++i) {
      const int g = fs_.nodes[vnode_items[i]].front;
      if (fronts.insert(g).second)
        new_front_nodes.insert(new_front_nodes.end(), fnode_items.begin() + fnode_start[g],
                               fnode_items.begin() + fnode_start[g + 1]);
    }
  };
  new_front_nodes.assign(fnode_items.begin() + fnode_start[f], fnode_items.begin() + fnode_start[f + 1]);
  std::vector<int> pending;  // in_s vertices not yet taken into removed and touched
  for (std::size_t v = 0; v < nv; ++v)
    if (in_s[v]) pending.push_back(static_cast<int>(v));
  const auto set_in_s = [&](int v) {
    in_s[v] = 1;
    pending.push_back(v);
  };
  // The hole edge of removed triangle t at corner k, kept in hole_edges while the opposite edge
  // has a triangle that stays.
  const auto update_hole_edge = [&](int t, int k) {
    const auto& tri = mesh_.triangles[t0 + t];
    if (remains(removed, tri[(k + 1) % 3], tri[k]))
      hole_edges.emplace(t, k);
    else
      hole_edges.erase({t, k});
  };
  std::vector<int> edge_from_node(fs_.nodes.size(), -1);  // set for front_nodes at each step
  std::vector<int> absorbed, newly_removed;
  std::vector<std::vector<int>> loops;
  bool traced = false;
  for (int grow = 0; grow <= kGrowSteps && !traced; ++grow) {
    newly_removed.clear();
    for (const int v : pending) {
      touch(v);
      for (int i = edge_start[v]; i < edge_start[v + 1]; ++i) {
        const int t = std::get<2>(edges[i]);
        if (removed[t]) continue;
        removed[t] = 1;
        newly_removed.push_back(t);
        for (const int w : mesh_.triangles[t0 + t]) touch(w);
      }
    }
    pending.clear();
    // Only the new triangles' own edges and the removed edges opposite them change status.
    for (const int t : newly_removed) {
      const auto& tri = mesh_.triangles[t0 + t];
      for (int k = 0; k < 3; ++k) {
        update_hole_edge(t, k);
        const auto [lo, hi] = owners(tri[(k + 1) % 3], tri[k]);
        for (auto it = lo; it != hi; ++it) {
          const int u = std::get<2>(*it);
          if (!removed[u]) continue;
          const auto& tu = mesh_.triangles[t0 + u];
          for (int j = 0; j < 3; ++j)
            if (tu[j] == tri[(k + 1) % 3] && tu[(j + 1) % 3] == tri[k]) update_hole_edge(u, j);
        }
      }
    }
    absorbed.assign(fronts.begin(), fronts.end());
    for (const int n : front_nodes) edge_from_node[n] = -1;
    if (!new_front_nodes.empty()) {
      std::sort(new_front_nodes.begin(), new_front_nodes.end());
      const std::size_t old_size = front_nodes.size();
      front_nodes.insert(front_nodes.end(), new_front_nodes.begin(), new_front_nodes.end());
      std::inplace_merge(front_nodes.begin(), front_nodes.begin() + old_size, front_nodes.end());
      new_front_nodes.clear();
    }

    std::vector<BoundaryEdge> boundary;
    for (const int n : front_nodes) {
      const FrontNode& fn = fs_.nodes[n];
      const int a = fn.vertex, b = fs_.nodes[fn.next].vertex;
      // A front edge stays when the triangle owning it (edge b -> a) stays; one with no triangle
      // on either side (a bridge of a split or a merge) goes when one of its ends is in the
      // hole's middle, and stays otherwise.
      const auto [lo, hi] = owners(b, a);
      if (lo == hi ? in_s[a] || in_s[b] : !remains(removed, b, a)) continue;
      edge_from_node[n] = static_cast<int>(boundary.size());
      boundary.push_back({a, b, n, fn.next});
    }
    for (const auto& [t, k] : hole_edges) {
      const auto& tri = mesh_.triangles[t0 + t];
      boundary.push_back({tri[k], tri[(k + 1) % 3], -1, -1});
    }
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
    loops.clear();
    int grow_at = -1;
    for (std::size_t s = 0; s < boundary.size() && grow_at < 0; ++s) {
      if (used[s]) continue;
      std::vector<int> loop;
      int e = static_cast<int>(s);
      for (;;) {
        used[e] = 1;
        loop.push_back(boundary[e].from);
        const BoundaryEdge& be = boundary[e];
        int next = -1;
        if (be.to_node >= 0) {
          const int k = edge_from_node[be.to_node];
          if (k >= 0 && (!used[k] || k == static_cast<int>(s))) next = k;
        }
        if (next < 0) {
          const auto [lo, hi] = out_range(be.to);
          if (hi - lo == 1 && (!used[lo->second] || lo->second == static_cast<int>(s))) next = lo->second;
        }
        if (next < 0) {
          grow_at = be.to;
          break;
        }
        if (next == static_cast<int>(s)) break;
        e = next;
        if (loop.size() > boundary.size()) {
          grow_at = be.to;
          break;
        }
      }
      if (grow_at < 0) loops.push_back(std::move(loop));
    }
    if (grow_at < 0) {
      // The hole's edges should be the older, well-sized ones: an edge far shorter than its
      // ends' target (left by the retries at half length) takes its ends' triangles into the
      // hole too.
      bool grew = false;
      for (const std::vector<int>& loop : loops)
        for (std::size_t i = 0; i < loop.size(); ++i) {
          const int a = loop[i], b = loop[(i + 1) % loop.size()];
          const double l = (mesh_.positions[a] - mesh_.positions[b]).norm();
          if (l >= kShortEdge * std::min(target_[a], target_[b])) continue;
          for (const int v : {a, b})
            if (static_cast<std::size_t>(v) >= first_vertex_ && !in_s[v]) set_in_s(v), grew = true;
        }
      if (!grew) {
        // Remaining triangles cut off from the rest of the component by the hole (an island
        // inside it) would be given a front of their own and capped from below: they join the
        // hole. The component is the remaining triangles' largest edge-connected part.
        std::vector<int> parent(nt - t0);
        for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = static_cast<int>(i);
        const auto find = [&](int x) {
          while (parent[x] != x) x = parent[x] = parent[parent[x]];
          return x;
        };
        for (const auto& [a, b, t] : edges) {
          if (removed[t] || a > b) continue;
          const auto [lo, hi] = owners(b, a);
          for (auto it = lo; it != hi; ++it)
            if (!removed[std::get<2>(*it)]) parent[find(t)] = find(std::get<2>(*it));
        }
        std::vector<int> count(parent.size(), 0);
        int biggest = -1;
        for (std::size_t t = 0; t < parent.size(); ++t)
          if (!removed[t]) {
            const int r = find(static_cast<int>(t));
            if (++count[r] > (biggest < 0 ? 0 : count[biggest]) || (count[r] == count[biggest] && r < biggest)) biggest = r;
          }
        for (std::size_t t = 0; t < parent.size(); ++t)
          if (!removed[t] && find(static_cast<int>(t)) != biggest)
            for (const int v : mesh_.triangles[t0 + t])
              if (!in_s[v]) set_in_s(v), grew = true;
      }
      if (!grew || grow == kGrowSteps) {
        traced = true;
        break;
      }
      continue;
    }
    if (static_cast<std::size_t>(grow_at) < first_vertex_ || in_s[grow_at]) {
      ++failed_rollbacks_;
      return false;
    }
    set_in_s(grow_at);
  }
  if (!traced) {
    ++failed_rollbacks_;
    return false;
  }
  // Apply: the absorbed fronts go, then the triangles, then the vertices left without one.
  for (const int g : absorbed) {
    Front& fr = fs_.fronts[g];
    fr.alive = false;
    fr.heap = {};
  }
  for (std::size_t n = 0; n < fs_.nodes.size(); ++n) {
    const FrontNode& fn = fs_.nodes[n];
    if (fn.front >= 0 && std::binary_search(absorbed.begin(), absorbed.end(), fn.front)) remove_node(static_cast<int>(n));
  }
  for (const int g : absorbed) fs_.fronts[g].size = 0;
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
  // Vertices of removed triangles that no remaining triangle uses (recomputed from the edges).
  std::vector<char> had(nv, 0);
  for (const auto& [a, b, t] : edges)
    if (removed[t]) had[a] = 1;
  mesh_.triangles.resize(kept);
  for (std::size_t v = first_vertex_; v < nv; ++v)
    if (had[v] && uses[v] == 0 && !dead_[v]) {
      dead_[v] = 1;
      vertex_hash_.remove(static_cast<int>(v), mesh_.positions[v]);
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
  vertex_hash_.for_each_near(zone.center, zone.radius, [&](int w) {
    if (static_cast<std::size_t>(w) >= first_vertex_ && !dead_[w]) target_[w] = zone_capped(mesh_.positions[w], target_[w]);
  });
  return true;
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
  for (int v = 0; v < m; ++v) vertex_hash_.insert(v, mesh_.positions[v], vertex_position());
}

}  // namespace cdp::adaptive
