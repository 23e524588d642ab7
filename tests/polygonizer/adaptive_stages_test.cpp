// The adaptive polygonizer's stages, each run alone on its typed input (polygonizer/README.md,
// "How a run goes"): settings, seed grid, creases, tracking, repair, checks. The whole pipeline
// and its recoveries are tested through polygonize_adaptive in the other adaptive_*_test files.
#include <gtest/gtest.h>

#include "../../polygonizer/src/adaptive/resolve_settings.h"
#include "../../polygonizer/src/adaptive/stage_checks.h"
#include "../../polygonizer/src/adaptive/stage_creases.h"
#include "../../polygonizer/src/adaptive/stage_repair.h"
#include "../../polygonizer/src/adaptive/stage_seed_grid.h"
#include "../../polygonizer/src/adaptive/stage_tracking.h"

#include <cdp/core/errors.h>
#include <cdp/core/mesh_topology.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "common/test_fields.h"
#include "polygonizer/mesh_checks.h"

namespace cdp::adaptive {
namespace {

const char* const kSphere = R"({"type": "sphere", "radius": 1})";
const char* const kTanglecube = R"({"type": "expression", "value": "x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + 11.8",
                                    "bounds": [[-3, -3, -3], [3, 3, 3]]})";
const char* const kCube = R"({"type": "expression", "value": "max(abs(x), max(abs(y), abs(z))) - 1",
                              "bounds": [[-1.5, -1.5, -1.5], [1.5, 1.5, 1.5]]})";

// What the stages share in one run.
struct Stages {
  std::unique_ptr<Field> field;
  AdaptiveOptions options;
  PhaseLedger phases;
  RunContext run;
  Settings settings;
  explicit Stages(const char* json, AdaptiveOptions o = {})
      : field(test::field_from_json(json)), options(std::move(o)), phases(*field), run{*field, options, phases},
        settings(resolve_settings(*field, options)) {}
};

// The tracking stage on `seeds`, without crease patches, at the hash cell the seed grid measured.
void track(Stages& s, const SeedGridStage& seeds, Mesh& mesh, Tracking& tracking) {
  Settings settings = s.settings;
  settings.hash_cell = seeds.hash_cell;
  track_surface(s.run, seeds, CreaseLayout{}, settings, mesh, tracking);
}

TEST(AdaptiveStages, SettingsResolveTheDefaultsFromTheBoxAndRefuseBadOptions) {
  const auto field = test::field_from_json(kSphere);
  const double diagonal = field->bounds().diagonal();
  const Settings s = resolve_settings(*field, AdaptiveOptions{});
  EXPECT_DOUBLE_EQ(s.diagonal, diagonal);
  EXPECT_DOUBLE_EQ(s.sizing.min_edge, 2e-3 * diagonal);
  EXPECT_DOUBLE_EQ(s.sizing.max_edge, 0.1 * diagonal);
  EXPECT_EQ(s.sizing.factor, 2);
  AdaptiveOptions tol;
  tol.sizing = SizingMode::Tolerance;
  tol.tolerance = 1e-3;
  EXPECT_LT(resolve_settings(*field, tol).sizing.tolerance, 1e-3);  // the sizing keeps a share for the refinement
  EXPECT_DOUBLE_EQ(requested_tolerance(tol, s), 1e-3);
  for (const auto& [what, set] : std::vector<std::pair<std::string, std::function<void(AdaptiveOptions&)>>>{
           {"nan tolerance", [](AdaptiveOptions& o) { o.tolerance = std::nan(""); }},
           {"min_edge above max_edge", [](AdaptiveOptions& o) { o.min_edge = 1, o.max_edge = 0.5; }},
           {"factor 0", [](AdaptiveOptions& o) { o.factor = 0; }},
           {"seed_resolution 1", [](AdaptiveOptions& o) { o.seed_resolution = 1; }}}) {
    AdaptiveOptions o;
    set(o);
    EXPECT_THROW(resolve_settings(*field, o), InvalidInputError) << what;
  }
  EXPECT_TRUE(remeshing_allowed(AdaptiveOptions{}));
  AdaptiveOptions bounded;
  bounded.max_triangles = 100;
  EXPECT_FALSE(remeshing_allowed(bounded));
}

TEST(AdaptiveStages, TheSeedGridMeasuresTheSurfacesArea) {
  Stages s(kSphere);
  const SeedGridStage seeds = sample_seed_grid_stage(*s.field, s.options, s.settings);
  EXPECT_GE(seeds.crossings, kMeasuredCrossings);
  // Crofton's estimate: meshes the checks pass measure 0.90-1.01 of it.
  EXPECT_NEAR(seeds.estimated_area / (4 * std::numbers::pi), 1.0, 0.1);
  EXPECT_GT(seeds.hash_cell, 0);
  EXPECT_LE(seeds.hash_cell, 2 * s.settings.sizing.max_edge);
}

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
    track_surface(outside.run, none, CreaseLayout{}, st, empty, nothing);
    ADD_FAILURE() << "no error";
  } catch (const NoSurfaceError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("adaptive: no zero crossing of the field in its box", 0), 0u) << e.what();
  }
  EXPECT_TRUE(nothing.no_crossing);
}

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

TEST(AdaptiveStages, TheChecksRefuseAnOpenMeshAndCountTheQualityBoundsMissed) {
  Mesh tetra;
  tetra.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tetra.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const CancelToken cancel;
  EXPECT_EQ(check_mesh(tetra, 1, true, 1, cancel), 1u);
  EXPECT_THROW(check_mesh(tetra, 2, true, 1, cancel), NoSurfaceError);  // one component from two seeds
  Mesh open = tetra;
  open.triangles.pop_back();
  try {
    check_mesh(open, 1, true, 1, cancel);
    ADD_FAILURE() << "no error";
  } catch (const NoSurfaceError& e) {
    EXPECT_NE(std::string(e.what()).find("3 boundary"), std::string::npos) << e.what();
  }
  // The tetrahedron's faces: three right isosceles triangles (45 degrees, edge ratio 1.41) and
  // one equilateral: none under 30 degrees, a mean edge ratio of 1.31 (over 1.25); triangles
  // beyond the tolerance are a bound missed too.
  EXPECT_EQ(missed_bounds(tetra, 0), 1);
  EXPECT_EQ(missed_bounds(tetra, 5), 2);
  Mesh sliver = tetra;
  sliver.positions[3] = {0.5, 0.5, 0.01};  // the faces at vertex 3 nearly flat: angles near 0
  EXPECT_EQ(missed_bounds(sliver, 0), 3);
  EXPECT_NEAR(min_angle_degrees(tetra), 45, 1e-9);
}

}  // namespace
}  // namespace cdp::adaptive
