// Black boxes (fields whose derivatives come from central differences, Field::derivative_step)
// at their creases: the tracker finds a kink on a vertex or between two (Tracker::kink_between,
// src/adaptive/tracker.h); with creases: follow the run stops there (BlackBoxKinkError), with
// ignore, or a field its caller promises smooth, it meshes across and the stats say so. The
// Python tests (tests/python/test_callable.py) run the same on numpy functions.
#include <gtest/gtest.h>

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/errors.h>
#include <cdp/core/curvature.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/core/models/analytic.h>

#include "src/adaptive/blocks.h"
#include "src/adaptive/resolve_settings.h"
#include "src/adaptive/stage_seed_grid.h"
#include "src/adaptive/tracker.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <functional>
#include <numbers>
#include <optional>
#include <string>
#include <utility>

#include "polygonizer/mesh_checks.h"

namespace cdp {
namespace {

// A value function with derivatives as Python's callable_field makes them: central differences
// of values, the gradient's 1e-5 and the Hessian's 1e-4 of the box's diagonal apart.
class DifferencedField : public Field {
 public:
  DifferencedField(std::function<double(const Vec3&)> f, double half_side, bool smooth = false)
      : f_(std::move(f)), smooth_(smooth) {
    set_bounds(Box{Vec3::Constant(-half_side), Vec3::Constant(half_side)});
    gradient_step_ = 1e-5 * bounds().diagonal();
    hessian_step_ = 1e-4 * bounds().diagonal();
  }
  std::string type_name() const override { return "differenced"; }
  bool smooth() const override { return smooth_; }
  std::optional<double> derivative_step() const override { return hessian_step_; }

 protected:
  double eval_value(const Vec3& p) const override { return f_(p); }
  double eval_value_gradient(const Vec3& p, Vec3& g) const override {
    for (int k = 0; k < 3; ++k) {
      const Vec3 e = Vec3::Unit(k) * gradient_step_;
      g[k] = (f_(p + e) - f_(p - e)) / (2 * gradient_step_);
    }
    return f_(p);
  }
  double eval_gradient_hessian(const Vec3& p, Vec3& g, Mat3& h) const override {
    const double v = eval_value_gradient(p, g), s = hessian_step_;
    for (int i = 0; i < 3; ++i) {
      const Vec3 ei = Vec3::Unit(i) * s;
      h(i, i) = (f_(p + ei) - 2 * v + f_(p - ei)) / (s * s);
      for (int j = 0; j < i; ++j) {
        const Vec3 ej = Vec3::Unit(j) * s;
        h(i, j) = h(j, i) = (f_(p + ei + ej) - f_(p + ei - ej) - f_(p - ei + ej) + f_(p - ei - ej)) / (4 * s * s);
      }
    }
    return v;
  }

