// Hard surfaces for the adaptive polygonizer (the robustness issue's suite): CSG creases and
// corners, shells and cavities, high-genus algebraic surfaces, thin and tiny components, random
// blob fields, each at several factors, tolerances and chord deviations. Two promises, tested separately:
//  - never wrong without saying so: a run either returns a closed, oriented, manifold, outward
//    mesh without self-intersections whose components and genus match an independent reference,
//    or throws a clear error naming a place (every case, every factor);
//  - the cases listed as meshing must mesh (those that do today; the others are the open part
//    of the issue, and each prints its outcome so the table in the notes can be regenerated:
//    `build/bin/test_polygonizer --gtest_filter='HardSurfaces*' | grep hard-surface`).
// References: closed forms where the shape is known, else marching tetrahedra on a fine grid
// whose topology is the same at two grid sizes.
#include <gtest/gtest.h>

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/errors.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/io/field_factory.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <sstream>

#include "common/test_fields.h"
#include "polygonizer/mesh_checks.h"

namespace cdp {
namespace {

struct HardSurface {
  std::string name;
  std::string json;           // the field as a user writes it
  int components = -1;        // closed form; -1: from the marching reference
  int genus = -1;
  std::vector<double> meshes_at;  // the factors the suite runs, at which the run must succeed
  // Factors at which the run must end with an error naming an acute crease of the field and
  // the angle of its faces, not a feature thinner than min_edge, which such a wedge is not (its
  // two faces meet there). None today: meshed along their creases, the gyroid ball and the box
  // minus a ball get past the wedges the tracker stalled at (the diagnosis is tested with the
  // creases ignored, adaptive/creases/crease_patches_test.cpp).
  std::vector<double> crease_at = {};
  // Tolerances (kTolerances) at which the mesh comes from the last run polygonize_adaptive
  // makes, every edge turning the normal by at most a radian (stats `turn_limited`), after every
  // other run failed: the Barth ball at the coarsest.
  std::vector<double> turn_limited_at = {};
  // Whether the surface bends somewhere with a radius of curvature below the default min_edge
  // (measured independently): a mesh then comes from the run made again with a lower min_edge,
  // and an error names the bend and says that run failed too.
  bool bends_below_min_edge = false;
};

// Wyvill blobs with random centres in [lo, hi]^3 and radii in [rmin, rmax]; with `apart`, centres
// closer than that to an earlier one are drawn again (separate components); `extra` goes into
// the object before the blobs (bounds).
std::string blobs_json(unsigned seed, int count, double lo, double hi, double rmin, double rmax, double apart = 0,
                       const std::string& extra = "") {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> c(lo, hi), r(rmin, rmax);
  std::vector<Vec3> centres;
  std::ostringstream s;
  s << R"({"type": "blobs", "kernel": "wyvill", "threshold": 0.3, )" << extra << R"("blobs": [)";
  for (int i = 0; i < count; ++i) {
    Vec3 p;
    for (int tries = 0; tries < 1000; ++tries) {
      p = Vec3(c(rng), c(rng), c(rng));
      bool clear = true;
      for (const Vec3& q : centres) clear = clear && (p - q).norm() >= apart;
      if (clear) break;
    }
    centres.push_back(p);
    if (i) s << ", ";
    s << R"({"center": [)" << p.x() << ", " << p.y() << ", " << p.z() << R"(], "radius": )" << r(rng) << "}";
  }
  s << "]}";
  return s.str();
}

using test::expression;

std::vector<HardSurface> make_hard_surfaces() {
  std::vector<HardSurface> v = {
      {"cube", expression("max(abs(x),max(abs(y),abs(z)))-1", 1.5), 1, 0, {1, 2, 3, 5}},
      // Not aligned with the axes (no ties of max at the edges; faces meet at exactly 90 degrees,
      // where the same-side test of the normals alone is a rounding decision) and a capped cylinder.
      {"rotated_cube",
       expression("max(abs(0.8*x+0.6*y),max(abs(-0.48*x+0.64*y+0.6*z),abs(0.36*x-0.48*y+0.8*z)))-1", 2), 1, 0,
       {1, 2, 3, 5}},
      {"capped_cylinder", expression("max(sqrt(x^2+y^2)-1, abs(z)-1)", 1.5), 1, 0, {1, 2, 3, 5}},
      // A box with a ball taken out: each face's round hole meets the ball in a 34-degree wedge,
      // which the crease-blind tracker takes for two sheets; crease-aware meshing meshes it.
      {"box_minus_ball", expression("max(max(abs(x),max(abs(y),abs(z)))-1, 1.2-sqrt(x^2+y^2+z^2))", 1.5), 1, 5,
       {1, 2, 3, 5}},
      // One component of genus 34: marching cubes of cell 0.01 gives a main component of genus 34
      // and 45 bubbles of 16 triangles where single grid points fall inside the acute rims (cells
      // of 0.03, 0.02, 0.015 also split the rims: 31, 28, 16 components, genus 31 in all), so
      // the marching reference of the suite's grids is not stable here and the count is given.
      {"gyroid_ball",
       expression("max(sin(4*x)*cos(4*y)+sin(4*y)*cos(4*z)+sin(4*z)*cos(4*x), x^2+y^2+z^2-4)", 2.2), 1, 34,
       {1, 2, 3, 5}},
      {"barth_ball",
       expression("max(4*(2.618034*x^2-y^2)*(2.618034*y^2-z^2)*(2.618034*z^2-x^2)-4.236068*(x^2+y^2+z^2-1)^2+0.01, "
                  "x^2+y^2+z^2-3.5)",
                  2.1),
       // Its necks bend with a radius of 0.0083 (k2 = -120 at (0, -0.61, 1.621), projected points of
       // a marching-cubes mesh of cell 0.01), below the default min_edge, 0.0145: the first runs
       // fail, and the run made again with min_edge at a quarter of that radius meshes it. One
       // component of genus 30, as marching cubes gives with cells of 0.005 and 0.0045 (grid
       // traversal; 8 and 4 minutes, too long for the suite). At factor 5 a small stuck front
       // along a crease loop on the ball was closed by the ear of its smallest angle, which lay
       // over the rest of that thin loop, and the fronts ran on over the triangles it covered
       // until the search bound stopped them; the ear chosen now holds no other front point.
       // At tolerance 1e-1 the sizing asks for chords up to the diameter of bends tighter than
       // the tolerance: every run failed (stalled fronts) until the last run bounded every edge's
       // turn; since the crease patches grade their fronts more gently (kPatchLookAheadGradations)
       // the run with min_edge lowered meshes it (at 7e-2 and 5e-2 the last run still does:
       // AdaptiveTurnLimit below).
       // Factors 1, 2 and 5 only: at 3 it takes 21 s (the suite's 2 minutes; the sweep in the
       // notes runs factors 1-10).
       1, 30, {1, 2, 5}, {}, {}, true},
      {"chmutov6",
       expression("(32*x^6-48*x^4+18*x^2-1)+(32*y^6-48*y^4+18*y^2-1)+(32*z^6-48*z^4+18*z^2-1)", 1.15), -1, -1, {1, 2, 3, 5}},
      {"chmutov4", expression("(8*x^4-8*x^2+1)+(8*y^4-8*y^2+1)+(8*z^4-8*z^2+1)", 1.3), -1, -1, {1, 2, 3, 5}},
      {"tanglecube", expression(test::kTanglecube, 3), 1, 5, {1, 2, 3, 5}},
      {"hollow_sphere", expression("max(sqrt(x^2+y^2+z^2)-1.25, 0.75-sqrt(x^2+y^2+z^2))", 2), 2, 0, {1, 2, 3, 5}},
      {"off_centre_cavity", expression("max(sqrt(x^2+y^2+z^2)-1.25, 0.5-sqrt((x-0.4)^2+y^2+z^2))", 2), 2, 0,
       {1, 2, 3, 5}},
      {"shell", expression("abs(sqrt(x^2+y^2+z^2)-1)-0.1", 1.5), 2, 0, {1, 2, 3, 5}},
      // A ball with six voids of radius 0.04 just under its surface, each around a node of the
      // seed grid (spacing 0.09375) whose outer neighbour lies outside the ball: every sign
      // change of a void faces the way a nearby triangle of the sphere does (edges up to 0.52),
      // within one of its edges. Those triangles once passed for the voids' own mesh: 1
      // component of 7, exit 0, at every factor (a Schwarz D surface cut by a ball, 40 of 61).
      {"ball_with_voids_under_its_skin",
       expression("max(sqrt(x^2+y^2+z^2)-1, max(max(max(0.04-sqrt((x-0.9375)^2+y^2+z^2), "
                  "0.04-sqrt((x+0.9375)^2+y^2+z^2)), max(0.04-sqrt(x^2+(y-0.9375)^2+z^2), "
                  "0.04-sqrt(x^2+(y+0.9375)^2+z^2))), max(0.04-sqrt(x^2+y^2+(z-0.9375)^2), "
                  "0.04-sqrt(x^2+y^2+(z+0.9375)^2))))",
                  1.5),
       7, 0, {1, 2, 3, 5}},
      {"spheres_1e-3_apart",
       expression("min(sqrt((x-1.0005)^2+y^2+z^2)-1, sqrt((x+1.0005)^2+y^2+z^2)-1)", 2.5), 2, 0, {1, 2, 3, 5}},
      {"needle", R"({"type": "ellipsoid", "radii": [5, 0.05, 0.05]})", 1, 0, {1, 2, 3, 5}},
      {"thin_torus", R"({"type": "torus", "major_radius": 1, "minor_radius": 0.01})", 1, 1, {1, 2, 3, 5}},
      {"tiny_blobs", blobs_json(7, 50, -4.5, 4.5, 0.1, 0.1, 0.5, R"("bounds": [[-5,-5,-5],[5,5,5]], )"), 50, 0,
       {1, 2, 3, 5}},
      {"fifty_blobs", blobs_json(3, 50, -2, 2, 0.5, 1.0), -1, -1, {1, 2, 3, 5}},
  };
  for (unsigned seed = 1; seed <= 20; ++seed)
    v.push_back({"random_blobs_" + std::to_string(seed), blobs_json(100 + seed, 2 + seed % 5, -1.6, 1.6, 0.7, 1.3),
                 -1, -1, {1, 2, 5}});
  return v;
}
// Made once: every test process names and filters all the cases at its start (a few hundred
// calls), and drawing the blob fields each time cost 0.6 s a process under the sanitizers.
const std::vector<HardSurface>& hard_surfaces() {
  static const std::vector<HardSurface> surfaces = make_hard_surfaces();
  return surfaces;
}

// Issue 12 asks for every factor and every tolerance: the suite runs three tolerances beside its
// factors, a coarse one (edges up to max_edge on flat parts), one in between and a fine one.
constexpr double kTolerances[] = {1e-1, 1e-2, 1e-3};

struct SurfaceCase {
  std::size_t surface;
  double factor;
  double tolerance = 0;  // positive: --tolerance instead of --factor
  bool chord = false;    // with tolerance: --chord (SizingMode::Chord) instead of --tolerance
};

std::string surface_case_name(const testing::TestParamInfo<SurfaceCase>& info) {
  std::ostringstream tolerance;
  tolerance << info.param.tolerance;
  std::string n = hard_surfaces()[info.param.surface].name +
                  (info.param.tolerance > 0 ? (info.param.chord ? "_chord" : "_tolerance") + tolerance.str()
                                            : "_factor" + std::to_string(static_cast<int>(info.param.factor)));
  for (char& c : n)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return n;
}

class HardSurfaces : public testing::TestWithParam<SurfaceCase> {};

TEST_P(HardSurfaces, CorrectMeshOrClearError) {
  const HardSurface h = hard_surfaces()[GetParam().surface];
  const double factor = GetParam().factor, tolerance = GetParam().tolerance;
  const auto field = test::field_from_json(h.json);
  AdaptiveOptions o;
  o.factor = factor;
  const bool chord = GetParam().chord;
  if (tolerance > 0) {
    o.sizing = chord ? SizingMode::Chord : SizingMode::Tolerance;
    o.tolerance = tolerance;
  }
  const std::string run = tolerance > 0 ? (chord ? "chord " : "tolerance ") + std::to_string(tolerance)
                                        : "factor " + std::to_string(factor);
  std::string outcome;
  try {
    const PolygonizeResult r = polygonize_adaptive(*field, o);
    const MeshTopology t = analyze_topology(r.mesh);
    int components = h.components, genus = h.genus;
    if (components < 0) {
      const test::MarchingReference ref = test::marching_reference(h.name, *field);
      if (!ref.stable) GTEST_SKIP() << h.name << ": the marching reference is not stable between grid sizes";
      components = ref.components, genus = ref.genus;
    }
    EXPECT_TRUE(t.watertight()) << h.name;
    EXPECT_EQ(static_cast<int>(t.components), components) << h.name;
    EXPECT_EQ(t.genus, genus) << h.name;
    EXPECT_EQ(test::count_self_intersections(r.mesh), 0u) << h.name;
    EXPECT_EQ(r.stats.adaptive->seeding.uncovered, 0u);
    test::expect_phases_add_up(r, h.name);  // min_edge lowered and turn-limited runs among them
    // A chord deviation limits the turn from the start and makes no such last run.
    const bool turn_limited = tolerance > 0 && !chord &&
                              std::find(h.turn_limited_at.begin(), h.turn_limited_at.end(), tolerance) !=
                                  h.turn_limited_at.end();
    EXPECT_EQ(r.stats.adaptive->recoveries.turn_limited, turn_limited) << h.name;
    if (h.bends_below_min_edge && tolerance == 0) {
      EXPECT_TRUE(r.stats.adaptive->recoveries.min_edge_lowered);
      EXPECT_LT(r.stats.adaptive->settings.min_edge, 0.0083);  // the necks' radius (above)
    }
    outcome = "meshed: " + std::to_string(t.triangles) + " triangles, " + std::to_string(t.components) +
              " components, genus " + std::to_string(t.genus) + ", min angle " +
              std::to_string(r.stats.adaptive->min_angle_degrees);
  } catch (const LimitExceededError& e) {
    outcome = std::string("error: ") + e.what();
  } catch (const NoSurfaceError& e) {
    outcome = std::string("error: ") + e.what();
  }
  std::cout << "hard-surface " << h.name << " " << run << ": " << outcome << "\n";
  if (outcome.rfind("error", 0) == 0) {
    // A clear error names the place.
    EXPECT_NE(outcome.find("near ("), std::string::npos) << outcome;
    bool required = tolerance > 0;  // every surface meshes at every tolerance and chord deviation of the suite
    for (double k : h.meshes_at) required = required || k == factor;
    EXPECT_FALSE(required) << h.name << " at " << run << " must mesh: " << outcome;
  }
  if (h.bends_below_min_edge && outcome.rfind("error", 0) == 0) {
    EXPECT_NE(outcome.find("radius of curvature of"), std::string::npos) << outcome;
    EXPECT_NE(outcome.find("meshed again with min_edge"), std::string::npos) << outcome;
  }
  for (double k : h.crease_at) {
    if (tolerance == 0 && k == factor) {
      EXPECT_NE(outcome.find("folds into a crease whose faces meet at"), std::string::npos) << outcome;
      EXPECT_EQ(outcome.find("thinner than min_edge"), std::string::npos) << outcome;
    }
  }
}

// Several times slower under the sanitizers, the suite runs there a subset at factor 2 and
// tolerance and chord 1e-2, named so that a surface added to the list does not change it:
// creases (the cube; the box minus a ball, whose acute hole rims only crease-aware meshing
// meshes), an acute crease that fails (the gyroid ball), a cavity, a needle, genus 5 and a few
// blob fields. The rest (instantiated as AdaptiveMore, with the runaways: the Barth ball, the
// fifty blobs, 264 s under the sanitizers) carries the label slow_under_sanitizers
// (tests/CMakeLists.txt).
bool under_sanitizers(const SurfaceCase& c) {
  static const std::set<std::string> kUnderSanitizers = {
      "cube", "gyroid_ball", "box_minus_ball", "hollow_sphere", "needle", "tanglecube",
      "random_blobs_1", "random_blobs_5", "random_blobs_9", "random_blobs_13", "random_blobs_17"};
  if (!kUnderSanitizers.count(hard_surfaces()[c.surface].name)) return false;
  return c.tolerance > 0 ? c.tolerance == 1e-2 : c.factor == 2;
}

// The cases under the sanitizers (`sanitized`) or the others.
std::vector<SurfaceCase> surface_cases(bool sanitized) {
  std::vector<SurfaceCase> all;
  const auto& surfaces = hard_surfaces();
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    for (double k : surfaces[s].meshes_at) all.push_back({s, k});
    for (double t : kTolerances) all.push_back({s, 0, t});
    for (double t : kTolerances) all.push_back({s, 0, t, true});
  }
  std::vector<SurfaceCase> out;
  for (const SurfaceCase& c : all)
    if (under_sanitizers(c) == sanitized) out.push_back(c);
  return out;
}

// The last run polygonize_adaptive makes in tolerance mode, every edge turning the normal by at
// most a radian from the start (stats `turn_limited`): the Barth ball at 7e-2, where every run
// before it fails, also with min_edge lowered (ctest label slow_under_sanitizers).
TEST(AdaptiveTurnLimit, TheBarthBallAtSevenHundredthsMeshesInTheTurnLimitedRun) {
  const auto field = test::field_from_json(
      R"json({"type": "expression",
              "value": "max(4*(2.618034*x^2-y^2)*(2.618034*y^2-z^2)*(2.618034*z^2-x^2)-4.236068*(x^2+y^2+z^2-1)^2+0.01, x^2+y^2+z^2-3.5)",
              "bounds": [[-2.1, -2.1, -2.1], [2.1, 2.1, 2.1]]})json");
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = 7e-2;
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  EXPECT_TRUE(r.stats.adaptive->recoveries.turn_limited);
  EXPECT_TRUE(r.stats.adaptive->recoveries.min_edge_lowered);
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.genus, 30);
  EXPECT_EQ(test::count_self_intersections(r.mesh), 0u);
}

