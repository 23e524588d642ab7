// One run of the adaptive polygonizer with one sizing: the stages in order (resolve_settings,
// stage_seed_grid, stage_creases, stage_tracking, stage_repair, stage_checks), and, when an
// attempt fails, the recoveries of kRecoveries (run.cpp), each an attempt made again with
// something changed. polygonize_adaptive (adaptive_polygonizer.cpp) makes the runs of kRuns.
#pragma once

#include "phase_ledger.h"
#include "stage_tracking.h"

#include <cdp/core/adaptive_polygonizer.h>

namespace cdp::adaptive {

// What a run changes from the options as given (the runs of kRuns).
struct RunRequest {
  // Settings::look_ahead on every front (the run made again when a mesh misses the quality bounds).
  bool look_ahead = false;
  // Positive: Sizing::max_turn from the start, the crease-aware patches included (the last run
  // in tolerance mode); stats "turn_limited".
  double max_turn = 0;
  // The run as given, which polygonize_adaptive meshes again with a lowered min_edge where it
  // fails at a bend tighter than min_edge (kRuns, lowered_min_edge): the recoveries, which keep
  // min_edge, are skipped where what failed needs shorter edges (Run::needs_shorter_edges).
  bool lowered_min_edge_follows = false;
};

// What a failed run tells polygonize_adaptive: the tightest bend it met (kRuns' lowered min_edge
// follows it), and whether what failed is beyond any run made again (kink_in_black_box,
// noise_in_volume: failure_message.h).
struct RunFailure {
  Bend tightest = no_bend();
  bool final = false;
  // Where the first attempt's fronts ran over finished mesh because two sheets of the surface lie
  // closer than its edges: their distance (Tracker::sheets_gap; kRuns' thin_sheets follows it).
  std::optional<double> sheets_gap;
};

// Meshes the surface with `options` as `request` changes them, the recoveries included.
// `failure` receives what polygonize_adaptive needs to know when the run fails.
// \return the mesh, closed, oriented, manifold, without self-intersections (unless the options
//         turn that check off), with its stats; the phases' times go to `phases`.
// \throw NoSurfaceError, LimitExceededError (the first attempt's error, its cause named:
//        failure_message.h), InvalidInputError (resolve_settings), CancelledError, and what
//        the field throws.
PolygonizeResult run_once(const Field& field, const AdaptiveOptions& options, PhaseLedger& phases,
                          const RunRequest& request, RunFailure& failure);

}  // namespace cdp::adaptive
