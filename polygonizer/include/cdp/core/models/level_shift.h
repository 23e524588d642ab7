// F - level: the surface where a field takes another value than zero (an iso-value, scikit-image's
// and Manifold's `level`), as a field of its own. The evaluation hooks pass on to F with the value
// shifted: derivatives, pieces, branch records and bounds are F's (a constant moves none of
// them), so creases, curvature and the seeding's proofs hold as they do for F. What Field derives
// from those hooks it derives again for F - level, on its own surface: which branch points are
// creases and which smooth seams (Field::branch_kinds, found near the zero set) and the smooth
// sides of a seam, which come from those kinds; passing smooth_sides on to F would use F's
// kinds, classified on F = 0.
#pragma once

#include <cdp/core/field.h>

namespace cdp {

class LevelShift final : public Field {
 public:
  // \pre `field` outlives this object.
  // \throw InvalidInputError for a level that is not finite.
  LevelShift(const Field& field, double level);

  std::string type_name() const override { return field_.type_name(); }
  bool thread_safe() const override { return field_.thread_safe(); }
  bool costly_calls() const override { return field_.costly_calls(); }
  bool predicts_from_hessians() const override { return field_.predicts_from_hessians(); }
  bool smooth() const override { return field_.smooth(); }
  std::optional<double> derivative_step() const override { return field_.derivative_step(); }
  std::optional<double> sample_spacing() const override { return field_.sample_spacing(); }
  std::optional<double> lipschitz_bound() const override { return field_.lipschitz_bound(); }
  std::optional<double> lipschitz_bound(const Box& region) const override { return field_.lipschitz_bound(region); }
  std::optional<std::pair<double, double>> value_range(const Box& region) const override;
  std::optional<std::pair<Vec3, Vec3>> gradient_range(const Box& region) const override {
    return field_.gradient_range(region);
  }
  std::optional<std::pair<double, double>> derivative_range(const Box& region, const Vec3& direction) const override {
    return field_.derivative_range(region, direction);
  }
  std::optional<double> constraint_spacing() const override { return field_.constraint_spacing(); }
  double level() const { return level_; }

 protected:
  double eval_value(const Vec3& p) const override { return field_.eval_value(p) - level_; }
  double eval_value_gradient(const Vec3& p, Vec3& gradient) const override {
    return field_.eval_value_gradient(p, gradient) - level_;
  }
  double eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const override {
    return field_.eval_gradient_hessian(p, gradient, hessian) - level_;
  }
  void eval_values(const Vec3* points, double* out, std::size_t n) const override;
  void eval_values_on_lattice(const Vec3& origin, double step, int n, double* out) const override;
  void eval_values_gradients(const Vec3* points, double* values, Vec3* gradients, std::size_t n) const override;
  void eval_gradients_hessians(const Vec3* points, double* values, Vec3* gradients, Mat3* hessians,
                               std::size_t n) const override;
  void eval_together(const Batch& plain, const Batch& with_gradients, const Batch& with_hessians) const override;
  FieldPiece eval_piece(const Vec3& p, const std::vector<std::uint8_t>& branch) const override;
  bool has_branch_points() const override { return field_.has_branch_points(); }
  bool eval_branch_record(const Vec3& p, const std::vector<std::uint8_t>& branch, BranchRecord& record) const override;
  std::pair<double, Vec3> eval_first_order(const Vec3& p, const std::vector<std::uint8_t>& branch) const override;
  void eval_first_order_flips(const Vec3& p, std::vector<std::uint8_t>& branch, std::span<const ChoiceStep> steps,
                              const std::function<bool(double, const Vec3&)>& hidden) const override;
  void eval_first_order_combinations(const Vec3& p, const std::vector<std::uint8_t>& base, std::span<const int> split,
                                     std::vector<std::pair<double, Vec3>>& out) const override;
  bool eval_piece_live(const Vec3& p, const std::vector<std::uint8_t>& branch, const std::int8_t* bits, bool hessian,
                       FieldPiece& piece, std::uint64_t& live) const override;
  bool choices_reaching(const std::vector<std::uint8_t>& branch, std::vector<std::uint8_t>& reaches) const override {
    return field_.choices_reaching(branch, reaches);
  }

 private:
  const Field& field_;
  double level_;
};

}  // namespace cdp