INSTANTIATE_TEST_SUITE_P(Adaptive, HardSurfaces, testing::ValuesIn(surface_cases(true)), surface_case_name);
INSTANTIATE_TEST_SUITE_P(AdaptiveMore, HardSurfaces, testing::ValuesIn(surface_cases(false)), surface_case_name);

}  // namespace
}  // namespace cdp

namespace cdp {
namespace {

// The retry with a lower min_edge (polygonize_adaptive) is made only where the caller left
// min_edge to its default, and not in paper mode: a min_edge the caller set is a bound, and the
// paper's algorithm is kept as printed.
TEST(AdaptiveMinEdge, ACallersMinEdgeAndPaperModeAreNotLowered) {
  const auto field = test::field_from_json(
      expression("max(4*(2.618034*x^2-y^2)*(2.618034*y^2-z^2)*(2.618034*z^2-x^2)-4.236068*(x^2+y^2+z^2-1)^2+0.01, "
                 "x^2+y^2+z^2-3.5)",
                 2.1));
  AdaptiveOptions o;
  o.factor = 1;
  o.min_edge = 2e-3 * field->bounds().diagonal();  // the default, set by the caller
  for (const Variant variant : {Variant::Improved, Variant::Paper}) {
    o.variant = variant;
    std::string error;
    try {
      polygonize_adaptive(*field, o);
    } catch (const NoSurfaceError& e) {
      error = e.what();
    } catch (const LimitExceededError& e) {
      error = e.what();
    }
    EXPECT_FALSE(error.empty()) << to_string(variant);
    EXPECT_EQ(error.find("meshed again with min_edge"), std::string::npos) << error;
  }
}

TEST(AdaptiveResultCheck, AMeshThatIntersectsItselfIsAnErrorNotAResult) {
  // A shell 0.008 thick, thinner than min_edge (2e-3 of the box diagonal, 0.0104): outside
  // what the tracker promises, and at factor 1 its fronts cross from one side of the shell to
  // the other. The check turns that into an error naming the place; without it the wrong mesh
  // would come back (the option exists to save the check's time, at this risk). A field outside
  // the promise keeps this test independent of the tracker's open defects (two spheres 1e-3
  // apart served here until the tracker meshed them; a shell 0.004 thick, until the seeding
  // stopped taking the other sheet's triangles for its own and seeded there too, which the
  // area bound then stops first). min_edge set by the caller: with the default, the run made
  // again for thin sheets (max_edge twice the shell's thickness) meshes the shell.
  const auto f = test::field_from_json(expression("abs(sqrt(x^2+y^2+z^2)-1)-0.004", 1.5));
  AdaptiveOptions o;
  o.factor = 1;
  o.min_edge = 0.0104;
  try {
    polygonize_adaptive(*f, o);
    FAIL() << "expected an error";
  } catch (const NoSurfaceError& e) {
    EXPECT_NE(std::string(e.what()).find("intersecting itself"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("near ("), std::string::npos) << e.what();
  }
  o.check_self_intersections = false;
  const PolygonizeResult r = polygonize_adaptive(*f, o);
  EXPECT_GT(test::count_self_intersections(r.mesh), 0u);
}

}  // namespace
}  // namespace cdp

namespace cdp {
namespace {

// Not a test: writes each hard surface's field as NAME.json into $CDP_HARD_SURFACES_DIR, for
// sweeps beyond the suite's factors (build/bin/test_polygonizer
// --gtest_also_run_disabled_tests --gtest_filter='*WriteFields*').
TEST(HardSurfaceFields, DISABLED_WriteFields) {
  const char* dir = std::getenv("CDP_HARD_SURFACES_DIR");
  if (!dir) GTEST_SKIP() << "set CDP_HARD_SURFACES_DIR";
  for (const HardSurface& h : hard_surfaces()) std::ofstream(std::string(dir) + "/" + h.name + ".json") << h.json << "\n";
}

}  // namespace
}  // namespace cdp

namespace cdp {
namespace {

// A closed, manifold mesh without self-intersections with the surface's components and genus.
void expect_topology(const Mesh& mesh, std::size_t components, int genus) {
  const MeshTopology t = analyze_topology(mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, components);
  EXPECT_EQ(t.genus, genus);
  EXPECT_EQ(test::count_self_intersections(mesh), 0u);
}

// A tolerance far coarser than the curvature asks for chords longer than the radius: around the
// needle's tips (radii 5, 0.05, 0.05) eps = 1e-2 gives edges of 0.035 on a tube 0.04 thick, and
// the fronts crossed it (the mesh intersected itself in 1136 pairs); the careful run after that
// failure, which turns the normal by at most a radian per edge, meshed it. Since expansions whose
// new points fold across the tube are placed again closer (Tracker::folds_across), the first
// run meshes it. The careful run is still what meshes blobs29 of the topology sweep at factor 1
// (blobs35 was this case until the attempt made again with a late seed first meshed it).
TEST(AdaptiveCarefulRun, ACoarseToleranceOnTheNeedleAndABlobFieldAtFactorOneMesh) {
  const auto field = test::field_from_json(R"({"type": "ellipsoid", "radii": [5, 0.05, 0.05]})");
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = 1e-2;
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  expect_topology(r.mesh, 1u, 0);
  EXPECT_FALSE(r.stats.adaptive->recoveries.remeshed_carefully);  // true without folds_across

  // blobs29 of the topology sweep (49 Wyvill blobs; blobs14, six blobs, was this case until the
  // grading became gentler, growth 1.25 per edge instead of 1.5, and its first run meshed it).
  const auto blobs = load_field(std::string(CDP_SOURCE_DIR) + "/results/topology_sweep/fields/blobs29.json");
  AdaptiveOptions f1;
  f1.factor = 1;
  const PolygonizeResult b = polygonize_adaptive(*blobs, f1);
  expect_topology(b.mesh, 9, 2);  // marching cubes at cells 0.048 and 0.036 agree
  EXPECT_TRUE(b.stats.adaptive->recoveries.remeshed_carefully);
  EXPECT_EQ(b.stats.adaptive->recoveries.careful_max_turn, 1.0);  // the careful run's own turn
  // A surface that meshes the first time never gets the careful run.
  o.tolerance = 1e-3;
  EXPECT_FALSE(polygonize_adaptive(*field, o).stats.adaptive->recoveries.remeshed_carefully);
}

}  // namespace
}  // namespace cdp

namespace cdp {
namespace {

// The careful run must not trade an error for a wrong mesh: on random blob field 19 at a
// tolerance far coarser than its necks (3e-2), its fronts once capped a neck on both sides and
// returned 6 closed components where the surface has 5 (marching cubes of cell 0.01 and the
// suite's reference agree on 5). Such a split is now found (two components facing each other
// across the solid) and the first run's error stands; a mesh, if one comes back, must be right.
TEST(AdaptiveCarefulRun, NeverSplitsAComponentAcrossANeck) {
  const auto& hs = hard_surfaces();
  const auto it = std::find_if(hs.begin(), hs.end(), [](const HardSurface& h) { return h.name == "random_blobs_19"; });
  ASSERT_NE(it, hs.end());
  const auto field = test::field_from_json(it->json);
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = 3e-2;
  try {
    const PolygonizeResult r = polygonize_adaptive(*field, o);
    EXPECT_EQ(analyze_topology(r.mesh).components, 5u);
  } catch (const NoSurfaceError& e) {
    EXPECT_NE(std::string(e.what()).find("near ("), std::string::npos) << e.what();
  } catch (const LimitExceededError& e) {
    EXPECT_NE(std::string(e.what()).find("near ("), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cdp

namespace cdp {
namespace {

// A run whose mesh has two closed components where the surface has one must not exit as a
// success: a front with long edges closed on each side of a junction between blobs, and every
// other check passed. blobs19 of the topology sweep (results/topology_sweep.md) came out so at
// factors 1 and 2 (3 components for 2); the mesh, if one comes back, must be right.
void expect_right_or_error(const Field& field, const AdaptiveOptions& o, std::size_t components, int genus,
                           const std::string& what) {
  try {
    const PolygonizeResult r = polygonize_adaptive(field, o);
    const MeshTopology t = analyze_topology(r.mesh);
    EXPECT_EQ(t.components, components) << what;
    EXPECT_EQ(t.genus, genus) << what;
  } catch (const NoSurfaceError& e) {
    EXPECT_NE(std::string(e.what()).find("near ("), std::string::npos) << what << ": " << e.what();
  } catch (const LimitExceededError& e) {
    EXPECT_NE(std::string(e.what()).find("near ("), std::string::npos) << what << ": " << e.what();
  }
}

TEST(AdaptiveNeckCut, TwoComponentsWhereTheSurfaceHasOneAreAnError) {
  // The fifty blobs of the suite at --tolerance 3e-2 (5 components for 4) are caught too, but
  // their careful run takes 20 s before the first error stands: not for make test.
  // blobs19 of the topology sweep: 2 components of genus 0 (marching cubes of cells 0.048, 0.036).
  const auto blobs19 = test::field_from_json(R"({"type": "blobs", "kernel": "wyvill", "threshold": 0.3, "blobs": [
      {"center": [-0.905834052458907, -0.3328158467400866, -0.10597067439718155], "radius": 1.1972511687198573},
      {"center": [-0.9207519856149716, 0.6555683919267876, -0.7399658972898049], "radius": 0.760309954708132},
      {"center": [0.019883684892564535, 0.03156756081063383, 0.5579669274098573], "radius": 0.9790142967096789},
      {"center": [-0.6758583955359339, -1.2416249338771088, 1.3663498012815993], "radius": 0.7652129639486631},
      {"center": [0.061968904798991975, -1.378550995795773, 1.3866147297230769], "radius": 1.2324267747569155},
      {"center": [1.5300046651672403, 1.4888153179012402, -0.8485242397451618], "radius": 1.0091562927274156}]})");
  for (double k : {1.0, 2.0}) {
    AdaptiveOptions o;
    o.factor = k;
    expect_right_or_error(*blobs19, o, 2, 0, "blobs19 at factor " + std::to_string(k));
  }
}

// Components of very different scales: a torus tube of radius 0.003 beside a sphere of radius
// 1.2, at factor 1 with min_edge 1e-4. The repair's hash of triangles (and the neck check's)
// are sized by the median or mean edge, the tube's 0.003, and each of the sphere's triangles
// (edges up to 1.4) filled millions of cells: the run took 330 s. Boxes that wide now go to a
// coarser level of the hash, and a query over more cells than are occupied visits the occupied
// ones (spatial_hash.h): 0.43 s, the same mesh. BM_AdaptiveMixedScales tracks its time.
TEST(AdaptiveScales, ASphereBesideAThinTubeMeshesWithTheTubesHashCells) {
  const auto field = test::field_from_json(R"J({"type": "expression",
    "value": "min(sqrt((x-2.8)^2+y^2+z^2)-1.2, sqrt((sqrt(x^2+y^2)-1)^2+z^2)-0.003)",
    "bounds": [[-4, -4, -4], [4, 4, 4]]})J");
  AdaptiveOptions o;
  o.factor = 1;
  o.min_edge = 1e-4;
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  expect_topology(r.mesh, 2, 1);  // a sphere and a torus
  // At factor 3 the tube's edges are about 0.003 and the cells 0.5: thousands of vertices shared
  // a cell of the vertex hash, and each new point's test against the finished mesh looked at
  // them all, past the search bound (an error within 0.2 s). The hash splits such cells now.
  o.factor = 3;
  const PolygonizeResult r3 = polygonize_adaptive(*field, o);
  expect_topology(r3.mesh, 2, 1);
}

// A stuck front narrower than min_edge and lying on one sheet (a slit) is closed by ears
// (Tracker::is_slit). The Barth ball at factor 9 with min_edge 0.0021 (the run made again with a
// lower min_edge, meshing along the creases) stalled at an 11-point slit 0.21 long and 0.002 wide
// along a crease loop on the ball, and its smooth run after it stalled too, after two minutes;
// it meshes now in about 15 s: one component of genus 30, the slit among its forced closures.
TEST(AdaptiveSlits, TheBarthBallsSlitAtFactorNineIsClosed) {
  const auto field = test::field_from_json(R"J({"type": "expression",
    "value": "max(4*(2.618034*x^2-y^2)*(2.618034*y^2-z^2)*(2.618034*z^2-x^2)-4.236068*(x^2+y^2+z^2-1)^2+0.01, x^2+y^2+z^2-3.5)",
    "bounds": [[-2.1, -2.1, -2.1], [2.1, 2.1, 2.1]]})J");
  AdaptiveOptions o;
  o.factor = 9;
  o.min_edge = 0.0021;
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  EXPECT_TRUE(r.stats.adaptive->creases.followed);
  EXPECT_GT(r.stats.adaptive->tracker.forced_closures, 0u);
  expect_topology(r.mesh, 1, 30);
}

// Two overlapping spheres on a bar, meshed smooth across their creases (CreaseHandling::Ignore),
// with edges down to min_edge along every crease and long ones elsewhere: at factors 5 and 6
// fronts went wrong at a crease and crowded the neighbour searches past their bound (5,000 front
// points a step), which ended the run. Past the default bound the run is now made again with
// rollbacks, as after a stall, and that run meshes them. (With the creases followed, the default,
// they mesh at every factor: the next test.)
TEST(AdaptiveSearchBound, TwoSpheresOnABarMeshSmoothAcrossTheirCreases) {
  const auto field = test::field_from_json(expression(test::kSpheresOnABar, 1.7));
  for (const double factor : {5.0, 6.0}) {
    SCOPED_TRACE(factor);
    AdaptiveOptions o;
    o.factor = factor;
    o.creases = CreaseHandling::Ignore;
    const PolygonizeResult r = polygonize_adaptive(*field, o);
    EXPECT_TRUE(r.stats.adaptive->recoveries.remeshed_with_rollbacks);
    expect_topology(r.mesh, 1, 0);
  }
}

// The same along their creases. The crease tracing stopped short of the corners of the small
// face the spheres' seam leaves on the bar (crease_test.cpp), the layout failed, and the surface
// was meshed smooth: factors 5, 6, 8 and 9 failed. Now every factor follows the creases.
TEST(AdaptiveCreasePatches, TwoSpheresOnABarMeshAlongTheirCreasesAtEveryFactor) {
  const auto field = test::field_from_json(expression(test::kSpheresOnABar, 1.7));
  for (const double factor : {1.0, 5.0, 8.0, 9.0, 10.0}) {
    SCOPED_TRACE(factor);
    AdaptiveOptions o;
    o.factor = factor;
    const PolygonizeResult r = polygonize_adaptive(*field, o);
    EXPECT_TRUE(r.stats.adaptive->creases.followed);
    expect_topology(r.mesh, 1, 0);
  }
}

// Walls that face each other across the solid are not a cut when each is a surface of its own: a
// shell 0.05 thick (its walls' facing vertices within two edges at factors 1-3, the grid of the
// test cannot tell them apart, their triangles lie on the surface) meshes as two spheres.
// blobs33 of the topology sweep (53 Wyvill blobs; 7 components, total genus 1 by marching cubes
// of cells 0.048 and 0.036) at factor 1 lost its handle with exit 0: fronts on the two sides of
// a tunnel narrower than the edges joined across it with triangles whose corners' normals were
// up to 162 degrees apart. Expansions that fold so are placed again (Tracker::folds_across).
TEST(AdaptiveFolds, ATunnelNarrowerThanTheEdgesKeepsItsHandle) {
  const auto blobs33 = test::field_from_json(R"({"type": "blobs", "kernel": "wyvill", "threshold": 0.3, "blobs": [
    {"center": [1.3125525085236793, 1.4919900208790082, 1.6826469958982142], "radius": 0.8128388723222941},
    {"center": [0.221234908422963, 1.543352621410293, 0.4201353519878208], "radius": 0.6440372766964819},
    {"center": [-0.4124506535918502, -1.15062848624954, 0.16831974246122128], "radius": 0.7873310182019662},
    {"center": [-1.2749295117059707, -0.49943884012131834, -1.8344874610588242], "radius": 0.7753504913800673},
    {"center": [-1.434204344222492, 1.806281197440562, 0.6655738523705503], "radius": 0.9521750695938518},
    {"center": [-1.586521128673421, -0.8826651406614121, 0.6081338458127665], "radius": 0.7597407446800583},
    {"center": [1.3158865403779574, 0.7207985452089529, 0.5575440808580345], "radius": 0.8754457890440073},
    {"center": [-0.847233062821068, -0.7806135490335504, 1.272823319501363], "radius": 0.531500130629768},
    {"center": [-0.634689397632489, -1.5297576775247705, 1.229059415722705], "radius": 0.9357872412915859},
    {"center": [-0.3641458907895969, -1.8147693750248606, 0.6522444530817721], "radius": 0.8179486553124369},
    {"center": [0.8916674544489736, 1.93623683012181, -1.6195557099989655], "radius": 0.5366680299461006},
    {"center": [0.2765690043230338, -1.896450576942199, 0.6414951361939689], "radius": 0.6228527431374249},
    {"center": [0.24659243045083157, 0.4278335986748014, -0.6433558099542145], "radius": 0.7293984710303251},
    {"center": [1.300018821991125, -0.5328670298905589, 0.5956136555043874], "radius": 0.605220356507026},
    {"center": [-0.5961177285114094, 0.26288318616950157, -0.3456516204458535], "radius": 0.7118928886561612},
    {"center": [1.970302099931461, -1.1572228715868156, 1.4002043142023708], "radius": 0.9056368323441086},
    {"center": [-0.3024733031992697, -1.0284438854078655, -0.7929221285446468], "radius": 0.6084892542186078},
    {"center": [0.34375180491143187, -0.858956025741044, -1.0347399679146174], "radius": 0.5007507482216524},
    {"center": [-1.7615347614446, 1.8082815388481195, 1.6724131353880303], "radius": 0.781718543164223},
    {"center": [0.8544495478895686, -1.3062225079679703, -1.5918029644150495], "radius": 0.6299243742891603},
    {"center": [-1.641771720326966, -1.5369338015637442, -0.03651655747686666], "radius": 0.5738261903305057},
    {"center": [1.8182336481995538, 0.18894764333461378, -0.7086942077188483], "radius": 0.9636058111423991},
    {"center": [0.6707897835106604, -1.6331464581647595, 1.5147746279878884], "radius": 0.5950345806884865},
    {"center": [0.539657839081916, -1.3853225480981317, -0.2315560736724449], "radius": 0.6778781949978114},
    {"center": [-1.0754800230213308, 0.10283644021700278, 1.349569347393449], "radius": 0.5234915485514879},
    {"center": [-1.094282885566014, -0.5636058950584624, -0.9719364371770527], "radius": 0.5118657652749004},
    {"center": [-0.11594631270381939, -0.5927287523316829, -0.13301961998134182], "radius": 0.690759778805891},
    {"center": [-0.3942541654540821, -1.6259847658472464, 0.07897382505111317], "radius": 0.8786808833663567},
    {"center": [-0.967161718915142, 1.6017958955324811, -1.7263909951281744], "radius": 0.8606734223135326},
    {"center": [-0.8309402819942542, -1.3705794376597047, 0.029432306801217223], "radius": 0.8455524895493352},
    {"center": [-0.10002077974790824, -1.416803314675993, 1.1534647148940338], "radius": 0.964325633304293},
    {"center": [1.821136535169551, -1.544664386574973, 0.9731293616638488], "radius": 0.962009033763586},
    {"center": [0.6727808813319553, -0.9533291386810596, 1.7372324200214297], "radius": 0.5169290034538196},
    {"center": [-1.6469674749248062, 0.323937669766567, 1.908507126665162], "radius": 0.7963656807771409},
    {"center": [1.5248983740264959, 0.7088882930106144, -1.1138366863565947], "radius": 0.7099861827305585},
    {"center": [1.0980041577553141, -1.3085351979324296, 0.13550072593681328], "radius": 0.6773381570570468},
    {"center": [0.3131380918185398, -0.9032052399386394, -1.3516202512874749], "radius": 0.5389803682262438},
    {"center": [1.7312737232881146, 1.8588273213727247, -0.5204931780341928], "radius": 0.5467635570922392},
    {"center": [0.37187456726502166, 0.34429839046614363, 0.0007584187850033786], "radius": 0.9578258719638664},
    {"center": [-1.7469924469356166, -0.2238659715004614, 1.218884095467577], "radius": 0.7301751660018792},
    {"center": [-0.5832206363436363, -0.17790581456230914, -0.5600849062890396], "radius": 0.5016203470681717},
    {"center": [0.2668923742553484, 1.698896775484526, -1.288209173958058], "radius": 0.5429934926895923},
    {"center": [-1.5429672543372548, 1.1195583615214262, -1.7673149232379024], "radius": 0.9581195490856709},
    {"center": [-0.1438711599179432, 0.7806687400739034, -0.08753063933999572], "radius": 0.7275348760626092},
    {"center": [1.8269800232834572, -1.1483059445477575, -0.1226387106631388], "radius": 0.5381480276909745},
    {"center": [-1.1980388890648124, -1.2884007193927118, 1.2689144863326183], "radius": 0.7341022341752559},
    {"center": [0.8581771221992769, 1.8113285989542316, 0.7001896967654222], "radius": 0.7439633502151833},
    {"center": [1.1632276442353824, -1.2927751787594652, -1.9731222020139554], "radius": 0.6227536991644875},
    {"center": [0.06169594757308339, -1.3522249396361916, 0.1211579283162103], "radius": 0.8226439210898632},
    {"center": [1.3043513886149984, 0.6545447194563798, -1.6900643682819085], "radius": 0.6842808716834687},
    {"center": [-1.993167673023665, 1.9262613833225402, 1.0490122368845651], "radius": 0.7709558681162354},
    {"center": [0.3977955056010507, 1.9114610223194823, -1.2467422114198579], "radius": 0.5850363918826521},
    {"center": [0.539379481030231, 1.2421967641105662, 0.6537213417802734], "radius": 0.7076310284000479}
]})");
  AdaptiveOptions o;
  o.factor = 1;
  const PolygonizeResult r = polygonize_adaptive(*blobs33, o);
  expect_topology(r.mesh, 7u, 1);
}

// blobs30 of the topology sweep (50 Wyvill blobs; 8 components, total genus 3 by marching cubes
// of cells 0.048 and 0.036) at --tolerance 1e-2 lost a handle with exit 0: the fronts stepped
// over a neck of the solid 0.044 wide near (-0.50, 0.94, 0.86), where F has a saddle at -0.0016,
// with edges of about 0.1, and every other check passed. The saddle lies outside that mesh
// (missed_necks.h); the run made again with edges of at most the neck's radius around it meshes
// the neck. Without the test the run exits with genus 2.
TEST(AdaptiveNecks, ANeckTheFrontsSteppedOverIsMeshedAgain) {
  const auto blobs30 = test::field_from_json(R"({"type": "blobs", "kernel": "wyvill", "threshold": 0.3, "blobs": [
    {"center": [-1.0525410088055156, -1.8992516084455757, 1.251276516224285], "radius": 0.7875135638920554},
    {"center": [1.9632560477805523, 0.7785304842494001, -0.8176494462937889], "radius": 0.5207129543302309},
    {"center": [-1.9532447315289079, -1.4268760443605872, 0.1396791307837577], "radius": 0.8698157564488873},
    {"center": [-0.8346708630470419, -1.2634272073681259, 1.0800791942550312], "radius": 0.7174999562966089},
    {"center": [-0.5505614472441906, 1.1674613758390149, 0.45777887306641496], "radius": 0.5788299596495505},
    {"center": [0.002207044986859419, -0.2955590426226151, -1.09076747973623], "radius": 0.9158990891547161},
    {"center": [-0.8068656837453254, -0.3633967723816327, 1.3332959364511492], "radius": 0.660101880891909},
    {"center": [-0.29167734110578136, 0.8987345879858886, 1.8026084322650835], "radius": 0.5940372437475105},
    {"center": [1.085378555288079, 0.1474482237422654, 1.2099131801292589], "radius": 0.9765201674144791},
    {"center": [1.1322828015894837, -1.0970141624229468, -0.20132965688010263], "radius": 0.8136632794862373},
    {"center": [-1.064281925894814, 0.2658030439027792, -0.9075035601229087], "radius": 0.8380100725783122},
    {"center": [1.7493250547449049, -0.4897698291524972, -1.4162548615510606], "radius": 0.9584011228391183},
    {"center": [-0.3880368289740681, -1.8124115003209775, -1.9712786369270843], "radius": 0.644142859781339},
    {"center": [0.7155451255369596, -1.2003077014134584, 1.3234018910376082], "radius": 0.7239156705470896},
    {"center": [1.3538310480438387, 0.8280575228015223, -0.7814254580048239], "radius": 0.9251844995963505},
    {"center": [0.8323390690892096, 1.6023931523383723, 0.5835111182059194], "radius": 0.5469200641539325},
    {"center": [0.1253897957042236, 0.5720925273942457, -0.42836673751855425], "radius": 0.9157470842329191},
    {"center": [-1.1205101303699805, 1.988123686196006, 1.2039558429711947], "radius": 0.8749893782376661},
    {"center": [-1.7466617848741621, 1.3465766767242924, -1.4684698874462878], "radius": 0.7294142978587203},
    {"center": [-0.21322969416728466, -0.19909990576198577, 1.1426631598012542], "radius": 0.6824073024214596},
    {"center": [1.1465959374974006, -0.2453044807294078, 1.572977732309473], "radius": 0.9019064291416456},
    {"center": [-1.1602341200227442, -0.9847057033581574, 1.6720953076741285], "radius": 0.9305948452486563},
    {"center": [-0.8400283200079803, -0.9809402133336129, 1.904845041495939], "radius": 0.5369357827275101},
    {"center": [-0.17502649148065208, 1.1369662947752093, -0.3625661733173917], "radius": 0.8080821904633851},
    {"center": [0.8422829603604232, -1.7593018152688789, -0.7240702022073089], "radius": 0.6368987291732228},
    {"center": [-0.44877068546536414, 0.671638522323263, 1.3366896295667217], "radius": 0.7921775605505198},
    {"center": [-0.43065959773341556, -0.34731221594387574, -0.0053816078454684835], "radius": 0.9328892923159948},
    {"center": [0.6434937464008827, -1.2695476398525236, 0.05663506809093244], "radius": 0.9798651487401981},
    {"center": [1.2516831755005406, 1.663859001995776, -1.6749842489480322], "radius": 0.8359802489057369},
    {"center": [0.7291705476728807, 1.672654005276038, 1.7539761951166613], "radius": 0.5686525019392796},
    {"center": [-0.3706213285139812, -1.274346534722242, 0.8879702301943464], "radius": 0.8076356797217826},
    {"center": [-1.200952977527752, -0.746322453399614, -0.5280909569423988], "radius": 0.6269983958849163},
    {"center": [-1.48272571340146, 0.7460207571034005, 1.031431801274302], "radius": 0.919449996916335},
    {"center": [0.053191254244281616, -1.8668771809015596, 0.9225603372687639], "radius": 0.9789385318820594},
    {"center": [0.8166215298757238, -0.07545859940681154, -0.8350062817074093], "radius": 0.7112659114244776},
    {"center": [-1.1161493224845338, -0.2658862057862539, -1.5200081081344297], "radius": 0.8942280891631467},
    {"center": [1.1505948575297587, -1.511662114914747, -1.79140209890393], "radius": 0.6192830252415712},
    {"center": [-0.27353740445606967, -0.7998329519615304, 1.4769355314267876], "radius": 0.9564946492845954},
    {"center": [0.8665840576156416, -0.3551802485034825, -1.3712604970868063], "radius": 0.8466410054080442},
    {"center": [-1.1102950880749334, -0.6115435768721662, -0.6640270897449265], "radius": 0.5258030269443148},
    {"center": [0.8775866277481135, -1.7228175080566293, -1.8113893731990154], "radius": 0.5746151820929217},
    {"center": [-1.6329272596267965, 1.210467398087217, 1.998084830343858], "radius": 0.6583919070569704},
    {"center": [-0.7051145809584476, -1.625035208038645, 1.879642128027264], "radius": 0.9549484964272765},
    {"center": [0.1904228798181813, -1.7135353435905532, 0.7452992326455505], "radius": 0.5289892118836999},
    {"center": [0.9282151581120499, -0.3401791717549494, -1.8162500249631854], "radius": 0.7994085030753112},
    {"center": [0.9924805273313275, -1.9131735495456965, 1.2731989805517725], "radius": 0.9816294125208602},
    {"center": [-1.470756882381815, 0.29100823865365477, 0.9353408697378849], "radius": 0.9921195412284426},
    {"center": [-1.1495094174510028, 1.8189460257741432, -1.5546794591741655], "radius": 0.5618459825924396},
    {"center": [-0.8706820897549412, 0.1427272376077462, -0.8593817802427841], "radius": 0.9453986077266358},
    {"center": [-0.8841456272836901, -1.4498535756756872, -1.1367836815929744], "radius": 0.6697786653791943}
]})");
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = 1e-2;
  o.blocks = false;  // the tracker alone steps over this neck (blocks mesh it at the first attempt)
  const PolygonizeResult r = polygonize_adaptive(*blobs30, o);
  expect_topology(r.mesh, 8u, 3);
  EXPECT_EQ(r.stats.adaptive->necks.reruns, 1u);
  EXPECT_FALSE(r.stats.adaptive->recoveries.remeshed_carefully);
  // The second run's own mesh was tested too, and passed.
  EXPECT_GT(r.stats.adaptive->necks.tested, 0u);
}

