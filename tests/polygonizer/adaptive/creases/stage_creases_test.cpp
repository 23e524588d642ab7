// The crease stage (polygonizer/src/adaptive/stage_creases.h) run alone on the seed grid's output.
#include <gtest/gtest.h>

#include "src/adaptive/stage_creases.h"

#include "polygonizer/adaptive/stage_fixtures.h"
#include "polygonizer/mesh_checks.h"

namespace cdp::adaptive {
namespace {

using namespace test_stages;

TEST(AdaptiveStages, TheCreaseStageMeshesACubesFacesFromItsTwelveEdges) {
  Stages s(kCube);
  const SeedGridStage seeds = sample_seed_grid_stage(*s.field, s.options, s.settings);
  const CreaseLayout layout = lay_out_creases(*s.field, s.options, s.settings, seeds.estimated_area);
  EXPECT_EQ(layout.traced.curves.size(), 12u);
  EXPECT_EQ(layout.traced.corners.size(), 8u);
  ASSERT_TRUE(layout.mesh.has_value()) << layout.fallback;
  EXPECT_TRUE(layout.fallback.empty());
  EXPECT_EQ(layout.components, 1u);
  test::expect_sound(layout.mesh->mesh, "cube patches");
  // Not followed: nothing traced.
  AdaptiveOptions ignore;
  ignore.creases = CreaseHandling::Ignore;
  EXPECT_FALSE(follows_creases(ignore));
  EXPECT_TRUE(lay_out_creases(*s.field, ignore, s.settings, seeds.estimated_area).traced.curves.empty());
}

}  // namespace
}  // namespace cdp::adaptive
