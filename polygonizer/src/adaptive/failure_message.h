// What a failed run's error says: the tracker's own message, with the cause where the run can
// name it (a kink of a black box, a bend tighter than min_edge, creases meshed across by choice,
// a crease layout that failed first).
#pragma once

#include "resolve_settings.h"
#include "stage_tracking.h"

#include <cdp/core/adaptive_polygonizer.h>

#include <string>

namespace cdp::adaptive {

// A run that fails having met a bend tighter than the step of a black box's central differences
// (Field::derivative_step) met a crease or corner of the function that the field does not
// describe: differences across it turn the normal within a step, a curvature no edge follows,
// and no branch data say where the two faces are. With CreaseHandling::Follow the tracker stops
// at the first vertex placed there (BlackBoxKinkError); meshing across by choice (Ignore), a run
// that failed having met one is not made again either: carefully, with finer turns, with
// min_edge lowered, it fails too, after several times as long (a gyroid clipped by a ball as a
// Python function: the first run failed at 3 s, the last at 17 s).
bool kink_in_black_box(const Field& field, const Bend& tightest);

// A sampled volume's bend this many times tighter than its sample spacing is not detail of its
// data. (The raw brain scan of examples/mesh_volume.py, spacing 2: its first run met a bend of
// radius 0.019 with min_edge 0.29.)
inline constexpr double kBelowSamples = 0.1;

// Whether a sampled volume (Field::sample_spacing) met the noise of its samples: a bend tighter
// than min_edge and than kBelowSamples of the sample spacing, which its interpolant makes only
// where the level passes near one of its saddles, and a scan's noise puts those everywhere. A
// run whose fronts got stuck there (a LimitExceededError of the tracking) is not made again:
// carefully, with finer turns or with min_edge lowered, it only follows the noise further (the
// raw brain scan failed its first run after 10 s, its five recoveries after 30 s, each finding a
// tighter bend, and a run with min_edge lowered failed after 23 s more). Its message names the
// noise and the smoothing that removes it. A run that meshed and failed a check of its mesh is
// made again as before (Run::mesh_with_recoveries): one stepped over a neck a hair from a
// saddle of a smooth volume, which a run with min_edge under its width meshes at little cost.
bool noise_in_volume(const Field& field, const Settings& resolved, const Bend& tightest);

// The error message of a run that failed with `message`: the cause first where it is a black
// box's kink or a sampled volume's noise, else `message` with the tightest bend where it is
// under min_edge, the field's sharpest crease where the run meshed across creases by choice, and
// `crease_fallback` (why the crease-aware meshing failed) where it did.
// \throw CancelledError (naming the sharpest crease traces the creases).
std::string explain_failure(const Field& field, const AdaptiveOptions& options, const Settings& resolved,
                            std::string message, const Bend& tightest, const std::string& crease_fallback);

}  // namespace cdp::adaptive
