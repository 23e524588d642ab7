// The Newton step converges onto the surface and reports, rather than loops, when it cannot.
#include <gtest/gtest.h>

#include <polygonizer/newton_projection.h>

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

}  // namespace
}  // namespace cdp
