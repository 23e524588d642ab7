#include <cdp/core/errors.h>
#include <cdp/core/field.h>

namespace cdp {

// A model without branch points is one piece: the field itself, with the empty branch.
FieldPiece Field::eval_piece(const Vec3& p, const std::vector<std::uint8_t>& branch) const {
  if (!branch.empty())
    throw InvalidInputError(type_name() + ": the model has no branch points, a piece's branch must be empty");
  FieldPiece piece;
  piece.value = eval_gradient_hessian(p, piece.gradient, piece.hessian);
  return piece;
}

}  // namespace cdp
