#include "short_edge_collapse.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <optional>
#include <tuple>

namespace cdp::marching {

namespace {

using Triangle = std::array<int, 3>;

// How far (in collapse lengths) a neighbouring vertex that blocks a short edge may be and still
// be merged to unblock it: the vertices a corner's root makes lie within a few hundredths of a
// cell of each other; ten collapse lengths reaches all of them and nothing a cell away.
constexpr double kUnblockLength = 10;

class Collapser {
 public:
  Collapser(Mesh& mesh, const std::vector<std::uint64_t>& keys, double min_length)
      : mesh_(mesh), keys_(keys), min_length_(min_length), star_(mesh.positions.size()),
        tri_alive_(mesh.triangles.size(), 1), locked_(mesh.positions.size(), 0) {
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int v : mesh.triangles[t]) star_[v].push_back(static_cast<int>(t));
    lock_open_boundary();
  }

  CollapseReport run() {
    CollapseReport report;
    // Each pass tries the short edges of the current mesh in one order; a collapse can make a
    // new short edge (or unblock one), so passes repeat until one changes nothing.
    for (bool changed = true; changed;) {
      changed = false;
      for (const auto& [length, key_a, key_b, a, b] : short_edges()) {
        if (!edge_alive(a, b) || (mesh_.positions[a] - mesh_.positions[b]).norm() >= min_length_) continue;
        std::optional<double> keep_b = quality_after_merge(a, b), keep_a = quality_after_merge(b, a);
        if (!keep_a && !keep_b && unblock(a, b)) {
          ++report.collapsed_edges;
          changed = true;
          if (!edge_alive(a, b)) continue;
          keep_b = quality_after_merge(a, b), keep_a = quality_after_merge(b, a);
        }
        if (!keep_a && !keep_b) continue;
        // The better shaped result; on a tie, the end with the smaller key stays.
        const bool remove_a = !keep_a || (keep_b && (*keep_b > *keep_a || (*keep_b == *keep_a && key_b < key_a)));
        remove_a ? merge(a, b) : merge(b, a);
        ++report.collapsed_edges;
        changed = true;
      }
    }
    report.dropped_components = drop_components_below_length();
    report.short_edges_left = short_edges().size();
    compact();
    return report;
  }

 private:
  // Vertices on an edge with one triangle (the mesh clipped at the box) or more than two stay.
  void lock_open_boundary() {
    std::vector<std::pair<int, int>> edges;
    for (const Triangle& t : mesh_.triangles)
      for (int q = 0; q < 3; ++q) edges.emplace_back(std::minmax(t[q], t[(q + 1) % 3]));
    std::sort(edges.begin(), edges.end());
    for (std::size_t i = 0; i < edges.size();) {
      std::size_t j = i;
      while (j < edges.size() && edges[j] == edges[i]) ++j;
      if (j - i != 2) locked_[edges[i].first] = locked_[edges[i].second] = 1;
      i = j;
    }
  }

  // Edges shorter than min_length, shortest first; ties (mirror-symmetric fields) by the keys.
  std::vector<std::tuple<double, std::uint64_t, std::uint64_t, int, int>> short_edges() const {
    std::vector<std::tuple<double, std::uint64_t, std::uint64_t, int, int>> out;
    for (std::size_t t = 0; t < mesh_.triangles.size(); ++t) {
      if (!tri_alive_[t]) continue;
      const Triangle& tri = mesh_.triangles[t];
      for (int q = 0; q < 3; ++q) {
        int a = tri[q], b = tri[(q + 1) % 3];
        if (keys_[a] > keys_[b]) std::swap(a, b);
        const double length = (mesh_.positions[a] - mesh_.positions[b]).norm();
        if (length < min_length_) out.emplace_back(length, keys_[a], keys_[b], a, b);
      }
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());  // each edge twice, from both sides
    return out;
  }

  bool edge_alive(int a, int b) const {
    for (int t : star_[a])
      if (tri_alive_[t] && contains(t, b)) return true;
    return false;
  }
  bool contains(int t, int v) const {
    const Triangle& tri = mesh_.triangles[t];
    return tri[0] == v || tri[1] == v || tri[2] == v;
  }
  // Twice the area vector of the triangle, with vertex `moved` (if any) placed at `to`.
  Vec3 normal(const Triangle& tri, int moved = -1, const Vec3& to = Vec3::Zero()) const {
    const auto p = [&](int q) -> const Vec3& { return tri[q] == moved ? to : mesh_.positions[tri[q]]; };
    return (p(1) - p(0)).cross(p(2) - p(0));
  }

