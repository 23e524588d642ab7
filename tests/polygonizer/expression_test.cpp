// The formula language: precedence, parameters, functions, and errors that name the position.
#include <gtest/gtest.h>

#include <cdp/core/errors.h>
#include <cdp/core/models/expression.h>

#include <cstring>
#include <functional>
#include <memory>
#include <span>
#include <numbers>
#include <random>

namespace cdp {
namespace {

double eval(const std::string& formula, const Vec3& p = Vec3(0.5, -1.5, 2.0),
            const std::map<std::string, double>& params = {}) {
  Expression e(formula, params, Box{{-1, -1, -1}, {1, 1, 1}});
  return e.value(p);
}

std::string error_of(const std::string& formula, const std::map<std::string, double>& params = {}) {
  try {
    Expression e(formula, params, Box{{-1, -1, -1}, {1, 1, 1}});
  } catch (const InvalidInputError& err) {
    return err.what();
  }
  return "";
}

TEST(Expression, FollowsTheUsualPrecedence) {
  EXPECT_DOUBLE_EQ(eval("1 + 2 * 3"), 7);
  EXPECT_DOUBLE_EQ(eval("(1 + 2) * 3"), 9);
  EXPECT_DOUBLE_EQ(eval("-2^2"), -4);        // unary minus binds looser than ^
  EXPECT_DOUBLE_EQ(eval("2^3^2"), 512);      // ^ is right-associative
  EXPECT_DOUBLE_EQ(eval("2^-1"), 0.5);
  EXPECT_DOUBLE_EQ(eval("8 / 4 / 2"), 1);    // / is left-associative
  EXPECT_DOUBLE_EQ(eval("1 - 2 - 3"), -4);
  EXPECT_DOUBLE_EQ(eval("x + 10*y + 100*z"), 0.5 - 15 + 200);
  EXPECT_DOUBLE_EQ(eval("y^4"), std::pow(-1.5, 4));  // integer powers of negative numbers
  EXPECT_DOUBLE_EQ(eval("y^3"), std::pow(-1.5, 3));
  EXPECT_DOUBLE_EQ(eval("1.5e2 + .5"), 150.5);
}

TEST(Expression, KnowsParametersPiAndFunctions) {
  EXPECT_DOUBLE_EQ(eval("a * x + b", Vec3(2, 0, 0), {{"a", 3}, {"b", -1}}), 5);
  EXPECT_DOUBLE_EQ(eval("pi"), std::numbers::pi);
  EXPECT_DOUBLE_EQ(eval("sqrt(16) + exp(0) + log(1) + sin(0) + cos(0) + tan(0)"), 6);
  EXPECT_DOUBLE_EQ(eval("abs(-3) + min(2, 5) + max(2, 5) + pow(2, 10)"), 3 + 2 + 5 + 1024);
}

// The functions SDF code uses: clamp, atan2, steps, hypot, min and max of many arguments, **.
TEST(Expression, KnowsTheFunctionsDistanceFieldsUse) {
  EXPECT_DOUBLE_EQ(eval("clamp(x, 0, 1) + clamp(y, -1, 1) + clamp(z, 0, 1)"), 0.5 - 1 + 1);
  EXPECT_DOUBLE_EQ(eval("atan2(1, -1)"), 0.75 * std::numbers::pi);
  EXPECT_DOUBLE_EQ(eval("atan(1)"), 0.25 * std::numbers::pi);
  EXPECT_DOUBLE_EQ(eval("floor(y) + round(x) + round(-2.5)"), -2 + 1 - 3);  // round: half away from zero
  EXPECT_DOUBLE_EQ(eval("mod(7, 3) + mod(-1, 3) + mod(1, -3)"), 1 + 2 - 2);  // the sign of the divisor
  EXPECT_DOUBLE_EQ(eval("hypot(3, 4) + hypot(1, 2, 2)"), 5 + 3);
  EXPECT_DOUBLE_EQ(eval("min(3, x, 2, z) + max(1, y, 7, -4)"), 0.5 + 7);
  EXPECT_DOUBLE_EQ(eval("2**3**2 + -2**2 + 2 * 3**2"), 512 - 4 + 18);  // ** is ^
}

// Each new function's gradient and Hessian against central differences of the values.
TEST(Expression, NewFunctionsHaveExactDerivatives) {
  const Box box{{-2, -2, -2}, {2, 2, 2}};
  for (const char* f : {"atan2(y - 0.3, x + 0.2) * z", "atan(x * y) + z", "hypot(x, 2 * y, z + 1)",
                        "mod(x * y, 0.7) + z", "clamp(x * y, -0.5, 0.5) + z^2", "floor(3 * x) + y * z"}) {
    SCOPED_TRACE(f);
    const Expression e(f, {}, box);
    const Vec3 p(0.37, 0.61, -0.45);
    Vec3 g;
    Mat3 H;
    e.gradient_hessian(p, g, H);
    const double h = 1e-5;
    for (int i = 0; i < 3; ++i) {
      const Vec3 d = h * Vec3::Unit(i);
      EXPECT_NEAR(g[i], (e.value(p + d) - e.value(p - d)) / (2 * h), 1e-7);
      const Vec3 dg = (e.gradient(p + d) - e.gradient(p - d)) / (2 * h);
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(H(j, i), dg[j], 1e-6);
    }
  }
}

// Named sub-expressions: used by name in any order, each evaluated once, errors named.
TEST(Expression, DefinitionsNameSubExpressions) {
  const Box box{{-1, -1, -1}, {1, 1, 1}};
  const Expression e("min(a, b) - k", {{"r", 0.5}}, box,
                     {{"b", "sqrt((x - 1)^2 + y^2 + z^2) - r"}, {"a", "sqrt(x^2 + y^2 + z^2) - r"}, {"k", "r / 5"}});
  const Vec3 p(0.2, 0.1, -0.3);
  EXPECT_DOUBLE_EQ(e.value(p), std::min(p.norm() - 0.5, (p - Vec3(1, 0, 0)).norm() - 0.5) - 0.1);
  const Expression chained("c", {}, box, {{"c", "b + 1"}, {"b", "a * 2"}, {"a", "x"}});
  EXPECT_DOUBLE_EQ(chained.value(Vec3(3, 0, 0)), 7);
  // Derivatives pass through the slots.
  Vec3 g;
  Mat3 H;
  const Expression squared("u * u", {}, box, {{"u", "x * y"}});
  squared.gradient_hessian(Vec3(2, 3, 0), g, H);
  EXPECT_DOUBLE_EQ(g.x(), 2 * 6 * 3);
  EXPECT_DOUBLE_EQ(H(0, 1), 4 * 2 * 3);
  // A definition nobody uses adds no branch point.
  EXPECT_FALSE(Expression("x", {}, box, {{"unused", "abs(y)"}}).has_pieces());
  const auto error_with = [&](const std::string& f, const std::map<std::string, std::string>& d,
                              const std::map<std::string, double>& params = {}) {
    try {
      Expression bad(f, params, box, d);
    } catch (const InvalidInputError& err) {
      return std::string(err.what());
    }
    return std::string();
  };
  EXPECT_EQ(error_with("a", {{"a", "b"}, {"b", "a + 1"}}), "expression: in definition 'b': definition 'a' refers to itself at position 1");
  EXPECT_EQ(error_with("a", {{"a", "x +"}}), "expression: in definition 'a': unexpected end of formula at position 4");
  EXPECT_EQ(error_with("a", {{"x", "1"}}), "expression: definition 'x' shadows a built-in name");
  EXPECT_EQ(error_with("a", {{"a", "1"}}, {{"a", 2}}), "expression: 'a' is both a parameter and a definition");
  EXPECT_EQ(error_with("a", {{"2a", "1"}}), "expression: definition name '2a' is not a name (letters, digits, _)");
}

TEST(Expression, ASubtreeWrittenTwiceIsOneBranchPoint) {
  // The smooth union's clamp written out at each use, as people write it without "define":
  // shared, its min and max are two branch points, not six, and C1 (Field::branch_kinds).
  const Box box{{-1.2, -1.2, -1.2}, {1.2, 1.2, 1.2}};
  const std::string a = "(sqrt((x-0.3)^2+y^2+z^2)-0.5)", b = "(sqrt((x+0.3)^2+y^2+z^2)-0.5)";
  const std::string h = "clamp(0.5+0.5*(" + b + "-" + a + ")/0.3, 0, 1)";
  const Expression flat(b + "*(1-" + h + ")+" + a + "*" + h + "-0.3*" + h + "*(1-" + h + ")", {}, box);
  const Expression named("b*(1-h)+a*h-0.3*h*(1-h)", {}, box,
                         {{"a", a}, {"b", b}, {"h", "clamp(0.5+0.5*(b-a)/0.3, 0, 1)"}});
  EXPECT_EQ(flat.branch_kinds().size(), 2u);
  for (const Field::BranchKind k : flat.branch_kinds()) EXPECT_NE(k, Field::BranchKind::Creased);
  EXPECT_FALSE(flat.has_pieces());
  // The same bits as the named form and as each copy evaluated apart.
  for (const Vec3& p : {Vec3(0.1, 0.2, 0.3), Vec3(-0.7, 0.05, 0.4), Vec3(0.9, -0.3, 0.0)}) {
    Vec3 g1, g2;
    Mat3 H1, H2;
    EXPECT_EQ(flat.gradient_hessian(p, g1, H1), named.gradient_hessian(p, g2, H2));
    EXPECT_EQ(g1, g2);
    EXPECT_EQ(H1, H2);
  }
  // mod repeats its dividend; a branch point in it is one.
  EXPECT_EQ(Expression("mod(abs(x) - 0.5, 0.3)", {}, box).branch_kinds().size(), 1u);
  // Different constants are different subtrees.
  EXPECT_EQ(Expression("max(x, 0.5) + max(x, 0.25)", {}, box).branch_kinds().size(), 2u);
}

TEST(Expression, SyntaxErrorsNameThePosition) {
  EXPECT_EQ(error_of("x + * y"), "expression: unexpected '*' at position 5");
  EXPECT_EQ(error_of("x + (y"), "expression: expected ')', found the end at position 7");
  EXPECT_EQ(error_of("x + y)"), "expression: unexpected ')' at position 6");
  EXPECT_EQ(error_of("x + w"), "expression: unknown name 'w' at position 5");
  EXPECT_EQ(error_of("x + foo(y)"), "expression: unknown function 'foo' at position 5");
  EXPECT_EQ(error_of("min(x)"), "expression: min takes two or more arguments, found 1 at position 6");
  EXPECT_EQ(error_of("clamp(x, 0)"), "expression: clamp takes 3 arguments, found 2 at position 11");
  EXPECT_EQ(error_of(""), "expression: unexpected end of formula at position 1");
  EXPECT_EQ(error_of("x # y"), "expression: unexpected '#' at position 3");
  EXPECT_EQ(error_of("x", {{"pi", 3}}), "expression: parameter 'pi' shadows a built-in name");
}

TEST(Expression, RejectsFormulasTooDeepForItsStack) {
  std::string deep;
  for (int i = 0; i < 70; ++i) deep += "(x+";
  deep += "x";
  for (int i = 0; i < 70; ++i) deep += ")";
  EXPECT_NE(error_of(deep).find("nested too deeply"), std::string::npos);
}

std::string repeat(const std::string& s, int n) {
  std::string r;
  for (int i = 0; i < n; ++i) r += s;
  return r;
}

// Each of these once overflowed the call stack (exit 139) in the recursive parser or in the
// recursive walks of the formula tree; nesting up to the limits still evaluates.
TEST(Expression, RejectsNestingThatWouldOverflowTheCallStack) {
  const std::string levels = "formula nested too deeply (more than 256 levels of parentheses, calls, signs and exponents)";
  EXPECT_EQ(error_of(repeat("(", 100000) + "x" + repeat(")", 100000)), "expression: " + levels + " at position 257");
  EXPECT_EQ(error_of(repeat("sin(", 100000) + "x" + repeat(")", 100000)),
            "expression: " + levels + " at position 1025");
  EXPECT_EQ(error_of(repeat("-", 100000) + "x"), "expression: " + levels + " at position 257");
  EXPECT_EQ(error_of("x" + repeat("^1", 100000)), "expression: " + levels + " at position 513");
  EXPECT_EQ(error_of(repeat("x+", 1000000) + "x"),
            "expression: formula nested too deeply (more than 10000 operations in a row) at position 20002");
  EXPECT_DOUBLE_EQ(eval(repeat("(", 200) + "x" + repeat(")", 200)), 0.5);
  EXPECT_DOUBLE_EQ(eval(repeat("-", 200) + "x"), 0.5);
  EXPECT_DOUBLE_EQ(eval(repeat("x+", 9999) + "x"), 5000);
}

}  // namespace
}  // namespace cdp

