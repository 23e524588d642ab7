// Mesh files: exact round trips in double precision, readers that refuse malformed files with
// the file and the problem named, and failures that leave nothing behind.
#include <gtest/gtest.h>

#include <cdp/core/errors.h>
#include <cdp/io/atomic_write.h>
#include <cdp/io/mesh_io.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

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
  {
    ASSERT_EQ(r.normals.size(), 4u);
    for (int i = 0; i < 4; ++i) EXPECT_LT((r.normals[i] - m.normals[i]).norm(), 1e-6);
  }
  // Only the file itself is left in the folder: the temporary was renamed.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir_), {}), 1);
}

// A mesh whose file is many of the writers' pieces (a megabyte each): read back bit for bit,
// binary and ASCII, its scalars too.
TEST_P(MeshIO, ALargeMeshWrittenInPiecesReadsBackExactly) {
  Mesh m;
  constexpr int kSide = 250;  // a grid of 250 x 250 squares: 63,001 vertices, 125,000 triangles
  for (int j = 0; j <= kSide; ++j)
    for (int i = 0; i <= kSide; ++i) {
      m.positions.push_back(Vec3(i / 7.0, j / 3.0, std::sin(0.1 * i * j) / 9.0));
      m.normals.push_back(Vec3(std::cos(i * 0.3), std::sin(j * 0.7), 1).normalized());
    }
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) {
      const int a = j * (kSide + 1) + i, b = a + 1, c = a + kSide + 1, d = c + 1;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  std::vector<double> scalar(m.positions.size());
  for (std::size_t v = 0; v < scalar.size(); ++v) scalar[v] = std::exp(0.001 * static_cast<double>(v)) / 3;
  m.vertex_scalars["shape_index"] = scalar;
  for (const bool binary : {true, false}) {
    if (!binary && GetParam() != "ply") continue;  // the text formats have one kind
    const auto path = dir_ / ("grid." + GetParam());
    write_mesh(m, path, binary);
    ASSERT_GT(std::filesystem::file_size(path), 2u << 20) << "the file should take several pieces";
    const Mesh r = read_mesh(path);
    EXPECT_EQ(r.positions, m.positions);
    EXPECT_EQ(r.normals, m.normals);
    EXPECT_EQ(r.triangles, m.triangles);
    if (GetParam() == "ply") {
      EXPECT_EQ(r.vertex_scalars.at("shape_index"), scalar);
    }
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir_), {}), 1);
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, MeshIO, ::testing::Values("ply", "obj", "off"));

// Contents made in pieces: a producer that throws leaves the target as it was and no temporary.
TEST(AtomicWrite, AProducerThatThrowsLeavesTheTargetAndNoTemporary) {
  const auto dir = std::filesystem::temp_directory_path() / ("cdp_atomic_pieces_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const auto path = dir / "out.txt";
  write_file_atomically(path, [](const ByteSink& append) {
    append("first ");
    append("second");
  });
  EXPECT_THROW(write_file_atomically(path,
                                     [](const ByteSink& append) {
                                       append("partial");
                                       throw std::runtime_error("the producer failed");
                                     }),
               std::runtime_error);
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "first second");
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 1) << "a temporary left behind";
  std::filesystem::remove_all(dir);
}

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

// Coordinates far from the origin or tiny ones come back bit for bit in every format (they used
// to pass through float: a torus at 1e6 lost most of its triangles, a sphere of radius 1e-6
// most of its vertices).
TEST_P(MeshIO, RoundTripIsExactInDoublePrecision) {
  Mesh m = tetrahedron_with_normals();
  for (auto& p : m.positions) p = p * (1.0 / 3) + Vec3(1e6 + 1.0 / 7, -1e-300, 5e-7);
  m.positions[1] = {1e-6 / 3, std::nextafter(1e-6, 1.0), -std::numeric_limits<double>::denorm_min()};
  m.normals[2] = {std::sqrt(0.5), -std::sqrt(0.5), 1e-17};
  for (bool binary : {true, false}) {
    const auto path = dir_ / ("exact." + GetParam());
    write_mesh(m, path, binary);
    const Mesh r = read_mesh(path);
    EXPECT_EQ(r.positions, m.positions) << path << (binary ? " binary" : " ascii");
    EXPECT_EQ(r.normals, m.normals) << path;
    EXPECT_EQ(r.triangles, m.triangles) << path;
  }
}

