// Block-parallel tracking (polygonizer/src/adaptive/blocks.h): the seams laid out, the blocks
// meshed from them into one sound mesh, the same bit for bit on any number of threads and in any
// block order, and the triangles at the cut planes as good as the rest.
#include <gtest/gtest.h>

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/core/triangle_intersection.h>
#include <cdp/io/field_factory.h>

#include "common/same_mesh.h"
#include "common/test_fields.h"
#include "polygonizer/adaptive/stage_fixtures.h"
#include "polygonizer/mesh_checks.h"
#include "src/adaptive/blocks.h"
#include "src/adaptive/stage_checks.h"
#include "src/adaptive/stage_seed_grid.h"

#include <iostream>
#include <string>
#include <numbers>

namespace cdp::adaptive {
namespace {

// A torus (R = 1, r = 0.4) of about 3.5 * 10^4 triangles at factor 12: cut into 3 x 3 x 1 blocks,
// so that its seams meet at corners on the four z-parallel lines where blocks meet (the line
// through the hole of a 2 x 2 cut would cross nothing).
const char* const kBlockTorus = R"({"type": "expression", "value": "(sqrt(x^2+y^2)-1)^2 + z^2 - 0.16",
                                    "bounds": [[-1.6, -1.6, -0.6], [1.6, 1.6, 0.6]]})";

AdaptiveOptions with_blocks(int threads, double factor = 12) {
  AdaptiveOptions o;
  o.factor = factor;
  o.blocks = true;
  o.threads = threads;
  return o;
}

TEST(AdaptiveBlocks, ATorusCutIntoBlocksMeshesSoundWithGoodTrianglesAtTheWalls) {
  const auto f = test::field_from_json(kBlockTorus);
  const PolygonizeResult r = polygonize_adaptive(*f, with_blocks(2));
  const BlocksReport& b = r.stats.adaptive->blocks;
  ASSERT_TRUE(b.used) << b.fallback;
  EXPECT_EQ(b.blocks, (std::array<int, 3>{3, 3, 1}));
  EXPECT_EQ(b.corners, 8u);  // each of the four lines crosses the tube twice
  EXPECT_EQ(b.components, 1u);
  EXPECT_EQ(r.stats.adaptive->seeding.seeds, 0u);  // every component crossed a cut
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight()) << t.boundary_edges << " boundary, " << t.nonmanifold_edges << " non-manifold";
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.genus, 1);
  EXPECT_EQ(test::count_self_intersections(r.mesh), 0u);
  // The bounds of issue 58 on the triangles the cut planes pass through.
  ASSERT_GT(b.wall_triangles, 100u);
  EXPECT_GE(b.wall_min_angle_degrees, 20.0);
  EXPECT_LE(b.wall_under_30_share, 0.01);
  EXPECT_LE(b.wall_mean_edge_ratio, 1.25);
}

// A cut plane's lean predicted from the seed grid (no evaluation): through a sphere's middle the
// surface crosses it square; just above its top it grazes it (the layout's samples there see the
// normal across the plane); in between, what exact gradients give at the grid's columns within
// 0.4 of a cell of the surface (kPredictedBand), to the differences' error.
TEST(AdaptiveBlocks, ACutPlanesLeanIsPredictedFromTheSeedGrid) {
  const auto f = test::field_from_json(
      R"({"type": "expression", "value": "sqrt(x^2+y^2+z^2)-1", "bounds": [[-1.2, -1.2, -1.2], [1.2, 1.2, 1.2]]})");
  SeedOptions so;
  so.resolution = 32;
  const SeedGrid grid = sample_seed_grid(*f, so);
  ASSERT_NEAR(grid.h, 0.075, 1e-12);
  const Box& box = f->bounds();
  const auto plane_z = [&](int layer) { return grid.origin[2] + (layer + 0.5) * grid.h; };
  ASSERT_NEAR(plane_z(15), -0.0375, 1e-12);
  EXPECT_GT(predicted_lean(grid, box, 2, 15), 0.95);
  ASSERT_NEAR(plane_z(29), 1.0125, 1e-12);
  EXPECT_LT(predicted_lean(grid, box, 2, 29), 0.1);
  const int layer = 22;  // z = 0.4875
  double exact = 1;
  for (int j = 0; j <= grid.n[1]; ++j)
    for (int i = 0; i <= grid.n[0]; ++i) {
      const Vec3 p(grid.origin[0] + grid.h * i, grid.origin[1] + grid.h * j, plane_z(layer));
      if (!box.contains(p)) continue;
      Vec3 g;
      const double v = f->value_gradient(p, g);
      if (std::abs(v) > 0.4 * grid.h * g.norm()) continue;  // kPredictedBand
      exact = std::min(exact, std::hypot(g[0], g[1]) / g.norm());
    }
  ASSERT_LT(exact, 0.95);
  EXPECT_NEAR(predicted_lean(grid, box, 2, layer), exact, 0.05);
}

