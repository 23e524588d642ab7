// Expression's programs specialized to the cells of a grid over its box (RegionPrograms in
// src/models/expression.cpp): inside the box an evaluation runs its cell's program, outside it
// the whole formula, and both give the same bits.
#include <gtest/gtest.h>

#include <cdp/core/models/expression.h>

#include "common/same_bits.h"

#include <atomic>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace cdp {
namespace {

using test::same_bits;

// Expression's protected piece evaluation, for Forced runs.
class RegionProbe : public Expression {
 public:
  using Expression::Expression;
  using Expression::eval_piece;
};

// Unions and smooth unions of many primitives, abs and clamp, subtrees written twice (stored
// where first computed, inside an argument a min may leave out elsewhere), definitions, and
// parts that are NaN or infinite over some of the box (a root of what is negative there, a
// division by what crosses zero): a min lets a NaN through on one side only.
const std::vector<std::pair<std::string, std::map<std::string, std::string>>>& region_formulas() {
  static const std::vector<std::pair<std::string, std::map<std::string, std::string>>> f = {
      {"min(sqrt(x^2+y^2+z^2) - 0.3, sqrt((x-1)^2+y^2+z^2) - 0.3, sqrt((x+1)^2+y^2+z^2) - 0.3, "
       "sqrt(x^2+(y-1)^2+z^2) - 0.3, sqrt(x^2+(y+1)^2+z^2) - 0.3, sqrt((x-1)^2+(y-1)^2+z^2) - 0.3)",
       {}},
      {"min(b - 0.5, max(a, -b), abs(z) - 1.5, min(a + 0.2, b + 0.3) - 0.1 * clamp(x, -0.5, 0.5))",
       {{"a", "max(abs(x) - 1, abs(y) - 0.5, abs(z) - 0.25)"}, {"b", "sqrt(x^2 + y^2) - 1"}}},
      {"min(sqrt(x) - 0.5, max(abs(y) - 1, z), 1 / (x - 0.3) + 10, log(y + 0.5), max(x*x+y*y, 2) - 1.8)", {}},
      {"min(max(abs(x)-1, abs(y)-1, abs(z)-1), max(abs(x-1)-0.5, abs(y)-0.5, abs(z-1)-0.5), "
       "max(abs(x)-1, abs(y)-1, abs(z)-1) + 0.3, sqrt(max(abs(x)-0.5, 0)^2 + max(abs(y)-0.5, 0)^2) - 0.1)",
       {}},
      // Every other function: a power past the small integer ones of a base that may be negative
      // (defined there), a tangent near its poles, cosines near their zeros, steps, atan2's cut.
      {"min(x^66 - 1, 5, abs(tan(1.5*y)) - 3, max(cos(3*x) - 0.2, sin(2*z)), exp(y) - 2.5, "
       "floor(2*x) + round(z) - 1, max(atan2(y, x) - 1, abs(z) - 0.7), max(pow(abs(y) + 0.1, 1.5), abs(x)) - 0.9)",
       {}},
  };
  return f;
}

// Piece evaluations, Jet1 and Jet2, for Forced runs.
class RegionProbe2 : public RegionProbe {
 public:
  using RegionProbe::RegionProbe;
  using Expression::eval_first_order;
};

TEST(ExpressionRegions, EvaluationsInsideTheBoxGiveTheBitsOfTheWholeFormula) {
  // The same formula with a box far away runs whole at every point here. The box's cells (16 a
  // side) have corners that are not exact in binary.
  const Box box{{-2.03, -1.97, -2.01}, {2.11, 2.07, 1.93}}, far{{10, 10, 10}, {11, 11, 11}};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coordinate(-1.8, 1.8), near(-0.2, 0.2);
  std::uniform_int_distribution<int> choice(0, 2);
  std::bernoulli_distribution flip(0.2);
  for (const auto& entry : region_formulas()) {
    std::size_t shorter = 0, forced_shorter = 0;
    const std::string& formula = entry.first;
    const std::map<std::string, std::string>& definitions = entry.second;
    SCOPED_TRACE(formula);
    const RegionProbe2 here(formula, std::map<std::string, double>{}, box, definitions);
    const RegionProbe2 whole(formula, std::map<std::string, double>{}, far, definitions);
    const std::size_t n = here.branch_kinds().size();
    // Points about a few centres, so that their cells are evaluated often enough to be
    // specialized; every other one on a plane between cells (16 cells a side here).
    Vec3 centre;
    for (int trial = 0; trial < 4000; ++trial) {
      if (trial % 500 == 0) centre = Vec3(coordinate(rng), coordinate(rng), coordinate(rng));
      Vec3 p = centre + Vec3(near(rng), near(rng), near(rng));
      if (trial % 2) {
        const int k = trial % 3;
        const double cell = (box.max[k] - box.min[k]) / 16;
        p[k] = box.min[k] + cell * std::round((p[k] - box.min[k]) / cell);
      }
      ASSERT_EQ(whole.instructions_at(p), whole.instructions());
      shorter += here.instructions_at(p) < here.instructions();
      Vec3 g[2], h_g[2];
      Mat3 h[2];
      const double v[2] = {here.value(p), whole.value(p)};
      const double vg[2] = {here.value_gradient(p, g[0]), whole.value_gradient(p, g[1])};
      const double vh[2] = {here.gradient_hessian(p, h_g[0], h[0]), whole.gradient_hessian(p, h_g[1], h[1])};
      ASSERT_TRUE(same_bits(v[0], v[1]) && same_bits(vg[0], vg[1]) && same_bits(vh[0], vh[1])) << p.transpose();
      ASSERT_TRUE(same_bits(g[0], g[1]) && same_bits(h_g[0], h_g[1]) && same_bits(h[0], h[1])) << p.transpose();
      // A piece: each choice free, as the values take it at p, or (one in fifteen) the other way,
      // so that many runs may run their cell's program and some may not.
      Field::BranchRecord natural;
      ASSERT_TRUE(whole.branch_record(p, natural));
      std::vector<std::uint8_t> branch(n);
      for (std::size_t k = 0; k < n; ++k) {
        const int c = choice(rng);
        branch[k] = c == 0 ? Field::kFreeBranch : static_cast<std::uint8_t>(natural.taken[k] ^ (c == 1 && flip(rng)));
      }
      forced_shorter += here.instructions_at(p, branch) < here.instructions();
      const FieldPiece a = here.eval_piece(p, branch), b = whole.eval_piece(p, branch);
      ASSERT_TRUE(same_bits(a.value, b.value) && same_bits(a.gradient, b.gradient) && same_bits(a.hessian, b.hessian))
          << p.transpose();
      const auto a1 = here.eval_first_order(p, branch), b1 = whole.eval_first_order(p, branch);
      ASSERT_TRUE(same_bits(a1.first, b1.first) && same_bits(a1.second, b1.second)) << p.transpose();
    }
    // The comparison is of something: many points ran a shorter program, and many pieces did.
    EXPECT_GT(shorter, 4000u / 4);
    EXPECT_GT(forced_shorter, 4000u / 20);
  }
}

TEST(ExpressionRegions, AnIntegerPowerOfABaseThatMayBeNegativeIsBoundedWhereItIsDefined) {
  // The cell of x in [-0.25, 0] (64 cells of 0.25 along x) has 8x + 0.5 in [-1.5, 0.5]. Bounded
  // as a real power (NaN below zero), its 66th power looked under 1 there, so the min was taken
  // for its first argument: 1.1e10 at x = -0.24, where the formula is 5. (The second argument is
  // long, so that leaving it out is worth a program of the cell's own.)
  const std::string formula =
      "min((8*x + 0.5)^66 - 1, 5 + 0 * (y^3 + z^3 + y*z + sin(y) + cos(z) + exp(y*z) + abs(y) + abs(z) + abs(y - z)))";
  const Expression here(formula, Box{{-8, -0.1, -0.1}, {8, 0.1, 0.1}}),
      whole(formula, Box{{10, 10, 10}, {11, 11, 11}});
  const Vec3 p(-0.24, 0.01, 0.02);
  for (int k = 0; k < 100; ++k) here.value(p);
  EXPECT_TRUE(same_bits(here.value(p), whole.value(p)));
  EXPECT_EQ(here.value(p), 5);
  // Bounded as defined, the first argument's range reaches above 5: nothing to leave out.
  EXPECT_EQ(here.instructions_at(p), here.instructions());
  const auto range = here.value_range(Box{{-0.25, 0, 0}, {0, 0.05, 0.05}});
  ASSERT_TRUE(range.has_value());
  EXPECT_GE(range->second, 5);
}

TEST(ExpressionRegions, ThreadsShareTheCellsPrograms) {
  // Two threads evaluating about the same points make and read the same cells' programs.
  std::string formula = "min(";
  for (int i = 0; i < 12; ++i)
    formula += (i ? ", " : "") + std::string("sqrt((x-") + std::to_string(0.3 * (i % 4) - 0.45) + ")^2+(y-" +
               std::to_string(0.4 * (i / 4) - 0.4) + ")^2+z^2) - 0.2";
  formula += ")";
  const Box box{{-1, -1, -1}, {1, 1, 1}}, far{{10, 10, 10}, {11, 11, 11}};
  const Expression here(formula, box), whole(formula, far);
  std::vector<Vec3> points;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> coordinate(-0.9, 0.9);
  for (int i = 0; i < 400; ++i) points.emplace_back(coordinate(rng), coordinate(rng), coordinate(rng));
  std::vector<double> expected(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) expected[i] = whole.value(points[i]);
  std::atomic<int> wrong{0};
  const auto work = [&] {
    for (int round = 0; round < 100; ++round)
      for (std::size_t i = 0; i < points.size(); ++i) wrong += !same_bits(here.value(points[i]), expected[i]);
  };
  std::thread other(work);
  work();
  other.join();
  EXPECT_EQ(wrong.load(), 0);
  std::size_t shorter = 0;
  for (const Vec3& p : points) shorter += here.instructions_at(p) < here.instructions();
  EXPECT_GT(shorter, points.size() / 2);
}

TEST(ExpressionRegions, AUnionOfManyPrimitivesRunsAFewNearEachPoint) {
  // 27 balls on a grid: near one of them, the program of one or two, once its cell has been
  // evaluated often enough to be specialized.
  std::string formula = "min(";
  for (int i = 0; i < 27; ++i)
    formula += (i ? ", " : "") + std::string("sqrt((x-") + std::to_string(i % 3 - 1) + ")^2+(y-" +
               std::to_string(i / 3 % 3 - 1) + ")^2+(z-" + std::to_string(i / 9 - 1) + ")^2) - 0.3";
  formula += ")";
  const Expression f(formula, Box{{-1.5, -1.5, -1.5}, {1.5, 1.5, 1.5}});
  for (const Vec3& p : {Vec3(0.31, 0.01, 0.02), Vec3(-0.7, 1.28, -1.03)}) {
    EXPECT_EQ(f.instructions_at(p), f.instructions());
    for (int k = 0; k < 100; ++k) f.value(p);
    EXPECT_LT(f.instructions_at(p), f.instructions() / 8);
  }
}

}  // namespace
}  // namespace cdp
