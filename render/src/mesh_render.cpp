#include <cdp/render/mesh_render.h>

#include <cdp/raytrace/embree_scene.h>
#include <cdp/raytrace/phong_normal.h>

#include <cdp/core/curvature.h>
#include <cdp/core/errors.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>

namespace cdp {

namespace {

const Vec3 kBackground(1.0, 1.0, 1.0);
const Vec3 kPlainColor(0.80, 0.80, 0.78);
const Vec3 kLineColor(0.10, 0.10, 0.12);
const Vec3 kMaxDirectionColor(0.85, 0.10, 0.10);
const Vec3 kMinDirectionColor(0.10, 0.25, 0.90);
constexpr double kLineOpacity = 0.85;
constexpr double kGlyphWidthPx = 1.6;
constexpr double kGlyphHalfLength = 0.42;  // of the glyph spacing
constexpr double kUmbilicTolerance = 0.05;
constexpr int kBandRows = 16;  // rows cast at once, to bound the memory of rays and hits
// Embree casts in float, which rounds a ray origin by about 6e-8 of its distance from the mesh's
// centre: pixels of at least 1e-6 of that distance keep the error below a tenth of a pixel.
// Finer pixels would show rounding noise, and far finer ones the same ray over and over.
constexpr double kMinPixelPerReach = 1e-6;

// The orthographic camera: screen axes, the viewing direction, the pixel size.
struct Frame {
  Vec3 right, up, toward_eye, focus;
  double pixel = 0.0;    // world size of a pixel
  double eye_offset = 0; // how far behind the image plane the ray origins start
  int width = 0, height = 0;