// A cut plane's samples far from the surface as the seed grid sees it are not evaluated: each
// sample has the sign F has there, every sample within a spacing of the surface (where
// plane_lean looks) has F's own value and gradient, and nine planes through a sphere, the torus
// of experiments/fields and the tanglecube cost 42 %, 77 % and 73 % of their samples (the torus
// and the tanglecube fill more of their boxes). Checked against F at every sample.
TEST(AdaptiveBlocks, ACutPlaneIsEvaluatedOnlyNearTheSurface) {
  const auto sphere = test::field_from_json(
      R"({"type": "expression", "value": "sqrt(x^2+y^2+z^2)-1", "bounds": [[-1.2, -1.2, -1.2], [1.2, 1.2, 1.2]]})");
  const auto torus = load_field(std::string(CDP_SOURCE_DIR) + "/experiments/fields/torus.json");
  const auto tangle = load_field(std::string(CDP_SOURCE_DIR) + "/experiments/fields/tanglecube.json");
  const std::pair<const Field*, double> cases[] = {{sphere.get(), 0.45}, {torus.get(), 0.8}, {tangle.get(), 0.75}};
  for (const auto& [f, most] : cases) {
    SeedOptions so;
    so.resolution = 40;
    const SeedGrid grid = sample_seed_grid(*f, so);
    std::size_t samples = 0, evaluated = 0;
    for (int a = 0; a < 3; ++a)
      for (const int layer : {grid.n[a] / 3, grid.n[a] / 2, 2 * grid.n[a] / 3}) {
        const double c = grid.origin[a] + (layer + 0.5) * grid.h;
        const EvaluationCounts before = f->counts();
        const PlaneSamples s = sample_plane(*f, grid, a, layer, c, 1);
        evaluated += (f->counts() - before).value_gradient;
        const double spacing = std::max(s.sb, s.sd);
        for (int j = 0; j <= s.nd; ++j)
          for (int i = 0; i <= s.nb; ++i) {
            const std::size_t k = s.index(i, j);
            Vec3 g;
            const double v = f->value_gradient(s.point(i, j), g);
            ++samples;
            ASSERT_EQ(s.values[k] < 0, v < 0) << "axis " << a << " layer " << layer << " at " << i << ", " << j;
            if (!(std::abs(v) <= spacing * g.norm())) continue;  // as plane_lean: a NaN gradient counts nowhere
            // F itself (a batch may round differently from a single call).
            ASSERT_NEAR(s.values[k], v, 1e-12 * (1 + std::abs(v)));
            ASSERT_LE((s.gradients[k] - g).norm(), 1e-9 * (1 + g.norm()));
          }
      }
    EXPECT_LT(static_cast<double>(evaluated), most * static_cast<double>(samples));
  }
}

