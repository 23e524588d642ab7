// Mesh files through OpenMesh: round trips, and failures that leave nothing behind.
#include <gtest/gtest.h>

#include <polygonizer/errors.h>
#include <polygonizer/mesh_io.h>

#include <filesystem>

namespace cdp {
namespace {

Mesh tetrahedron_with_normals() {
  Mesh m;
  m.positions = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  m.triangles = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  for (const auto& p : m.positions) m.normals.push_back(p.normalized());
  m.vertex_scalars["mac"] = {1, 2, 3, 4};
  return m;
}

class MeshIO : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("cdp_mesh_io_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

TEST_P(MeshIO, RoundTripKeepsPositionsTrianglesAndNormals) {
  const Mesh m = tetrahedron_with_normals();
  const auto path = dir_ / ("tet." + GetParam());
  write_mesh(m, path);
  const Mesh r = read_mesh(path);
  ASSERT_EQ(r.positions.size(), 4u);
  ASSERT_EQ(r.triangles.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_LT((r.positions[i] - m.positions[i]).norm(), 1e-6);
  EXPECT_EQ(r.triangles, m.triangles);
  if (GetParam() != "off") {  // OpenMesh's OFF reader drops normals
    ASSERT_EQ(r.normals.size(), 4u);
    for (int i = 0; i < 4; ++i) EXPECT_LT((r.normals[i] - m.normals[i]).norm(), 1e-6);
  }
  // Only the file itself is left in the folder: the temporary was renamed.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir_), {}), 1);
}

INSTANTIATE_TEST_SUITE_P(Formats, MeshIO, ::testing::Values("ply", "obj", "off"));

TEST(MeshIOErrors, MissingFileAndUnknownFormatAreNamed) {
  try {
    read_mesh("/nonexistent/mesh.ply");
    FAIL();
  } catch (const InvalidInputError& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/mesh.ply: file not found");
  }
  const auto dir = std::filesystem::temp_directory_path() / ("cdp_mesh_io_err_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  EXPECT_THROW(write_mesh(tetrahedron_with_normals(), dir / "mesh.xyz123"), InvalidInputError);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 0) << "no half-written file";
  std::filesystem::remove_all(dir);
}

// Only PLY stores named vertex properties; binary and ASCII files keep them exactly.
TEST(MeshIOScalars, PlyKeepsVertexScalars) {
  const auto dir = std::filesystem::temp_directory_path() / ("cdp_mesh_io_scalars_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  Mesh m = tetrahedron_with_normals();
  m.vertex_scalars["shape_index"] = {-1, -0.25, 0.5, 1};
  for (bool binary : {true, false}) {
    const auto path = dir / (binary ? "bin.ply" : "ascii.ply");
    write_mesh(m, path, binary);
    const Mesh r = read_mesh(path);
    EXPECT_EQ(r.vertex_scalars, m.vertex_scalars) << path;
  }
  std::filesystem::remove_all(dir);
}

TEST(MeshIOErrors, NonManifoldMeshIsRejectedByTheOpenMeshConversion) {
  Mesh m = tetrahedron_with_normals();
  m.positions.push_back({3, 0, 0});
  m.triangles.push_back({0, 1, 4});
  m.triangles.push_back({1, 0, 4});
  EXPECT_THROW(to_openmesh(m), InvalidInputError);
}

}  // namespace
}  // namespace cdp
