// The sharp-feature measures against closed forms: a cube's mesh on its exact creases, the same
// cube shrunk by 1% (every crease point 0.01 sqrt 2 from the nearest edge, corners 0.01 sqrt 3),
// and a smooth field without creases.
#include <cdp/raytrace/crease_distance.h>

#include <cdp/core/models/expression.h>

#include "common/reference_meshes.h"

#include <gtest/gtest.h>

#include <cmath>

namespace cdp {
namespace {

Mesh cube_mesh(double half) {
  Mesh m;
  for (int i = 0; i < 8; ++i) m.positions.push_back(half * Vec3(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1));
  // Two triangles a face, counter-clockwise seen from outside.
  m.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                 {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return m;
}

const Expression& cube_field() {
  static const Expression cube("max(abs(x),max(abs(y),abs(z)))-1", {}, Box{Vec3::Constant(-1.5), Vec3::Constant(1.5)});
  return cube;
}

TEST(CreaseDistance, AnExactCubeMeshHasItsEdgesOnTheCreases) {
  const CreaseDistance d = crease_distance(cube_field(), cube_mesh(1));
  EXPECT_EQ(d.crease_curves, 12u);
  EXPECT_EQ(d.corners, 8u);
  EXPECT_EQ(d.sharp_edges, 12u);  // the faces' diagonals are flat
  EXPECT_GT(d.edge_points, 12u * 100);
  EXPECT_LE(d.crease_to_mesh_edges.max, 1e-9);
  EXPECT_LE(d.crease_to_sharp_edges.max, 1e-9);
  EXPECT_LE(d.sharp_edges_to_crease.max, 1e-9);
  EXPECT_LE(d.edge_chamfer, 1e-9);
}

TEST(CreaseDistance, AShrunkCubeIsAsFarFromTheCreasesAsTheClosedFormSays) {
  const CreaseDistance d = crease_distance(cube_field(), cube_mesh(0.99));
  // From (1, 1, z) to the edge (0.99, 0.99, z): 0.01 sqrt 2; from a corner to the shrunk corner
  // 0.01 sqrt 3.
  EXPECT_NEAR(d.crease_to_mesh_edges.min, 0.01 * std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(d.crease_to_mesh_edges.max, 0.01 * std::sqrt(3.0), 1e-9);
  // Every point of a shrunk edge is 0.01 sqrt 2 from the crease beside it.
  EXPECT_NEAR(d.sharp_edges_to_crease.min, 0.01 * std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(d.sharp_edges_to_crease.max, 0.01 * std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(d.edge_chamfer, 0.5 * (d.crease_to_sharp_edges.mean + 0.01 * std::sqrt(2.0)), 1e-12);
}

TEST(CreaseDistance, ASmoothFieldHasNoCreasesToMeasure) {
  const Expression sphere("x^2+y^2+z^2-1", {}, Box{Vec3::Constant(-1.5), Vec3::Constant(1.5)});
  const CreaseDistance d = crease_distance(sphere, icosphere(2));
  EXPECT_EQ(d.crease_curves, 0u);
  EXPECT_EQ(d.crease_to_mesh_edges.count, 0u);
  EXPECT_TRUE(std::isnan(d.edge_chamfer));
}

}  // namespace
}  // namespace cdp