TEST(MeshIOReaders, ForeignFilesAreReadWithPolygonsAsFans) {
  const auto dir = std::filesystem::temp_directory_path() / ("cdp_mesh_io_foreign_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name, std::ios::binary) << text;
    return dir / name;
  };
  // A unit square as one quad, in each format, with the usual extras: comments, colours,
  // texture coordinates, CRLF line ends, negative OBJ indices, a big-endian PLY with float
  // coordinates, an extra element and a uint count.
  const auto obj = write("quad.obj", "# a quad\r\nmtllib x.mtl\r\no quad\r\nv 0 0 0\r\nv 1 0 0\r\nv 1 1 0 0.5 0.5 0.5\r\n"
                                     "v 0 1 0\r\nvt 0 0\r\ns off\r\nf -4/1 -3/1 -2/1 -1/1\r\n");
  const auto off = write("quad.off", "OFF # comment\n4 1 4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3 255 0 0\n");
  std::string be = "ply\nformat binary_big_endian 1.0\ncomment big\nelement vertex 4\nproperty float x\n"
                   "property float y\nproperty float z\nproperty uchar red\nelement face 1\n"
                   "property list uint int vertex_indices\nelement extra 1\nproperty list uchar double data\nend_header\n";
  const auto put_be = [&](const void* p, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) be.push_back(static_cast<const char*>(p)[n - 1 - i]);
  };
  const float xyz[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  for (const auto& v : xyz) {
    for (float c : v) put_be(&c, 4);
    be.push_back(7);
  }
  const std::uint32_t four = 4;
  put_be(&four, 4);
  for (std::int32_t i = 0; i < 4; ++i) put_be(&i, 4);
  be.push_back(1);
  const double d = 2.5;
  put_be(&d, 8);
  const auto ply = write("quad.ply", be);
  for (const auto& path : {obj, off, ply}) {
    const Mesh r = read_mesh(path);
    ASSERT_EQ(r.positions.size(), 4u) << path;
    EXPECT_EQ(r.positions[2], Vec3(1, 1, 0)) << path;
    ASSERT_EQ(r.triangles.size(), 2u) << path;
    EXPECT_EQ(r.triangles[0], (std::array<int, 3>{0, 1, 2})) << path;
    EXPECT_EQ(r.triangles[1], (std::array<int, 3>{0, 2, 3})) << path;
  }
  EXPECT_EQ(read_mesh(ply).vertex_scalars.at("red"), (std::vector<double>{7, 7, 7, 7}));
  std::filesystem::remove_all(dir);
}

