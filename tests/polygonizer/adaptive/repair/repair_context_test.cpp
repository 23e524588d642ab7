// RepairContext's distance estimates (src/adaptive/repair_context.h): the edge midpoints
// predicted from their ends' derivatives against the field's own values there, on the unit
// sphere and across a C1 seam, and the tolerance's refinement with and without them against the
// sphere's distance in closed form and on any number of threads.
#include "src/adaptive/repair_refine.h"

#include "polygonizer/adaptive/repair/repair_fixtures.h"

#include <cdp/core/triangle_geometry.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>

namespace cdp::adaptive::repair {
namespace {

using namespace test_repair;

// z = k max(x, 0)^2 / 2: a plane that bends into a parabola along x = 0, where the second
// derivative jumps (C1, as a rounded box's face meets its fillet). Declared smooth, as a
// compiled model's author may, so that the predictions are asked.
class SeamField final : public Field {
 public:
  explicit SeamField(double k) : k_(k) { set_bounds(Box{Vec3::Constant(-2), Vec3::Constant(2)}); }
  std::string type_name() const override { return "seam"; }
  bool smooth() const override { return true; }
  bool thread_safe() const override { return true; }
  // The surface point above (x, y).
  Vec3 on_surface(double x, double y) const { return {x, y, 0.5 * k_ * std::pow(std::max(x, 0.0), 2)}; }

 protected:
  double eval_value(const Vec3& p) const override { return p.z() - 0.5 * k_ * std::pow(std::max(p.x(), 0.0), 2); }
  double eval_value_gradient(const Vec3& p, Vec3& g) const override {
    g = {-k_ * std::max(p.x(), 0.0), 0, 1};
    return eval_value(p);
  }
  double eval_gradient_hessian(const Vec3& p, Vec3& g, Mat3& h) const override {
    h = Mat3::Zero();
    h(0, 0) = p.x() > 0 ? -k_ : 0;
    return eval_value_gradient(p, g);
  }

