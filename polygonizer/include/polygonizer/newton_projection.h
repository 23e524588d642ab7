// The paper's Newton step: moves a point onto F = 0 along the gradient, with bounds.
#pragma once

#include <polygonizer/field.h>

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
  bool ok() const { return status == ProjectionStatus::Converged; }
};

const char* to_string(ProjectionStatus status);

ProjectionResult project_to_surface(const Field& field, const Vec3& start, const ProjectionOptions& options = {});

}  // namespace cdp