// 126k triangles: several times slower under the sanitizers (ctest label slow_under_sanitizers).
TEST(AdaptiveBlocks, ABlackBoxsRoundedEdgesAreFollowedAcrossTheWalls) {
  // Quilez's rounded box with its C1 seams hidden (no branch data: a black box, as a compiled
  // plug-in or a Python function is), cut into blocks: a seam crossing from a flat face onto a
  // rounded edge, spaced by the targets alone, went from the flat face's long edges to the
  // rounded edge's short ones at once, and the blocks' fronts started from it with slivers and
  // chords cutting the rounded edges: at factor 20, 77,856 triangles (40 % fewer than tracked
  // alone), middles up to 0.022 off, the walls' smallest angle 11 degrees. The seams' spacing and
  // their vertices' targets are graded now (grade_along, grade_seam_targets in blocks.cpp).
  const auto box = test::field_from_json(
      R"({"type": "expression", "value": "sqrt(max(abs(x)-0.6,0)^2+max(abs(y)-0.4,0)^2+max(abs(z)-0.3,0)^2)+min(max(abs(x)-0.6,max(abs(y)-0.4,abs(z)-0.3)),0)-0.15",
          "bounds": [[-1.1, -1.1, -1.1], [1.1, 1.1, 1.1]]})");
  const test::Rewrapped black_box(*box, /*smooth=*/false, /*thread_safe=*/true);
  AdaptiveOptions o = with_blocks(2, 20);
  o.creases = CreaseHandling::Ignore;
  const PolygonizeResult r = polygonize_adaptive(black_box, o);
  const BlocksReport& b = r.stats.adaptive->blocks;
  ASSERT_TRUE(b.used) << "[" << b.fallback << "]";
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.genus, 0);
  double worst = 0;
  for (const auto& tri : r.mesh.triangles)
    worst = std::max(worst, std::abs(box->value((r.mesh.positions[tri[0]] + r.mesh.positions[tri[1]] +
                                                  r.mesh.positions[tri[2]]) / 3)));
  std::cout << r.mesh.triangles.size() << " triangles (" << b.estimated_triangles << " estimated), middles within "
            << worst << ", walls' smallest angle " << b.wall_min_angle_degrees << "\n";
  EXPECT_LE(worst, 0.002);
  EXPECT_GE(static_cast<double>(r.mesh.triangles.size()), 0.85 * b.estimated_triangles);
  EXPECT_GE(b.wall_min_angle_degrees, 20.0);
}

TEST(AdaptiveBlocks, TheMeshIsTheSameOnOneTwoThreeAndEightThreads) {
  const auto f = test::field_from_json(kBlockTorus);
  const PolygonizeResult one = polygonize_adaptive(*f, with_blocks(1));
  ASSERT_TRUE(one.stats.adaptive->blocks.used) << one.stats.adaptive->blocks.fallback;
  for (const int threads : {2, 3, 8}) {
    const PolygonizeResult r = polygonize_adaptive(*f, with_blocks(threads));
    EXPECT_EQ(r.stats.adaptive->blocks.threads, static_cast<unsigned>(threads));
    test::expect_same_mesh(one.mesh, r.mesh, std::to_string(threads) + " threads");
  }
}

TEST(AdaptiveBlocks, TheBlocksMeshTheSameInAnyOrder) {
  test_stages::Stages s(kBlockTorus, with_blocks(2));
  const SeedGridStage seeds = sample_seed_grid_stage(*s.field, s.options, s.settings);
  Settings settings = s.settings;
  settings.hash_cell = seeds.hash_cell;
  // Each block repaired in its task, as a run does.
  QualityOptions repair;
  repair.improve_below = 30 * std::numbers::pi / 180;
  repair.diagonal = settings.diagonal;
  repair.min_edge = settings.sizing.min_edge;
  repair.aim_mean_edge_ratio = 1.25;
  const BlockMeshing first = mesh_blocks(*s.field, s.options, settings, seeds, &repair);
  ASSERT_TRUE(first.mesh) << first.report.fallback;
  EXPECT_GT(first.quality.relaxed, 0u);
  for (const std::uint64_t shuffle : {1u, 2u, 3u}) {
    const BlockMeshing other = mesh_blocks(*s.field, s.options, settings, seeds, &repair, shuffle);
    ASSERT_TRUE(other.mesh) << other.report.fallback;
    test::expect_same_mesh(first.mesh->mesh, other.mesh->mesh, "order " + std::to_string(shuffle));
  }
}

TEST(AdaptiveBlocks, AComponentThatCrossesNoCutIsLeftToTheSeeding) {
  // The torus and a small ball inside one block, away from every cut.
  const auto f = test::field_from_json(R"J({"type": "expression",
      "value": "min((sqrt(x^2+y^2)-1)^2 + z^2 - 0.16, sqrt((x-1.3)^2+(y-1.3)^2+z^2) - 0.15)",
      "bounds": [[-1.6, -1.6, -0.6], [1.6, 1.6, 0.6]]})J");
  const PolygonizeResult r = polygonize_adaptive(*f, with_blocks(2));
  const BlocksReport& b = r.stats.adaptive->blocks;
  ASSERT_TRUE(b.used) << b.fallback;
  EXPECT_EQ(b.components, 1u);
  EXPECT_EQ(r.stats.adaptive->seeding.seeds, 1u);
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, 2u);
  EXPECT_EQ(r.stats.components, 2u);
  EXPECT_EQ(test::count_self_intersections(r.mesh), 0u);
}

