// A field from a formula in x, y, z: + - * / ^, parentheses, unary minus, numbers, named
// parameters, pi, and sqrt exp log sin cos tan abs min max pow. The formula is compiled once to
// a small stack program and run with doubles or jets, so gradient and Hessian are exact.
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
  // Throws InvalidInputError "expression: <problem> at position N" on a syntax error, an unknown
  // name or a wrong argument count. `bounds` is required: a formula has no box of its own.
  Expression(const std::string& formula, const std::map<std::string, double>& params, const Box& bounds);
  ~Expression() override;
  std::string type_name() const override { return "expression"; }
  bool thread_safe() const override { return true; }  // evaluation reads immutable data only
  const std::string& formula() const { return formula_; }
  bool has_pieces() const override;  // a min, max or abs anywhere in the formula

 protected:
  double eval_value(const Vec3& p) const override;
  double eval_value_gradient(const Vec3& p, Vec3& gradient) const override;
  double eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const override;
  // Each min, max and abs is a branch point, numbered in the order the formula is evaluated
  // (arguments before the call); a branch is 0 for the first argument (+u for abs), 1 for the
  // second (-u).
  std::vector<FieldPiece> eval_pieces(const Vec3& p, double radius) const override;
  FieldPiece eval_piece(const Vec3& p, const std::vector<std::uint8_t>& branch) const override;

 private:
  std::string formula_;
  std::unique_ptr<detail::ExpressionProgram> program_;
};

}  // namespace cdp
