// build/bin/experiment end to end on a tiny sweep: every run polygonized and evaluated, the
// per-run files and the summary written with plausible numbers; a failing run reported, not
// dropped; bad experiment files refused with the key named; two runs give the same meshes.
#include <gtest/gtest.h>

#include <cdp/io/mesh_io.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "apps/app_files.h"
#include "common/run_command.h"

namespace cdp {
namespace {

namespace fs = std::filesystem;

using test::read_json;

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

constexpr const char* kSweep = R"({
  "description": "tiny torus sweep for the tests",
  "field": {"type": "torus", "major_radius": 1, "minor_radius": 0.4},
  "seed": 3,
  "runs": [
    {"method": "adaptive", "factor": [2, 4]},
    {"method": "mt", "cell": 0.1},
    {"method": "mc", "cell": 0.1, "traversal": "grid"},
    {"method": "adaptive", "factor": 3, "max_edge": 0.001, "label": "impossible"}
  ],
  "evaluation": {"views": 2, "resolution": 24, "projection": "orthographic"},
  "keep_meshes": true
})";

TEST(ExperimentApp, TinySweepWritesRunsAndSummary) {
  test::TempDir dir("experiment_app");
  const auto file = dir.write("tiny.json", kSweep);
  const fs::path out = dir.path / "out";
  const auto r = test::run_app("experiment", file.string() + " --out " + out.string() + " --jobs 2");
  // One run is meant to fail (max_edge below the default min_edge): the experiment completes
  // (the failure is a result, reported in the summary), says so, and exits with status 2.
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("5 runs, 1 failed"), std::string::npos) << r.err;
  ASSERT_TRUE(fs::exists(out / "summary.json")) << r.err;
  ASSERT_TRUE(fs::exists(out / "summary.csv"));
  const auto summary = read_json(out / "summary.json");
  ASSERT_EQ(summary["runs"].size(), 5u);
  std::map<std::string, nlohmann::json> runs;
  for (const auto& run : summary["runs"]) runs[run["id"]] = run;
  for (const std::string id : {"adaptive_factor2", "adaptive_factor4", "mt_cell0.1", "mc_cell0.1"}) {
    SCOPED_TRACE(id);
    ASSERT_TRUE(runs.count(id)) << summary.dump(1);
    const auto& run = runs[id];
    EXPECT_EQ(run["status"], "ok") << run.value("reason", "");
    EXPECT_TRUE(fs::exists(out / "meshes" / (id + ".ply")));
    EXPECT_TRUE(fs::exists(out / "runs" / id / "stats.json"));
    EXPECT_TRUE(fs::exists(out / "runs" / id / "metrics.json"));
    const auto& m = run["metrics"];
    EXPECT_TRUE(m["topology"]["closed"].get<bool>());
    EXPECT_EQ(m["topology"]["genus"].get<int>(), 1);
    // A torus of minor radius 0.4 meshed this finely: depth errors far below the radius,
    // Phong errors of a few degrees at most.
    EXPECT_LT(m["depth_error"]["mean"].get<double>(), 0.02);
    EXPECT_LT(m["phong_error_deg"]["mean"].get<double>(), 10.0);
    EXPECT_GT(run["stats"]["triangles"].get<int>(), 100);
  }
  // The adaptive method's edge ratio is the point of the paper: well under MT's.
  EXPECT_LT(runs["adaptive_factor4"]["metrics"]["edge_ratio"]["mean"].get<double>(), 1.5);
  EXPECT_GT(runs["mt_cell0.1"]["metrics"]["edge_ratio"]["mean"].get<double>(),
            runs["adaptive_factor4"]["metrics"]["edge_ratio"]["mean"].get<double>());
  // More triangles at the higher factor, and a lower depth error.
  EXPECT_GT(runs["adaptive_factor4"]["stats"]["triangles"].get<int>(), runs["adaptive_factor2"]["stats"]["triangles"].get<int>());
  // The impossible run is reported with its reason.
  const auto& bad = runs["adaptive_impossible_factor3"];
  EXPECT_EQ(bad["status"], "failed");
  EXPECT_NE(bad["reason"].get<std::string>().find("min_edge"), std::string::npos) << bad.dump();
  const std::string csv = read_text(out / "summary.csv");
  EXPECT_NE(csv.find("adaptive_impossible_factor3,adaptive,factor,3,failed"), std::string::npos) << csv;

  // A second run of the same file gives the same meshes, byte for byte.
  const fs::path out2 = dir.path / "out2";
  test::run_app("experiment", file.string() + " --out " + out2.string() + " --jobs 1");
  for (const std::string id : {"adaptive_factor2", "mt_cell0.1"})
    EXPECT_EQ(read_text(out / "meshes" / (id + ".ply")), read_text(out2 / "meshes" / (id + ".ply"))) << id;
}

