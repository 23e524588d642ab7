// The tracking stage (polygonizer/src/adaptive/stage_tracking.h) run alone on the seed grid's output.
#include <gtest/gtest.h>

#include "src/adaptive/stage_checks.h"
#include "src/adaptive/stage_tracking.h"

#include <cdp/core/errors.h>

#include <string>

#include "polygonizer/adaptive/stage_fixtures.h"

namespace cdp::adaptive {
namespace {

using namespace test_stages;

TEST(AdaptiveStages, TrackingMeshesEveryComponentOrNamesWhyNot) {
  Stages s(kSphere);
  const SeedGridStage seeds = sample_seed_grid_stage(*s.field, s.options, s.settings);
  Mesh mesh;
  Tracking tracking;
  track(s, seeds, mesh, tracking);
  EXPECT_EQ(tracking.seeding.seeds, 1u);
  EXPECT_EQ(tracking.seeding.uncovered, 0u);
  EXPECT_FALSE(tracking.remeshed);
  EXPECT_EQ(check_mesh(mesh, 1, true, 1, s.options.cancel), 1u);
  // A box the surface does not reach: the error says so, and the stage says why.
  Stages outside(R"({"type": "sphere", "radius": 1, "bounds": [[2, 2, 2], [3, 3, 3]]})");
  const SeedGridStage none = sample_seed_grid_stage(*outside.field, outside.options, outside.settings);
  Mesh empty;
  Tracking nothing;
  Settings st = outside.settings;
  try {
    track_surface(outside.run, none, nullptr, false, 0, st, empty, nothing);
    ADD_FAILURE() << "no error";
  } catch (const NoSurfaceError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("adaptive: no zero crossing of the field in its box", 0), 0u) << e.what();
  }
  EXPECT_TRUE(nothing.no_crossing);
}

}  // namespace
}  // namespace cdp::adaptive