  // The ray through the point (x, y) of the picture, in pixels from its top-left corner.
  Ray ray(double x, double y) const {
    Ray r;
    r.origin = focus + (x - 0.5 * width) * pixel * right + (0.5 * height - y) * pixel * up + eye_offset * toward_eye;
    r.direction = -toward_eye;
    return r;
  }
  // Screen position of a world point, in pixels.
  Eigen::Vector2d project(const Vec3& p) const {
    const Vec3 q = p - focus;
    return {0.5 * width + q.dot(right) / pixel, 0.5 * height - q.dot(up) / pixel};
  }
};

Vec3 axis(UpAxis a) {
  return a == UpAxis::X ? Vec3::UnitX() : a == UpAxis::Y ? Vec3::UnitY() : Vec3::UnitZ();
}

Frame make_frame(const Box& box, const ViewOptions& v) {
  const Vec3 up_axis = axis(v.up);
  // The default eye side follows the up axis cyclically: y -> z, z -> x, x -> y.
  const Vec3 eye0 = v.up == UpAxis::Y ? Vec3::UnitZ() : v.up == UpAxis::Z ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 right0 = up_axis.cross(eye0);
  // fmod is exact, and keeps a huge azimuth (1e308) from overflowing to an infinite angle.
  const double a = std::fmod(v.azimuth_deg, 360.0) * std::numbers::pi / 180.0;
  const double e = v.elevation_deg * std::numbers::pi / 180.0;
  const Vec3 eye_a = std::cos(a) * eye0 + std::sin(a) * right0;
  Frame f;
  f.right = std::cos(a) * right0 - std::sin(a) * eye0;
  f.toward_eye = (std::cos(e) * eye_a + std::sin(e) * up_axis).normalized();
  f.up = f.toward_eye.cross(f.right).normalized();
  f.focus = v.focus.value_or(box.center());
  f.width = v.width;
  f.height = v.height;
  const double radius = 0.5 * box.diagonal();
  f.pixel = 2.0 * radius / v.zoom / std::min(v.width, v.height);
  f.eye_offset = (f.focus - box.center()).norm() + 2.0 * radius;
  return f;
}

std::string number(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

// Options can each be valid and still make a camera that cannot draw the mesh.
void check_frame(const Frame& f, const Box& box, const ViewOptions& v) {
  const std::string size = std::to_string(v.width) + " x " + std::to_string(v.height);
  if (!(v.zoom * std::min(v.width, v.height) >= 1.0))
    throw InvalidInputError("zoom " + number(v.zoom) + " is too small for a " + size +
                            " picture: the mesh would span less than a pixel");
  // The ray origins lie within this distance of the mesh's centre, the focus at `focus_distance`.
  const double radius = 0.5 * box.diagonal(), picture = 0.5 * f.pixel * std::hypot(f.width, f.height);
  auto reach = [&](double focus_distance) { return 2.0 * focus_distance + 2.0 * radius + picture; };
  if (f.pixel >= kMinPixelPerReach * reach((f.focus - box.center()).norm())) return;
  if (f.pixel >= kMinPixelPerReach * reach(0.0))
    throw InvalidInputError("focus is too far from the mesh (" + number((f.focus - box.center()).norm()) +
                            " from its centre, whose bounding radius is " + number(radius) +
                            "): the picture's pixels would be finer than float ray casting resolves there");
  throw InvalidInputError("zoom " + number(v.zoom) + " is too large for a " + size +
                          " picture: its pixels would be finer than float ray casting resolves");
}

void validate(const RenderOptions& o) {
  const ViewOptions& v = o.view;
  if (v.width < 1 || v.width > 8192 || v.height < 1 || v.height > 8192)
    throw InvalidInputError("width and height must be in [1, 8192]");
  if (!std::isfinite(v.azimuth_deg)) throw InvalidInputError("azimuth must be finite");
  if (!(v.elevation_deg >= -90.0 && v.elevation_deg <= 90.0))
    throw InvalidInputError("elevation must be in [-90, 90] degrees");
  if (!(v.zoom > 0.0) || !std::isfinite(v.zoom)) throw InvalidInputError("zoom must be positive");
  if (v.focus && !v.focus->allFinite()) throw InvalidInputError("focus must be finite");
  if (o.samples < 1 || o.samples > 8) throw InvalidInputError("samples must be in [1, 8]");
  if (!(o.line_width_px > 0.0) || !std::isfinite(o.line_width_px))
    throw InvalidInputError("line width must be positive");
  if (!(o.glyph_spacing_px >= 2.0) || !std::isfinite(o.glyph_spacing_px))
    throw InvalidInputError("glyph spacing must be at least 2 pixels");
  if (o.directions && !o.field) throw InvalidInputError("principal directions need a field");
  if (o.mapping && (!(o.mapping->lo < o.mapping->hi) || !std::isfinite(o.mapping->lo) || !std::isfinite(o.mapping->hi) ||
                    (o.mapping->scale == ColorScale::Log && !(o.mapping->lo > 0.0))))
    throw InvalidInputError("the colour range must be finite with lo < hi (and lo > 0 on a log scale)");
}

// Screen altitudes (pixels) of a triangle from each vertex to the opposite edge.
std::array<double, 3> screen_altitudes(const Frame& f, const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  const Eigen::Vector2d q[3] = {f.project(p0), f.project(p1), f.project(p2)};
  const Eigen::Vector2d e1 = q[1] - q[0], e2 = q[2] - q[0];
  const double area2 = std::abs(e1.x() * e2.y() - e1.y() * e2.x());
  std::array<double, 3> h{};
  for (int i = 0; i < 3; ++i) {
    const double edge = (q[(i + 2) % 3] - q[(i + 1) % 3]).norm();
    h[i] = edge > 0.0 ? area2 / edge : 0.0;
  }
  return h;
}

// Adds an anti-aliased segment to the picture (linear colours, row-major).
void draw_segment(std::vector<Vec3>& pixels, int width, int height, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                  const Vec3& color) {
  const double r = 0.5 * kGlyphWidthPx + 1.0;
  const int x0 = std::max(0, static_cast<int>(std::floor(std::min(a.x(), b.x()) - r)));
  const int x1 = std::min(width - 1, static_cast<int>(std::ceil(std::max(a.x(), b.x()) + r)));
  const int y0 = std::max(0, static_cast<int>(std::floor(std::min(a.y(), b.y()) - r)));
  const int y1 = std::min(height - 1, static_cast<int>(std::ceil(std::max(a.y(), b.y()) + r)));
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const Eigen::Vector2d p(x + 0.5, y + 0.5);
      const double s = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
      const double d = (p - (a + s * ab)).norm();
      const double cover = std::clamp(0.5 * kGlyphWidthPx + 0.5 - d, 0.0, 1.0);
      Vec3& c = pixels[static_cast<std::size_t>(y) * width + x];
      c = (1 - cover) * c + cover * color;
    }
  }
}

}  // namespace

