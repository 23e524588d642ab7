// The crease stage of a run (CreaseHandling::Follow): the creases traced, and the patches they
// bound meshed from them (crease_patches.h) before the tracking stage meshes the rest.
#pragma once

#include "crease_patches.h"
#include "tracker.h"

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/crease_curves.h>

#include <cstddef>
#include <optional>
#include <string>

namespace cdp::adaptive {

// Creases are traced on the seed grid first and, when they cannot be laid out as patch boundaries
// (a corner whose boundary breaks off: a short crease between crossings of the grid was
// missed), once more on a grid twice as fine (eight times the values, on a field cheap enough
// to have min/max/abs branches: an expression).
inline constexpr int kCreaseTracings = 2;

// Whether the options follow creases: CreaseHandling::Follow in Variant::Improved (the paper
// variant has no crease handling).
inline bool follows_creases(const AdaptiveOptions& options) {
  return options.creases == CreaseHandling::Follow && options.variant == Variant::Improved;
}

struct CreaseLayout {
  CreaseTracingResult traced;       // the creases found (none for a field without pieces)
  std::optional<CreaseMesh> mesh;   // the patches, meshed; none where there are no creases or the layout failed
  std::size_t components = 0;       // the patches' components
  // Why the creases are not followed (the layout's or the patches' error), or empty.
  std::string fallback;
  int tracing_resolution = 0;       // of the last tracing made; 0 when none was
};

// Traces the field's creases and meshes the patches they bound with `settings`;
// `estimated_area` as Tracker::set_estimated_area. Nothing for CreaseHandling::Ignore or
// Variant::Paper. A layout that fails is not an error: `fallback` says why, and the tracking
// stage meshes the surface as a smooth one.
// \throw CancelledError, and what the trackers throw but a layout, stall or bound error.
CreaseLayout lay_out_creases(const Field& field, const AdaptiveOptions& options, const Settings& settings,
                             double estimated_area);

}  // namespace cdp::adaptive
