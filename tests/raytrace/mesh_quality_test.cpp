// Checks <cdp/raytrace/mesh_quality.h> against values computed by hand.
#include <cdp/raytrace/mesh_quality.h>
#include "common/reference_meshes.h"

#include <gtest/gtest.h>

#include <cmath>

namespace cdp {
namespace {

TEST(MeshQuality, RegularTetrahedronIsPerfect) {
  const MeshQuality q = compute_mesh_quality(regular_tetrahedron());
  EXPECT_EQ(q.triangles, 4u);
  EXPECT_EQ(q.vertices, 4u);
  EXPECT_NEAR(q.edge_ratio.mean, 1.0, 1e-14);
  EXPECT_NEAR(q.edge_ratio.std, 0.0, 1e-14);
  EXPECT_EQ(q.near_equilateral_fraction, 1.0);
  EXPECT_NEAR(q.min_angle_deg.min, 60.0, 1e-12);
  EXPECT_NEAR(q.min_angle_deg.mean, 60.0, 1e-12);
  EXPECT_NEAR(q.radius_ratio.min, 1.0, 1e-14);
  EXPECT_NEAR(q.edge_length.mean, 1.0, 1e-14);
  EXPECT_EQ(q.histogram_counts.front(), 4u);
  EXPECT_TRUE(q.topology.closed());
  EXPECT_TRUE(q.topology.watertight());
  EXPECT_EQ(q.topology.components, 1u);
  EXPECT_EQ(q.topology.genus, 0);
}

TEST(MeshQuality, TwoRightTrianglesOfASquare) {
  Mesh m;
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  const MeshQuality q = compute_mesh_quality(m);
  // Sides 1, 1, sqrt 2: ratio sqrt 2, smallest angle 45 deg, 2 r/R = 16 A^2 / (p a b c) = 2 (sqrt 2 - 1).
  EXPECT_NEAR(q.edge_ratio.mean, std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(q.edge_ratio.std, 0.0, 1e-15);
  EXPECT_EQ(q.near_equilateral_fraction, 0.0);
  EXPECT_NEAR(q.min_angle_deg.min, 45.0, 1e-12);
  EXPECT_NEAR(q.radius_ratio.mean, 2.0 * (std::sqrt(2.0) - 1.0), 1e-15);
  EXPECT_NEAR(q.edge_length.mean, (2.0 + std::sqrt(2.0)) / 3.0, 1e-15);
  EXPECT_EQ(q.histogram_counts[4], 2u);  // [1.4, 1.5)
  EXPECT_FALSE(q.topology.closed());
  EXPECT_EQ(q.topology.boundary_edges, 4u);
  EXPECT_EQ(q.topology.components, 1u);
}

TEST(MeshQuality, MixedTrianglesDegenerateOnesAndTheHistogram) {
  Mesh m;
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, std::sqrt(3.0) / 2, 0), Vec3(10, 0, 0), Vec3(2, 0, 0)};
  // Equilateral, a 1 : 10 sliver (ratio about 10), and a degenerate one (collinear).
  m.triangles = {{0, 1, 2}, {0, 3, 2}, {0, 1, 4}};
  MeshQualityOptions o;
  o.near_equilateral_ratio = 1.05;
  const MeshQuality q = compute_mesh_quality(m, o);
  EXPECT_EQ(q.degenerate, 1u);
  EXPECT_EQ(q.edge_ratio.count, 2u);
  EXPECT_EQ(q.near_equilateral_fraction, 0.5);
  EXPECT_EQ(q.histogram_overflow, 1u);
  EXPECT_EQ(q.histogram_counts[0], 1u);
  const double sliver = 10.0;  // longest side (0 to 3), shortest is 1
  EXPECT_NEAR(q.edge_ratio.max, sliver, 1e-12);
  EXPECT_NEAR(q.edge_ratio.mean, 0.5 * (1.0 + sliver), 1e-12);
}

TEST(MeshQuality, IcosphereIsNearlyEquilateralAndGenusZero) {
  const MeshQuality q = compute_mesh_quality(icosphere(2));
  EXPECT_EQ(q.triangles, 320u);
  EXPECT_EQ(q.vertices, 162u);
  EXPECT_LT(q.edge_ratio.mean, 1.25);
  EXPECT_GT(q.min_angle_deg.min, 45.0);
  EXPECT_TRUE(q.topology.watertight());
  EXPECT_EQ(q.topology.genus, 0);
}

}  // namespace
}  // namespace cdp
