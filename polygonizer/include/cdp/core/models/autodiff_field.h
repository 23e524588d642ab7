// A field written once as a template function of the point, with exact gradient and Hessian
// from forward-mode automatic differentiation (autodiff.h).
//
// Derived classes provide  template <class T> T evaluate(const T& x, const T& y, const T& z) const
// and call it with T = double, Jet1 and Jet2. Inside, write `using std::sqrt;` (and so on) so
// that plain numbers find the standard functions and jets find the ones in autodiff.h.
//
// CSG: a model built with min, max and abs (written unqualified, after `using std::max;` and so
// on) reports its smooth pieces (Field::pieces, Field::piece), so that its creases are traced
// and meshed along as an expression's are. Its calls of min, max and abs are its branch points,
// numbered in the order they happen; that order and their number must not depend on the point
// (no `if` on a value around them): a piece evaluated where they differ is an InvalidInputError.
// Qualified calls (`std::max(a, b)`) still compile on jets, through their comparison, but are
// not branch points: the model then counts as smooth there. Arguments are evaluated in an order
// C++ leaves open, so the numbering of nested calls in one argument list (max(abs(x), abs(y)))
// may differ between compilers; within one build it is fixed, which is all pieces need.
#pragma once

#include <cdp/core/autodiff.h>
#include <cdp/core/errors.h>
#include <cdp/core/field.h>

#include <atomic>
#include <string>
#include <utility>

namespace cdp {

// Evaluation is taken to be thread-safe (evaluate is const and, in every model here, reads only
// the model's own data); a derived class with a cache overrides thread_safe() to return false.
template <class Derived>
class AutodiffField : public Field {
 public:
  bool thread_safe() const override { return true; }
  // Whether evaluate calls min, max or abs (counted once, at the centre of the box).
  bool has_branch_points() const override {
    int n = branch_points_.load(std::memory_order_relaxed);
    if (n < 0) {
      detail::BranchTrace trace;
      record(bounds().center(), trace);
      n = static_cast<int>(trace.calls);
      branch_points_.store(n, std::memory_order_relaxed);
    }
    return n > 0;
  }

 protected:
  // The three evaluations have the model's evaluate inlined into them (flatten): evaluate<Jet1>
  // has other callers too (the branch records, eval_first_order), and where GCC 12 then called
  // it out of line, the jets went through memory and a sphere's value and gradient took three
  // times as long (BM_Field/sphere/value_gradient 33.6 -> 92.4 us; the double torus 37 -> 110).
  [[gnu::flatten]] double eval_value(const Vec3& p) const override { return self().evaluate(p.x(), p.y(), p.z()); }
  [[gnu::flatten]] double eval_value_gradient(const Vec3& p, Vec3& gradient) const override {
    const Jet1 r = self().evaluate(Jet1::variable(p.x(), 0), Jet1::variable(p.y(), 1), Jet1::variable(p.z(), 2));
    gradient = r.g;
    return r.v;
  }
  [[gnu::flatten]] double eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const override {
    const Jet2 r = self().evaluate(Jet2::variable(p.x(), 0), Jet2::variable(p.y(), 1), Jet2::variable(p.z(), 2));
    gradient = r.g;
    hessian = r.h;
    return r.v;
  }
  bool eval_branch_record(const Vec3& p, const std::vector<std::uint8_t>& branch, BranchRecord& out) const override {
    detail::BranchTrace trace;
    if (!branch.empty()) {
      trace.forced = &branch;
      trace.record_forced = true;
    }
    record(p, trace);
    if (trace.calls == 0) return false;
    out = std::move(trace.record);
    return true;
  }
  std::pair<double, Vec3> eval_first_order(const Vec3& p, const std::vector<std::uint8_t>& branch) const override {
    detail::BranchTrace trace;
    trace.forced = &branch;
    detail::BranchTraceScope scope(trace);
    const Jet1 r = self().evaluate(Jet1::variable(p.x(), 0), Jet1::variable(p.y(), 1), Jet1::variable(p.z(), 2));
    return {r.v, r.g};
  }
  FieldPiece eval_piece(const Vec3& p, const std::vector<std::uint8_t>& branch) const override {
    detail::BranchTrace trace;
    trace.forced = &branch;
    Jet2 r;
    {
      detail::BranchTraceScope scope(trace);
      r = self().evaluate(Jet2::variable(p.x(), 0), Jet2::variable(p.y(), 1), Jet2::variable(p.z(), 2));
    }
    if (trace.calls != branch.size())
      throw InvalidInputError(this->type_name() + ": a piece's branch has " + std::to_string(branch.size()) +
                              " choices, the model made " + std::to_string(trace.calls) +
                              " calls of min, max and abs at the point (their number must not depend on the point)");
    return piece_from_jet(branch, r);
  }

 private:
  const Derived& self() const { return static_cast<const Derived&>(*this); }
  void record(const Vec3& p, detail::BranchTrace& trace) const {
    detail::BranchTraceScope scope(trace);
    const Jet1 r = self().evaluate(Jet1::variable(p.x(), 0), Jet1::variable(p.y(), 1), Jet1::variable(p.z(), 2));
    trace.record.value = r.v;
    trace.record.gradient = r.g;
  }
  mutable std::atomic<int> branch_points_{-1};  // unknown until has_branch_points is first asked
};

// A compiled model from a functor with a templated call operator, registered by name with
// register_compiled_model (field_factory.h / compiled_models.cpp).
template <class Fn>
class FunctionField : public AutodiffField<FunctionField<Fn>> {
 public:
  // `smooth`: the functor's zero set has no creases (Field::smooth); false unless its author
  // says so.
  FunctionField(std::string name, Fn fn, const Box& bounds, bool smooth = false)
      : name_(std::move(name)), fn_(std::move(fn)), smooth_(smooth) {
    this->set_bounds(bounds);
  }
  std::string type_name() const override { return name_; }
  bool smooth() const override { return smooth_; }
  template <class T>
  T evaluate(const T& x, const T& y, const T& z) const {
    return fn_(x, y, z);
  }

 private:
  std::string name_;
  Fn fn_;
  bool smooth_;
};

}  // namespace cdp
