// Interval arithmetic for a formula over a box: Interval bounds a value, IntervalDual a value and
// its derivative along one direction (forward differentiation with intervals). The expression
// program runs with them as with doubles and jets (expression.cpp), which gives
// Expression::value_range and derivative_range, the bounds the seeding's search and band scan
// prove regions with (see Field).
//
// Every bound is a proof, so every result is rounded outward (a bound rounded inward could
// prove a box empty that is not), and what cannot be bounded is the whole line: a division by an
// interval holding zero, a square root's slope at zero, the jump of floor, round or atan2's cut.
// The bounds are not tight where a variable occurs more than once (x * x over [-1, 1] is
// [-1, 1]); that costs proofs, never soundness.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

namespace cdp::detail {

struct Interval {
  double lo = 0, hi = 0;
  Interval() = default;
  Interval(double c) : lo(c), hi(c) {}  // NOLINT(google-explicit-constructor): the formula's constants
  Interval(double a, double b) : lo(a), hi(b) {}

  static Interval entire() {
    return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  }
  static std::pair<double, double> entire_pair() {
    return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  }
  // A bound that holds: not NaN (a NaN operand, inf - inf).
  bool known() const { return !std::isnan(lo) && !std::isnan(hi); }
  bool has_zero() const { return lo <= 0 && hi >= 0; }
};

// [lo, hi] moved outward by at least one unit in the last place each: the operations below are
// within half an ulp (+, -, *, /, sqrt) or one (glibc's exp, log, sin, cos, tan, atan, atan2)
// of the exact result, so the exact bounds lie inside. |x| 2^-52 is at least x's ulp (plus the
// smallest subnormal, for the subnormals and zero); two multiply-adds, several times cheaper
// than std::nextafter, which a formula's interval run spends most of its time in otherwise.
inline Interval outward(double lo, double hi) {
  constexpr double ulp = 0x1p-52, tiny = std::numeric_limits<double>::denorm_min();
  if (std::isnan(lo) || std::isnan(hi)) return Interval::entire();
  return {lo - (std::abs(lo) * ulp + tiny), hi + (std::abs(hi) * ulp + tiny)};
}
inline Interval hull(const Interval& a, const Interval& b) { return {std::min(a.lo, b.lo), std::max(a.hi, b.hi)}; }

inline Interval operator+(const Interval& a, const Interval& b) { return outward(a.lo + b.lo, a.hi + b.hi); }
inline Interval operator-(const Interval& a, const Interval& b) { return outward(a.lo - b.hi, a.hi - b.lo); }
inline Interval operator-(const Interval& a) { return {-a.hi, -a.lo}; }
inline Interval operator*(const Interval& a, const Interval& b) {
  // 0 times an infinite bound is 0 here: the infinity stands for "unbounded", not a value.
  const auto mul = [](double x, double y) { return x == 0 || y == 0 ? 0.0 : x * y; };
  const double p[4] = {mul(a.lo, b.lo), mul(a.lo, b.hi), mul(a.hi, b.lo), mul(a.hi, b.hi)};
  return outward(*std::min_element(p, p + 4), *std::max_element(p, p + 4));
}
inline Interval operator/(const Interval& a, const Interval& b) {
  if (b.has_zero()) return Interval::entire();
  return a * outward(1 / b.hi, 1 / b.lo);
}
// x^2 without the dependency x * x has: never negative.
inline Interval square(const Interval& a) {
  const double m = std::max(std::abs(a.lo), std::abs(a.hi));
  const double low = a.has_zero() ? 0.0 : std::min(std::abs(a.lo), std::abs(a.hi));
  const Interval r = outward(low * low, m * m);
  return {std::max(r.lo, 0.0), r.hi};
}
inline Interval sqrt(const Interval& a) {
  // The part below zero is NaN in a double evaluation, which the seeding handles on its own;
  // the bound is over where the root is defined.
  if (!(a.hi >= 0)) return Interval::entire();
  const Interval r = outward(std::sqrt(std::max(a.lo, 0.0)), std::sqrt(a.hi));
  return {std::max(r.lo, 0.0), r.hi};
}
inline Interval exp(const Interval& a) {
  const Interval r = outward(std::exp(a.lo), std::exp(a.hi));
  return {std::max(r.lo, 0.0), r.hi};
}
inline Interval log(const Interval& a) {
  if (!(a.hi > 0)) return Interval::entire();
  return outward(a.lo > 0 ? std::log(a.lo) : -std::numeric_limits<double>::infinity(), std::log(a.hi));
}
inline Interval pow(const Interval& a, double c) {
  if (c == 0) return 1.0;
  if (c == 1) return a;
  if (c == 2) return square(a);
  if (c == std::round(c) && std::abs(c) <= 64) {
    const int n = static_cast<int>(c);
    if (n < 0) {
      if (a.has_zero()) return Interval::entire();
      return Interval(1.0) / pow(a, -c);
    }
    // By squaring (std::pow is the most of an interval run's time on a polynomial): at most
    // 2 log2(n) roundings of half an ulp each, so 2n ulps outward hold the exact power.
    const auto power = [n](double x) {
      double r = 1, b = x;
      for (int e = n; e > 0; e >>= 1, b *= b)
        if (e & 1) r *= b;
      return r;
    };
    const auto widened = [n](double lo, double hi) {
      const double rel = 2 * n * 0x1p-52;
      constexpr double tiny = std::numeric_limits<double>::denorm_min();
      return Interval(lo - (std::abs(lo) * rel + tiny), hi + (std::abs(hi) * rel + tiny));
    };
    if (n % 2 == 1) return widened(power(a.lo), power(a.hi));  // increasing
    const double m = std::max(std::abs(a.lo), std::abs(a.hi));
    const double low = a.has_zero() ? 0.0 : std::min(std::abs(a.lo), std::abs(a.hi));
    const Interval r = widened(power(low), power(m));
    return {std::max(r.lo, 0.0), r.hi};
  }
  // An integer beyond the powers above, of a base that may be negative: defined there (a
  // double's pow of -3 and 66 is 3^66), so not the real power's bound below.
  if (c == std::round(c) && !(a.lo >= 0)) return Interval::entire();
  // A real exponent: defined for a >= 0 (the rest is NaN, as for sqrt).
  if (!(a.hi >= 0)) return Interval::entire();
  const double lo = std::max(a.lo, 0.0);
  if (c > 0) return outward(std::pow(lo, c), std::pow(a.hi, c));
  if (lo == 0) return Interval::entire();
  return outward(std::pow(a.hi, c), std::pow(lo, c));
}
inline Interval pow(const Interval& a, const Interval& b) {
  if (b.lo == b.hi) return pow(a, b.lo);
  if (!(a.lo > 0)) return Interval::entire();
  return exp(b * log(a));
}
// sin over [lo, hi]: the end values, and 1 or -1 where a peak lies inside.
inline Interval sin(const Interval& a) {
  constexpr double pi = std::numbers::pi, two_pi = 2 * std::numbers::pi;
  if (!std::isfinite(a.lo) || !std::isfinite(a.hi) || a.hi - a.lo >= two_pi) return {-1, 1};
  const double s0 = std::sin(a.lo), s1 = std::sin(a.hi);
  Interval r = outward(std::min(s0, s1), std::max(s0, s1));
  // A peak within a ulp of an end counts as inside (the ends' own rounding).
  const auto peak_inside = [&](double at) {
    const double k = std::ceil((a.lo - at) / two_pi - 1e-12);
    return at + k * two_pi <= a.hi + std::abs(a.hi) * 1e-12 + 1e-12;
  };
  if (peak_inside(pi / 2)) r.hi = 1;
  if (peak_inside(-pi / 2)) r.lo = -1;
  return {std::max(r.lo, -1.0), std::min(r.hi, 1.0)};
}
// The double pi / 2 is 6.1e-17 short of the true one, more than the outward rounding of a small
// sum widens it by: the shifted range is widened by that much more.
inline Interval cos(const Interval& a) {
  const Interval s = a + Interval(std::numbers::pi / 2);
  return sin(Interval(s.lo - 2e-16, s.hi + 2e-16));
}
inline Interval tan(const Interval& a) {
  constexpr double pi = std::numbers::pi;
  if (!std::isfinite(a.lo) || !std::isfinite(a.hi) || a.hi - a.lo >= pi) return Interval::entire();
  // A pole pi/2 + k pi inside (or within rounding of an end) makes it unbounded.
  const double k = std::ceil((a.lo - pi / 2) / pi - 1e-12);
  if (pi / 2 + k * pi <= a.hi + std::abs(a.hi) * 1e-12 + 1e-12) return Interval::entire();
  return outward(std::tan(a.lo), std::tan(a.hi));
}
inline Interval atan(const Interval& a) { return outward(std::atan(a.lo), std::atan(a.hi)); }
// atan2(y, x) away from its cut (x <= 0, y = 0) and the origin: continuous, monotone along
// each side of the box, without a critical point inside, so the corners bound it.
inline Interval atan2(const Interval& y, const Interval& x) {
  if (!(x.lo > 0 || y.lo > 0 || y.hi < 0)) return {-std::numbers::pi, std::numbers::pi};
  const double c[4] = {std::atan2(y.lo, x.lo), std::atan2(y.lo, x.hi), std::atan2(y.hi, x.lo), std::atan2(y.hi, x.hi)};
  return outward(*std::min_element(c, c + 4), *std::max_element(c, c + 4));
}
inline Interval floor(const Interval& a) { return {std::floor(a.lo), std::floor(a.hi)}; }
inline Interval round(const Interval& a) { return {std::round(a.lo), std::round(a.hi)}; }
inline Interval abs(const Interval& a) {
  if (a.lo >= 0) return a;
  if (a.hi <= 0) return -a;
  return {0, std::max(-a.lo, a.hi)};
}
inline Interval min(const Interval& a, const Interval& b) { return {std::min(a.lo, b.lo), std::min(a.hi, b.hi)}; }
inline Interval max(const Interval& a, const Interval& b) { return {std::max(a.lo, b.lo), std::max(a.hi, b.hi)}; }

// A value's interval and the interval of its derivative along one direction u (the seed
// derivatives of x, y, z are u's components). Where the value is not differentiable (min and
// max whose arguments' ranges overlap, abs about zero) the derivative's interval holds every
// one-sided derivative (Clarke's generalized gradient along u), so a derivative range that
// excludes zero still proves that F has no critical point, smooth or not, in the box.
struct IntervalDual {
  Interval v, d;
  IntervalDual() = default;
  IntervalDual(double c) : v(c), d(0.0) {}  // NOLINT(google-explicit-constructor): constants
  IntervalDual(const Interval& value, const Interval& derivative) : v(value), d(derivative) {}
};

inline IntervalDual operator+(const IntervalDual& a, const IntervalDual& b) { return {a.v + b.v, a.d + b.d}; }
inline IntervalDual operator-(const IntervalDual& a, const IntervalDual& b) { return {a.v - b.v, a.d - b.d}; }
inline IntervalDual operator-(const IntervalDual& a) { return {-a.v, -a.d}; }
inline IntervalDual operator*(const IntervalDual& a, const IntervalDual& b) {
  return {a.v * b.v, a.d * b.v + a.v * b.d};
}
inline IntervalDual operator/(const IntervalDual& a, const IntervalDual& b) {
  return {a.v / b.v, (a.d * b.v - a.v * b.d) / square(b.v)};
}
inline IntervalDual sqrt(const IntervalDual& a) {
  const Interval r = sqrt(a.v);
  return {r, a.d / (Interval(2.0) * r)};
}
inline IntervalDual exp(const IntervalDual& a) {
  const Interval r = exp(a.v);
  return {r, r * a.d};
}
inline IntervalDual log(const IntervalDual& a) { return {log(a.v), a.d / a.v}; }
inline IntervalDual pow(const IntervalDual& a, double c) {
  if (c == 0) return 1.0;
  if (c == 1) return a;
  return {pow(a.v, c), Interval(c) * pow(a.v, c - 1) * a.d};
}
inline IntervalDual pow(const IntervalDual& a, const IntervalDual& b) {
  if (b.v.lo == b.v.hi && b.d.lo == 0 && b.d.hi == 0) return pow(a, b.v.lo);
  return exp(b * log(a));
}
inline IntervalDual sin(const IntervalDual& a) { return {sin(a.v), cos(a.v) * a.d}; }
inline IntervalDual cos(const IntervalDual& a) { return {cos(a.v), -(sin(a.v) * a.d)}; }
inline IntervalDual tan(const IntervalDual& a) {
  const Interval r = tan(a.v);
  return {r, (Interval(1.0) + square(r)) * a.d};
}
inline IntervalDual atan(const IntervalDual& a) { return {atan(a.v), a.d / (Interval(1.0) + square(a.v))}; }
inline IntervalDual atan2(const IntervalDual& y, const IntervalDual& x) {
  const Interval r = atan2(y.v, x.v);
  if (!(x.v.lo > 0 || y.v.lo > 0 || y.v.hi < 0)) return {r, Interval::entire()};  // the cut may lie inside
  return {r, (x.v * y.d - y.v * x.d) / (square(x.v) + square(y.v))};
}
// Steps: flat between jumps, a jump unbounded.
inline IntervalDual floor(const IntervalDual& a) {
  const Interval r = floor(a.v);
  return {r, r.lo == r.hi ? Interval(0.0) : Interval::entire()};
}
inline IntervalDual round(const IntervalDual& a) {
  const Interval r = round(a.v);
  return {r, r.lo == r.hi ? Interval(0.0) : Interval::entire()};
}
inline IntervalDual abs(const IntervalDual& a) {
  if (a.v.lo > 0) return a;
  if (a.v.hi < 0) return -a;
  return {abs(a.v), hull(a.d, -a.d)};
}
inline IntervalDual min(const IntervalDual& a, const IntervalDual& b) {
  if (a.v.hi < b.v.lo) return a;
  if (b.v.hi < a.v.lo) return b;
  return {min(a.v, b.v), hull(a.d, b.d)};
}
inline IntervalDual max(const IntervalDual& a, const IntervalDual& b) {
  if (a.v.hi < b.v.lo) return b;
  if (b.v.hi < a.v.lo) return a;
  return {max(a.v, b.v), hull(a.d, b.d)};
}

}  // namespace cdp::detail
