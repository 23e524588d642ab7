// Expression::value_range and derivative_range (interval arithmetic, src/models/interval.h):
// bounds that hold at every point of the box, for every operation of the formula language, and
// tight enough to prove what the seeding asks of them.
#include <gtest/gtest.h>

#include <cdp/core/models/expression.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace cdp {
namespace {

// Formulas that use every operation, several where it is not differentiable or has a jump.
const std::vector<std::string>& formulas() {
  static const std::vector<std::string> f = {
      "sqrt(x^2 + y^2 + z^2) - 1",
      "max(max(abs(x), abs(y)), abs(z)) - 0.8",
      "min(sqrt(x^2+y^2+z^2) - 1, sqrt((x-1.1)^2 + y^2 + z^2) - 0.05)",
      "exp(x) * sin(3*y) - cos(2*z) / (2 + x*y)",
      "log(1.5 + x) + tan(0.6*y) - atan(z*4) + x^3 - y^-2",
      "atan2(y, x) - 0.5 * z",
      "atan2(y + 2, x)",
      "floor(3*x) * 0.1 + mod(y, 0.7) - round(z)",
      "clamp(x + y, -0.3, 0.4) - hypot(y, z) + pow(abs(x) + 0.1, 1.5) + pow(2, y)",
      "min(max(x, y), -z) * 2 - (x - 0.2) * (x - 0.2)",
      "x^6 - 3*y^4 + z^5 - 2*x^2*y^3",
  };
  return f;
}

// Random boxes of sizes from 1e-3 to 2, and points inside each.
template <class Fn>
void for_random_boxes(Fn fn) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> at(-1.5, 1.5), unit(0, 1), size_exp(-3, 0.3);
  for (int b = 0; b < 300; ++b) {
    const Vec3 lo(at(rng), at(rng), at(rng));
    const Vec3 size = Vec3(std::pow(10, size_exp(rng)), std::pow(10, size_exp(rng)), std::pow(10, size_exp(rng)));
    const Box box{lo, lo + size};
    Vec3 u(at(rng), at(rng), at(rng));
    if (u.squaredNorm() == 0) u = Vec3::UnitX();
    u.normalize();
    std::vector<Vec3> points;
    for (int c = 0; c < 8; ++c)
      points.emplace_back(c & 1 ? box.max.x() : box.min.x(), c & 2 ? box.max.y() : box.min.y(),
                          c & 4 ? box.max.z() : box.min.z());
    for (int k = 0; k < 40; ++k)
      points.push_back(box.min + Vec3(unit(rng), unit(rng), unit(rng)).cwiseProduct(size));
    fn(box, u, points);
  }
}

TEST(ExpressionRanges, ValuesAndDirectionalDerivativesLieWithinTheirBounds) {
  const Box bounds{{-3, -3, -3}, {3, 3, 3}};
  for (const std::string& formula : formulas()) {
    SCOPED_TRACE(formula);
    const Expression e(formula, {}, bounds);
    int checked_values = 0, checked_slopes = 0;
    for_random_boxes([&](const Box& box, const Vec3& u, const std::vector<Vec3>& points) {
      const auto values = e.value_range(box);
      const auto slopes = e.derivative_range(box, u);
      ASSERT_TRUE(values && slopes);
      ASSERT_LE(values->first, values->second);
      for (const Vec3& p : points) {
        Vec3 g;
        const double v = e.value_gradient(p, g);
        if (!std::isfinite(v)) continue;
        EXPECT_GE(v, values->first) << p.transpose();
        EXPECT_LE(v, values->second) << p.transpose();
        ++checked_values;
        if (!g.allFinite()) continue;
        EXPECT_GE(g.dot(u), slopes->first) << p.transpose();
        EXPECT_LE(g.dot(u), slopes->second) << p.transpose();
        ++checked_slopes;
      }
    });
    EXPECT_GT(checked_values, 3000);
    EXPECT_GT(checked_slopes, 3000);
  }
}

TEST(ExpressionRanges, ProveWhatTheSeedingAsks) {
  const Box bounds{{-2, -2, -2}, {2, 2, 2}};
  // A unit sphere's distance: a box far from the surface holds no zero, and near the surface
  // away from the centre the derivative along the radius keeps its sign.
  const Expression sphere("sqrt(x^2 + y^2 + z^2) - 1", {}, bounds);
  const Box far{{1.5, 1.5, 1.5}, {1.6, 1.6, 1.6}}, near{{0.95, -0.05, -0.05}, {1.05, 0.05, 0.05}};
  EXPECT_GT(sphere.value_range(far)->first, 0);
  EXPECT_GT(sphere.derivative_range(near, Vec3::UnitX())->first, 0.9);
  // Across a box's edge no axis derivative keeps its sign, but the diagonal's does.
  const Expression cube("max(max(abs(x), abs(y)), abs(z)) - 0.8", {}, bounds);
  const Box edge{{0.75, 0.75, -0.05}, {0.85, 0.85, 0.05}};
  EXPECT_LE(cube.derivative_range(edge, Vec3::UnitX())->first, 0);
  EXPECT_GT(cube.derivative_range(edge, Vec3(1, 1, 0).normalized())->first, 0.7);
  // Around the centre of a small ball beside the sphere, nothing keeps its sign: a critical point.
  const Expression bead("min(sqrt(x^2+y^2+z^2) - 1, sqrt((x-1.1)^2 + y^2 + z^2) - 0.05)", {}, bounds);
  const Box around{{1.05, -0.05, -0.05}, {1.15, 0.05, 0.05}};
  for (const Vec3& u : std::vector<Vec3>{Vec3::UnitX(), Vec3::UnitY(), Vec3(1, 1, 1).normalized()}) {
    const auto r = bead.derivative_range(around, u);
    EXPECT_TRUE(r->first <= 0 && r->second >= 0) << u.transpose();
  }
  // Unbounded where the formula is: the slope of the root at the sphere's centre.
  EXPECT_TRUE(std::isinf(sphere.derivative_range(Box{{-0.1, -0.1, -0.1}, {0.1, 0.1, 0.1}}, Vec3::UnitX())->second));
}

}  // namespace
}  // namespace cdp