 private:
  double k_;
};

// Every edge's predicted midpoint on the sphere is within its own error bound of the field's
// signed distance there, and the bound is far under the tolerance (so the estimates spend no
// evaluation at the midpoints), the centroids likewise; the triangles' estimates are those of a
// context that measures, raised a little by the bounds.
TEST(RepairContext, PredictedMidpointsAndCentroidsMatchTheFieldOnTheSphere) {
  const auto field = unit_sphere();
  Mesh mesh = icosphere(3);
  QualityOptions o = sphere_options();
  o.tolerance = 1e-2;
  o.predict_estimates = QualityOptions::Predict::Always;  // the sphere is cheap: not by default
  RepairContext ctx(*field, mesh, o);
  ASSERT_TRUE(ctx.predict_);
  for (const Tri& t : mesh.triangles) {
    std::array<RepairContext::Mid, 3> mids;
    for (int i = 0; i < 3; ++i) {
      const int x = t[i], y = t[(i + 1) % 3];
      const std::optional<RepairContext::Mid> m = ctx.predicted_midpoint(x, y);
      ASSERT_TRUE(m);
      const double measured = ctx.signed_distance(0.5 * (mesh.positions[x] + mesh.positions[y]));
      EXPECT_LE(std::abs(m->d - measured), m->u + 1e-15);
      EXPECT_LT(m->u, 1e-2 * o.tolerance);
      EXPECT_LT(m->d, -0.1 * o.tolerance);  // a chord's midpoint lies inside, well measurable
      mids[i] = *m;
    }
    const std::optional<RepairContext::Mid> c = ctx.predicted_centroid(t, mids);
    ASSERT_TRUE(c);
    const double measured = ctx.signed_distance((mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3);
    EXPECT_LE(std::abs(c->d - measured), c->u + 1e-15);
    EXPECT_LT(c->u, 1e-2 * o.tolerance);
  }
  // And so the triangles' estimates, against a context that measures.
  QualityOptions measuring = o;
  measuring.predict_estimates = QualityOptions::Predict::Never;
  Mesh copy = mesh;
  const RepairContext measured(*field, copy, measuring);
  // The predicted ones at or above, by their bounds: 1.2 % at most.
  for (const Tri& t : mesh.triangles) {
    const double p = ctx.estimate_distance(t), m = measured.estimate_distance(t);
    EXPECT_GE(p, (1 - 1e-4) * m);
    EXPECT_LT(p, 1.03 * m);
  }
}

// Across the seam the two predictions disagree: the midpoints of edges across it are measured or
// within their bound of the field's value, and only those are measured.
TEST(RepairContext, APredictionAcrossAC1SeamIsMeasuredOrWithinItsBound) {
  const SeamField field(4.0);
  Mesh mesh;
  const double length = 0.1;  // sagitta on the parabola k L^2 / 8 = 5e-3
  int refused = 0, kept = 0;
  for (int i = 0; i <= 40; ++i) {
    const double x0 = -length + i * (2 * length / 40);
    mesh.positions.push_back(field.on_surface(x0, 0));
    mesh.positions.push_back(field.on_surface(x0 + length, 0.01));
  }
  mesh.normals.assign(mesh.positions.size(), Vec3::UnitZ());
  for (int i = 0; i + 2 < static_cast<int>(mesh.positions.size()); i += 2) mesh.triangles.push_back({i, i + 1, i + 2});
  QualityOptions o = sphere_options();
  o.tolerance = 5e-3;
  o.predict_estimates = QualityOptions::Predict::Always;
  RepairContext ctx(field, mesh, o);
  ASSERT_TRUE(ctx.predict_);
  for (int i = 0; i + 1 < static_cast<int>(mesh.positions.size()); i += 2) {
    const Vec3 a = mesh.positions[i], b = mesh.positions[i + 1];
    const double measured = ctx.signed_distance(0.5 * (a + b));
    const std::optional<RepairContext::Mid> m = ctx.predicted_midpoint(i, i + 1);
    if (!m) {
      // Only an edge across the seam or ending on it: on either side the field is a quadratic,
      // exactly predicted.
      EXPECT_TRUE(a.x() < 1e-12 && b.x() > 0) << "edge from x = " << a.x();
      ++refused;
      continue;
    }
    ++kept;
    // The bound is the value's; the gradient's length, predicted exactly for quartics, moves the
    // distance by far less (3e-6 where the seam halves the edge, whose values A and H get exactly).
    EXPECT_LE(std::abs(m->d - measured), m->u + 1e-3 * o.tolerance) << "edge from x = " << a.x();
  }
  EXPECT_GT(refused, 10);
  EXPECT_GT(kept, 10);  // both sides' own edges: a plane, a parabola
  // The sample the estimate falls back to is the field's own.
  const RepairContext::Mid across = ctx.midpoint_sample(10, 11);
  EXPECT_EQ(across.u, -1);
}

// The refinement with predicted estimates keeps the tolerance (closed form) as the measured one
// does, with a fraction of the value-and-gradient evaluations: one Hessian a vertex instead.
TEST(RepairContext, TheRefinementKeepsTheToleranceWithPredictedEstimates) {
  const auto field = unit_sphere();
  EvaluationCounts spent[2];
  std::size_t triangles[2];
  for (const bool predict : {false, true}) {
    SCOPED_TRACE(predict ? "predicted" : "measured");
    Mesh mesh = icosphere(2);
    QualityOptions o = sphere_options();
    o.tolerance = 1e-3;
    o.predict_estimates = predict ? QualityOptions::Predict::Always : QualityOptions::Predict::CostlyFields;
    o.measure_near_bound = false;  // its dense samples are projections either way
    field->reset_counts();
    RepairContext ctx(*field, mesh, o);
    EXPECT_EQ(ctx.predict_, predict);  // the sphere's points are cheap
    std::vector<int> all(mesh.triangles.size());
    std::iota(all.begin(), all.end(), 0);
    EXPECT_TRUE(refine(ctx, all).empty());
    ctx.compact();
    spent[predict] = field->counts();
    triangles[predict] = mesh.triangles.size();
    double worst = 0;
    for (const auto& t : mesh.triangles)
      worst = std::max(worst, 1 - closest_point_on_triangle(Vec3::Zero(), mesh.positions[t[0]], mesh.positions[t[1]],
                                                              mesh.positions[t[2]]).norm());
    EXPECT_LE(worst, o.tolerance);
    EXPECT_GT(worst, 0.5 * o.tolerance);  // refined to the tolerance, not far past it
    expect_a_sphere(mesh);
  }
  // The same refinement up to the triangles at the bound that either estimate may split (the
  // icosphere's are nearly all alike): 11,300 and 11,740 triangles when written.
  EXPECT_NEAR(double(triangles[true]) / double(triangles[false]), 1.0, 0.06);
  EXPECT_EQ(spent[false].gradient_hessian, 0u);
  // 13.8k against 66.8k: the splits' projections.
  EXPECT_LT(3 * spent[true].value_gradient, spent[false].value_gradient);
  EXPECT_LE(spent[true].gradient_hessian, triangles[true]);  // a vertex's jet once: V = T / 2 + 2
}

// With predicted estimates the refinement is the same, mesh and evaluation counts, on one thread
// and on three, and for a field that is not thread-safe (the predictions and measurements decided
// alike in both branches of its estimates).
TEST(RepairContext, PredictedEstimatesAreTheSameOnAnyThreadsAndInBatches) {
  const auto shared = unit_sphere();
  // Not thread-safe, as a Python function given with its derivatives: the estimates in batches.
  const test::Rewrapped unshared(*shared, true, false);
  ASSERT_TRUE(shared->thread_safe());
  ASSERT_FALSE(unshared.thread_safe());
  struct Outcome {
    Mesh mesh;
    EvaluationCounts spent;
  };
  const auto refined = [](const Field& field, int threads) {
    Outcome out{icosphere(2), {}};
    QualityOptions o = sphere_options();
    o.tolerance = 1e-3;  // refined over several rounds
    o.threads = threads;
    o.measure_near_bound = false;
    o.predict_estimates = QualityOptions::Predict::Always;
    field.reset_counts();
    RepairContext ctx(field, out.mesh, o);
    std::vector<int> all(out.mesh.triangles.size());
    std::iota(all.begin(), all.end(), 0);
    EXPECT_TRUE(refine(ctx, all).empty());
    ctx.compact();
    out.spent = field.counts();
    return out;
  };
  const Outcome one = refined(*shared, 1), three = refined(*shared, 3), batched = refined(unshared, 1);
  EXPECT_GT(one.spent.gradient_hessian, 0u);
  EXPECT_GT(one.mesh.triangles.size(), 20 * icosphere(2).triangles.size());
  for (const Outcome* other : {&three, &batched}) {
    EXPECT_EQ(one.mesh.positions, other->mesh.positions);
    EXPECT_EQ(one.mesh.triangles, other->mesh.triangles);
    EXPECT_EQ(one.spent.value_gradient, other->spent.value_gradient);
    EXPECT_EQ(one.spent.gradient_hessian, other->spent.gradient_hessian);
  }
}

// Uniform numbers in [0, 1) from a 64-bit linear congruential generator: the same on every machine.
struct Uniform {
  std::uint64_t state;
  double operator()() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) / 9007199254740992.0;
  }
};

// min_angle takes the arc tangent at the corner facing the shortest edge (and at corners whose
// edges tie with it): the least of the three corners' angle_at, bit for bit, on triangles of
// every shape but slivers, exact isosceles and equilateral ones (ties) among them.
TEST(RepairContext, MinAngleIsTheLeastOfTheThreeCorners) {
  const auto three = [](const Vec3& a, const Vec3& b, const Vec3& c) {
    return std::min({angle_at(a, b, c), angle_at(b, c, a), angle_at(c, a, b)});
  };
  Uniform uniform{12345ull};
  std::size_t tested = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 a(uniform(), uniform(), uniform()), b(uniform(), uniform(), uniform()), c(uniform(), uniform(), uniform());
    if (three(a, b, c) < 1e-3) continue;  // a sliver: its cross product is rounding
    ++tested;
    ASSERT_EQ(min_angle(a, b, c), three(a, b, c)) << i;
  }
  EXPECT_GT(tested, 19000u);
  const double h = std::sqrt(3.0) / 2;
  for (const auto& [a, b, c] : {std::array<Vec3, 3>{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, h, 0)},
                                std::array<Vec3, 3>{Vec3(0.1, 0.2, 0.3), Vec3(1.1, 0.2, 0.3), Vec3(0.6, 3.2, 0.3)},
                                std::array<Vec3, 3>{Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(1, 0.1, 0)},
                                std::array<Vec3, 3>{Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(1, 0, 0)}})
    EXPECT_EQ(min_angle(a, b, c), three(a, b, c)) << a.transpose() << " | " << b.transpose() << " | " << c.transpose();
}

