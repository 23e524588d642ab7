// relax (src/adaptive/repair_relax.h) alone, on an icosphere whose vertices were moved along
// the sphere.
#include "src/adaptive/repair_relax.h"

#include "polygonizer/adaptive/repair/repair_fixtures.h"

namespace cdp::adaptive::repair {
namespace {

using namespace test_repair;

// icosphere(3) with every vertex moved along the sphere by up to a third of an edge, in a
// direction of its own (a fixed pattern, no random numbers: the same mesh everywhere).
Mesh jittered_sphere() {
  Mesh mesh = icosphere(3);
  const double edge = (mesh.positions[mesh.triangles[0][0]] - mesh.positions[mesh.triangles[0][1]]).norm();
  for (int v = 0; v < static_cast<int>(mesh.positions.size()); ++v) {
    const Vec3 n = mesh.normals[v], e1 = n.unitOrthogonal(), e2 = n.cross(e1);
    const double turn = 2.399963 * v, size = edge / 3 * (0.5 + 0.5 * std::sin(1.7 * v));
    move_on_sphere(mesh, v, size * (std::cos(turn) * e1 + std::sin(turn) * e2));
  }
  return mesh;
}

struct Relaxed {
  Mesh mesh;
  double before = 0, after = 0;
  QualityReport report;
};

Relaxed relaxed(int threads, double aim) {
  const auto field = unit_sphere();
  Relaxed r;
  r.mesh = jittered_sphere();
  QualityOptions o = sphere_options();
  o.threads = threads;
  o.aim_mean_edge_ratio = aim;
  RepairContext ctx(*field, r.mesh, o);
  r.before = mean_edge_ratio(ctx);
  relax(ctx);
  r.after = mean_edge_ratio(ctx);
  ctx.compact();
  r.report = ctx.report_;
  return r;
}

TEST(RepairRelax, TheMeanEdgeRatioFallsWithNoVertexAddedAndTheSphereKept) {
  const Mesh input = jittered_sphere();
  const Relaxed r = relaxed(1, 0);
  EXPECT_GT(r.before, 1.35);
  EXPECT_LT(r.after, r.before - 0.05);
  EXPECT_GT(r.report.relaxed, 0u);
  EXPECT_EQ(r.report.relax_search_sweeps, 0u);
  EXPECT_EQ(r.mesh.positions.size(), input.positions.size());
  EXPECT_EQ(r.mesh.triangles.size(), input.triangles.size());
  EXPECT_LT(off_sphere(r.mesh), 1e-9);
  expect_a_sphere(r.mesh);
}

TEST(RepairRelax, SearchSweepsGoOnTowardsTheAimAndTwoThreadsMakeTheSameMesh) {
  const Relaxed plain = relaxed(1, 0), one = relaxed(1, 1.0), two = relaxed(2, 1.0);
  EXPECT_GT(one.report.relax_search_sweeps, 0u);
  EXPECT_LT(one.after, plain.after);
  EXPECT_EQ(one.mesh.positions, two.mesh.positions);
  EXPECT_EQ(one.mesh.triangles, two.mesh.triangles);
  EXPECT_EQ(one.report.relaxed, two.report.relaxed);
  expect_a_sphere(one.mesh);
}

}  // namespace
}  // namespace cdp::adaptive::repair
