// Principal curvatures against closed forms; the matrix C of the paper against the shape operator.
#include <gtest/gtest.h>

#include <cdp/core/curvature.h>
#include <cdp/core/errors.h>
#include <cdp/core/newton_projection.h>

#include <Eigen/LU>

#include <random>

#include "common/same_bits.h"
#include "common/test_fields.h"

namespace cdp {
namespace {

constexpr double kTol = 1e-9;

TEST(Curvature, SphereHasBothCurvaturesOneOverRadiusAndShapeIndexMinusOne) {
  for (double r : {0.5, 1.0, 3.0}) {
    Sphere s(Vec3(1, 2, 3), r);
    const Vec3 p = Vec3(1, 2, 3) + r * Vec3(1, -2, 0.5).normalized();
    const Curvature c = curvature_at(s, p);
    EXPECT_NEAR(c.k1, 1 / r, kTol);
    EXPECT_NEAR(c.k2, 1 / r, kTol);
    EXPECT_NEAR(c.gaussian, 1 / (r * r), kTol);
    EXPECT_NEAR(c.mean, 1 / r, kTol);
    EXPECT_NEAR(c.mac, 1 / r, kTol);
    EXPECT_NEAR(c.min_radius, r, 1e-9 * r);
    // Positive curvatures (gradient outward): kmax + kmin > 0, kmax = kmin, so
    // -(2/pi) atan(+inf) = -1. A sphere is a "cup" of shape index -1 in this paper's convention.
    EXPECT_NEAR(c.shape_index, -1.0, kTol);
    EXPECT_NEAR(c.normal.dot(Vec3(1, -2, 0.5).normalized()), 1.0, kTol);
  }
}

TEST(Curvature, InsideOutSphereIsConcaveWithShapeIndexPlusOne) {
  // F = 1 - |x|^2 / 4: negative outside radius 2, so the normal points inward.
  const auto f = test::field_from_json(
      R"({"type": "expression", "value": "1 - (x^2 + y^2 + z^2)/4", "bounds": [[-3,-3,-3],[3,3,3]]})");
  const Curvature c = curvature_at(*f, Vec3(0, 2, 0));
  EXPECT_NEAR(c.k1, -0.5, kTol);
  EXPECT_NEAR(c.k2, -0.5, kTol);
  EXPECT_NEAR(c.shape_index, 1.0, kTol);
}

TEST(Curvature, CylinderFromExpressionHasCurvaturesOneOverRadiusAndZero) {
  const auto f = test::field_from_json(
      R"({"type": "expression", "value": "sqrt(x^2 + y^2) - r + 0*z", "params": {"r": 0.7},
          "bounds": [[-1,-1,-1],[1,1,1]]})");
  const Vec3 p(0.7 * std::cos(0.3), 0.7 * std::sin(0.3), 0.2);
  const Curvature c = curvature_at(*f, p);
  EXPECT_NEAR(c.k1, 1 / 0.7, kTol);
  EXPECT_NEAR(c.k2, 0.0, kTol);
  EXPECT_NEAR(c.gaussian, 0.0, kTol);
  EXPECT_NEAR(std::abs(c.dir2.z()), 1.0, kTol);  // the ruling is the flat direction
  EXPECT_NEAR(c.shape_index, -0.5, kTol);        // -(2/pi) atan(1)
}

TEST(Curvature, TorusEquatorsMatchClosedForms) {
  const double R = 1.0, r = 0.3;
  Torus t(Vec3::Zero(), R, r);
  const Curvature outer = curvature_at(t, Vec3(R + r, 0, 0));
  EXPECT_NEAR(outer.k1, 1 / r, kTol);
  EXPECT_NEAR(outer.k2, 1 / (R + r), kTol);
  const Curvature inner = curvature_at(t, Vec3(0, R - r, 0));
  EXPECT_NEAR(inner.k1, 1 / r, kTol);
  EXPECT_NEAR(inner.k2, -1 / (R - r), kTol);
  EXPECT_LT(inner.gaussian, 0);
}

TEST(Curvature, EllipsoidGaussianCurvatureAtRandomSurfacePoints) {
  const double a = 1.0, b = 2.0, c = 0.5;
  Ellipsoid e(Vec3::Zero(), Vec3(a, b, c));
  std::mt19937 rng(7);
  std::normal_distribution<double> n;
  for (int i = 0; i < 50; ++i) {
    const Vec3 dir = Vec3(n(rng), n(rng), n(rng)).normalized();
    const Vec3 p = dir.cwiseProduct(Vec3(a, b, c)) / dir.norm();  // on the ellipsoid
    const double q = p.x() * p.x() / std::pow(a, 4) + p.y() * p.y() / std::pow(b, 4) + p.z() * p.z() / std::pow(c, 4);
    const double expected = 1.0 / (a * a * b * b * c * c * q * q);
    const Curvature k = curvature_at(e, p);
    EXPECT_NEAR(k.gaussian, expected, 1e-9 * expected) << p.transpose();
    EXPECT_GT(k.k2, 0);
  }
}

TEST(Curvature, PaperMatrixCHasEigenvaluesZeroK1K2AndAnnihilatesTheNormal) {
  Torus t(Vec3::Zero(), 1.0, 0.4);
  const Vec3 p = project_to_surface(t, Vec3(0.9, 0.7, 0.3)).point;
  const Curvature c = curvature_at(t, p);
  EXPECT_LT((c.normal.transpose() * c.C).norm(), 1e-12);
  // The eigenvalues are the roots of det(lambda I - C) = lambda^3 - tr(C) lambda^2 + m lambda -
  // det(C), m the sum of C's principal 2x2 minors: those of 0, k1 and k2 exactly when tr(C) =
  // k1 + k2, m = k1 k2 and det(C) = 0. (Compared by coefficient: a general eigensolver's template
  // was most of this file's compile time under the sanitizers.)
  const Mat3& C = c.C;
  const double minors = C(0, 0) * C(1, 1) - C(0, 1) * C(1, 0) + C(0, 0) * C(2, 2) - C(0, 2) * C(2, 0) +
                        C(1, 1) * C(2, 2) - C(1, 2) * C(2, 1);
  EXPECT_NEAR(C.trace(), c.k1 + c.k2, 1e-9);
  EXPECT_NEAR(minors, c.k1 * c.k2, 1e-9);
  EXPECT_NEAR(C.determinant(), 0.0, 1e-9);
  // Principal directions: unit, tangent, orthogonal.
  EXPECT_NEAR(c.dir1.norm(), 1.0, 1e-12);
  EXPECT_NEAR(c.dir1.dot(c.normal), 0.0, 1e-12);
  EXPECT_NEAR(c.dir2.dot(c.normal), 0.0, 1e-12);
  EXPECT_NEAR(c.dir1.dot(c.dir2), 0.0, 1e-12);
  EXPECT_GE(c.k1, c.k2);
}

TEST(Curvature, VanishingGradientIsANoSurfaceError) {
  try {
    curvature_from_derivatives(Vec3::Zero(), Mat3::Identity());
    FAIL() << "expected NoSurfaceError";
  } catch (const NoSurfaceError& e) {
    EXPECT_NE(std::string(e.what()).find("gradient vanishes"), std::string::npos) << e.what();
  }
  Vec3 nan_gradient(std::nan(""), 0, 0);
  EXPECT_THROW(curvature_from_derivatives(nan_gradient, Mat3::Identity()), NoSurfaceError);
}

TEST(Curvature, CurvaturesAtABatchAreThoseOfEachPointBitForBit) {
  // More points than one batch holds (16384), so that the batches' seams are crossed too.
  const auto f = test::tanglecube();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-2.5, 2.5);
  std::vector<Vec3> points(20000);
  for (Vec3& p : points) p = Vec3(u(rng), u(rng), u(rng));
  f->reset_counts();
  const std::vector<Curvature> batch = curvatures_at(*f, points);
  EXPECT_EQ(f->counts().gradient_hessian, points.size());
  ASSERT_EQ(batch.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Curvature one = curvature_at(*f, points[i]);
    ASSERT_TRUE(test::same_bits(batch[i].k1, one.k1) && test::same_bits(batch[i].k2, one.k2) &&
                test::same_bits(batch[i].mac, one.mac) && test::same_bits(batch[i].shape_index, one.shape_index) &&
                test::same_bits(batch[i].normal, one.normal))
        << "point " << i;
  }
}

}  // namespace
}  // namespace cdp
