// The repair stage (polygonizer/src/adaptive/stage_repair.h) run alone on a tracked mesh.
#include <gtest/gtest.h>

#include "src/adaptive/stage_checks.h"
#include "src/adaptive/repair_context.h"
#include "src/adaptive/stage_repair.h"

#include <numbers>
#include <set>

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
  BandChanges band;
  const QualityReport q = repair_mesh(s.run, s.settings, seeds, CreaseLayout{}, BlockMeshing{}, tracking, mesh, band);
  EXPECT_GT(q.bad_before, 0u);
  EXPECT_GE(min_angle_degrees(mesh), before);
  EXPECT_EQ(missed_bounds(mesh, q.over_tolerance), 0);
  test::expect_sound(mesh, "tanglecube repaired");
  AdaptiveOptions paper;
  paper.variant = Variant::Paper;
  const RunContext run{*s.field, paper, s.phases};
  Mesh again = mesh;
  const QualityReport none = repair_mesh(run, s.settings, seeds, CreaseLayout{}, BlockMeshing{}, tracking, again, band);
  EXPECT_EQ(none.moves + none.flips + none.collapses + none.splits, 0u);
  EXPECT_EQ(again.positions, mesh.positions);
}

// The band's repair of a mesh meshed in blocks: the triangles beside the first `seams` vertices
// and those with a vertex numbered `finished` or more are repaired; every other triangle stays as
// it was, and the mesh stays sound.
TEST(AdaptiveStages, TheBandsRepairChangesOnlyTheBandAndKeepsTheMeshSound) {
  AdaptiveOptions paper;  // unrepaired: triangles under 30 degrees everywhere
  paper.variant = Variant::Paper;
  paper.factor = 1;
  Stages s(kTanglecube, paper);
  const SeedGridStage seeds = sample_seed_grid_stage(*s.field, s.options, s.settings);
  Mesh mesh;
  Tracking tracking;
  track(s, seeds, mesh, tracking);
  const std::size_t nv = mesh.positions.size(), seams = 40, finished = nv - nv / 4;
  // The triangles outside the band, by their corners' positions.
  std::vector<char> near(nv, 0);
  for (std::size_t v = 0; v < seams; ++v) near[v] = 1;
  for (const auto& t : mesh.triangles)
    if (static_cast<std::size_t>(std::min({t[0], t[1], t[2]})) < seams)
      for (int v : t) near[static_cast<std::size_t>(v)] = 1;
  std::vector<std::array<Vec3, 3>> outside;
  std::size_t bad_inside = 0;
  for (const auto& t : mesh.triangles) {
    bool in = false;
    for (int v : t) in = in || near[static_cast<std::size_t>(v)] || static_cast<std::size_t>(v) >= finished;
    if (!in)
      outside.push_back({mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]});
    else
      bad_inside += repair::min_angle(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]) <
                    30 * std::numbers::pi / 180;
  }
  ASSERT_GT(bad_inside, 0u);
  QualityOptions q;
  q.improve_below = 30 * std::numbers::pi / 180;
  q.diagonal = s.settings.diagonal;
  q.min_edge = s.settings.sizing.min_edge;
  q.aim_mean_edge_ratio = 1.25;
  const Mesh input = mesh;
  BandChanges band;
  const QualityReport r = repair_band(*s.field, mesh, seams, finished, q, band);
  EXPECT_EQ(r.bad_before, bad_inside);
  EXPECT_LT(r.bad_after, r.bad_before);
  EXPECT_FALSE(band.moved.empty());
  test::expect_sound(mesh, "tanglecube, its band repaired");
  // Every triangle outside the band is still there, and each vertex not listed as moved is
  // where it was.
  std::set<std::array<double, 9>> now;
  for (const auto& t : mesh.triangles) {
    std::array<double, 9> k;
    for (int c = 0; c < 3; ++c)
      for (int d = 0; d < 3; ++d) k[3 * c + d] = mesh.positions[t[c]][d];
    now.insert(k);
  }
  for (const auto& p : outside) {
    std::array<double, 9> k;
    for (int c = 0; c < 3; ++c)
      for (int d = 0; d < 3; ++d) k[3 * c + d] = p[c][d];
    EXPECT_TRUE(now.count(k));
  }
  ASSERT_EQ(band.renumbered.size(), nv);
  const std::set<int> moved(band.moved.begin(), band.moved.end());
  for (std::size_t v = 0; v < nv; ++v) {
    const int r2 = band.renumbered[v];
    if (r2 >= 0 && !moved.count(r2)) {
      EXPECT_EQ(mesh.positions[static_cast<std::size_t>(r2)], input.positions[v]) << v;
    }
  }
}

}  // namespace
}  // namespace cdp::adaptive
