#include <cdp/raytrace/camera.h>

#include <cdp/core/errors.h>

#include <cmath>
#include <numbers>

namespace cdp {

namespace {
constexpr double kImageMargin = 1.02;
}

const char* to_string(Projection projection) {
  return projection == Projection::Perspective ? "perspective" : "orthographic";
}

Projection parse_projection(const std::string& name) {
  if (name == "perspective") return Projection::Perspective;
  if (name == "orthographic") return Projection::Orthographic;
  throw InvalidInputError("projection must be \"perspective\" or \"orthographic\", found \"" + name + "\"");
}

void validate(const CameraOptions& o) {
  if (o.directions.empty() && (o.views < 1 || o.views > 10000))
    throw InvalidInputError("camera: views must be in [1, 10000], found " + std::to_string(o.views));
  if (o.resolution < 1 || o.resolution > 8192)
    throw InvalidInputError("camera: resolution must be in [1, 8192], found " + std::to_string(o.resolution));
  if (!(o.distance > 1.0) || !std::isfinite(o.distance))
    throw InvalidInputError("camera: distance must be > 1 half-diagonal (the eye outside the box)");
  if (!(o.fov_deg >= 0.0 && o.fov_deg < 180.0)) throw InvalidInputError("camera: fov_deg must be in [0, 180)");
  for (const Vec3& d : o.directions)
    if (!d.allFinite() || d.norm() == 0.0) throw InvalidInputError("camera: a view direction is zero or not finite");
}

std::vector<Vec3> view_directions(const CameraOptions& o) {
  std::vector<Vec3> dirs;
  if (!o.directions.empty()) {
    for (const Vec3& d : o.directions) dirs.push_back(d.normalized());
    return dirs;
  }
  // Fibonacci spiral: z evenly spaced in (-1, 1), longitude advancing by the golden angle.
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < o.views; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / o.views;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * i;
    // The eye sits at +position and looks back at the centre.
    dirs.push_back(-Vec3(r * std::cos(phi), r * std::sin(phi), z).normalized());
  }
  return dirs;
}

std::vector<Ray> make_camera_rays(const Box& box, const CameraOptions& o) {
  validate(o);
  if (!box.valid()) throw InvalidInputError("camera: the field's box is empty or not finite");
  const Vec3 center = box.center();
  const double radius = 0.5 * box.diagonal();
  // A finite box can still have a diagonal that overflows (a sphere of radius 1e160): the eye
  // would be infinitely far and every ray NaN.
  if (!std::isfinite(o.distance * radius))
    throw InvalidInputError("camera: the field's box is too large for double precision (its diagonal overflows)");
  const double eye_distance = o.distance * radius;
  const int n = o.resolution;
  std::vector<Ray> rays;
  const std::vector<Vec3> dirs = view_directions(o);
  rays.reserve(dirs.size() * static_cast<std::size_t>(n) * n);
  for (const Vec3& dir : dirs) {
    const Vec3 up_hint = std::abs(dir.z()) < 0.9 ? Vec3::UnitZ() : Vec3::UnitX();
    const Vec3 right = dir.cross(up_hint).normalized();
    const Vec3 up = right.cross(dir);
    const Vec3 eye = center - eye_distance * dir;
    // Half-extent of the square image: on the plane through the centre (orthographic) or at unit
    // distance from the eye (perspective), fitted to the projected corners of the box.
    double half = 0.0;
    if (o.projection == Projection::Perspective && o.fov_deg > 0) {
      half = std::tan(0.5 * o.fov_deg * std::numbers::pi / 180.0);
    } else {
      for (int k = 0; k < 8; ++k) {
        const Vec3 corner((k & 1) ? box.max.x() : box.min.x(), (k & 2) ? box.max.y() : box.min.y(),
                          (k & 4) ? box.max.z() : box.min.z());
        const Vec3 q = corner - eye;
        // The eye is outside the bounding sphere, so every corner is in front of it.
        const double depth = o.projection == Projection::Perspective ? q.dot(dir) : 1.0;
        half = std::max({half, std::abs(q.dot(right)) / depth, std::abs(q.dot(up)) / depth});
      }
      half *= kImageMargin;
    }
    for (int row = 0; row < n; ++row) {
      for (int col = 0; col < n; ++col) {
        const double sx = (2.0 * (col + 0.5) / n - 1.0) * half;
        const double sy = (1.0 - 2.0 * (row + 0.5) / n) * half;
        Ray ray;
        if (o.projection == Projection::Orthographic) {
          ray.origin = eye + sx * right + sy * up;
          ray.direction = dir;
        } else {
          ray.origin = eye;
          ray.direction = (dir + sx * right + sy * up).normalized();
        }
        rays.push_back(ray);
      }
    }
  }
  return rays;
}

nlohmann::json to_json(const CameraOptions& o) {
  nlohmann::json j{{"resolution", o.resolution}, {"projection", to_string(o.projection)}, {"distance", o.distance},
                   {"fov_deg", o.fov_deg}};
  if (o.directions.empty()) {
    j["views"] = o.views;
  } else {
    nlohmann::json dirs = nlohmann::json::array();
    for (const Vec3& d : o.directions) dirs.push_back({d.x(), d.y(), d.z()});
    j["views"] = o.directions.size();
    j["directions"] = dirs;
  }
  return j;
}

}  // namespace cdp