TEST(AdaptiveBlocks, ALoopWhollyInsideAFaceIsFoundFromThePlanesSamples) {
  // A small ball on the cut x = 0.45 (the torus's cuts at factor 12 are at +-0.45), away from
  // every line where walls meet: its seam is a loop no corner starts, found from the samples.
  const auto f = test::field_from_json(R"J({"type": "expression",
      "value": "min((sqrt(x^2+y^2)-1)^2 + z^2 - 0.16, sqrt((x-0.45)^2+(y-1.5)^2+z^2) - 0.08)",
      "bounds": [[-1.6, -1.6, -0.6], [1.6, 1.6, 0.6]]})J");
  const PolygonizeResult r = polygonize_adaptive(*f, with_blocks(2));
  const BlocksReport& b = r.stats.adaptive->blocks;
  ASSERT_TRUE(b.used) << b.fallback;
  ASSERT_EQ(b.cuts[0].size(), 2u);
  EXPECT_NEAR(b.cuts[0][1], 0.45, 1e-9);
  EXPECT_EQ(b.corners, 8u);
  EXPECT_EQ(b.seams, 17u);  // the torus's 16 and the ball's loop
  EXPECT_EQ(b.components, 2u);
  EXPECT_EQ(r.stats.adaptive->seeding.seeds, 0u);
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, 2u);
  EXPECT_EQ(t.genus, 1);
}

TEST(AdaptiveBlocks, ACreaseMeshedAsSmoothFallsBackToTrackingAloneAtOnce) {
  // Two capsules (experiments/sdf_models) with their creases ignored: a seam turns sharply where
  // it crosses a crease, so the layout is refused and the surface tracked alone, with its reason.
  const auto f = test::field_from_json(R"J({"type": "expression", "value": "min(c1, c2)",
      "define": {"c1": "hypot(x+0.8-1.2*clamp((x+0.8)/1.2,0,1), y, z)-0.25",
                 "c2": "hypot(x-0.4, y-clamp(y,0,0.9), z)-0.2"},
      "bounds": [[-1.4, -1.4, -1.4], [1.4, 1.4, 1.4]]})J");
  AdaptiveOptions o = with_blocks(2, 8);
  o.creases = CreaseHandling::Ignore;
  const PolygonizeResult r = polygonize_adaptive(*f, o);
  const BlocksReport& b = r.stats.adaptive->blocks;
  EXPECT_FALSE(b.used);
  EXPECT_NE(b.fallback.find("seam turns too sharply"), std::string::npos) << b.fallback;
  EXPECT_EQ(b.meshed_blocks, 0u);  // refused while laying out, before any block ran
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.genus, 0);
}

// 107k triangles, in blocks and then tracked alone: several times slower under the sanitizers
// (ctest label slow_under_sanitizers, tests/CMakeLists.txt).
TEST(AdaptiveBlocks, ANeckTheBlocksFrontsSteppedOverIsFound) {
  // The crowd of 200 Wyvill blobs (3 components, genus 30; sdf_models_test.cpp) at chord 5.4e-3: a
  // block's front steps over a neck and closes a handle (at 5e-3 until the seams were traced in
  // steps of a whole edge, kTraceShare in blocks.cpp; since then a block's front stalls there).
  // The neck search, were it to start only from the seeding tracker's vertices near critical
  // points (none here: every component crosses a cut), would not see it (genus 28, exit 0). It
  // starts from the blocks' too, and the run is made again without blocks. (blobs39 of the topology sweep at chord 1e-2 showed it first;
  // since the seams are graded, grade_along in blocks.cpp, its block's front stalls at that neck
  // instead, which falls back as plainly.)
  const auto f = load_field(std::string(CDP_SOURCE_DIR) + "/tests/polygonizer/fields/crowd_200_wyvill_blobs.json");
  AdaptiveOptions o = with_blocks(2);
  o.sizing = SizingMode::Chord;
  o.tolerance = 5.4e-3;
  const PolygonizeResult r = polygonize_adaptive(*f, o);
  EXPECT_GT(r.stats.adaptive->blocks.meshed_blocks, 0u) << r.stats.adaptive->blocks.fallback;
  EXPECT_GE(r.stats.adaptive->necks.reruns, 1u);
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, 3u);
  EXPECT_EQ(t.genus, 30);
}

