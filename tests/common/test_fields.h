// Small fields shared by the tests of every module.
#pragma once

#include <cdp/core/models/analytic.h>
#include <cdp/core/models/blobs.h>
#include <cdp/core/models/expression.h>
#include <cdp/io/field_factory.h>

#include <cmath>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

namespace cdp::test {

inline constexpr const char* kTanglecube = "x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + 11.8";
// Two overlapping spheres (radius 0.85 at x = -0.5 and 0.5) on a bar (|x| <= 1.2,
// -1.15 <= y <= -0.65, |z| <= 0.25), in the box +-1.7: where the spheres' seam meets the bar's
// top face, three of its corners lie within 0.03 of each other.
inline constexpr const char* kSpheresOnABar =
    "min(min(sqrt((x-0.5)^2+y^2+z^2)-0.85, sqrt((x+0.5)^2+y^2+z^2)-0.85), "
    "max(abs(x)-1.2,max(abs(y+0.9)-0.25,abs(z)-0.25)))";

inline std::unique_ptr<Field> tanglecube() {
  return std::make_unique<Expression>(kTanglecube, std::map<std::string, double>{}, Box{{-3, -3, -3}, {3, 3, 3}});
}

// Three Wyvill blobs far apart: three sphere-like components.
inline std::unique_ptr<Field> three_separate_blobs() {
  return std::make_unique<Blobs>(BlobKernel::Wyvill, 0.3,
                                 std::vector<Blob>{{{0, 0, 0}, 1.0, 1.0}, {{3, 0, 0}, 1.0, 1.0}, {{0, 3, 0.5}, 1.2, 1.0}});
}

// The JSON of an expression field in the cube [-half, half]^3.
inline std::string expression(const std::string& value, double half) {
  std::ostringstream s;
  s << R"({"type": "expression", "value": ")" << value << R"(", "bounds": [[)" << -half << ", " << -half << ", "
    << -half << "], [" << half << ", " << half << ", " << half << "]]}";
  return s.str();
}

// The distance of p from the field's zero set, to first order: |F| / |grad F|.
inline double first_order_distance(const Field& f, const Vec3& p) {
  Vec3 g;
  const double v = f.value_gradient(p, g);
  return std::abs(v) / g.norm();
}

// A field from JSON text, as a user would write it.
inline std::unique_ptr<Field> field_from_json(const std::string& text) {
  return make_field(nlohmann::json::parse(text), "<test>");
}

// The same field, claiming what it is told, for tests of what the claims change: not smooth (as
// a callable's), the repair probes every vertex it touches for a crease; not thread-safe (as a
// Python function), the relaxation projects in one batch and the refinement measures in batches;
// asking for predicted estimates (Field::predicts_from_hessians, as a VIS model does), the
// repair predicts its estimates' midpoints and centroids from the vertices' Hessians.
class Rewrapped : public Field {
 public:
  Rewrapped(const Field& f, bool smooth, bool thread_safe, bool predicts_from_hessians = false)
      : f_(f), smooth_(smooth), thread_safe_(thread_safe), predicts_(predicts_from_hessians) {
    set_bounds(f.bounds());
  }
  std::string type_name() const override { return "rewrapped"; }
  bool smooth() const override { return smooth_; }
  bool thread_safe() const override { return thread_safe_; }
  bool predicts_from_hessians() const override { return predicts_; }
  std::optional<double> lipschitz_bound() const override { return f_.lipschitz_bound(); }

 protected:
  double eval_value(const Vec3& p) const override { return f_.value(p); }
  double eval_value_gradient(const Vec3& p, Vec3& g) const override { return f_.value_gradient(p, g); }
  double eval_gradient_hessian(const Vec3& p, Vec3& g, Mat3& h) const override { return f_.gradient_hessian(p, g, h); }

 private:
  const Field& f_;
  bool smooth_, thread_safe_, predicts_;
};

}  // namespace cdp::test
