#include <cdp/core/newton_projection.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

namespace cdp {

const char* to_string(ProjectionStatus status) {
  switch (status) {
    case ProjectionStatus::Converged: return "converged";
    case ProjectionStatus::MaxIterations: return "did not converge within the iteration limit";
    case ProjectionStatus::VanishingGradient: return "the gradient vanishes";
    case ProjectionStatus::TooFar: return "the point moved farther than the travel limit";
    case ProjectionStatus::NotFinite: return "the field is not finite";
    case ProjectionStatus::OutOfRange: return "the field's box is too large (or too small) for double precision";
    case ProjectionStatus::NoProgress: return "the Newton step no longer moves the point in double precision";
  }
  return "unknown";
}

namespace {

using Limits = detail::ProjectionLimits;

// An infinite tolerance (a box whose diagonal overflows, as for a sphere of radius 1e160) would
// accept the start point, however far from the surface, as converged.
bool usable(const Limits& l) {
  return l.tol > 0 && std::isfinite(l.tol) && std::isfinite(l.max_step) && std::isfinite(l.max_travel);
}

Limits resolve(const Field& field, const ProjectionOptions& options) {
  Limits l;
  l.diag = field.bounds().diagonal();
  l.tol = options.tolerance > 0 ? options.tolerance : 1e-10 * l.diag;
  l.max_step = options.max_step > 0 ? options.max_step : 0.1 * l.diag;
  l.max_travel = options.max_travel > 0 ? options.max_travel : 0.5 * l.diag;
  l.max_iterations = options.max_iterations;
  return l;
}

// Newton round r.iterations at r.point, where the field has value f and gradient g: ends the
// projection (sets r.status and returns true) or takes the step and counts the round. The single
// and the batched projection both go through here, so their points follow the same arithmetic.
bool newton_round(ProjectionResult& r, const Vec3& start, double f, const Vec3& g, const Limits& l) {
  if (r.iterations == 0) r.start_gradient = g;
  r.gradient = g;
  const double g2 = g.squaredNorm();
  if (!std::isfinite(f) || !std::isfinite(g2)) {
    r.status = ProjectionStatus::NotFinite;
    return true;
  }
  // A gradient this small relative to the value cannot give a trustworthy step.
  if (g2 <= 1e-300 || std::sqrt(g2) * l.diag < 1e-12 * std::abs(f)) {
    r.status = ProjectionStatus::VanishingGradient;
    return true;
  }
  r.residual = std::abs(f) / std::sqrt(g2);
  if (r.residual <= l.tol) {
    r.status = ProjectionStatus::Converged;
    return true;
  }
  if (r.iterations == l.max_iterations) {
    r.status = ProjectionStatus::MaxIterations;
    return true;
  }
  Vec3 step = -(f / g2) * g;
  const double len = step.norm();
  if (len > l.max_step) step *= l.max_step / len;
  // A step that rounds to nothing would repeat until the iteration limit: say so now.
  if (r.point + step == r.point) {
    r.status = ProjectionStatus::NoProgress;
    return true;
  }
  r.point += step;
  if ((r.point - start).norm() > l.max_travel) {
    r.status = ProjectionStatus::TooFar;
    return true;
  }
  ++r.iterations;
  return false;
}

}  // namespace

ProjectionResult project_to_surface(const Field& field, const Vec3& start, const ProjectionOptions& options) {
  const Limits l = resolve(field, options);
  ProjectionResult r;
  r.point = start;
  if (!usable(l)) {
    r.status = ProjectionStatus::OutOfRange;
    return r;
  }
  // Each round ends the projection or counts an iteration, and round max_iterations ends it.
  for (int round = 0; round <= l.max_iterations; ++round) {
    Vec3 g;
    const double f = field.value_gradient(r.point, g);
    if (newton_round(r, start, f, g, l)) return r;
  }
  r.status = ProjectionStatus::MaxIterations;
  return r;
}

std::vector<ProjectionResult> project_to_surface(const Field& field, std::span<const Vec3> starts,
                                                 std::span<const ProjectionOptions> options) {
  BatchProjector projector;
  const std::span<const ProjectionResult> r = projector.project(field, starts, options);
  return {r.begin(), r.end()};
}

std::span<const ProjectionResult> BatchProjector::project(const Field& field, std::span<const Vec3> starts,
                                                          std::span<const ProjectionOptions> options,
                                                          double hessians_below) {
  if (options.size() != starts.size())
    throw std::invalid_argument("project_to_surface: " + std::to_string(starts.size()) + " start points but " +
                                std::to_string(options.size()) + " options");
  const std::size_t n = starts.size();
  results_.assign(n, ProjectionResult{});
  limits_.resize(n);
  hessians_.resize(n);
  has_hessian_.assign(n, 0);
  hessian_seconds_ = 0;
  active_.clear();
  int rounds = 0;
  for (std::size_t i = 0; i < n; ++i) {
    results_[i].point = starts[i];
    limits_[i] = resolve(field, options[i]);
    if (!usable(limits_[i])) results_[i].status = ProjectionStatus::OutOfRange;
    else if (limits_[i].max_iterations >= 0) active_.push_back(i), rounds = std::max(rounds, limits_[i].max_iterations + 1);
  }
  points_.resize(active_.size());
  gradients_.resize(active_.size());
  values_.resize(active_.size());
  for (int round = 0; round < rounds && !active_.empty(); ++round) {
    const std::size_t m = active_.size();
    for (std::size_t k = 0; k < m; ++k) points_[k] = results_[active_[k]].point;
    // The points near convergence (see the header) go to gradients_hessians, the rest to
    // values_gradients; each point's value and gradient end up at its slot k either way.
    near_.clear();
    if (hessians_below > 0 && round > 0)
      for (std::size_t k = 0; k < m; ++k)
        if (results_[active_[k]].residual <= hessians_below) near_.push_back(k);
    if (near_.empty()) {
      field.values_gradients(points_.data(), values_.data(), gradients_.data(), m);
    } else {
      const std::size_t h = near_.size();
      split_points_.resize(m);
      split_values_.resize(m);
      split_gradients_.resize(m);
      round_hessians_.resize(h);
      // The near points first, then the others, each group in its order; scattered back below.
      std::size_t far = h;
      for (std::size_t k = 0, j = 0; k < m; ++k) {
        if (j < h && near_[j] == k) split_points_[j++] = points_[k];
        else split_points_[far++] = points_[k];
      }
      const auto start = std::chrono::steady_clock::now();
      field.gradients_hessians(split_points_.data(), split_values_.data(), split_gradients_.data(),
                               round_hessians_.data(), h);
      hessian_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (h < m)
        field.values_gradients(split_points_.data() + h, split_values_.data() + h, split_gradients_.data() + h, m - h);
      far = h;
      for (std::size_t k = 0, j = 0; k < m; ++k) {
        const std::size_t from = j < h && near_[j] == k ? j++ : far++;
        values_[k] = split_values_[from];
        gradients_[k] = split_gradients_[from];
      }
    }
    std::size_t kept = 0;
    for (std::size_t k = 0, j = 0; k < m; ++k) {
      const std::size_t i = active_[k];
      const bool with_hessian = j < near_.size() && near_[j] == k;
      if (with_hessian) ++j;
      const bool ended = newton_round(results_[i], starts[i], values_[k], gradients_[k], limits_[i]);
      // The Hessian is at the result's point only where the round ended without a step.
      if (ended && with_hessian && results_[i].point == points_[k])
        hessians_[i] = round_hessians_[j - 1], has_hessian_[i] = 1;
      if (!ended) active_[kept++] = i;
    }
    active_.resize(kept);
  }
  return results_;
}

}  // namespace cdp
