// refine (src/adaptive/repair_refine.h) alone, on a coarse icosphere, against the distance of
// a flat triangle from the unit sphere in closed form.
#include "src/adaptive/repair_refine.h"

#include "polygonizer/adaptive/repair/repair_fixtures.h"

#include <numeric>

namespace cdp::adaptive::repair {
namespace {

using namespace test_repair;

// The point of triangle (a, b, c) nearest the origin (Ericson, Real-Time Collision Detection,
// 5.1.5: the vertex, edge or face region the origin projects into).
Vec3 nearest_to_origin(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 p = Vec3::Zero(), ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// The largest distance from triangle (a, b, c), inside the unit sphere, to the sphere: 1 minus
// the distance of the triangle from the centre.
double distance_to_sphere(const Vec3& a, const Vec3& b, const Vec3& c) { return 1 - nearest_to_origin(a, b, c).norm(); }

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
