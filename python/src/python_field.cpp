#include "python_field.h"

#include <cdp/core/errors.h>

#include <algorithm>
#include <cstring>

namespace cdp::python {

namespace {

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// Central differences evaluate F (or the user's gradient) on a stencil around each point, laid
// out point after point: a batch of one is the call a single point makes.
//   0: p; 1-6: p +- hg e_k (first derivatives, k = 0, 1, 2);
//   7-12: p +- hh e_k (diagonal second differences of F);
//   13-24: p + (+-hh) e_i + (+-hh) e_j for i < j (mixed second differences of F).
constexpr std::size_t kGradientStencil = 7;
constexpr std::size_t kAxisStencil = 13;  // when the user's Hessian replaces the mixed differences
constexpr std::size_t kFullStencil = 25;
constexpr int kPairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};

void add_axis_points(const Vec3& p, double h, std::vector<Vec3>& out) {
  for (int k = 0; k < 3; ++k) {
    Vec3 a = p, b = p;
    a[k] += h;
    b[k] -= h;
    out.push_back(a);
    out.push_back(b);
  }
}

void add_mixed_points(const Vec3& p, double h, std::vector<Vec3>& out) {
  for (const auto& [i, j] : kPairs)
    for (const double si : {1.0, -1.0})
      for (const double sj : {1.0, -1.0}) {
        Vec3 q = p;
        q[i] += si * h;
        q[j] += sj * h;
        out.push_back(q);
      }
}

// The steps as they came out in floating point, (p + h e_k)_k - p_k and p_k - (p - h e_k)_k: far
// from the origin p + h - p is not h, and central differences divide by what the function was
// actually given.
double step_up(const Vec3& p, int k, double h) { return (p[k] + h) - p[k]; }
double step_down(const Vec3& p, int k, double h) { return p[k] - (p[k] - h); }
double spacing(const Vec3& p, int k, double h) { return step_up(p, k, h) + step_down(p, k, h); }

// The points of p's stencil for a value and gradient (0-6 above), or a value, gradient and Hessian
// from values alone (0-24).
void add_gradient_stencil(const Vec3& p, double hg, std::vector<Vec3>& out) {
  out.push_back(p);
  add_axis_points(p, hg, out);
}
void add_full_stencil(const Vec3& p, double hg, double hh, std::vector<Vec3>& out) {
  add_gradient_stencil(p, hg, out);
  add_axis_points(p, hh, out);
  add_mixed_points(p, hh, out);
}

// The value and gradient at p from F on its stencil, fi[0..6].
double value_gradient_from(const double* fi, const Vec3& p, double hg, Vec3& gradient) {
  for (int k = 0; k < 3; ++k) gradient[k] = (fi[1 + 2 * k] - fi[2 + 2 * k]) / spacing(p, k, hg);
  return fi[0];
}

// The Hessian at p from F on its full stencil, fi[0..24].
Mat3 hessian_from(const double* fi, const Vec3& p, double hh) {
  Mat3 hessian;
  for (int k = 0; k < 3; ++k) {
    const double hp = step_up(p, k, hh), hm = step_down(p, k, hh);
    hessian(k, k) = 2 * ((fi[7 + 2 * k] - fi[0]) / hp - (fi[0] - fi[8 + 2 * k]) / hm) / (hp + hm);
  }
  for (int m = 0; m < 3; ++m) {
    const auto [a, b] = kPairs[m];
    const double* q = &fi[13 + 4 * m];  // ++, +-, -+, --
    hessian(a, b) = hessian(b, a) = (q[0] - q[1] - q[2] + q[3]) / (spacing(p, a, hh) * spacing(p, b, hh));
  }
  return hessian;
}

}  // namespace

PythonField::PythonField(PythonFieldFunctions functions, const Box& bounds, std::optional<double> lipschitz,
                         double gradient_step, double hessian_step, bool smooth)
    : functions_(std::move(functions)), lipschitz_(lipschitz), smooth_(smooth) {
  bounds_ = bounds;
  gradient_step_ = gradient_step > 0 ? gradient_step : kGradientStep * bounds.diagonal();
  hessian_step_ = hessian_step > 0 ? hessian_step : kHessianStep * bounds.diagonal();
}

PythonField::~PythonField() {
  // The functions are let go of here, under the GIL: the last reference to a field may be
  // dropped by C++ code that runs without it.
  if (!Py_IsInitialized()) {
    functions_.value.release();
    functions_.gradient.release();
    functions_.hessian.release();
    return;
  }
  py::gil_scoped_acquire gil;
  functions_ = {};
}

