#include <cdp/core/crease.h>
#include <cdp/core/errors.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace cdp {

namespace {

// Gradients whose Gram matrix has a determinant below this fraction of the product of their
// squared lengths are taken as dependent: for two pieces, an angle below about 1e-4 rad (1e-8 =
// sin^2), where a Newton step would be 1e4 times the residual and no longer meaningful.
constexpr double kDependentGradients = 1e-8;

}  // namespace

const char* to_string(CreaseStatus status) {
  switch (status) {
    case CreaseStatus::Converged: return "converged";
    case CreaseStatus::MaxIterations: return "max_iterations";
    case CreaseStatus::DependentGradients: return "dependent_gradients";
    case CreaseStatus::NotFinite: return "not_finite";
  }
  return "unknown";
}

CreaseProjection project_to_crease(const Field& field, const Vec3& start,
                                   std::span<const std::vector<std::uint8_t>> branches, const CreaseOptions& options) {
  return project_to_crease(field, start, branches, {}, options);
}

CreaseProjection project_to_crease(const Field& field, const Vec3& start,
                                   std::span<const std::vector<std::uint8_t>> branches,
                                   std::span<const std::pair<double, Vec3>> at_start, const CreaseOptions& options) {
  const int n = static_cast<int>(branches.size());
  if (n != 2 && n != 3)
    throw InvalidInputError("project_to_crease: needs 2 pieces (a crease) or 3 (a corner), not " + std::to_string(n));
  if (!at_start.empty() && at_start.size() != branches.size())
    throw InvalidInputError("project_to_crease: " + std::to_string(at_start.size()) + " evaluations at the start for " +
                            std::to_string(n) + " pieces");
  const double diag = field.bounds().diagonal();
  const double tol = options.tolerance > 0 ? options.tolerance : 1e-10 * diag;
  const double max_step = options.max_step > 0 ? options.max_step : 0.1 * diag;
  CreaseProjection out;
  out.point = start;
  // Two or three rows: storage on the stack (a projection is made at every crease step).
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::ColMajor, 3, 3> J(n, 3);
  Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 3, 1> F(n);
  for (int it = 0;; ++it) {
    double residual = 0, product = 1;
    for (int i = 0; i < n; ++i) {
      const auto [value, gradient] = it == 0 && !at_start.empty()
                                         ? at_start[static_cast<std::size_t>(i)]
                                         : field.piece_first_order(out.point, branches[static_cast<std::size_t>(i)]);
      const double g = gradient.norm();
      if (!std::isfinite(value) || !gradient.allFinite()) {
        out.status = CreaseStatus::NotFinite;
        return out;
      }
      J.row(i) = gradient.transpose();
      F(i) = value;
      out.gradients[static_cast<std::size_t>(i)] = gradient;
      residual = std::max(residual, g > 0 ? std::abs(value) / g : std::numeric_limits<double>::infinity());
      product *= g * g;
    }
    out.residual = residual;
    out.iterations = it;
    if (residual <= tol) {
      out.status = CreaseStatus::Converged;
      return out;
    }
    if (it >= options.max_iterations) {
      out.status = CreaseStatus::MaxIterations;
      return out;
    }
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 3, 3> gram = J * J.transpose();
    if (!(gram.determinant() > kDependentGradients * product)) {
      out.status = CreaseStatus::DependentGradients;
      return out;
    }
    // The smallest step that zeroes the linearised pieces: in their gradients' span.
    Vec3 step = -J.transpose() * gram.ldlt().solve(F);
    if (const double len = step.norm(); len > max_step) step *= max_step / len;
    out.point += step;
  }
}

CreaseProjection project_to_seam(const Field& field, const Vec3& start, const std::vector<std::uint8_t>& branch,
                                 std::size_t k, const CreaseOptions& options) {
  const double diag = field.bounds().diagonal();
  const double tol = options.tolerance > 0 ? options.tolerance : 1e-10 * diag;
  const double max_step = options.max_step > 0 ? options.max_step : 0.1 * diag;
  CreaseProjection out;
  out.point = start;
  for (int it = 0;; ++it) {
    const auto [value, gradient] = field.piece_first_order(out.point, branch);
    const std::optional<Field::BranchSwitch> sw = field.branch_switch(out.point, k);
    const double g = gradient.norm();
    if (!sw || !std::isfinite(value) || !gradient.allFinite() || !std::isfinite(sw->distance)) {
      out.status = CreaseStatus::NotFinite;
      return out;
    }
    Eigen::Matrix<double, 2, 3> J;
    J.row(0) = gradient.transpose();
    J.row(1) = sw->normal.transpose();
    const Eigen::Vector2d F(value, sw->distance);
    out.residual = std::max(g > 0 ? std::abs(value) / g : std::numeric_limits<double>::infinity(),
                            std::abs(sw->distance));
    out.iterations = it;
    if (out.residual <= tol) {
      out.status = CreaseStatus::Converged;
      return out;
    }
    if (it >= options.max_iterations) {
      out.status = CreaseStatus::MaxIterations;
      return out;
    }
    const Eigen::Matrix2d gram = J * J.transpose();
    if (!(gram.determinant() > kDependentGradients * g * g)) {
      out.status = CreaseStatus::DependentGradients;
      return out;
    }
    Vec3 step = -J.transpose() * gram.ldlt().solve(F);
    if (const double len = step.norm(); len > max_step) step *= max_step / len;
    out.point += step;
  }
}

}  // namespace cdp
