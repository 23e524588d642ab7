// The crease stage of a run (CreaseHandling::Follow): the creases traced, and the patches they
// bound meshed from them (crease_patches.h) before the tracking stage meshes the rest.
#pragma once

#include "crease_patches.h"
#include "tracker.h"

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/crease_curves.h>

#include <array>
#include <cstddef>
#include <optional>
#include <string>

namespace cdp::adaptive {

// Creases are traced on the seed grid first and, when they cannot be laid out as patch boundaries
// (a corner whose boundary breaks off: a short crease between crossings of the grid was
// missed) or their patches' fronts stall or run on (a patch with a crease the grid missed, so
// unbounded there), once more on a grid twice as fine (eight times the values, on a field cheap
// enough to have min/max/abs branches: an expression).
inline constexpr int kCreaseTracings = 2;

// The patches' fronts look ahead (Settings::look_ahead) with a gentler gradation than a smooth
// surface's re-run (kLookAheadGradation, 0.4): a patch's fronts run one after another
// (Tracker::run_fronts), and the first to run covers the patch up to the short edges of the
// loops that have not run yet (a sphere drilled by a hole of radius 0.05: the rims' edges 0.017,
// the sphere's 0.33; the first front arrived at the other rim with edges of 0.06-0.1 and left a
// 19.9-degree triangle at factor 3, 17.9 at 3.2, 0.37 at the rim at 4.25). Over ten creased SDF
// models at factors 1 to 6 in steps of 0.25 (210 runs), 0.3 left 2 runs meshed across their
// creases instead of 6 and 2 with a triangle under 10 degrees instead of 9, at the same triangle
// count; the drilled sphere's smallest angle over them went from 0.37 degrees to 16.6. Where a
// patch's front stalls (StalledFrontError) the patches are meshed again with the next share
// before the surface is meshed across its creases: 0.25 meshed the last 2 (a box with two
// crossing filleted holes at factors 2.5 and 5.75, genus 3, 20.0 and 18.4 degrees), and the
// Barth ball at tolerance 3e-2 in its first run (0.6 s; before, the last run of kRuns, 12 s);
// as the first share it left a stalled front on the crossing holes at factor 3.
inline constexpr std::array<double, 2> kPatchLookAheadGradations{0.3, 0.25};

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
  // The surface's area the patches were bounded by (Tracker::set_estimated_area): the caller's,
  // or where the last tracing sampled a finer grid than the seed grid and that grid measures
  // more (measured_area: a table top thinner than a seed cell, missed by it), that grid's.
  double estimated_area = 0;
};

// Traces the field's creases and meshes the patches they bound with `settings`;
// `estimated_area` as Tracker::set_estimated_area. The first tracing searches `seed_grid` (the
// seed grid stage's, at options.seed_resolution), if given. Nothing for CreaseHandling::Ignore or
// Variant::Paper. A layout that fails is not an error: `fallback` says why, and the tracking
// stage meshes the surface as a smooth one.
// \throw CancelledError, and what the trackers throw but a layout, stall or bound error.
CreaseLayout lay_out_creases(const Field& field, const AdaptiveOptions& options, const Settings& settings,
                             double estimated_area, const SeedGrid* seed_grid = nullptr);

}  // namespace cdp::adaptive