py::array PythonField::call(const py::object& function, const Vec3* points, std::size_t n) const {
  py::array_t<double> argument({static_cast<py::ssize_t>(n), py::ssize_t{3}});
  if (n > 0) std::memcpy(argument.mutable_data(), points, n * sizeof(Vec3));
  python_calls_.fetch_add(1, std::memory_order_relaxed);
  const py::object result = function(argument);
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(result);
  if (!a) {
    const std::string type = py::str(py::type::handle_of(result).attr("__name__"));
    throw InvalidInputError("callable field: a function returned a " + type + " where an array of numbers was expected");
  }
  return a;
}

std::vector<double> PythonField::call_value(const Vec3* points, std::size_t n) const {
  const py::array a = call(functions_.value, points, n);
  const auto rows = static_cast<py::ssize_t>(n);
  // (N, 1) is accepted too: p[:, :1] ** 2 + ... keeps the column.
  if (!((a.ndim() == 1 && a.shape(0) == rows) || (a.ndim() == 2 && a.shape(0) == rows && a.shape(1) == 1)))
    throw InvalidInputError("callable field: f returned shape " + shape_text(a) + " for " + std::to_string(n) +
                            " points; expected (" + std::to_string(n) + ",)");
  std::vector<double> out(n);
  if (n > 0) std::memcpy(out.data(), a.data(), n * sizeof(double));
  return out;
}

std::vector<Vec3> PythonField::call_gradient(const Vec3* points, std::size_t n) const {
  const py::array a = call(functions_.gradient, points, n);
  if (a.ndim() != 2 || a.shape(0) != static_cast<py::ssize_t>(n) || a.shape(1) != 3)
    throw InvalidInputError("callable field: gradient returned shape " + shape_text(a) + " for " + std::to_string(n) +
                            " points; expected (" + std::to_string(n) + ", 3)");
  std::vector<Vec3> out(n);
  const double* d = static_cast<const double*>(a.data());
  for (std::size_t i = 0; i < n; ++i) out[i] = Vec3(d[3 * i], d[3 * i + 1], d[3 * i + 2]);
  return out;
}

std::vector<Mat3> PythonField::call_hessian(const Vec3* points, std::size_t n) const {
  const py::array a = call(functions_.hessian, points, n);
  if (a.ndim() != 3 || a.shape(0) != static_cast<py::ssize_t>(n) || a.shape(1) != 3 || a.shape(2) != 3)
    throw InvalidInputError("callable field: hessian returned shape " + shape_text(a) + " for " + std::to_string(n) +
                            " points; expected (" + std::to_string(n) + ", 3, 3)");
  std::vector<Mat3> out(n);
  const double* d = static_cast<const double*>(a.data());
  // numpy is row-major, Eigen column-major: copy entry by entry.
  for (std::size_t i = 0; i < n; ++i)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) out[i](r, c) = d[9 * i + 3 * r + c];
  return out;
}

void PythonField::eval_values(const Vec3* points, double* out, std::size_t n) const {
  if (n == 0) return;
  py::gil_scoped_acquire gil;
  const std::vector<double> v = call_value(points, n);
  std::memcpy(out, v.data(), n * sizeof(double));
}

double PythonField::eval_value(const Vec3& p) const {
  py::gil_scoped_acquire gil;
  return call_value(&p, 1)[0];
}

double PythonField::eval_value_gradient(const Vec3& p, Vec3& gradient) const {
  double v;
  eval_values_gradients(&p, &v, &gradient, 1);
  return v;
}

double PythonField::eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const {
  double v;
  eval_gradients_hessians(&p, &v, &gradient, &hessian, 1);
  return v;
}

void PythonField::eval_values_gradients(const Vec3* points, double* values, Vec3* gradients, std::size_t n) const {
  if (n == 0) return;
  py::gil_scoped_acquire gil;
  if (has_gradient()) {
    const std::vector<double> v = call_value(points, n);
    const std::vector<Vec3> g = call_gradient(points, n);
    std::copy(v.begin(), v.end(), values);
    std::copy(g.begin(), g.end(), gradients);
    return;
  }
  std::vector<Vec3> stencil;
  stencil.reserve(kGradientStencil * n);
  for (std::size_t i = 0; i < n; ++i) add_gradient_stencil(points[i], gradient_step_, stencil);
  const std::vector<double> f = call_value(stencil.data(), stencil.size());
  for (std::size_t i = 0; i < n; ++i)
    values[i] = value_gradient_from(&f[kGradientStencil * i], points[i], gradient_step_, gradients[i]);
}