  // The worst shape (twice the area over the longest edge squared) among the triangles that
  // merging u into v moves, or nothing when the merge would change the topology, fold a
  // triangle over, or leave one degenerate.
  std::optional<double> quality_after_merge(int u, int v) const {
    if (locked_[u] || locked_[v]) return std::nullopt;
    std::vector<int> apexes, around_u, around_v;
    for (int t : star_[u]) {
      if (!tri_alive_[t]) continue;
      for (int w : mesh_.triangles[t])
        if (w != u) around_u.push_back(w);
      if (contains(t, v))
        for (int w : mesh_.triangles[t])
          if (w != u && w != v) apexes.push_back(w);
    }
    if (apexes.size() != 2 || apexes[0] == apexes[1]) return std::nullopt;
    for (int t : star_[v])
      if (tri_alive_[t])
        for (int w : mesh_.triangles[t])
          if (w != v) around_v.push_back(w);
    // Link condition: the ends' common neighbours are exactly the two apexes (otherwise the
    // merge would pinch a handle or a thin neck shut, or flatten a tetrahedron).
    std::sort(around_u.begin(), around_u.end());
    around_u.erase(std::unique(around_u.begin(), around_u.end()), around_u.end());
    std::sort(around_v.begin(), around_v.end());
    around_v.erase(std::unique(around_v.begin(), around_v.end()), around_v.end());
    std::vector<int> common;
    std::set_intersection(around_u.begin(), around_u.end(), around_v.begin(), around_v.end(),
                          std::back_inserter(common));
    std::sort(apexes.begin(), apexes.end());
    if (common != apexes) return std::nullopt;

    const Vec3& to = mesh_.positions[v];
    // Summed in a fixed order, so that both traversals (whose stars list triangles in different
    // orders) round alike.
    std::vector<std::array<double, 3>> normals;
    for (int t : star_[u])
      if (tri_alive_[t]) {
        const Vec3 n = normal(mesh_.triangles[t]);
        normals.push_back({n.x(), n.y(), n.z()});
      }
    std::sort(normals.begin(), normals.end());
    Vec3 star_normal = Vec3::Zero();
    for (const auto& n : normals) star_normal += Vec3(n[0], n[1], n[2]);
    double worst = std::numeric_limits<double>::infinity();
    for (int t : star_[u]) {
      if (!tri_alive_[t] || contains(t, v)) continue;
      const Triangle& tri = mesh_.triangles[t];
      const Vec3 before = normal(tri), after = normal(tri, u, to);
      // A triangle may not turn over, neither against its own normal nor (for one too small
      // to have a trustworthy normal) against the surface around u.
      if (after.dot(before) < 0 || after.dot(star_normal) <= 0) return std::nullopt;
      double longest = 0;
      for (int q = 0; q < 3; ++q) {
        const int a = tri[q], b = tri[(q + 1) % 3];
        const Vec3 pa = a == u ? to : mesh_.positions[a], pb = b == u ? to : mesh_.positions[b];
        longest = std::max(longest, (pa - pb).squaredNorm());
      }
      const double shape = after.norm() / longest;
      if (!(shape > 0)) return std::nullopt;
      worst = std::min(worst, shape);
      // The moved triangle must not exist already around v (a tetrahedron would fold flat).
      int x = -1, y = -1;
      for (int w : tri)
        if (w != u) (x < 0 ? x : y) = w;
      for (int s : star_[v])
        if (tri_alive_[s] && contains(s, x) && contains(s, y)) return std::nullopt;
    }
    return worst;
  }

