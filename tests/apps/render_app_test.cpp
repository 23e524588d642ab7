// build/bin/render writes real PNG pictures of meshes and fails cleanly on bad input.
#include <gtest/gtest.h>

#include "common/reference_meshes.h"

#include <cdp/io/mesh_io.h>

#include <nlohmann/json.hpp>

#include "common/png_decode.h"
#include "common/run_command.h"

#include <filesystem>
#include <fstream>
#include <iterator>

namespace cdp {
namespace {

struct RenderApp : public ::testing::Test {
  test::TempDir dir{"render_app"};
  std::filesystem::path mesh_path = dir.path / "sphere.ply";
  void SetUp() override {
    Mesh sphere = icosphere(3);
    std::vector<double> si(sphere.positions.size());
    for (std::size_t i = 0; i < si.size(); ++i) si[i] = sphere.positions[i].x();  // a made-up scalar in [-1, 1]
    sphere.vertex_scalars["shape_index"] = si;
    write_mesh(sphere, mesh_path);
  }
  std::string png(const std::string& name) const { return (dir.path / name).string(); }
};

std::string bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

double mean(const test::DecodedPng& p) {
  double s = 0;
  for (auto v : p.rgb) s += v;
  return s / p.rgb.size();
}

TEST_F(RenderApp, WritesAPngOfTheRequestedSizeShowingTheMesh) {
  const auto r = test::run_app("render", mesh_path.string() + " -o " + png("a.png") + " --width 120 --height 90");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto summary = nlohmann::json::parse(r.out);
  EXPECT_EQ(summary["width"], 120);
  EXPECT_GT(summary["coverage"].get<double>(), 0.1);
  std::string error;
  const auto image = test::read_png_file(png("a.png"), &error);
  ASSERT_TRUE(image) << error;
  EXPECT_EQ(image->width, 120);
  EXPECT_EQ(image->height, 90);
  const std::array<int, 3> white{255, 255, 255};
  EXPECT_NE(image->at(60, 45), white) << "the centre shows the sphere";
  for (auto [x, y] : {std::pair{0, 0}, std::pair{119, 0}, std::pair{0, 89}, std::pair{119, 89}})
    EXPECT_EQ(image->at(x, y), white) << "corner " << x << "," << y;

  // The wireframe darkens the picture; the same command gives the same bytes.
  ASSERT_EQ(test::run_app("render", mesh_path.string() + " -o " + png("w.png") + " --width 120 --height 90 --wireframe").exit_code, 0);
  ASSERT_EQ(test::run_app("render", mesh_path.string() + " -o " + png("w2.png") + " --width 120 --height 90 --wireframe").exit_code, 0);
  const auto wire = test::read_png_file(png("w.png"));
  const auto wire2 = test::read_png_file(png("w2.png"));
  ASSERT_TRUE(wire && wire2);
  EXPECT_LT(mean(*wire), mean(*image) - 1.0);
  EXPECT_EQ(wire->rgb, wire2->rgb);
  EXPECT_EQ(bytes(png("w.png")), bytes(png("w2.png")));
}

TEST_F(RenderApp, ColoursByAVertexPropertyOfThePly) {
  const auto r = test::run_app("render", mesh_path.string() + " -o " + png("c.png") +
                                             " --width 80 --height 80 --color shape_index --up y --azimuth 90");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto summary = nlohmann::json::parse(r.out);
  EXPECT_EQ(summary["color"]["map"], "coolwarm");
  EXPECT_EQ(summary["color"]["range"], nlohmann::json({-1.0, 1.0}));
  // Azimuth 90 looks from +x, where the scalar (x) is +1: the red end of coolwarm.
  const auto image = test::read_png_file(png("c.png"));
  ASSERT_TRUE(image);
  const auto c = image->at(40, 40);
  EXPECT_GT(c[0], c[2] + 40);
}

TEST_F(RenderApp, OtherPngReadersAcceptTheFile) {
  if (!std::filesystem::exists("/usr/bin/python3")) GTEST_SKIP() << "no /usr/bin/python3";
  ASSERT_EQ(test::run_app("render", mesh_path.string() + " -o " + png("p.png") + " --width 33 --height 21").exit_code, 0);
  // Pillow (installed with matplotlib) checks the chunk CRCs and inflates with zlib.
  const std::string cmd = "/usr/bin/python3 -c \"import sys; from PIL import Image; im = Image.open(sys.argv[1]); im.load(); "
                          "print(im.size[0], im.size[1], im.mode)\" " + png("p.png") + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  ASSERT_TRUE(pipe);
  char buf[256] = {};
  const std::size_t n = fread(buf, 1, sizeof(buf) - 1, pipe);
  const int status = pclose(pipe);
  const std::string out(buf, n);
  if (out.find("No module named") != std::string::npos) GTEST_SKIP() << "Pillow is not installed";
  EXPECT_EQ(status, 0) << out;
  EXPECT_EQ(out, "33 21 RGB\n");
}

// --azimuth 1e308 aborted on an Embree assertion: its angle in radians overflowed.
TEST_F(RenderApp, HugeAzimuthAndVerticalViewsDraw) {
  for (const char* view : {"--azimuth 1e308", "--elevation 90", "--elevation -90 --up z"}) {
    const auto r = test::run_app("render", mesh_path.string() + " -o " + png("v.png") + " --width 30 --height 30 " + view);
    ASSERT_EQ(r.exit_code, 0) << view << ": " << r.err;
    EXPECT_GT(nlohmann::json::parse(r.out)["coverage"].get<double>(), 0.1) << view;
  }
}

TEST_F(RenderApp, BadInputGivesOneLineAndNoPicture) {
  Mesh empty;
  empty.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  write_mesh(empty, dir.path / "empty.ply");
  const std::string m = mesh_path.string(), out = png("bad.png");
  const struct {
    std::string args, message;
  } cases[] = {
      {(dir.path / "missing.ply").string() + " -o " + out, (dir.path / "missing.ply").string() + ": file not found"},
      {(dir.path / "empty.ply").string() + " -o " + out, (dir.path / "empty.ply").string() + ": the mesh has no triangles"},
      {m + " -o " + out + " --zoom two", "--zoom: expects a positive number, found \"two\""},
      {m + " -o " + out + " --focus 1,2", "--focus: expects three numbers x,y,z, found \"1,2\""},
      {m + " -o " + out + " --up w", "--up: w not in {x,y,z}"},
      {m + " -o " + out + " --width 0", "--width: expects an integer between 1 and 8192, found \"0\""},
      {m + " -o " + out + " --color mac", m + ": no vertex property \"mac\" (give --field FIELD.json to compute it)"},
      {m + " -o " + out + " --directions", "--directions needs --field FIELD.json (the curvature comes from the field)"},
      {m + " -o " + png("bad.ppm"), png("bad.ppm") + ": the output must be a .png file"},
      {m + " -o " + out + " --bogus", "The following argument was not expected: --bogus; see render --help"},
      {m + " -o " + out + " --width", "--width needs a value; see render --help"},
      {m + " -o " + png("no/such/folder.png"), png("no/such/folder.png") + ": the folder " + png("no/such") + " does not exist"},
      // These three aborted on an Embree assertion (exit 134).
      {m + " -o " + out + " --focus 1e20,0,0", "focus is too far from the mesh (1e+20 from its centre"},
      {m + " -o " + out + " --zoom 1e-300", "zoom 1e-300 is too small for a 800 x 800 picture"},
      {m + " -o " + out + " --zoom 1e300", "zoom 1e+300 is too large for a 800 x 800 picture"},
      // The focus off the mesh (the unit sphere): a picture of the background only, once written
      // with exit 0.
      {m + " -o " + out + " --focus 5,0,0 --zoom 4", m + ": no pixel of the picture shows the mesh"},
  };
  for (const auto& c : cases) {
    const auto r = test::run_app("render", c.args);
    EXPECT_EQ(r.exit_code, 1) << c.args;
    // Some messages go on with the numbers of the case: compare their start.
    EXPECT_EQ(r.err.substr(0, ("render: " + c.message).size()), "render: " + c.message) << c.args;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(r.out.empty());
  }
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_FALSE(std::filesystem::exists(png("bad.ppm")));
}

}  // namespace
}  // namespace cdp
