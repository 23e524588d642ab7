// Topology of hand-built meshes: what the checks of every polygonizer test rely on.
#include <gtest/gtest.h>

#include <cdp/core/mesh_topology.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <vector>

namespace cdp {
namespace {

Mesh tetrahedron() {
  Mesh m;
  m.positions = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  m.triangles = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  return m;
}

// A torus as an n x m quad grid split into triangles, outward.
Mesh grid_torus(int n, int m) {
  Mesh mesh;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double u = 2 * std::numbers::pi * i / n, v = 2 * std::numbers::pi * j / m;
      mesh.positions.emplace_back((1 + 0.3 * std::cos(v)) * std::cos(u), (1 + 0.3 * std::cos(v)) * std::sin(u),
                                  0.3 * std::sin(v));
    }
  auto id = [&](int i, int j) { return ((i + n) % n) * m + (j + m) % m; };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return mesh;
}

TEST(MeshTopology, TetrahedronIsAClosedOutwardSphere) {
  const MeshTopology t = analyze_topology(tetrahedron());
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.vertices, 4u);
  EXPECT_EQ(t.edges, 6u);
  EXPECT_EQ(t.euler_characteristic, 2);
  EXPECT_EQ(t.genus, 0);
  EXPECT_EQ(t.components, 1u);
  EXPECT_NEAR(t.signed_volume, 8.0 / 3.0, 1e-12);  // regular tetrahedron in the cube [-1,1]^3
}

TEST(MeshTopology, GridTorusHasGenusOne) {
  const MeshTopology t = analyze_topology(grid_torus(12, 8));
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.genus, 1);
  EXPECT_EQ(t.euler_characteristic, 0);
}

TEST(MeshTopology, TwoDisjointTetrahedraAreTwoComponentsOfGenusZero) {
  Mesh m = tetrahedron();
  Mesh b = tetrahedron();
  for (auto& p : b.positions) m.positions.push_back(p + Vec3(5, 0, 0));
  for (auto t : b.triangles) m.triangles.push_back({t[0] + 4, t[1] + 4, t[2] + 4});
  const MeshTopology t = analyze_topology(m);
  EXPECT_EQ(t.components, 2u);
  EXPECT_EQ(t.genus, 0);
  EXPECT_TRUE(t.watertight());
}

TEST(MeshTopology, OpenFlippedAndInsideOutMeshesAreFlagged) {
  Mesh open = tetrahedron();
  open.triangles.pop_back();
  EXPECT_EQ(analyze_topology(open).boundary_edges, 3u);
  EXPECT_FALSE(analyze_topology(open).closed());
  EXPECT_EQ(analyze_topology(open).genus, -1);

  Mesh flipped = tetrahedron();
  std::swap(flipped.triangles[0][1], flipped.triangles[0][2]);
  EXPECT_EQ(analyze_topology(flipped).misoriented_edges, 3u);
  EXPECT_FALSE(analyze_topology(flipped).watertight());

  Mesh inside_out = tetrahedron();
  for (auto& t : inside_out.triangles) std::swap(t[1], t[2]);
  const MeshTopology t = analyze_topology(inside_out);
  EXPECT_TRUE(t.oriented());
  EXPECT_LT(t.signed_volume, 0);
  EXPECT_FALSE(t.watertight());
}

TEST(MeshTopology, NonManifoldEdgesAndVerticesAreCounted) {
  Mesh fin = tetrahedron();
  fin.positions.push_back({3, 0, 0});
  fin.triangles.push_back({0, 1, 4});  // a third triangle on edge 0-1
  EXPECT_EQ(analyze_topology(fin).nonmanifold_edges, 1u);

  // Two tetrahedra sharing only vertex 0.
  Mesh bowtie = tetrahedron();
  const Mesh b = tetrahedron();
  for (int i = 1; i < 4; ++i) bowtie.positions.push_back(b.positions[i] * -1.0 + Vec3(2, 2, 2));
  for (auto t : b.triangles) {
    std::array<int, 3> u{};
    for (int k = 0; k < 3; ++k) u[k] = t[k] == 0 ? 0 : t[k] + 3;
    bowtie.triangles.push_back(u);
  }
  const MeshTopology t = analyze_topology(bowtie);
  EXPECT_EQ(t.nonmanifold_vertices, 1u);
  EXPECT_EQ(t.nonmanifold_edges, 0u);
  EXPECT_FALSE(t.watertight());
}

TEST(MeshTopology, DegenerateAndDuplicateTrianglesAreCounted) {
  Mesh m = tetrahedron();
  m.triangles.push_back({0, 2, 1});
  m.positions.push_back({0.5, 0.5, 0.5});
  m.positions.push_back({1.5, 1.5, 1.5});
  m.triangles.push_back({0, 4, 5});  // collinear points
  const MeshTopology t = analyze_topology(m);
  EXPECT_EQ(t.duplicate_triangles, 1u);
  EXPECT_EQ(t.degenerate_triangles, 1u);
}

