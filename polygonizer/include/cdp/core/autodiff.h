// Forward-mode automatic differentiation in three variables, to second order.
// Values are computed exactly as with plain doubles, so value(), value_gradient() and
// gradient_hessian() of a model agree to the last bit.
//
// Jet<1> carries a value and its gradient, Jet<2> also the Hessian. A model written once as a
// template over its scalar type T (double, Jet<1>, Jet<2>) gets exact derivatives: every
// operation applies the chain rule f(u) -> {f, f' du, f' d2u + f'' du du^T}.
#pragma once

#include <cdp/core/field.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

namespace cdp {

namespace detail {
struct NoHessian {};
}  // namespace detail

template <int Order>
struct Jet {
  static_assert(Order == 1 || Order == 2);
  double v = 0;
  Vec3 g = Vec3::Zero();
  std::conditional_t<Order == 2, Mat3, detail::NoHessian> h{};

  Jet() {
    if constexpr (Order == 2) h.setZero();
  }
  Jet(double value) : v(value) {  // NOLINT: constants mix freely with jets
    if constexpr (Order == 2) h.setZero();
  }
  // The coordinate variable number `axis` (0, 1, 2) at value `value`.
  static Jet variable(double value, int axis) {
    Jet j(value);
    j.g[axis] = 1.0;
    return j;
  }
};

using Jet1 = Jet<1>;
using Jet2 = Jet<2>;

// f(u) given f(v), f'(v), f''(v).
template <int O>
inline Jet<O> chain(const Jet<O>& u, double f, double df, double d2f) {
  Jet<O> r(f);
  r.g = df * u.g;
  if constexpr (O == 2) r.h = df * u.h + d2f * (u.g * u.g.transpose());
  return r;
}

template <int O>
inline Jet<O> operator+(const Jet<O>& a, const Jet<O>& b) {
  Jet<O> r(a.v + b.v);
  r.g = a.g + b.g;
  if constexpr (O == 2) r.h = a.h + b.h;
  return r;
}
template <int O>
inline Jet<O> operator-(const Jet<O>& a, const Jet<O>& b) {
  Jet<O> r(a.v - b.v);
  r.g = a.g - b.g;
  if constexpr (O == 2) r.h = a.h - b.h;
  return r;
}
template <int O>
inline Jet<O> operator-(const Jet<O>& a) {
  Jet<O> r(-a.v);
  r.g = -a.g;
  if constexpr (O == 2) r.h = -a.h;
  return r;
}
template <int O>
inline Jet<O> operator*(const Jet<O>& a, const Jet<O>& b) {
  Jet<O> r(a.v * b.v);
  r.g = a.v * b.g + b.v * a.g;
  if constexpr (O == 2) r.h = a.v * b.h + b.v * a.h + a.g * b.g.transpose() + b.g * a.g.transpose();
  return r;
}
template <int O>
inline Jet<O> operator/(const Jet<O>& a, const Jet<O>& b) {
  const double inv = 1.0 / b.v;
  Jet<O> r = a * chain(b, inv, -inv * inv, 2.0 * inv * inv * inv);
  r.v = a.v / b.v;  // the value exactly as plain doubles compute it
  return r;
}

// Mixed with plain numbers (ints convert: these are not templates in the scalar argument).
#define CDP_JET_SCALAR_OPS(O)                                                                     \
  inline Jet<O> operator+(const Jet<O>& a, double b) { Jet<O> r = a; r.v += b; return r; }       \
  inline Jet<O> operator+(double a, const Jet<O>& b) { return b + a; }                            \
  inline Jet<O> operator-(const Jet<O>& a, double b) { return a + (-b); }                         \
  inline Jet<O> operator-(double a, const Jet<O>& b) { return (-b) + a; }                         \
  inline Jet<O> operator*(const Jet<O>& a, double b) { return chain(a, a.v * b, b, 0.0); }        \
  inline Jet<O> operator*(double a, const Jet<O>& b) { return b * a; }                            \
  inline Jet<O> operator/(const Jet<O>& a, double b) { return chain(a, a.v / b, 1.0 / b, 0.0); }                    \
  inline Jet<O> operator/(double a, const Jet<O>& b) { return Jet<O>(a) / b; }                    \
  inline bool operator<(const Jet<O>& a, const Jet<O>& b) { return a.v < b.v; }                   \
  inline bool operator>(const Jet<O>& a, const Jet<O>& b) { return a.v > b.v; }                   \
  inline bool operator<(const Jet<O>& a, double b) { return a.v < b; }                            \
  inline bool operator>(const Jet<O>& a, double b) { return a.v > b; }                            \
  inline Jet<O>& operator+=(Jet<O>& a, const Jet<O>& b) { return a = a + b; }                     \
  inline Jet<O>& operator-=(Jet<O>& a, const Jet<O>& b) { return a = a - b; }                     \
  inline Jet<O>& operator*=(Jet<O>& a, const Jet<O>& b) { return a = a * b; }                     \
  inline Jet<O>& operator/=(Jet<O>& a, const Jet<O>& b) { return a = a / b; }
CDP_JET_SCALAR_OPS(1)
CDP_JET_SCALAR_OPS(2)
#undef CDP_JET_SCALAR_OPS

template <int O>
inline Jet<O> sqrt(const Jet<O>& u) {
  const double s = std::sqrt(u.v);
  return chain(u, s, 0.5 / s, -0.25 / (s * u.v));
}
template <int O>
inline Jet<O> exp(const Jet<O>& u) {
  const double e = std::exp(u.v);
  return chain(u, e, e, e);
}
template <int O>
inline Jet<O> log(const Jet<O>& u) {
  return chain(u, std::log(u.v), 1.0 / u.v, -1.0 / (u.v * u.v));
}
template <int O>
inline Jet<O> sin(const Jet<O>& u) {
  const double s = std::sin(u.v);
  return chain(u, s, std::cos(u.v), -s);
}
template <int O>
inline Jet<O> cos(const Jet<O>& u) {
  const double c = std::cos(u.v);
  return chain(u, c, -std::sin(u.v), -c);
}
template <int O>
inline Jet<O> tan(const Jet<O>& u) {
  const double t = std::tan(u.v);
  const double d = 1.0 + t * t;
  return chain(u, t, d, 2.0 * t * d);
}

template <int O>
inline Jet<O> atan(const Jet<O>& u) {
  const double d = 1.0 / (1.0 + u.v * u.v);
  return chain(u, std::atan(u.v), d, -2.0 * u.v * d * d);
}
// The angle of (x, y) in (-pi, pi]: smooth except across its cut, the half-line x < 0, y = 0,
// where it jumps by 2 pi (and undefined at the origin, where its gradient is not finite).
template <int O>
inline Jet<O> atan2(const Jet<O>& y, const Jet<O>& x) {
  const double r2 = x.v * x.v + y.v * y.v;
  const double fy = x.v / r2, fx = -y.v / r2;
  Jet<O> r(std::atan2(y.v, x.v));
  r.g = fy * y.g + fx * x.g;
  if constexpr (O == 2) {
    const double r4 = r2 * r2;
    const double fxx = 2.0 * x.v * y.v / r4, fyy = -fxx, fxy = (y.v * y.v - x.v * x.v) / r4;
    r.h = fy * y.h + fx * x.h + fxx * (x.g * x.g.transpose()) + fyy * (y.g * y.g.transpose()) +
          fxy * (x.g * y.g.transpose() + y.g * x.g.transpose());
  }
  return r;
}
// Steps (floor, round): constant between their jumps, so zero derivatives there. A model that
// repeats a shape with them (x - p * round(x / p)) must keep its surface off the jumps, where
// the copies meet: nothing reports a crease there.
template <int O>
inline Jet<O> floor(const Jet<O>& u) {
  return Jet<O>(std::floor(u.v));
}
template <int O>
inline Jet<O> round(const Jet<O>& u) {
  return Jet<O>(std::round(u.v));
}

namespace detail {

// The branch points of a model written over jets (AutodiffField): while a BranchTrace is
// installed on this thread (BranchTraceScope), every min, max and abs of jets is a branch
// point, numbered in the order the calls happen, and either records the branch it takes and
// how far its switch lies (the pieces near a point, Field::pieces) or takes a given branch
// (one piece evaluated elsewhere, Field::piece). Branch 0 is the first argument of min and max
// and +u for abs, 1 the second argument and -u, as in expressions. Without a trace (every
// ordinary evaluation) they only cost the test of a null pointer.
struct BranchTrace {
  const std::vector<std::uint8_t>* forced = nullptr;  // take these branches; record when null
  bool record_forced = false;                         // record also where forced
  Field::BranchRecord record;                         // recorded: the branch taken, where it switches
  std::size_t calls = 0;                              // branch points met
};

inline thread_local BranchTrace* active_branch_trace = nullptr;

class BranchTraceScope {
 public:
  explicit BranchTraceScope(BranchTrace& trace) : previous_(active_branch_trace) { active_branch_trace = &trace; }
  ~BranchTraceScope() { active_branch_trace = previous_; }
  BranchTraceScope(const BranchTraceScope&) = delete;
  BranchTraceScope& operator=(const BranchTraceScope&) = delete;

