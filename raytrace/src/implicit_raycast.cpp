#include <cdp/raytrace/implicit_raycast.h>

#include <cdp/core/errors.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace cdp {

namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kInf = std::numeric_limits<double>::infinity();

// The part [t0, t1] of the ray (t >= 0) inside the box; false when it misses the box.
bool clip_to_box(const Ray& ray, const Box& box, double& t0, double& t1) {
  t0 = 0.0;
  t1 = kInf;
  for (int a = 0; a < 3; ++a) {
    const double o = ray.origin[a], d = ray.direction[a];
    if (d == 0.0) {
      if (o < box.min[a] || o > box.max[a]) return false;
      continue;
    }
    double ta = (box.min[a] - o) / d, tb = (box.max[a] - o) / d;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

class RayFunction {
 public:
  RayFunction(const Field& field, const Ray& ray) : field_(field), ray_(ray) {}
  Vec3 point(double t) const { return ray_.origin + t * ray_.direction; }
  double value(double t) const { return field_.value(point(t)); }
  // F and dF/dt.
  double value_slope(double t, double& slope) const {
    Vec3 g;
    const double f = field_.value_gradient(point(t), g);
    slope = g.dot(ray_.direction);
    return f;
  }
  double gradient_norm(double t) const { return field_.gradient(point(t)).norm(); }

 private:
  const Field& field_;
  const Ray& ray_;
};

// A root of F in [a, b] with F(a) > 0 >= F(b): Newton steps, replaced by bisection whenever they
// leave the bracket, until the step or the bracket is below a few ulps.
double refine_root(const RayFunction& fn, double a, double b, double fb, int max_iterations) {
  if (fb == 0.0) return b;
  double x = 0.5 * (a + b);
  for (int it = 0; it < max_iterations; ++it) {
    double slope;
    const double f = fn.value_slope(x, slope);
    if (f == 0.0) return x;
    if (f > 0.0) a = x;
    else b = x;
    const double tol = 4.0 * kEps * std::max(std::abs(a), std::abs(b)) + std::numeric_limits<double>::min();
    if (b - a <= tol) return f > 0.0 ? b : a;
    double next = slope != 0.0 ? x - f / slope : a;
    if (!(next > a && next < b)) next = 0.5 * (a + b);  // also catches NaN
    if (std::abs(next - x) <= tol) return next;
    x = next;
  }
  return x;
}

struct Minimum {
  double t, f;
};

// Golden-section search for the minimum of F in (a, c), given a < b < c with F(b) < F(a) and
// F(b) <= F(c). Stops early when F(b) <= 0 (a crossing) or when the Lipschitz bound shows that
// F stays above `floor` on the bracket.
Minimum golden_minimum(const RayFunction& fn, double a, double b, double fb, double c, double lipschitz,
                       double floor, double tol, int max_iterations) {
  constexpr double r = 0.3819660112501051;  // 2 - golden ratio
  for (int it = 0; it < max_iterations && c - a > tol; ++it) {
    if (fb <= 0.0) break;
    if (fb - lipschitz * std::max(b - a, c - b) > floor) break;
    const double x = (c - b > b - a) ? b + r * (c - b) : b - r * (b - a);
    const double fx = fn.value(x);
    if (fx < fb) {
      if (x > b) a = b;
      else c = b;
      b = x;
      fb = fx;
    } else {
      if (x > b) c = x;
      else a = x;
    }
  }
  return {b, fb};
}

}  // namespace

const char* to_string(RayStatus status) {
  switch (status) {
    case RayStatus::Miss: return "miss";
    case RayStatus::Hit: return "hit";
    case RayStatus::StartsInside: return "starts_inside";
    case RayStatus::StepLimit: return "step_limit";
    case RayStatus::NotFinite: return "not_finite";
  }
  return "unknown";
}

double max_gradient_norm(const Field& field, const Box& box, int grid) {
  const int n = std::max(grid, 2);
  const std::size_t total = static_cast<std::size_t>(n) * n * n;
  std::vector<double> norms(total);
  const Vec3 step = box.size() / (n - 1);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, total, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const std::size_t ix = i % n, iy = (i / n) % n, iz = i / (static_cast<std::size_t>(n) * n);
      const Vec3 p = box.min + Vec3(ix * step.x(), iy * step.y(), iz * step.z());
      norms[i] = field.gradient(p).norm();
    }
  });
  double m = 0.0;
  for (double g : norms) {
    if (!std::isfinite(g)) return g;  // the caller reports it
    m = std::max(m, g);
  }
  return m;
}