UpAxis parse_up_axis(const std::string& name) {
  if (name == "x") return UpAxis::X;
  if (name == "y") return UpAxis::Y;
  if (name == "z") return UpAxis::Z;
  throw InvalidInputError("up axis must be x, y or z, found \"" + name + "\"");
}

void add_curvature_scalars(const Field& field, Mesh& mesh) {
  const std::size_t n = mesh.positions.size();
  std::vector<double> mac(n), shape(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 64), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      try {
        const Curvature c = curvature_at(field, mesh.positions[i]);
        mac[i] = c.mac;
        shape[i] = c.shape_index;
      } catch (const NoSurfaceError&) {
        mac[i] = shape[i] = std::numeric_limits<double>::quiet_NaN();
      }
    }
  });
  mesh.vertex_scalars["mac"] = std::move(mac);
  mesh.vertex_scalars["shape_index"] = std::move(shape);
}

RenderResult render_mesh(const Mesh& input, const RenderOptions& o) {
  validate(o);
  if (input.triangles.empty()) throw InvalidInputError("the mesh has no triangles");
  // Blended vertex normals need normals: meshes read without them get area-weighted ones.
  Mesh with_normals;
  const bool has_normals = input.normals.size() == input.positions.size();
  if (!has_normals) {
    with_normals.positions = input.positions;
    with_normals.triangles = input.triangles;
    with_normals.normals = area_weighted_normals(input);
  }
  const Mesh& mesh = has_normals ? input : with_normals;

  RenderResult result;
  const std::vector<double>* scalars = nullptr;
  if (!o.color.empty()) {
    const auto it = input.vertex_scalars.find(o.color);
    if (it == input.vertex_scalars.end()) throw InvalidInputError("the mesh has no vertex property \"" + o.color + "\"");
    if (it->second.size() != input.positions.size())
      throw InvalidInputError("vertex property \"" + o.color + "\" does not have one value per vertex");
    scalars = &it->second;
    result.mapping = o.mapping ? *o.mapping : default_color_mapping(o.color, *scalars);
  }

  Box box{Vec3::Constant(std::numeric_limits<double>::infinity()), Vec3::Constant(-std::numeric_limits<double>::infinity())};
  for (const Vec3& p : mesh.positions) {
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
  }
  if (!box.min.allFinite() || !box.max.allFinite()) throw InvalidInputError("a vertex position is not finite");
  if (box.diagonal() == 0.0) throw InvalidInputError("the mesh has no extent (all vertices coincide)");
  const Frame frame = make_frame(box, o.view);
  check_frame(frame, box, o.view);
  const EmbreeScene scene(mesh);

  // Light attached to the camera, a little above and to the left of the eye (a pure headlight
  // flattens the picture); Blinn-Phong with the half vector between light and eye.
  const Vec3 light = (frame.toward_eye + 0.35 * frame.up - 0.25 * frame.right).normalized();
  const Vec3 half_vector = (light + frame.toward_eye).normalized();
  const double specular = scalars ? 0.12 : 0.22;

  const int W = o.view.width, H = o.view.height, S = o.samples;
  std::vector<Vec3> pixels(static_cast<std::size_t>(W) * H, Vec3::Zero());
  std::size_t hits_total = 0;
  for (int band = 0; band < H; band += kBandRows) {
    const int rows = std::min(kBandRows, H - band);
    std::vector<Ray> rays;
    rays.reserve(static_cast<std::size_t>(rows) * W * S * S);
    for (int y = band; y < band + rows; ++y)
      for (int x = 0; x < W; ++x)
        for (int sy = 0; sy < S; ++sy)
          for (int sx = 0; sx < S; ++sx) rays.push_back(frame.ray(x + (sx + 0.5) / S, y + (sy + 0.5) / S));
    const std::vector<MeshHit> hits = scene.intersect(rays);
    for (std::size_t i = 0; i < hits.size(); ++i) {
      const MeshHit& h = hits[i];
      const std::size_t pixel = static_cast<std::size_t>(band) * W + i / (S * S);
      if (!h.hit()) {
        pixels[pixel] += kBackground;
        continue;
      }
      ++hits_total;
      const auto& tri = mesh.triangles[h.triangle];
      const Vec3 &p0 = mesh.positions[tri[0]], &p1 = mesh.positions[tri[1]], &p2 = mesh.positions[tri[2]];
      const Vec3 face = (p1 - p0).cross(p2 - p0);
      Vec3 n = phong_normal(mesh, h.triangle, h.u, h.v);
      if (n.squaredNorm() == 0.0) n = face.normalized();
      // Two-sided: a triangle seen from its back is lit like its front.
      if (face.dot(frame.toward_eye) < 0.0) n = -n;
      const double b[3] = {1.0 - h.u - h.v, h.u, h.v};
      Vec3 base = kPlainColor;
      if (scalars) {
        const double value = b[0] * (*scalars)[tri[0]] + b[1] * (*scalars)[tri[1]] + b[2] * (*scalars)[tri[2]];
        base = (*result.mapping)(value);
      }
      const double diffuse = std::max(0.0, n.dot(light));
      const double highlight = std::pow(std::max(0.0, n.dot(half_vector)), 40.0);
      Vec3 c = (0.2 + 0.75 * diffuse) * base + Vec3::Constant(specular * highlight);
      if (o.wireframe) {
        const auto alt = screen_altitudes(frame, p0, p1, p2);
        const double d = std::min({b[0] * alt[0], b[1] * alt[1], b[2] * alt[2]});
        if (d < 0.5 * o.line_width_px) c = (1 - kLineOpacity) * c + kLineOpacity * kLineColor;
      }
      pixels[pixel] += c.cwiseMin(1.0).cwiseMax(0.0);
    }
  }
  for (Vec3& c : pixels) c /= S * S;
  result.coverage = static_cast<double>(hits_total) / (static_cast<double>(W) * H * S * S);

  if (o.directions) {
    std::vector<Ray> rays;
    std::vector<Eigen::Vector2d> centres;
    for (double y = 0.5 * o.glyph_spacing_px; y < H; y += o.glyph_spacing_px)
      for (double x = 0.5 * o.glyph_spacing_px; x < W; x += o.glyph_spacing_px) {
        centres.emplace_back(x, y);
        rays.push_back(frame.ray(x, y));
      }
    const std::vector<MeshHit> hits = scene.intersect(rays);
    std::vector<std::optional<Curvature>> curv(hits.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, hits.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        if (!hits[i].hit()) continue;
        try {
          curv[i] = curvature_at(*o.field, rays[i].origin + hits[i].t * rays[i].direction);
        } catch (const NoSurfaceError&) {
        }
      }
    });
    const double half = kGlyphHalfLength * o.glyph_spacing_px;
    for (std::size_t i = 0; i < curv.size(); ++i) {
      if (!curv[i]) continue;
      const Curvature& c = *curv[i];
      const double scale = std::max(std::abs(c.k1), std::abs(c.k2));
      if (!std::isfinite(c.k1) || !std::isfinite(c.k2) || !(c.k1 - c.k2 >= kUmbilicTolerance * scale) || scale == 0.0)
        continue;
      ++result.glyphs;
      for (const auto& [dir, color] : {std::pair{c.dir2, kMinDirectionColor}, std::pair{c.dir1, kMaxDirectionColor}}) {
        // Screen direction in pixels (y down); its length is the foreshortening.
        const Eigen::Vector2d s(dir.dot(frame.right), -dir.dot(frame.up));
        draw_segment(pixels, W, H, centres[i] - half * s, centres[i] + half * s, color);
      }
    }
  }

  result.image = Image(W, H, {255, 255, 255});
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const Vec3& c = pixels[static_cast<std::size_t>(y) * W + x];
      result.image.set(x, y,
                       {static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(c.x(), 0.0, 1.0))),
                        static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(c.y(), 0.0, 1.0))),
                        static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(c.z(), 0.0, 1.0)))});
    }
  return result;
}

}  // namespace cdp
