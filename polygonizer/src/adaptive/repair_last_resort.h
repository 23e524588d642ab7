// What the refinement's estimate cannot clear (it keeps kToleranceMargin for its own error),
// measured as the tolerance is defined, densely over the triangle; and the last resort for a
// triangle still beyond the tolerance there: a ridge or fillet narrower than the edges around
// it, whose corners' normals are too far apart for a midpoint split to face like the surface,
// or edges under twice min_edge on a bend just above what min_edge can follow.
#pragma once

#include "repair_context.h"

#include <vector>

namespace cdp::adaptive::repair {

// Rounds of the last resort (see last_resort) on what the refinement left beyond the tolerance.
// A round ends with the refinement and the angle repair of what it split.
inline constexpr int kLastResortRounds = 4;

// A triangle measured farther from the surface than the tolerance: its slot and corners when
// measured, by how much, and the surface point its farthest sample's Newton path landed on.
struct Beyond {
  int t;
  Tri T;
  double d;
  ProjectionResult worst;
};

// The live triangles of `work` whose estimate does not clear them, measured densely
// (RepairContext::sampled_distance, each at most once per call); those beyond the tolerance
// there. Counts QualityReport::measured_densely.
// \pre ctx.options_.tolerance > 0.
std::vector<Beyond> measure_densely(RepairContext& ctx, const std::vector<int>& work);

// Any edge of b's triangle halved, longest first, down to halves of
// QualityOptions::last_resort_min_edge; else a new vertex inside it at the surface point nearest
// its farthest sample, which splits it in three. The same checks as every split (the new
// triangles face like the surface, intersect nothing); the angles are repaired after.
// \return whether it split (true too for a triangle changed since it was measured: nothing to
// do). Counts QualityReport::last_resorts.
bool last_resort(RepairContext& ctx, const Beyond& b);

}  // namespace cdp::adaptive::repair
