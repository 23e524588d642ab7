// Closed-form shapes, written as signed distance functions (exact distance for the sphere and
// the torus, scaled for the ellipsoid) so that |grad F| <= 1 and the Lipschitz bound is 1.
#pragma once

#include <cdp/core/models/autodiff_field.h>

namespace cdp {

class Sphere : public AutodiffField<Sphere> {
 public:
  Sphere(const Vec3& center, double radius);
  std::string type_name() const override { return "sphere"; }
  std::optional<double> lipschitz_bound() const override { return 1.0; }
  bool smooth() const override { return true; }
  template <class T>
  T evaluate(const T& x, const T& y, const T& z) const {
    using std::sqrt;
    const T dx = x - center_.x(), dy = y - center_.y(), dz = z - center_.z();
    return sqrt(dx * dx + dy * dy + dz * dz) - radius_;
  }

 private:
  Vec3 center_;
  double radius_;
};

// F = m (|((x-cx)/a, (y-cy)/b, (z-cz)/c)| - 1) with m = min(a, b, c).
class Ellipsoid : public AutodiffField<Ellipsoid> {
 public:
  Ellipsoid(const Vec3& center, const Vec3& radii);
  std::string type_name() const override { return "ellipsoid"; }
  std::optional<double> lipschitz_bound() const override { return 1.0; }
  bool smooth() const override { return true; }
  template <class T>
  T evaluate(const T& x, const T& y, const T& z) const {
    using std::sqrt;
    const T u = (x - center_.x()) / radii_.x(), v = (y - center_.y()) / radii_.y(), w = (z - center_.z()) / radii_.z();
    return scale_ * (sqrt(u * u + v * v + w * w) - 1.0);
  }

 private:
  Vec3 center_, radii_;
  double scale_;
};

// Torus around the z axis through `center`: F = |(rho - R, z)| - r with rho the distance to the axis.
class Torus : public AutodiffField<Torus> {
 public:
  Torus(const Vec3& center, double major_radius, double minor_radius);
  std::string type_name() const override { return "torus"; }
  std::optional<double> lipschitz_bound() const override { return 1.0; }
  bool smooth() const override { return true; }
  double major_radius() const { return major_; }
  double minor_radius() const { return minor_; }
  template <class T>
  T evaluate(const T& x, const T& y, const T& z) const {
    using std::sqrt;
    const T dx = x - center_.x(), dy = y - center_.y(), dz = z - center_.z();
    const T q = sqrt(dx * dx + dy * dy) - major_;
    return sqrt(q * q + dz * dz) - minor_;
  }

 private:
  Vec3 center_;
  double major_, minor_;
};

}  // namespace cdp
