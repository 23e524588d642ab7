#include "python_field.h"

#include <cdp/core/errors.h>

#include <cstring>

namespace cdp::python {

namespace {

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// The points p, p + h e_k, p - h e_k (k = 0, 1, 2), and the steps as they came out in floating
// point: far from the origin p + h - p is not h, and central differences divide by what the
// function was actually given.
struct Stencil {
  std::vector<Vec3> points;
  Vec3 plus = Vec3::Zero(), minus = Vec3::Zero();  // (p + h e_k)_k - p_k and p_k - (p - h e_k)_k
};

void add_axis_points(const Vec3& p, double h, Stencil& s) {
  for (int k = 0; k < 3; ++k) {
    Vec3 a = p, b = p;
    a[k] += h;
    b[k] -= h;
    s.points.push_back(a);
    s.points.push_back(b);
    s.plus[k] = a[k] - p[k];
    s.minus[k] = p[k] - b[k];
  }
}

}  // namespace

PythonField::PythonField(PythonFieldFunctions functions, const Box& bounds, std::optional<double> lipschitz,
                         double gradient_step, double hessian_step)
    : functions_(std::move(functions)), lipschitz_(lipschitz) {
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
  py::gil_scoped_acquire gil;
  if (has_gradient()) {
    const double v = call_value(&p, 1)[0];
    gradient = call_gradient(&p, 1)[0];
    return v;
  }
  Stencil s;
  s.points.push_back(p);
  add_axis_points(p, gradient_step_, s);
  const std::vector<double> f = call_value(s.points.data(), s.points.size());
  for (int k = 0; k < 3; ++k) gradient[k] = (f[1 + 2 * k] - f[2 + 2 * k]) / (s.plus[k] + s.minus[k]);
  return f[0];
}

double PythonField::eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const {
  py::gil_scoped_acquire gil;
  if (has_gradient()) {
    const double v = call_value(&p, 1)[0];
    if (has_hessian()) {
      gradient = call_gradient(&p, 1)[0];
      hessian = call_hessian(&p, 1)[0];
      return v;
    }
    // Central differences of the user's gradient, one call for all seven points.
    Stencil s;
    s.points.push_back(p);
    add_axis_points(p, gradient_step_, s);
    const std::vector<Vec3> g = call_gradient(s.points.data(), s.points.size());
    gradient = g[0];
    for (int k = 0; k < 3; ++k) hessian.col(k) = (g[1 + 2 * k] - g[2 + 2 * k]) / (s.plus[k] + s.minus[k]);
    hessian = (0.5 * (hessian + hessian.transpose())).eval();
    return v;
  }
  // Values only (or a Hessian without a gradient): one call for every point of the stencils.
  // 0: p; 1-6: p +- hg e_k (gradient); 7-12: p +- hh e_k (diagonal of the Hessian);
  // 13-24: p + (+-hh) e_i + (+-hh) e_j for i < j (mixed second differences).
  Stencil g, h;
  g.points.push_back(p);
  add_axis_points(p, gradient_step_, g);
  add_axis_points(p, hessian_step_, h);
  std::vector<Vec3> points = g.points;
  points.insert(points.end(), h.points.begin(), h.points.end());
  const bool mixed = !has_hessian();
  constexpr int kPairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  if (mixed)
    for (const auto& [i, j] : kPairs)
      for (const double si : {1.0, -1.0})
        for (const double sj : {1.0, -1.0}) {
          Vec3 q = p;
          q[i] += si * hessian_step_;
          q[j] += sj * hessian_step_;
          points.push_back(q);
        }
  const std::vector<double> f = call_value(points.data(), points.size());
  for (int k = 0; k < 3; ++k) gradient[k] = (f[1 + 2 * k] - f[2 + 2 * k]) / (g.plus[k] + g.minus[k]);
  if (!mixed) {
    hessian = call_hessian(&p, 1)[0];
    return f[0];
  }
  for (int k = 0; k < 3; ++k) {
    const double hp = h.plus[k], hm = h.minus[k];
    hessian(k, k) = 2 * ((f[7 + 2 * k] - f[0]) / hp - (f[0] - f[8 + 2 * k]) / hm) / (hp + hm);
  }
  for (int n = 0; n < 3; ++n) {
    const auto [i, j] = kPairs[n];
    const double* q = &f[13 + 4 * n];  // ++, +-, -+, --
    hessian(i, j) = hessian(j, i) = (q[0] - q[1] - q[2] + q[3]) / ((h.plus[i] + h.minus[i]) * (h.plus[j] + h.minus[j]));
  }
  return f[0];
}

}  // namespace cdp::python