 private:
  BranchTrace* previous_;
};

// Whether a branch point between a and b takes branch 1, given that the values choose
// `natural` (a branch point past the forced ones takes its natural branch and is counted, so
// that the caller sees the mismatch).
template <int O>
bool take_branch(BranchTrace& t, bool natural, const Jet<O>& a, const Jet<O>& b) {
  const std::size_t k = t.calls++;
  bool taken = natural;
  if (t.forced && k < t.forced->size() && (*t.forced)[k] != Field::kFreeBranch) taken = (*t.forced)[k] != 0;
  if (!t.forced || t.record_forced) t.record.add(taken, a.v - b.v, a.g - b.g);
  return taken;
}

}  // namespace detail

template <int O>
inline Jet<O> abs(const Jet<O>& u) {
  if (detail::BranchTrace* t = detail::active_branch_trace) return detail::take_branch(*t, u.v < 0, u, -u) ? -u : u;
  return u.v < 0 ? -u : u;
}
template <int O>
inline Jet<O> min(const Jet<O>& a, const Jet<O>& b) {
  if (detail::BranchTrace* t = detail::active_branch_trace) return detail::take_branch(*t, b.v < a.v, a, b) ? b : a;
  return b.v < a.v ? b : a;
}
template <int O>
inline Jet<O> max(const Jet<O>& a, const Jet<O>& b) {
  if (detail::BranchTrace* t = detail::active_branch_trace) return detail::take_branch(*t, a.v < b.v, a, b) ? b : a;
  return a.v < b.v ? b : a;
}
// u^p for a constant exponent: exact for negative u when p is an integer.
template <int O>
inline Jet<O> pow(const Jet<O>& u, double p) {
  if (p == 0.0) return Jet<O>(1.0);
  if (p == 1.0) return u;
  if (p == 2.0) return u * u;
  const double f = std::pow(u.v, p);
  const double df = p * std::pow(u.v, p - 1.0);
  const double d2f = (p == 1.0) ? 0.0 : p * (p - 1.0) * std::pow(u.v, p - 2.0);
  return chain(u, f, df, d2f);
}
template <int O>
inline Jet<O> pow(const Jet<O>& u, const Jet<O>& w) {
  Jet<O> r = exp(w * log(u));
  r.v = std::pow(u.v, w.v);
  return r;
}
template <int O>
inline Jet<O> pow(double a, const Jet<O>& w) {
  Jet<O> r = exp(w * std::log(a));
  r.v = std::pow(a, w.v);
  return r;
}

// A field's piece (Field::pieces) from its branches and a second-order jet of it.
inline FieldPiece piece_from_jet(const std::vector<std::uint8_t>& branch, const Jet2& r) {
  FieldPiece piece;
  piece.branch = branch;
  piece.value = r.v;
  piece.gradient = r.g;
  piece.hessian = r.h;
  return piece;
}

// Value of a plain number or a jet, for code templated on the scalar type.
inline double value_of(double x) { return x; }
template <int O>
inline double value_of(const Jet<O>& j) {
  return j.v;
}

}  // namespace cdp
