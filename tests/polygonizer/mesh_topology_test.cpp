// Topology of hand-built meshes: what the checks of every polygonizer test rely on.
#include <gtest/gtest.h>

#include <cdp/core/mesh_topology.h>

#include <cmath>
#include <numbers>

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

}  // namespace
}  // namespace cdp
