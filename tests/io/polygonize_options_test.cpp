// The options table (polygonize_options.h): every option reaches the method's options, bad
// values and misspellings are refused with one line naming them.
#include <gtest/gtest.h>

#include <cdp/core/errors.h>
#include <cdp/io/polygonize_options.h>

#include <set>
#include <string>

namespace cdp {
namespace {

std::string options_error(const std::string& method, const nlohmann::json& options) {
  try {
    polygonize_request(method, options);
  } catch (const InvalidInputError& e) {
    return e.what();
  }
  return "";
}

TEST(PolygonizeOptions, NamesAreUniqueAndFlagsAreTheNamesWithDashes) {
  std::set<std::string> names;
  for (const OptionSpec& spec : polygonize_options()) {
    EXPECT_TRUE(names.insert(std::string(spec.name)).second) << spec.name;
    std::string flag = option_flag(spec);
    EXPECT_EQ(flag.substr(0, 2), "--");
    for (char& c : flag) c = c == '-' ? '_' : c;
    EXPECT_EQ(flag.substr(2), spec.name);
    EXPECT_EQ(find_polygonize_option(spec.name), &spec);
    if (spec.kind == OptionKind::Choice) {
      ASSERT_FALSE(spec.choices.empty()) << spec.name;
      EXPECT_EQ(spec.default_text, spec.choices.front()) << spec.name;
    }
  }
}

TEST(PolygonizeOptions, TheDefaultsAreTheLibrarys) {
  // The table's default texts must be what the options structs hold when nothing is given.
  const PolygonizeRequest r = polygonize_request("adaptive", nlohmann::json::object());
  const AdaptiveOptions a;
  EXPECT_EQ(r.adaptive.factor, a.factor);
  EXPECT_EQ(std::stod(std::string(find_polygonize_option("factor")->default_text)), a.factor);
  EXPECT_EQ(std::stoi(std::string(find_polygonize_option("seed_resolution")->default_text)), a.seed_resolution);
  EXPECT_EQ(std::stoi(std::string(find_polygonize_option("threads")->default_text)), a.threads);
  EXPECT_EQ(find_polygonize_option("variant")->default_text, to_string(a.variant));
  EXPECT_EQ(find_polygonize_option("creases")->default_text, to_string(a.creases));
  EXPECT_EQ(find_polygonize_option("triangle_count")->default_text, to_string(a.triangle_count));
  EXPECT_EQ(find_polygonize_option("check_self_intersections")->default_text, a.check_self_intersections ? "true" : "false");
  EXPECT_EQ(find_polygonize_option("curvature")->default_text, a.curvature_properties ? "true" : "false");
  const MarchingOptions m;
  EXPECT_EQ(std::stoi(std::string(find_polygonize_option("seed_resolution")->default_text)), m.seed_resolution);
}

TEST(PolygonizeOptions, EveryOptionReachesTheMethodsOptions) {
  const PolygonizeRequest a = polygonize_request(
      "adaptive", {{"tolerance", 0.01}, {"min_edge", 0.002}, {"max_edge", 0.5}, {"triangle_count", "paper_floor"},
                   {"variant", "paper"}, {"creases", "ignore"}, {"curvature", true}, {"check_self_intersections", false},
                   {"seed_resolution", 40}, {"max_triangles", 1000}, {"threads", 1}});
  EXPECT_EQ(a.adaptive.sizing, SizingMode::Tolerance);
  EXPECT_EQ(a.adaptive.tolerance, 0.01);
  EXPECT_EQ(a.adaptive.min_edge, 0.002);
  EXPECT_EQ(a.adaptive.max_edge, 0.5);
  EXPECT_EQ(a.adaptive.triangle_count, TriangleCountRule::PaperFloor);
  EXPECT_EQ(a.adaptive.variant, Variant::Paper);
  EXPECT_EQ(a.adaptive.creases, CreaseHandling::Ignore);
  EXPECT_TRUE(a.adaptive.curvature_properties);
  EXPECT_FALSE(a.adaptive.check_self_intersections);
  EXPECT_EQ(a.adaptive.seed_resolution, 40);
  EXPECT_EQ(a.adaptive.max_triangles, 1000u);
  EXPECT_EQ(a.adaptive.threads, 1);
  EXPECT_EQ(polygonize_request("adaptive", {{"chord", 0.02}}).adaptive.sizing, SizingMode::Chord);
  EXPECT_EQ(polygonize_request("adaptive", {{"factor", 5}}).adaptive.factor, 5.0);
  // The older spelling of the paper's rule.
  EXPECT_EQ(polygonize_request("adaptive", {{"triangle_count", "paper"}}).adaptive.triangle_count,
            TriangleCountRule::PaperFloor);
  const PolygonizeRequest mc = polygonize_request(
      "mc", {{"cell", 0.05}, {"traversal", "grid"}, {"face_ambiguity", "join_inside"}, {"seed_resolution", 16}});
  EXPECT_EQ(mc.marching.cell_size, 0.05);
  EXPECT_EQ(mc.marching.traversal, Traversal::Grid);
  EXPECT_EQ(mc.marching.face_ambiguity, FaceAmbiguity::JoinInside);
  EXPECT_EQ(mc.marching.seed_resolution, 16);
  EXPECT_EQ(polygonize_request("mt", {{"precision", 3}}).marching.precision, 3);
  // null is the default.
  EXPECT_EQ(polygonize_request("adaptive", {{"factor", nullptr}}).adaptive.factor, AdaptiveOptions{}.factor);
}

TEST(PolygonizeOptions, MistakesAreOneLineErrorsNamingTheOption) {
  EXPECT_EQ(options_error("adaptive", {{"factr", 2}}), "unknown option \"factr\" (did you mean \"factor\"?)");
  EXPECT_EQ(options_error("adaptive", {{"zzzzzz", 2}}), "unknown option \"zzzzzz\"");
  EXPECT_EQ(options_error("marching", {}), "method must be \"adaptive\", \"mc\" or \"mt\", not \"marching\"");
  EXPECT_EQ(options_error("adaptive", {{"cell", 0.1}}), "cell does not apply to method \"adaptive\"");
  EXPECT_EQ(options_error("mt", {{"face_ambiguity", "join_inside"}}), "face_ambiguity does not apply to method \"mt\"");
  EXPECT_EQ(options_error("adaptive", {{"factor", 2}, {"chord", 0.1}}), "give one of factor, tolerance and chord, not several");
  EXPECT_EQ(options_error("mc", {{"cell", 0.1}, {"precision", 2}}), "give one of cell and precision, not several");
  EXPECT_EQ(options_error("adaptive", {{"factor", -1}}), "factor must be a positive number, not -1.0");
  EXPECT_EQ(options_error("adaptive", {{"factor", "2"}}), "factor must be a positive number, not \"2\"");
  EXPECT_EQ(options_error("adaptive", {{"min_edge", 0}}), "min_edge must be a positive number, not 0.0");
  EXPECT_EQ(options_error("adaptive", {{"seed_resolution", 1}}), "seed_resolution must be an integer in [2, 2147483647], not 1");
  EXPECT_EQ(options_error("adaptive", {{"seed_resolution", 2.5}}), "seed_resolution must be an integer in [2, 2147483647], not 2.5");
  EXPECT_EQ(options_error("adaptive", {{"triangle_count", "floor"}}),
            "triangle_count must be \"hartmann\" or \"paper_floor\", not \"floor\"");
  EXPECT_EQ(options_error("adaptive", {{"curvature", 1}}), "curvature must be true or false, not 1");
  EXPECT_EQ(options_error("adaptive", nlohmann::json::array()), "the options must be an object");
}

}  // namespace
}  // namespace cdp
