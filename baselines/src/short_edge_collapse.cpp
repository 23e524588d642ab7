#include "short_edge_collapse.h"

#include <algorithm>
#include <limits>
#include <optional>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

namespace cdp::marching {

namespace {

using Triangle = std::array<int, 3>;

// How far (in collapse lengths) a neighbouring vertex that blocks a short edge may be and still
// be merged to unblock it: the vertices a corner's root makes lie within a few hundredths of a
// cell of each other; ten collapse lengths reaches all of them and nothing a cell away.
constexpr double kUnblockLength = 10;

// The triangles around a vertex, as a range of triangle indices.
struct Star {
  const int* first;
  const int* last;
  const int* begin() const { return first; }
  const int* end() const { return last; }
};

using ShortEdge = std::tuple<double, std::uint64_t, std::uint64_t, int, int>;  // length, keys, ends

class Collapser {
 public:
  Collapser(Mesh& mesh, const std::vector<std::uint64_t>& keys, double min_length)
      : mesh_(mesh), keys_(keys), min_length_(min_length), tri_alive_(mesh.triangles.size(), 1) {}

  CollapseReport run() {
    CollapseReport report;
    std::vector<ShortEdge> edges = short_edges_of_all();
    if (edges.empty()) return report;  // the common case on smooth fields costs one pass
    build_stars();
    // Each pass tries the short edges in one order (shortest first, keys on ties); a collapse
    // can make new short edges (around the vertex kept) or unblock one, so passes repeat with the
    // edges still short: those left and those around the vertices kept, until one changes
    // nothing. That is the set a scan of the whole mesh would find, at the cost of a few stars.
    while (!edges.empty()) {
      std::vector<int> kept;
      for (const auto& [length, key_a, key_b, a, b] : edges) {
        if (!edge_alive(a, b)) continue;
        std::optional<double> keep_b = quality_after_merge(a, b), keep_a = quality_after_merge(b, a);
        if (!keep_a && !keep_b && unblock(a, b, kept)) {
          ++report.collapsed_edges;
          if (!edge_alive(a, b)) continue;
          keep_b = quality_after_merge(a, b), keep_a = quality_after_merge(b, a);
        }
        if (!keep_a && !keep_b) continue;
        // The better shaped result; on a tie, the end with the smaller key stays.
        const bool remove_a = !keep_a || (keep_b && (*keep_b > *keep_a || (*keep_b == *keep_a && key_b < key_a)));
        remove_a ? merge(a, b) : merge(b, a);
        kept.push_back(remove_a ? b : a);
        ++report.collapsed_edges;
      }
      if (kept.empty()) break;
      edges = short_edges_left(edges, kept);
    }
    edges = short_edges_left(edges, {});
    report.dropped_components = drop_components_below_length(edges);
    report.short_edges_left = short_edges_left(edges, {}).size();
    if (report.collapsed_edges > 0 || report.dropped_components > 0) compact();
    return report;
  }

 private:
  ShortEdge short_edge(int a, int b) const {
    if (keys_[a] > keys_[b]) std::swap(a, b);
    return {(mesh_.positions[a] - mesh_.positions[b]).norm(), keys_[a], keys_[b], a, b};
  }

  // Edges shorter than min_length, shortest first; ties (mirror-symmetric fields) by the keys.
  std::vector<ShortEdge> short_edges_of_all() const {
    std::vector<ShortEdge> out;
    for (const Triangle& tri : mesh_.triangles)
      for (int q = 0; q < 3; ++q) {
        const ShortEdge e = short_edge(tri[q], tri[(q + 1) % 3]);
        if (std::get<0>(e) < min_length_) out.push_back(e);
      }
    return sorted_unique(std::move(out));
  }

