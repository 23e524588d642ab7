// The paper's Newton step: moves a point onto F = 0 along the gradient, with bounds.
#pragma once

#include <cdp/core/field.h>

#include <span>
#include <vector>

namespace cdp {

struct ProjectionOptions {
  int max_iterations = 40;
  // Converged when |F| / |grad F| (first-order distance to the surface) is below this.
  // Non-positive: 1e-10 times the field's bounding-box diagonal.
  double tolerance = 0;
  // One step moves at most this far (longer Newton steps are shortened). Non-positive: 0.1 diagonal.
  double max_step = 0;
  // The point may end at most this far from where it started. Non-positive: 0.5 diagonal.
  double max_travel = 0;
};

// OutOfRange: the field's box diagonal, which sets the default tolerance and limits, overflows
// (or vanishes), so no result could be trusted. NoProgress: the Newton step rounds to nothing
// (the point's coordinates are too coarse in floating point for the tolerance).
enum class ProjectionStatus { Converged, MaxIterations, VanishingGradient, TooFar, NotFinite, OutOfRange, NoProgress };

struct ProjectionResult {
  Vec3 point = Vec3::Zero();
  ProjectionStatus status = ProjectionStatus::MaxIterations;
  int iterations = 0;
  double residual = 0;  // |F| / |grad F| at `point`
  // The gradient at `start` (the first Newton evaluation; zero if there was none). Where it and
  // the gradient at `point` point different ways, the projection crossed a crease of the field.
  Vec3 start_gradient = Vec3::Zero();
  // The gradient at the last point evaluated: when ok(), at `point` (so that a caller needing the
  // normal there need not evaluate the field again).
  Vec3 gradient = Vec3::Zero();
  bool ok() const { return status == ProjectionStatus::Converged; }
};

const char* to_string(ProjectionStatus status);

// The paper's Newton iteration from `start` onto F = 0, each step along the gradient and bounded
// by options.max_step, the whole walk by options.max_travel.
// \return the point and how the iteration ended (ProjectionStatus): no error is thrown for a
//         point that cannot be projected; the status says why.
// \throw what the field's evaluations throw.
ProjectionResult project_to_surface(const Field& field, const Vec3& start, const ProjectionOptions& options = {});

// Projects every start point, starts[i] with options[i], in lockstep: each Newton round evaluates
// the points still iterating in one values_gradients call, so that a field whose calls cost more
// than its arithmetic (a Python function) is called once a round rather than once a point. Each
// result is the one project_to_surface gives, bit for bit, with the same evaluation count.
// \pre starts.size() == options.size().
// \throw std::invalid_argument when the sizes differ; what the field's evaluations throw.
std::vector<ProjectionResult> project_to_surface(const Field& field, std::span<const Vec3> starts,
                                                 std::span<const ProjectionOptions> options);

namespace detail {
// One projection's tolerance and limits, with every default resolved.
struct ProjectionLimits {
  double diag = 0, tol = 0, max_step = 0, max_travel = 0;
  int max_iterations = 0;
};
}  // namespace detail

// The batched projection above, keeping its buffers from call to call: for callers that project
// a few points at a time and often (the adaptive tracker, every expansion), where allocating them
// each time would cost more than the Newton steps on a cheap field.
class BatchProjector {
 public:
  // The results stay valid until the next call. With `hessians_below` > 0, a point whose
  // residual (|F| / |grad F|) after the round before was at most that is evaluated with
  // gradients_hessians instead of values_gradients: a point one Newton step from converging,
  // whose evaluation then ends the projection more often than not. Where it does, the result
  // keeps that Hessian (hessian()), and a caller that needs the Hessian where the projection
  // lands (the tracker's curvature) does not evaluate that point a second time. The points, and
  // so the results, are those of project_to_surface where the field's two calls give the same
  // value and gradient.
  std::span<const ProjectionResult> project(const Field& field, std::span<const Vec3> starts,
                                            std::span<const ProjectionOptions> options, double hessians_below = 0);
  // The Hessian at results[i].point from the last round of the last call, or nullptr when that
  // round was not evaluated with Hessians.
  const Mat3* hessian(std::size_t i) const { return has_hessian_[i] ? &hessians_[i] : nullptr; }
  // Wall time of the last call's rounds with Hessians (the tracker reports the Hessians' cost).
  double hessian_seconds() const { return hessian_seconds_; }

 private:
  std::vector<ProjectionResult> results_;
  std::vector<detail::ProjectionLimits> limits_;
  std::vector<std::size_t> active_;  // the points still iterating, in order
  std::vector<Vec3> points_, gradients_, split_points_, split_gradients_;
  std::vector<double> values_, split_values_;
  std::vector<std::size_t> near_;  // of the round's points, those evaluated with Hessians
  std::vector<Mat3> round_hessians_, hessians_;
  std::vector<char> has_hessian_;
  double hessian_seconds_ = 0;
};

}  // namespace cdp
