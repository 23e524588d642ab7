#include <cdp/core/errors.h>
#include <cdp/core/models/analytic.h>

namespace cdp {

namespace {
// Boxes leave a margin around the surface so that seeding grids see F > 0 on the boundary.
constexpr double kMargin = 0.1;
}  // namespace

Sphere::Sphere(const Vec3& center, double radius) : center_(center), radius_(radius) {
  if (!(radius > 0)) throw InvalidInputError("sphere: radius must be positive");
  const Vec3 r = Vec3::Constant(radius * (1 + kMargin));
  set_bounds({center - r, center + r});
}

Ellipsoid::Ellipsoid(const Vec3& center, const Vec3& radii)
    : center_(center), radii_(radii), scale_(radii.minCoeff()) {
  if (!(radii.array() > 0).all()) throw InvalidInputError("ellipsoid: every radius must be positive");
  const Vec3 r = radii * (1 + kMargin);
  set_bounds({center - r, center + r});
}

Torus::Torus(const Vec3& center, double major_radius, double minor_radius)
    : center_(center), major_(major_radius), minor_(minor_radius) {
  if (!(minor_radius > 0) || !(major_radius > minor_radius))
    throw InvalidInputError("torus: need 0 < minor_radius < major_radius");
  const double m = kMargin * minor_radius;
  const Vec3 r(major_ + minor_ + m, major_ + minor_ + m, minor_ + m);
  set_bounds({center - r, center + r});
}

}  // namespace cdp