  // The edges of `previous` still in the mesh and the short edges around the vertices `kept`.
  std::vector<ShortEdge> short_edges_left(const std::vector<ShortEdge>& previous, const std::vector<int>& kept) const {
    std::vector<ShortEdge> out;
    for (const ShortEdge& e : previous)
      if (edge_alive(std::get<3>(e), std::get<4>(e))) out.push_back(e);
    for (int v : kept)
      for (int t : star(v))
        if (tri_alive_[t])
          for (int w : mesh_.triangles[t]) {
            if (w == v) continue;
            const ShortEdge e = short_edge(v, w);
            if (std::get<0>(e) < min_length_) out.push_back(e);
          }
    return sorted_unique(std::move(out));
  }

  static std::vector<ShortEdge> sorted_unique(std::vector<ShortEdge> edges) {
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());  // each edge seen twice
    return edges;
  }

  // Triangles around each vertex, flat (one pass to count, one to fill); a vertex whose star a
  // merge changes gets its own list in rebuilt_.
  void build_stars() {
    offsets_.assign(mesh_.positions.size() + 1, 0);
    for (const Triangle& tri : mesh_.triangles)
      for (int v : tri) ++offsets_[v + 1];
    for (std::size_t v = 0; v < mesh_.positions.size(); ++v) offsets_[v + 1] += offsets_[v];
    incident_.resize(offsets_.back());
    std::vector<int> fill(offsets_.begin(), offsets_.end() - 1);
    for (std::size_t t = 0; t < mesh_.triangles.size(); ++t)
      for (int v : mesh_.triangles[t]) incident_[fill[v]++] = static_cast<int>(t);
  }
  Star star(int v) const {
    if (const auto it = rebuilt_.find(v); it != rebuilt_.end()) return {it->second.data(), it->second.data() + it->second.size()};
    return {incident_.data() + offsets_[v], incident_.data() + offsets_[v + 1]};
  }

  // Whether an edge at v has one triangle or more than two: the mesh is clipped at the box there
  // (or not a manifold), and v stays where it is.
  bool on_open_boundary(int v) const {
    std::vector<int> ends;
    for (int t : star(v))
      if (tri_alive_[t])
        for (int w : mesh_.triangles[t])
          if (w != v) ends.push_back(w);
    std::sort(ends.begin(), ends.end());
    for (std::size_t i = 0; i < ends.size();) {
      std::size_t j = i;
      while (j < ends.size() && ends[j] == ends[i]) ++j;
      if (j - i != 2) return true;
      i = j;
    }
    return false;
  }

  bool edge_alive(int a, int b) const {
    for (int t : star(a))
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
    std::vector<int> apexes, around_u, around_v;
    for (int t : star(u)) {
      if (!tri_alive_[t]) continue;
      for (int w : mesh_.triangles[t])
        if (w != u) around_u.push_back(w);
      if (contains(t, v))
        for (int w : mesh_.triangles[t])
          if (w != u && w != v) apexes.push_back(w);
    }
    if (apexes.size() != 2 || apexes[0] == apexes[1]) return std::nullopt;
    for (int t : star(v))
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
    if (common != apexes || on_open_boundary(u) || on_open_boundary(v)) return std::nullopt;

    const Vec3& to = mesh_.positions[v];
    // Summed in a fixed order, so that both traversals (whose stars list triangles in different
    // orders) round alike.
    std::vector<std::array<double, 3>> normals;
    for (int t : star(u))
      if (tri_alive_[t]) {
        const Vec3 n = normal(mesh_.triangles[t]);
        normals.push_back({n.x(), n.y(), n.z()});
      }
    std::sort(normals.begin(), normals.end());
    Vec3 star_normal = Vec3::Zero();
    for (const auto& n : normals) star_normal += Vec3(n[0], n[1], n[2]);
    double worst = std::numeric_limits<double>::infinity();
    for (int t : star(u)) {
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
      for (int s : star(v))
        if (tri_alive_[s] && contains(s, x) && contains(s, y)) return std::nullopt;
    }
    return worst;
  }

