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

#include <cstdint>
#include <map>
#include <memory>
#include <string>

namespace cdp {

namespace detail {
struct ExpressionProgram;
class RegionPrograms;
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
  // Evaluation reads immutable data, and the cells' programs (instructions_at), made once each
  // under a lock and published atomically.
  bool thread_safe() const override { return true; }
  const std::string& formula() const { return formula_; }
  // The length of the program a plain evaluation at p runs, and of the whole formula's. Inside
  // bounds() a formula with several min, max or abs runs specialized to p's cell of a grid over
  // the box: the min and max whose arguments' ranges over the cell (value_range's interval
  // arithmetic) do not overlap are left out with what only they read, so a union of many
  // primitives is near any point the formula of a few. The values, gradients and Hessians are
  // the same bits as the whole formula's (what is left out is what a min or max discarded). A
  // cell is specialized once evaluated 64 times (asking here counts as one), while the cells'
  // programs stay within 32 MB for the whole field.
  std::size_t instructions_at(const Vec3& p) const;
  // The same for a piece with the choices `branch` given (Field::piece): its cell's program for
  // such runs, when the choices agree with those the cell's ranges decide.
  std::size_t instructions_at(const Vec3& p, const std::vector<std::uint8_t>& branch) const;
  std::size_t instructions() const;

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
  // What an evaluation at p runs (with `forced`, one with those choices given): the program
  // specialized to p's cell of the box (the min and max that cannot switch there left out: the
  // same bits), or the whole one.
  const detail::ExpressionProgram& program_at(const Vec3& p, const std::uint8_t* forced = nullptr) const;
  std::string formula_;
  std::unique_ptr<detail::ExpressionProgram> program_;
  std::unique_ptr<detail::RegionPrograms> regions_;  // after program_, which it refers to
};

}  // namespace cdp
