#include <polygonizer/newton_projection.h>

#include <cmath>

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

ProjectionResult project_to_surface(const Field& field, const Vec3& start, const ProjectionOptions& options) {
  const double diag = field.bounds().diagonal();
  const double tol = options.tolerance > 0 ? options.tolerance : 1e-10 * diag;
  const double max_step = options.max_step > 0 ? options.max_step : 0.1 * diag;
  const double max_travel = options.max_travel > 0 ? options.max_travel : 0.5 * diag;

  ProjectionResult r;
  r.point = start;
  // An infinite tolerance (a box whose diagonal overflows, as for a sphere of radius 1e160)
  // would accept the start point, however far from the surface, as converged.
  if (!(tol > 0 && std::isfinite(tol) && std::isfinite(max_step) && std::isfinite(max_travel))) {
    r.status = ProjectionStatus::OutOfRange;
    return r;
  }
  Vec3 g;
  for (r.iterations = 0; r.iterations <= options.max_iterations; ++r.iterations) {
    const double f = field.value_gradient(r.point, g);
    if (r.iterations == 0) r.start_gradient = g;
    const double g2 = g.squaredNorm();
    if (!std::isfinite(f) || !std::isfinite(g2)) {
      r.status = ProjectionStatus::NotFinite;
      return r;
    }
    // A gradient this small relative to the value cannot give a trustworthy step.
    if (g2 <= 1e-300 || std::sqrt(g2) * diag < 1e-12 * std::abs(f)) {
      r.status = ProjectionStatus::VanishingGradient;
      return r;
    }
    r.residual = std::abs(f) / std::sqrt(g2);
    if (r.residual <= tol) {
      r.status = ProjectionStatus::Converged;
      return r;
    }
    if (r.iterations == options.max_iterations) break;
    Vec3 step = -(f / g2) * g;
    const double len = step.norm();
    if (len > max_step) step *= max_step / len;
    // A step that rounds to nothing would repeat until the iteration limit: say so now.
    if (r.point + step == r.point) {
      r.status = ProjectionStatus::NoProgress;
      return r;
    }
    r.point += step;
    if ((r.point - start).norm() > max_travel) {
      r.status = ProjectionStatus::TooFar;
      return r;
    }
  }
  r.status = ProjectionStatus::MaxIterations;
  return r;
}

}  // namespace cdp
