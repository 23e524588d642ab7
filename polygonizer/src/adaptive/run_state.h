// The state of one run (run.h) across its attempts: what its stages made, and what its
// recoveries changed. Private to run.cpp and run_report.cpp.
#pragma once

#include "blocks.h"
#include "missed_necks.h"
#include "quality.h"
#include "run.h"
#include "run_context.h"
#include "stage_creases.h"
#include "stage_repair.h"
#include "stage_seed_grid.h"
#include "stage_tracking.h"
#include "../parallel.h"

#include <chrono>
#include <cstddef>
#include <exception>

namespace cdp::adaptive {

struct Recovery;

class Run {
 public:
  Run(const Field& field, const AdaptiveOptions& options, PhaseLedger& phases, const RunRequest& request);
  // A cancelled run's memory (the tracker's hashes and arrays, the mesh, the crease layout, the
  // seed grid) is freed on a thread of its own (background_release.h), so that CancelledError
  // reaches the caller at once.
  ~Run();
  Run(const Run&) = delete;
  Run& operator=(const Run&) = delete;
  PolygonizeResult mesh_with_recoveries(RunFailure& failure);

 private:
  // The stages before the first triangle: settings, seed grid, crease layout, blocks.
  void prepare();
  // One attempt: tracking, repair, checks (throws their errors); where it fails after its
  // seeding found thin bridges not tried before, once more with them seeded first.
  void attempt();
  // attempt's meshing with the bridges seeded first as tracking.bridges.first says.
  void attempt_meshing();
  // The attempt made again with the new thin bridges the failed one found seeded first; true
  // when it meshed. When it fails too, the failed attempt's necks and sheets stand.
  bool attempt_bridges_first();
  // Drops a crease layout whose meshing failed with `e` and meshes the surface as smooth;
  // false where there was none.
  bool fall_back(const std::exception& e);
  // The mesh adopted as finished before the tracker seeds: the crease patches' or the blocks'
  // (whose arrays track moves into the tracker's; their counters stay).
  const CreaseMesh* finished() const;
  // track_surface after it.
  void track();
  // Drops the blocks' mesh (their `fallback` says why): the surface is tracked alone from then on.
  void drop_blocks(const char* why);
  // The tracked mesh's neck search (check_necks, into `necks`), its repair, its checks.
  std::size_t repair_and_check();
  // Adds a ball of finer edges around each neck the last attempt stepped over.
  void zone_missed_necks();
  // Whether the last attempt failed where no recovery can mend it and a run with a lowered
  // min_edge follows (RunRequest::lowered_min_edge_follows): it stepped over a neck too narrow
  // for edges of min_edge (kUnmeshableNeck), or stepped over again a narrow neck inside the
  // zone an earlier attempt put round it (kRezonedNeck). Sets `doomed`, which ends the recoveries.
  bool needs_shorter_edges();
  // Tries one recovery of kRecoveries; true when it meshed.
  bool recover(const Recovery& r, bool after_limit);
  // The stats of the run's mesh (run_report.cpp).
  void write_stats();

  Mesh& mesh() { return result.mesh; }
  // The components the checks expect: one per seed, and the crease patches'.
  std::size_t expected_components() const { return tracking.seeding.seeds + creases.components + blocks.components; }

  RunContext ctx;
  RunRequest request;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  EvaluationCounts before = ctx.field.counts();

  Settings resolved;  // as the options resolve
  Settings settings;  // as the request and the recoveries change them
  SeedGridStage seeds;
  double seed_grid_seconds = 0;
  CreaseLayout creases;
  BlockMeshing blocks;  // AdaptiveOptions::blocks
  detail::PassClock passes;  // the run's data-parallel passes on its thread (BlocksReport::pass_seconds)
  PolygonizeResult result;
  Tracking tracking;
  QualityReport quality;
  std::size_t components = 0;
  NeckSearch necks;  // of the last attempt
  // Two sheets of the surface closer than the edges where this attempt's mesh intersected itself
  // (check_mesh): their distance (RunFailure::sheets_gap).
  std::optional<double> sheets_gap;
  // The saddles of the necks earlier attempts stepped over, walked from again after every later
  // attempt (repair_and_check): the finer edges a rerun puts round a neck can leave no vertex near
  // enough to predict it, and the neck then went unseen.
  std::vector<CriticalStart> necks_missed_before;
  // The thin bridges seeded first so far (attempt_bridges_first): each tried once in the run.
  std::vector<Vec3> bridges_tried;
  bool careful = false;  // the careful recovery ran
  bool doomed = false;   // no recovery can mend what failed (needs_shorter_edges)
  std::size_t neck_reruns = 0;
};

}  // namespace cdp::adaptive
