#include <cdp/core/errors.h>
#include <cdp/core/models/level_shift.h>

#include <cmath>

namespace cdp {

LevelShift::LevelShift(const Field& field, double level) : field_(field), level_(level) {
  if (!std::isfinite(level)) throw InvalidInputError("level must be a finite number");
  set_bounds(field.bounds());
}

std::optional<std::pair<double, double>> LevelShift::value_range(const Box& region) const {
  auto range = field_.value_range(region);
  if (range) range->first -= level_, range->second -= level_;
  return range;
}

void LevelShift::eval_values(const Vec3* points, double* out, std::size_t n) const {
  field_.eval_values(points, out, n);
  for (std::size_t i = 0; i < n; ++i) out[i] -= level_;
}

void LevelShift::eval_values_on_lattice(const Vec3& origin, double step, int n, double* out) const {
  field_.eval_values_on_lattice(origin, step, n, out);
  const std::size_t count = static_cast<std::size_t>(n) * n * n;
  for (std::size_t i = 0; i < count; ++i) out[i] -= level_;
}

void LevelShift::eval_values_gradients(const Vec3* points, double* values, Vec3* gradients, std::size_t n) const {
  field_.eval_values_gradients(points, values, gradients, n);
  for (std::size_t i = 0; i < n; ++i) values[i] -= level_;
}

void LevelShift::eval_gradients_hessians(const Vec3* points, double* values, Vec3* gradients, Mat3* hessians,
                                         std::size_t n) const {
  field_.eval_gradients_hessians(points, values, gradients, hessians, n);
  for (std::size_t i = 0; i < n; ++i) values[i] -= level_;
}

void LevelShift::eval_together(const Batch& plain, const Batch& with_gradients, const Batch& with_hessians) const {
  field_.eval_together(plain, with_gradients, with_hessians);
  for (const Batch* b : {&plain, &with_gradients, &with_hessians})
    for (std::size_t i = 0; i < b->n; ++i) b->values[i] -= level_;
}

FieldPiece LevelShift::eval_piece(const Vec3& p, const std::vector<std::uint8_t>& branch) const {
  FieldPiece piece = field_.eval_piece(p, branch);
  piece.value -= level_;
  return piece;
}

bool LevelShift::eval_branch_record(const Vec3& p, const std::vector<std::uint8_t>& branch, BranchRecord& record) const {
  if (!field_.eval_branch_record(p, branch, record)) return false;
  record.value -= level_;
  return true;
}

std::pair<double, Vec3> LevelShift::eval_first_order(const Vec3& p, const std::vector<std::uint8_t>& branch) const {
  auto first = field_.eval_first_order(p, branch);
  first.first -= level_;
  return first;
}

void LevelShift::eval_first_order_flips(const Vec3& p, std::vector<std::uint8_t>& branch,
                                        std::span<const ChoiceStep> steps,
                                        const std::function<bool(double, const Vec3&)>& hidden) const {
  field_.eval_first_order_flips(p, branch, steps, [&](double v, const Vec3& g) { return hidden(v - level_, g); });
}

void LevelShift::eval_first_order_combinations(const Vec3& p, const std::vector<std::uint8_t>& base,
                                               std::span<const int> split,
                                               std::vector<std::pair<double, Vec3>>& out) const {
  field_.eval_first_order_combinations(p, base, split, out);
  for (auto& [v, g] : out) v -= level_;
}

bool LevelShift::eval_piece_live(const Vec3& p, const std::vector<std::uint8_t>& branch, const std::int8_t* bits,
                                 bool hessian, FieldPiece& piece, std::uint64_t& live) const {
  if (!field_.eval_piece_live(p, branch, bits, hessian, piece, live)) return false;
  piece.value -= level_;
  return true;
}

}  // namespace cdp
