// Expression's programs specialized to the cells of a grid over its box (RegionPrograms in
// src/models/expression.cpp): inside the box an evaluation runs its cell's program, outside it
// the whole formula, and both give the same bits.
#include <gtest/gtest.h>

#include <cdp/core/models/expression.h>

#include "common/same_bits.h"

#include <cmath>
#include <map>
#include <random>
#include <string>
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
  };
  return f;
}

TEST(ExpressionRegions, EvaluationsInsideTheBoxGiveTheBitsOfTheWholeFormula) {
  // The same formula with a box far away runs whole at every point here.
  const Box box{{-2, -2, -2}, {2, 2, 2}}, far{{10, 10, 10}, {11, 11, 11}};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coordinate(-1.8, 1.8), near(-0.2, 0.2);
  std::uniform_int_distribution<int> choice(0, 2);
  std::bernoulli_distribution flip(0.2);
  std::size_t shorter = 0, forced_shorter = 0;
  for (const auto& entry : region_formulas()) {
    const std::string& formula = entry.first;
    const std::map<std::string, std::string>& definitions = entry.second;
    SCOPED_TRACE(formula);
    const RegionProbe here(formula, std::map<std::string, double>{}, box, definitions);
    const RegionProbe whole(formula, std::map<std::string, double>{}, far, definitions);
    const std::size_t n = here.branch_kinds().size();
    // Points about a few centres, so that their cells are evaluated often enough to be
    // specialized; every other one on a plane between cells (16 cells a side here).
    Vec3 centre;
    for (int trial = 0; trial < 4000; ++trial) {
      if (trial % 500 == 0) centre = Vec3(coordinate(rng), coordinate(rng), coordinate(rng));
      Vec3 p = centre + Vec3(near(rng), near(rng), near(rng));
      if (trial % 2) p[trial % 3] = -2 + 0.25 * std::round((p[trial % 3] + 2) / 0.25);
      ASSERT_EQ(whole.instructions_at(p), whole.instructions());
      shorter += here.instructions_at(p) < here.instructions();
      Vec3 g[2], h_g[2];
      Mat3 h[2];
      const double v[2] = {here.value(p), whole.value(p)};
      const double vg[2] = {here.value_gradient(p, g[0]), whole.value_gradient(p, g[1])};
      const double vh[2] = {here.gradient_hessian(p, h_g[0], h[0]), whole.gradient_hessian(p, h_g[1], h[1])};
      ASSERT_TRUE(same_bits(v[0], v[1]) && same_bits(vg[0], vg[1]) && same_bits(vh[0], vh[1])) << p.transpose();
      ASSERT_TRUE(same_bits(g[0], g[1]) && same_bits(h_g[0], h_g[1]) && same_bits(h[0], h[1])) << p.transpose();
      // A piece: each choice free, as the values take it at p, or (one in ten) the other way, so
      // that many runs may run their cell's program and some may not.
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
    }
  }
  // The comparison is of something: most points ran a shorter program, and many pieces did.
  EXPECT_GT(shorter, 4 * 4000 / 2);
  EXPECT_GT(forced_shorter, 4 * 4000 / 8);
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