 private:
  std::function<double(const Vec3&)> f_;
  bool smooth_;
  double gradient_step_, hessian_step_;
};

// A unit sphere capped by the plane z = 0.7: faces meeting 134 degrees apart along a circle.
double sphere_capped_by_a_plane(const Vec3& p) { return std::max(p.norm() - 1, p.z() - 0.7); }

AdaptiveOptions black_box_options(double factor, CreaseHandling creases = CreaseHandling::Follow) {
  AdaptiveOptions o;
  o.factor = factor;
  o.creases = creases;
  return o;
}

// The calls the tracker and what follows it make (the seed grid's values left out: the same
// in every run of a field).
std::uint64_t calls_past_the_grid(const Field& field) {
  return field.counts().value_gradient + field.counts().gradient_hessian;
}

TEST(BlackBoxKinks, AStepAcrossACreaseStopsARunThatFollowsCreases) {
  // No vertex lands within the differences' step of the circle (the fronts step over it with
  // each end on a face): only the turn between a step's ends shows it. The run stops there,
  // before a mesh is made (meshed across: 1,590 calls past the seed grid; stopped: 450), and
  // its error names the kink.
  const DifferencedField field(sphere_capped_by_a_plane, 1.25), across(sphere_capped_by_a_plane, 1.25);
  polygonize_adaptive(across, black_box_options(3, CreaseHandling::Ignore));
  try {
    polygonize_adaptive(field, black_box_options(3));
    FAIL() << "meshed across a crease of a black box";
  } catch (const LimitExceededError& e) {  // BlackBoxKinkError, its message explained (failure_message.h)
    const std::string message = e.what();
    EXPECT_NE(message.find("crosses a kink of a field without branch data"), std::string::npos) << message;
    EXPECT_NE(message.find("creases: ignore meshes across"), std::string::npos) << message;
  }
  EXPECT_LT(calls_past_the_grid(field), calls_past_the_grid(across) / 2);
}

// A torus (R = 1, r = 0.4) with a knob, a ball of radius 0.15 under its tube at 225 degrees: a
// crease circle where they meet, inside the first of the 2 x 2 x 2 blocks the torus is cut into
// at factor 12 (the cuts at 0.05).
double torus_with_a_knob(const Vec3& p) {
  const double q = std::hypot(p.x(), p.y()) - 1, c = -std::sqrt(0.5);
  return std::min(std::hypot(q, p.z()) - 0.4, (p - Vec3(c, c, -0.45)).norm() - 0.15);
}

std::string what(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const std::exception& e) {
    return e.what();
  }
}

TEST(BlackBoxKinks, AKinkInABlockStopsTheBlocksAfterItAndEndsTheRunTheSameInAnyOrder) {
  // The run ends with the kink of the lowest block that meets one, so the blocks after it in
  // block order are stopped as soon as it does (a Python function's blocks in lockstep ran to
  // their end first): in the orders where it runs before some of them, they are stopped, and the
  // error and the tightest bend are the same in every order.
  const DifferencedField field(torus_with_a_knob, 1.6);
  AdaptiveOptions o = black_box_options(12);
  o.blocks = true;
  o.threads = 1;
  adaptive::Settings settings = adaptive::resolve_settings(field, o);
  const adaptive::SeedGridStage seeds = adaptive::sample_seed_grid_stage(field, o, settings);
  settings.hash_cell = seeds.hash_cell;
  std::string first;
  std::pair<double, Vec3> tightest;
  std::size_t most_stopped = 0;
  for (const std::uint64_t shuffle : {0u, 1u, 2u, 3u, 4u, 5u}) {
    const adaptive::BlockMeshing b = adaptive::mesh_blocks(field, o, settings, seeds, nullptr, shuffle);
    ASSERT_TRUE(b.kink) << "order " << shuffle << ": " << b.report.fallback;
    EXPECT_FALSE(b.mesh);
    const std::string message = what(b.kink);
    if (first.empty()) first = message, tightest = b.tightest;
    EXPECT_EQ(message, first) << "order " << shuffle;
    EXPECT_EQ(b.tightest.first, tightest.first) << "order " << shuffle;
    EXPECT_EQ(b.tightest.second, tightest.second) << "order " << shuffle;
    most_stopped = std::max(most_stopped, b.stopped);
  }
  EXPECT_NE(first.find("a kink of a field without branch data"), std::string::npos) << first;
  EXPECT_GT(most_stopped, 0u);
  EXPECT_THROW(polygonize_adaptive(field, o), LimitExceededError);
}

constexpr double kDegree = std::numbers::pi / 180;

TEST(BlackBoxKinks, TheTurnCurvatureDoesNotExplainIsACreasesAngle) {
  // On one sphere the ends' curvature carries the normal along the chord: a radian's chord (a
  // step at factor 1) leaves about 2 degrees, a tenth of one next to nothing.
  const Sphere unit(Vec3::Zero(), 1);
  for (const double arc : {1.0, 0.1}) {
    const Vec3 a(1, 0, 0), b(std::cos(arc), std::sin(arc), 0);
    const double left = adaptive::Tracker::unexplained_turn(a, curvature_at(unit, a), b, curvature_at(unit, b));
    EXPECT_LT(left, arc * arc * arc * 3 * kDegree) << arc;
  }
  // Two unit spheres whose centres are 2 sin(6 degrees) apart meet at 12 degrees: a chord from
  // one across their circle to the other leaves that angle, whether the crease is convex (their
  // intersection: the raw turn is the faces' and the crease's) or concave (their union: the
  // crease takes its angle from the faces' turn). Within 1.5 degrees at a chord of 0.6.
  const double c = std::sin(6 * kDegree);
  const Sphere upper(Vec3(0, 0, c), 1), lower(Vec3(0, 0, -c), 1);
  const double r = std::sqrt(1 - c * c);
  for (const double arc : {0.3, 0.05}) {
    // On the lens (the intersection) the upper sphere bounds the lower half-space, and the
    // other way round; on the union, each bounds its own side.
    const Vec3 on_upper = Vec3(0, 0, c) + Vec3(r, 0, -c - std::sin(arc)).normalized(),
               on_lower = Vec3(0, 0, -c) + Vec3(r, 0, c + std::sin(arc)).normalized();
    const double lens = adaptive::Tracker::unexplained_turn(on_upper, curvature_at(upper, on_upper), on_lower,
                                                            curvature_at(lower, on_lower));
    EXPECT_NEAR(lens, 12 * kDegree, (0.1 + 50 * arc * arc * arc) * kDegree) << arc;
    const Vec3 union_upper = Vec3(0, 0, c) + Vec3(r, 0, -c + std::sin(arc)).normalized(),
               union_lower = Vec3(0, 0, -c) + Vec3(r, 0, c - std::sin(arc)).normalized();
    const double raw = std::acos(curvature_at(upper, union_upper).normal.dot(curvature_at(lower, union_lower).normal));
    const double valley = adaptive::Tracker::unexplained_turn(union_upper, curvature_at(upper, union_upper), union_lower,
                                                              curvature_at(lower, union_lower));
    EXPECT_NEAR(valley, 12 * kDegree, (0.1 + 50 * arc * arc * arc) * kDegree) << arc;
    // The raw turn is less than the chord's curvature alone turns (a radian a unit length).
    if (arc > 0.1) {
      EXPECT_LT(raw, (union_upper - union_lower).norm());
    }
  }
}

TEST(BlackBoxKinks, ShallowCreasesConvexOrConcaveStopTheRun) {
  // Two unit spheres meeting at 8 degrees, as their intersection (a lens: a convex crease) and
  // their union (a concave one), at factors 1 and 3 and a tolerance; a raw turn of more than 10
  // degrees, and more than the ends' curvature explains, missed both (the meshes cut them by
  // chords, and said nothing) at every one of them.
  const double c = std::sin(4 * kDegree), h = 1.25 + c;
  const auto lens = [c](const Vec3& p) { return std::max((p - Vec3(0, 0, c)).norm(), (p + Vec3(0, 0, c)).norm()) - 1; };
  const auto both = [c](const Vec3& p) { return std::min((p - Vec3(0, 0, c)).norm(), (p + Vec3(0, 0, c)).norm()) - 1; };
  AdaptiveOptions tolerance;
  tolerance.sizing = SizingMode::Tolerance;
  tolerance.tolerance = 1e-3;
  for (const auto& [name, f] : {std::pair<std::string, std::function<double(const Vec3&)>>{"lens", lens}, {"union", both}}) {
    for (const auto& [run, o] : {std::pair{"factor 1", black_box_options(1)}, std::pair{"factor 3", black_box_options(3)},
                                 std::pair{"tolerance 1e-3", tolerance}}) {
      const DifferencedField field(f, h);
      try {
        polygonize_adaptive(field, o);
        ADD_FAILURE() << name << " at " << run << ": meshed across a crease of a black box";
      } catch (const LimitExceededError& e) {
        EXPECT_NE(std::string(e.what()).find("crosses a kink"), std::string::npos) << name << " at " << run << ": " << e.what();
      }
    }
    const DifferencedField field(f, h);
    const PolygonizeResult r = polygonize_adaptive(field, black_box_options(3, CreaseHandling::Ignore));
    EXPECT_TRUE(r.stats.adaptive->creases.across_black_box) << name;
    EXPECT_EQ(analyze_topology(r.mesh).genus, 0) << name;
  }
}

TEST(BlackBoxKinks, IgnoreOrASmoothPromiseMeshesAcross) {
  // With ignore the stats say the mesh cut a kink; a field promised smooth (here wrongly) is not
  // searched for kinks between vertices, and meshes the same.
  std::size_t triangles[2] = {0, 0};
  for (const bool smooth : {false, true}) {
    const DifferencedField field(sphere_capped_by_a_plane, 1.25, smooth);
    const PolygonizeResult r =
        polygonize_adaptive(field, black_box_options(3, smooth ? CreaseHandling::Follow : CreaseHandling::Ignore));
    const std::string what = smooth ? "smooth" : "ignore";
    test::expect_sound(r.mesh, what);
    const MeshTopology t = analyze_topology(r.mesh);
    EXPECT_EQ(t.components, 1u) << what;
    EXPECT_EQ(t.genus, 0) << what;
    if (!smooth) {
      EXPECT_TRUE(r.stats.adaptive->creases.across_black_box);
    }
    triangles[smooth] = r.mesh.triangles.size();
  }
  EXPECT_EQ(triangles[0], triangles[1]);
}

TEST(BlackBoxKinks, ASmoothBlackBoxFindsNoKink) {
  // A torus and a sphere squashed to an ellipsoid: the curvature at a step's two ends explains
  // its turn, and where it changes along the step what it leaves spreads over the step's length,
  // which kink_between tells from a crease.
  const DifferencedField torus([](const Vec3& p) { return std::hypot(std::hypot(p.x(), p.y()) - 1, p.z()) - 0.3; }, 1.5);
  const DifferencedField ellipsoid(
      [](const Vec3& p) { return Vec3(p.x(), 2 * p.y(), 4 * p.z()).norm() - 1; }, 1.25);
  for (const auto& [name, field] : {std::pair{"torus", &torus}, std::pair{"ellipsoid", &ellipsoid}}) {
    for (const double factor : {1.0, 3.0}) {
      const PolygonizeResult r = polygonize_adaptive(*field, black_box_options(factor));
      EXPECT_FALSE(r.stats.adaptive->creases.across_black_box) << name << " at " << factor;
      EXPECT_EQ(analyze_topology(r.mesh).genus, name == std::string("torus") ? 1 : 0) << name << " at " << factor;
    }
  }
}

TEST(BlackBoxKinks, ARoundedBoxIsNoKink) {
  // Where a fillet meets a flat face the curvature jumps (C1): each face predicts its own half of
  // a step across the seam, and what neither predicts shrinks with the step. Fillets of radius
  // 0.05 (115 differences' steps) and 0.02 (46).
  for (const double r : {0.05, 0.02}) {
    const DifferencedField field(
        [r](const Vec3& p) {
          const Vec3 q = p.cwiseAbs() - Vec3::Constant(0.8 - r);
          return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0) - r;
        },
        1.25);
    const PolygonizeResult m = polygonize_adaptive(field, black_box_options(1));
    EXPECT_FALSE(m.stats.adaptive->creases.across_black_box) << r;
    test::expect_sound(m.mesh, "rounded box");
  }
}

TEST(BlackBoxKinks, OnlyFollowingCreasesOfABlackBoxNotPromisedSmoothStops) {
  const DifferencedField black_box(sphere_capped_by_a_plane, 1.25), promised(sphere_capped_by_a_plane, 1.25, true);
  EXPECT_TRUE(adaptive::resolve_settings(black_box, black_box_options(3)).stop_at_kink);
  EXPECT_FALSE(adaptive::resolve_settings(black_box, black_box_options(3, CreaseHandling::Ignore)).stop_at_kink);
  EXPECT_FALSE(adaptive::resolve_settings(promised, black_box_options(3)).stop_at_kink);
  AdaptiveOptions paper = black_box_options(3);
  paper.variant = Variant::Paper;
  EXPECT_FALSE(adaptive::resolve_settings(black_box, paper).stop_at_kink);
}

}  // namespace
}  // namespace cdp