// quadratic_max is the largest |q| of q = 4 (x a b + y b c + z c a) over the triangle: at least
// every sample of a fine barycentric grid (to rounding), and within that grid's spacing of its
// largest sample, on random midpoint values of either sign, equal ones (the maximum at the
// centroid, 4/3 of them), and degenerate ones (D = 0).
TEST(RepairContext, QuadraticMaxIsTheLargestOverTheTriangle) {
  constexpr int kSteps = 240;
  const auto sampled = [](double x, double y, double z) {
    double best = 0;
    for (int i = 0; i <= kSteps; ++i)
      for (int j = 0; i + j <= kSteps; ++j) {
        const double a = double(i) / kSteps, b = double(j) / kSteps, c = 1 - a - b;
        best = std::max(best, std::abs(4 * (x * a * b + y * b * c + z * c * a)));
      }
    return best;
  };
  Uniform uniform{777ull};
  std::size_t inside = 0;
  for (int i = 0; i < 3000; ++i) {
    // Mostly of one sign, as on a curved surface, some of mixed signs.
    const double s = i % 4 == 0 ? -1 : 1;
    const double x = uniform() + 0.2, y = s * (uniform() + 0.2), z = (i % 3 == 0 ? -1 : 1) * (uniform() + 0.2);
    const double got = RepairContext::quadratic_max(x, y, z), want = sampled(x, y, z);
    const double edges = std::max({std::abs(x), std::abs(y), std::abs(z)});
    inside += got > edges;
    ASSERT_GE(got, want * (1 - 1e-12)) << x << " " << y << " " << z;
    ASSERT_LE(got, want * (1 + 1e-4)) << x << " " << y << " " << z;
  }
  EXPECT_GT(inside, 1000u);  // the critical point inside, above the edges' largest
  EXPECT_DOUBLE_EQ(RepairContext::quadratic_max(0.3, 0.3, 0.3), 0.4);
  EXPECT_DOUBLE_EQ(RepairContext::quadratic_max(-0.3, -0.3, -0.3), 0.4);
  EXPECT_EQ(RepairContext::quadratic_max(0, 0, 0), 0);
  // D = 0: x = y = 1, z = 4 (2 (1 + 4 + 4) - 18 = 0), and z = 0 with x = y (a parabolic cylinder).
  EXPECT_DOUBLE_EQ(RepairContext::quadratic_max(1, 1, 4), sampled(1, 1, 4));
  EXPECT_NEAR(RepairContext::quadratic_max(1, 1, 0), sampled(1, 1, 0), 1e-4);
  // The estimate: the quadratic scaled to meet the centroid's sample, and the samples.
  EXPECT_DOUBLE_EQ(RepairContext::estimate_from_samples(0.3, 0.3, 0.3, 0.8), 0.8);
  EXPECT_DOUBLE_EQ(RepairContext::estimate_from_samples(0.3, 0.3, 0.3, 0.2), 0.4);
  EXPECT_EQ(RepairContext::estimate_from_samples(0.3, 0.3, std::nan(""), 0.2), std::numeric_limits<double>::infinity());
}

