// Issue 18: no slivers and a tolerance that holds, with the paper's algorithm kept as a mode.
//  - smooth surfaces: every triangle's smallest angle at least 20 degrees, at several factors;
//  - creased surfaces (CSG, shells): none under 5 degrees;
//  - the bunny VIS-800 at factor 3: the worst triangle (it was 2.2 degrees before the repair);
//  - with a tolerance: the largest distance from the mesh to the surface, sampled densely over
//    every triangle, at most the tolerance;
//  - Variant::Paper: the printed algorithm, every addition off.
// Every mesh is also checked closed, manifold, oriented and free of self-intersections.
#include <gtest/gtest.h>

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/mesh_angles.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/core/newton_projection.h>
#include <cdp/io/field_factory.h>

#include <array>
#include <cmath>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "common/test_fields.h"
#include "polygonizer/mesh_checks.h"

namespace cdp {
namespace {

using test::expression;

std::string blob_field_json(unsigned seed, int count) {
  // As the hard-surface suite's random_blobs_N (adaptive/hard_surfaces_test.cpp).
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> c(-1.6, 1.6), r(0.7, 1.3);
  std::ostringstream s;
  s << R"({"type": "blobs", "kernel": "wyvill", "threshold": 0.3, "blobs": [)";
  for (int i = 0; i < count; ++i) {
    const double x = c(rng), y = c(rng), z = c(rng);
    if (i) s << ", ";
    s << R"({"center": [)" << x << ", " << y << ", " << z << R"(], "radius": )" << r(rng) << "}";
  }
  s << "]}";
  return s.str();
}

struct Surface {
  std::string name, json;
  // Factors of the test: 1, 2, 3 and 5 (the sphere and the torus also 10, a finer mesh of a
  // cheap field).
  std::vector<double> factors;
};

const std::vector<Surface>& smooth_surfaces() {
  static const std::vector<Surface> v = {
      {"sphere", R"({"type": "sphere", "radius": 1})", {1, 2, 3, 5, 10}},
      {"torus", R"({"type": "torus", "major_radius": 1, "minor_radius": 0.35})", {1, 2, 3, 5, 10}},
      {"tanglecube", expression(test::kTanglecube, 3), {1, 2, 3, 5}},
      {"chmutov4", expression("(8*x^4-8*x^2+1)+(8*y^4-8*y^2+1)+(8*z^4-8*z^2+1)", 1.3), {1, 2, 3, 5}},
      {"blobs_103", blob_field_json(103, 5), {1, 2, 3, 5}},
      {"blobs_111", blob_field_json(111, 3), {1, 2, 3, 5}},
  };
  return v;
}

using test::expect_sound;

// The repair and the relaxation move vertices: each must still lie on the surface (first-order
// distance within Newton's tolerance, 1e-10 of the diagonal, with room for rounding) and carry
// the field's normal there.
void expect_on_surface(const Field& field, const Mesh& mesh, const std::string& what) {
  const double diagonal = field.bounds().diagonal();
  std::size_t off = 0, turned = 0;
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    Vec3 g;
    const double f = field.value_gradient(mesh.positions[v], g);
    if (!(std::abs(f) <= 1e-8 * diagonal * g.norm())) ++off;
    if (!(g.normalized().dot(mesh.normals[v]) > 1 - 1e-9)) ++turned;
  }
  EXPECT_EQ(off, 0u) << what << ": vertices off the surface";
  EXPECT_EQ(turned, 0u) << what << ": normals that are not the field's";
}

struct SmoothCase {
  std::size_t surface;
  double factor;
};

// The issue's bound on smooth surfaces: no angle under 20 degrees, at most 1% of triangles with
// one under 30. Prints the figures (the table the note quotes).
// The issue's bound on the mean over triangles of longest / shortest edge.
constexpr double kMeanEdgeRatio = 1.25;

AngleStatistics expect_smooth_angles(const Mesh& mesh, const std::string& what) {
  const AngleStatistics a = angle_statistics(mesh);
  std::cout << "angles " << what << ": " << mesh.num_triangles() << " triangles, min " << a.min_degrees
            << ", under 10/20/30: " << a.share_under_10 << " " << a.share_under_20 << " " << a.share_under_30
            << ", mean edge ratio " << a.mean_edge_ratio << "\n";
  EXPECT_GE(a.min_degrees, 20.0) << what;
  EXPECT_LE(a.share_under_30, 0.01) << what;
  return a;
}

class SmoothAngles : public testing::TestWithParam<SmoothCase> {};

TEST_P(SmoothAngles, EveryTriangleAtLeast20Degrees) {
  const Surface& s = smooth_surfaces()[GetParam().surface];
  const auto field = test::field_from_json(s.json);
  AdaptiveOptions o;
  o.factor = GetParam().factor;
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  const std::string what = s.name + " factor " + std::to_string(GetParam().factor);
  expect_sound(r.mesh, what);
  expect_on_surface(*field, r.mesh, what);
  const AngleStatistics a = expect_smooth_angles(r.mesh, what);
  EXPECT_EQ(a.degenerate, 0u) << what;
  // The relaxation's mean edge ratio (repair_relax.cpp, relax), at every factor: factors 1 and 2
  // were above on the graded surfaces (blobs_103 at factor 1: 1.28, chmutov4 at 2: 1.2501)
  // before its flips towards valence 6.
  EXPECT_LE(a.mean_edge_ratio, kMeanEdgeRatio) << what;
}

std::vector<SmoothCase> smooth_cases() {
  std::vector<SmoothCase> v;
  for (std::size_t s = 0; s < smooth_surfaces().size(); ++s)
    for (double k : smooth_surfaces()[s].factors) v.push_back({s, k});
  return v;
}

std::string smooth_name(const testing::TestParamInfo<SmoothCase>& info) {
  return smooth_surfaces()[info.param.surface].name + "_factor" + std::to_string(static_cast<int>(info.param.factor));
}

INSTANTIATE_TEST_SUITE_P(Adaptive, SmoothAngles, testing::ValuesIn(smooth_cases()), smooth_name);

TEST(AdaptiveAngles, CreasedSurfacesNoAngleUnder5Degrees) {
  // CSG creases: the repair leaves crease vertices where they are (the issue asks 5 degrees
  // there); the cases are those of the hard-surface suite that mesh.
  const std::vector<std::pair<std::string, std::string>> creased = {
      {"hollow_sphere", expression("max(sqrt(x^2+y^2+z^2)-1.25, 0.75-sqrt(x^2+y^2+z^2))", 2)},
      {"shell", expression("abs(sqrt(x^2+y^2+z^2)-1)-0.1", 1.5)},
      {"off_centre_cavity", expression("max(sqrt(x^2+y^2+z^2)-1.25, 0.5-sqrt((x-0.4)^2+y^2+z^2))", 2)},
  };
  for (const auto& [name, json] : creased)
    for (double k : {1.0, 3.0}) {
      const auto field = test::field_from_json(json);
      AdaptiveOptions o;
      o.factor = k;
      const PolygonizeResult r = polygonize_adaptive(*field, o);
      const std::string what = name + " factor " + std::to_string(k);
      expect_sound(r.mesh, what);
      const AngleStatistics a = angle_statistics(r.mesh);
      std::cout << "angles " << what << ": min " << a.min_degrees << ", under 20: " << a.share_under_20 << "\n";
      EXPECT_GE(a.min_degrees, 5.0) << what;
    }
}

// The triangles of `mesh` none of whose corners is within `reach` times the triangle's longest
// edge of a crease (Field::pieces finds the pieces within a radius: more than one there is a
// crease within it): "away from the creases", where issue 18 asks a creased surface for the
// smooth surfaces' bounds.
Mesh away_from_creases(const Field& field, const Mesh& mesh, double reach) {
  Mesh away;
  away.positions = mesh.positions;
  for (const auto& t : mesh.triangles) {
    double longest = 0;
    for (int k = 0; k < 3; ++k) longest = std::max(longest, (mesh.positions[t[k]] - mesh.positions[t[(k + 1) % 3]]).norm());
    bool near = false;
    for (int k = 0; k < 3 && !near; ++k) near = field.pieces(mesh.positions[t[k]], reach * longest).size() > 1;
    if (!near) away.triangles.push_back(t);
  }
  return away;
}

// Meshed along their creases: away from them (no corner within one longest edge of a crease)
// the smooth surfaces' bounds, no triangle under 20 degrees, at most 1% under 30 and a mean edge
// ratio of at most 1.25 (the cube, the shell and the box less a ball at these sizes have no
// triangle that far from a crease), at factor 3 and at tolerance 1e-2. The ratio was over 1.25
// on the two spheres at 1e-3 (1.260) and the box less a ball at 1e-3 (1.285) until the
// refinement measured triangles near the bound before splitting them (kDenseClearShare): 1.130
// and 1.199 now.
void expect_smooth_away_from_creases(const std::string& name, const std::string& json) {
  for (int run = 0; run < 2; ++run) {
    const auto field = test::field_from_json(json);
    AdaptiveOptions o;
    if (run == 0) {
      o.factor = 3;
    } else {
      o.sizing = SizingMode::Tolerance;
      o.tolerance = 1e-2;
    }
    const PolygonizeResult r = polygonize_adaptive(*field, o);
    const std::string what = name + (run == 0 ? " factor 3" : " eps 1e-2");
    expect_sound(r.mesh, what);
    EXPECT_TRUE(r.stats.adaptive->creases.followed) << what;
    const Mesh away = away_from_creases(*field, r.mesh, 1);
    EXPECT_GT(away.num_triangles(), 0u) << what;
    const AngleStatistics a = angle_statistics(away);
    std::cout << "angles away from the creases, " << what << ": " << a.triangles << " of "
              << r.mesh.num_triangles() << " triangles, min " << a.min_degrees << ", under 30 " << a.share_under_30
              << ", mean edge ratio " << a.mean_edge_ratio << "\n";
    EXPECT_GE(a.min_degrees, 20.0) << what;
    EXPECT_LE(a.share_under_30, 0.01) << what;
    EXPECT_LE(a.mean_edge_ratio, kMeanEdgeRatio) << what;
  }
}

TEST(AdaptiveAngles, CreasedSurfacesAwayFromTheCreases) {
  expect_smooth_away_from_creases("capped_cylinder", expression("max(sqrt(x^2+y^2)-1,abs(z)-1)", 1.5));
  expect_smooth_away_from_creases("two_spheres",
                                  expression("min(sqrt((x-0.5)^2+y^2+z^2)-1, sqrt((x+0.5)^2+y^2+z^2)-1)", 2));
}

// Label slow_under_sanitizers (tests/CMakeLists.txt): several times slower there.
TEST(AdaptiveAngles, GyroidBallAwayFromItsCreases) {
  expect_smooth_away_from_creases(
      "gyroid_ball", expression("max(sin(4*x)*cos(4*y)+sin(4*y)*cos(4*z)+sin(4*z)*cos(4*x), x^2+y^2+z^2-4)", 2.2));
}

TEST(AdaptiveAngles, BunnyVis800WorstTriangle) {
  // The issue's case is factor 3: 2.2 degrees before, from fronts of 4-5 mm edges meeting
  // fronts of 0.5-0.9 mm edges. Factor 1 has triangles folded against the surface normals on
  // the sharply curved spots (8.1 degrees until the repair accepted replacing them by
  // triangles that face the surface no worse).
  const auto field = load_field(std::string(CDP_SOURCE_DIR) + "/experiments/fields/bunny_vis800.json");
  AdaptiveOptions o;
  for (double k : {1.0, 3.0, 5.0}) {
    o.factor = k;
    const PolygonizeResult r = polygonize_adaptive(*field, o);
    const std::string what = "bunny vis800 factor " + std::to_string(k);
    expect_sound(r.mesh, what);
    const AngleStatistics a = expect_smooth_angles(r.mesh, what);
    // 1.30 at factor 3 before the relaxation; factor 1 was at 1.273 with its moves alone, 1.246
    // with its flips.
    EXPECT_LE(a.mean_edge_ratio, kMeanEdgeRatio) << what;
  }
  // The paper's method alone, for contrast: the slivers the repair removes are there.
  o.factor = 3;
  o.variant = Variant::Paper;
  const PolygonizeResult p = polygonize_adaptive(*field, o);
  EXPECT_LT(angle_statistics(p.mesh).min_degrees, 10.0);
}

TEST(AdaptiveAngles, HorseMpuSubResolutionRidge) {
  // The horse MPU model has a ridge of radius 1e-4 near (-0.012, 0.081, 0.073), below the
  // sizing's resolution (min_edge 5.9e-4): the ends of an edge across it have normals 100-150
  // degrees apart. The repair refused every collapse there (a collapsed midpoint's normal had to
  // be within 30 degrees of both ends' normals, impossible across the ridge) and left 17.1
  // degrees; a landing on the arc between the two normals is now accepted, and the merged
  // corner may face either flank. Factors 1 and 2 were at 16.1 and 14.0 degrees there (factor
  // 10, 13.1 before, 21.7 now, takes 10 s and is left to the measurements).
  const auto field = load_field(std::string(CDP_SOURCE_DIR) + "/experiments/fields/horse_mpu.json");
  AdaptiveOptions o;
  for (double k : {1.0, 2.0, 3.0}) {
    o.factor = k;
    const PolygonizeResult r = polygonize_adaptive(*field, o);
    const std::string what = "horse mpu factor " + std::to_string(k);
    expect_sound(r.mesh, what);
    expect_smooth_angles(r.mesh, what);
  }
}

// The largest distance from the mesh to the surface over a barycentric grid of 28 points per
// triangle (corners, 5 more per side, interior). Each point's distance is that to the nearest
// of a few surface points: where Newton's path lands, then moved toward the foot of the point
// (a step along the tangent plane to the point's projection on it, back onto the surface),
// kFootSteps times. Each is on the surface, so the distance is at least the true one; the steps
// take off what Newton's path, which follows the gradient and not the shortest way, adds where
// the surface curves (a fillet of a blob field: 1.014 eps by the path, 0.94 eps by a search for
// a sign change on spheres around the point).
double densely_sampled_distance(const Field& field, const Mesh& mesh, const std::array<int, 3>& t) {
  constexpr int kGrid = 6;
  constexpr int kFootSteps = 8;
  ProjectionOptions po;
  po.tolerance = 1e-10 * field.bounds().diagonal();
  double worst = 0;
  for (int i = 0; i <= kGrid; ++i)
    for (int j = 0; i + j <= kGrid; ++j) {
      const double a = double(i) / kGrid, b = double(j) / kGrid;
      const Vec3 p = a * mesh.positions[t[0]] + b * mesh.positions[t[1]] + (1 - a - b) * mesh.positions[t[2]];
      ProjectionResult r = project_to_surface(field, p, po);
      EXPECT_TRUE(r.ok());
      double nearest = (r.point - p).norm();
      for (int k = 0; k < kFootSteps && r.ok() && r.gradient.squaredNorm() > 0; ++k) {
        const Vec3 n = r.gradient.normalized();
        const Vec3 to = p - r.point;
        r = project_to_surface(field, r.point + (to - n * n.dot(to)), po);
        if (r.ok()) nearest = std::min(nearest, (r.point - p).norm());
      }
      worst = std::max(worst, nearest);
    }
  return worst;
}
double densely_sampled_distance(const Field& field, const Mesh& mesh) {
  double worst = 0;
  for (const auto& t : mesh.triangles) worst = std::max(worst, densely_sampled_distance(field, mesh, t));
  return worst;
}

TEST(AdaptiveTolerance, ReportsTheTrianglesFartherThanEpsMeasuredDensely) {
  // The unit sphere at eps 4e-4 with edges of at least 0.05 (whose triangles lie about 4.2e-4
  // from the surface): the refinement cannot split, and its estimate (which keeps a 10% margin
  // for its own error) leaves 8377 triangles it cannot clear. Measured densely, 3763 are
  // farther than eps: those, and only those, are reported (before, all 8377 were; a bunny
  // VIS-800 at 1.0337e-3 had 3 such triangles, all within eps, and polygonize warned "3
  // triangles lie farther than 0.00103 (up to 0.000999)"). The count is checked here against
  // the test's own dense measurement of every triangle.
  const auto field = test::field_from_json(R"({"type": "sphere", "radius": 1})");
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = 4e-4;
  o.min_edge = 0.05;
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  expect_sound(r.mesh, "sphere eps 4e-4, min_edge 0.05");
  std::size_t beyond = 0;
  double worst = 0;
  for (const auto& t : r.mesh.triangles) {
    const double d = densely_sampled_distance(*field, r.mesh, t);
    if (d > o.tolerance) ++beyond;
    worst = std::max(worst, d);
  }
  const std::size_t measured = r.stats.adaptive->quality.measured_densely;
  const std::size_t over = r.stats.adaptive->quality.over_tolerance;
  std::cout << "sphere eps 4e-4: " << r.mesh.num_triangles() << " triangles, " << measured << " measured, " << over
            << " over, " << beyond << " beyond by the test, worst " << worst << "\n";
  EXPECT_GT(beyond, 0u);
  EXPECT_EQ(over, beyond);
  EXPECT_GT(measured, over);
  // The same distance by two computations (the polygonizer's Newton path, the test's nearest of
  // the path's end and its foot steps; on a sphere both are radial): equal within the accuracy
  // both projections are asked for, not bit for bit (they differed by 48 ulps on one mesh).
  EXPECT_NEAR(r.stats.adaptive->quality.over_tolerance_worst, worst,
              1e-10 * field->bounds().diagonal());
}

TEST(AdaptiveTolerance, TrianglesNearTheBoundAreMeasuredBeforeTheyAreSplit) {
  // A sphere capped by a plane, meshed along its crease: the patch's fronts lay rings of nearly
  // equilateral triangles a little over the target length, which estimate just over 0.9 eps
  // (the estimate's margin) though they lie within eps. Split, they left a band of triangles of
  // edge ratio 1.6 (3560 triangles, 486 splits, mean ratio 1.247); measured densely first and
  // kept where within 0.95 eps (kDenseClearShare), 2730, 69 and 1.132. The distance still holds,
  // by the test's own dense sampling.
  const auto field = test::field_from_json(expression("max(sqrt(x^2+y^2+z^2)-1, x-0.5)", 2));
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = 2e-3;
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  const std::string what = "capped sphere eps 2e-3";
  expect_sound(r.mesh, what);
  EXPECT_TRUE(r.stats.adaptive->creases.followed);
  const AdaptiveReport& x = *r.stats.adaptive;
  EXPECT_GT(x.quality.refine_cleared, 0u);
  EXPECT_LE(x.quality.refine_cleared, x.quality.refine_measured);
  EXPECT_EQ(x.quality.over_tolerance, 0u);
  const AngleStatistics a = angle_statistics(r.mesh);
  std::cout << what << ": " << r.mesh.num_triangles() << " triangles, " << x.quality.splits
            << " splits, mean edge ratio " << a.mean_edge_ratio << ", min angle " << a.min_degrees << "\n";
  EXPECT_LE(a.mean_edge_ratio, 1.2);
  EXPECT_GE(a.min_degrees, 20.0);
  EXPECT_LE(densely_sampled_distance(*field, r.mesh), o.tolerance);
}

struct ToleranceCase {
  std::string name, json;
  double eps;
  // Meshed as a field that asks for predicted estimates (Field::predicts_from_hessians, as a VIS
  // model does), so that the repair predicts its estimates' midpoints (repair_context.h).
  bool predicted = false;
};

class ToleranceBound : public testing::TestWithParam<ToleranceCase> {};

TEST_P(ToleranceBound, LargestDistanceAtMostEps) {
  const std::unique_ptr<Field> plain = test::field_from_json(GetParam().json);
  // Asking for predictions, and claiming smoothness: the four surfaces are (the tanglecube and
  // Chmutov's quartic are polynomials, whose expressions do not say so).
  std::optional<test::Rewrapped> asking;
  if (GetParam().predicted) asking.emplace(*plain, true, plain->thread_safe(), true);
  const Field* field = asking ? &*asking : plain.get();
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = GetParam().eps;
  // The default min_edge (2e-3 of the diagonal) would cap how short edges may get; a bound
  // asked for must not be given up for it.
  o.min_edge = 1e-6 * field->bounds().diagonal();
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  const std::string what = GetParam().name + " eps " + std::to_string(GetParam().eps);
  expect_sound(r.mesh, what);
  const double d = densely_sampled_distance(*field, r.mesh);
  const AngleStatistics a = angle_statistics(r.mesh);
  std::cout << "tolerance " << what << ": " << r.mesh.num_triangles() << " triangles, largest distance " << d
            << " (" << d / GetParam().eps << " eps), min angle " << a.min_degrees << ", mean edge ratio "
            << a.mean_edge_ratio << "\n";
  EXPECT_LE(d, GetParam().eps) << what;
  EXPECT_GE(a.min_degrees, 20.0) << what;
  // The tolerance's edge splits leave vertices of valence 4 and 8; the relaxation's flips
  // bring the ratio back under the bound (random blobs at 1e-3: 1.34 with its moves alone).
  EXPECT_LE(a.mean_edge_ratio, kMeanEdgeRatio) << what;
  EXPECT_EQ(r.stats.adaptive->quality.over_tolerance, 0u);
  // The predictions take the place of most value-and-gradient evaluations at the midpoints: one
  // Hessian a vertex more, 3 to 5 value-and-gradient evaluations a vertex fewer.
  if (GetParam().predicted) {
    EXPECT_GT(r.stats.field_evaluations.gradient_hessian, 1.5 * r.stats.vertices) << what;
  } else {
    EXPECT_LT(r.stats.adaptive->phase("quality").evaluations.gradient_hessian, 0.01 * r.stats.vertices) << what;
  }
}

// The two coarser tolerances of each surface (`finest` false), or the finest (true): those are
// several times slower under the sanitizers (the torus at 1e-4 alone took 38 s there) and
// carry the label slow_under_sanitizers (tests/CMakeLists.txt), the same code paths.
std::vector<ToleranceCase> tolerance_cases(bool finest) {
  const std::string sphere = R"({"type": "sphere", "radius": 1})";
  const std::string torus = R"({"type": "torus", "major_radius": 1, "minor_radius": 0.35})";
  const std::string tangle = expression(test::kTanglecube, 3);
  const std::string chmutov = expression("(8*x^4-8*x^2+1)+(8*y^4-8*y^2+1)+(8*z^4-8*z^2+1)", 1.3);
  const std::vector<ToleranceCase> cases{
      {"sphere", sphere, 1e-2},     {"sphere", sphere, 1e-3},     {"sphere", sphere, 1e-4},
      {"torus", torus, 1e-2},       {"torus", torus, 1e-3},       {"torus", torus, 1e-4},
      {"tanglecube", tangle, 1e-2}, {"tanglecube", tangle, 3e-3}, {"tanglecube", tangle, 1e-3},
      {"chmutov4", chmutov, 1e-2},  {"chmutov4", chmutov, 3e-3},  {"chmutov4", chmutov, 1e-3}};
  std::vector<ToleranceCase> chosen;
  for (std::size_t i = 0; i < cases.size(); ++i)
    if ((i % 3 == 2) == finest) chosen.push_back(cases[i]);
  // And the coarsest of each with predicted estimates (the others too would add the sanitizers'
  // slowest cases for the same code paths).
  if (!finest)
    for (std::size_t i = 0; i < cases.size(); i += 3) {
      chosen.push_back(cases[i]);
      chosen.back().name += "_predicted";
      chosen.back().predicted = true;
    }
  return chosen;
}

std::string tolerance_name(const testing::TestParamInfo<ToleranceCase>& info) {
  std::ostringstream s;
  s << info.param.name << "_eps" << static_cast<int>(std::round(-std::log10(info.param.eps) * 10));
  return s.str();
}

INSTANTIATE_TEST_SUITE_P(Adaptive, ToleranceBound, testing::ValuesIn(tolerance_cases(false)), tolerance_name);
INSTANTIATE_TEST_SUITE_P(AdaptiveFinest, ToleranceBound, testing::ValuesIn(tolerance_cases(true)), tolerance_name);

TEST(AdaptiveTolerance, ACreaseMeshedAcrossIsNotSplitWithoutEnd) {
  // A crease the sizing does not see (the cube with its creases ignored) cannot meet a
  // tolerance of 5e-4: the refinement's splits across it fold, and splitting a triangle's other
  // edges there never resolves it. With those splits unbounded this run took 137 s and made
  // 8,510 triangles (the creases_cube experiment's smooth run, its box offset, 162 s, 11,780
  // triangles, slivers of 0.06 degrees); about 600 with them kept to triangles near the bound,
  // the triangles left beyond the tolerance reported.
  const auto field = test::field_from_json(expression("max(abs(x),max(abs(y),abs(z)))-1", 1.5));
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = 5e-4;
  o.creases = CreaseHandling::Ignore;
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  expect_sound(r.mesh, "cube across its creases eps 5e-4");
  EXPECT_LT(r.mesh.num_triangles(), 1500u);
  EXPECT_GT(r.stats.adaptive->quality.over_tolerance, 0u);
}

// The bunny VIS-2000 at 1e-3 of ten times its longest factor-1 edge, with the default min_edge:
// four triangles near (-0.046, 0.035, -0.015) span a ridge whose normals are 110 degrees apart
// across an 8 mm edge, up to 1.45 eps from the surface. Splitting the longest edge there folds;
// the refinement gave up on them and polygonize warned. It now tries the other edges, and the
// bound holds, measured densely by the test: on the triangles within `around` of the ridge, or
// on every triangle when `around` is 0.
void expect_narrow_ridge_within_eps(double around) {
  const auto field = load_field(std::string(CDP_SOURCE_DIR) + "/experiments/fields/bunny_vis2000.json");
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = 0.0010351162319589128;
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  expect_sound(r.mesh, "bunny vis2000 eps 1.035e-3");
  EXPECT_EQ(r.stats.adaptive->quality.over_tolerance, 0u);
  const Vec3 ridge(-0.046, 0.035, -0.015);
  double worst = 0;
  std::size_t measured = 0;
  for (const auto& t : r.mesh.triangles) {
    const Vec3 centroid = (r.mesh.positions[t[0]] + r.mesh.positions[t[1]] + r.mesh.positions[t[2]]) / 3;
    if (around > 0 && (centroid - ridge).norm() > around) continue;
    worst = std::max(worst, densely_sampled_distance(*field, r.mesh, t));
    ++measured;
  }
  EXPECT_GT(measured, 0u);
  EXPECT_LE(worst, o.tolerance);
  EXPECT_GE(angle_statistics(r.mesh).min_degrees, 20.0);
}

TEST(AdaptiveTolerance, ANarrowRidgeIsRefinedAcrossItsOtherEdges) { expect_narrow_ridge_within_eps(0.02); }

// Every triangle measured densely, 2000 centres a value: more than the ten minutes ctest allows
// under the sanitizers (release: 5 s), so labelled slow_under_sanitizers (tests/CMakeLists.txt).
TEST(AdaptiveTolerance, ANarrowRidgeMeshIsWithinEpsEverywhere) { expect_narrow_ridge_within_eps(0); }

struct LastResortCase {
  std::string name, field;
  double eps;
  // Where the refinement left triangles beyond eps before the last resort; the test measures
  // every triangle within `radius` of it densely (0: the whole mesh).
  Vec3 near;
  double radius;
};

class LastResort : public testing::TestWithParam<LastResortCase> {};

TEST_P(LastResort, SplitsWhatTheRefinementLeftBeyondTheTolerance) {
  // Runs on which the refinement leaves triangles beyond eps that the last resort then splits
  // (another edge, a vertex inside, or halves below the default min_edge); the test measures
  // the distance itself. Before the side points (expand_point.cpp), blobs31 and blobs37 of the
  // topology sweep at 1e-2, blobs37 at 1e-3 and the Igea MPU at 1e-3 were such runs, each with
  // a warning of triangles 1.3-2.5 eps away before the last resort; with them, none of those
  // needs it, and these two blob fields (drawn like the sweep's, from seeds 8032 and 8029) do.
  const LastResortCase& c = GetParam();
  const auto field = load_field(std::string(CDP_SOURCE_DIR) + c.field);
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = c.eps;
  o.blocks = false;  // the tracker alone leaves these triangles (the blocks' meshes need no last resort)
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  const std::string what = c.name + " eps " + std::to_string(c.eps);
  expect_sound(r.mesh, what);
  EXPECT_GT(r.stats.adaptive->quality.last_resorts, 0u) << what;
  EXPECT_EQ(r.stats.adaptive->quality.over_tolerance, 0u) << what;
  double worst = 0;
  std::size_t measured = 0;
  for (const auto& t : r.mesh.triangles) {
    const Vec3 centroid = (r.mesh.positions[t[0]] + r.mesh.positions[t[1]] + r.mesh.positions[t[2]]) / 3;
    if (c.radius > 0 && (centroid - c.near).norm() > c.radius) continue;
    worst = std::max(worst, densely_sampled_distance(*field, r.mesh, t));
    ++measured;
  }
  std::cout << "last resort " << what << ": " << r.mesh.num_triangles() << " triangles, "
            << r.stats.adaptive->quality.last_resorts << " last resorts, " << measured
            << " measured, largest distance " << worst / c.eps << " eps\n";
  EXPECT_GT(measured, 0u);
  EXPECT_LE(worst, c.eps) << what;
  EXPECT_GE(angle_statistics(r.mesh).min_degrees, 20.0) << what;
}

const std::string kLastResortFields = "/tests/polygonizer/fields/";

std::string last_resort_name(const testing::TestParamInfo<LastResortCase>& info) {
  return info.param.name + "_eps" + std::to_string(static_cast<int>(std::round(-std::log10(info.param.eps) * 10)));
}

INSTANTIATE_TEST_SUITE_P(Adaptive, LastResort,
                         testing::Values(LastResortCase{"blobs_seed8032", kLastResortFields + "blobs_seed8032.json",
                                                        1e-2, Vec3::Zero(), 0}),
                         last_resort_name);
// 52k triangles, each measured: labelled slow_under_sanitizers (tests/CMakeLists.txt).
INSTANTIATE_TEST_SUITE_P(AdaptiveLarge, LastResort,
                         testing::Values(LastResortCase{"blobs_seed8029", kLastResortFields + "blobs_seed8029.json",
                                                        3e-3, Vec3::Zero(), 0}),
                         last_resort_name);

TEST(AdaptiveTolerance, SidePointsKeepSliversFromHingingOnAFillet) {
  // blobs39 of the topology sweep at 1e-2: the fronts reach a fillet of radius 0.014 with edges
  // of 0.15, and each expansion beside the fillet vertex (target 0.02) left a sliver whose long
  // edge became the next front edge, a fan of slivers hinged on it that no split could mend
  // without folding: 7 triangles up to 10 eps from the surface near (0.96, -1.28, -0.38),
  // smallest angle 7.7 degrees. With points along such long new front edges, none.
  const auto field = load_field(std::string(CDP_SOURCE_DIR) + "/results/topology_sweep/fields/blobs39.json");
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = 1e-2;
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  expect_sound(r.mesh, "blobs39 eps 1e-2");
  EXPECT_GT(r.stats.adaptive->tracker.side_points, 0u);
  EXPECT_EQ(r.stats.adaptive->quality.over_tolerance, 0u);
  EXPECT_GE(angle_statistics(r.mesh).min_degrees, 20.0);
  const Vec3 fillet(0.96, -1.28, -0.38);
  double worst = 0;
  std::size_t measured = 0;
  for (const auto& t : r.mesh.triangles) {
    const Vec3 centroid = (r.mesh.positions[t[0]] + r.mesh.positions[t[1]] + r.mesh.positions[t[2]]) / 3;
    if ((centroid - fillet).norm() > 0.2) continue;
    worst = std::max(worst, densely_sampled_distance(*field, r.mesh, t));
    ++measured;
  }
  EXPECT_GT(measured, 0u);
  EXPECT_LE(worst, o.tolerance);
}

TEST(AdaptiveAngles, AMeshMissingTheBoundsIsMadeAgainWithTheLookAhead) {
  // Fronts that reach a fillet with edges several times what it asks for hinge fans of slivers
  // on it across the fillet, which the repair cannot split without folding. Without the
  // look-ahead: blobs26 of the topology sweep at factor 1, 2.4 degrees; blobs27 and blobs39 at
  // tolerance 5e-2, 4.9 and 2.2 degrees with 6 and 12 triangles beyond the tolerance. Each is
  // made again with it (polygonize_adaptive) and meets every bound; the components and the
  // genus are the topology sweep's references (marching cubes on a fine grid).
  struct Case {
    const char* field;
    SizingMode sizing;
    double value;
    std::size_t components;
    int genus;
  };
  for (const Case& c : {Case{"blobs26", SizingMode::Factor, 1, 3, 3}, Case{"blobs27", SizingMode::Tolerance, 5e-2, 7, 2},
                        Case{"blobs39", SizingMode::Tolerance, 5e-2, 5, 4}}) {
    const auto field =
        load_field(std::string(CDP_SOURCE_DIR) + "/results/topology_sweep/fields/" + c.field + ".json");
    AdaptiveOptions o;
    o.sizing = c.sizing;
    (c.sizing == SizingMode::Factor ? o.factor : o.tolerance) = c.value;
    const PolygonizeResult r = polygonize_adaptive(*field, o);
    const std::string what = std::string(c.field) + (c.sizing == SizingMode::Factor ? " factor " : " eps ") +
                             std::to_string(c.value);
    expect_sound(r.mesh, what);
    expect_on_surface(*field, r.mesh, what);
    const MeshTopology t = analyze_topology(r.mesh);
    EXPECT_EQ(t.components, c.components) << what;
    EXPECT_EQ(t.genus, c.genus) << what;
    EXPECT_TRUE(r.stats.adaptive->recoveries.quality_rerun) << what;
    EXPECT_TRUE(r.stats.adaptive->recoveries.quality_rerun_kept) << what;
    EXPECT_TRUE(r.stats.adaptive->recoveries.look_ahead) << what;
    const AngleStatistics a = expect_smooth_angles(r.mesh, what);
    EXPECT_LE(a.mean_edge_ratio, kMeanEdgeRatio) << what;
    EXPECT_EQ(r.stats.adaptive->quality.over_tolerance, 0u) << what;
  }
}

// Coarse tolerances on the scans, where sizes change within a few edges: the relaxation's
// equilateral steps left the mean edge ratio at 1.253 (bunny VIS-800 at 1e-2) and 1.258 (Igea
// MPU at 1e-2), and the second run with the look-ahead did no better. The search sweeps
// (QualityOptions::aim_mean_edge_ratio) bring it under the bound in the first run.
void expect_relaxation_searched(const char* name, double tolerance) {
  const auto field = load_field(std::string(CDP_SOURCE_DIR) + "/experiments/fields/" + name + ".json");
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = tolerance;
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  const std::string what = std::string(name) + " eps " + std::to_string(tolerance);
  expect_sound(r.mesh, what);
  expect_on_surface(*field, r.mesh, what);
  EXPECT_EQ(analyze_topology(r.mesh).components, 1u) << what;
  const AdaptiveReport& x = *r.stats.adaptive;
  EXPECT_GE(x.quality.relax_search_sweeps, 1u) << what;
  EXPECT_GT(x.quality.relax_searched, 0u) << what;
  EXPECT_LE(x.quality.relax_searched, x.quality.relaxed) << what;
  EXPECT_FALSE(x.recoveries.quality_rerun) << what;
  const AngleStatistics a = expect_smooth_angles(r.mesh, what);
  EXPECT_LE(a.mean_edge_ratio, kMeanEdgeRatio) << what;
  EXPECT_EQ(x.quality.over_tolerance, 0u) << what;
}

// The Igea MPU model takes over a minute under the sanitizers: labelled slow_under_sanitizers
// (tests/CMakeLists.txt); the bunny's test below runs the same code path there.
TEST(AdaptiveAngles, ARelaxationLeftOverTheMeanEdgeRatioOnTheIgeaSearchesItsMoves) {
  expect_relaxation_searched("igea_mpu", 1e-2);
}

TEST(AdaptiveAngles, ARelaxationLeftOverTheMeanEdgeRatioSearchesItsMoves) {
  expect_relaxation_searched("bunny_vis800", 1e-2);
  // A field with creases (min, max, abs) meshed along them searches too (the cube at factor 3:
  // 1.343 -> 1.309; its crease vertices never move, so the mean stays over the aim there);
  // meshed across them as if smooth it does not (1.278 stays: the triangles across a crease stay
  // stretched, and on the union of two spheres at 5e-4 the search had taken the smallest angle
  // from 19.7 to 13.6 degrees).
  const auto cube = test::field_from_json(expression("max(abs(x),max(abs(y),abs(z)))-1", 1.5));
  for (CreaseHandling h : {CreaseHandling::Follow, CreaseHandling::Ignore}) {
    AdaptiveOptions o;
    o.factor = 3;
    o.creases = h;
    const PolygonizeResult r = polygonize_adaptive(*cube, o);
    const bool follow = h == CreaseHandling::Follow;
    const std::string what = std::string("cube factor 3, creases ") + (follow ? "followed" : "ignored");
    expect_sound(r.mesh, what);
    EXPECT_EQ(r.stats.adaptive->creases.followed, follow) << what;
    const AngleStatistics a = angle_statistics(r.mesh);
    std::cout << "angles " << what << ": min " << a.min_degrees << ", mean edge ratio " << a.mean_edge_ratio << "\n";
    if (follow) {
      EXPECT_GE(r.stats.adaptive->quality.relax_search_sweeps, 1u) << what;
      EXPECT_GT(r.stats.adaptive->quality.relax_searched, 0u) << what;
      EXPECT_GE(a.min_degrees, 20.0) << what;
    } else {
      EXPECT_EQ(r.stats.adaptive->quality.relax_search_sweeps, 0u) << what;
      EXPECT_GT(a.mean_edge_ratio, kMeanEdgeRatio) << what;
    }
  }
}

TEST(AdaptiveAngles, OnlyAnImprovedMeshMissingTheBoundsIsMadeAgain) {
  // Within the bounds: made once, as before, and the relaxation does not search.
  {
    const auto field = test::field_from_json(R"({"type": "torus", "major_radius": 1, "minor_radius": 0.35})");
    AdaptiveOptions o;
    o.factor = 3;
    const PolygonizeResult r = polygonize_adaptive(*field, o);
    EXPECT_FALSE(r.stats.adaptive->recoveries.quality_rerun);
    EXPECT_FALSE(r.stats.adaptive->recoveries.look_ahead);
    EXPECT_EQ(r.stats.adaptive->quality.relax_search_sweeps, 0u);
    EXPECT_EQ(r.stats.adaptive->quality.relax_searched, 0u);
  }
  // A run whose triangles the caller bounded is never made again (nor is paper mode's:
  // AdaptivePaperVariant.SwitchesOffEveryAddition).
  const auto field = load_field(std::string(CDP_SOURCE_DIR) + "/results/topology_sweep/fields/blobs39.json");
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = 5e-2;
  o.max_triangles = 1000000;
  const PolygonizeResult bounded = polygonize_adaptive(*field, o);
  EXPECT_LT(angle_statistics(bounded.mesh).min_degrees, 20.0);
  EXPECT_FALSE(bounded.stats.adaptive->recoveries.quality_rerun);
  EXPECT_FALSE(bounded.stats.adaptive->recoveries.look_ahead);
}

TEST(AdaptivePaperVariant, SwitchesOffEveryAddition) {
  const auto field = test::tanglecube();
  AdaptiveOptions o;
  o.factor = 3;
  o.variant = Variant::Paper;
  const PolygonizeResult p = polygonize_adaptive(*field, o);
  const AdaptiveReport& x = *p.stats.adaptive;
  EXPECT_EQ(x.settings.variant, Variant::Paper);
  EXPECT_EQ(x.settings.triangle_count, TriangleCountRule::Hartmann);
  EXPECT_FALSE(x.settings.grading);
  EXPECT_FALSE(x.settings.quality_repair);
  EXPECT_FALSE(x.settings.tolerance_refinement);
  const QualityReport& q = x.quality;
  const std::pair<const char*, std::size_t> repairs[] = {
      {"flips", q.flips},
      {"moves", q.moves},
      {"relaxed", q.relaxed},
      {"relax_flips", q.relax_flips},
      {"relax_searched", q.relax_searched},
      {"relax_search_sweeps", q.relax_search_sweeps},
      {"collapses", q.collapses},
      {"splits", q.splits},
      {"last_resorts", q.last_resorts},
      {"side_points", x.tracker.side_points}};
  for (const auto& [name, n] : repairs) EXPECT_EQ(n, 0u) << name;
  expect_sound(p.mesh, "paper tanglecube");
  // Its slivers (issue 18's bounds are the improved variant's) do not make it mesh again with
  // the look-ahead.
  EXPECT_LT(angle_statistics(p.mesh).min_degrees, 20.0);
  EXPECT_FALSE(x.recoveries.quality_rerun);
  EXPECT_FALSE(x.recoveries.look_ahead);

  // The default variant on the same surface has each addition on, and they act.
  o.variant = Variant::Improved;
  const PolygonizeResult d = polygonize_adaptive(*field, o);
  EXPECT_EQ(d.stats.adaptive->settings.variant, Variant::Improved);
  EXPECT_TRUE(d.stats.adaptive->settings.grading);
  EXPECT_TRUE(d.stats.adaptive->settings.quality_repair);
  EXPECT_GT(d.stats.adaptive->quality.flips, 0u);
  EXPECT_GT(d.stats.adaptive->quality.relaxed, 0u);
  EXPECT_GT(d.stats.adaptive->quality.relax_flips, 0u);
  EXPECT_LT(angle_statistics(d.mesh).mean_edge_ratio, angle_statistics(p.mesh).mean_edge_ratio);
  EXPECT_GT(angle_statistics(d.mesh).min_degrees, angle_statistics(p.mesh).min_degrees);

  // Tolerance: the paper sizes edges for a sagitta of eps at the point (edge_length reports the
  // target at a point of radius r: the paper's is 2 sqrt(2 r eps - eps^2)); the refinement is off.
  o.sizing = SizingMode::Tolerance;
  o.tolerance = 1e-2;
  o.variant = Variant::Paper;
  const PolygonizeResult pt = polygonize_adaptive(*field, o);
  EXPECT_FALSE(pt.stats.adaptive->settings.tolerance_refinement);
  EXPECT_EQ(pt.stats.adaptive->quality.splits, 0u);
  o.variant = Variant::Improved;
  const PolygonizeResult dt = polygonize_adaptive(*field, o);
  EXPECT_TRUE(dt.stats.adaptive->settings.tolerance_refinement);
  // The improved sizing asks for shorter edges (a share of eps), so more triangles.
  EXPECT_GT(dt.mesh.num_triangles(), pt.mesh.num_triangles());
}

TEST(AdaptiveAngles, RepairIsDeterministic) {
  const auto field = test::tanglecube();
  AdaptiveOptions o;
  o.factor = 3;
  const PolygonizeResult a = polygonize_adaptive(*field, o);
  const PolygonizeResult b = polygonize_adaptive(*field, o);
  ASSERT_EQ(a.mesh.positions.size(), b.mesh.positions.size());
  ASSERT_EQ(a.mesh.triangles, b.mesh.triangles);
  for (std::size_t i = 0; i < a.mesh.positions.size(); ++i) ASSERT_EQ(a.mesh.positions[i], b.mesh.positions[i]);
}

TEST(AngleStatistics, CountsAndCumulativeHistogram) {
  Mesh m;
  // An equilateral triangle and a right isosceles one (45, 45, 90) and a 12-78-90 one.
  const double t = std::tan(12 * std::acos(-1.0) / 180);
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, std::sqrt(3.0) / 2, 0}, {0, 1, 0}, {1, t, 0}};
  m.triangles = {{0, 1, 2}, {0, 1, 3}, {0, 1, 4}};
  const AngleStatistics a = angle_statistics(m);
  EXPECT_EQ(a.triangles, 3u);
  EXPECT_NEAR(a.min_degrees, 12.0, 1e-9);
  EXPECT_EQ(a.share_under_10, 0.0);
  EXPECT_NEAR(a.share_under_20, 1.0 / 3, 1e-15);
  EXPECT_NEAR(a.share_under_30, 1.0 / 3, 1e-15);
  ASSERT_EQ(a.below.size(), 60u);
  EXPECT_EQ(a.below[10], 0);  // under 11 degrees
  EXPECT_EQ(a.below[12], 1);  // under 13
  EXPECT_EQ(a.below[44], 1);  // under 45
  EXPECT_EQ(a.below[45], 2);  // under 46
  EXPECT_EQ(a.below[59], 3);
}

}  // namespace
}  // namespace cdp

