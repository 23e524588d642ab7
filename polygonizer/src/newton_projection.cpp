#include <polygonizer/newton_projection.h>

#include <algorithm>
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

// One projection's tolerance and limits, with every default resolved.
struct Limits {
  double diag = 0, tol = 0, max_step = 0, max_travel = 0;
  int max_iterations = 0;
  // An infinite tolerance (a box whose diagonal overflows, as for a sphere of radius 1e160)
  // would accept the start point, however far from the surface, as converged.
  bool usable() const { return tol > 0 && std::isfinite(tol) && std::isfinite(max_step) && std::isfinite(max_travel); }
};

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
  if (!l.usable()) {
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
  if (options.size() != starts.size())
    throw std::invalid_argument("project_to_surface: " + std::to_string(starts.size()) + " start points but " +
                                std::to_string(options.size()) + " options");
  const std::size_t n = starts.size();
  std::vector<ProjectionResult> results(n);
  std::vector<Limits> limits(n);
  std::vector<std::size_t> active;  // the points still iterating, in order
  active.reserve(n);
  int rounds = 0;
  for (std::size_t i = 0; i < n; ++i) {
    results[i].point = starts[i];
    limits[i] = resolve(field, options[i]);
    if (!limits[i].usable()) results[i].status = ProjectionStatus::OutOfRange;
    else if (limits[i].max_iterations >= 0) active.push_back(i), rounds = std::max(rounds, limits[i].max_iterations + 1);
  }
  std::vector<Vec3> points(active.size()), gradients(active.size());
  std::vector<double> values(active.size());
  for (int round = 0; round < rounds && !active.empty(); ++round) {
    const std::size_t m = active.size();
    for (std::size_t k = 0; k < m; ++k) points[k] = results[active[k]].point;
    field.values_gradients(points.data(), values.data(), gradients.data(), m);
    std::size_t kept = 0;
    for (std::size_t k = 0; k < m; ++k) {
      const std::size_t i = active[k];
      if (!newton_round(results[i], starts[i], values[k], gradients[k], limits[i])) active[kept++] = i;
    }
    active.resize(kept);
  }
  return results;
}

}  // namespace cdp