  // A short edge a-b can be blocked by its neighbourhood: a vertex of degree 3 on it (the tip of
  // a small cap: merging a-b would break the link condition), or a needle from a third vertex
  // near the same lattice corner that merging a-b would turn over. One collapse of an edge from
  // a or b to an apex of a-b, if no longer than kUnblockLength times min_length, removes the
  // obstacle; the shortest that is valid is made.
  bool unblock(int a, int b, std::vector<int>& kept) {
    std::vector<std::tuple<double, std::uint64_t, int, int>> edges;  // length, apex key, end, apex
    for (int t : star(a)) {
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
      kept.push_back(remove_w ? end : w);
      return true;
    }
    return false;
  }

  void merge(int u, int v) {
    std::vector<int> around_v;
    for (int t : star(v))
      if (tri_alive_[t] && !contains(t, u)) around_v.push_back(t);
    for (int t : star(u)) {
      if (!tri_alive_[t]) continue;
      if (contains(t, v)) {
        tri_alive_[t] = 0;
        continue;
      }
      for (int& w : mesh_.triangles[t])
        if (w == u) w = v;
      around_v.push_back(t);
    }
    rebuilt_[u].clear();
    rebuilt_[v] = std::move(around_v);
  }

  // Removes the components all of whose edges are under min_length; each holds one of the
  // short edges left, so a walk from those (stopping at the first long edge) finds them all.
  std::size_t drop_components_below_length(const std::vector<ShortEdge>& left) {
    std::size_t dropped = 0;
    std::unordered_set<int> seen;
    for (const ShortEdge& e : left) {
      const int start = std::get<3>(e);
      if (seen.count(start)) continue;
      std::vector<int> stack{start}, triangles;
      seen.insert(start);
      bool long_edge = false;
      while (!stack.empty() && !long_edge) {
        const int x = stack.back();
        stack.pop_back();
        for (int t : star(x)) {
          if (!tri_alive_[t]) continue;
          triangles.push_back(t);
          const Triangle& tri = mesh_.triangles[t];
          for (int q = 0; q < 3; ++q) {
            if ((mesh_.positions[tri[q]] - mesh_.positions[tri[(q + 1) % 3]]).norm() >= min_length_) long_edge = true;
            if (seen.insert(tri[q]).second) stack.push_back(tri[q]);
          }
        }
      }
      if (long_edge) continue;
      for (int t : triangles) tri_alive_[t] = 0;
      ++dropped;
    }
    return dropped;
  }

  // Drops dead triangles and unreferenced vertices in place, keeping the order of the rest.
  void compact() {
    std::vector<int> index(mesh_.positions.size(), -1);
    std::size_t kept_triangles = 0;
    for (std::size_t t = 0; t < mesh_.triangles.size(); ++t)
      if (tri_alive_[t]) {
        for (int v : mesh_.triangles[t]) index[v] = 0;
        mesh_.triangles[kept_triangles++] = mesh_.triangles[t];
      }
    mesh_.triangles.resize(kept_triangles);
    std::size_t kept_vertices = 0;
    for (std::size_t v = 0; v < index.size(); ++v)
      if (index[v] == 0) {
        index[v] = static_cast<int>(kept_vertices);
        mesh_.positions[kept_vertices++] = mesh_.positions[v];
      }
    mesh_.positions.resize(kept_vertices);
    for (Triangle& tri : mesh_.triangles)
      for (int& v : tri) v = index[v];
  }

  Mesh& mesh_;
  const std::vector<std::uint64_t>& keys_;
  double min_length_;
  std::vector<char> tri_alive_;
  // Triangles around each vertex as first built (incident_[offsets_[v] .. offsets_[v + 1]]),
  // and the stars merges have changed since; dead triangles are skipped where read.
  std::vector<int> offsets_, incident_;
  std::unordered_map<int, std::vector<int>> rebuilt_;
};

}  // namespace

CollapseReport collapse_short_edges(Mesh& mesh, const std::vector<std::uint64_t>& keys, double min_length) {
  return Collapser(mesh, keys, min_length).run();
}

}  // namespace cdp::marching
