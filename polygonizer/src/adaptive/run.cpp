// run_once: one run of the adaptive polygonizer, as a short driver over the stages, and the
// recoveries it makes when an attempt fails (kRecoveries).
#include "run.h"

#include "blocks.h"
#include "failure_message.h"
#include "resolve_settings.h"
#include "run_state.h"
#include "stage_checks.h"
#include "surface_gaps.h"
#include "../background_release.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <stdexcept>

namespace cdp::adaptive {

// A recovery: the attempt made again with something changed, up to `runs` times.
enum class RecoveryKind { AroundNecks, Carefully, FinerTurns };
struct Recovery {
  RecoveryKind kind;
  const char* name;
  int runs;
  bool after_limit;  // tried after a LimitExceededError too, not only after a NoSurfaceError
  bool zones_necks;  // each run first zones the necks the attempt before it stepped over (Run::zone_missed_necks)
  bool strict;       // the mesh must pass a stricter test too: no two components facing across the solid
  // A further run after any failure; otherwise only after a NoSurfaceError that found necks stepped over.
  bool after_any_failure;
};

namespace {

// A neck or tunnel a run stepped over is approached with edges as short as its radius (not
// below min_edge) from kNeckZoneEdges of that run's edges around it, so that the fronts reach
// it with edges that cannot jump it: a front outside the ball places points at most about an
// edge into it, and the grading lets the edges grow back only by kGrowth per edge. (3 edges
// meshed the 11 runs of the topology sweep as well, with 1.1-2.9 times the triangles.)
constexpr double kNeckZoneEdges = 1.5;
// The careful run's edges turn the normal by at most one radian (Sizing::max_turn).
constexpr double kCarefulMaxTurn = 1;
// The finer runs' turns; in factor mode shares of the factor's own, 1 / factor (a turn of 0.5 at
// the default factor 2 would repeat the careful run): the sizing of twice and four times the
// factor where the surface bends most.
constexpr std::array<double, 2> kFinerTurns{0.5, 0.25};

// The recoveries, in the order they are tried after a run's first attempt fails. The first that
// meshes ends the run; when all fail, the first attempt's error stands. None where
// remeshing_allowed says no, nor after a failure none mends (RunFailure::final), nor for a field
// whose seeding found no sign change; only the polygonizer's own errors are recovered from (an
// exception from a callable field or a cancellation goes on unchanged). Only after a failure,
// so that every surface that meshes at the first attempt comes out as it always has.
constexpr std::array<Recovery, 3> kRecoveries{{
    // The mesh stepped over necks (check_necks): made again as it was, with balls of
    // short edges around them (kNeckZoneEdges). The rest of its mesh passed every check, and the
    // careful run's sizing is finer everywhere and fails more often (blobs38 of the topology
    // sweep at factor 1: its careful mesh intersected itself far from the neck). Again while a
    // run steps over more necks.
    {RecoveryKind::AroundNecks, "around_necks", 3, false, true, false, false},
    // Settings::anticipate and the rollbacks on from the start, every edge turning the normal by
    // at most kCarefulMaxTurn, the necks' balls so far: where a front with long edges met a neck
    // narrower than them (the fifty blobs at factor 2 capped one off, and a second seed then
    // meshed the whole blob again over the first mesh), the new points are placed closer. Again
    // with a ball at each further neck it steps over (blobs30 of the topology sweep at factors 1
    // and 2: the careful run, its curvature sizing finer everywhere, met a second neck). The
    // surface is meshed as smooth when the crease-aware meshing failed (Run::fall_back).
    {RecoveryKind::Carefully, "carefully", 3, true, true, true, false},
    // After the careful runs: edges that turn the normal by half as much, then a quarter
    // (kFinerTurns). A front of edges as long as the radius of curvature that met a fillet or neck
    // tighter than min_edge (the dense blob fields of the topology sweep at factor 1 and at
    // coarse tolerances, which mesh at factor 3) reaches it with edges short enough to close
    // there. The mesh is then finer than asked where the surface bends (stats careful_max_turn).
    {RecoveryKind::FinerTurns, "finer_turns", static_cast<int>(kFinerTurns.size()), true, false, true, true},
}};

}  // namespace

Run::Run(const Field& field, const AdaptiveOptions& options, PhaseLedger& phases, const RunRequest& request)
    : ctx{field, options, phases}, request(request) {}

Run::~Run() {
  if (!ctx.options.cancel.cancelled()) return;
  // Plain data only: the tracker keeps its callbacks (a Python caller's, say) to be let go of
  // here, on the caller's thread.
  if (tracking.tracker) tracking.tracker->release_in_background();
  detail::release_in_background(result.mesh, creases, blocks, seeds.grid);
}

void Run::prepare() {
  ctx.enter("seed_grid", "sampling the seed grid");
  // Within the seed grid's phase: resolving asks has_pieces, whose first call samples a grid of
  // its own to classify the field's branch points (Field::branch_kinds, once per field).
  resolved = resolve_settings(ctx.field, ctx.options);
  seeds = sample_seed_grid_stage(ctx.field, ctx.options, resolved);
  settings = resolved;
  settings.look_ahead = request.look_ahead;
  if (request.max_turn > 0) settings.sizing.max_turn = request.max_turn;
  settings.hash_cell = seeds.hash_cell;
  // The seed grid and the hash cell's curvature sample: the fixed cost before any triangle.
  seed_grid_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Creases first (CreaseHandling::Follow): the patches they bound are meshed from them, and the
  // seeding meets that mesh as finished surface, so only components without creases are left to it.
  if (follows_creases(ctx.options)) {
    ctx.enter("creases");  // the tracing too; AdaptiveOptions::phase hears of it where it finds creases
    creases = lay_out_creases(ctx.field, ctx.options, settings, seeds.estimated_area, &seeds.grid);
    // A bend the patches' trackers met is one the run met: a surface meshed wholly in patches
    // left the run none, and no rerun for the tolerance or a thin feature followed.
    if (creases.mesh && creases.mesh->tightest.first < tracking.tightest.first) tracking.tightest = creases.mesh->tightest;
    // A finer tracing grid that measured more surface than the seed grid bounds the seeds' fronts too.
    seeds.estimated_area = std::max(seeds.estimated_area, creases.estimated_area);
  }
  // Blocks where no crease patches were meshed: the patches' fronts run serially for now.
  if (uses_blocks(ctx.options) && ctx.options.variant == Variant::Improved && !creases.mesh) {
    // Those bounds are on one tracker's work (its steps; its searches averaged over windows of
    // Tracker's kSearchWindow steps, more than a block takes): each block's tracker would keep
    // them on its own, the whole run not.
    if (ctx.options.max_steps > 0 || ctx.options.max_search_visits > 0) {
      blocks.report.fallback = "the caller's max_steps or max_search_visits bound one tracker: tracked alone";
      return;
    }
    // A surface too small to cut is tracked alone (mesh_blocks only reports its estimate).
    if (worth_cutting(ctx.field, seeds)) ctx.enter("tracking", "meshing blocks");
    const QualityOptions repair = repair_options(ctx, resolved, creases);
    blocks = mesh_blocks(ctx.field, ctx.options, settings, seeds, &repair);
    // A bend the blocks' trackers met is one the run met, kept or not (a black box's kink among them).
    if (blocks.tightest.first < tracking.tightest.first) tracking.tightest = blocks.tightest;
  }
}

const CreaseMesh* Run::finished() const {
  if (creases.mesh) return &*creases.mesh;
  if (blocks.mesh) return &*blocks.mesh;
  return nullptr;
}

void Run::track() {
  if (blocks.mesh && blocks.adopted) throw std::logic_error("adaptive: the blocks' mesh adopted twice");
  // The blocks' mesh moves into the tracker's, as a run made again tracks alone (drop_blocks):
  // their copy was a fifth of the peak memory (94 of 444 MB, the torus at tolerance 1e-5). The
  // crease patches' mesh is copied: a recovery adopts it again.
  CreaseMesh* adopt = creases.mesh ? &*creases.mesh : blocks.mesh ? &*blocks.mesh : nullptr;
  const bool consume = !creases.mesh && blocks.mesh;
  // Whatever track_surface throws, the arrays may be gone from here on: adopting them again
  // would adopt nothing.
  if (consume) blocks.adopted = true;
  track_surface(ctx, seeds, adopt, consume, creases.components + blocks.components, settings, mesh(), tracking);
  // Moved-from vectors are left in an unspecified state: emptied here, so that only the
  // counters are certain to remain (and nothing the tracker did not take is held).
  if (consume) {
    CreaseMesh& m = *blocks.mesh;
    m.mesh = Mesh{};
    for (std::vector<double>* v : {&m.target, &m.mac, &m.shape_index}) std::vector<double>().swap(*v);
  }
}

void Run::drop_blocks(const char* why) {
  if (!blocks.mesh) return;
  blocks.report.fallback = why;
  blocks.mesh.reset();
  blocks.components = 0;
}

bool Run::fall_back(const std::exception& e) {
  if (blocks.mesh) {
    drop_blocks(e.what());
  } else {
    if (!creases.mesh) return false;
    creases.fallback = e.what();
    creases.mesh.reset();
    creases.components = 0;
  }
  track();
  return true;
}

std::size_t Run::repair_and_check() {
  // A neck stepped over fails before the repair (check_necks: the repair makes no handle).
  ctx.enter("checks");
  // The blocks' trackers' critical starts too: a neck their fronts stepped over is found only
  // from them (blobs39 of the topology sweep at chord 1e-2 lost a handle without them).
  std::vector<CriticalStart> starts = tracking.tracker->critical_starts();
  if (blocks.mesh) starts.insert(starts.begin(), blocks.critical_starts.begin(), blocks.critical_starts.end());
  // And the saddles earlier attempts found stepped over, whatever this mesh's vertices predict.
  // The smooth union of two unit balls 0.09999 apart (k = 0.2, a neck 0.0065 wide) at chord 1e-2
  // was found three times; the careful run after them, with edges of min_edge (0.014) round the
  // neck, placed no vertex within kCriticalReach of its edges of it, cut the neck again and ended
  // with two components and exit 0. First, so that the bound on the walks never leaves them out.
  starts.insert(starts.begin(), necks_missed_before.begin(), necks_missed_before.end());
  try {
    check_necks(ctx.field, mesh(), starts, resolved.sizing.min_edge, necks);
  } catch (const MissedNeckError&) {
    for (const MissedNeck& m : necks.missed) necks_missed_before.push_back({m.point, Vec3::Zero(), m.edge});
    throw;
  }
  quality = {};
  BandChanges band;
  quality = repair_mesh(ctx, resolved, seeds, creases, blocks, tracking, mesh(), band, &sheets_gap);
  if (resolved.curvature_properties) {
    if (ctx.options.variant != Variant::Improved) ctx.phases.enter("quality");
    add_curvature_properties(ctx.field, *tracking.tracker, quality, band, mesh());
  }
  // Nothing but the tracker's counters is asked for from here on; the checks are the run's peak.
  tracking.tracker->release_bulk();
  ctx.enter("checks", "checking the mesh");
  // After blocks in lockstep, the band's repair can cut a black box's rounded edges
  // (check_bends_kept): the run then tracks the surface alone (attempt's fall_back).
  if (blocks.mesh && blocks.report.lockstep_batches > 0) check_bends_kept(ctx.field, mesh(), settings.sizing);
  return check_mesh(mesh(), expected_components(), ctx.options.check_self_intersections, ctx.options.threads,
                    ctx.options.cancel, &band.sealed, &ctx.field, resolved.sizing.min_edge, &sheets_gap);
}

// A meshing whose seeding found thin bridges (seeding.h) is made again with them seeded first
// only where it failed, so that every surface that meshed before meshes as it did. The bridges
// are tried once in a run: every recovery after a failed try would meet the same ones (the two
// balls joined by a rod thinner than min_edge fail every attempt of the run as given in 0.01 s;
// with min_edge lowered, the rod seeded after the balls runs into their meshes, and seeded
// first meshes in 0.2-5 s).
void Run::attempt() {
  tracking.bridges.first.clear();
  try {
    attempt_meshing();
  } catch (const UnsearchedCellsError&) {
    throw;
  } catch (const NoSurfaceError&) {
    if (!attempt_bridges_first()) throw;
  } catch (const LimitExceededError&) {
    if (!attempt_bridges_first()) throw;
  }
}

bool Run::attempt_bridges_first() {
  std::vector<Vec3> fresh;
  for (const Vec3& p : tracking.bridges.found)
    if (std::find(bridges_tried.begin(), bridges_tried.end(), p) == bridges_tried.end()) {
      fresh.push_back(p);
      bridges_tried.push_back(p);
    }
  if (fresh.empty() || !remeshing_allowed(ctx.options)) return false;
  const NeckSearch failed_necks = necks;
  const std::optional<double> failed_gap = sheets_gap;
  tracking.bridges.first = std::move(fresh);
  try {
    attempt_meshing();
    return true;
  } catch (const UnsearchedCellsError&) {
    throw;
  } catch (const NoSurfaceError&) {
  } catch (const LimitExceededError&) {
  }
  necks = failed_necks;
  sheets_gap = failed_gap;
  tracking.bridges.first.clear();
  return false;
}

void Run::attempt_meshing() {
  necks = {};
  sheets_gap.reset();
  // A crease-aware mesh that fails on the way (a component left to the seeds that then stalls,
  // patches that intersect) is not the end: the surface is meshed again as a smooth one
  // (fall_back), and the stats say why.
  try {
    if (blocks.kink) std::rethrow_exception(blocks.kink);
    track();
    // The patches' topology before the repair works on it; intersections after (the repair
    // removes some that chords on the two faces of an acute crease make). Not the blocks': their
    // pieces were each repaired already, and a NoSurfaceError of the checks after the band's
    // repair falls back to tracking alone the same way.
    if (creases.mesh) {
      ctx.enter("checks");
      check_mesh(mesh(), expected_components(), false, ctx.options.threads, ctx.options.cancel);
    }
    components = repair_and_check();
  } catch (const MissedNeckError&) {
    throw;
  } catch (const UnsearchedCellsError&) {
    throw;
  } catch (const NoSurfaceError& e) {
    if (!fall_back(e)) throw;
    components = repair_and_check();
  } catch (const LimitExceededError& e) {
    if (!fall_back(e)) throw;
    components = repair_and_check();
  }
  check_components_apart(ctx.field, mesh(), components);
}

void Run::zone_missed_necks() {
  for (const MissedNeck& m : necks.missed)
    settings.finer_zones.push_back(
        {m.point, 0.5 * m.width + kNeckZoneEdges * m.edge, std::max(resolved.sizing.min_edge, 0.5 * m.width)});
}

namespace {

// A neck less than kUnmeshableNeck times min_edge wide cannot be meshed with edges at least
// min_edge long: its waist, about pi times its width around, would hold fewer than the three
// edges a tube needs. (A neck 0.96 times min_edge wide was meshed, its edges shorter than
// min_edge there: the crowd of 200 blobs at tolerance 1e-3.)
constexpr double kUnmeshableNeck = 0.5;
// A neck less than kRezonedNeck times min_edge wide that an attempt steps over again inside the
// ball of short edges an earlier attempt of the run put round it (zone_missed_necks) is not
// mended by more attempts at that min_edge either: its waist holds fewer than about six edges of
// min_edge, and the zone already asked for them. cdp.sdf's smooth barbell (two balls of radius
// 0.5 joined by a rod 0.005 wide, k = 0.02) at tolerance 1e-3 stepped over its rod, 0.0039 wide
// with min_edge 0.0038, in all ten attempts of the run as given (23 s, one of them 20 s and
// 1.8 million triangles) before the run with min_edge lowered meshed it in 0.3 s. Over the
// topology sweep (480 runs) and the SDF sweep (646) nothing changes; of the 105 thin-feature
// runs, 9 barbells with rods 0.01 wide mesh 2-24 times faster, the same topology.
constexpr double kRezonedNeck = 2;

}  // namespace

// Every recovery keeps min_edge (zone_missed_necks' balls too), so an attempt that stepped over
// a neck too narrow for it dooms the rest: the crowd of 200 blobs at factor 3 stepped over the
// same neck, 0.0058 wide with min_edge 0.018, in its first attempt and its eight recoveries
// (16 s) before the run with min_edge lowered meshed it (4 s). Over the test suite, the topology
// sweep and the experiment fields at factors 1, 2, 5 and 12 and tolerances 1e-3 and 1e-4, only
// the crowd steps over such a neck, and none of its recoveries meshed after it had. So does a
// narrow neck stepped over again inside its zone (kRezonedNeck).
bool Run::needs_shorter_edges() {
  if (!request.lowered_min_edge_follows) return false;
  const double min_edge = resolved.sizing.min_edge;
  const auto zoned_before = [&](const MissedNeck& m) {
    return std::any_of(settings.finer_zones.begin(), settings.finer_zones.end(),
                       [&](const FinerZone& z) { return (m.point - z.center).norm() <= z.radius; });
  };
  const bool unmeshable = std::any_of(necks.missed.begin(), necks.missed.end(), [&](const MissedNeck& m) {
    return m.width < kUnmeshableNeck * min_edge || (m.width < kRezonedNeck * min_edge && zoned_before(m));
  });
  if (!unmeshable) return false;
  tracking.note_tightest();
  doomed = lowered_min_edge(ctx.field, ctx.options, tracking.tightest.first).has_value();
  return doomed;
}

bool Run::recover(const Recovery& r, bool after_limit) {
  if (doomed || (after_limit && !r.after_limit)) return false;
  // The blocks were meshed with the first attempt's settings, which a recovery changes.
  drop_blocks("a recovery meshes by tracking alone");
  const bool may_mesh_again = remeshing_allowed(ctx.options);
  switch (r.kind) {
    case RecoveryKind::AroundNecks:
      if (!may_mesh_again || necks.missed.empty()) return false;
      break;
    case RecoveryKind::Carefully:
      if (!may_mesh_again || tracking.no_crossing) return false;
      settings.anticipate = careful = true;
      settings.sizing.max_turn = kCarefulMaxTurn;
      break;
    case RecoveryKind::FinerTurns:
      if (!careful) return false;
      break;
  }
  for (int run = 0; run < r.runs; ++run) {
    if (r.kind == RecoveryKind::AroundNecks) ++neck_reruns;
    if (r.kind == RecoveryKind::FinerTurns)
      settings.sizing.max_turn =
          resolved.sizing.mode == SizingMode::Factor ? kFinerTurns[run] / resolved.sizing.factor : kFinerTurns[run];
    if (r.zones_necks) zone_missed_necks();
    bool no_surface = false;
    try {
      attempt();
      // A run made again strictly must pass a test stricter than attempt's own: no two components
      // may face each other across the solid at all, joined or not (a shell thinner than two
      // edges keeps its first error).
      if (!r.strict || facing_across_solid(ctx.field, mesh(), 1).empty()) return true;
    } catch (const NoSurfaceError&) {
      if (needs_shorter_edges()) return false;
      no_surface = true;
    } catch (const LimitExceededError&) {
      // the neighbour searches' bound: shorter edges at the fillet may not crowd it
    }
    if (!r.after_any_failure && !(no_surface && !necks.missed.empty())) return false;
  }
  return false;
}

PolygonizeResult Run::mesh_with_recoveries(RunFailure& failure) {
  const PhaseCloser closer{ctx.phases};
  const detail::ScopedPassClock time_passes(&passes);  // this run's passes on this thread
  prepare();
  // `stuck`: the attempt ended on a bound of the tracking (LimitExceededError), not on a check of
  // its mesh, which a neck stepped over fails and a run with min_edge lowered meshes at little
  // cost (noise_in_volume).
  const auto hopeless = [&](bool stuck) {
    tracking.note_tightest();
    return failure.final = kink_in_black_box(ctx.field, tracking.tightest) ||
                           (stuck && noise_in_volume(ctx.field, resolved, tracking.tightest));
  };
  const auto recover_all = [&](bool after_limit) {
    return std::any_of(kRecoveries.begin(), kRecoveries.end(), [&](const Recovery& r) { return recover(r, after_limit); });
  };
  // An error of the run says what the crease-aware meshing ran into first (failure_message.h).
  const auto why = [&](const std::exception& e) {
    tracking.note_tightest();
    failure.tightest = tracking.tightest;
    // A recovery may be what met the kink: no run made again after it either.
    failure.final = failure.final || kink_in_black_box(ctx.field, tracking.tightest);
    return explain_failure(ctx.field, ctx.options, resolved, e.what(), tracking.tightest, creases.fallback);
  };
  try {
    try {
      attempt();
    } catch (const NoSurfaceError&) {
      failure.sheets_gap = sheets_gap;  // before the recoveries mesh again
      if (hopeless(false) || needs_shorter_edges() || !recover_all(false)) throw;
    } catch (const UnsearchedCellsError&) {
      throw;
    } catch (const LimitExceededError&) {
      // Before the recoveries replace the tracker that stopped.
      if (tracking.tracker) failure.sheets_gap = tracking.tracker->sheets_gap();
      if (hopeless(true) || !recover_all(true)) throw;
    }
  } catch (const NoSurfaceError& e) {
    throw NoSurfaceError(why(e));
  } catch (const UnsearchedCellsError& e) {
    throw UnsearchedCellsError(why(e));
  } catch (const LimitExceededError& e) {
    throw LimitExceededError(why(e));
  }
  ctx.phases.close();  // the run's time ends here, the ledger's with it
  write_stats();
  if (ctx.options.progress) ctx.options.progress(1.0);
  return std::move(result);
}

PolygonizeResult run_once(const Field& field, const AdaptiveOptions& options, PhaseLedger& phases,
                          const RunRequest& request, RunFailure& failure) {
  Run run(field, options, phases, request);
  return run.mesh_with_recoveries(failure);
}

}  // namespace cdp::adaptive
