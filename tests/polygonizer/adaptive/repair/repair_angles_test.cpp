// repair_angles (src/adaptive/repair_angles.h) alone, on an icosphere with a vertex pushed
// against its neighbour.
#include "src/adaptive/repair_angles.h"

#include "polygonizer/adaptive/repair/repair_fixtures.h"

namespace cdp::adaptive::repair {
namespace {

using namespace test_repair;

TEST(RepairAngles, TrianglesSqueezedAgainstANeighbourAreRepairedOnTheSurface) {
  const auto field = unit_sphere();
  Mesh mesh = icosphere(2);
  // Vertex 0 pushed 85 % of the way towards a neighbour: its star turns into slivers and caps.
  int neighbour = -1;
  for (const auto& t : mesh.triangles)
    if (t[0] == 0) neighbour = t[1];
  ASSERT_GE(neighbour, 0);
  move_on_sphere(mesh, 0, 0.85 * (mesh.positions[neighbour] - mesh.positions[0]));
  const double before = angle_statistics(mesh).min_degrees;
  ASSERT_LT(before, 10);

  const QualityOptions o = sphere_options();
  RepairContext ctx(*field, mesh, o);
  repair_angles(ctx);
  ctx.compact();

  EXPECT_GT(ctx.report_.bad_before, 0u);
  EXPECT_EQ(ctx.report_.bad_after, 0u);
  EXPECT_GE(angle_statistics(mesh).min_degrees, 30);
  EXPECT_GT(ctx.report_.moves + ctx.report_.flips + ctx.report_.collapses + ctx.report_.inserts, 0u);
  EXPECT_LT(off_sphere(mesh), 1e-9);
  expect_a_sphere(mesh);
}

TEST(RepairAngles, AMeshWithinTheBoundIsLeftAsItIs) {
  const auto field = unit_sphere();
  Mesh mesh = icosphere(2);
  const Mesh before = mesh;
  RepairContext ctx(*field, mesh, sphere_options());
  repair_angles(ctx);
  ctx.compact();
  EXPECT_EQ(ctx.report_.bad_before, 0u);
  EXPECT_EQ(mesh.positions, before.positions);
  EXPECT_EQ(mesh.triangles, before.triangles);
}

}  // namespace
}  // namespace cdp::adaptive::repair
