// The seed-grid stage (polygonizer/src/adaptive/stage_seed_grid.h) run alone.
#include <gtest/gtest.h>

#include "src/adaptive/stage_seed_grid.h"

#include <numbers>

#include "polygonizer/adaptive/stage_fixtures.h"

namespace cdp::adaptive {
namespace {

using namespace test_stages;

TEST(AdaptiveStages, TheSeedGridMeasuresTheSurfacesArea) {
  Stages s(kSphere);
  const SeedGridStage seeds = sample_seed_grid_stage(*s.field, s.options, s.settings);
  EXPECT_GE(seeds.crossings, kMeasuredCrossings);
  // Crofton's estimate: meshes the checks pass measure 0.90-1.01 of it.
  EXPECT_NEAR(seeds.estimated_area / (4 * std::numbers::pi), 1.0, 0.1);
  EXPECT_GT(seeds.hash_cell, 0);
  EXPECT_LE(seeds.hash_cell, 2 * s.settings.sizing.max_edge);
}

}  // namespace
}  // namespace cdp::adaptive
