// A field from a formula in x, y, z: + - * / ^ (or **), parentheses, unary minus, numbers,
// named parameters, pi, named sub-expressions, and the functions
//   sqrt exp log sin cos tan atan pow abs          one argument (pow two)
//   min max hypot                                  two or more arguments
//   clamp(u, lo, hi) = min(max(u, lo), hi)
//   atan2(y, x)                                    cut along x < 0, y = 0 (a jump of 2 pi)
//   floor round mod(a, b) = a - b floor(a / b)     steps, with zero derivative between jumps
// The formula is compiled once to a small stack program and run with doubles or jets, so
// gradient and Hessian are exact. min, max, abs and clamp are branch points: their creases are
// known (Field::pieces). The steps are not: a surface that crosses one of their jumps (a
// repeated shape that reaches the edge of its cell) has a crease or a gap nothing reports.
#pragma once

#include <cdp/core/field.h>

#include <map>
#include <memory>
#include <string>

namespace cdp {

namespace detail {
struct ExpressionProgram;
}

class Expression : public Field {
 public:
  // `definitions` names sub-expressions ({"r": "sqrt(x^2+y^2)"}) that the formula and each other
  // may use by name, in any order; each used one is evaluated once per evaluation, and one
  // without x, y, z is folded to a number. Throws InvalidInputError "expression: <problem> at
  // position N" (prefixed "in definition 'NAME': " inside one) on a syntax error, an unknown
  // name, a wrong argument count or a definition that refers to itself. `bounds` is required: a
  // formula has no box of its own.
  Expression(const std::string& formula, const std::map<std::string, double>& params, const Box& bounds,
             const std::map<std::string, std::string>& definitions = {});
  // The same in the order of Python's cdp.expression(formula, bounds, params, define).
  Expression(const std::string& formula, const Box& bounds, const std::map<std::string, double>& params = {},
             const std::map<std::string, std::string>& definitions = {})
      : Expression(formula, params, bounds, definitions) {}
  ~Expression() override;
  std::string type_name() const override { return "expression"; }
  bool thread_safe() const override { return true; }  // evaluation reads immutable data only
  const std::string& formula() const { return formula_; }

  // By interval arithmetic over the formula (src/models/interval.h): bounds that hold, loose
  // where a variable occurs more than once; infinite where nothing bounds them (a division by
  // an interval holding zero, the slope of a root at zero, a jump).
  std::optional<std::pair<double, double>> value_range(const Box& region) const override;
  std::optional<std::pair<double, double>> derivative_range(const Box& region, const Vec3& direction) const override;

 protected:
  double eval_value(const Vec3& p) const override;
  double eval_value_gradient(const Vec3& p, Vec3& gradient) const override;
  double eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const override;
  // Each min, max and abs is a branch point (clamp is two), numbered in the order the formula
  // is evaluated (arguments before the call); a branch is 0 for the first argument (+u for abs),
  // 1 for the second (-u), kFreeBranch for the one the values take.
  bool has_branch_points() const override;
  bool eval_branch_record(const Vec3& p, const std::vector<std::uint8_t>& branch, BranchRecord& record) const override;
  std::pair<double, Vec3> eval_first_order(const Vec3& p, const std::vector<std::uint8_t>& branch) const override;
  void eval_first_order_flips(const Vec3& p, std::vector<std::uint8_t>& branch, std::span<const ChoiceStep> steps,
                              const std::function<bool(double, const Vec3&)>& hidden) const override;
  void eval_first_order_combinations(const Vec3& p, const std::vector<std::uint8_t>& base, std::span<const int> split,
                                     std::vector<std::pair<double, Vec3>>& out) const override;
  FieldPiece eval_piece(const Vec3& p, const std::vector<std::uint8_t>& branch) const override;
  bool eval_piece_live(const Vec3& p, const std::vector<std::uint8_t>& branch, const std::int8_t* bits, bool hessian,
                       FieldPiece& piece, std::uint64_t& live) const override;
  bool choices_reaching(const std::vector<std::uint8_t>& branch, std::vector<std::uint8_t>& reaches) const override;

 private:
  void check_branch(const std::vector<std::uint8_t>& branch) const;  // InvalidInputError unless one of ours
  std::string formula_;
  std::unique_ptr<detail::ExpressionProgram> program_;
};

}  // namespace cdp
