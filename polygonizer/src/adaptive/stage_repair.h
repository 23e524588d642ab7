// The repair stage of a run (Variant::Improved): the mesh's triangles repaired to the quality
// bounds and, with a tolerance, refined to it (quality.h); the curvature properties measured
// where the repair moved vertices.
#pragma once

#include "quality.h"
#include "run_context.h"
#include "stage_creases.h"
#include "stage_tracking.h"

#include <cstddef>

namespace cdp::adaptive {

// Variant::Improved repairs triangles whose smallest angle is under 30 degrees: the quality
// bounds (stage_checks.h) ask for every triangle at 20 degrees or more and 99% at 30 or more,
// and aiming the repair at the higher bound leaves the lower one a margin.
inline constexpr double kRepairBelowDegrees = 30;

// Repairs `mesh` (tracked, the crease patches' components included in `creases`), where the
// variant repairs. A mesh whose area is well over the seed grid's estimate is checked first
// (check_mesh): it has a front that ran over finished mesh, which no repair mends.
// `resolved`: the run's settings as the options resolve them.
// \return what the repair did (empty for Variant::Paper).
// \throw NoSurfaceError from that check; CancelledError.
QualityReport repair_mesh(const RunContext& run, const Settings& resolved, const SeedGridStage& seeds,
                          const CreaseLayout& creases, const Tracking& tracking, Mesh& mesh);

// The "mac" and "shape_index" vertex scalars (AdaptiveOptions::curvature_properties): the
// tracker's own where the repair changed nothing, else measured again at every vertex.
void add_curvature_properties(const Field& field, const Tracker& tracker, const QualityReport& quality, Mesh& mesh);

}  // namespace cdp::adaptive