// The tanglecube has saddles of F near its six tunnels and at its centre: the search finds them,
// each lies on its own side of the correct mesh, and no run is made again. (A side test with the
// wrong answer would send every run with a critical point to the careful run.)
TEST(AdaptiveNecks, TheSaddlesOfACorrectMeshLieOnTheirOwnSide) {
  const auto f = test::field_from_json(expression(test::kTanglecube, 3));
  for (double k : {1.0, 2.0, 3.0}) {
    AdaptiveOptions o;
    o.factor = k;
    // Tracking alone: blocks at factor 3 start the search from other vertices, and test 5 of the
    // 20 critical points (the others lie more than kThinWaist edges from their surface).
    o.blocks = false;
    const PolygonizeResult r = polygonize_adaptive(*f, o);
    expect_topology(r.mesh, 1u, 5);
    EXPECT_GE(r.stats.adaptive->necks.tested, 10u) << "factor " << k;
    EXPECT_FALSE(r.stats.adaptive->recoveries.remeshed_carefully) << "factor " << k;
  }
}

TEST(AdaptiveNeckCut, AShellIsNotACut) {
  const auto f = test::field_from_json(expression("abs(sqrt(x^2+y^2+z^2)-1)-0.025", 1.5));
  for (double k : {1.0, 2.0, 3.0}) {
    AdaptiveOptions o;
    o.factor = k;
    const PolygonizeResult r = polygonize_adaptive(*f, o);
    EXPECT_EQ(analyze_topology(r.mesh).components, 2u) << "factor " << k;
    EXPECT_FALSE(r.stats.adaptive->recoveries.remeshed_carefully) << "factor " << k;
  }
}

}  // namespace
}  // namespace cdp

