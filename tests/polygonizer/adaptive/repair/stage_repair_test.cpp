// The repair stage (polygonizer/src/adaptive/stage_repair.h) run alone on a tracked mesh.
#include <gtest/gtest.h>

#include "src/adaptive/stage_checks.h"
#include "src/adaptive/repair_context.h"
#include "src/adaptive/repair_last_resort.h"
#include "src/adaptive/stage_repair.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
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

// Tanglecube tracked as the paper variant meshes it at `factor`: unrepaired, with triangles under
// 30 degrees everywhere and, at a tolerance, beyond it.
Mesh unrepaired_tanglecube(double factor, Settings& settings, std::unique_ptr<Field>& field) {
  AdaptiveOptions paper;
  paper.variant = Variant::Paper;
  paper.factor = factor;
  Stages s(kTanglecube, paper);
  const SeedGridStage seeds = sample_seed_grid_stage(*s.field, s.options, s.settings);
  Mesh mesh;
  Tracking tracking;
  track(s, seeds, mesh, tracking);
  settings = s.settings;
  field = std::move(s.field);
  return mesh;
}

// The seams (the first `seams` vertices) and their neighbours: a triangle with a corner among them
// is in the band.
std::vector<char> near_seams(const Mesh& mesh, std::size_t seams) {
  std::vector<char> near(mesh.positions.size(), 0);
  for (std::size_t v = 0; v < seams; ++v) near[v] = 1;
  for (const auto& t : mesh.triangles)
    if (static_cast<std::size_t>(std::min({t[0], t[1], t[2]})) < seams)
      for (int v : t) near[static_cast<std::size_t>(v)] = 1;
  return near;
}

// The band's repair of a mesh meshed in blocks: the triangles beside the first `seams` vertices
// and those with a vertex numbered `finished` or more are repaired; every other triangle stays as
// it was, and the mesh stays sound.
TEST(AdaptiveStages, TheBandsRepairChangesOnlyTheBandAndKeepsTheMeshSound) {
  Settings settings;
  std::unique_ptr<Field> field;
  Mesh mesh = unrepaired_tanglecube(1, settings, field);
  const std::size_t nv = mesh.positions.size(), seams = 40, finished = nv - nv / 4;
  // The triangles outside the band, by their corners' positions.
  const std::vector<char> near = near_seams(mesh, seams);
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
  q.diagonal = settings.diagonal;
  q.min_edge = settings.sizing.min_edge;
  q.aim_mean_edge_ratio = 1.25;
  const Mesh input = mesh;
  BandChanges band;
  const QualityReport r = repair_band(*field, mesh, seams, finished, q, band);
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


// A band as the blocks leave one: the vertices within `width` of the cut planes numbered first
// (the seams' place), the rest after them in their order.
std::size_t number_seams_first(Mesh& mesh, const std::array<std::vector<double>, 3>& cuts, double width) {
  const std::size_t nv = mesh.positions.size();
  std::vector<int> order;
  std::vector<char> seam(nv, 0);
  for (std::size_t v = 0; v < nv; ++v)
    for (int a = 0; a < 3; ++a)
      for (double c : cuts[a]) seam[v] = seam[v] || std::abs(mesh.positions[v][a] - c) < width;
  for (int pass = 1; pass >= 0; --pass)
    for (std::size_t v = 0; v < nv; ++v)
      if (seam[v] == pass) order.push_back(static_cast<int>(v));
  std::vector<int> at(nv);
  Mesh out;
  for (std::size_t i = 0; i < nv; ++i) {
    at[static_cast<std::size_t>(order[i])] = static_cast<int>(i);
    out.positions.push_back(mesh.positions[static_cast<std::size_t>(order[i])]);
    out.normals.push_back(mesh.normals[static_cast<std::size_t>(order[i])]);
  }
  for (const auto& t : mesh.triangles) out.triangles.push_back({at[t[0]], at[t[1]], at[t[2]]});
  mesh = std::move(out);
  return static_cast<std::size_t>(std::count(seam.begin(), seam.end(), 1));
}

// The band repaired in parts (repair_band's cuts): the cells' parts side by side, then the
// triangles around the vertices they share. The same mesh and counts on one thread and on two,
// sound, every triangle outside the band kept; and each triangle left beyond the tolerance
// counted once: the count is what measuring the band's triangles afresh finds (a first pass
// that counted the triangles beside its parts' shared vertices would count them twice).
TEST(AdaptiveStages, TheBandRepairedInPartsIsTheSameOnAnyThreadsAndCountsEachTriangleOnce) {
  Settings settings;
  std::unique_ptr<Field> field;
  Mesh mesh = unrepaired_tanglecube(3, settings, field);
  const std::array<std::vector<double>, 3> cuts{{{-1.1, 0.3, 1.7}, {-0.9, 0.6}, {-1.3, 0.2, 1.4}}};
  const std::size_t seams = number_seams_first(mesh, cuts, 0.03);
  ASSERT_GT(seams, 50u);
  QualityOptions q;
  q.improve_below = 30 * std::numbers::pi / 180;
  q.diagonal = settings.diagonal;
  q.min_edge = 0.2;  // splits that would clear the tolerance refused: some triangles stay beyond it
  q.last_resort_min_edge = 0.2;
  q.tolerance = 2e-3;
  Mesh one = mesh, two = mesh;
  BandChanges b1, b2;
  q.threads = 1;
  const QualityReport r1 = repair_band(*field, one, seams, mesh.positions.size(), q, b1, nullptr, &cuts);
  q.threads = 2;
  const QualityReport r2 = repair_band(*field, two, seams, mesh.positions.size(), q, b2, nullptr, &cuts);
  EXPECT_GT(b1.parts, 5u);
  EXPECT_GT(b1.junctions, 5u);
  EXPECT_EQ(one.positions, two.positions);
  EXPECT_EQ(one.triangles, two.triangles);
  EXPECT_EQ(b1.moved, b2.moved);
  EXPECT_EQ(r1.flips + r1.moves + r1.splits, r2.flips + r2.moves + r2.splits);
  EXPECT_EQ(r1.over_tolerance, r2.over_tolerance);
  test::expect_sound(one, "tanglecube, its band repaired in parts");
  // The band's triangles come after those outside it, which stay as they were (renumbered).
  std::size_t outside = 0;
  const std::vector<char> near = near_seams(mesh, seams);
  for (const auto& t : mesh.triangles) {
    if (near[t[0]] || near[t[1]] || near[t[2]]) continue;
    const std::array<int, 3> now = one.triangles[outside++];
    for (int c = 0; c < 3; ++c) EXPECT_EQ(one.positions[now[c]], mesh.positions[t[c]]);
  }
  ASSERT_GT(r1.over_tolerance, 0u);
  Mesh measured = one;
  QualityOptions plain = q;
  plain.threads = 1;
  repair::RepairContext ctx(*field, measured, plain);
  std::vector<int> band_triangles;
  for (std::size_t t = outside; t < one.triangles.size(); ++t) band_triangles.push_back(static_cast<int>(t));
  EXPECT_EQ(repair::measure_densely(ctx, band_triangles).size(), r1.over_tolerance);
}

}  // namespace
}  // namespace cdp::adaptive
