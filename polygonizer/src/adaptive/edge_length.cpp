#include "edge_length.h"

#include <cdp/core/curvature.h>
#include <cdp/core/errors.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace cdp::adaptive {

double chord_for_deviation(double r, double eps) {
  // Beyond eps = r the sagitta formula has no solution below the diameter.
  const double e = std::min(eps, r);
  return 2.0 * std::sqrt(std::max(0.0, 2.0 * r * e - e * e));
}

double edge_length(const Sizing& s, double min_radius) {
  double l = s.max_edge;
  if (std::isfinite(min_radius) && min_radius > 0) {
    l = s.mode == SizingMode::Factor ? min_radius / s.factor : chord_for_deviation(min_radius, s.tolerance);
    if (s.max_turn > 0) l = std::min(l, min_radius * s.max_turn);
  }
  return std::clamp(l, s.min_edge, s.max_edge);
}

double seam_edge_length(const Field& field, const Sizing& sizing, const Vec3& p, double own,
                        const std::vector<std::uint8_t>& branch, Field::SeamSideAt at) {
  double best = std::numeric_limits<double>::infinity();
  for (const Field::SmoothSide& side : field.smooth_sides(p, own / kSeamGradation, branch, at)) {
    try {
      const Curvature c = curvature_from_derivatives(side.piece.gradient, side.piece.hessian);
      best = std::min(best, edge_length(sizing, c.min_radius) + kSeamGradation * side.distance);
    } catch (const NoSurfaceError&) {
      // No gradient beyond the seam: nothing to anticipate.
    }
  }
  return best;
}

}  // namespace cdp::adaptive
