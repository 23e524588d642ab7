#include <cdp/core/mesh_topology.h>
#include "union_find.h"

#include <algorithm>

namespace cdp {

namespace {

struct HalfEdge {
  int lo, hi;       // undirected key
  bool forward;     // traversed lo -> hi
  int face;
};

// Sorts items by key(item) in [0, keys) with a counting sort (stable, linear), then each run of
// equal keys by `less`: the order std::sort by (key, less) gives, without its n log n on meshes
// of millions of triangles (a run holds about six half-edges or two triangles).
template <class T, class Key, class Less>
void bucket_sort(std::vector<T>& items, std::size_t keys, Key key, Less less) {
  std::vector<std::size_t> start(keys + 1, 0);
  for (const T& x : items) ++start[static_cast<std::size_t>(key(x)) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<T> sorted(items.size());
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (const T& x : items) sorted[fill[static_cast<std::size_t>(key(x))]++] = x;
  }
  for (std::size_t k = 0; k < keys; ++k)
    if (start[k + 1] - start[k] > 1)
      std::sort(sorted.begin() + static_cast<std::ptrdiff_t>(start[k]),
                sorted.begin() + static_cast<std::ptrdiff_t>(start[k + 1]), less);
  items = std::move(sorted);
}

}  // namespace

MeshTopology analyze_topology(const Mesh& mesh) {
  MeshTopology t;
  const std::size_t nv = mesh.positions.size();
  const std::size_t nf = mesh.triangles.size();
  t.triangles = nf;

  std::vector<char> referenced(nv, 0);
  std::vector<HalfEdge> halfedges;
  halfedges.reserve(3 * nf);
  std::vector<std::array<int, 3>> sorted_tris(nf);
  for (std::size_t f = 0; f < nf; ++f) {
    const auto& tri = mesh.triangles[f];
    for (int k = 0; k < 3; ++k) referenced[tri[k]] = 1;
    const Vec3& a = mesh.positions[tri[0]];
    const Vec3& b = mesh.positions[tri[1]];
    const Vec3& c = mesh.positions[tri[2]];
    const Vec3 cr = (b - a).cross(c - a);
    t.signed_volume += a.dot(b.cross(c)) / 6.0;
    t.area += 0.5 * cr.norm();
    const double e2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
    const bool repeated = tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2];
    if (repeated || cr.squaredNorm() <= 1e-24 * e2 * e2) ++t.degenerate_triangles;
    auto s = tri;
    std::sort(s.begin(), s.end());
    sorted_tris[f] = s;
    if (repeated) continue;
    for (int k = 0; k < 3; ++k) {
      const int u = tri[k], v = tri[(k + 1) % 3];
      halfedges.push_back({std::min(u, v), std::max(u, v), u < v, static_cast<int>(f)});
    }
  }
  bucket_sort(sorted_tris, nv, [](const std::array<int, 3>& x) { return x[0]; },
              [](const std::array<int, 3>& a, const std::array<int, 3>& b) { return a < b; });
  for (std::size_t i = 1; i < nf; ++i)
    if (sorted_tris[i] == sorted_tris[i - 1]) ++t.duplicate_triangles;

  t.vertices = static_cast<std::size_t>(std::count(referenced.begin(), referenced.end(), 1));
  t.unreferenced_vertices = nv - t.vertices;

  bucket_sort(halfedges, nv, [](const HalfEdge& h) { return h.lo; }, [](const HalfEdge& a, const HalfEdge& b) {
    return a.hi != b.hi ? a.hi < b.hi : a.face < b.face;
  });
  UnionFind faces(nf);
  for (auto group = halfedges.begin(); group != halfedges.end();) {
    const auto stop = std::find_if(group, halfedges.end(), [&](const HalfEdge& h) {
      return h.lo != group->lo || h.hi != group->hi;
    });
    const auto uses = stop - group;
    ++t.edges;
    if (uses == 1) ++t.boundary_edges;
    if (uses >= 3) ++t.nonmanifold_edges;
    if (uses == 2 && group[0].forward == group[1].forward) ++t.misoriented_edges;
    for (auto other = group + 1; other != stop; ++other) faces.unite(group->face, other->face);
    group = stop;
  }
  for (std::size_t f = 0; f < nf; ++f) t.components += faces.find(static_cast<int>(f)) == static_cast<int>(f);

  // Vertex manifoldness: the triangles around a vertex must form one fan, i.e. be connected
  // through edges that contain the vertex.
  std::vector<int> offsets(nv + 1, 0);
  for (const auto& tri : mesh.triangles)
    for (int k = 0; k < 3; ++k) ++offsets[tri[k] + 1];
  std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
  std::vector<int> incident(offsets.back());
  {
    std::vector<int> fill = offsets;
    for (std::size_t f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) incident[fill[mesh.triangles[f][k]]++] = static_cast<int>(f);
  }
  // (other vertex, local face index) for the faces around a vertex, sorted: faces that share an
  // edge with the vertex are then neighbours in the list.
  std::vector<std::pair<int, int>> around;
  UnionFind local(0);
  for (std::size_t v = 0; v < nv; ++v) {
    const int begin = offsets[v], end = offsets[v + 1];
    if (end - begin <= 1) continue;
    local.reset(static_cast<std::size_t>(end - begin));
    around.clear();
    for (int i = begin; i < end; ++i)
      for (int w : mesh.triangles[incident[i]])
        if (w != static_cast<int>(v)) around.emplace_back(w, i - begin);
    std::sort(around.begin(), around.end());
    for (std::size_t k = 1; k < around.size(); ++k)
      if (around[k].first == around[k - 1].first) local.unite(around[k - 1].second, around[k].second);
    int fans = 0;
    for (int i = 0; i < end - begin; ++i) fans += local.find(i) == i;
    if (fans > 1) ++t.nonmanifold_vertices;
  }

  t.euler_characteristic = static_cast<int>(t.vertices) - static_cast<int>(t.edges) + static_cast<int>(nf);
  if (t.closed() && t.edge_manifold() && t.oriented() && t.vertex_manifold() && nf > 0)
    t.genus = (2 * static_cast<int>(t.components) - t.euler_characteristic) / 2;
  return t;
}

}  // namespace cdp
