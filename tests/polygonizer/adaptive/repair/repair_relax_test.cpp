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

TEST(RepairCreases, ProbedTogetherTheVerticesGetTheAnswersAndCountsOfOneAtATime) {
  // A sphere capped by the plane x = 0.5: the icosphere's vertices near the cap's rim straddle
  // the crease, the others see one smooth piece; probe_creases asks for them all in two calls.
  const auto field = test::field_from_json(test::expression("max(sqrt(x^2+y^2+z^2)-1, x-0.5)", 1.5));
  Mesh mesh = icosphere(4);
  const int n = static_cast<int>(mesh.positions.size());
  std::vector<int> all(static_cast<std::size_t>(n));
  for (int v = 0; v < n; ++v) all[static_cast<std::size_t>(v)] = v;
  all.push_back(3);  // a vertex asked for twice is probed once
  Mesh copy = mesh;
  RepairContext alone(*field, mesh, sphere_options()), together(*field, copy, sphere_options());
  field->reset_counts();
  std::size_t creases = 0;
  for (int v = 0; v < n; ++v) creases += alone.on_crease(v);
  const EvaluationCounts one_at_a_time = field->counts();
  field->reset_counts();
  together.probe_creases(all);
  EXPECT_EQ(field->counts().value_gradient, one_at_a_time.value_gradient);
  for (int v = 0; v < n; ++v) EXPECT_EQ(together.on_crease(v), alone.on_crease(v)) << "vertex " << v;
  EXPECT_EQ(field->counts().value_gradient, one_at_a_time.value_gradient);  // cached: no more probes
  EXPECT_GT(creases, 0u);
  EXPECT_LT(creases, static_cast<std::size_t>(n) / 2);
  EXPECT_EQ(together.report_.crease_vertices, creases);
  EXPECT_EQ(alone.report_.crease_vertices, creases);
}

}  // namespace
}  // namespace cdp::adaptive::repair
