// Checks the batched root search of baselines/src/edge_root.h (a header private to the module):
// find_edge_roots gives every edge the root and the evaluation count that find_edge_root gives
// it alone, calls the field once a round, and reports a field that is not finite as the single
// search of the first such edge would.
#include "../../baselines/src/edge_root.h"

#include <cdp/core/errors.h>
#include <cdp/core/models/analytic.h>
#include <cdp/core/models/expression.h>

#include <common/test_fields.h>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace cdp {
namespace {

using marching::EdgeRoot;
using marching::EdgeRootQuery;

// A field from a function, recording the size of every batched call.
class FunctionField : public Field {
 public:
  explicit FunctionField(std::function<double(const Vec3&)> f) : f_(std::move(f)) {}
  std::string type_name() const override { return "function"; }
  mutable std::vector<std::size_t> batches;

 protected:
  double eval_value(const Vec3& p) const override { return f_(p); }
  double eval_value_gradient(const Vec3& p, Vec3& g) const override {
    g = Vec3::Zero();
    return f_(p);
  }
  double eval_gradient_hessian(const Vec3& p, Vec3& g, Mat3& h) const override {
    g = Vec3::Zero();
    h = Mat3::Zero();
    return f_(p);
  }
  void eval_values(const Vec3* points, double* out, std::size_t n) const override {
    batches.push_back(n);
    Field::eval_values(points, out, n);
  }

 private:
  std::function<double(const Vec3&)> f_;
};

// The crossing edges of a lattice of cell h over [lo, hi]^3 (each edge once, in lattice order),
// with F at their ends.
std::vector<EdgeRootQuery> crossing_edges(const Field& field, double lo, double hi, double h) {
  const int n = static_cast<int>(std::lround((hi - lo) / h));
  const auto at = [&](int i, int j, int k) { return Vec3(lo + h * i, lo + h * j, lo + h * k); };
  std::vector<EdgeRootQuery> out;
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const Vec3 a = at(i, j, k);
        const double fa = field.value(a);
        const int next[3][3] = {{i + 1, j, k}, {i, j + 1, k}, {i, j, k + 1}};
        for (const auto& q : next) {
          if (q[0] > n || q[1] > n || q[2] > n) continue;
          const Vec3 b = at(q[0], q[1], q[2]);
          const double fb = field.value(b);
          if ((fa < 0) != (fb < 0)) out.push_back({a, b, fa, fb});
        }
      }
  return out;
}

// Roots and evaluation counts of the batched search equal those of the single one, bit for bit.
void expect_same_as_single(const Field& field, const std::vector<EdgeRootQuery>& edges, double tolerance) {
  ASSERT_FALSE(edges.empty());
  std::vector<EdgeRoot> single;
  const EvaluationCounts before_single = field.counts();
  for (const EdgeRootQuery& e : edges) single.push_back(marching::find_edge_root(field, e.a, e.fa, e.b, e.fb, tolerance));
  const EvaluationCounts before_batch = field.counts();
  std::vector<EdgeRoot> batched;
  marching::find_edge_roots(field, edges, tolerance, batched);
  const EvaluationCounts after = field.counts();
  EXPECT_EQ((before_batch - before_single).value, (after - before_batch).value);
  EXPECT_EQ((after - before_batch).value_gradient, 0u);
  ASSERT_EQ(batched.size(), single.size());
  std::size_t differing = 0;
  long long evaluations = 0;
  for (std::size_t i = 0; i < edges.size(); ++i) {
    evaluations += single[i].evaluations;
    if (batched[i].evaluations != single[i].evaluations || batched[i].point.x() != single[i].point.x() ||
        batched[i].point.y() != single[i].point.y() || batched[i].point.z() != single[i].point.z())
      ++differing;
  }
  EXPECT_EQ(differing, 0u) << "of " << edges.size() << " edges";
  EXPECT_EQ(evaluations, static_cast<long long>((after - before_batch).value));
}

TEST(EdgeRoots, BatchedEqualsSingleOnSmoothFields) {
  const Torus torus({0.01, 0.02, -0.015}, 1.0, 0.4);
  const auto tangle = test::tanglecube();
  const auto blobs = test::three_separate_blobs();
  for (double tolerance : {1e-7, 1e-3, 0.05}) {
    SCOPED_TRACE(tolerance);
    expect_same_as_single(torus, crossing_edges(torus, -1.6, 1.6, 0.1), tolerance);
    expect_same_as_single(*tangle, crossing_edges(*tangle, -3, 3, 0.2), tolerance);
    expect_same_as_single(*blobs, crossing_edges(*blobs, -1.5, 4.5, 0.15), tolerance);
  }
}

