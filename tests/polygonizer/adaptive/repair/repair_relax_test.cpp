// relax (src/adaptive/repair_relax.h) alone, on an icosphere whose vertices were moved along
// the sphere.
#include "src/adaptive/repair_relax.h"

#include "polygonizer/adaptive/repair/repair_fixtures.h"

#include <algorithm>
#include <map>

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

// The unit sphere, not smooth (the repair probes for creases), its calls costly or not as told
// (Field::costly_calls, as a Python function's), each call of it counted.
class CountedCalls final : public Field {
 public:
  CountedCalls(const Field& f, bool costly) : f_(f), costly_(costly) { set_bounds(f.bounds()); }
  std::string type_name() const override { return "counted"; }
  bool costly_calls() const override { return costly_; }
  mutable std::size_t calls = 0;

 protected:
  double eval_value(const Vec3& p) const override { return ++calls, f_.value(p); }
  double eval_value_gradient(const Vec3& p, Vec3& g) const override { return ++calls, f_.value_gradient(p, g); }
  double eval_gradient_hessian(const Vec3& p, Vec3& g, Mat3& h) const override {
    return ++calls, f_.gradient_hessian(p, g, h);
  }
  void eval_values(const Vec3* p, double* out, std::size_t n) const override { ++calls, f_.values(p, out, n); }
  void eval_values_gradients(const Vec3* p, double* v, Vec3* g, std::size_t n) const override {
    ++calls, f_.values_gradients(p, v, g, n);
  }
  void eval_gradients_hessians(const Vec3* p, double* v, Vec3* g, Mat3* h, std::size_t n) const override {
    ++calls, f_.gradients_hessians(p, v, g, h, n);
  }

 private:
  const Field& f_;
  bool costly_;
};

// jittered_sphere with one edge in every few triangles flipped (valences 5 and 7 around it),
// which the relaxation's flips put back.
Mesh flipped_sphere() {
  Mesh mesh = jittered_sphere();
  std::map<std::pair<int, int>, std::vector<int>> edges;
  for (int t = 0; t < static_cast<int>(mesh.triangles.size()); ++t)
    for (int k = 0; k < 3; ++k) edges[std::minmax(mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3])].push_back(t);
  std::vector<char> touched(mesh.triangles.size(), 0);
  for (int t = 0; t < static_cast<int>(mesh.triangles.size()); t += 7) {
    const auto T = mesh.triangles[t];
    const int a = T[0], b = T[1], c = T[2];
    const std::vector<int>& pair = edges[std::minmax(a, b)];
    const int u = pair[0] == t ? pair[1] : pair[0];
    int d = -1;
    for (int w : mesh.triangles[u])
      if (w != a && w != b) d = w;
    if (touched[t] || touched[u] || edges.count(std::minmax(c, d))) continue;
    touched[t] = touched[u] = 1;
    mesh.triangles[t] = {c, a, d};
    mesh.triangles[u] = {d, b, c};
    edges.erase(std::minmax(a, b));
    edges[std::minmax(c, d)] = {t, u};
    std::replace(edges[std::minmax(a, d)].begin(), edges[std::minmax(a, d)].end(), u, t);
    std::replace(edges[std::minmax(b, c)].begin(), edges[std::minmax(b, c)].end(), t, u);
  }
  return mesh;
}

// `mesh` relaxed on the unit sphere told costly or not (CountedCalls), and the calls it made.
struct CostlyOrNot {
  Mesh mesh;
  QualityReport report;
  std::size_t calls = 0;
};
CostlyOrNot relaxed_counting(bool costly, Mesh mesh, const QualityOptions& o) {
  const auto sphere = unit_sphere();
  const CountedCalls field(*sphere, costly);
  CostlyOrNot r;
  {
    RepairContext ctx(field, mesh, o);
    relax(ctx);
    ctx.compact();
    r.report = ctx.report_;
  }
  r.calls = field.calls;
  r.mesh = std::move(mesh);
  return r;
}

TEST(RepairRelax, ACostlyFieldsFlipsAskForTheirSamplesInBatchesAndMakeTheSameMesh) {
  // prefetch_flip_samples: the flips' crease probes and midpoint distances asked for together
  // before the pass of flips, the same numbers as one at a time.
  const std::array<CostlyOrNot, 2> r{relaxed_counting(false, flipped_sphere(), sphere_options()),
                                     relaxed_counting(true, flipped_sphere(), sphere_options())};
  const std::array<std::size_t, 2> flips{r[0].report.relax_flips, r[1].report.relax_flips};
  const std::array<Mesh, 2> meshes{r[0].mesh, r[1].mesh};
  const std::array<std::size_t, 2> calls{r[0].calls, r[1].calls};
  EXPECT_GT(flips[0], 10u);
  EXPECT_EQ(flips[1], flips[0]);
  EXPECT_EQ(meshes[1].positions, meshes[0].positions);
  EXPECT_EQ(meshes[1].triangles, meshes[0].triangles);
  // 2,539 calls one at a time, 5 batched, when written.
  EXPECT_LT(10 * calls[1], calls[0]) << calls[0] << " calls one at a time, " << calls[1] << " batched";
}

TEST(RepairRelax, ACostlyFieldsMovesWithATolerancePrefetchTheirStarsAndMakeTheSameMesh) {
  // prefetch_stars: with a tolerance, judging a move measures its star before and after it; a
  // costly field's are asked for a chunk of moves at a time, the same numbers as one at a time.
  QualityOptions o = sphere_options();
  o.tolerance = 0.05;
  const std::array<CostlyOrNot, 2> r{relaxed_counting(false, jittered_sphere(), o),
                                     relaxed_counting(true, jittered_sphere(), o)};
  const std::array<std::size_t, 2> relaxed{r[0].report.relaxed, r[1].report.relaxed};
  const std::array<Mesh, 2> meshes{r[0].mesh, r[1].mesh};
  const std::array<std::size_t, 2> calls{r[0].calls, r[1].calls};
  EXPECT_GT(relaxed[0], 50u);
  EXPECT_EQ(relaxed[1], relaxed[0]);
  EXPECT_EQ(meshes[1].positions, meshes[0].positions);
  EXPECT_EQ(meshes[1].triangles, meshes[0].triangles);
  EXPECT_LT(4 * calls[1], calls[0]) << calls[0] << " calls one at a time, " << calls[1] << " prefetched";
}

TEST(RepairContext, ACostlyFieldsDenseSamplesOfATriangleAreProjectedTogether) {
  // sampled_distance: the 28 points of a triangle projected in batched Newton rounds, the same
  // distance as one point at a time.
  const auto sphere = unit_sphere();
  Mesh mesh = icosphere(1);
  std::array<double, 2> d{};
  std::array<std::size_t, 2> calls{};
  for (int costly = 0; costly < 2; ++costly) {
    const CountedCalls field(*sphere, costly == 1);
    RepairContext ctx(field, mesh, sphere_options());
    field.calls = 0;
    d[costly] = ctx.sampled_distance(mesh.triangles[0], -1);
    calls[costly] = field.calls;
  }
  EXPECT_GT(d[0], 0.01);
  EXPECT_EQ(d[1], d[0]);
  EXPECT_LT(4 * calls[1], calls[0]) << calls[0] << " calls one at a time, " << calls[1] << " batched";
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
