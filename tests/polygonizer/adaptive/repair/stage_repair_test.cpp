// The repair stage (polygonizer/src/adaptive/stage_repair.h) run alone on a tracked mesh.
#include <gtest/gtest.h>

#include "src/adaptive/stage_checks.h"
#include "src/adaptive/stage_repair.h"

#include "polygonizer/adaptive/stage_fixtures.h"
#include "polygonizer/mesh_checks.h"

namespace cdp::adaptive {
namespace {

using namespace test_stages;

TEST(AdaptiveStages, TheRepairRaisesTheSmallestAngleAndThePaperVariantSkipsIt) {
  AdaptiveOptions coarse;  // a few thousand triangles
  coarse.factor = 1;
  Stages s(kTanglecube, coarse);
  const SeedGridStage seeds = sample_seed_grid_stage(*s.field, s.options, s.settings);
  Mesh mesh;
  Tracking tracking;
  track(s, seeds, mesh, tracking);
  const double before = min_angle_degrees(mesh);
  const QualityReport q = repair_mesh(s.run, s.settings, seeds, CreaseLayout{}, tracking, mesh);
  EXPECT_GT(q.bad_before, 0u);
  EXPECT_GE(min_angle_degrees(mesh), before);
  EXPECT_EQ(missed_bounds(mesh, q.over_tolerance), 0);
  test::expect_sound(mesh, "tanglecube repaired");
  AdaptiveOptions paper;
  paper.variant = Variant::Paper;
  const RunContext run{*s.field, paper, s.phases};
  Mesh again = mesh;
  const QualityReport none = repair_mesh(run, s.settings, seeds, CreaseLayout{}, tracking, again);
  EXPECT_EQ(none.moves + none.flips + none.collapses + none.splits, 0u);
  EXPECT_EQ(again.positions, mesh.positions);
}

}  // namespace
}  // namespace cdp::adaptive
