// Oriented points from meshes (area-weighted normals) and the farthest-point subset.
#include <gtest/gtest.h>

#include <cdp/core/errors.h>
#include <cdp/core/oriented_points.h>

#include <algorithm>
#include <set>

#include "polygonizer/oriented_point_sets.h"

namespace cdp {
namespace {

// An octahedron with vertex 0 at +x; plus one vertex no triangle uses.
Mesh octahedron_with_loose_vertex() {
  Mesh m;
  m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {5, 5, 5}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

TEST(OrientedPoints, NormalsAreAreaWeightedOutwardAndLooseVerticesDropped) {
  const OrientedPoints pts = oriented_points_from_mesh(octahedron_with_loose_vertex(), "octahedron");
  ASSERT_EQ(pts.size(), 6u);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    EXPECT_NEAR((pts.normals[i] - pts.positions[i]).norm(), 0.0, 1e-15) << i;  // the vertex direction
  }
}

TEST(OrientedPoints, LargerFacesWeighMore) {
  // Two triangles at vertex 0: a big one in the z = 0 plane, a small one in the x = 0 plane.
  Mesh m;
  m.positions = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {0, 0, -1}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}, {0, 4, 3}};
  const OrientedPoints pts = oriented_points_from_mesh(m, "two");
  // Areas 50 and 0.5: the sum of cross products is (0.5 * 2) x + (50 * 2) z, up to orientation.
  EXPECT_NEAR(pts.normals[0].x(), -1.0 / std::hypot(1.0, 100.0), 1e-12);
  EXPECT_NEAR(pts.normals[0].z(), 100.0 / std::hypot(1.0, 100.0), 1e-12);
}

TEST(OrientedPoints, MeshWithoutTrianglesIsAnError) {
  Mesh points_only;
  points_only.positions = {{0, 0, 0}, {1, 0, 0}};
  EXPECT_THROW(oriented_points_from_mesh(points_only, "cloud"), InvalidInputError);
}

TEST(FarthestPointSubset, SpreadsEvenlyAndIsDeterministic) {
  const OrientedPoints sphere = test::sphere_points(3000);
  const std::vector<std::size_t> a = farthest_point_subset(sphere.positions, 120);
  EXPECT_EQ(a, farthest_point_subset(sphere.positions, 120));
  ASSERT_EQ(a.size(), 120u);
  EXPECT_EQ(std::set<std::size_t>(a.begin(), a.end()).size(), 120u);
  // Starts at the lexicographically smallest point.
  const auto lex = std::min_element(sphere.positions.begin(), sphere.positions.end(), [](const Vec3& p, const Vec3& q) {
    return std::tie(p.x(), p.y(), p.z()) < std::tie(q.x(), q.y(), q.z());
  });
  EXPECT_EQ(a.front(), static_cast<std::size_t>(lex - sphere.positions.begin()));
  // Farthest-point sampling's guarantee: no point is farther from the subset than the closest
  // two subset points are from each other.
  double min_pair = HUGE_VAL, covering = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = i + 1; j < a.size(); ++j)
      min_pair = std::min(min_pair, (sphere.positions[a[i]] - sphere.positions[a[j]]).norm());
  for (const Vec3& p : sphere.positions) {
    double nearest = HUGE_VAL;
    for (std::size_t i : a) nearest = std::min(nearest, (p - sphere.positions[i]).norm());
    covering = std::max(covering, nearest);
  }
  EXPECT_LE(covering, min_pair);
  // 120 points on the unit sphere: spacing of the order of sqrt(4 pi / 120) ~ 0.32.
  EXPECT_GT(min_pair, 0.2);
}

TEST(FarthestPointSubset, MorePointsThanAvailableIsAnError) {
  const OrientedPoints sphere = test::sphere_points(10);
  EXPECT_THROW(farthest_point_subset(sphere.positions, 11), InvalidInputError);
  EXPECT_EQ(farthest_point_subset(sphere.positions, 10).size(), 10u);
  const OrientedPoints picked = select_points(sphere, {3, 1});
  EXPECT_EQ(picked.positions[0], sphere.positions[3]);
  EXPECT_EQ(picked.normals[1], sphere.normals[1]);
}

}  // namespace
}  // namespace cdp
