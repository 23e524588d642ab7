// refine (src/adaptive/repair_refine.h) alone, on a coarse icosphere, against the distance of
// a flat triangle from the unit sphere in closed form (through closest_point_on_triangle, whose
// regions tests/raytrace/embree_scene_test.cpp checks).
#include "src/adaptive/repair_refine.h"

#include "polygonizer/adaptive/repair/repair_fixtures.h"

#include <cdp/core/triangle_geometry.h>

#include <numeric>

namespace cdp::adaptive::repair {
namespace {

using namespace test_repair;

// The largest distance from triangle (a, b, c), inside the unit sphere, to the sphere: 1 minus
// the distance of the triangle from the centre.
double distance_to_sphere(const Vec3& a, const Vec3& b, const Vec3& c) {
  return 1 - closest_point_on_triangle(Vec3::Zero(), a, b, c).norm();
}

TEST(RepairRefine, SplitsTheTrianglesBeyondTheToleranceUntilWithinIt) {
  const auto field = unit_sphere();
  Mesh mesh = icosphere(1);
  const std::size_t triangles_before = mesh.triangles.size();
  QualityOptions o = sphere_options();
  o.tolerance = 1e-2;
  double worst_before = 0;
  for (const auto& t : mesh.triangles)
    worst_before = std::max(worst_before, distance_to_sphere(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]));
  ASSERT_GT(worst_before, 3 * o.tolerance);

  RepairContext ctx(*field, mesh, o);
  std::vector<int> all(mesh.triangles.size());
  std::iota(all.begin(), all.end(), 0);
  EXPECT_TRUE(refine(ctx, all).empty());
  ctx.compact();

  EXPECT_GT(ctx.report_.splits, 0u);
  EXPECT_EQ(mesh.triangles.size(), triangles_before + 2 * ctx.report_.splits);
  double worst = 0;
  for (const auto& t : mesh.triangles)
    worst = std::max(worst, distance_to_sphere(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]));
  EXPECT_LE(worst, o.tolerance);
  EXPECT_LT(off_sphere(mesh), 1e-9);
  expect_a_sphere(mesh);
}

}  // namespace
}  // namespace cdp::adaptive::repair