RaycastSetup make_raycast_setup(const Field& field, const RaycastOptions& o) {
  if (!(o.lipschitz >= 0.0) || !std::isfinite(o.lipschitz)) throw InvalidInputError("raycast: lipschitz must be >= 0");
  if (o.lipschitz_grid < 2 || o.lipschitz_grid > 1024) throw InvalidInputError("raycast: lipschitz_grid must be in [2, 1024]");
  if (!(o.lipschitz_safety >= 1.0)) throw InvalidInputError("raycast: lipschitz_safety must be >= 1");
  if (!(o.min_step > 0.0 && o.min_step < 1.0)) throw InvalidInputError("raycast: min_step must be in (0, 1)");
  if (!(o.tangent_tolerance > 0.0 && o.tangent_tolerance < 1.0))
    throw InvalidInputError("raycast: tangent_tolerance must be in (0, 1)");
  if (o.max_steps < 1 || o.max_refine_iterations < 1)
    throw InvalidInputError("raycast: max_steps and max_refine_iterations must be positive");
  RaycastSetup s;
  s.box = field.bounds();
  if (!s.box.valid()) throw NoSurfaceError("raycast: the field's box is empty or not finite");
  const double diag = s.box.diagonal();
  s.min_step = o.min_step * diag;
  s.tangent_tolerance = o.tangent_tolerance * diag;
  if (o.lipschitz > 0.0) {
    s.lipschitz = o.lipschitz;
  } else if (const auto model = field.lipschitz_bound(); model && *model > 0.0 && std::isfinite(*model)) {
    s.lipschitz = *model;
    s.lipschitz_from_model = true;
  } else {
    const double g = max_gradient_norm(field, s.box, o.lipschitz_grid);
    if (!std::isfinite(g)) throw NoSurfaceError("raycast: the field's gradient is not finite inside its box");
    s.lipschitz = g * o.lipschitz_safety;
  }
  // A constant field: any positive bound is valid and makes every step leave the box.
  if (s.lipschitz <= 0.0) s.lipschitz = std::numeric_limits<double>::min();
  return s;
}

SurfaceHit cast_ray(const Field& field, const Ray& ray, const RaycastSetup& s, const RaycastOptions& o) {
  SurfaceHit h;
  double t_enter, t_exit;
  if (!clip_to_box(ray, s.box, t_enter, t_exit)) return h;
  const RayFunction fn(field, ray);
  const double L = s.lipschitz;
  const double x_tol = 1e-6 * s.min_step;

  auto hit_at = [&](double t, std::uint8_t flag) {
    h.status = RayStatus::Hit;
    h.flags |= flag;
    h.t = t;
    Vec3 g;
    field.value_gradient(fn.point(t), g);
    const double n = g.norm();
    h.normal = n > 0.0 && std::isfinite(n) ? Vec3(g / n) : Vec3::Zero();
    return h;
  };

  double t = t_enter, f = fn.value(t);
  h.steps = 1;
  if (!std::isfinite(f)) {
    h.status = RayStatus::NotFinite;
    return h;
  }
  if (f < 0.0) {
    h.status = RayStatus::StartsInside;
    h.t = t;
    return h;
  }
  if (f == 0.0) return hit_at(t, 0);

  bool have_prev = false;
  double tp = 0.0, fp = 0.0;
  while (t < t_exit) {
    if (h.steps >= o.max_steps) {
      h.status = RayStatus::StepLimit;
      h.t = t;
      return h;
    }
    const double tn = std::min(t + std::max(f / L, s.min_step), t_exit);
    const double fn_ = fn.value(tn);
    ++h.steps;
    if (!std::isfinite(fn_)) {
      h.status = RayStatus::NotFinite;
      h.t = tn;
      return h;
    }
    if (fn_ <= 0.0) return hit_at(refine_root(fn, t, tn, fn_, o.max_refine_iterations), 0);

    // A sampled local minimum where the Lipschitz bound lets F reach zero between the samples:
    // search the minimum, which is either a crossing, a touch, or a near miss.
    if (have_prev && f < fp && f <= fn_ && (fp + f <= L * (t - tp) || f + fn_ <= L * (tn - t))) {
      const double floor = s.tangent_tolerance * fn.gradient_norm(t);
      const Minimum m = golden_minimum(fn, tp, t, f, tn, L, floor, x_tol, o.max_refine_iterations);
      if (m.f <= 0.0) return hit_at(refine_root(fn, tp, m.t, m.f, o.max_refine_iterations), kRayGrazing);
      const double g = fn.gradient_norm(m.t);
      if (m.f <= s.tangent_tolerance * g) return hit_at(m.t, kRayTangent);
      h.flags |= kRayNearMiss;
    }
    tp = t;
    fp = f;
    t = tn;
    f = fn_;
    have_prev = true;
  }
  h.status = RayStatus::Miss;
  return h;
}

GroundTruthCounts GroundTruth::counts() const {
  GroundTruthCounts c;
  for (const SurfaceHit& h : hits) {
    switch (h.status) {
      case RayStatus::Hit: ++c.hits; break;
      case RayStatus::Miss: ++c.misses; break;
      case RayStatus::StartsInside: ++c.starts_inside; break;
      case RayStatus::StepLimit: ++c.step_limit; break;
      case RayStatus::NotFinite: ++c.not_finite; break;
    }
    if (h.flags & kRayGrazing) ++c.grazing;
    if (h.flags & kRayTangent) ++c.tangent;
    if (h.flags & kRayNearMiss) ++c.near_miss;
  }
  return c;
}

GroundTruth compute_ground_truth(const Field& field, std::vector<Ray> rays, const RaycastOptions& options) {
  GroundTruth truth;
  truth.setup = make_raycast_setup(field, options);
  truth.rays = std::move(rays);
  truth.hits.resize(truth.rays.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, truth.rays.size(), 64),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        truth.hits[i] = cast_ray(field, truth.rays[i], truth.setup, options);
                    });
  return truth;
}

}  // namespace cdp