namespace cdp {
namespace {

// Expression's protected piece evaluations, for comparing its own flips with Field's (one
// eval_first_order a flip).
class PieceProbe : public Expression {
 public:
  using Expression::Expression;
  using Expression::eval_first_order_combinations;
  using Expression::eval_first_order_flips;
  using Field::ChoiceStep;
  void combinations_one_by_one(const Vec3& p, const std::vector<std::uint8_t>& base, std::span<const int> split,
                               std::vector<std::pair<double, Vec3>>& out) const {
    Field::eval_first_order_combinations(p, base, split, out);
  }
  void flips_one_by_one(const Vec3& p, std::vector<std::uint8_t>& branch, std::span<const ChoiceStep> steps,
                        const std::function<bool(double, const Vec3&)>& hidden) const {
    Field::eval_first_order_flips(p, branch, steps, hidden);
  }
};

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(Expression, FlipsAndCombinationsFromOneRunGiveTheBitsOfARunEach) {
  // Subtrees written twice (stored where first computed, and read inside an argument another
  // choice takes), definitions that use each other, abs, clamp, n-ary min and max: each flip
  // recomputed from one run gives the value and gradient, bit for bit, of a run with the choice
  // flipped, and the choices made free as the answers say (some free where the values choose
  // otherwise than the branch did, so the run is made again) change the later flips as they do
  // one by one. Likewise every combination of a few choices flipped together.
  const Box box{{-2, -2, -2}, {2, 2, 2}};
  std::vector<std::unique_ptr<PieceProbe>> fields;
  const auto add = [&](const std::string& formula, const std::map<std::string, std::string>& definitions = {}) {
    fields.push_back(std::make_unique<PieceProbe>(formula, std::map<std::string, double>{}, box, definitions));
  };
  add("min(min(abs(x)-1, max(y, z*z)), max(abs(x+y) - 0.5, min(z, x)))");
  add("min(max(x*x+y*y-1, z), max(x*x+y*y-2, -z)) + min(x*x+y*y, abs(sin(x*x+y*y)))");
  add("max(c, -min(r - 0.5, c + 0.1)) + min(max(c, 0), clamp(r, 0.2, 0.4)) * atan2(y, x + 3)",
      {{"r", "sqrt(x^2+y^2+0.01)"}, {"c", "min(r - 1, abs(z) - 0.5)"}});
  add("min(max(abs(x)-1, abs(y)-1, abs(z)-1), max(abs(x-1)-0.5, abs(y)-0.5, abs(z-1)-0.5), "
      "max(abs(x)-1, abs(y)-1, abs(z)-1) + 0.3, sqrt(max(abs(x)-0.5, 0)^2 + max(abs(y)-0.5, 0)^2) - 0.1)");
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-1.5, 1.5);
  std::uniform_int_distribution<int> choice(0, 2);
  std::size_t flips = 0, freed = 0, combinations = 0;
  for (std::size_t which = 0; which < fields.size(); ++which) {
    const PieceProbe& f = *fields[which];
    const std::size_t n = f.branch_kinds().size();
    ASSERT_GT(n, 0u);
    for (int trial = 0; trial < 300; ++trial) {
      SCOPED_TRACE("formula " + std::to_string(which) + ", trial " + std::to_string(trial));
      std::vector<std::uint8_t> branch(n);
      std::vector<PieceProbe::ChoiceStep> steps;
      for (std::size_t k = 0; k < n; ++k) {
        branch[k] = static_cast<std::uint8_t>(choice(rng));
        if (branch[k] != Field::kFreeBranch) steps.push_back({static_cast<int>(k), choice(rng) != 0});
      }
      const Vec3 p(coordinate(rng), coordinate(rng), coordinate(rng));
      // Every other flip answered hidden.
      std::vector<std::pair<double, Vec3>> seen[2];
      std::vector<std::uint8_t> result[2] = {branch, branch};
      for (int way = 0; way < 2; ++way) {
        int calls = 0;
        const auto hidden = [&](double v, const Vec3& g) {
          seen[way].emplace_back(v, g);
          return calls++ % 2 == 1;
        };
        if (way == 0)
          f.flips_one_by_one(p, result[0], steps, hidden);
        else
          f.eval_first_order_flips(p, result[1], steps, hidden);
      }
      EXPECT_EQ(result[0], result[1]);
      ASSERT_EQ(seen[0].size(), seen[1].size());
      for (std::size_t i = 0; i < seen[0].size(); ++i) {
        EXPECT_TRUE(same_bits(seen[0][i].first, seen[1][i].first));
        for (int c = 0; c < 3; ++c) EXPECT_TRUE(same_bits(seen[0][i].second[c], seen[1][i].second[c]));
      }
      // The combinations of up to five given choices, each from the one before in Gray code order.
      std::vector<int> split;
      for (const auto& step : steps)
        if (split.size() < 5 && step.flip) split.push_back(step.choice);
      std::vector<std::pair<double, Vec3>> combined[2];
      f.combinations_one_by_one(p, branch, split, combined[0]);
      f.eval_first_order_combinations(p, branch, split, combined[1]);
      ASSERT_EQ(combined[0].size(), std::size_t{1} << split.size());
      ASSERT_EQ(combined[1].size(), combined[0].size());
      for (std::size_t i = 0; i < combined[0].size(); ++i) {
        EXPECT_TRUE(same_bits(combined[0][i].first, combined[1][i].first));
        for (int c = 0; c < 3; ++c) EXPECT_TRUE(same_bits(combined[0][i].second[c], combined[1][i].second[c]));
      }
      combinations += combined[0].size();
      flips += seen[0].size();
      for (std::size_t k = 0; k < n; ++k) freed += result[0][k] != branch[k];
    }
  }
  EXPECT_GT(flips, 1000u);
  EXPECT_GT(freed, 1000u);
  EXPECT_GT(combinations, 10000u);
}

}  // namespace
}  // namespace cdp
