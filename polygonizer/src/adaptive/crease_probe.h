// The crease probe of fields meshed as smooth (a crease met on the way: the tracker's placements,
// the repair's crease vertices), defined once for both: a field's gradient read a short step to
// either side of a surface point turns by more than curvature can turn it over that step.
#pragma once

#include <cdp/core/field.h>

#include <array>

namespace cdp::adaptive {

// The probe's step as a share of the box's diagonal. Newton leaves points within 1e-10 of the
// diagonal from the surface, hence from a crease they landed on; a probe this far away is clear
// of that and still on the crease's two pieces.
inline constexpr double kCreaseProbe = 1e-7;
// Gradients more than 10 degrees apart across such a probe mean a crease, not curvature.
inline constexpr double kCreaseCosine = 0.985;

// Where the probes of a surface point go, for a box of diagonal `diagonal`.
struct CreaseProbe {
  explicit CreaseProbe(double diagonal) : step(kCreaseProbe * diagonal) {}
  // The two points probed around x along the unit direction n (a normal): just inside, then
  // just outside. On a crease of max(f, g) (or min) the gradient at x is one side's, and one of
  // the two makes the other side's piece the active one.
  std::array<Vec3, 2> points(const Vec3& x, const Vec3& n) const { return {Vec3(x - step * n), Vec3(x + step * n)}; }
  double step;
};

}  // namespace cdp::adaptive
