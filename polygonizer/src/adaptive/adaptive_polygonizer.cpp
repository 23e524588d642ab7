// polygonize_adaptive: the runs of kRuns, each a run of the stages with its recoveries (run.h).
// The map of the whole is polygonizer/README.md.
#include "phase_ledger.h"
#include "failure_message.h"
#include "resolve_settings.h"
#include "run.h"
#include "stage_checks.h"

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/errors.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace cdp {

const char* to_string(SizingMode mode) {
  switch (mode) {
    case SizingMode::Factor: return "factor";
    case SizingMode::Tolerance: return "tolerance";
    case SizingMode::Chord: return "chord";
  }
  return "?";
}

const char* to_string(CreaseHandling creases) { return creases == CreaseHandling::Follow ? "follow" : "ignore"; }

const char* to_string(TriangleCountRule rule) {
  return rule == TriangleCountRule::PaperFloor ? "paper_floor" : "hartmann";
}

const char* to_string(Variant variant) { return variant == Variant::Paper ? "paper" : "improved"; }

const PhaseReport& AdaptiveReport::phase(std::string_view name) const {
  const auto it = std::find(kAdaptivePhases.begin(), kAdaptivePhases.end(), name);
  if (it == kAdaptivePhases.end()) throw std::out_of_range("AdaptiveReport: no phase " + std::string(name));
  return phases[static_cast<std::size_t>(it - kAdaptivePhases.begin())];
}

namespace {

// The runs polygonize_adaptive makes, in order. The first is the options as given; the next
// three are made only when every run before them failed (each with its own recoveries, run.cpp),
// the last two only when a mesh misses the tolerance or the quality bounds. Each is made only where
// adaptive::remeshing_allowed (Variant::Improved, no bound of the caller's on triangles, steps
// or searches), and none after a failure that no run made again mends (adaptive::RunFailure::final:
// a black box's kink, a sampled volume's noise).
enum class RunKind { AsGiven, LoweredMinEdge, TurnLimited, ThinSheets, ForTolerance, LookAhead };
struct RunRow {
  RunKind kind;
  const char* name;
};
constexpr std::array<RunRow, 6> kRuns{{
    {RunKind::AsGiven, "as_given"},
    // min_edge lowered to kBendEdgeShare of the tightest bend the first run met, where it failed
    // at a bend tighter than min_edge (adaptive::lowered_min_edge, resolve_settings.h); stats
    // "min_edge_lowered".
    {RunKind::LoweredMinEdge, "lowered_min_edge"},
    // Tolerance mode: every edge turning the normal by at most kTurnLimit from the start, at the
    // lowered min_edge where there is one; stats "turn_limited".
    {RunKind::TurnLimited, "turn_limited"},
    // Where the first run's fronts ran over finished mesh because two sheets of the surface lie
    // closer than its edges (a shell, a plate: Tracker::sheets_closer_than_edges), max_edge
    // twice their distance and a seed grid fine enough to see both (adaptive::options_for_sheets,
    // resolve_settings.h); last, so that what meshed before meshes as before. cdp.sdf's sphere
    // shells 0.01 and 0.02 thick failed at factors 1-3 in 0.2 s; stats "thin_sheets".
    {RunKind::ThinSheets, "thin_sheets"},
    // Tolerance mode: a mesh of the run as given with triangles beyond the tolerance, where the
    // chord the sizing allows round the tightest bend its fronts met is under twice min_edge
    // (left to its default), so that the refinement cannot halve edges that long there: meshed
    // again with min_edge half that chord (adaptive::min_edge_for_tolerance), kept when fewer
    // triangles lie beyond the tolerance and it misses no more quality bounds. cdp.sdf's smooth
    // barbell (two balls joined by a rod of radius 0.0025) had 260 triangles beyond a tolerance
    // of 5e-4 (up to 1.05e-3, min_edge 0.0038) and 91 beyond 1e-4 (up to 1.8e-4, min_edge
    // 0.0012), exit 0. Stats "tolerance_rerun".
    {RunKind::ForTolerance, "for_tolerance"},
    // A smooth surface's mesh that misses the quality bounds: meshed again with the front
    // look-ahead, the mesh that misses fewer kept (may_rerun_for_quality); stats "quality_rerun".
    {RunKind::LookAhead, "look_ahead"},
}};

// Tolerance mode asks for chords up to the diameter of a bend tighter than the tolerance
// (chord_for_deviation), which can step over the necks of a surface like the Barth ball. Where
// every run below fails (the first, the careful and finer ones it makes again, and those with a
// lowered min_edge), the surface is meshed once more with every edge turning the normal by at
// most kTurnLimit radians from the start, the crease-aware patches included, at the lowered
// min_edge where there is one. The Barth ball at tolerances 1e-1 and 3e-2 failed every run before
// and meshes so (genus 30); a run that meshes before is the same as it was, and a coarse
// tolerance is not held to that bound where it meshes without it (the Igea VIS-4004 at 5e-2:
// 850 triangles, 3,020 with the bound on every run). The stats say so (`turn_limited`).
constexpr double kTurnLimit = 1;

// A mesh of a smooth surface (no crease followed) that misses the quality bounds is made once more
// with the front look-ahead (Settings::look_ahead: an expansion's edges no longer than a nearby
// front point's target plus kLookAheadGradation times its distance), and the run that misses
// fewer bounds is kept, the first on a tie. Where the first run's slivers come from (a front
// whose edges are several times what a fillet ahead asks for: the point placed in the fillet
// keeps a front edge as long as the ones it came with, and the expansions beside it hinge a fan
// of slivers on it across the fillet, which no repair can split without folding), the
// look-ahead has the front grade its edges down before it gets there. Not on every run: over
// the 343 runs of experiments/fields and the topology sweep's 40 fields (factors 1, 2, 3, 5;
// tolerances 5e-2, 1e-2, 1e-3) it mends 4 of the 8 that miss a bound (blobs26 at factor 1,
// 2.4 -> 24.9 degrees; blobs27 and blobs39 at 5e-2, 4.9 and 2.2 -> 30.1 degrees, no triangle
// beyond the tolerance; the bunny MPU model at 1e-3, 4 triangles beyond it -> none) but misses
// bounds on 5 that met them (the horse MPU model at 1e-3: 18.4 degrees; blobs40 at factor 1:
// 2.3), so the first run stays the one without it, and surfaces that meet the bounds come out
// as before, bit for bit, at the cost of one run.
// Only where remeshing_allowed (the bounds are Variant::Improved's promise).
bool may_rerun_for_quality(const AdaptiveOptions& o, const PolygonizeResult& r) {
  return adaptive::remeshing_allowed(o) && !r.stats.adaptive->creases.followed;
}

int missed_bounds(const PolygonizeResult& r) {
  return adaptive::missed_bounds(r.mesh, r.stats.adaptive->quality.over_tolerance);
}

// The first run's error, which stands when every run made again fails too.
struct FirstError {
  bool limit = false;  // a LimitExceededError, else a NoSurfaceError
  std::string message;
};

}  // namespace

PolygonizeResult polygonize_adaptive(const Field& field, const AdaptiveOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const EvaluationCounts before = field.counts();
  adaptive::PhaseLedger phases(field);
  // SizingMode::Chord limits the turn from the start (kChordMaxTurn): the same run again would fail again.
  const bool may_limit_turn = adaptive::remeshing_allowed(options) && options.sizing == SizingMode::Tolerance;
  std::optional<PolygonizeResult> kept;
  RunKind kept_from = RunKind::AsGiven;
  std::optional<FirstError> first_error;
  std::optional<double> lowered;
  std::string lowered_error;
  std::optional<AdaptiveOptions> for_sheets;
  std::string sheets_error;
  int missed = 0;
  std::optional<double> for_tolerance;
  // A run's NoSurfaceError or LimitExceededError (`limit`): whether it ends polygonize_adaptive.
  // The first run's error stands unless a run made again meshes; the lowered run's is quoted.
  const auto failed = [&](const RunRow& row, const adaptive::RunFailure& failure, bool limit, const std::exception& e) {
    if (row.kind == RunKind::LoweredMinEdge) lowered_error = e.what();
    if (row.kind == RunKind::ThinSheets) sheets_error = e.what();
    if (row.kind != RunKind::AsGiven) return false;
    if (failure.final) return true;
    lowered = adaptive::lowered_min_edge(field, options, failure.tightest.first);
    if (failure.sheets_gap) for_sheets = adaptive::options_for_sheets(field, options, *failure.sheets_gap);
    if (!lowered && !may_limit_turn && !for_sheets) return true;
    first_error = FirstError{limit, e.what()};
    return false;
  };
  for (const RunRow& row : kRuns) {
    AdaptiveOptions again = options;
    adaptive::RunRequest request;
    switch (row.kind) {
      case RunKind::AsGiven:
        request.lowered_min_edge_follows = true;
        break;
      case RunKind::LoweredMinEdge:
        if (kept || !lowered) continue;
        again.min_edge = *lowered;
        break;
      case RunKind::TurnLimited:
        if (kept || !may_limit_turn) continue;
        if (lowered) again.min_edge = *lowered;
        request.max_turn = kTurnLimit;
        break;
      case RunKind::ThinSheets:
        if (kept || !for_sheets) continue;
        again = *for_sheets;
        break;
      case RunKind::ForTolerance:
        if (!kept || kept_from != RunKind::AsGiven || options.sizing != SizingMode::Tolerance ||
            kept->stats.adaptive->quality.over_tolerance == 0)
          continue;
        for_tolerance = adaptive::min_edge_for_tolerance(field, options, kept->stats.adaptive->tracker.min_curvature_radius);
        if (!for_tolerance) continue;
        again.min_edge = *for_tolerance;
        break;
      case RunKind::LookAhead:
        if (!kept || !may_rerun_for_quality(options, *kept) || (missed = missed_bounds(*kept)) == 0) continue;
        // The same min_edge (lowered when that was needed) or max_edge as the mesh it may replace.
        if (kept_from == RunKind::ThinSheets) again = *for_sheets;
        else if (kept_from == RunKind::ForTolerance) again.min_edge = *for_tolerance;
        else if (kept_from != RunKind::AsGiven && lowered) again.min_edge = *lowered;
        request.look_ahead = true;
        break;
    }
    adaptive::RunFailure failure;
    try {
      PolygonizeResult r = adaptive::run_once(field, again, phases, request, failure);
      if (row.kind == RunKind::LookAhead) {
        const bool keep = missed_bounds(r) < missed;
        if (keep) {
          // Made with the kept mesh's min_edge or thin-sheet options: what changed them stays said.
          const RecoveryReport& was = kept->stats.adaptive->recoveries;
          RecoveryReport& is = r.stats.adaptive->recoveries;
          is.min_edge_lowered = was.min_edge_lowered;
          is.thin_sheets = was.thin_sheets;
          is.tolerance_rerun = was.tolerance_rerun;
          is.tolerance_rerun_kept = was.tolerance_rerun_kept;
          kept = std::move(r);
        }
        kept->stats.adaptive->recoveries.quality_rerun = true;
        kept->stats.adaptive->recoveries.quality_rerun_kept = keep;
      } else if (row.kind == RunKind::ForTolerance) {
        const bool keep = r.stats.adaptive->quality.over_tolerance < kept->stats.adaptive->quality.over_tolerance &&
                          missed_bounds(r) <= missed_bounds(*kept);
        if (keep) {
          r.stats.adaptive->recoveries.min_edge_lowered = true;
          kept = std::move(r);
          kept_from = RunKind::ForTolerance;
        }
        kept->stats.adaptive->recoveries.tolerance_rerun = true;
        kept->stats.adaptive->recoveries.tolerance_rerun_kept = keep;
      } else {
        r.stats.adaptive->recoveries.min_edge_lowered =
            row.kind != RunKind::AsGiven && row.kind != RunKind::ThinSheets && lowered.has_value();
        r.stats.adaptive->recoveries.thin_sheets = row.kind == RunKind::ThinSheets;
        kept = std::move(r);
        kept_from = row.kind;
      }
    } catch (const adaptive::UnsearchedCellsError&) {
      throw;  // the same cells would be left again (stage_tracking.h)
    } catch (const NoSurfaceError& e) {
      if (failed(row, failure, false, e)) throw;
    } catch (const LimitExceededError& e) {
      if (failed(row, failure, true, e)) throw;
    }
  }
  if (!kept) {
    // The first error stands, with what the runs made again did.
    std::ostringstream retries;
    const char* const turn =
        may_limit_turn ? " (and with every edge turning the normal by at most a radian, which failed too)" : "";
    if (lowered)
      retries << " (meshed again with min_edge " << *lowered << ", which failed too: " << lowered_error << turn << ")";
    else
      retries << turn;
    if (for_sheets)
      retries << " (meshed again with max_edge " << for_sheets->max_edge << " and seed_resolution "
              << for_sheets->seed_resolution << ", which failed too: " << sheets_error << ")";
    if (first_error->limit) throw LimitExceededError(first_error->message + retries.str());
    throw NoSurfaceError(first_error->message + retries.str());
  }
  kept->stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  kept->stats.field_evaluations = field.counts() - before;
  phases.write(*kept->stats.adaptive);
  return std::move(*kept);
}

}  // namespace cdp
