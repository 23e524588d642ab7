// Checks <cdp/raytrace/implicit_raycast.h> against closed-form intersections: sphere and ellipsoid
// (quadratics), torus and tanglecube (polynomials solved by dense sampling and bisection here),
// rays that just miss, just hit and touch, and the counted failure statuses.
#include <cdp/raytrace/implicit_raycast.h>

#include <common/test_fields.h>
#include <cdp/core/errors.h>
#include <cdp/core/models/analytic.h>
#include <cdp/core/models/expression.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <functional>
#include <optional>

namespace cdp {
namespace {

// The smaller non-negative root of a t^2 + 2 b t + c = 0, if any.
std::optional<double> quadratic_first_root(double a, double b, double c) {
  const double disc = b * b - a * c;
  if (disc < 0) return std::nullopt;
  const double s = std::sqrt(disc);
  const double t0 = (-b - s) / a, t1 = (-b + s) / a;
  if (t0 >= 0) return t0;
  if (t1 >= 0) return t1;
  return std::nullopt;
}

std::optional<double> sphere_hit(const Ray& r, const Vec3& c, double radius) {
  const Vec3 q = r.origin - c;
  return quadratic_first_root(1.0, q.dot(r.direction), q.squaredNorm() - radius * radius);
}

std::optional<double> ellipsoid_hit(const Ray& r, const Vec3& c, const Vec3& radii) {
  const Vec3 q = (r.origin - c).cwiseQuotient(radii), e = r.direction.cwiseQuotient(radii);
  return quadratic_first_root(e.squaredNorm(), q.dot(e), q.squaredNorm() - 1.0);
}

// First sign change of g (positive outside) over [t0, t1] by dense sampling, then bisection in
// long double. Returns nothing when no sample is <= 0.
std::optional<double> dense_first_root(const std::function<long double(long double)>& g, double t0, double t1,
                                       int samples) {
  long double a = t0, ga = g(a);
  for (int i = 1; i <= samples; ++i) {
    const long double b = t0 + (t1 - t0) * static_cast<long double>(i) / samples, gb = g(b);
    if (ga > 0 && gb <= 0) {
      long double lo = a, hi = b;
      for (int k = 0; k < 200; ++k) {
        const long double m = 0.5L * (lo + hi);
        (g(m) > 0 ? lo : hi) = m;
      }
      return static_cast<double>(0.5L * (lo + hi));
    }
    a = b;
    ga = gb;
  }
  return std::nullopt;
}

// Torus around z through c: (|p|^2 + R^2 - r^2)^2 - 4 R^2 (x^2 + y^2).
std::optional<double> torus_hit(const Ray& ray, const Vec3& c, double R, double r, double t_max) {
  auto g = [&](long double t) {
    const long double x = ray.origin.x() - c.x() + t * ray.direction.x(), y = ray.origin.y() - c.y() + t * ray.direction.y(),
                      z = ray.origin.z() - c.z() + t * ray.direction.z();
    const long double s = x * x + y * y + z * z + R * R - r * r;
    return s * s - 4.0L * R * R * (x * x + y * y);
  };
  return dense_first_root(g, 0.0, t_max, 50000);
}

CameraOptions small_camera(int views, int resolution) {
  CameraOptions o;
  o.views = views;
  o.resolution = resolution;
  return o;
}

void expect_matches(const GroundTruth& gt, const std::function<std::optional<double>(const Ray&)>& exact, double tol,
                    std::size_t min_hits) {
  std::size_t hits = 0;
  for (std::size_t i = 0; i < gt.rays.size(); ++i) {
    const auto t = exact(gt.rays[i]);
    const SurfaceHit& h = gt.hits[i];
    ASSERT_EQ(h.hit(), t.has_value()) << "ray " << i << " status " << to_string(h.status);
    if (!t) continue;
    ++hits;
    EXPECT_NEAR(h.t, *t, tol) << "ray " << i;
    EXPECT_NEAR(h.normal.norm(), 1.0, 1e-12);
    EXPECT_LT(h.normal.dot(gt.rays[i].direction), 0.0) << "normal faces the ray at a first hit";
  }
  EXPECT_GE(hits, min_hits);
}

TEST(ImplicitRaycast, SphereMatchesClosedFormToMachinePrecision) {
  const Vec3 c(0.3, -0.2, 0.1);
  const Sphere sphere(c, 0.8);
  const auto gt = compute_ground_truth(sphere, make_camera_rays(sphere.bounds(), small_camera(4, 16)));
  EXPECT_TRUE(gt.setup.lipschitz_from_model);
  EXPECT_EQ(gt.setup.lipschitz, 1.0);
  expect_matches(gt, [&](const Ray& r) { return sphere_hit(r, c, 0.8); }, 1e-13, 150);
  const auto counts = gt.counts();
  EXPECT_EQ(counts.step_limit + counts.starts_inside + counts.not_finite, 0u);
}

TEST(ImplicitRaycast, EllipsoidMatchesClosedForm) {
  const Vec3 c(0, 0.1, -0.3), radii(1.2, 0.5, 0.8);
  const Ellipsoid ellipsoid(c, radii);
  const auto gt = compute_ground_truth(ellipsoid, make_camera_rays(ellipsoid.bounds(), small_camera(3, 16)));
  expect_matches(gt, [&](const Ray& r) { return ellipsoid_hit(r, c, radii); }, 1e-12, 100);
}

TEST(ImplicitRaycast, TorusMatchesThePolynomialRoots) {
  const Vec3 c(0.1, 0.0, -0.2);
  const Torus torus(c, 1.0, 0.35);
  const auto gt = compute_ground_truth(torus, make_camera_rays(torus.bounds(), small_camera(3, 12)));
  const double t_max = 10.0;  // every camera ray leaves the box well before
  expect_matches(gt, [&](const Ray& r) { return torus_hit(r, c, 1.0, 0.35, t_max); }, 1e-10, 40);
}

TEST(ImplicitRaycast, TanglecubeWithEstimatedLipschitzBoundMatchesDenseSampling) {
  const auto field = test::tanglecube();
  ASSERT_FALSE(field->lipschitz_bound());
  RaycastOptions o;
  o.lipschitz_grid = 16;
  const auto gt = compute_ground_truth(*field, make_camera_rays(field->bounds(), small_camera(2, 10)), o);
  EXPECT_FALSE(gt.setup.lipschitz_from_model);
  // max |grad F| on the box is at its corners, |(78, 78, 78)|; the bound is twice that.
  EXPECT_NEAR(gt.setup.lipschitz, 2.0 * 78.0 * std::sqrt(3.0), 1e-9);
  expect_matches(
      gt,
      [&](const Ray& ray) {
        auto g = [&](long double t) {
          long double s = 11.8L;
          for (int a = 0; a < 3; ++a) {
            const long double x = ray.origin[a] + t * ray.direction[a];
            s += x * x * x * x - 5.0L * x * x;
          }
          return s;
        };
        // The caster only looks inside the box; so does the reference.
        double t0 = 0, t1 = 1e300;
        for (int a = 0; a < 3; ++a) {
          double ta = (-3.0 - ray.origin[a]) / ray.direction[a], tb = (3.0 - ray.origin[a]) / ray.direction[a];
          if (ta > tb) std::swap(ta, tb);
          t0 = std::max(t0, ta);
          t1 = std::min(t1, tb);
        }
        return t0 <= t1 ? dense_first_root(g, t0, t1, 200000) : std::nullopt;
      },
      1e-10, 25);
}

TEST(ImplicitRaycast, ExpressionSphereUsesTheEstimatedBound) {
  const Expression field("x^2 + y^2 + z^2 - 1", {}, Box{{-1.5, -1.5, -1.5}, {1.5, 1.5, 1.5}});
  RaycastOptions o;
  o.lipschitz_grid = 4;  // corners and thirds: max |grad| = 2 |(1.5, 1.5, 1.5)|
  const auto gt = compute_ground_truth(field, make_camera_rays(field.bounds(), small_camera(2, 12)), o);
  EXPECT_NEAR(gt.setup.lipschitz, 2.0 * 2.0 * 1.5 * std::sqrt(3.0), 1e-12);
  expect_matches(gt, [&](const Ray& r) { return sphere_hit(r, Vec3::Zero(), 1.0); }, 1e-13, 25);
}

// Rays along +x at height `offset` above the centre of a unit sphere.
Ray side_ray(double offset) { return {Vec3(-3.0, offset, 0.0), Vec3::UnitX()}; }

TEST(ImplicitRaycast, RaysThatJustMissJustHitOrTouchTheSphere) {
  const Sphere sphere(Vec3::Zero(), 1.0);
  const RaycastOptions o;
  const RaycastSetup s = make_raycast_setup(sphere, o);

  const SurfaceHit miss = cast_ray(sphere, side_ray(1.0 + 1e-7), s, o);
  EXPECT_EQ(miss.status, RayStatus::Miss);
  EXPECT_TRUE(miss.flags & kRayNearMiss);

  const SurfaceHit far_miss = cast_ray(sphere, side_ray(1.5), s, o);
  EXPECT_EQ(far_miss.status, RayStatus::Miss);
  EXPECT_EQ(far_miss.flags, 0);

  for (double gap : {1e-4, 1e-7, 1e-10, 1e-12}) {
    const Ray r = side_ray(1.0 - gap);
    const SurfaceHit hit = cast_ray(sphere, r, s, o);
    ASSERT_EQ(hit.status, RayStatus::Hit) << "gap " << gap;
    const double exact = *sphere_hit(r, Vec3::Zero(), 1.0);
    // Near tangency the root is ill-conditioned: dF/dt ~ sqrt(2 gap).
    EXPECT_NEAR(hit.t, exact, 1e-15 / std::sqrt(gap) + 1e-14) << "gap " << gap;
  }
  // The thinnest chords are far below the minimum step: only the minimum search finds them.
  EXPECT_TRUE(cast_ray(sphere, side_ray(1.0 - 1e-12), s, o).flags & kRayGrazing);

  const SurfaceHit touch = cast_ray(sphere, side_ray(1.0), s, o);
  ASSERT_EQ(touch.status, RayStatus::Hit);
  EXPECT_TRUE(touch.flags & (kRayTangent | kRayGrazing));
  EXPECT_NEAR(touch.t, 3.0, 1e-6);
  EXPECT_NEAR(touch.normal.y(), 1.0, 1e-6);
}

TEST(ImplicitRaycast, RayTouchingTheTopOfTheTorusTubeIsATangentHit) {
  const Vec3 c(0.1, 0.0, -0.2);
  const Torus torus(c, 1.0, 0.35);
  const RaycastOptions o;
  const RaycastSetup s = make_raycast_setup(torus, o);
  const Ray top{Vec3(-3.0, c.y(), c.z() + 0.35), Vec3::UnitX()};
  const SurfaceHit h = cast_ray(torus, top, s, o);
  ASSERT_EQ(h.status, RayStatus::Hit);
  EXPECT_TRUE(h.flags & (kRayTangent | kRayGrazing));
  EXPECT_NEAR(top.origin.x() + h.t, c.x() - 1.0, 1e-6);

  const Ray above{Vec3(-3.0, c.y(), c.z() + 0.35 + 1e-6), Vec3::UnitX()};
  EXPECT_EQ(cast_ray(torus, above, s, o).status, RayStatus::Miss);
  const Ray through_hole{Vec3(c.x(), c.y(), c.z() - 3.0), Vec3::UnitZ()};
  EXPECT_EQ(cast_ray(torus, through_hole, s, o).status, RayStatus::Miss);
}

TEST(ImplicitRaycast, FailuresAreReportedAndCounted) {
  Sphere clipped(Vec3::Zero(), 1.0);
  clipped.set_bounds({Vec3::Constant(-0.5), Vec3::Constant(0.5)});  // the surface leaves the box
  RaycastOptions o;
  EXPECT_EQ(cast_ray(clipped, side_ray(0.0), make_raycast_setup(clipped, o), o).status, RayStatus::StartsInside);

  const Sphere sphere(Vec3::Zero(), 1.0);
  o.max_steps = 3;
  const SurfaceHit limited = cast_ray(sphere, side_ray(0.999), make_raycast_setup(sphere, o), o);
  EXPECT_EQ(limited.status, RayStatus::StepLimit);
  EXPECT_LE(limited.steps, 3);

  const Expression nan_field("sqrt(x) - 0.5", {}, Box{{-1, -1, -1}, {1, 1, 1}});
  RaycastOptions given;
  given.lipschitz = 10.0;
  EXPECT_EQ(cast_ray(nan_field, side_ray(0.0), make_raycast_setup(nan_field, given), given).status,
            RayStatus::NotFinite);
  EXPECT_THROW(make_raycast_setup(nan_field, RaycastOptions{}), NoSurfaceError);

  RaycastOptions bad;
  bad.min_step = 0;
  EXPECT_THROW(make_raycast_setup(sphere, bad), InvalidInputError);

  GroundTruth gt = compute_ground_truth(sphere, {side_ray(0.0), side_ray(2.0), side_ray(1.0 + 1e-7)});
  const auto counts = gt.counts();
  EXPECT_EQ(counts.hits, 1u);
  EXPECT_EQ(counts.misses, 2u);
  EXPECT_EQ(counts.near_miss, 1u);
}

TEST(ImplicitRaycast, ResultDoesNotDependOnTheThreadCount) {
  const auto field = test::tanglecube();
  RaycastOptions o;
  o.lipschitz_grid = 8;
  const auto rays = make_camera_rays(field->bounds(), small_camera(2, 16));
  GroundTruth one;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = compute_ground_truth(*field, rays, o);
  }
  const GroundTruth many = compute_ground_truth(*field, rays, o);
  ASSERT_EQ(one.hits.size(), many.hits.size());
  for (std::size_t i = 0; i < one.hits.size(); ++i) {
    EXPECT_EQ(one.hits[i].status, many.hits[i].status);
    EXPECT_EQ(one.hits[i].t, many.hits[i].t);
    EXPECT_EQ(one.hits[i].normal, many.hits[i].normal);
  }
}

}  // namespace
}  // namespace cdp
