// The tolerance's refinement: with QualityOptions::tolerance, the triangles whose estimated
// distance to the surface (RepairContext::estimate_distance, from the edge midpoints and the
// centroid) is over kToleranceMargin of the tolerance have their longest edge split at its
// midpoint moved onto the surface, round after round on what the splits made.
#pragma once

#include "repair_context.h"

#include <vector>

namespace cdp::adaptive::repair {

// Splits the triangles of `work` beyond the bound, and then those the splits made, for at most
// kRefineRounds rounds (each halves the longest edge of every triangle still beyond it, and 24
// halvings take any edge below min_edge). A triangle estimated just under the tolerance is
// measured densely first (QualityOptions::measure_near_bound) and left whole where it is
// within kDenseClearShare of the tolerance there. Where the longest edge cannot be split (a
// ridge narrower than the edges), the others are tried on a triangle near the bound. A
// thread-safe field's estimates of a round are made first on all cores (the same on any
// number of threads).
// \pre ctx.options_.tolerance > 0.
// \return the triangles that may still be beyond the bound (a split that failed its checks, or
// rounds run out), sorted.
// \throw CancelledError.
std::vector<int> refine(RepairContext& ctx, std::vector<int> work);

}  // namespace cdp::adaptive::repair