// tri_below skips the arc tangent only where the angle is clearly above the bound: the same
// answer as tri_min_angle(t) < improve_below on random triangles, on isosceles triangles whose
// apex angle is the bound to within a few units in the last place (either side), and on
// degenerate ones.
TEST(RepairContext, TriBelowIsTheSmallestAngleUnderTheBound) {
  SeamField field(1);
  Mesh mesh;
  Uniform uniform{4242ull};
  for (int i = 0; i < 30000; ++i) mesh.positions.push_back(Vec3(uniform(), uniform(), uniform()));
  const double bound = 30 * std::numbers::pi / 180;
  // Isosceles: apex at the origin, the apex angle the bound plus k units in the last place.
  for (int k = -40; k <= 40; ++k) {
    const double angle = bound + k * std::numeric_limits<double>::epsilon();
    const int at = static_cast<int>(mesh.positions.size());
    mesh.positions.push_back(Vec3(0.3, 0.1, 0.2));
    mesh.positions.push_back(Vec3(0.3, 0.1, 0.2) + Vec3(1, 0, 0));
    mesh.positions.push_back(Vec3(0.3, 0.1, 0.2) + Vec3(std::cos(angle), std::sin(angle), 0));
    mesh.triangles.push_back({at, at + 1, at + 2});
  }
  for (int i = 0; i + 2 < 30000; i += 3) mesh.triangles.push_back({i, i + 1, i + 2});
  mesh.triangles.push_back({0, 0, 1});  // degenerate
  mesh.positions.push_back(Vec3(std::nan(""), 0, 0));
  mesh.triangles.push_back({0, 1, static_cast<int>(mesh.positions.size()) - 1});
  mesh.normals.assign(mesh.positions.size(), Vec3::UnitZ());
  QualityOptions o = sphere_options();
  o.improve_below = bound;
  RepairContext ctx(field, mesh, o);
  std::size_t below = 0;
  for (const Tri& t : mesh.triangles) {
    const bool want = ctx.tri_min_angle(t) < bound;
    below += want;
    ASSERT_EQ(ctx.tri_below(t), want) << t[0];
  }
  EXPECT_GT(below, 2000u);
}

