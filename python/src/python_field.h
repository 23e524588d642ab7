// A field defined by Python functions, called vectorised on (N, 3) float64 arrays: F returns
// (N,), the optional gradient (N, 3), the optional Hessian (N, 3, 3). Missing derivatives come
// from central differences (python/README.md gives the steps and the accuracy measured).
//
// Every evaluation takes the GIL, so the algorithms may call it from any thread (the ray casting
// of cdp.evaluate runs on TBB's) once the binding has released it. Each batched evaluation
// (values, values_gradients, gradients_hessians) is one Python call of each function it needs,
// the finite differences putting all the stencil points of all the batch's points into that one
// call: the seed grid and the marching lattices ask for values in slabs, the adaptive tracker for
// the points of each expansion's Newton round and curvature together, the batched Newton
// projection for its points still iterating; tasks in lockstep ask for all three kinds in one call
// (eval_together). A single-point evaluation is a batch of one.
#pragma once

#include "bindings.h"

#include <atomic>
#include <optional>

namespace cdp::python {

struct PythonFieldFunctions {
  py::object value;
  py::object gradient;  // None: central differences of value
  py::object hessian;   // None: central differences of gradient (or of value)
};

class PythonField final : public Field {
 public:
  // Steps are absolute lengths; non-positive means the defaults (kGradientStep and kHessianStep
  // times the box diagonal).
  PythonField(PythonFieldFunctions functions, const Box& bounds, std::optional<double> lipschitz, double gradient_step,
              double hessian_step, bool smooth = false);
  ~PythonField() override;

  std::string type_name() const override { return "python"; }
  std::optional<double> lipschitz_bound() const override { return lipschitz_; }
  bool smooth() const override { return smooth_; }  // as its caller promised
  bool costly_calls() const override { return true; }  // each call enters the interpreter
  // The Hessian's step: second differences of F, or first differences of the given gradient.
  std::optional<double> derivative_step() const override {
    if (has_hessian() && has_gradient()) return std::nullopt;
    return has_gradient() || has_hessian() ? gradient_step_ : hessian_step_;
  }

  double gradient_step() const { return gradient_step_; }
  double hessian_step() const { return hessian_step_; }
  bool has_gradient() const { return !functions_.gradient.is_none(); }
  bool has_hessian() const { return !functions_.hessian.is_none(); }
  // Calls into Python so far, of any of the functions.
  std::uint64_t python_calls() const { return python_calls_.load(std::memory_order_relaxed); }
  void reset_python_calls() const { python_calls_ = 0; }

  // Default steps, relative to the box diagonal: about the cube root (first derivatives) and
  // fourth root (second differences of values) of the double precision epsilon, where the
  // truncation and rounding errors of central differences balance for a field that varies on
  // the scale of its box.
  static constexpr double kGradientStep = 1e-5;
  static constexpr double kHessianStep = 1e-4;

 protected:
  double eval_value(const Vec3& p) const override;
  double eval_value_gradient(const Vec3& p, Vec3& gradient) const override;
  double eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const override;
  void eval_values(const Vec3* points, double* out, std::size_t n) const override;
  void eval_values_gradients(const Vec3* points, double* values, Vec3* gradients, std::size_t n) const override;
  void eval_gradients_hessians(const Vec3* points, double* values, Vec3* gradients, Mat3* hessians,
                               std::size_t n) const override;
  // Without derivatives of its own: one call of F for the three batches' stencils.
  void eval_together(const Batch& plain, const Batch& with_gradients, const Batch& with_hessians) const override;

 private:
  // The GIL must be held. Check the shapes the functions return and throw InvalidInputError
  // naming the function otherwise.
  std::vector<double> call_value(const Vec3* points, std::size_t n) const;
  std::vector<Vec3> call_gradient(const Vec3* points, std::size_t n) const;
  std::vector<Mat3> call_hessian(const Vec3* points, std::size_t n) const;
  py::array call(const py::object& function, const Vec3* points, std::size_t n) const;

  PythonFieldFunctions functions_;
  std::optional<double> lipschitz_;
  double gradient_step_;
  double hessian_step_;
  bool smooth_;
  mutable std::atomic<std::uint64_t> python_calls_{0};
};

}  // namespace cdp::python
