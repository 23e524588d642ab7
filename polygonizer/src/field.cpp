#include <cdp/core/errors.h>
#include <cdp/core/field.h>

#include <algorithm>

namespace cdp {

// A model without branch points is one piece: the field itself, with the empty branch.
FieldPiece Field::eval_piece(const Vec3& p, const std::vector<std::uint8_t>& branch) const {
  if (!branch.empty())
    throw InvalidInputError(type_name() + ": the model has no branch points, a piece's branch must be empty");
  FieldPiece piece;
  piece.value = eval_gradient_hessian(p, piece.gradient, piece.hessian);
  return piece;
}

std::vector<FieldPiece> Field::pieces_near_branches(
    const std::vector<std::uint8_t>& taken, const std::vector<double>& distance, double radius,
    const std::function<FieldPiece(const std::vector<std::uint8_t>&)>& piece) {
  std::vector<int> split;
  for (std::size_t k = 0; k < taken.size(); ++k)
    if (distance[k] <= radius) split.push_back(static_cast<int>(k));
  // The nearest switches (ties: the earlier branch point), then back in program order.
  std::stable_sort(split.begin(), split.end(), [&](int a, int b) {
    return distance[static_cast<std::size_t>(a)] < distance[static_cast<std::size_t>(b)];
  });
  if (split.size() > static_cast<std::size_t>(kMaxSplitBranchPoints)) split.resize(kMaxSplitBranchPoints);
  std::sort(split.begin(), split.end());
  std::vector<FieldPiece> out;
  for (std::uint32_t mask = 0; mask < (1u << split.size()); ++mask) {
    std::vector<std::uint8_t> branch = taken;
    for (std::size_t j = 0; j < split.size(); ++j)
      if (mask >> j & 1u) branch[static_cast<std::size_t>(split[j])] ^= 1u;
    FieldPiece next = piece(branch);
    // Different branches often give the same function (a choice inside an argument that is not
    // taken): the same numbers at p, bit for bit, are one piece.
    const bool seen = std::any_of(out.begin(), out.end(), [&](const FieldPiece& q) {
      return q.value == next.value && q.gradient == next.gradient && q.hessian == next.hessian;
    });
    if (!seen) out.push_back(std::move(next));
  }
  return out;
}

}  // namespace cdp
