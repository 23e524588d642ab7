// Mesh files through OpenMesh: round trips, and failures that leave nothing behind.
#include <gtest/gtest.h>

#include <polygonizer/errors.h>
#include <polygonizer/mesh_io.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

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

// A binary little-endian PLY of double vertices and int triangles; `declared` vertices in the header.
std::string binary_ply(const std::vector<Vec3>& vertices, const std::vector<std::array<int, 3>>& faces,
                       std::size_t declared) {
  std::string s = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(declared) +
                  "\nproperty double x\nproperty double y\nproperty double z\nelement face " +
                  std::to_string(faces.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  auto put = [&s](const void* p, std::size_t n) { s.append(static_cast<const char*>(p), n); };
  for (const Vec3& v : vertices) put(v.data(), 3 * sizeof(double));
  for (const auto& f : faces) {
    const unsigned char three = 3;
    put(&three, 1);
    put(f.data(), 3 * sizeof(int));
  }
  return s;
}

// Each file once gave a smaller or empty mesh (read as a perfect one by evaluate), a stray
// OpenMesh line on stderr, or std::bad_alloc; each is now an error saying what is wrong.
TEST(MeshIOErrors, FilesThatCannotBeReadWholeAreRefusedWithTheProblemNamed) {
  const auto dir = std::filesystem::temp_directory_path() / ("cdp_mesh_io_bad_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Vec3> tri = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::string ply_header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string face_header = "element face %\nproperty list uchar int vertex_indices\nend_header\n";
  auto faces = [&](int n) { return face_header.substr(0, 13) + std::to_string(n) + face_header.substr(14); };
  const struct {
    std::string file, text, message;
  } cases[] = {
      {"garbage.obj", "this is not a mesh\n", "the mesh has no triangles"},
      {"garbage.off", "garbage garbage\n", "cannot read mesh (unsupported or malformed file)"},
      {"nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "line 2: \"nan\" is not a finite number"},
      {"inf.off", "OFF\n3 1 0\n0 0 0\n1e999 0 0\n0 1 0\n3 0 1 2\n", "line 4: \"1e999\" is not a finite number"},
      {"nan.ply", binary_ply({{0, 0, 0}, {1, nan, 0}, {0, 1, 0}}, {{0, 1, 2}}, 3),
       "vertex 1 has a non-finite coordinate"},
      {"index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
       "a face has an out-of-range vertex index (the file has 3 vertices)"},
      {"index.ply", binary_ply(tri, {{0, 1, 2}, {0, 1, 5}}, 3),
       "1 face(s) with an out-of-range or repeated vertex index (the file has 3 vertices)"},
      {"points.ply", ply_header + "end_header\n0 0 0\n1 0 0\n0 1 0\n", "the mesh has no triangles"},
      {"header_only.ply", ply_header + faces(1),
       "the header declares 3 vertices and 1 faces, which need at least 13 numbers, but the file holds only 0"},
      {"truncated.ply", ply_header + faces(2) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
       "the header declares 3 vertices and 2 faces, which need at least 17 numbers, but the file holds only 13"},
      {"huge.ply", binary_ply(tri, {{0, 1, 2}}, 1000000000000),
       "the header declares 1000000000000 vertices and 1 faces, which need at least 24000000000013 bytes, but the "
       "file holds only 85"},
  };
  for (const auto& c : cases) {
    const auto path = dir / c.file;
    std::ofstream(path, std::ios::binary) << c.text;
    testing::internal::CaptureStderr();
    try {
      (void)read_mesh(path);
      ADD_FAILURE() << c.file << " was read";
    } catch (const InvalidInputError& e) {
      EXPECT_EQ(std::string(e.what()), path.string() + ": " + c.message);
    }
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "") << c.file << ": OpenMesh's messages stay out of stderr";
  }
  // The same data, whole, reads.
  std::ofstream(dir / "whole.ply", std::ios::binary) << binary_ply(tri, {{0, 1, 2}}, 3);
  EXPECT_EQ(read_mesh(dir / "whole.ply").triangles.size(), 1u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace cdp