// intersects (one query of the hash over the added triangles' box, the floating-point filters
// before the exact test) answers as every added triangle tested exactly against every live
// triangle not ignored: on an icosphere, stars of a vertex moved by up to a few edges (into and
// through its neighbours) and splits of random edges by a vertex placed within a few edges.
TEST(RepairContext, IntersectsIsTheExactTestOfEveryPair) {
  const auto field = unit_sphere();
  Mesh mesh = icosphere(3);
  RepairContext ctx(*field, mesh, sphere_options());
  Uniform uniform{99ull};
  const double edge = (mesh.positions[mesh.triangles[0][0]] - mesh.positions[mesh.triangles[0][1]]).norm();
  const auto brute = [&](const std::vector<Tri>& added, const std::vector<int>& ignored, int mv, const Vec3& moved) {
    const auto pos = [&](int v) { return v == mv ? moved : mesh.positions[v]; };
    for (const Tri& a : added) {
      const std::array<Vec3, 3> pa{pos(a[0]), pos(a[1]), pos(a[2])};
      for (int u = 0; u < static_cast<int>(mesh.triangles.size()); ++u) {
        if (std::find(ignored.begin(), ignored.end(), u) != ignored.end()) continue;
        const Tri& x = mesh.triangles[u];
        if (triangles_intersect(pa, {pos(x[0]), pos(x[1]), pos(x[2])})) return true;
      }
    }
    return false;
  };
  std::size_t hits = 0, misses = 0;
  for (int i = 0; i < 600; ++i) {
    const int v = static_cast<int>(uniform() * static_cast<double>(mesh.positions.size()));
    const Vec3 moved = mesh.positions[v] + 6 * edge * Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5);
    std::vector<Tri> star;
    for (int u : ctx.vt_[v]) star.push_back(mesh.triangles[u]);
    const bool want = brute(star, ctx.vt_[v], v, moved);
    ASSERT_EQ(ctx.intersects(star, ctx.vt_[v], v, moved), want) << i;
    (want ? hits : misses)++;
    // A split of edge k of triangle t: a new vertex (an id past the mesh's) anywhere within a
    // few edges of the edge's middle, joined to its ends and the two apexes.
    const int t = static_cast<int>(uniform() * static_cast<double>(mesh.triangles.size()));
    const int k = static_cast<int>(uniform() * 3);
    const Tri T = mesh.triangles[t];
    const int a = T[k], b = T[(k + 1) % 3], c = T[(k + 2) % 3];
    const int u = ctx.across(t, a, b);
    ASSERT_GE(u, 0);
    int d = -1;
    for (int w : mesh.triangles[u])
      if (w != a && w != b) d = w;
    const int m = static_cast<int>(mesh.positions.size());
    const Vec3 at = 0.5 * (mesh.positions[a] + mesh.positions[b]) + 5 * edge * Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5);
    const std::vector<Tri> split{Tri{a, m, c}, Tri{m, b, c}, Tri{b, m, d}, Tri{m, a, d}};
    const bool want_split = brute(split, {t, u}, m, at);
    ASSERT_EQ(ctx.intersects(split, {t, u}, m, at), want_split) << i;
    (want_split ? hits : misses)++;
  }
  EXPECT_GT(hits, 100u);
  EXPECT_GT(misses, 100u);
}

