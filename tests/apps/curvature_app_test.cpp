// build/bin/curvature answers for every model type and fails cleanly on bad input.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "common/run_command.h"

namespace cdp {
namespace {

struct AppCase {
  std::string name, json, at;
};

std::ostream& operator<<(std::ostream& os, const AppCase& c) { return os << c.name; }

class CurvatureApp : public ::testing::TestWithParam<AppCase> {};

TEST_P(CurvatureApp, PrintsEveryMeasureForAProjectedPoint) {
  test::TempDir dir("curvature_app_" + GetParam().name);
  const auto field = dir.write("field.json", GetParam().json);
  const auto r = test::run_app("curvature", field.string() + " --at " + GetParam().at);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"projected", "normal", "k1", "k2", "dir1", "dir2", "gaussian", "mean", "mac", "shape_index"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_GE(j["k1"].get<double>(), j["k2"].get<double>());
  EXPECT_NEAR(j["gaussian"].get<double>(), j["k1"].get<double>() * j["k2"].get<double>(), 1e-9);
}

INSTANTIATE_TEST_SUITE_P(
    EveryModelType, CurvatureApp,
    ::testing::Values(
        AppCase{"sphere", R"({"type": "sphere", "radius": 2})", "1,1,1"},
        AppCase{"ellipsoid", R"({"type": "ellipsoid", "radii": [1, 2, 3]})", "1,1,1"},
        AppCase{"torus", R"({"type": "torus", "major_radius": 1, "minor_radius": 0.25})", "1.3,0,0.1"},
        AppCase{"blobs", R"({"type": "blobs", "kernel": "blinn", "threshold": 0.5,
                             "blobs": [{"center": [0,0,0], "radius": 1, "strength": 1}]})",
                "1,0,0"},
        AppCase{"expression", R"({"type": "expression", "value": "x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + 11.8",
                                  "bounds": [[-3,-3,-3],[3,3,3]]})",
                "2,0.2,0.1"},
        AppCase{"compiled", R"({"type": "double_torus"})", "0,0.4,0"}),
    [](const auto& info) { return info.param.name; });

TEST(CurvatureAppErrors, SphereAnswerMatchesTheClosedForm) {
  test::TempDir dir("curvature_app_sphere");
  const auto field = dir.write("s.json", R"({"type": "sphere", "radius": 2})");
  const auto r = test::run_app("curvature", field.string() + " --at 0,3,0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["projected"][1].get<double>(), 2.0, 1e-12);
  EXPECT_NEAR(j["k1"].get<double>(), 0.5, 1e-12);
  EXPECT_NEAR(j["shape_index"].get<double>(), -1.0, 1e-12);
}

TEST(CurvatureAppErrors, BadInputGivesOneLineAndExitCodeOne) {
  test::TempDir dir("curvature_app_errors");
  const auto typo = dir.write("typo.json", R"({"type": "sphere", "radius": 1, "centre": [0,0,0]})");
  const auto huge = dir.write("huge.json", R"({"type": "sphere", "radius": 1e160})");
  const auto tiny = dir.write("tiny.json", R"({"type": "sphere", "radius": 1e-150})");
  const auto deep = dir.write("deep.json", R"({"type": "expression", "bounds": [[-1,-1,-1],[1,1,1]], "value": ")" +
                                               std::string(4000, '(') + "x" + std::string(4000, ')') + "\"}");
  const auto flat = dir.write("flat.json",
                              R"({"type": "expression", "value": "x^2 + y^2 + z^2 - 1", "bounds": [[-2,-2,-2],[2,2,2]]})");
  const struct {
    std::string args, message;
  } cases[] = {
      {typo.string() + " --at 1,0,0", typo.string() + ": centre: unknown key (did you mean \"center\"?)"},
      {(dir.path / "missing.json").string() + " --at 1,0,0", (dir.path / "missing.json").string() + ": cannot open file"},
      {deep.string() + " --at 1,0,0", deep.string() + ": value: expression: formula nested too deeply (more than 256 "
                                                      "levels of parentheses, calls, signs and exponents) at position 257"},
      {flat.string() + " --at 1,zero,0", "--at: expects three numbers x,y,z, found \"1,zero,0\""},
      {flat.string() + " --at 0,0,0", flat.string() + ": cannot project 0,0,0 onto the surface: the gradient vanishes"},
      {huge.string() + " --at 1,0,0", huge.string() + ": cannot project 1,0,0 onto the surface: the field's box is too "
                                                      "large (or too small) for double precision"},
      // The Hessian of a sphere of radius 1e-150 overflows (1/r): said so, with the file, once.
      {tiny.string() + " --at 1e-150,0,0", tiny.string() + ": no curvature at the projected point: the Hessian is not "
                                                           "finite (|grad F| = 1)"},
      {flat.string() + " --at 1,0,0 --at 2,0,0", "--at given twice"},
      {flat.string(), "--at is required; see curvature --help"},
  };
  for (const auto& c : cases) {
    const auto r = test::run_app("curvature", c.args);
    EXPECT_EQ(r.exit_code, 1) << c.args;
    EXPECT_EQ(r.err, "curvature: " + c.message + "\n") << c.args;
    EXPECT_TRUE(r.out.empty());
  }
}

}  // namespace
}  // namespace cdp
