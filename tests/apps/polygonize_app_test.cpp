// build/bin/polygonize: every method writes a closed mesh with normals and the common STATS.json;
// bad arguments and bad fields end with a one-line error and no output file.
#include <gtest/gtest.h>

#include <cdp/core/mesh_topology.h>
#include <cdp/io/mesh_io.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "apps/app_files.h"
#include "common/run_command.h"

namespace cdp {
namespace {

using test::kTorus;
using test::read_json;

class PolygonizeApp : public ::testing::TestWithParam<std::string> {};

TEST_P(PolygonizeApp, WritesAClosedTorusAndItsStats) {
  const std::string method = GetParam();
  test::TempDir dir("polygonize_app_" + method);
  const auto field = dir.write("torus.json", kTorus);
  const std::string size = method == "adaptive" ? "--factor 2" : "--cell 0.1";
  const auto r = test::run_app("polygonize", field.string() + " -o " + (dir.path / "out.ply").string() + " --method " +
                                                 method + " " + size + " --stats " + (dir.path / "stats.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Mesh mesh = read_mesh(dir.path / "out.ply");
  const MeshTopology t = analyze_topology(mesh);
  EXPECT_TRUE(t.closed());
  EXPECT_TRUE(t.oriented());
  EXPECT_EQ(t.genus, 1);
  EXPECT_EQ(mesh.normals.size(), mesh.positions.size());
  const auto stats = read_json(dir.path / "stats.json");
  for (const char* key : {"method", "triangles", "vertices", "components", "seconds", "field_evaluations", "splits", "merges"})
    EXPECT_TRUE(stats.contains(key)) << key;
  EXPECT_EQ(stats["method"], method);
  EXPECT_EQ(stats["triangles"].get<std::size_t>(), mesh.num_triangles());
  EXPECT_EQ(stats["components"].get<int>(), 1);
  EXPECT_GT(stats["field_evaluations"]["total"].get<double>(), 0);
  // The program's own peak resident memory (Linux's VmHWM): at least its mesh's bytes, and far
  // below a gigabyte for this torus.
  ASSERT_TRUE(stats.contains("peak_resident_bytes"));
  const double peak = stats["peak_resident_bytes"].get<double>();
  EXPECT_GT(peak, static_cast<double>(mesh.num_vertices() * 48 + mesh.num_triangles() * 12));
  EXPECT_LT(peak, 1e9);
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, PolygonizeApp, ::testing::Values("adaptive", "mc", "mt"),
                         [](const auto& info) { return info.param; });

// --level meshes F = C: x^2 + y^2 + z^2 at 1.44 is the sphere of radius 1.2, for every method;
// the mesh goes to STL as well as to the other formats.
TEST(PolygonizeApp, LevelMeshesAnotherValueOfTheFieldAndStlIsWritten) {
  test::TempDir dir("polygonize_app_level");
  const auto field = dir.write("square.json", R"J({"type": "expression", "value": "x^2 + y^2 + z^2",
      "bounds": [[-2,-2,-2],[2,2,2]]})J");
  for (const std::string method : {"adaptive", "mc", "mt"}) {
    const auto out = dir.path / ("out_" + method + ".stl");
    const std::string size = method == "adaptive" ? "--factor 2" : "--cell 0.1";
    const auto r = test::run_app("polygonize", field.string() + " -o " + out.string() + " --method " + method + " " + size +
                                                   " --level 1.44");
    ASSERT_EQ(r.exit_code, 0) << method << ": " << r.err;
    const Mesh mesh = read_mesh(out);
    ASSERT_GT(mesh.num_triangles(), 100u) << method;
    // Adaptive vertices are projected onto the surface (STL keeps floats); marching's are
    // interpolated linearly along cell edges of 0.1, where r^2 bends: ~h^2/8 F''/F' = 1e-3.
    const double within = method == "adaptive" ? 1e-5 : 2e-3;
    for (const Vec3& p : mesh.positions) EXPECT_NEAR(p.norm(), 1.2, within) << method;
    EXPECT_TRUE(analyze_topology(mesh).closed()) << method;
  }
}

TEST(PolygonizeApp, AdaptiveKeepsTheInnerSphereOfAHollowBallAndSaysNothingIsUncovered) {
  // The case that lost its inner sphere with exit 0 (robustness issue): the program's mesh has
  // both spheres, and its stats say every sign change of the seed grid was meshed.
  test::TempDir dir("polygonize_app_hollow");
  const auto field = dir.write("hollow.json", R"J({"type": "expression",
      "value": "max(sqrt(x^2+y^2+z^2)-1.25, 0.75-sqrt(x^2+y^2+z^2))", "bounds": [[-2,-2,-2],[2,2,2]]})J");
  const auto r = test::run_app("polygonize", field.string() + " -o " + (dir.path / "out.ply").string() +
                                                 " --factor 1 --stats " + (dir.path / "stats.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const MeshTopology t = analyze_topology(read_mesh(dir.path / "out.ply"));
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, 2u);
  const auto stats = read_json(dir.path / "stats.json");
  EXPECT_EQ(stats["components"].get<int>(), 2);
  EXPECT_EQ(stats["seeds"].get<int>(), 2);
  EXPECT_EQ(stats["uncovered_crossings"].get<int>(), 0);
  EXPECT_GT(stats["sign_changes"].get<int>(), 0);
}

TEST(PolygonizeApp, AToleranceTheMeshCannotKeepIsAOneLineWarningNamingWhere) {
  // --min-edge 0.05 keeps the refinement from splitting the unit sphere's triangles down to a
  // distance of 1e-5: the mesh is written (closed and valid), and the broken promise is said on
  // one line with the count, the worst distance and a place; a tolerance the mesh keeps says
  // nothing.
  test::TempDir dir("polygonize_app_over_tolerance");
  const auto field = dir.write("sphere.json", R"({"type": "sphere", "radius": 1})");
  const auto out = dir.path / "out.ply", stats = dir.path / "stats.json";
  const auto r = test::run_app("polygonize", field.string() + " -o " + out.string() +
                                                 " --quiet --tolerance 1e-5 --min-edge 0.05 --stats " + stats.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(analyze_topology(read_mesh(out)).watertight());
  const auto s = read_json(stats);
  const std::size_t over = s["quality"]["over_tolerance"].get<std::size_t>();
  EXPECT_GT(over, 0u);
  // Each counted triangle was measured densely and found farther than the tolerance: the worst
  // distance the line names exceeds it.
  EXPECT_GE(s["quality"]["measured_densely"].get<std::size_t>(), over);
  EXPECT_GT(s["quality"]["over_tolerance_worst"].get<double>(), 1e-5);
  EXPECT_NE(r.err.find("polygonize: " + field.string() + ": warning: " + std::to_string(over) +
                       " triangles lie farther from the surface than the tolerance 1e-05 (up to "),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find(", near ("), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;

  const auto kept = test::run_app("polygonize", field.string() + " -o " + out.string() + " --quiet --tolerance 1e-2");
  ASSERT_EQ(kept.exit_code, 0) << kept.err;
  EXPECT_EQ(kept.err, "");
}

TEST(PolygonizeApp, CreasesItCouldNotFollowAreAOneLineWarningSayingWhy) {
  // A ball capped by a sheet whose crease fades out where its pieces become tangent (the model of
  // AdaptiveCreases.ALayoutThatFailsFallsBackToSmoothMeshingAndSaysWhy): the layout fails, the
  // surface is meshed across the crease as smooth and written, and that is said on one line with
  // the reason STATS.json gives; with --creases ignore, asked for, nothing is said.
  test::TempDir dir("polygonize_app_creases_not_followed");
  const auto field = dir.write(
      "ball_sheet.json",
      R"json({"type": "expression", "value": "max(max(z, z+x*abs(y)), sqrt(x^2+y^2+z^2)-1)",
              "bounds": [[-1.5, -1.5, -1.5], [1.5, 1.5, 1.5]]})json");
  const auto out = dir.path / "out.ply", stats = dir.path / "stats.json";
  const auto r = test::run_app("polygonize", field.string() + " -o " + out.string() + " --quiet --factor 1 --stats " +
                                                 stats.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(analyze_topology(read_mesh(out)).watertight());
  const auto s = read_json(stats);
  ASSERT_FALSE(s["creases"]["followed"].get<bool>());
  const std::string why = s["creases"]["fallback"].get<std::string>();
  ASSERT_NE(why, "");
  EXPECT_EQ(r.err, "polygonize: " + field.string() +
                       ": warning: the creases are not followed, the surface is meshed across them as smooth (" + why +
                       ")\n");

  const auto ignored =
      test::run_app("polygonize", field.string() + " -o " + out.string() + " --quiet --factor 1 --creases ignore");
  ASSERT_EQ(ignored.exit_code, 0) << ignored.err;
  EXPECT_EQ(ignored.err, "");
}

TEST(PolygonizeApp, AChordDeviationIsASizingNotAPromise) {
  // --chord sizes as --tolerance does and measures nothing: the run that --tolerance warns about
  // above writes its mesh silently, with the sizing named in the statistics and no triangle
  // measured.
  test::TempDir dir("polygonize_app_chord");
  const auto field = dir.write("sphere.json", R"({"type": "sphere", "radius": 1})");
  const auto out = dir.path / "out.ply", stats = dir.path / "stats.json";
  const auto r = test::run_app("polygonize", field.string() + " -o " + out.string() +
                                                 " --quiet --chord 1e-5 --min-edge 0.05 --stats " + stats.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_TRUE(analyze_topology(read_mesh(out)).watertight());
  const auto s = read_json(stats);
  EXPECT_EQ(s["sizing"], "chord");
  EXPECT_EQ(s["tolerance"].get<double>(), 1e-5);
  EXPECT_FALSE(s["tolerance_refinement"].get<bool>());
  EXPECT_EQ(s["quality"]["measured_densely"].get<std::size_t>(), 0u);
  EXPECT_EQ(s["quality"]["over_tolerance"].get<std::size_t>(), 0u);
}

TEST(PolygonizeApp, AdaptiveRunThatCannotFinishIsAnErrorWithoutOutput) {
  // A run stopped by a bound: a one-line error, no mesh file and no stats file.
  test::TempDir dir("polygonize_app_limit");
  const auto field = dir.write("torus.json", kTorus);
  const auto out = dir.path / "out.ply", stats = dir.path / "stats.json";
  const auto r = test::run_app("polygonize", field.string() + " -o " + out.string() + " --factor 3 --max-triangles 50 "
                                             "--stats " + stats.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("polygonize: " + field.string() + ": adaptive: "), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_FALSE(std::filesystem::exists(stats));
}

std::string read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST_P(PolygonizeApp, RepeatReportsTheRunOfMedianTimeAndTheSameMesh) {
  // --repeat N times the method N times on one field (claims on time compare medians, not one
  // run that the machine's other work may have slowed): the mesh is the one run's, byte for
  // byte; STATS.json keeps every run's time, its `seconds` is their median and its counts are
  // the one run's.
  const std::string method = GetParam();
  test::TempDir dir("polygonize_app_repeat_" + method);
  const auto field = dir.write("torus.json", kTorus);
  const std::string common = field.string() + " --method " + method + (method == "adaptive" ? " --factor 2" : " --cell 0.1");
  const auto once = test::run_app("polygonize", common + " -o " + (dir.path / "once.ply").string() + " --stats " +
                                                    (dir.path / "once.json").string());
  ASSERT_EQ(once.exit_code, 0) << once.err;
  const auto thrice = test::run_app("polygonize", common + " -o " + (dir.path / "thrice.ply").string() + " --repeat 3 --stats " +
                                                      (dir.path / "thrice.json").string());
  ASSERT_EQ(thrice.exit_code, 0) << thrice.err;
  EXPECT_EQ(read_bytes(dir.path / "once.ply"), read_bytes(dir.path / "thrice.ply"));
  const auto a = read_json(dir.path / "once.json"), b = read_json(dir.path / "thrice.json");
  EXPECT_FALSE(a.contains("repeat_seconds"));
  ASSERT_TRUE(b.contains("repeat_seconds"));
  std::vector<double> times = b["repeat_seconds"].get<std::vector<double>>();
  ASSERT_EQ(times.size(), 3u);
  std::sort(times.begin(), times.end());
  EXPECT_EQ(b["seconds"].get<double>(), times[1]);
  EXPECT_EQ(a["field_evaluations"], b["field_evaluations"]);
  EXPECT_EQ(a["triangles"], b["triangles"]);
}

TEST(PolygonizeAppErrors, BadArgumentsAndFieldsGiveAOneLineErrorAndNoOutput) {
  test::TempDir dir("polygonize_app_errors");
  const auto torus = dir.write("torus.json", kTorus);
  const auto typo = dir.write("typo.json", R"({"type": "torus", "major_radius": 1, "minor_raduis": 0.4})");
  const auto nan = dir.write("nan.json", R"J({"type": "expression", "value": "sqrt(-1 - x*x)", "bounds": [[-1,-1,-1],[1,1,1]]})J");
  const auto empty = dir.write("empty.json", R"({"type": "sphere", "radius": 1, "bounds": [[5,5,5],[6,6,6]]})");
  const std::string out = (dir.path / "out.ply").string();
  struct Case {
    std::string args, expected;
  };
  const std::vector<Case> cases = {
      {torus.string() + " -o " + out + " --method marching", "--method: marching not in {adaptive,mc,mt}"},
      {torus.string() + " -o " + out + " --cell 0.1", "--cell does not apply"},
      {torus.string() + " -o " + out + " --method mc --factor 2", "--factor does not apply"},
      {torus.string() + " -o " + out + " --factor two", "--factor: expects a positive number, found \"two\""},
      {torus.string() + " -o " + out + " --factor 2 --tolerance 0.01", "--factor excludes --tolerance"},
      {torus.string() + " -o " + out + " --chord 0.01 --tolerance 0.01", "--tolerance excludes --chord"},
      {torus.string() + " -o " + out + " --chord 0.01 --factor 2", "--factor excludes --chord"},
      {torus.string() + " -o " + out + " --chord 0", "--chord: expects a positive number"},
      {torus.string() + " -o " + out + " --method mc --chord 0.01", "--chord does not apply"},
      {torus.string() + " -o " + out + " --method mt --precision 3", "precision"},
      {torus.string() + " -o " + (dir.path / "out.dae").string(), ".ply, .obj, .off or .stl"},
      {torus.string() + " -o " + out + " --level nan", "--level: expects a number"},
      {(dir.path / "missing.json").string() + " -o " + out, "missing.json"},
      {typo.string() + " -o " + out, "minor_raduis"},
      {nan.string() + " -o " + out, ""},
      {empty.string() + " -o " + out, ""},
      {torus.string(), "--output is required"},
      {torus.string() + " -o " + out + " --repeat 0", "--repeat: expects an integer between 1 and 100"},
      {torus.string() + " -o " + out + " --repeat 101", "--repeat: expects an integer between 1 and 100"},
  };
  for (const auto& c : cases) {
    const auto r = test::run_app("polygonize", c.args);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.err.find("polygonize: "), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_LE(std::count(r.err.begin(), r.err.end(), '\n'), 6) << r.err;  // usage lines at most
    EXPECT_FALSE(std::filesystem::exists(out)) << c.args;
  }
}

}  // namespace
}  // namespace cdp
