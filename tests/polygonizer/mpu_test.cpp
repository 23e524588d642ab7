// MPU implicits: accuracy on known surfaces, exact derivatives (weights included), weights that
// cover the box, and bad input.
#include <gtest/gtest.h>

#include <cdp/core/errors.h>
#include <cdp/core/models/mpu.h>
#include <cdp/io/field_factory.h>

#include <random>

#include "common/test_fields.h"
#include "polygonizer/oriented_point_sets.h"

namespace cdp {
namespace {

using test::first_order_distance;

MpuOptions options_with_error(double max_error) {
  MpuOptions o;
  o.max_error = max_error;
  return o;
}

TEST(Mpu, SphereWithinTolerance) {
  const Mpu mpu(test::sphere_points(1500), options_with_error(0.001));
  const MpuStats& st = mpu.stats();
  EXPECT_GT(st.leaves, 8u);
  EXPECT_EQ(st.leaves, st.bivariate + st.quadric + st.plane + st.empty);
  EXPECT_EQ(st.at_max_depth, 0u);
  EXPECT_LT(mpu.value(Vec3::Zero()), 0.0);
  EXPECT_GT(mpu.value(Vec3(1.2, 0.1, 0)), 0.0);
  // On the true sphere (points between the samples), within the tolerance 0.001 of the box
  // diagonal (about 0.0035 here).
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  double worst = 0;
  for (int i = 0; i < 1000; ++i) {
    const Vec3 p = Vec3(g(rng), g(rng), g(rng)).normalized();
    worst = std::max(worst, first_order_distance(mpu, p));
  }
  RecordProperty("max_deviation", std::to_string(worst));
  EXPECT_LT(worst, st.tolerance);
}

TEST(Mpu, TorusWithinTolerance) {
  const Mpu mpu(test::torus_points(80, 32), options_with_error(0.001));
  EXPECT_LT(mpu.value(Vec3(1, 0, 0)), 0.0);
  EXPECT_GT(mpu.value(Vec3(0, 0, 0)), 0.0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> angle(0, 2 * M_PI);
  double worst = 0;
  for (int i = 0; i < 1000; ++i) {
    const double u = angle(rng), v = angle(rng);
    const Vec3 n(std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v));
    worst = std::max(worst, first_order_distance(mpu, Vec3(std::cos(u), std::sin(u), 0.0) + 0.4 * n));
  }
  RecordProperty("max_deviation", std::to_string(worst));
  EXPECT_LT(worst, mpu.stats().tolerance);
  // Near the surface the field approximates the signed distance.
  for (double t : {-0.05, 0.05}) EXPECT_NEAR(mpu.value(Vec3(1.4 + t, 0, 0)), t, 0.01);
}

TEST(Mpu, DerivativesMatchFiniteDifferences) {
  const Mpu mpu(test::torus_points(40, 16), options_with_error(0.002));
  const Box box = mpu.bounds();
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double h = 1e-6;
  for (int trial = 0; trial < 60; ++trial) {
    const Vec3 p = box.min + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(box.size());
    Vec3 g, g2;
    Mat3 H;
    const double v0 = mpu.value(p);
    EXPECT_EQ(v0, mpu.value_gradient(p, g));  // the same sums in every path
    EXPECT_EQ(v0, mpu.gradient_hessian(p, g2, H));
    EXPECT_LT((g - g2).norm(), 1e-14 * std::max(1.0, g.norm()));
    for (int a = 0; a < 3; ++a) {
      const Vec3 e = h * Vec3::Unit(a);
      const double fd = (mpu.value(p + e) - mpu.value(p - e)) / (2 * h);
      EXPECT_NEAR(g[a], fd, 1e-6 * std::max(1.0, g.norm())) << "gradient " << a << " at " << p.transpose();
      Vec3 gp, gm;
      mpu.value_gradient(p + e, gp);
      mpu.value_gradient(p - e, gm);
      const Vec3 hfd = (gp - gm) / (2 * h);
      for (int b = 0; b < 3; ++b)
        EXPECT_NEAR(H(b, a), hfd[b], 1e-4 * std::max(1.0, H.norm())) << "hessian " << b << a << " at " << p.transpose();
    }
    EXPECT_TRUE(H.isApprox(H.transpose(), 1e-12));
  }
}

TEST(Mpu, WeightsSumToAPositiveValueThroughoutTheBox) {
  const OrientedPoints pts = test::torus_points(40, 16);
  const Mpu mpu(pts, options_with_error(0.002));
  // Near every point, and on a grid over the whole box (corners included).
  for (std::size_t i = 0; i < pts.size(); i += 7) {
    EXPECT_GT(mpu.weight_sum(pts.positions[i]), 0.1) << i;
    EXPECT_GT(mpu.weight_sum(pts.positions[i] + 0.05 * pts.normals[i]), 0.1) << i;
  }
  const Box box = mpu.bounds();
  for (int i = 0; i <= 10; ++i)
    for (int j = 0; j <= 10; ++j)
      for (int k = 0; k <= 10; ++k) {
        const Vec3 p = box.min + Vec3(i, j, k).cwiseProduct(box.size()) / 10.0;
        ASSERT_GT(mpu.weight_sum(p), 0.1) << p.transpose();
        ASSERT_TRUE(std::isfinite(mpu.value(p)));
      }
  // The box boundary is outside the surface.
  EXPECT_GT(mpu.value(box.min), 0.0);
  EXPECT_GT(mpu.value(box.max), 0.0);
}

TEST(Mpu, DeterministicBuild) {
  const OrientedPoints pts = test::sphere_points(800);
  const Mpu a(pts), b(pts);
  EXPECT_EQ(a.stats().leaves, b.stats().leaves);
  for (double x : {0.0, 0.3, 0.97, 1.1}) EXPECT_EQ(a.value(Vec3(x, 0.2, -0.1)), b.value(Vec3(x, 0.2, -0.1)));
}

TEST(Mpu, BadInputIsAnError) {
  EXPECT_THROW(Mpu(test::sphere_points(14)), InvalidInputError);  // fewer than min_points
  OrientedPoints bad = test::sphere_points(100);
  bad.normals[5] = Vec3(0, 0, 0);
  EXPECT_THROW(Mpu{bad}, InvalidInputError);
  MpuOptions o;
  o.support_factor = 0.5;
  EXPECT_THROW(Mpu(test::sphere_points(100), o), InvalidInputError);
  o = {};
  o.max_error = 0;
  EXPECT_THROW(Mpu(test::sphere_points(100), o), InvalidInputError);
}

TEST(Mpu, LoadsFromJsonAndReportsBadKeys) {
  const std::string dir = std::string(CDP_SOURCE_DIR) + "/experiments/fields";
  const auto field = load_field(dir + "/bunny_mpu.json");
  ASSERT_EQ(field->type_name(), "mpu");
  const auto& mpu = dynamic_cast<const Mpu&>(*field);
  EXPECT_GT(mpu.stats().points, 34000u);
  EXPECT_FALSE(mpu.constraint_spacing());
  auto error_of = [&](const std::string& text) -> std::string {
    try {
      make_field(nlohmann::json::parse(text), "t.json", dir);
    } catch (const InvalidInputError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of(R"({"type": "mpu", "points": "missing.ply"})").find("missing.ply"), std::string::npos);
  EXPECT_NE(error_of(R"({"type": "mpu", "points": "../../data/bunny.ply", "min_points": 5})")
                .find("min_points"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"type": "mpu", "points": "../../data/bunny.ply", "support_factor": 0.4})")
                .find("support_factor"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"type": "mpu", "points": "../../data/bunny.ply", "max_eror": 0.01})")
                .find("max_eror"),
            std::string::npos);
}

}  // namespace
}  // namespace cdp
