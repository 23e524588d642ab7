// A field written once as a template function of the point, with exact gradient and Hessian
// from forward-mode automatic differentiation (autodiff.h).
//
// Derived classes provide  template <class T> T evaluate(const T& x, const T& y, const T& z) const
// and call it with T = double, Jet1 and Jet2. Inside, write `using std::sqrt;` (and so on) so
// that plain numbers find the standard functions and jets find the ones in autodiff.h.
#pragma once

#include <cdp/core/autodiff.h>
#include <cdp/core/field.h>

#include <string>
#include <utility>

namespace cdp {

// Evaluation is taken to be thread-safe (evaluate is const and, in every model here, reads only
// the model's own data); a derived class with a cache overrides thread_safe() to return false.
template <class Derived>
class AutodiffField : public Field {
 public:
  bool thread_safe() const override { return true; }

 protected:
  double eval_value(const Vec3& p) const override { return self().evaluate(p.x(), p.y(), p.z()); }
  double eval_value_gradient(const Vec3& p, Vec3& gradient) const override {
    const Jet1 r = self().evaluate(Jet1::variable(p.x(), 0), Jet1::variable(p.y(), 1), Jet1::variable(p.z(), 2));
    gradient = r.g;
    return r.v;
  }
  double eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const override {
    const Jet2 r = self().evaluate(Jet2::variable(p.x(), 0), Jet2::variable(p.y(), 1), Jet2::variable(p.z(), 2));
    gradient = r.g;
    hessian = r.h;
    return r.v;
  }

 private:
  const Derived& self() const { return static_cast<const Derived&>(*this); }
};

// A compiled model from a functor with a templated call operator, registered by name with
// register_compiled_model (field_factory.h / compiled_models.cpp).
template <class Fn>
class FunctionField : public AutodiffField<FunctionField<Fn>> {
 public:
  FunctionField(std::string name, Fn fn, const Box& bounds) : name_(std::move(name)), fn_(std::move(fn)) {
    this->set_bounds(bounds);
  }
  std::string type_name() const override { return name_; }
  template <class T>
  T evaluate(const T& x, const T& y, const T& z) const {
    return fn_(x, y, z);
  }

 private:
  std::string name_;
  Fn fn_;
};

}  // namespace cdp
