// The seed grid stage of a run: the grid every seed and the surface-area estimate come from,
// and the hash cell the spatial hashes use.
#pragma once

#include "tracker.h"

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/surface_seeds.h>

#include <cstddef>

namespace cdp::adaptive {

// Crossed grid edges per unit area: (|nx| + |ny| + |nz|) / h^2 for a patch of normal n,
// kMeanCrossings / h^2 on average over all orientations (Crofton); with fewer than
// kMeasuredCrossings the surface is too small for the grid to measure.
inline constexpr double kMeanCrossings = 1.5;
inline constexpr std::size_t kMeasuredCrossings = 64;

struct SeedGridStage {
  SeedGrid grid;
  std::size_t crossings = 0;  // grid edges the surface crosses
  // The surface's area as the crossings measure it; 0 below kMeasuredCrossings.
  double estimated_area = 0;
  // Twice the median edge length the sizing asks for at up to 64 crossings (a deterministic
  // sample spread over the surface); `settings.hash_cell` where none could be measured.
  double hash_cell = 0;
  // The triangles the mesh will have, about: the area times the mean, over the same sample of
  // crossings, of one over the area of an equilateral triangle with the sizing's edge there; 0
  // where the area is not measured. What the blocks are counted from (blocks.h); it runs low
  // (stage_seed_grid.cpp).
  double estimated_triangles = 0;
};

// Samples the seed grid (AdaptiveOptions::seed_resolution, threads) and measures the surface from it.
// \throw CancelledError, and what the field's evaluations throw.
SeedGridStage sample_seed_grid_stage(const Field& field, const AdaptiveOptions& options, const Settings& settings);

// The surface's area as the grid's crossings measure it (kMeanCrossings); 0 below
// kMeasuredCrossings crossings.
double measured_area(const SeedGrid& grid);

}  // namespace cdp::adaptive