TEST(ExperimentApp, RepeatsTimeEveryRunSeveralTimesEachPolygonizationAlone) {
  // "repeats": each run's polygonize gets --repeat, and its stats keep every time, the median
  // being the run's `seconds`. The polygonizations are timed with the machine to themselves:
  // with two jobs, no other step of the experiment runs while one does (status.json's steps).
  test::TempDir dir("experiment_app_repeats");
  const auto file = dir.write("tiny.json", R"({"field": {"type": "torus", "major_radius": 1, "minor_radius": 0.4},
      "repeats": 3, "runs": [{"method": "adaptive", "factor": [2, 3]}, {"method": "mt", "cell": [0.1, 0.08]}],
      "evaluation": {"views": 2, "resolution": 48}})");
  const fs::path out = dir.path / "out";
  const auto r = test::run_app("experiment", file.string() + " --out " + out.string() + " --jobs 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto summary = read_json(out / "summary.json");
  ASSERT_EQ(summary["runs"].size(), 4u);
  struct Step {
    std::string id, name;
    double start, end;
  };
  std::vector<Step> steps;
  for (const auto& run : summary["runs"]) {
    ASSERT_TRUE(run["stats"].contains("repeat_seconds")) << run.dump();
    std::vector<double> times = run["stats"]["repeat_seconds"].get<std::vector<double>>();
    ASSERT_EQ(times.size(), 3u);
    std::sort(times.begin(), times.end());
    EXPECT_EQ(run["stats"]["seconds"].get<double>(), times[1]);
    const auto status = read_json(out / "runs" / run["id"].get<std::string>() / "status.json");
    for (const std::string name : {"polygonize", "evaluate"}) {
      ASSERT_TRUE(status["steps"].contains(name)) << status.dump();
      steps.push_back({run["id"], name, status["steps"][name]["start"], status["steps"][name]["end"]});
      EXPECT_LE(steps.back().start, steps.back().end);
    }
  }
  for (const Step& a : steps) {
    for (const Step& b : steps) {
      if (a.name != "polygonize" || &a == &b) continue;
      EXPECT_TRUE(a.end <= b.start || b.end <= a.start)
          << a.id << " polygonize [" << a.start << ", " << a.end << "] overlaps " << b.id << " " << b.name << " ["
          << b.start << ", " << b.end << "]";
    }
  }
}

