// The Newton step converges onto the surface and reports, rather than loops, when it cannot.
#include <gtest/gtest.h>

#include <cdp/core/newton_projection.h>

#include <cstdint>
#include <map>
#include <memory>
#include <random>
#include <span>
#include <stdexcept>
#include <vector>

#include "common/same_bits.h"
#include "common/test_fields.h"

namespace cdp {
namespace {

TEST(NewtonProjection, ConvergesOntoTheSurfaceFromNearbyPoints) {
  Torus t(Vec3::Zero(), 1.0, 0.3);
  for (const Vec3& start : {Vec3(1.5, 0, 0), Vec3(0.8, 0.8, 0.2), Vec3(0, -1.1, -0.1)}) {
    const ProjectionResult r = project_to_surface(t, start);
    ASSERT_TRUE(r.ok()) << to_string(r.status);
    EXPECT_LT(std::abs(t.value(r.point)), 1e-9);
    EXPECT_LE(r.iterations, 10);
  }
}

TEST(NewtonProjection, ReportsTheGradientWhereItLanded) {
  // The quality pass takes the landed point's normal from the result instead of evaluating again.
  Torus t(Vec3::Zero(), 1.0, 0.3);
  const ProjectionResult r = project_to_surface(t, Vec3(0.8, 0.8, 0.2));
  ASSERT_TRUE(r.ok()) << to_string(r.status);
  EXPECT_EQ(r.gradient, t.gradient(r.point));
  EXPECT_NE(r.gradient, r.start_gradient);
}

TEST(NewtonProjection, ConvergesQuadraticallyOnAPolynomialField) {
  const auto f = test::tanglecube();
  const ProjectionResult r = project_to_surface(*f, Vec3(2.0, 0.3, 0.1));
  ASSERT_TRUE(r.ok()) << to_string(r.status);
  EXPECT_LT(r.residual, 1e-9);
  EXPECT_LE(r.iterations, 12);
}

TEST(NewtonProjection, ReportsTheGradientWhereItStartedSoACreaseCrossingShows) {
  // From outside the cube's edge x = y = 1 on the y side, Newton runs along +y's gradient and
  // lands on the edge, where max(|x|, ...) picks the x piece at the tie: the two gradients
  // differ though the landing point alone looks like a point of the face x = 1.
  const auto f = test::field_from_json(
      R"({"type": "expression", "value": "max(abs(x),max(abs(y),abs(z)))-1", "bounds": [[-2,-2,-2],[2,2,2]]})");
  const ProjectionResult r = project_to_surface(*f, Vec3(1, 1.2, 0.3));
  ASSERT_TRUE(r.ok()) << to_string(r.status);
  EXPECT_NEAR(r.point.y(), 1, 1e-9);
  EXPECT_EQ(r.start_gradient, Vec3(0, 1, 0));
}

TEST(NewtonProjection, ReportsAVanishingGradient) {
  const auto f = test::field_from_json(
      R"({"type": "expression", "value": "x^2 + y^2 + z^2 - 1", "bounds": [[-2,-2,-2],[2,2,2]]})");
  const ProjectionResult r = project_to_surface(*f, Vec3::Zero());
  EXPECT_EQ(r.status, ProjectionStatus::VanishingGradient);
  EXPECT_FALSE(r.ok());
}

TEST(NewtonProjection, StopsWithinItsBoundsWhenThereIsNoSurface) {
  // F >= 1 everywhere: Newton would walk forever towards the minimum at the origin and beyond.
  const auto f = test::field_from_json(
      R"({"type": "expression", "value": "x^2 + y^2 + z^2 + 1", "bounds": [[-2,-2,-2],[2,2,2]]})");
  ProjectionOptions opt;
  opt.max_iterations = 25;
  const ProjectionResult r = project_to_surface(*f, Vec3(1, 1, 1), opt);
  EXPECT_FALSE(r.ok());
  EXPECT_LE(r.iterations, 25);
  const auto before = f->counts().value_gradient;
  EXPECT_LE(before, 26u);
}

TEST(NewtonProjection, ReportsTooFarWhenTheTravelLimitIsHit) {
  Sphere s(Vec3::Zero(), 1.0);
  ProjectionOptions opt;
  opt.max_travel = 0.1;
  const ProjectionResult r = project_to_surface(s, Vec3(3, 0, 0), opt);
  EXPECT_EQ(r.status, ProjectionStatus::TooFar);
}

TEST(NewtonProjection, ReportsNonFiniteFields) {
  const auto f =
      test::field_from_json(R"({"type": "expression", "value": "log(x - 5) + y + z", "bounds": [[-1,-1,-1],[1,1,1]]})");
  const ProjectionResult r = project_to_surface(*f, Vec3(0.1, 0.2, 0.3));
  EXPECT_EQ(r.status, ProjectionStatus::NotFinite);
}

// The box of a sphere of radius 1e160 has an infinite diagonal, hence an infinite default
// tolerance: the start point was returned as converged, 1e160 away from the surface.
TEST(NewtonProjection, ReportsABoxTooLargeForDoublePrecision) {
  const Sphere huge(Vec3::Zero(), 1e160);
  const ProjectionResult r = project_to_surface(huge, Vec3(1, 0, 0));
  EXPECT_EQ(r.status, ProjectionStatus::OutOfRange);
  EXPECT_FALSE(r.ok());
}

// Near x = 1e20 doubles are 16384 apart, far coarser than the tolerance (1e-10 of the box
// diagonal, 3.8 here): the step rounds to nothing, which is reported at once.
TEST(NewtonProjection, ReportsAStepThatCannotMoveThePoint) {
  const Sphere far(Vec3(1e20, 0, 0), 1e10);
  const ProjectionResult r = project_to_surface(far, Vec3(1e20 + 1e10 + 3e5, 0, 0));
  EXPECT_EQ(r.status, ProjectionStatus::NoProgress);
  EXPECT_LT(r.iterations, 5);
}

using test::same_bits;

// Wraps a field and records the size of every values_gradients batch asked of it.
class BatchRecorder : public Field {
 public:
  explicit BatchRecorder(const Field& inner) : inner_(inner) { bounds_ = inner.bounds(); }
  std::string type_name() const override { return "recorder"; }
  mutable std::vector<std::size_t> batches;