  // A short edge a-b can be blocked by its neighbourhood: a vertex of degree 3 on it (the tip of
  // a small cap: merging a-b would break the link condition), or a needle from a third vertex
  // near the same lattice corner that merging a-b would turn over. One collapse of an edge from
  // a or b to an apex of a-b, if no longer than kUnblockLength times min_length, removes the
  // obstacle; the shortest that is valid is made.
  bool unblock(int a, int b) {
    std::vector<std::tuple<double, std::uint64_t, int, int>> edges;  // length, apex key, end, apex
    for (int t : star_[a]) {
      if (!tri_alive_[t] || !contains(t, b)) continue;
      for (int w : mesh_.triangles[t])
        if (w != a && w != b)
          for (int end : {a, b}) {
            const double length = (mesh_.positions[w] - mesh_.positions[end]).norm();
            if (length < kUnblockLength * min_length_) edges.emplace_back(length, keys_[w], end, w);
          }
    }
    std::sort(edges.begin(), edges.end(), [&](const auto& x, const auto& y) {
      return std::make_tuple(std::get<0>(x), std::get<1>(x), keys_[std::get<2>(x)]) <
             std::make_tuple(std::get<0>(y), std::get<1>(y), keys_[std::get<2>(y)]);
    });
    for (const auto& [length, key, end, w] : edges) {
      const std::optional<double> keep_end = quality_after_merge(w, end), keep_w = quality_after_merge(end, w);
      if (!keep_end && !keep_w) continue;
      const bool remove_w = keep_end && (!keep_w || *keep_end > *keep_w || (*keep_end == *keep_w && keys_[end] < key));
      remove_w ? merge(w, end) : merge(end, w);
      return true;
    }
    return false;
  }

  void merge(int u, int v) {
    for (int t : star_[u]) {
      if (!tri_alive_[t]) continue;
      if (contains(t, v)) {
        tri_alive_[t] = 0;
        continue;
      }
      for (int& w : mesh_.triangles[t])
        if (w == u) w = v;
      star_[v].push_back(t);
    }
    star_[u].clear();
    star_[v].erase(std::remove_if(star_[v].begin(), star_[v].end(), [&](int t) { return !tri_alive_[t]; }),
                   star_[v].end());
  }

  std::size_t drop_components_below_length() {
    std::vector<int> parent(mesh_.positions.size());
    std::iota(parent.begin(), parent.end(), 0);
    const auto find = [&](int x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    for (std::size_t t = 0; t < mesh_.triangles.size(); ++t)
      if (tri_alive_[t]) {
        const Triangle& tri = mesh_.triangles[t];
        for (int q = 1; q < 3; ++q) {
          const int a = find(tri[0]), b = find(tri[q]);
          if (a != b) parent[std::max(a, b)] = std::min(a, b);
        }
      }
    std::vector<char> long_edge(mesh_.positions.size(), 0), present(mesh_.positions.size(), 0);
    for (std::size_t t = 0; t < mesh_.triangles.size(); ++t)
      if (tri_alive_[t]) {
        const Triangle& tri = mesh_.triangles[t];
        const int root = find(tri[0]);
        present[root] = 1;
        for (int q = 0; q < 3; ++q)
          if ((mesh_.positions[tri[q]] - mesh_.positions[tri[(q + 1) % 3]]).norm() >= min_length_) long_edge[root] = 1;
      }
    std::size_t dropped = 0;
    for (std::size_t r = 0; r < present.size(); ++r) dropped += present[r] && !long_edge[r];
    for (std::size_t t = 0; t < mesh_.triangles.size(); ++t)
      if (tri_alive_[t] && !long_edge[find(mesh_.triangles[t][0])]) tri_alive_[t] = 0;
    return dropped;
  }

  void compact() {
    std::vector<int> index(mesh_.positions.size(), -1);
    std::vector<Triangle> triangles;
    for (std::size_t t = 0; t < mesh_.triangles.size(); ++t)
      if (tri_alive_[t]) {
        triangles.push_back(mesh_.triangles[t]);
        for (int v : mesh_.triangles[t]) index[v] = 0;
      }
    std::vector<Vec3> positions;
    for (std::size_t v = 0; v < index.size(); ++v)
      if (index[v] == 0) {
        index[v] = static_cast<int>(positions.size());
        positions.push_back(mesh_.positions[v]);
      }
    for (Triangle& tri : triangles)
      for (int& v : tri) v = index[v];
    mesh_.positions = std::move(positions);
    mesh_.triangles = std::move(triangles);
  }

  Mesh& mesh_;
  const std::vector<std::uint64_t>& keys_;
  double min_length_;
  std::vector<std::vector<int>> star_;  // triangles around each vertex (dead ones pruned lazily)
  std::vector<char> tri_alive_, locked_;
};

}  // namespace

CollapseReport collapse_short_edges(Mesh& mesh, const std::vector<std::uint64_t>& keys, double min_length) {
  return Collapser(mesh, keys, min_length).run();
}

}  // namespace cdp::marching