// The counts straight from their definitions in mesh_topology.h (maps of edges and of vertex
// sets, searches over triangles), slow and independent of analyze_topology's single pass.
MeshTopology reference_topology(const Mesh& m) {
  MeshTopology t;
  const int nf = static_cast<int>(m.triangles.size());
  t.triangles = m.triangles.size();
  const auto repeated = [&](int f) {
    const auto& x = m.triangles[f];
    return x[0] == x[1] || x[1] == x[2] || x[0] == x[2];
  };
  std::set<int> used;
  std::map<std::array<int, 3>, int> sets;
  std::map<std::pair<int, int>, std::vector<std::pair<int, bool>>> edges;  // users, lo -> hi
  for (int f = 0; f < nf; ++f) {
    const auto& x = m.triangles[f];
    used.insert(x.begin(), x.end());
    auto s = x;
    std::sort(s.begin(), s.end());
    t.duplicate_triangles += sets[s]++ > 0;
    if (repeated(f)) continue;
    for (int k = 0; k < 3; ++k) {
      const int u = x[k], w = x[(k + 1) % 3];
      edges[{std::min(u, w), std::max(u, w)}].push_back({f, u < w});
    }
  }
  t.vertices = used.size();
  t.unreferenced_vertices = m.positions.size() - used.size();
  std::vector<std::vector<int>> next(nf);  // triangles sharing an edge
  for (const auto& [e, users] : edges) {
    ++t.edges;
    t.boundary_edges += users.size() == 1;
    t.nonmanifold_edges += users.size() >= 3;
    t.misoriented_edges += users.size() == 2 && users[0].second == users[1].second;
    for (const auto& a : users)
      for (const auto& b : users)
        if (a.first != b.first) next[a.first].push_back(b.first);
  }
  std::vector<char> seen(nf, 0);
  for (int f = 0; f < nf; ++f) {
    if (seen[f]) continue;
    ++t.components;
    std::vector<int> stack{f};
    seen[f] = 1;
    while (!stack.empty()) {
      const int g = stack.back();
      stack.pop_back();
      for (int h : next[g])
        if (!seen[h]) seen[h] = 1, stack.push_back(h);
    }
  }
  // Fans: the occurrences of v in triangles, joined when their triangles share another vertex
  // (an edge containing v).
  for (int v : used) {
    std::vector<int> at;
    for (int f = 0; f < nf; ++f)
      for (int c : m.triangles[f])
        if (c == v) at.push_back(f);
    if (at.size() <= 1) continue;
    std::vector<int> fan(at.size(), -1);
    int fans = 0;
    for (std::size_t i = 0; i < at.size(); ++i) {
      if (fan[i] >= 0) continue;
      std::vector<std::size_t> stack{i};
      fan[i] = fans;
      while (!stack.empty()) {
        const std::size_t a = stack.back();
        stack.pop_back();
        for (std::size_t b = 0; b < at.size(); ++b) {
          if (fan[b] >= 0) continue;
          bool shares = false;
          for (int p : m.triangles[at[a]])
            for (int q : m.triangles[at[b]]) shares = shares || (p == q && p != v);
          if (shares) fan[b] = fans, stack.push_back(b);
        }
      }
      ++fans;
    }
    t.nonmanifold_vertices += fans > 1;
  }
  return t;
}

// Small random index soups (repeated indices, duplicates, open, flipped and non-manifold
// pieces), a grid torus pinched at a vertex, and one with triangles removed, flipped, repeated
// and re-indexed.
TEST(MeshTopology, RandomMeshesMatchTheDefinitions) {
  std::mt19937 rng(20261125);
  const auto check = [](const Mesh& m) {
    const MeshTopology a = analyze_topology(m), b = reference_topology(m);
    EXPECT_EQ(a.vertices, b.vertices);
    EXPECT_EQ(a.unreferenced_vertices, b.unreferenced_vertices);
    EXPECT_EQ(a.edges, b.edges);
    EXPECT_EQ(a.boundary_edges, b.boundary_edges);
    EXPECT_EQ(a.nonmanifold_edges, b.nonmanifold_edges);
    EXPECT_EQ(a.misoriented_edges, b.misoriented_edges);
    EXPECT_EQ(a.nonmanifold_vertices, b.nonmanifold_vertices);
    EXPECT_EQ(a.duplicate_triangles, b.duplicate_triangles);
    EXPECT_EQ(a.components, b.components);
    return !::testing::Test::HasFailure();
  };
  for (int it = 0; it < 2000; ++it) {
    Mesh m;
    const int nv = 1 + static_cast<int>(rng() % 10), nf = static_cast<int>(rng() % 20);
    for (int i = 0; i < nv; ++i) m.positions.emplace_back(rng() % 5, rng() % 5, rng() % 5);
    for (int f = 0; f < nf; ++f)
      m.triangles.push_back({static_cast<int>(rng() % nv), static_cast<int>(rng() % nv), static_cast<int>(rng() % nv)});
    ASSERT_TRUE(check(m)) << "soup " << it;
  }
  const Mesh torus = grid_torus(8, 6);
  // Vertices whose stars are closed fans but for one change (analyze_topology's fast path): two
  // vertices merged into one (its triangles then close two fans), and a triangle turned over
  // among otherwise closed fans.
  for (int it = 0; it < 200; ++it) {
    Mesh m = torus;
    const int a = static_cast<int>(rng() % m.positions.size()), b = static_cast<int>(rng() % m.positions.size());
    for (auto& tri : m.triangles)
      for (int& x : tri)
        if (x == b) x = a;
    if (it % 2) {
      auto& flipped = m.triangles[rng() % m.triangles.size()];
      std::swap(flipped[1], flipped[2]);
    }
    ASSERT_TRUE(check(m)) << "pinched torus " << it;
  }
  for (int it = 0; it < 300; ++it) {
    Mesh m = torus;
    for (int k = static_cast<int>(rng() % 6); k > 0; --k) {
      const std::size_t f = rng() % m.triangles.size();
      switch (rng() % 4) {
        case 0: m.triangles.erase(m.triangles.begin() + static_cast<std::ptrdiff_t>(f)); break;
        case 1: std::swap(m.triangles[f][0], m.triangles[f][1]); break;
        case 2: m.triangles.push_back(m.triangles[f]); break;
        default: m.triangles[f][rng() % 3] = static_cast<int>(rng() % m.positions.size()); break;
      }
    }
    ASSERT_TRUE(check(m)) << "torus " << it;
  }
}

}  // namespace
}  // namespace cdp
