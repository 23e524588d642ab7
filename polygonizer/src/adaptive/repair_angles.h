// The angle repair: the few badly shaped triangles the fronts leave behind (smallest angle under
// QualityOptions::improve_below) repaired one by one, smallest angle first, by the context's
// operations in a fixed order (flips of each edge, the collapse of a needle's shortest edge,
// moves of its corners and of their neighbours, a vertex inside the quad of a cap's longest
// edge, the apex of a cap on a crease edge merged onto the crease, collapses of its other
// edges), each applied only where it raises the smallest angle it
// touches by kMinGain and keeps the checks of every operation (repair_context.h).
#pragma once

#include "repair_context.h"

namespace cdp::adaptive::repair {

// Rounds over the triangles under the bound, then over what is still under it among those
// visited or changed, at most kQualityRounds. Sets QualityReport::bad_before (the most seen
// under the bound) and bad_after.
// \throw CancelledError (polled every kPollEvery triangles).
void repair_angles(RepairContext& ctx);

}  // namespace cdp::adaptive::repair
