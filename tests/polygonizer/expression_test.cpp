// The formula language: precedence, parameters, functions, and errors that name the position.
#include <gtest/gtest.h>

#include <cdp/core/errors.h>
#include <cdp/core/models/expression.h>

#include <numbers>

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

TEST(Expression, SyntaxErrorsNameThePosition) {
  EXPECT_EQ(error_of("x + * y"), "expression: unexpected '*' at position 5");
  EXPECT_EQ(error_of("x + (y"), "expression: expected ')', found the end at position 7");
  EXPECT_EQ(error_of("x + y)"), "expression: unexpected ')' at position 6");
  EXPECT_EQ(error_of("x + w"), "expression: unknown name 'w' at position 5");
  EXPECT_EQ(error_of("x + foo(y)"), "expression: unknown function 'foo' at position 5");
  EXPECT_EQ(error_of("min(x)"), "expression: min takes 2 argument(s), found 1 at position 6");
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