 protected:
  double eval_value(const Vec3& p) const override { return inner_.value(p); }
  double eval_value_gradient(const Vec3& p, Vec3& g) const override { return inner_.value_gradient(p, g); }
  double eval_gradient_hessian(const Vec3& p, Vec3& g, Mat3& h) const override { return inner_.gradient_hessian(p, g, h); }
  void eval_values_gradients(const Vec3* points, double* values, Vec3* gradients, std::size_t n) const override {
    batches.push_back(n);
    inner_.values_gradients(points, values, gradients, n);
  }

 private:
  const Field& inner_;
};

// Start points all over the box and beyond, with options that differ from point to point
// (every limit, including none and no iterations at all), so that every status comes up.
struct Starts {
  std::vector<Vec3> points;
  std::vector<ProjectionOptions> options;
};

Starts random_starts(const Field& field, std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.1, 1.1);
  const Box box = field.bounds();
  const double d = box.diagonal();
  constexpr int kIterations[] = {-1, 0, 1, 2, 3, 5, 40, 40, 40, 40};
  constexpr double kTolerance[] = {0, 0, 1e-6, 1e-12};
  constexpr double kStep[] = {0, 0, 0.001, 0.01, 0.05, 0.3};
  constexpr double kTravel[] = {0, 0, 0.002, 0.02, 0.1, 1};
  const auto pick = [&](const auto& a) { return a[std::uniform_int_distribution<std::size_t>(0, std::size(a) - 1)(rng)]; };
  Starts s;
  for (std::size_t i = 0; i < n; ++i) {
    s.points.push_back(box.min + box.size().cwiseProduct(Vec3(u(rng), u(rng), u(rng))));
    ProjectionOptions o;
    o.max_iterations = pick(kIterations);
    o.tolerance = pick(kTolerance) * d;
    o.max_step = pick(kStep) * d;
    o.max_travel = pick(kTravel) * d;
    s.options.push_back(o);
  }
  return s;
}

// The same status, iterations, residual and point, bit for bit.
::testing::AssertionResult same_result(const ProjectionResult& a, const ProjectionResult& b) {
  if (a.status != b.status) return ::testing::AssertionFailure() << to_string(a.status) << " vs " << to_string(b.status);
  if (a.iterations != b.iterations) return ::testing::AssertionFailure() << a.iterations << " vs " << b.iterations << " iterations";
  if (!same_bits(a.residual, b.residual)) return ::testing::AssertionFailure() << "residual " << a.residual << " vs " << b.residual;
  for (int k = 0; k < 3; ++k)
    if (!same_bits(a.point[k], b.point[k])) return ::testing::AssertionFailure() << "coordinate " << k << " differs";
  return ::testing::AssertionSuccess();
}

TEST(NewtonProjection, BatchedGivesEveryPointTheSingleResultBitForBit) {
  std::vector<std::unique_ptr<Field>> fields;
  fields.push_back(test::tanglecube());
  fields.push_back(test::three_separate_blobs());
  fields.push_back(std::make_unique<Torus>(Vec3::Zero(), 1.0, 0.3));
  fields.push_back(test::field_from_json(
      R"({"type": "expression", "value": "max(abs(x),max(abs(y),abs(z)))-1", "bounds": [[-1.5,-1.5,-1.5],[1.5,1.5,1.5]]})"));
  fields.push_back(test::field_from_json(
      R"({"type": "expression", "value": "log(x - 0.5) + y^2 + z", "bounds": [[-1,-1,-1],[1,1,1]]})"));
  std::map<ProjectionStatus, int> seen;
  for (const auto& field : fields) {
    SCOPED_TRACE(field->type_name());
    const Starts s = random_starts(*field, 2000, 7);
    field->reset_counts();
    std::vector<ProjectionResult> single;
    for (std::size_t i = 0; i < s.points.size(); ++i) single.push_back(project_to_surface(*field, s.points[i], s.options[i]));
    const EvaluationCounts single_counts = field->counts();
    field->reset_counts();
    const std::vector<ProjectionResult> batched = project_to_surface(*field, s.points, s.options);
    EXPECT_EQ(field->counts().value_gradient, single_counts.value_gradient);
    EXPECT_EQ(field->counts().total(), single_counts.total());
    ASSERT_EQ(batched.size(), single.size());
    for (std::size_t i = 0; i < single.size(); ++i) {
      const ProjectionResult &a = single[i], &b = batched[i];
      ASSERT_TRUE(same_result(a, b)) << "point " << i;
      ++seen[a.status];
    }
  }
  // The starts reach every way a projection ends but OutOfRange (next test).
  for (const ProjectionStatus st : {ProjectionStatus::Converged, ProjectionStatus::MaxIterations,
                                    ProjectionStatus::VanishingGradient, ProjectionStatus::TooFar,
                                    ProjectionStatus::NotFinite})
    EXPECT_GT(seen[st], 0) << to_string(st);
}

TEST(NewtonProjection, BatchedEvaluatesThePointsStillIteratingOnceARound) {
  const auto blobs = test::three_separate_blobs();
  const BatchRecorder field(*blobs);
  const Starts s = random_starts(field, 300, 11);
  const std::vector<ProjectionResult> r = project_to_surface(field, s.points, s.options);
  // Round k evaluates the points that have not ended before it: those ending at iteration j
  // were evaluated in rounds 0..j (a point with max_iterations -1 in none).
  std::size_t rounds = 0;
  for (std::size_t i = 0; i < r.size(); ++i)
    if (s.options[i].max_iterations >= 0) rounds = std::max(rounds, static_cast<std::size_t>(r[i].iterations) + 1);
  ASSERT_EQ(field.batches.size(), rounds);
  for (std::size_t k = 0; k < rounds; ++k) {
    std::size_t iterating = 0;
    for (std::size_t i = 0; i < r.size(); ++i)
      if (s.options[i].max_iterations >= 0 && static_cast<std::size_t>(r[i].iterations) >= k) ++iterating;
    EXPECT_EQ(field.batches[k], iterating) << "round " << k;
  }
}

// Whether the last round of the projection `r` of `start` was evaluated with the Hessian under
// hessians_below = `below` and left the point where it was: a round after the first, the point
// before it within `below` (found by projecting again with one iteration fewer), and an ending
// that takes no step.
bool last_round_had_hessian(const Field& field, const Vec3& start, ProjectionOptions o, const ProjectionResult& r,
                            double below) {
  if (r.iterations < 1 || r.status == ProjectionStatus::TooFar || r.status == ProjectionStatus::OutOfRange) return false;
  o.max_iterations = r.iterations - 1;
  return project_to_surface(field, start, o).residual <= below;
}

TEST(NewtonProjection, BatchedWithHessiansNearConvergenceGivesTheSameResultsAndTheHessianWhereTheyLand) {
  // With hessians_below, the points within it of the surface are evaluated with their Hessians:
  // the results stay those of the plain projection, bit for bit (the fields here give the same
  // value and gradient by either call), a result whose last evaluation had a Hessian keeps it,
  // bit for bit the field's own at that point, and only those do.
  std::vector<std::unique_ptr<Field>> fields;
  fields.push_back(test::tanglecube());
  fields.push_back(test::three_separate_blobs());
  fields.push_back(std::make_unique<Torus>(Vec3::Zero(), 1.0, 0.3));
  std::size_t kept = 0, evaluated_with_hessians = 0;
  for (const auto& field : fields) {
    SCOPED_TRACE(field->type_name());
    const Starts s = random_starts(*field, 2000, 13);
    const double below = 1e-4 * field->bounds().diagonal();
    const std::vector<ProjectionResult> plain = project_to_surface(*field, s.points, s.options);
    field->reset_counts();
    BatchProjector projector;
    const std::span<const ProjectionResult> r = projector.project(*field, s.points, s.options, below);
    evaluated_with_hessians += field->counts().gradient_hessian;
    for (std::size_t i = 0; i < plain.size(); ++i) {
      const ProjectionResult &a = plain[i], &b = r[i];
      ASSERT_TRUE(same_result(a, b)) << "point " << i;
      // The last evaluation had a Hessian where the one before left the point within `below`
      // and the last did not move it.
      const bool expected = last_round_had_hessian(*field, s.points[i], s.options[i], b, below);
      const Mat3* h = projector.hessian(i);
      ASSERT_EQ(h != nullptr, expected) << "point " << i;
      if (!h) continue;
      ++kept;
      Vec3 g;
      Mat3 want;
      field->gradient_hessian(b.point, g, want);
      for (int k = 0; k < 9; ++k) ASSERT_TRUE(same_bits((*h)(k), want(k))) << "point " << i;
    }
  }
  EXPECT_GT(kept, 400u);  // 535 with these starts: the path is exercised, not only skipped
  EXPECT_GE(evaluated_with_hessians, kept);

  // A round with Hessians whose step then ends the projection (TooFar: the travel limit set
  // between the last two points) leaves no Hessian: it was evaluated where the point no longer is.
  const auto blobs = test::three_separate_blobs();
  const Starts s = random_starts(*blobs, 2000, 17);
  std::size_t too_far = 0;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    ProjectionOptions o;
    const ProjectionResult full = project_to_surface(*blobs, s.points[i], o);
    if (full.status != ProjectionStatus::Converged || full.iterations < 2) continue;
    o.max_iterations = full.iterations - 1;
    const double before = (project_to_surface(*blobs, s.points[i], o).point - s.points[i]).norm();
    const double after = (full.point - s.points[i]).norm();
    if (!(after > before)) continue;
    o.max_iterations = 40;
    o.max_travel = 0.5 * (before + after);
    BatchProjector projector;
    const std::span<const ProjectionResult> r =
        projector.project(*blobs, std::span(&s.points[i], 1), std::span(&o, 1), 1e9 * blobs->bounds().diagonal());
    ASSERT_EQ(r[0].status, ProjectionStatus::TooFar) << "point " << i;
    EXPECT_EQ(projector.hessian(0), nullptr) << "point " << i;
    ++too_far;
  }
  EXPECT_GT(too_far, 10u);
}

TEST(NewtonProjection, BatchedHandlesOutOfRangeAndEmptyInput) {
  const Sphere huge(Vec3::Zero(), 1e160);
  const std::vector<Vec3> starts = {Vec3(1, 0, 0), Vec3(0, 2, 0)};
  const std::vector<ProjectionOptions> options(2);
  const std::vector<ProjectionResult> r = project_to_surface(huge, starts, options);
  for (const ProjectionResult& x : r) EXPECT_EQ(x.status, ProjectionStatus::OutOfRange);
  EXPECT_EQ(huge.counts().total(), 0u);
  EXPECT_TRUE(project_to_surface(huge, std::span<const Vec3>{}, std::span<const ProjectionOptions>{}).empty());
  EXPECT_THROW(project_to_surface(huge, starts, std::span(options).first(1)), std::invalid_argument);
}

}  // namespace
}  // namespace cdp
