// build/bin/evaluate measures a mesh against its field, and refuses meshes it cannot measure
// with one line naming the mesh file, exit code 1 and no metrics file.
#include <gtest/gtest.h>

#include <algorithm>

#include "common/reference_meshes.h"

#include <cdp/io/mesh_io.h>

#include <nlohmann/json.hpp>

#include "common/run_command.h"

#include <filesystem>
#include <fstream>

namespace cdp {
namespace {

constexpr const char* kFewRays = " --rays 8 --views 2 --samples 100";

struct EvaluateApp : public ::testing::Test {
  test::TempDir dir{"evaluate_app"};
  std::filesystem::path field = dir.write("sphere.json", R"({"type": "sphere", "radius": 1})");
  std::filesystem::path metrics = dir.path / "metrics.json";
  std::string args(const std::filesystem::path& mesh) const {
    return field.string() + " " + mesh.string() + " -o " + metrics.string() + kFewRays;
  }
  void expect_refused(const std::filesystem::path& mesh, const std::string& message) const {
    const auto r = test::run_app("evaluate", args(mesh));
    EXPECT_EQ(r.exit_code, 1) << mesh;
    // "evaluate: MESH: problem" or, from the text formats, "evaluate: MESH:LINE: problem".
    EXPECT_EQ(r.err.rfind("evaluate: " + mesh.string() + ":", 0), 0u) << r.err;
    EXPECT_EQ(r.err.size() - r.err.find(message), message.size() + 1) << "ends with the message: " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_FALSE(std::filesystem::exists(metrics)) << mesh;
  }
};

TEST_F(EvaluateApp, IcosphereOfTheSphereHasSmallErrors) {
  const auto mesh = dir.path / "ico.ply";
  write_mesh(icosphere(3), mesh);
  const auto r = test::run_app("evaluate", args(mesh));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(metrics);
  const auto j = nlohmann::json::parse(in);
  EXPECT_GT(j["depth_error"]["count"].get<int>(), 0);
  EXPECT_LT(j["depth_error"]["mean"].get<double>(), 0.01);
}

TEST_F(EvaluateApp, MeshThatNoRayHitsIsAnErrorNotAPerfectScore) {
  const auto mesh = dir.path / "far.ply";
  write_mesh(icosphere(1, Vec3(10, 10, 10)), mesh);
  expect_refused(mesh, "no ray hits the mesh (28 of 128 rays hit the surface)");
}

// These were all scored as perfect (0 triangles read), with OpenMesh's own lines on stderr, or
// ended in std::bad_alloc. read_mesh's other refusals: tests/polygonizer/mesh_io_test.cpp.
TEST_F(EvaluateApp, BrokenMeshFilesGiveOneLineNamingTheFile) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 1000000000000\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n";
  const struct {
    std::string file, text, message;
  } cases[] = {
      {"garbage.obj", "not a mesh at all\n", "1: unknown OBJ statement \"not\""},
      {"nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "vertex 0 has a coordinate that is not a finite number"},
      {"index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n", "6: a face refers to vertex \"9\" of 3"},
      {"huge.ply", ply, "the header declares 1000000000000 vertex records but the file is too short for them"},
  };
  for (const auto& c : cases) expect_refused(dir.write(c.file, c.text), c.message);
}

// Both aborted on an Embree assertion (NaN rays; rays starting beyond Embree's float range).
TEST_F(EvaluateApp, FieldsTooLargeForTheRaysAreErrors) {
  const auto mesh = dir.path / "ico.ply";
  write_mesh(icosphere(1), mesh);
  const auto huge = dir.write("huge.json", R"({"type": "sphere", "radius": 1e160})");
  const auto large = dir.write("large.json", R"({"type": "sphere", "radius": 1e18})");
  const struct {
    std::filesystem::path field;
    std::string message;
  } cases[] = {
      {huge, huge.string() + ": camera: the field's box is too large for double precision (its diagonal overflows)"},
      {large, mesh.string() + ": EmbreeScene: ray 0 is not finite or starts more than 1e18 half-diagonals of the "
                              "mesh from its centre, out of Embree's float range"},
  };
  for (const auto& c : cases) {
    const auto r = test::run_app("evaluate", c.field.string() + " " + mesh.string() + " -o " + metrics.string() + kFewRays);
    EXPECT_EQ(r.exit_code, 1) << c.field;
    EXPECT_EQ(r.err, "evaluate: " + c.message + "\n");
    EXPECT_FALSE(std::filesystem::exists(metrics));
  }
}

// A mesh without normals (another tool's OBJ) is judged with the field's normals by default,
// so that the Phong error measures the mesh rather than a normal estimator; each choice is
// named in metrics.json.
TEST_F(EvaluateApp, NormalsComeFromTheFileTheFieldOrTheMesh) {
  Mesh ico = icosphere(2);
  const auto with = dir.path / "with.ply";
  write_mesh(ico, with);
  ico.normals.clear();
  const auto without = dir.path / "without.obj";
  write_mesh(ico, without);
  const auto normals = [&](const std::filesystem::path& mesh, const std::string& flag) {
    const auto r = test::run_app("evaluate", args(mesh) + flag);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(metrics);
    const auto j = nlohmann::json::parse(in);
    std::filesystem::remove(metrics);
    return std::make_pair(j["normals"].get<std::string>(), j["phong_error_deg"]["mean"].get<double>());
  };
  EXPECT_EQ(normals(with, "").first, "file");
  const auto [field_source, field_phong] = normals(without, "");
  EXPECT_EQ(field_source.rfind("field", 0), 0u) << field_source;
  const auto [mesh_source, mesh_phong] = normals(without, " --normals mesh");
  EXPECT_EQ(mesh_source.rfind("mesh", 0), 0u) << mesh_source;
  // On the icosphere of the unit sphere the field's normals are the file's (radial).
  EXPECT_NEAR(field_phong, normals(with, " --normals file").second, 1e-9);
  EXPECT_NE(field_phong, mesh_phong);
  const auto r = test::run_app("evaluate", args(without) + " --normals file");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err, "evaluate: " + without.string() + ": --normals file, but the mesh file has no vertex normals\n");
  EXPECT_FALSE(std::filesystem::exists(metrics));
}

}  // namespace
}  // namespace cdp
