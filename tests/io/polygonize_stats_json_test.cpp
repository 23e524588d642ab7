// to_json(PolygonizeStats): every field of the typed reports lands under its key of docs/stats.md,
// with its own value (each set to a different number here, so that two swapped fields fail).
#include <cdp/io/polygonize_stats_json.h>

#include <gtest/gtest.h>

#include <string>

namespace cdp {
namespace {

// The value at a dotted key ("quality.flips"), or null when a member on the way is missing.
nlohmann::json at(const nlohmann::json& j, const std::string& key) {
  const nlohmann::json* p = &j;
  std::size_t start = 0;
  for (;;) {
    const std::size_t dot = key.find('.', start);
    const std::string name = key.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (!p->is_object() || !p->contains(name)) return nullptr;
    p = &(*p)[name];
    if (dot == std::string::npos) return *p;
    start = dot + 1;
  }
}

TEST(PolygonizeStatsJson, EveryAdaptiveFieldUnderItsKey) {
  PolygonizeStats s;
  s.method = "adaptive";
  s.triangles = 1;
  s.field_evaluations = {2, 3, 4};
  AdaptiveReport& r = s.adaptive.emplace();
  r.settings = {.variant = Variant::Paper, .sizing = SizingMode::Tolerance, .factor = 0, .tolerance = 5,
                .min_edge = 6, .max_edge = 7, .triangle_count = TriangleCountRule::PaperFloor,
                .seed_resolution = 8, .grading = true, .quality_repair = false, .tolerance_refinement = true};
  r.seeding = {.sign_changes = 10, .seeds = 11, .failed_seeds = 12, .covered_nearby = 13, .below_resolution = 14,
               .thin_bridges = 82, .seeds_first = 83,
               .refined_cells = 15, .unresolved_cells = 16, .unsearched_cells = 78, .probes = 17, .probes_outside = 81,
               .band_cells = 79,
               .band_components = 80, .uncovered = 18,
               .first_uncovered = Vec3::Zero(), .non_finite_samples = 19};
  r.tracker = {.steps = 20, .search_visits = 21, .deferrals = 22, .anticipations = 23, .side_points = 24,
               .forced_closures = 25, .rollbacks = 26, .rollbacks_failed = 27, .crease_points = 28,
               .over_mesh_rejections = 29, .sheet_jumps = 81, .curvature_seconds = 30, .hessian_seconds = 31,
               .min_curvature_radius = 32};
  r.creases = {.handling = CreaseHandling::Follow, .followed = true, .curves = 40, .corners = 41, .vertices = 42,
               .pieces = 43, .components = 44, .steps = 45, .patch_refusals = 46, .fallback = "why",
               .tracing_resolution = 47, .across_black_box = true};
  r.quality.repair_below_degrees = 50;
  r.quality.flips = 51;
  r.quality.relax_crossings = 52;
  r.quality.over_tolerance = 53;
  r.quality.over_tolerance_worst = 54;
  r.quality.over_tolerance_near = Vec3(55, 56, 57);
  r.necks = {.walks = 60, .critical_points = 61, .tested = 62, .reruns = 63, .unwalked = 64, .caps = 65};
  r.recoveries = {.min_edge_lowered = true, .turn_limited = false, .look_ahead = true, .quality_rerun = false,
                  .quality_rerun_kept = true, .tolerance_rerun = true, .tolerance_rerun_kept = false,
                  .remeshed_with_rollbacks = false, .remeshed_carefully = true,
                  .careful_max_turn = 70};
  r.phases[2] = {.seconds = 71, .evaluations = {72, 73, 74}};
  r.split_evaluations = 75;
  r.seed_grid_seconds = 76;
  r.min_angle_degrees = 77;
  const nlohmann::json j = to_json(s);

  const std::pair<const char*, nlohmann::json> expected[] = {
      {"method", "adaptive"}, {"triangles", 1}, {"field_evaluations.value", 2}, {"field_evaluations.total", 9},
      {"variant", "paper"}, {"sizing", "tolerance"}, {"tolerance", 5.0}, {"edge_length.min", 6.0},
      {"edge_length.max", 7.0}, {"triangle_count_rule", "paper_floor"}, {"seed_resolution", 8}, {"grading", true},
      {"quality_repair", false}, {"tolerance_refinement", true}, {"sign_changes", 10}, {"seeds", 11},
      {"failed_seeds", 12}, {"covered_nearby", 13}, {"below_resolution", 14}, {"thin_bridges", 82}, {"seeds_first", 83}, {"refined_cells", 15},
      {"unresolved_cells", 16}, {"unsearched_cells", 78}, {"probes", 17}, {"probes_outside", 81}, {"band_cells", 79},
      {"band_components", 80}, {"uncovered_crossings", 18}, {"non_finite_samples", 19},
      {"steps", 20}, {"search_visits", 21}, {"deferrals", 22}, {"anticipations", 23}, {"side_points", 24},
      {"forced_closures", 25}, {"rollbacks", 26}, {"rollbacks_failed", 27}, {"crease_points", 28},
      {"over_mesh_rejections", 29}, {"sheet_jumps", 81}, {"curvature_seconds", 30.0}, {"hessian_seconds", 31.0},
      {"curvature.min_radius", 32.0}, {"creases.handling", "follow"}, {"creases.followed", true},
      {"creases.curves", 40}, {"creases.corners", 41}, {"creases.vertices", 42}, {"creases.pieces", 43},
      {"creases.components", 44}, {"creases.steps", 45}, {"creases.patch_refusals", 46},
      {"creases.fallback", "why"}, {"creases.tracing_resolution", 47}, {"creases.across_black_box", true},
      {"quality.repair_below_degrees", 50.0}, {"quality.flips", 51}, {"quality.relax_crossings", 52},
      {"quality.over_tolerance", 53}, {"quality.over_tolerance_worst", 54.0},
      {"quality.over_tolerance_near_x", 55.0}, {"quality.over_tolerance_near_y", 56.0},
      {"quality.over_tolerance_near_z", 57.0}, {"necks.walks", 60}, {"necks.critical_points", 61},
      {"necks.tested", 62}, {"necks.reruns", 63}, {"necks.unwalked", 64}, {"necks.caps", 65}, {"min_edge_lowered", true}, {"turn_limited", false},
      {"look_ahead", true}, {"quality_rerun", false}, {"quality_rerun_kept", true},
      {"tolerance_rerun", true}, {"tolerance_rerun_kept", false},
      {"remeshed_with_rollbacks", false}, {"remeshed_carefully", true}, {"careful_max_turn", 70.0},
      {"phases.tracking.seconds", 71.0}, {"phases.tracking.value", 72}, {"phases.tracking.value_gradient", 73},
      {"phases.tracking.gradient_hessian", 74}, {"phases.seed_grid.value", 0}, {"split_evaluations", 75},
      {"seed_grid_seconds", 76.0}, {"min_angle_degrees", 77.0}};
  for (const auto& [key, value] : expected) {
    EXPECT_EQ(at(j, key), value) << key;
    // The same kind (an integer stays one, a number stays one), as STATS.json's readers expect.
    EXPECT_EQ(at(j, key).is_number_integer(), value.is_number_integer()) << key;
  }
  // Factor sizing writes the factor and no tolerance; no over_tolerance details without any.
  r.settings.sizing = SizingMode::Factor;
  r.settings.factor = 3;
  r.quality.over_tolerance = 0;
  const nlohmann::json f = to_json(s);
  EXPECT_EQ(at(f, "factor"), 3.0);
  EXPECT_TRUE(at(f, "tolerance").is_null());
  EXPECT_TRUE(at(f, "quality.over_tolerance_worst").is_null());
  EXPECT_TRUE(at(f, "traversal").is_null());
}

TEST(PolygonizeStatsJson, EveryLatticeFieldUnderItsKey) {
  PolygonizeStats s;
  s.method = "mc";
  LatticeReport& r = s.lattice.emplace();
  r = {.traversal = "grid", .face_ambiguity = "join_inside", .cell_size = 1, .precision = 2, .cells = {3, 4, 5},
       .root_tolerance = 6, .cubes_visited = 7, .cubes_crossed = 8, .corner_evaluations = 9,
       .root_evaluations = 10, .centre_vertices = 11, .collapsed_edges = 12, .dropped_components = 13,
       .short_edges_left = 14, .seeding = LatticeSeedingReport{20, 21, 22, 23, 24, 25, 26, 27, 28},
       .open_boundary_faces = 30};
  s.angles = AngleStatistics{.triangles = 0, .degenerate = 40, .min_degrees = 41, .below = {42, 43}};
  const nlohmann::json j = to_json(s);
  const std::pair<const char*, nlohmann::json> expected[] = {
      {"traversal", "grid"}, {"face_ambiguity", "join_inside"}, {"cell_size", 1.0}, {"precision", 2},
      {"lattice_cells", {3, 4, 5}}, {"root_tolerance", 6.0}, {"cubes_visited", 7}, {"cubes_crossed", 8},
      {"corner_evaluations", 9}, {"root_evaluations", 10}, {"centre_vertices", 11}, {"collapsed_edges", 12},
      {"dropped_components", 13}, {"short_edges_left", 14}, {"seed_resolution", 20}, {"seeds", 21},
      {"unresolved_seeds", 22}, {"starts", 23}, {"seed_search_cubes", 24}, {"sign_changes", 25},
      {"completion_starts", 26}, {"unreached_sign_changes", 27}, {"completion_evaluations", 28},
      {"open_boundary_faces", 30}, {"angles.degenerate", 40}, {"angles.min_degrees", 41.0},
      {"angles.cumulative_below_degrees", {42, 43}}};
  for (const auto& [key, value] : expected) EXPECT_EQ(at(j, key), value) << key;
  // Marching Tetrahedra has no face rule; a grid traversal no seeding; a closed box no open faces.
  r.face_ambiguity.clear();
  r.precision.reset();
  r.seeding.reset();
  r.open_boundary_faces.reset();
  const nlohmann::json m = to_json(s);
  for (const char* key : {"face_ambiguity", "precision", "seeds", "open_boundary_faces", "steps"})
    EXPECT_TRUE(at(m, key).is_null()) << key;
}

// "summary" (add_mesh_summary) reads the mesh: a tetrahedron is watertight with genus 0; the
// same with a face missing is open, not watertight, without a genus; with a face turned, not
// oriented.
TEST(PolygonizeStatsJson, SummaryTellsWhetherTheMeshIsWatertight) {
  Mesh tetrahedron;
  tetrahedron.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  tetrahedron.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const auto summary = [](const Mesh& m) {
    PolygonizeStats s;
    add_mesh_summary(m, s);
    return to_json(s)["summary"];
  };
  const nlohmann::json closed = summary(tetrahedron);
  EXPECT_TRUE(closed["watertight"].get<bool>());
  EXPECT_TRUE(closed["outward"].get<bool>());
  EXPECT_EQ(closed["components"], 1);
  EXPECT_EQ(closed["genus"], 0);
  EXPECT_NEAR(closed["smallest_angle_degrees"].get<double>(), 45.0, 1e-9);
  Mesh open = tetrahedron;
  open.triangles.pop_back();
  const nlohmann::json o = summary(open);
  EXPECT_FALSE(o["closed"].get<bool>());
  EXPECT_FALSE(o["watertight"].get<bool>());
  EXPECT_EQ(o["genus"], -1);
  Mesh turned = tetrahedron;
  std::swap(turned.triangles[3][0], turned.triangles[3][1]);
  const nlohmann::json t = summary(turned);
  EXPECT_TRUE(t["closed"].get<bool>());
  EXPECT_FALSE(t["oriented"].get<bool>());
  EXPECT_FALSE(t["watertight"].get<bool>());
  EXPECT_FALSE(summary(Mesh{})["watertight"].get<bool>());  // nothing is not a closed surface
}

}  // namespace
}  // namespace cdp
