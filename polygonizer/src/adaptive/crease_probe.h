// The crease test of fields meshed as smooth (a crease met on the way: the tracker's placements,
// the repair's crease vertices), defined once for both: a field's gradient probed a short step
// to either side of a point turns by more than curvature can turn it over that step.
#pragma once

namespace cdp::adaptive {

// The probe's step as a share of the box's diagonal. Newton leaves points within 1e-10 of the
// diagonal from the surface, hence from a crease they landed on; a probe this far away is clear
// of that and still on the crease's two pieces.
inline constexpr double kCreaseProbe = 1e-7;
// Gradients more than 10 degrees apart across such a probe mean a crease, not curvature.
inline constexpr double kCreaseCosine = 0.985;

}  // namespace cdp::adaptive
