// The tracking stage of a run: the paper's surface tracker grows the mesh from a seed on every
// component not yet covered (seeding.h), after the crease patches' mesh where there is one.
#pragma once

#include "run_context.h"
#include "seeding.h"
#include "stage_creases.h"
#include "stage_seed_grid.h"
#include "tracker.h"

#include <limits>
#include <optional>
#include <utility>

namespace cdp::adaptive {

// The radius of curvature at a tracker's tightest bend, and where.
using Bend = std::pair<double, Vec3>;
inline Bend no_bend() { return {std::numeric_limits<double>::infinity(), Vec3::Zero()}; }

struct Tracking {
  std::optional<Tracker> tracker;  // of the last meshing (its counters go into the stats)
  SeedingReport seeding;
  // Thin bridges (seeding.h): seeded first (the run's choice), found by the last meshing.
  Bridges bridges;
  bool remeshed = false;     // meshed again with the rollbacks on after a stalled front
  bool no_crossing = false;  // the seeding found no sign change at all
  // The tightest bend every tracker of the run met so far (note_tightest): below min_edge the
  // surface has detail that edges of min_edge cannot follow (the perturbed Barth sextic's necks
  // bend with a radius of 0.0083, min_edge is 0.0145), and a failure is reported as such.
  Bend tightest = no_bend();
  void note_tightest() {
    if (tracker && tracker->tightest_bend().first < tightest.first) tightest = tracker->tightest_bend();
  }
};

// The small-component search (seeding.h) stopped at its budget with cells left that may hold a
// component: the mesh may miss one, so the run ends here, without the recoveries or the runs
// made again (each would meet the same cells, after longer).
struct UnsearchedCellsError : LimitExceededError {
  using LimitExceededError::LimitExceededError;
};

// Meshes the whole surface into `mesh` (emptied first): `finished` (the crease patches' or the
// blocks' mesh, of `finished_components` components) adopted as it is, if given, then the
// tracker from the seeds. A stalled front (StalledFrontError) is where a front that ran over
// finished mesh ends, thousands of steps later (the MPU models at some factors): the surface is
// then meshed again from the start with the rollbacks on (`remeshed`). With `consume`, the
// finished mesh's arrays are moved into `mesh` and the tracker rather than copied (the blocks'
// mesh, adopted once: a copy of the whole mesh was a fifth of a run's peak memory), and a
// stalled front is not meshed again here (the caller tracks alone). The seeding starts from
// tracking.bridges.first before anything else and fills tracking.bridges.found (not with
// `consume`: the finished mesh cannot be adopted again for a meshing with them first).
// \throw NoSurfaceError when the field has no sign change, when no seed could be meshed, when
//        sign changes are left uncovered; the first run's StalledFrontError when the second
//        fails (or with `consume`); UnsearchedCellsError where the small-component search left
//        cells unsplit; LimitExceededError for the tracker's bounds; CancelledError.
void track_surface(const RunContext& run, const SeedGridStage& seeds, CreaseMesh* finished, bool consume,
                   std::size_t finished_components, Settings& settings, Mesh& mesh, Tracking& tracking);

}  // namespace cdp::adaptive