void PythonField::eval_gradients_hessians(const Vec3* points, double* values, Vec3* gradients, Mat3* hessians,
                                          std::size_t n) const {
  if (n == 0) return;
  py::gil_scoped_acquire gil;
  std::vector<Vec3> stencil;
  if (has_gradient()) {
    const std::vector<double> v = call_value(points, n);
    std::copy(v.begin(), v.end(), values);
    if (has_hessian()) {
      const std::vector<Vec3> g = call_gradient(points, n);
      const std::vector<Mat3> h = call_hessian(points, n);
      std::copy(g.begin(), g.end(), gradients);
      std::copy(h.begin(), h.end(), hessians);
      return;
    }
    // Central differences of the user's gradient, one call for the stencils of all points.
    stencil.reserve(kGradientStencil * n);
    for (std::size_t i = 0; i < n; ++i) {
      stencil.push_back(points[i]);
      add_axis_points(points[i], gradient_step_, stencil);
    }
    const std::vector<Vec3> g = call_gradient(stencil.data(), stencil.size());
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3* gi = &g[kGradientStencil * i];
      gradients[i] = gi[0];
      Mat3& hessian = hessians[i];
      for (int k = 0; k < 3; ++k) hessian.col(k) = (gi[1 + 2 * k] - gi[2 + 2 * k]) / spacing(points[i], k, gradient_step_);
      hessian = (0.5 * (hessian + hessian.transpose())).eval();
    }
    return;
  }
  // Values only (or a Hessian without a gradient): one call for every point of the stencils.
  const bool mixed = !has_hessian();
  const std::size_t size = mixed ? kFullStencil : kAxisStencil;
  stencil.reserve(size * n);
  for (std::size_t i = 0; i < n; ++i) {
    if (mixed) {
      add_full_stencil(points[i], gradient_step_, hessian_step_, stencil);
    } else {
      add_gradient_stencil(points[i], gradient_step_, stencil);
      add_axis_points(points[i], hessian_step_, stencil);
    }
  }
  const std::vector<double> f = call_value(stencil.data(), stencil.size());
  for (std::size_t i = 0; i < n; ++i) values[i] = value_gradient_from(&f[size * i], points[i], gradient_step_, gradients[i]);
  if (!mixed) {
    const std::vector<Mat3> h = call_hessian(points, n);
    std::copy(h.begin(), h.end(), hessians);
    return;
  }
  for (std::size_t i = 0; i < n; ++i) hessians[i] = hessian_from(&f[size * i], points[i], hessian_step_);
}

void PythonField::eval_together(const Batch& plain, const Batch& with_gradients, const Batch& with_hessians) const {
  // A function given with derivatives of its own is called once for each it needs, as the three
  // batched hooks call it.
  if (has_gradient() || has_hessian()) {
    Field::eval_together(plain, with_gradients, with_hessians);
    return;
  }
  const std::size_t n = plain.n + kGradientStencil * with_gradients.n + kFullStencil * with_hessians.n;
  if (n == 0) return;
  py::gil_scoped_acquire gil;
  // One call: the plain points, then the gradients' stencils, then the Hessians', each laid out as
  // the hooks lay theirs, so each point gets the numbers its own hook would give it.
  std::vector<Vec3> stencil;
  stencil.reserve(n);
  stencil.insert(stencil.end(), plain.points, plain.points + plain.n);
  for (std::size_t i = 0; i < with_gradients.n; ++i) add_gradient_stencil(with_gradients.points[i], gradient_step_, stencil);
  for (std::size_t i = 0; i < with_hessians.n; ++i)
    add_full_stencil(with_hessians.points[i], gradient_step_, hessian_step_, stencil);
  const std::vector<double> f = call_value(stencil.data(), stencil.size());
  std::copy_n(f.begin(), plain.n, plain.values);
  const double* at = f.data() + plain.n;
  for (std::size_t i = 0; i < with_gradients.n; ++i, at += kGradientStencil)
    with_gradients.values[i] = value_gradient_from(at, with_gradients.points[i], gradient_step_, with_gradients.gradients[i]);
  for (std::size_t i = 0; i < with_hessians.n; ++i, at += kFullStencil) {
    const Vec3& p = with_hessians.points[i];
    with_hessians.values[i] = value_gradient_from(at, p, gradient_step_, with_hessians.gradients[i]);
    with_hessians.hessians[i] = hessian_from(at, p, hessian_step_);
  }
}

}  // namespace cdp::python