TEST(ExperimentApp, BadExperimentFilesAreRefusedWithTheKeyNamed) {
  test::TempDir dir("experiment_app_bad");
  struct Case {
    std::string json, expected;
  };
  const std::vector<Case> cases = {
      {R"({"field": {"type": "sphere", "radius": 1}, "runs": [{"method": "adaptive", "factr": 2}]})", "factr"},
      {R"({"field": {"type": "sphere", "radius": 1}, "runs": [{"method": "bogus", "factor": 2}]})", "method"},
      {R"({"field": {"type": "sphere", "radius": 1}, "runs": [], "evalutaion": {}})", "evalutaion"},
      {R"({"field": "missing_field.json", "runs": [{"method": "adaptive", "factor": 2}]})", "missing_field.json"},
      {R"({"field": {"type": "sphere", "radius": 1}, "runs": [{"method": "mt", "cell": 0.1, "factor": 2}]})", "factor"},
      {R"({"field": {"type": "sphere", "radius": 1}, "runs": [{"method": "mt", "cell": 0.1, "chord": 0.01}]})", "chord"},
      {R"({"field": {"type": "sphere", "radius": 1}, "runs": [{"method": "adaptive", "factor": 2, "chord": 0.01}]})",
       "give either \"factor\" or \"chord\", not both"},
      {R"({"field": {"type": "sphere", "radius": 1}, "runs": [{"method": "adaptive"}]})",
       "needs \"factor\", \"tolerance\" or \"chord\""},
      {R"({"field": {"type": "sphere", "radius": 1}, "runs": [)", "tiny.json"},
      {R"({"field": {"type": "sphere", "radius": 1}, "repeats": 0, "runs": [{"method": "adaptive", "factor": 2}]})",
       "repeats"},
      {R"({"field": {"type": "sphere", "radius": 1}, "repeats": 101, "runs": [{"method": "adaptive", "factor": 2}]})",
       "repeats"},
  };
  for (const auto& c : cases) {
    const auto file = dir.write("tiny.json", c.json);
    const fs::path out = dir.path / "out";
    const auto r = test::run_app("experiment", file.string() + " --out " + out.string());
    EXPECT_NE(r.exit_code, 0) << c.json;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.json << "\n" << r.err;
    EXPECT_FALSE(fs::exists(out / "summary.json")) << c.json;
  }
}

TEST(ExperimentApp, AChordSweepRunsTheChordSizingBesideTheTolerance) {
  // "chord" is a third sweep key of the adaptive method: polygonize --chord, the run named and
  // summarized by it, apart from the tolerance's runs at the same values.
  test::TempDir dir("experiment_app_chord");
  const auto file = dir.write("chord.json", R"({"field": {"type": "sphere", "radius": 1},
      "runs": [{"method": "adaptive", "chord": [0.01, 0.003]}, {"method": "adaptive", "tolerance": 0.01}],
      "evaluation": {"views": 2, "resolution": 24}})");
  const fs::path out = dir.path / "out";
  const auto r = test::run_app("experiment", file.string() + " --out " + out.string() + " --jobs 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto summary = read_json(out / "summary.json");
  std::map<std::string, nlohmann::json> runs;
  for (const auto& run : summary["runs"]) runs[run["id"]] = run;
  ASSERT_EQ(runs.size(), 3u) << summary.dump(1);
  for (const std::string id : {"adaptive_chord0.01", "adaptive_chord0.003", "adaptive_tolerance0.01"}) {
    SCOPED_TRACE(id);
    ASSERT_TRUE(runs.count(id)) << summary.dump(1);
    const auto& run = runs[id];
    EXPECT_EQ(run["status"], "ok") << run.value("reason", "");
    const std::string mode = id.find("chord") != std::string::npos ? "chord" : "tolerance";
    EXPECT_EQ(run["parameter_name"], mode);
    EXPECT_EQ(run["stats"]["sizing"], mode);
    EXPECT_EQ(run["metrics"]["topology"]["genus"].get<int>(), 0);
  }
  // The smaller deviation asks for shorter edges; chord 0.01 measures nothing that tolerance
  // 0.01 measures and splits, and sizes for 0.01 where the tolerance sizes for a share of it.
  EXPECT_GT(runs["adaptive_chord0.003"]["stats"]["triangles"].get<int>(),
            runs["adaptive_chord0.01"]["stats"]["triangles"].get<int>());
  EXPECT_LT(runs["adaptive_chord0.01"]["stats"]["triangles"].get<int>(),
            runs["adaptive_tolerance0.01"]["stats"]["triangles"].get<int>());
}