// keep_boundary fixes the ends of every edge held by other than two triangles: an icosphere
// with triangles cut away (boundary edges, one triangle) and one edge given a third triangle
// (non-manifold), against the edges counted over the whole mesh; with a triangle of a repeated
// corner too (that case is left to across).
TEST(RepairContext, TheBoundaryKeptIsTheEdgesNotHeldByTwoTriangles) {
  const auto field = unit_sphere();
  for (const bool repeated : {false, true}) {
    Mesh mesh = icosphere(2);
    std::vector<Tri> kept;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      if (t % 7 != 3) kept.push_back(mesh.triangles[t]);
    mesh.triangles = kept;
    const Tri first = mesh.triangles[0];
    mesh.positions.push_back(Vec3(0, 0, 2));
    mesh.triangles.push_back({first[0], first[1], static_cast<int>(mesh.positions.size()) - 1});
    if (repeated) mesh.triangles.push_back({first[2], first[2], first[0]});
    mesh.normals.assign(mesh.positions.size(), Vec3::UnitZ());
    std::map<std::pair<int, int>, int> held;
    for (const Tri& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) ++held[std::minmax(t[k], t[(k + 1) % 3])];
    QualityOptions o = sphere_options();
    o.keep_boundary = true;
    RepairContext ctx(*field, mesh, o);
    std::vector<char> want(mesh.positions.size(), 0);
    if (!repeated)
      for (const auto& [edge, n] : held)
        if (n != 2) want[edge.first] = want[edge.second] = 1;
    std::size_t fixed = 0;
    for (int v = 0; v < static_cast<int>(mesh.positions.size()); ++v) {
      fixed += ctx.fixed(v);
      if (!repeated) {
        EXPECT_EQ(ctx.fixed(v), want[v] != 0) << v;
      }
    }
    EXPECT_GT(fixed, 20u);
    if (repeated) {  // as across has it, edge by edge
      for (int t = 0; t < ctx.tri_count(); ++t)
        for (int k = 0; k < 3; ++k) {
          const Tri& x = mesh.triangles[t];
          if (ctx.across(t, x[k], x[(k + 1) % 3]) < 0) {
            EXPECT_TRUE(ctx.fixed(x[k]) && ctx.fixed(x[(k + 1) % 3]));
          }
        }
    }
  }
}

}  // namespace
}  // namespace cdp::adaptive::repair
