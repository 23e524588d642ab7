#include "edge_root.h"

#include <cdp/core/errors.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace cdp::marching {

namespace {

// A search ends after this many probes however slowly its bracket shrinks (bisection needs
// about 60 to go from a cell to adjacent doubles; the secant steps converge in far fewer).
constexpr int kMaxRootIterations = 200;

[[noreturn]] void throw_not_finite(const Vec3& p) {
  std::ostringstream s;
  s << "marching: the field is not finite at (" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  throw NoSurfaceError(s.str());
}

}  // namespace

EdgeRootSearch::EdgeRootSearch(const Vec3& a, double fa, const Vec3& b, double fb, double tolerance)
    : a_(a), d_(b - a), len_((b - a).norm()), tolerance_(tolerance) {
  flo_ = raw_lo_ = fa;
  fhi_ = raw_hi_ = fb;
  lo_inside_ = fa < 0;
  stop_width_ = 0.5 * tolerance / len_;
  // Dekker's device: a probe never lands closer than `nudge` to an end of the bracket, so once
  // the estimate has converged the next probe falls on the root's other side and closes the
  // bracket, instead of creeping up on the root from one side.
  nudge_ = 0.4 * stop_width_;
  advance();
}

void EdgeRootSearch::advance() {
  if (iterations_ >= kMaxRootIterations || !(hi_ - lo_ > stop_width_)) {
    searching_ = false;
    return;
  }
  double t = slow_steps_ >= 2 ? 0.5 * (lo_ + hi_) : lo_ + (hi_ - lo_) * flo_ / (flo_ - fhi_);
  if (!(t > lo_ && t < hi_)) t = 0.5 * (lo_ + hi_);
  t = std::clamp(t, lo_ + nudge_, hi_ - nudge_);
  if (!(t > lo_ && t < hi_)) {  // the bracket is down to adjacent doubles
    searching_ = false;
    return;
  }
  t_ = t;
}

bool EdgeRootSearch::take(double ft) {
  ++evaluations_;
  if (!std::isfinite(ft)) {
    searching_ = false;
    return false;
  }
  if (ft == 0) {
    lo_ = hi_ = t_;
    raw_lo_ = raw_hi_ = 0;
    searching_ = false;
    return true;
  }
  const double width = hi_ - lo_;
  if ((ft < 0) == lo_inside_) {
    lo_ = t_, flo_ = raw_lo_ = ft;
    if (last_kept_ == -1) fhi_ *= 0.5;
    last_kept_ = -1;
  } else {
    hi_ = t_, fhi_ = raw_hi_ = ft;
    if (last_kept_ == +1) flo_ *= 0.5;
    last_kept_ = +1;
  }
  slow_steps_ = hi_ - lo_ > 0.5 * width ? slow_steps_ + 1 : 0;
  if (slow_steps_ > 2) slow_steps_ = 0;  // one bisection, then try the secant again
  ++iterations_;
  advance();
  return true;
}

Vec3 EdgeRootSearch::point() const {
  double t = lo_;
  if (hi_ > lo_) t = std::clamp(lo_ + (hi_ - lo_) * raw_lo_ / (raw_lo_ - raw_hi_), lo_, hi_);
  const double margin = std::min(0.5 * tolerance_ / len_, 1e-3);
  t = std::clamp(t, margin, 1 - margin);
  return a_ + t * d_;
}

EdgeRoot find_edge_root(const Field& field, const Vec3& a, double fa, const Vec3& b, double fb, double tolerance) {
  EdgeRootSearch search(a, fa, b, fb, tolerance);
  while (search.searching()) {  // bounded by kMaxRootIterations
    const Vec3 p = search.probe();
    if (!search.take(field.value(p))) throw_not_finite(p);
  }
  return {search.point(), search.evaluations()};
}

void find_edge_roots(const Field& field, std::span<const EdgeRootQuery> queries, double tolerance,
                     std::vector<EdgeRoot>& out) {
  std::vector<EdgeRootSearch> searches;
  searches.reserve(queries.size());
  std::vector<std::size_t> active;
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const EdgeRootQuery& q = queries[i];
    searches.emplace_back(q.a, q.fa, q.b, q.fb, tolerance);
    if (searches.back().searching()) active.push_back(i);
  }
  std::vector<Vec3> probes;
  std::vector<double> values;
  std::size_t first_failed = queries.size();
  Vec3 failed_at = Vec3::Zero();
  // Each round takes one probe from every search still running, so the rounds are bounded by
  // kMaxRootIterations like one search.
  for (int round = 0; round < kMaxRootIterations && !active.empty(); ++round) {
    probes.resize(active.size());
    values.resize(active.size());
    for (std::size_t r = 0; r < active.size(); ++r) probes[r] = searches[active[r]].probe();
    field.values(probes.data(), values.data(), probes.size());
    std::size_t kept = 0;
    for (std::size_t r = 0; r < active.size(); ++r) {
      EdgeRootSearch& s = searches[active[r]];
      if (!s.take(values[r]) && active[r] < first_failed) first_failed = active[r], failed_at = probes[r];
      if (s.searching()) active[kept++] = active[r];
    }
    active.resize(kept);
  }
  if (first_failed < queries.size()) throw_not_finite(failed_at);
  out.resize(queries.size());
  for (std::size_t i = 0; i < queries.size(); ++i) out[i] = {searches[i].point(), searches[i].evaluations()};
}

}  // namespace cdp::marching