// 144k triangles in blocks: several times slower under the sanitizers (ctest label
// slow_under_sanitizers, tests/CMakeLists.txt).
TEST(AdaptiveBlocks, ASurfaceCrossingABlocksEdgeTwiceBetweenItsSamplesIsFoundAndTraced) {
  // The crowd of 200 Wyvill blobs at factor 3: a neck crosses the edge x = -1.7278, z = 0.0592 of
  // a layout at y = 0.0237 and 0.0507, between samples of the edge 0.041 apart (kDipHalvings in
  // blocks.cpp), and its seam on the face turns back within one step of the tracer, which left
  // the face by its start (the first step's back_out). The first two layouts have the surface
  // passing by a corner of a face or grazing an edge, and are given up for the next (kLayoutShifts):
  // the third is kept. Every layout failed before, and the run was tracked alone.
  const auto f = load_field(std::string(CDP_SOURCE_DIR) + "/tests/polygonizer/fields/crowd_200_wyvill_blobs.json");
  AdaptiveOptions o = with_blocks(2);
  o.factor = 3;
  const PolygonizeResult r = polygonize_adaptive(*f, o);
  EXPECT_TRUE(r.stats.adaptive->blocks.used) << r.stats.adaptive->blocks.fallback;
  EXPECT_EQ(r.stats.adaptive->blocks.layouts, 3u);
  EXPECT_GT(r.stats.adaptive->blocks.meshed_blocks, 0u);
  test::expect_sound(r.mesh, "crowd in blocks");
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_EQ(t.components, 3u);
  EXPECT_EQ(t.genus, 30);
  EXPECT_GE(r.stats.adaptive->min_angle_degrees, 20.0);
}

TEST(AdaptiveBlocks, AreTheDefaultForAFieldWhoseCallsAreCheap) {
  const auto f = test::field_from_json(kBlockTorus);
  AdaptiveOptions o;
  o.factor = 12;
  const PolygonizeResult r = polygonize_adaptive(*f, o);
  EXPECT_TRUE(r.stats.adaptive->blocks.requested);
  EXPECT_TRUE(r.stats.adaptive->blocks.used) << r.stats.adaptive->blocks.fallback;
  test::expect_same_mesh(r.mesh, polygonize_adaptive(*f, with_blocks(0)).mesh);
  o.blocks = false;
  const PolygonizeResult alone = polygonize_adaptive(*f, o);
  EXPECT_FALSE(alone.stats.adaptive->blocks.requested);
  EXPECT_FALSE(alone.stats.adaptive->blocks.used);
  // A bound on one tracker's work, blocks unset: tracked alone, no fallback to explain.
  o.blocks.reset();
  o.max_steps = 1'000'000;
  const PolygonizeResult bounded = polygonize_adaptive(*f, o);
  EXPECT_FALSE(bounded.stats.adaptive->blocks.requested);
  EXPECT_TRUE(bounded.stats.adaptive->blocks.fallback.empty()) << bounded.stats.adaptive->blocks.fallback;
}

TEST(AdaptiveBlocks, TheRunsPassesAreTimedApartFromTheBlocks) {
  // What the projected speedups divide (BM_AdaptiveBlocks): the data-parallel passes the run made
  // on its own thread, each of at least two blocks of work, and never the blocks' own time again
  // (their trackers' checks are passes of one thread's work inside them).
  const auto f = test::field_from_json(kBlockTorus);
  const PolygonizeResult r = polygonize_adaptive(*f, with_blocks(1));
  const BlocksReport& b = r.stats.adaptive->blocks;
  ASSERT_TRUE(b.used) << b.fallback;
  ASSERT_FALSE(b.pass_seconds.empty());
  ASSERT_EQ(b.pass_seconds.size(), b.pass_blocks.size());
  double passes = 0, blocks = 0;
  for (std::size_t i = 0; i < b.pass_seconds.size(); ++i) {
    EXPECT_GE(b.pass_blocks[i], 2u);
    passes += b.pass_seconds[i];
  }
  for (const double t : b.block_seconds) blocks += t;
  EXPECT_GT(passes, 0.0);
  EXPECT_LE(passes + blocks, r.stats.seconds);
}

