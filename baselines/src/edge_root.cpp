#include "edge_root.h"

#include <cdp/core/errors.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace cdp::marching {

EdgeRoot find_edge_root(const Field& field, const Vec3& a, double fa, const Vec3& b, double fb, double tolerance) {
  const double len = (b - a).norm();
  const Vec3 d = b - a;
  // Bracket [lo, hi] in the edge parameter; `lo_inside` is the side of lo (hi is the other).
  // The Illinois method halves the kept end's value, so signs are tracked apart from values.
  double lo = 0, hi = 1, flo = fa, fhi = fb, raw_lo = fa, raw_hi = fb;
  const bool lo_inside = fa < 0;
  int last_kept = 0;  // -1: lo moved last time, +1: hi moved
  int slow_steps = 0;
  EdgeRoot out;
  const double stop_width = 0.5 * tolerance / len;
  // Dekker's device: a probe never lands closer than `nudge` to an end of the bracket, so once
  // the estimate has converged the next probe falls on the root's other side and closes the
  // bracket, instead of creeping up on the root from one side.
  const double nudge = 0.4 * stop_width;
  for (int iter = 0; iter < 200 && hi - lo > stop_width; ++iter) {
    double t = slow_steps >= 2 ? 0.5 * (lo + hi) : lo + (hi - lo) * flo / (flo - fhi);
    if (!(t > lo && t < hi)) t = 0.5 * (lo + hi);
    t = std::clamp(t, lo + nudge, hi - nudge);
    if (!(t > lo && t < hi)) break;  // the bracket is down to adjacent doubles
    const double width = hi - lo;
    const double ft = field.value(a + t * d);
    ++out.evaluations;
    if (!std::isfinite(ft)) {
      std::ostringstream s;
      const Vec3 p = a + t * d;
      s << "marching: the field is not finite at (" << p.x() << ", " << p.y() << ", " << p.z() << ")";
      throw NoSurfaceError(s.str());
    }
    if (ft == 0) {
      lo = hi = t;
      raw_lo = raw_hi = 0;
      break;
    }
    if ((ft < 0) == lo_inside) {
      lo = t, flo = raw_lo = ft;
      if (last_kept == -1) fhi *= 0.5;
      last_kept = -1;
    } else {
      hi = t, fhi = raw_hi = ft;
      if (last_kept == +1) flo *= 0.5;
      last_kept = +1;
    }
    slow_steps = hi - lo > 0.5 * width ? slow_steps + 1 : 0;
    if (slow_steps > 2) slow_steps = 0;  // one bisection, then try the secant again
  }
  double t = lo;
  if (hi > lo) t = std::clamp(lo + (hi - lo) * raw_lo / (raw_lo - raw_hi), lo, hi);
  const double margin = std::min(0.5 * tolerance / len, 1e-3);
  t = std::clamp(t, margin, 1 - margin);
  out.point = a + t * d;
  return out;
}

}  // namespace cdp::marching