namespace cdp {
namespace {

// A careful run that fails too is made again with edges that turn the normal by half, then a
// quarter of a radian (kFinerTurns in run.cpp). blobs27 of the topology sweep at factor 1
// meshes at half a radian; the references are marching cubes at cells 0.048 and 0.036, which
// agree (results/topology_sweep/summary.csv). blobs18 at tolerance 5e-2 (half a radian) and
// blobs19 at tolerance 1e-2 (a quarter) were this test's fields until the attempt made again
// with a component seeded late first meshed them, with no careful run: their first meshes had
// closed over a neck, and the blob beyond it, seeded after, ran into them. No run of the sweep
// needs the quarter radian since.
TEST(AdaptiveFinerRun, WhatTheCarefulRunCannotMeshIsMeshedWithShorterEdgesWhereItBends) {
  const std::string dir = std::string(CDP_SOURCE_DIR) + "/results/topology_sweep/fields/";
  const auto b27 = load_field(dir + "blobs27.json");
  AdaptiveOptions f1;
  f1.factor = 1;
  const PolygonizeResult r27 = polygonize_adaptive(*b27, f1);
  expect_topology(r27.mesh, 7, 2);
  EXPECT_TRUE(r27.stats.adaptive->recoveries.remeshed_carefully);
  EXPECT_EQ(r27.stats.adaptive->recoveries.careful_max_turn, 0.5);

  const auto b19 = load_field(dir + "blobs19.json");
  AdaptiveOptions f2;
  f2.sizing = SizingMode::Tolerance;
  f2.tolerance = 1e-2;
  const PolygonizeResult r19 = polygonize_adaptive(*b19, f2);
  expect_topology(r19.mesh, 2, 0);
  EXPECT_EQ(r19.stats.adaptive->recoveries.careful_max_turn, 0.0);
  EXPECT_GE(r19.stats.adaptive->seeding.seeds_first, 1u);

  // A run that meshes the first time has no careful turn.
  AdaptiveOptions f3;
  f3.factor = 3;
  const PolygonizeResult plain = polygonize_adaptive(*b19, f3);
  EXPECT_FALSE(plain.stats.adaptive->recoveries.remeshed_carefully);
  EXPECT_EQ(plain.stats.adaptive->recoveries.careful_max_turn, 0.0);
}

}  // namespace
}  // namespace cdp