TEST(ExperimentApp, FailedRunsMakeANonZeroExitAndReadOnlyModesWriteNothing) {
  test::TempDir dir("experiment_app_status");
  const auto file = dir.write("doomed.json", R"({"field": {"type": "sphere", "radius": 1},
    "runs": [{"method": "adaptive", "factor": [2, 3], "max_edge": 0.0001}],
    "evaluation": {"views": 1, "resolution": 8}})");
  const fs::path out = dir.path / "out";
  for (const std::string mode : {"--list", "--commands", "--run nope"}) {
    const auto r = test::run_app("experiment", file.string() + " --out " + out.string() + " " + mode);
    EXPECT_EQ(r.exit_code, mode == "--run nope" ? 1 : 0) << mode << r.err;
    EXPECT_FALSE(fs::exists(out)) << mode << " wrote " << out;
  }
  // Every run fails: the tables list the failures, and the exit status says so.
  const auto r = test::run_app("experiment", file.string() + " --out " + out.string() + " --jobs 1");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("2 runs, 2 failed"), std::string::npos) << r.err;
  EXPECT_NE(read_text(out / "summary.csv").find(",failed,"), std::string::npos);
  EXPECT_EQ(test::run_app("experiment", file.string() + " --out " + out.string() + " --summarize").exit_code, 2);
  EXPECT_EQ(test::run_app("experiment", file.string() + " --out " + out.string() + " --run adaptive_factor2").exit_code, 2);
}

TEST(ExperimentApp, OptionsGivenTwiceOrTwoModesAreErrors) {
  test::TempDir dir("experiment_app_options");
  const auto file = dir.write("e.json", R"({"field": {"type": "sphere", "radius": 1}, "runs": [{"method": "mt", "cell": 0.2}]})");
  for (const auto& [args, expected] : std::vector<std::pair<std::string, std::string>>{
           {"--out a --out b --list", "--out given twice"},
           {"--list --commands", "--list excludes --commands"},
           {"--summarize --run x", "--run excludes --summarize"},
           {"--jobs 1 --jobs 2 --list", "--jobs given twice"}}) {
    const auto r = test::run_app("experiment", file.string() + " " + args);
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_EQ(r.err, "experiment: " + expected + "\n") << args;
  }
}

TEST(ExperimentApp, LabelsCannotNamePathsOutsideTheOutputFolder) {
  test::TempDir dir("experiment_app_labels");
  const fs::path out = dir.path / "a" / "b" / "out";
  for (const std::string label : {"../../../elsewhere/X", "/tmp/X", "..", ".hidden", "a b", "x/y"}) {
    const auto file = dir.write("labels.json", R"({"field": {"type": "sphere", "radius": 1},
      "runs": [{"method": "mt", "cell": 0.2, "label": ")" + label + R"("}], "evaluation": {"views": 1, "resolution": 8}})");
    const auto r = test::run_app("experiment", file.string() + " --out " + out.string());
    EXPECT_EQ(r.exit_code, 1) << label;
    EXPECT_NE(r.err.find("label"), std::string::npos) << label << "\n" << r.err;
    EXPECT_FALSE(fs::exists(dir.path / "a")) << label;
    EXPECT_FALSE(fs::exists(dir.path / "elsewhere")) << label;
  }
  // A plain label is fine.
  const auto file = dir.write("labels.json", R"({"field": {"type": "sphere", "radius": 1},
    "runs": [{"method": "mt", "cell": 0.2, "label": "coarse-1.5"}], "evaluation": {"views": 1, "resolution": 8}})");
  EXPECT_EQ(test::run_app("experiment", file.string() + " --out " + out.string() + " --list").out, "mt_coarse-1.5_cell0.2\n");
}

}  // namespace
}  // namespace cdp
