// Pictures of meshes: framing (a sphere covers the area the projection predicts), camera
// orientation, wireframe, colour maps, principal-direction glyphs, determinism, bad options.
#include <gtest/gtest.h>

#include <cdp/render/mesh_render.h>
#include "common/reference_meshes.h"

#include <cdp/core/errors.h>

#include "common/test_fields.h"

#include <cmath>
#include <numbers>
#include <optional>

namespace cdp {
namespace {

bool is_background(const Image& im, int x, int y) { return im.at(x, y) == Rgb{255, 255, 255}; }

double mean_brightness(const Image& im) {
  double s = 0;
  for (std::uint8_t v : im.rgb) s += v;
  return s / im.rgb.size();
}

Mesh merged(const Mesh& a, const Mesh& b) {
  Mesh m = a;
  const int offset = static_cast<int>(a.positions.size());
  m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
  m.normals.insert(m.normals.end(), b.normals.begin(), b.normals.end());
  for (auto t : b.triangles) m.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return m;
}

TEST(MeshRender, SphereCoversTheAreaOfItsOrthographicDisc) {
  // Unit sphere: box half-diagonal sqrt(3) spans half the shorter side at zoom 1, so the disc
  // covers pi / (4 * 3) of a square picture; at zoom 1.5 the disc still fits, 2.25 times larger.
  RenderOptions o;
  o.view.width = o.view.height = 200;
  const Mesh sphere = icosphere(4);
  const RenderResult r1 = render_mesh(sphere, o);
  EXPECT_NEAR(r1.coverage, std::numbers::pi / 12, 0.01);
  o.view.zoom = 1.5;
  EXPECT_NEAR(render_mesh(sphere, o).coverage, 2.25 * std::numbers::pi / 12, 0.015);
  // Centre shaded, corners background.
  EXPECT_FALSE(is_background(r1.image, 100, 100));
  for (auto [x, y] : {std::pair{0, 0}, std::pair{199, 0}, std::pair{0, 199}, std::pair{199, 199}})
    EXPECT_TRUE(is_background(r1.image, x, y));
}

TEST(MeshRender, CameraFollowsAzimuthElevationUpAndFocus) {
  // A big sphere at -x and a small one at +x.
  const Mesh scene = merged(icosphere(3, {-2, 0, 0}, 1.0), icosphere(3, {2, 0, 0}, 0.5));
  RenderOptions o;
  o.view.width = 240;
  o.view.height = 120;
  auto column_coverage = [&](const Image& im, int x) {
    int n = 0;
    for (int y = 0; y < im.height; ++y) n += !is_background(im, x, y);
    return n;
  };
  // Up y, azimuth 0: seen from +z, +x to the right; the big sphere left.
  Image im = render_mesh(scene, o).image;
  // Box x in [-3, 2.5], half-diagonal 3.09 over 60 px: the centres land near x = 86 and x = 164.
  const int left = 120 - 40, right = 120 + 40;
  EXPECT_GT(column_coverage(im, left), column_coverage(im, right));
  // Azimuth 180: seen from -z, the big sphere on the right.
  o.view.azimuth_deg = 180;
  im = render_mesh(scene, o).image;
  EXPECT_LT(column_coverage(im, left), column_coverage(im, right));
  // Up z, azimuth 0: seen from +x, both spheres on the axis of view (centred, the small one in front).
  o.view.azimuth_deg = 0;
  o.view.up = UpAxis::Z;
  im = render_mesh(scene, o).image;
  EXPECT_FALSE(is_background(im, 120, 60));
  EXPECT_TRUE(is_background(im, left - 30, 60));
  // Focus on the small sphere with zoom: it fills the centre.
  o.view.up = UpAxis::Y;
  o.view.focus = Vec3(2, 0, 0);
  o.view.zoom = 4;
  im = render_mesh(scene, o).image;
  EXPECT_FALSE(is_background(im, 120, 60));
  EXPECT_FALSE(is_background(im, 120, 30));
  // Elevation 90 with up y: seen from above, still a picture of both.
  o.view.focus.reset();
  o.view.zoom = 1;
  o.view.elevation_deg = 90;
  EXPECT_GT(render_mesh(scene, o).coverage, 0.05);
}

TEST(MeshRender, WireframeLinesAreAboutOnePixelWideAtAnyDensity) {
  // The darkening is line length x line width. One more subdivision doubles the total edge
  // length (4x the edges, half as long), so it should double the darkening; doubling the width
  // should too. Lines whose width grew with the triangles would fail the first ratio.
  RenderOptions o;
  o.view.width = o.view.height = 200;
  o.samples = 4;
  auto darkening = [&](const Mesh& m, double width) {
    o.wireframe = false;
    const double plain = mean_brightness(render_mesh(m, o).image);
    o.wireframe = true;
    o.line_width_px = width;
    return plain - mean_brightness(render_mesh(m, o).image);
  };
  const Mesh coarse = icosphere(2), fine = icosphere(3);
  const double d2 = darkening(coarse, 1.0), d3 = darkening(fine, 1.0), d2_wide = darkening(coarse, 2.0);
  EXPECT_GT(d2, 1.0);
  EXPECT_NEAR(d3 / d2, 2.0, 0.3) << d2 << " " << d3;
  EXPECT_NEAR(d2_wide / d2, 2.0, 0.3) << d2 << " " << d2_wide;
}

TEST(MeshRender, ShapeIndexOfASphereIsConvexBlueAndMacUsesALogMap) {
  Mesh sphere = icosphere(3);
  const auto field = test::field_from_json(R"({"type": "sphere", "radius": 1})");
  add_curvature_scalars(*field, sphere);
  for (double v : sphere.vertex_scalars.at("shape_index")) EXPECT_NEAR(v, -1.0, 1e-9);
  for (double v : sphere.vertex_scalars.at("mac")) EXPECT_NEAR(v, 1.0, 1e-9);
  RenderOptions o;
  o.view.width = o.view.height = 100;
  o.color = "shape_index";
  const RenderResult r = render_mesh(sphere, o);
  ASSERT_TRUE(r.mapping);
  EXPECT_EQ(r.mapping->kind, ColorMapKind::Coolwarm);
  const Rgb c = r.image.at(50, 50);
  EXPECT_GT(c[2], c[0] + 40) << "convex (-1) is the blue end";
  o.color = "mac";
  const RenderResult m = render_mesh(sphere, o);
  ASSERT_TRUE(m.mapping);
  EXPECT_EQ(m.mapping->scale, ColorScale::Log);
  EXPECT_LT(m.mapping->lo, 1.0);
  EXPECT_GT(m.mapping->hi, 1.0);
}

TEST(MeshRender, PrincipalDirectionGlyphsOnATorusButNotOnASphere) {
  RenderOptions o;
  o.view.width = o.view.height = 120;
  o.view.up = UpAxis::Z;
  o.view.elevation_deg = 60;
  o.directions = true;
  // A sphere is umbilic everywhere: no direction is defined, no glyph is drawn.
  const auto sphere = test::field_from_json(R"({"type": "sphere", "radius": 1})");
  o.field = sphere.get();
  EXPECT_EQ(render_mesh(icosphere(3), o).glyphs, 0);
  // A torus has distinct curvatures everywhere; render an icosphere-free stand-in: any mesh
  // near the surface works, since the curvature comes from the field at the hit points.
  const auto torus = test::field_from_json(R"({"type": "torus", "major_radius": 1, "minor_radius": 0.4})");
  o.field = torus.get();
  const Mesh shell = icosphere(3, Vec3::Zero(), 1.2);
  const RenderResult r = render_mesh(shell, o);
  EXPECT_GT(r.glyphs, 10);
  int red = 0, blue = 0;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 120; ++x) {
      const Rgb c = r.image.at(x, y);
      red += c[0] > 150 && c[1] < 90 && c[2] < 90;
      blue += c[2] > 150 && c[0] < 90;
    }
  EXPECT_GT(red, 20);
  EXPECT_GT(blue, 20);
}

TEST(MeshRender, SameInputSamePixels) {
  RenderOptions o;
  o.view.width = 90;
  o.view.height = 70;
  o.view.azimuth_deg = 33;
  o.view.elevation_deg = 21;
  o.wireframe = true;
  const Mesh m = icosphere(3);
  EXPECT_EQ(render_mesh(m, o).image.rgb, render_mesh(m, o).image.rgb);
}

TEST(MeshRender, BadOptionsAndMeshesAreErrors) {
  const Mesh sphere = icosphere(1);
  auto bad = [&](auto change) {
    RenderOptions o;
    o.view.width = o.view.height = 16;
    change(o);
    EXPECT_THROW(render_mesh(sphere, o), InvalidInputError);
  };
  bad([](RenderOptions& o) { o.view.width = 0; });
  bad([](RenderOptions& o) { o.view.zoom = -1; });
  bad([](RenderOptions& o) { o.view.elevation_deg = 91; });
  bad([](RenderOptions& o) { o.samples = 0; });
  bad([](RenderOptions& o) { o.line_width_px = 0; });
  bad([](RenderOptions& o) { o.directions = true; });
  bad([](RenderOptions& o) { o.color = "mac"; });
  RenderOptions o;
  EXPECT_THROW(render_mesh(Mesh{}, o), InvalidInputError);
  EXPECT_THROW(parse_up_axis("w"), InvalidInputError);
}

// These once aborted in Embree (NaN or out-of-range rays) or drew one ray over and over.
TEST(MeshRender, CamerasThatCannotDrawTheMeshAreErrors) {
  const Mesh sphere = icosphere(1);  // bounding radius sqrt(3)
  const struct {
    double zoom;
    std::optional<Vec3> focus;
    std::string message;
  } cases[] = {
      {1e-300, {}, "zoom 1e-300 is too small for a 40 x 20 picture: the mesh would span less than a pixel"},
      {0.04, {}, "zoom 0.04 is too small for a 40 x 20 picture: the mesh would span less than a pixel"},
      {1e300, {}, "zoom 1e+300 is too large for a 40 x 20 picture: its pixels would be finer than float ray casting resolves"},
      {1e20, {}, "zoom 1e+20 is too large for a 40 x 20 picture: its pixels would be finer than float ray casting resolves"},
      {1, Vec3(1e20, 0, 0), "focus is too far from the mesh (1e+20 from its centre, whose bounding radius is 1.73205): "
                            "the picture's pixels would be finer than float ray casting resolves there"},
  };
  for (const auto& c : cases) {
    RenderOptions o;
    o.view.width = 40;
    o.view.height = 20;
    o.view.zoom = c.zoom;
    o.view.focus = c.focus;
    try {
      (void)render_mesh(sphere, o);
      ADD_FAILURE() << c.message;
    } catch (const InvalidInputError& e) {
      EXPECT_EQ(std::string(e.what()), c.message);
    }
  }
}

// The azimuth is taken modulo 360 (exactly), so a huge one is an angle like any other, and the
// camera looks straight down the up axis at elevation +-90.
TEST(MeshRender, AnyFiniteAzimuthAndTheVerticalViewsDraw) {
  const Mesh sphere = icosphere(2);
  RenderOptions o;
  o.view.width = o.view.height = 24;
  auto image = [&](double azimuth, double elevation) {
    o.view.azimuth_deg = azimuth;
    o.view.elevation_deg = elevation;
    const RenderResult r = render_mesh(sphere, o);
    EXPECT_GT(r.coverage, 0.1) << azimuth << " " << elevation;
    return r.image.rgb;
  };
  EXPECT_EQ(image(1e308, 0), image(std::fmod(1e308, 360.0), 0));
  EXPECT_EQ(image(-1e300, 10), image(std::fmod(-1e300, 360.0), 10));
  EXPECT_EQ(image(400, 20), image(40, 20));
  (void)image(0, 90);
  (void)image(0, -90);
}

}  // namespace
}  // namespace cdp