TEST(MeshIOReaders, MalformedFilesAreErrorsNamingTheFileAndTheProblem) {
  const auto dir = std::filesystem::temp_directory_path() / ("cdp_mesh_io_bad_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string ply_head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                               "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  struct Case {
    std::string name, text, expected;
  };
  const std::vector<Case> cases = {
      {"empty.ply", "", "not a PLY file"},
      {"noend.ply", "ply\nformat ascii 1.0\nelement vertex 3\n", "no end_header"},
      {"header.ply", "ply\nformat ascii 1.0\nend_header\n", "the mesh has no triangles"},
      {"noformat.ply", "ply\nelement vertex 0\nend_header\n", "no format line"},
      {"type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n", "unknown property type"},
      {"short.ply", ply_head + "0 0 0\n1 0 0\n", "too short for them"},
      {"ends.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1\n", "the data ends early (face 0)"},
      {"huge.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                   "property float y\nproperty float z\nend_header\nabc", "too short for them"},
      {"nan.ply", ply_head + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", "vertex 1 has a coordinate that is not a finite number"},
      {"index.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "face 0 refers to vertex 3 of 3"},
      {"negative.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", "refers to vertex -1"},
      {"word.ply", ply_head + "0 0 zero\n1 0 0\n0 1 0\n3 0 1 2\n", "\"zero\" is not a number (vertex 0)"},
      {"twoface.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "face 0 has 2 vertices"},
      {"garbage.obj", "\x01\x02\x03 garbage\n", "unknown OBJ statement"},
      {"nul.obj", std::string("v 0 0 0\0\n", 9), "not a text file"},
      {"index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "index.obj:4: a face refers to vertex 4 of 3"},
      {"vertex.obj", "v 0 0\n", "a vertex needs three numbers"},
      {"inf.obj", "v 0 0 inf\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "not a finite number"},
      {"nofaces.obj", "v 0 0 0\n", "no triangles"},
      {"garbage.off", "hello\n", "not an OFF file"},
      {"counts.off", "OFF\n3\n", "the vertex and face counts"},
      {"huge.off", "OFF\n1000000000 1 0\n0 0 0\n", "too short for them"},
      {"index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "refers to vertex \"7\" of 3"},
      {"binary.off", "OFF BINARY\n", "binary OFF is not supported"},
  };
  for (const auto& c : cases) {
    const auto path = dir / c.name;
    std::ofstream(path, std::ios::binary) << c.text;
    try {
      read_mesh(path);
      ADD_FAILURE() << c.name << " was accepted";
    } catch (const InvalidInputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(path.string(), 0), 0u) << what;
      EXPECT_NE(what.find(c.expected), std::string::npos) << c.name << ": " << what;
    }
  }
  EXPECT_THROW(read_mesh(dir), InvalidInputError);  // a folder
  std::filesystem::remove_all(dir);
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
      {"garbage.obj", "this is not a mesh\n", "garbage.obj:1: unknown OBJ statement \"this\""},
      {"garbage.off", "garbage garbage\n", "garbage.off:1: not an OFF file"},
      {"nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "vertex 1 has a coordinate that is not a finite number"},
      {"inf.off", "OFF\n3 1 0\n0 0 0\n1e999 0 0\n0 1 0\n3 0 1 2\n", "inf.off:4: a vertex: \"1e999\" is not a number"},
      {"nan.ply", binary_ply({{0, 0, 0}, {1, nan, 0}, {0, 1, 0}}, {{0, 1, 2}}, 3),
       "vertex 1 has a coordinate that is not a finite number"},
      {"index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
       "index.obj:4: a face refers to vertex 7 of 3"},
      {"index.ply", binary_ply(tri, {{0, 1, 2}, {0, 1, 5}}, 3),
       "face 1 refers to vertex 5 of 3"},
      {"points.ply", ply_header + "end_header\n0 0 0\n1 0 0\n0 1 0\n", "the mesh has no triangles"},
      {"header_only.ply", ply_header + faces(1),
       "the header declares 3 vertex records but the file is too short for them"},
      {"truncated.ply", ply_header + faces(2) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
       "the data ends early (face 1)"},
      {"huge.ply", binary_ply(tri, {{0, 1, 2}}, 1000000000000),
       "the header declares 1000000000000 vertex records but the file is too short for them"},
  };
  for (const auto& c : cases) {
    const auto path = dir / c.file;
    std::ofstream(path, std::ios::binary) << c.text;
    testing::internal::CaptureStderr();
    try {
      (void)read_mesh(path);
      ADD_FAILURE() << c.file << " was read";
    } catch (const InvalidInputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(path.string(), 0), 0u) << what;
      EXPECT_NE(what.find(c.message), std::string::npos) << c.file << ": " << what;
    }
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "") << c.file << ": nothing of the library on stderr";
  }
  // The same data, whole, reads.
  std::ofstream(dir / "whole.ply", std::ios::binary) << binary_ply(tri, {{0, 1, 2}}, 3);
  EXPECT_EQ(read_mesh(dir / "whole.ply").triangles.size(), 1u);
  std::filesystem::remove_all(dir);
}

TEST(ReadOrientedPoints, BunnyScanHasOutwardUnitNormals) {
  const OrientedPoints pts = read_oriented_points(std::string(CDP_SOURCE_DIR) + "/data/bunny.ply");
  EXPECT_GT(pts.size(), 34000u);
  EXPECT_LE(pts.size(), 35947u);
  const Vec3 centre = bounding_box(pts.positions).center();
  double outward = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ASSERT_NEAR(pts.normals[i].norm(), 1.0, 1e-12);
    outward += pts.normals[i].dot(pts.positions[i] - centre) > 0;
  }
  EXPECT_GT(outward / static_cast<double>(pts.size()), 0.8);
}

TEST(ReadOrientedPoints, AMissingFileIsAnErrorNamingIt) {
  try {
    read_oriented_points("/nonexistent/scan.ply");
    FAIL() << "no error";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scan.ply"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cdp
