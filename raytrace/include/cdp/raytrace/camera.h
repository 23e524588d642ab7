// The rays of the evaluation: a deterministic set of views around a field's box, N x N rays each.
// Ground truth and mesh hits are computed for exactly these rays, so they are compared one to one.
#pragma once

#include <cdp/core/field.h>

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace cdp {

// A ray o + t d, t >= 0, with a unit direction d (so t is a distance).
struct Ray {
  Vec3 origin = Vec3::Zero();
  Vec3 direction = Vec3::UnitZ();
};

enum class Projection { Perspective, Orthographic };

// \return "perspective" or "orthographic".
const char* to_string(Projection projection);
// Throws InvalidInputError on anything but "perspective" or "orthographic".
// \throw InvalidInputError for any other name.
Projection parse_projection(const std::string& name);

struct CameraOptions {
  // Number of views; their viewing directions follow a Fibonacci spiral on the unit sphere, which
  // avoids the axis-aligned directions where rays run along the symmetry planes of most models.
  int views = 8;
  // Rays per view along each side of the image: resolution^2 rays per view.
  int resolution = 64;
  Projection projection = Projection::Perspective;
  // Eye distance from the box centre, in units of the box's half-diagonal (its bounding sphere's
  // radius); must be > 1 so the eye is outside the box.
  double distance = 3.0;
  // Perspective: full field of view in degrees; 0 fits the square image to the projected corners
  // of the box (with a 2% margin). Orthographic: unused; the image always fits the box corners.
  double fov_deg = 0.0;
  // Explicit viewing directions (the eye looks along them); when not empty they replace `views`.
  std::vector<Vec3> directions;
};

// Throws InvalidInputError on out-of-range options (the box is checked by make_camera_rays).
// \throw InvalidInputError for views outside [1, 10000] (without directions), resolution outside
//        [1, 8192], a distance not above 1 or not finite, fov_deg outside [0, 180), or a direction
//        that is zero or not finite.
void validate(const CameraOptions& options);

// The viewing direction of every view, unit length, in order.
// \pre the options pass validate (unchecked here: a zero direction stays zero, views < 1 gives none).
std::vector<Vec3> view_directions(const CameraOptions& options);

// All rays, view after view, each view row after row (row-major, pixel centres). Deterministic.
// \return resolution^2 rays per view direction.
// \throw InvalidInputError as validate, for a box that is not valid, or for one whose diagonal times
//        the distance overflows.
std::vector<Ray> make_camera_rays(const Box& box, const CameraOptions& options);

// The options as written into metrics and cache keys (every field that changes the rays).
nlohmann::json to_json(const CameraOptions& options);

}  // namespace cdp