TEST(AdaptiveBlocks, ASurfaceTooSmallForBlocksIsTrackedAlone) {
  const auto f = test::field_from_json(kBlockTorus);
  const PolygonizeResult r = polygonize_adaptive(*f, with_blocks(2, 2));
  const BlocksReport& b = r.stats.adaptive->blocks;
  EXPECT_TRUE(b.requested);
  EXPECT_FALSE(b.used);
  EXPECT_EQ(b.blocks, (std::array<int, 3>{1, 1, 1}));
  EXPECT_TRUE(b.fallback.empty()) << b.fallback;
}

// max_steps and max_search_visits bound one tracker's work (the searches averaged over windows
// longer than a block's run): with blocks asked for, a run the caller bounds so is tracked alone,
// and the bound ends it as it would without blocks.
TEST(AdaptiveBlocks, ACallersBoundOnSearchesHoldsWithBlocksAskedFor) {
  const auto f = test::field_from_json(kBlockTorus);
  AdaptiveOptions o = with_blocks(2);
  const PolygonizeResult plain = polygonize_adaptive(*f, o);
  ASSERT_TRUE(plain.stats.adaptive->blocks.used) << plain.stats.adaptive->blocks.fallback;
  o.max_steps = 10 * plain.stats.triangles;  // far more than the mesh needs
  const PolygonizeResult bounded = polygonize_adaptive(*f, o);
  EXPECT_FALSE(bounded.stats.adaptive->blocks.used);
  EXPECT_NE(bounded.stats.adaptive->blocks.fallback.find("max_steps"), std::string::npos);
  o.max_steps = 0;
  o.max_search_visits = 1;
  EXPECT_THROW(polygonize_adaptive(*f, o), LimitExceededError);
}

// The final check tests only the pairs with a triangle that is not sealed (sealed_triangles: a
// block's own, strictly inside its block, checked in its task): most of a block mesh is sealed,
// and a triangle that is not (one the band's repair made) is still tested against sealed ones.
TEST(AdaptiveBlocks, TheFinalCheckTestsEveryTriangleThatIsNotSealedAgainstAll) {
  test_stages::Stages s(kBlockTorus, with_blocks(2));
  const SeedGridStage seeds = sample_seed_grid_stage(*s.field, s.options, s.settings);
  Settings settings = s.settings;
  settings.hash_cell = seeds.hash_cell;
  const BlockMeshing b = mesh_blocks(*s.field, s.options, settings, seeds);
  ASSERT_TRUE(b.mesh) << b.report.fallback;
  Mesh mesh = b.mesh->mesh;
  std::vector<char> sealed = sealed_triangles(b, mesh);
  std::size_t n = 0;
  for (const char c : sealed) n += c;
  EXPECT_GT(n, mesh.triangles.size() / 2);
  EXPECT_LT(n, mesh.triangles.size());
  EXPECT_NO_THROW(check_mesh(mesh, 1, true, 2, CancelToken{}, &sealed));
  // A small triangle, not sealed, through the middle of a sealed one.
  const auto it = std::find(sealed.begin(), sealed.end(), 1);
  const auto& t = mesh.triangles[static_cast<std::size_t>(it - sealed.begin())];
  const Vec3 c = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3;
  const Vec3 n0 = (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]).normalized();
  const Vec3 along = (mesh.positions[t[1]] - mesh.positions[t[0]]).normalized() * 1e-3;
  const int v = static_cast<int>(mesh.positions.size());
  for (const Vec3& p : {Vec3(c + 1e-3 * n0), Vec3(c - 1e-3 * n0 + along), Vec3(c - 1e-3 * n0 - along)}) {
    mesh.positions.push_back(p);
    mesh.normals.push_back(n0);
  }
  mesh.triangles.push_back({v, v + 1, v + 2});
  sealed.push_back(0);
  std::vector<char> involved(sealed.size());
  for (std::size_t i = 0; i < sealed.size(); ++i) involved[i] = !sealed[i];
  EXPECT_FALSE(self_intersecting_pairs_involving(mesh, involved).empty());
}

}  // namespace
}  // namespace cdp::adaptive