// Creases and a plane through lattice points: probes that hit F = 0 exactly, slow secant steps
// that fall back to bisection, roots next to corners.
TEST(EdgeRoots, BatchedEqualsSingleOnCreasesAndExactZeros) {
  const Expression cube("max(abs(x), max(abs(y), abs(z))) - 0.5", {}, Box{{-1, -1, -1}, {1, 1, 1}});
  const Expression plane("x + 0.25 * y - 0.125", {}, Box{{-1, -1, -1}, {1, 1, 1}});
  const Expression steep("(x^2 + y^2 + z^2)^4 - 0.3", {}, Box{{-1, -1, -1}, {1, 1, 1}});
  for (double tolerance : {1e-7, 1e-2}) {
    SCOPED_TRACE(tolerance);
    expect_same_as_single(cube, crossing_edges(cube, -1, 1, 0.125), tolerance);
    expect_same_as_single(plane, crossing_edges(plane, -1, 1, 0.125), tolerance);
    expect_same_as_single(steep, crossing_edges(steep, -1, 1, 0.1), tolerance);
  }
}

TEST(EdgeRoots, OneCallPerRoundForAllEdges) {
  FunctionField sphere([](const Vec3& p) { return p.squaredNorm() - 1; });
  const std::vector<EdgeRootQuery> edges = crossing_edges(sphere, -1.5, 1.5, 0.1);
  sphere.batches.clear();
  std::vector<EdgeRoot> roots;
  marching::find_edge_roots(sphere, edges, 1e-7, roots);
  int most = 0;
  for (const EdgeRoot& r : roots) most = std::max(most, r.evaluations);
  // Round r evaluates the searches that need more than r probes: as many calls as the longest
  // search, the first with every edge.
  ASSERT_EQ(sphere.batches.size(), static_cast<std::size_t>(most));
  EXPECT_EQ(sphere.batches.front(), edges.size());
  for (std::size_t r = 1; r < sphere.batches.size(); ++r) EXPECT_LE(sphere.batches[r], sphere.batches[r - 1]);
}

TEST(EdgeRoots, NotFiniteReportsTheFirstFailingEdgeInOrder) {
  // The sphere, but not finite in two slabs, met by different edges after different probes.
  FunctionField field([](const Vec3& p) {
    if (std::abs(p.z() - 0.52) < 0.03 || std::abs(p.x() + 0.73) < 0.004) return std::numeric_limits<double>::quiet_NaN();
    return p.squaredNorm() - 1;
  });
  // First in order an edge whose root lies in the slab |x + 0.73| < 0.004, which its search
  // reaches after a few probes; later ones fail at their first probe (z = 0.5).
  const double z0 = std::sqrt(1 - 0.73 * 0.73);
  std::vector<EdgeRootQuery> edges{{Vec3(-0.9, 0, z0), Vec3(-0.6, 0, z0), 0, 0}};
  for (double z : {0.9, -0.8, 0.5, 0.1}) {
    const double x = std::sqrt(1 - z * z);
    edges.push_back({Vec3(-x - 0.1, 0, z), Vec3(-x + 0.1, 0, z), 0, 0});
    edges.push_back({Vec3(0, 0, z + 0.05), Vec3(0, 0, z - 0.05), 0, 0});
  }
  for (EdgeRootQuery& e : edges) e.fa = field.value(e.a), e.fb = field.value(e.b);
  std::string single_error;
  for (const EdgeRootQuery& e : edges) {
    if ((e.fa < 0) == (e.fb < 0) || !std::isfinite(e.fa) || !std::isfinite(e.fb)) continue;
    try {
      marching::find_edge_root(field, e.a, e.fa, e.b, e.fb, 1e-9);
    } catch (const NoSurfaceError& err) {
      single_error = err.what();
      break;
    }
  }
  ASSERT_FALSE(single_error.empty()) << "the test's field should fail on some edge";
  std::vector<EdgeRootQuery> valid;
  for (const EdgeRootQuery& e : edges)
    if ((e.fa < 0) != (e.fb < 0) && std::isfinite(e.fa) && std::isfinite(e.fb)) valid.push_back(e);
  std::vector<EdgeRoot> roots;
  try {
    marching::find_edge_roots(field, valid, 1e-9, roots);
    FAIL() << "no error";
  } catch (const NoSurfaceError& err) {
    EXPECT_EQ(std::string(err.what()), single_error);
  }
}

}  // namespace
}  // namespace cdp
