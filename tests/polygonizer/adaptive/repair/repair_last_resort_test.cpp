// measure_densely and last_resort (src/adaptive/repair_last_resort.h) alone, on a coarse
// icosphere, against the distance of a flat triangle from the unit sphere in closed form.
#include "src/adaptive/repair_last_resort.h"

#include "polygonizer/adaptive/repair/repair_fixtures.h"

#include <numeric>

namespace cdp::adaptive::repair {
namespace {

using namespace test_repair;

std::vector<int> every_triangle(const Mesh& mesh) {
  std::vector<int> all(mesh.triangles.size());
  std::iota(all.begin(), all.end(), 0);
  return all;
}

TEST(RepairLastResort, TheDenseMeasureOfEachTriangleLiesBetweenItsCentroidsAndItsPlanesDistance) {
  const auto field = unit_sphere();
  Mesh mesh = icosphere(1);
  QualityOptions o = sphere_options();
  o.tolerance = 1e-2;
  RepairContext ctx(*field, mesh, o);
  const std::vector<Beyond> beyond = measure_densely(ctx, every_triangle(mesh));
  // Every triangle of icosphere(1) is about 0.05 from the sphere at its middle.
  ASSERT_EQ(beyond.size(), mesh.triangles.size());
  EXPECT_EQ(ctx.report_.measured_densely, mesh.triangles.size());
  for (const Beyond& b : beyond) {
    const Vec3 &p0 = mesh.positions[b.T[0]], &p1 = mesh.positions[b.T[1]], &p2 = mesh.positions[b.T[2]];
    const double at_centroid = 1 - ((p0 + p1 + p2) / 3).norm();  // the grid samples the centroid
    const double plane = 1 - std::abs((p1 - p0).cross(p2 - p0).normalized().dot(p0));
    EXPECT_GE(b.d, at_centroid - 1e-9);
    EXPECT_LE(b.d, plane + 1e-9);
    EXPECT_LT(std::abs(b.worst.point.norm() - 1), 1e-9);
  }
}

TEST(RepairLastResort, SplitsATriangleBeyondOnceAndNotBelowItsShortestEdge) {
  const auto field = unit_sphere();
  Mesh mesh = icosphere(1);
  QualityOptions o = sphere_options();
  o.tolerance = 1e-2;
  {
    // Halves and corners must be a whole radius apart: no split is allowed, nothing changes.
    Mesh kept = mesh;
    QualityOptions far = o;
    far.last_resort_min_edge = 1;
    RepairContext ctx(*field, kept, far);
    const std::vector<Beyond> beyond = measure_densely(ctx, {0});
    ASSERT_EQ(beyond.size(), 1u);
    EXPECT_FALSE(last_resort(ctx, beyond[0]));
    EXPECT_EQ(ctx.report_.last_resorts, 0u);
    EXPECT_EQ(kept.triangles, mesh.triangles);
  }
  RepairContext ctx(*field, mesh, o);
  const std::vector<Beyond> beyond = measure_densely(ctx, {0});
  ASSERT_EQ(beyond.size(), 1u);
  const std::size_t vertices = mesh.positions.size(), triangles = mesh.triangles.size();
  EXPECT_TRUE(last_resort(ctx, beyond[0]));
  EXPECT_EQ(mesh.positions.size(), vertices + 1);
  EXPECT_EQ(mesh.triangles.size(), triangles + 2);  // its longest edge halved: two triangles in four
  EXPECT_LT(std::abs(mesh.positions.back().norm() - 1), 1e-9);
  // Measured before the split, the triangle has changed since: nothing more to do.
  EXPECT_TRUE(last_resort(ctx, beyond[0]));
  EXPECT_EQ(ctx.report_.last_resorts, 1u);
  EXPECT_EQ(mesh.triangles.size(), triangles + 2);
  ctx.compact();
  expect_a_sphere(mesh);
}

}  // namespace
}  // namespace cdp::adaptive::repair
