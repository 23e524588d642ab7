// Compiled models: a C++ model is one templated function of the point; gradient and Hessian
// come from automatic differentiation. To add one, write the functor and add one line to the
// list at the bottom. Its JSON (cdp::io's field factory) is {"type": "<name>"} with an optional "bounds".
#include <cdp/core/errors.h>
#include <cdp/core/models/autodiff_field.h>

#include <cdp/core/models/compiled.h>

#include <algorithm>
#include <cmath>

namespace cdp {

namespace {

// Genus-2 surface (a smooth double torus): (x (x-1)^2 (x-2) + y^2)^2 + z^2 - 0.01, whose
// cross-section z = 0 has two holes, around x = 0.5 and x = 1.5.
struct DoubleTorus {
  template <class T>
  T operator()(const T& x, const T& y, const T& z) const {
    const T a = x * (x - 1.0) * (x - 1.0) * (x - 2.0) + y * y;
    return a * a + z * z - 0.01;
  }
};

// Tanglecube (genus 5), the same surface as the expression example, compiled.
struct Tanglecube {
  template <class T>
  T operator()(const T& x, const T& y, const T& z) const {
    const T x2 = x * x, y2 = y * y, z2 = z * z;
    return x2 * x2 - 5.0 * x2 + y2 * y2 - 5.0 * y2 + z2 * z2 - 5.0 * z2 + 11.8;
  }
};

// A cylinder with flat caps, max(sqrt(x^2 + y^2) - 1, |z| - 1): a CSG shape, whose two circular
// creases are traced from its pieces (min, max and abs are its branch points) and meshed along.
struct CappedCylinder {
  template <class T>
  T operator()(const T& x, const T& y, const T& z) const {
    using std::abs, std::max, std::sqrt;
    return max(sqrt(x * x + y * y) - 1.0, abs(z) - 1.0);
  }
};

// `smooth`: a polynomial or other functor without creases on its zero set (Field::smooth).
template <class Fn>
CompiledModelMaker compiled(const std::string& name, const Box& bounds, bool smooth) {
  return [name, bounds, smooth]() -> std::unique_ptr<Field> {
    return std::make_unique<FunctionField<Fn>>(name, Fn{}, bounds, smooth);
  };
}

}  // namespace

std::map<std::string, CompiledModelMaker> compiled_models() {
  return {
      {"capped_cylinder", compiled<CappedCylinder>("capped_cylinder", Box{{-1.5, -1.5, -1.5}, {1.5, 1.5, 1.5}}, false)},
      {"double_torus", compiled<DoubleTorus>("double_torus", Box{{-0.3, -0.7, -0.3}, {2.3, 0.7, 0.3}}, true)},
      {"tanglecube", compiled<Tanglecube>("tanglecube", Box{{-3, -3, -3}, {3, 3, 3}}, true)},
  };
}

}  // namespace cdp
