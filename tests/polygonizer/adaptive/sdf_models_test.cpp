// Models written the way SDF modelling code writes them (fogleman/sdf, Inigo Quilez's distance
// functions): rounded primitives and smooth booleans, which are C1 where their max, min and
// clamps switch, beside sharp booleans, whose creases the mesher follows. Each at several
// factors and tolerances, checked as the hard-surface suite checks: a sound mesh with the
// reference's components and genus (closed forms, or marching tetrahedra stable between two grid
// sizes), no self-intersection, and angles of at least 20 degrees on a model without creases and
// 5 at creases. These must mesh (a clear error is a failure here).
#include <gtest/gtest.h>

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/io/field_factory.h>

#include <cmath>
#include <initializer_list>
#include <map>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/test_fields.h"
#include "polygonizer/mesh_checks.h"

namespace cdp {
namespace {

struct SdfModel {
  std::string name;
  std::string json;
  int components = -1;  // closed form; -1: from the marching reference
  int genus = -1;
  bool creased = false;  // has creases the mesher must follow
};

// {"type": "expression", "value": value, "define": {...}, "bounds": ±half}
std::string model(const std::string& value, double half, const std::map<std::string, std::string>& define = {}) {
  std::ostringstream s;
  s << R"({"type": "expression", "value": ")" << value << R"(", )";
  if (!define.empty()) {
    s << R"("define": {)";
    bool first = true;
    for (const auto& [name, formula] : define) {
      s << (first ? "" : ", ") << '"' << name << R"(": ")" << formula << '"';
      first = false;
    }
    s << "}, ";
  }
  s << R"("bounds": [[)" << -half << ", " << -half << ", " << -half << "], [" << half << ", " << half << ", " << half
    << "]]}";
  return s.str();
}

// Inigo Quilez's polynomial smooth minimum of a and b with radius k, as named sub-expressions.
std::map<std::string, std::string> smooth_min(const std::string& a, const std::string& b, double k) {
  const std::string K = std::to_string(k);
  return {{"a", a}, {"b", b}, {"h", "clamp(0.5+0.5*(b-a)/" + K + ",0,1)"}, {"u", "b+h*(a-b)-" + K + "*h*(1-h)"}};
}

const std::string kRoundedBox = "sqrt(max(abs(x)-0.6,0)^2+max(abs(y)-0.4,0)^2+max(abs(z)-0.3,0)^2)-0.15";
const std::string kSphere = "sqrt((x-0.5)^2+(y-0.3)^2+z^2)-0.45";
// The rounded box as cdp.sdf writes it (Inigo Quilez's exact distance, length(max(q, 0)) +
// min(max(q), 0) - r, in one hypot): its max(q) switches at the sharp edges of its core, inside
// the surface, where the min hides it.
const std::map<std::string, std::string> kSdfRoundedBox = {
    {"q0", "abs(x)-0.7"}, {"q1", "abs(y)-0.4"}, {"q2", "abs(z)-0.3"}, {"m", "min(max(q0,q1,q2),0)"},
    {"r", "hypot(max(q0,0),max(q1,0),max(q2,0),m)+2*m-0.1"}};
std::map<std::string, std::string> with(std::map<std::string, std::string> a, const std::map<std::string, std::string>& b) {
  a.insert(b.begin(), b.end());
  return a;
}

std::vector<SdfModel> sdf_models() {
  std::vector<SdfModel> v = {
      {"rounded_box", model(kRoundedBox, 1.1), 1, 0},
      {"smooth_union", model("u", 1.2, smooth_min(kRoundedBox, kSphere, 0.2)), 1, 0},
      {"smooth_union_minus_cylinder", model("max(u, 0.2-sqrt(x^2+y^2))", 1.2, smooth_min(kRoundedBox, kSphere, 0.2)), 1,
       1, true},
      {"sdf_rounded_box_minus_cylinder", model("max(r, 0.2-hypot(x,y))", 1.0, kSdfRoundedBox), 1, 1, true},
      // A rounded block with a ball blended on and a hole through both (cdp.sdf: rounded_box((1.6,
      // 1, 0.8), 0.1) | sphere(0.55, center=(0.6, 0.3, 0.3)).k(0.2) - cylinder(0.2)).
      {"blended_block",
       model("max(u, 0.2-hypot(x,y))", 1.3, with(kSdfRoundedBox, smooth_min("r", "hypot(x-0.6,y-0.3,z-0.3)-0.55", 0.2))),
       1, 1, true},
      // A capsule chain: each capsule's clamp is C1 where its cylinder meets its caps.
      {"capsules",
       model("min(c1, c2)", 1.4,
             {{"c1", "hypot(x+0.8-1.2*clamp((x+0.8)/1.2,0,1), y, z)-0.25"},
              {"c2", "hypot(x-0.4, y-clamp(y,0,0.9), z)-0.2"}}),
       1, 0, true},
      {"onion", model("abs(" + kRoundedBox + ")-0.04", 1.2), 2, 0},
      // fogleman/sdf's README model: sphere(1) & box(1.5) - the three cylinders(0.5).
      {"fogleman_readme",
       model("max(max(sqrt(x^2+y^2+z^2)-1, max(abs(x),abs(y),abs(z))-0.75), -min(hypot(y,z)-0.5, hypot(x,z)-0.5, "
             "hypot(x,y)-0.5))",
             1.2),
       -1, -1, true},
      {"drilled_sphere", model("max(sqrt(x^2+y^2+z^2)-1, 0.05-hypot(x,y))", 1.2), 1, 1, true},
      // Two pipes of equal radius crossing at right angles, in a box: the two ellipses where the
      // pipes meet cross at the top and bottom, where the pipes are tangent.
      {"crossed_pipes", model("max(min(hypot(y,z)-0.5, hypot(x,z)-0.5), max(abs(x),abs(y),abs(z))-1)", 1.2), 1, 0,
       true},
      // A box with a ball blended onto one edge: the edge's crease fades out inside the blend, from
      // both ends, and its switch goes on over the ball as a seam between the two faces' patches.
      {"box_blended_ball",
       model("u", 1.4, smooth_min("max(abs(x),abs(y),abs(z))-0.75", "hypot(x-0.75,y-0.75,z)-0.5", 0.25)), 1, 0, true},
      // fogleman/sdf's tetrahedron (max(|x + y| - z, |x - y| + z)) with a ball blended in from
      // inside, which bulges its faces: each abs hides behind the max on two faces and shows on
      // the others, so a piece that flips the max must not leave it free.
      {"tetrahedron_blended_ball",
       model("u", 1.5, smooth_min("(max(abs(x+y)-z, abs(x-y)+z)-1)*0.5773502691896258", "hypot(x,y,z)-0.5", 0.2)), 1, 0,
       true},
      // A box smoothly intersected with a ball (the polynomial smooth maximum, radius 0.2): the
      // box's corners are rounded off by the ball, its edges fade into the blend.
      {"box_smooth_intersection_ball",
       model("b+h*(a-b)+0.2*h*(1-h)", 1.0,
             {{"a", "max(abs(x),abs(y),abs(z))-0.75"}, {"b", "hypot(x,y,z)-1"}, {"h", "clamp(0.5-0.5*(b-a)/0.2,0,1)"}}),
       1, 0, true},
      // A box with a hole cut by a smooth difference (a fillet of 0.1 round the hole): inside the
      // hole the blend hides the box, where the pieces of its faces are all one function.
      {"box_filleted_hole",
       model("d0-(d1+d0)*h+0.1*h*(1-h)", 0.9,
             {{"d0", "max(abs(x)-0.75,abs(y)-0.75,abs(z)-0.75)"}, {"d1", "hypot(x,y)-0.5"}, {"h", "clamp(0.5-(d1+d0)*5,0,1)"}}),
       1, 1, true},
      // Two crossing holes cut by one smooth difference: each face, its fillet and its hole's
      // wall are one smooth patch, bounded outside by the face's edges (coded by the box's
      // choice, the holes' hidden) and inside where the holes cross (coded by the holes' choice,
      // the box's hidden); a box with four mouths joined inside, genus 3.
      {"box_crossing_filleted_holes",
       model("d0-(d1+d0)*h+0.1*h*(1-h)", 0.9,
             {{"d0", "max(abs(x)-0.75,abs(y)-0.75,abs(z)-0.75)"},
              {"d1", "min(hypot(y,z)-0.5, hypot(x,z)-0.5)"},
              {"h", "clamp(0.5-(d1+d0)*5,0,1)"}}),
       1, 3, true},
      // fogleman/sdf's README model with its holes cut by a smooth difference (k = 0.1): six
      // mouths joined inside, genus 5.
      {"fogleman_filleted_holes",
       model("d0-(d1+d0)*h+0.1*h*(1-h)", 0.9,
             {{"d0", "max(hypot(x,y,z)-1, max(abs(x),abs(y),abs(z))-0.75)"},
              {"d1", "min(hypot(y,z)-0.5, hypot(x,z)-0.5, hypot(x,y)-0.5)"},
              {"h", "clamp(0.5-(d1+d0)*5,0,1)"}}),
       1, 5, true},
      // A Menger sponge of level 1: creases meeting at the openings' corners and at the corners
      // of the cavity, where six meet and each wall plane touches the corner from two quadrants.
      {"menger_level1",
       model("max(max(abs(x),abs(y),abs(z))-1, -min(max(abs(x),abs(y))-0.4, max(abs(y),abs(z))-0.4, "
             "max(abs(x),abs(z))-0.4))",
             1.3),
       1, 5, true},
  };
  return v;
}

struct SdfCase {
  std::size_t model;
  double factor;
  double tolerance = 0;  // positive: SizingMode::Tolerance instead of the factor
};

std::string sdf_case_name(const testing::TestParamInfo<SdfCase>& info) {
  std::ostringstream s;
  s << sdf_models()[info.param.model].name;
  if (info.param.tolerance > 0) s << "_tolerance" << info.param.tolerance;
  else s << "_factor" << info.param.factor;
  std::string n = s.str();
  for (char& c : n)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return n;
}

class SdfModels : public testing::TestWithParam<SdfCase> {};

// The smallest angle of the triangles none of whose corners lies on a crease (where two pieces of
// the field meet within 1e-6 of the diagonal): the quality bound away from creases, measured from
// the field rather than from the mesher's own record of its crease vertices.
struct AwayFromCreases {
  double degrees = 180;
  Vec3 where = Vec3::Zero();  // the centroid of that triangle
};
AwayFromCreases min_angle_away_from_creases(const Field& field, const Mesh& mesh) {
  const double near = 1e-6 * field.bounds().diagonal();
  std::vector<char> on_crease(mesh.positions.size());
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) on_crease[v] = field.pieces(mesh.positions[v], near).size() > 1;
  AwayFromCreases best;
  for (const auto& t : mesh.triangles) {
    if (on_crease[static_cast<std::size_t>(t[0])] || on_crease[static_cast<std::size_t>(t[1])] ||
        on_crease[static_cast<std::size_t>(t[2])])
      continue;
    for (int c = 0; c < 3; ++c) {
      const Vec3& p = mesh.positions[static_cast<std::size_t>(t[c])];
      const Vec3 u = mesh.positions[static_cast<std::size_t>(t[(c + 1) % 3])] - p;
      const Vec3 w = mesh.positions[static_cast<std::size_t>(t[(c + 2) % 3])] - p;
      const double a = std::atan2(u.cross(w).norm(), u.dot(w)) * 180 / std::numbers::pi;
      if (a < best.degrees)
        best = {a, (mesh.positions[static_cast<std::size_t>(t[0])] + mesh.positions[static_cast<std::size_t>(t[1])] +
                    mesh.positions[static_cast<std::size_t>(t[2])]) / 3};
    }
  }
  return best;
}

// The suite's model called `name`.
// \throw std::out_of_range where there is none.
SdfModel sdf_model(const std::string& name) {
  for (const SdfModel& m : sdf_models())
    if (m.name == name) return m;
  throw std::out_of_range("no SDF model " + name);
}

// At each factor: creases followed, angles of at least 5 degrees at them and 20 away from them.
void expect_angle_bounds_at_factors(const SdfModel& m, std::initializer_list<double> factors) {
  const auto field = test::field_from_json(m.json);
  for (const double factor : factors) {
    AdaptiveOptions o;
    o.factor = factor;
    const PolygonizeResult r = polygonize_adaptive(*field, o);
    EXPECT_EQ(r.stats.adaptive->creases.fallback, "") << m.name << " " << factor;
    EXPECT_GE(r.stats.adaptive->min_angle_degrees, 5.0) << m.name << " " << factor;
    const AwayFromCreases away = min_angle_away_from_creases(*field, r.mesh);
    EXPECT_GE(away.degrees, 20.0) << m.name << " " << factor << ": away from creases, near " << away.where.transpose();
  }
}

TEST_P(SdfModels, MeshWithTheirCreasesAndGoodTriangles) {
  const SdfModel m = sdf_models()[GetParam().model];
  const auto field = test::field_from_json(m.json);
  AdaptiveOptions o;
  o.factor = GetParam().factor;
  if (GetParam().tolerance > 0) {
    o.sizing = SizingMode::Tolerance;
    o.tolerance = GetParam().tolerance;
  }
  EXPECT_EQ(field->has_pieces(), m.creased) << m.name;
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  const MeshTopology t = analyze_topology(r.mesh);
  int components = m.components, genus = m.genus;
  if (components < 0) {
    const test::MarchingReference ref = test::marching_reference(m.name, *field);
    ASSERT_TRUE(ref.stable) << m.name << ": the marching reference is not stable between grid sizes";
    components = ref.components, genus = ref.genus;
  }
  test::expect_sound(r.mesh, m.name);
  EXPECT_EQ(static_cast<int>(t.components), components) << m.name;
  EXPECT_EQ(t.genus, genus) << m.name;
  EXPECT_EQ(r.stats.adaptive->seeding.uncovered, 0u);
  // Creases followed, not meshed across after a failed layout.
  EXPECT_EQ(r.stats.adaptive->creases.fallback, "") << m.name;
  if (m.creased) {
    EXPECT_GT(r.stats.adaptive->creases.curves, 0u) << m.name;
  }
  const double min_angle = r.stats.adaptive->min_angle_degrees;
  const AwayFromCreases away = min_angle_away_from_creases(*field, r.mesh);
  EXPECT_GE(min_angle, m.creased ? 5.0 : 20.0) << m.name;
  EXPECT_GE(away.degrees, 20.0) << m.name << ": away from creases, near " << away.where.transpose();
  std::cout << "sdf-model " << m.name << " " << sdf_case_name({GetParam(), 0}) << ": " << t.triangles << " triangles, "
            << r.stats.seconds << " s, min angle " << min_angle << ", away from creases " << away.degrees << "\n";
}

std::vector<SdfCase> all_cases() {
  std::vector<SdfCase> out;
  for (std::size_t s = 0; s < sdf_models().size(); ++s) {
    // Under the sanitizers factor 3 only: the other cases carry the ctest label
    // slow_under_sanitizers (tests/CMakeLists.txt).
    for (double k : {1.0, 3.0, 10.0}) out.push_back({s, k});
    for (double t : {1e-1, 1e-2, 1e-3, 1e-4}) out.push_back({s, 0, t});
  }
  return out;
}

INSTANTIATE_TEST_SUITE_P(Adaptive, SdfModels, testing::ValuesIn(all_cases()), sdf_case_name);

// The drilled sphere's patch on the sphere is bounded by the hole's two rims, whose edges are a
// twentieth of the sphere's: the fronts start from one rim and reach the other with edges
// graded down by the look-ahead (kPatchLookAheadGradations). With the smooth re-run's gradation
// (0.4) the factors between the suite's missed the bounds: 17.9 degrees away from the creases at
// 3.2, 0.37 at the rim at 4.25.
TEST(SdfDrilledSphere, EveryQuarterFactorFromOneToSixMeetsTheAngleBounds) {
  const auto field = test::field_from_json(model("max(sqrt(x^2+y^2+z^2)-1, 0.05-hypot(x,y))", 1.2));
  for (int quarter = 4; quarter <= 24; ++quarter) {
    AdaptiveOptions o;
    o.factor = quarter / 4.0;
    const PolygonizeResult r = polygonize_adaptive(*field, o);
    const MeshTopology t = analyze_topology(r.mesh);
    EXPECT_EQ(t.components, 1u) << o.factor;
    EXPECT_EQ(t.genus, 1) << o.factor;
    EXPECT_EQ(r.stats.adaptive->creases.fallback, "") << o.factor;
    EXPECT_GE(r.stats.adaptive->min_angle_degrees, 5.0) << o.factor;
    const AwayFromCreases away = min_angle_away_from_creases(*field, r.mesh);
    EXPECT_GE(away.degrees, 20.0) << o.factor << ": away from creases, near " << away.where.transpose();
  }
}

// At factor 2.5 the patch of one hole's wall placed a vertex 0.0024 past the crease where two
// holes' walls meet (the patch tests' margin allows the crease's sagitta), the apex of a 2.8
// degree cap on a crease edge that the crease probes kept from moving or merging; the repair
// now merges such an apex onto the crease (repair_angles.cpp).
TEST(SdfFoglemanFilletedHoles, AtFactorTwoAndAHalfNoCapHangsOverTheCreaseOfTwoHoles) {
  const SdfModel m = sdf_model("fogleman_filleted_holes");
  const auto field = test::field_from_json(m.json);
  AdaptiveOptions o;
  o.factor = 2.5;
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  test::expect_sound(r.mesh, m.name);
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_EQ(static_cast<int>(t.components), m.components);
  EXPECT_EQ(t.genus, m.genus);
  EXPECT_EQ(r.stats.adaptive->creases.fallback, "");
  EXPECT_GE(r.stats.adaptive->min_angle_degrees, 5.0);
  const AwayFromCreases away = min_angle_away_from_creases(*field, r.mesh);
  EXPECT_GE(away.degrees, 20.0) << "away from creases, near " << away.where.transpose();
}

// The box's edge y = z = -0.75 passes 0.15 from where the hole's fillet begins on the face
// z = -0.75. At the edge the field takes the face y = -0.75's branch of the box's max, which sees
// no fillet near, so the crease's edges stayed 0.3 long beside the fillet's 0.03, and the strip
// of flat face between them was closed with triangles of 19.4 and 19.9 degrees at these factors.
// Each face's seams now shorten the crease's edges (Field::smooth_sides on a piece).
TEST(SdfBoxFilletedHole, AtTheBoxEdgeBesideTheFilletTheFaceOfTheFilletShortensTheCrease) {
  expect_angle_bounds_at_factors(sdf_model("box_filleted_hole"), {5.5, 6.0});
}

// With two holes crossing, the fillet begins 0.1-0.15 from the box's edges on the faces y = +-0.75.
// A crease sample there took the fillet's far side continued to the sample, a radius of 1.5-1.8
// where the fillet begins with 0.2, so the crease kept edges of 0.3 beside the fillet's 0.03: 18.2
// and 17.4 degrees away from creases at these factors. Crease samples now take it where it begins
// (Field::SeamSideAt::Seam).
TEST(SdfBoxCrossingFilletedHoles, BesideTheFilletTheCreaseGradesToWhereTheFilletBegins) {
  expect_angle_bounds_at_factors(sdf_model("box_crossing_filleted_holes"), {2.75, 6.5});
}

// 90k triangles and two runs: several times slower under the sanitizers (ctest label
// slow_under_sanitizers, tests/CMakeLists.txt).
TEST(SdfCrowd, TwoHundredBlobsJoinedByANarrowNeckMeshWithMinEdgeLowered) {
  // 200 Wyvill blobs (radii 0.4-0.7, centres in +-2, Python's random with seed 200): two of them
  // are joined by a neck 0.006 wide near (-0.554, 1.006, 0.822), F = -3.7e-5 at its saddle,
  // which bends with a radius of 0.0012, below the lowest min_edge a failed run is made again
  // with (0.0018). That run meshes it. Reference: Marching Cubes at cells 0.02 and 0.01 (3
  // components, genus 30 both; marching tetrahedra at the suite's 56 and 72 cells disagree).
  const auto field = load_field(std::string(CDP_SOURCE_DIR) + "/tests/polygonizer/fields/crowd_200_wyvill_blobs.json");
  AdaptiveOptions o;
  o.factor = 2;
  // The first attempt steps over the neck, narrower than min_edge: the recoveries, which keep
  // min_edge, are skipped (Run::needs_shorter_edges), and the run with min_edge lowered meshes
  // it. Before, eight recoveries stepped over it again first. The first attempt fails before
  // its repair (check_necks): one repair, the lowered run's (before, the first attempt was
  // repaired and checked, 0.7 s of the 4.9 s, and only then searched for necks).
  int meshings = 0, repairs = 0;
  o.phase = [&](const std::string& phase) {
    meshings += phase == "meshing";
    repairs += phase == "repairing triangles";
  };
  const PolygonizeResult r = polygonize_adaptive(*field, o);
  EXPECT_EQ(meshings, 2);
  EXPECT_EQ(repairs, 1);
  test::expect_sound(r.mesh, "crowd");
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_EQ(t.components, 3u);
  EXPECT_EQ(t.genus, 30);
  EXPECT_TRUE(r.stats.adaptive->recoveries.min_edge_lowered);
  EXPECT_GE(r.stats.adaptive->min_angle_degrees, 20.0);
}

}  // namespace
}  // namespace cdp
