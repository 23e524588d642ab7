// Gradient and Hessian of every model against central finite differences at random points.
#include <gtest/gtest.h>

#include <cdp/io/field_factory.h>

#include <random>

#include "common/test_fields.h"

namespace cdp {
namespace {

struct ModelCase {
  std::string name;
  std::string json;
};

std::ostream& operator<<(std::ostream& os, const ModelCase& c) { return os << c.name; }

class FieldDerivatives : public ::testing::TestWithParam<ModelCase> {};

// Relative error of `approx` against `exact`, with a floor of `scale` on the magnitude.
double relative_error(double approx, double exact, double scale) {
  return std::abs(approx - exact) / std::max(std::abs(exact), scale);
}

TEST_P(FieldDerivatives, GradientAndHessianMatchCentralDifferences) {
  const auto field = test::field_from_json(GetParam().json);
  const Box box = field->bounds();
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double h = 1e-5 * box.diagonal();
  int checked = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const Vec3 p = box.min + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(box.size());
    Vec3 g, g2;
    Mat3 H;
    const double v0 = field->value(p);
    const double v1 = field->value_gradient(p, g);
    const double v2 = field->gradient_hessian(p, g2, H);
    ASSERT_EQ(v0, v1);
    ASSERT_EQ(v0, v2);
    ASSERT_TRUE(g.isApprox(g2, 1e-14) || (g - g2).norm() < 1e-300);
    // Scale of the derivatives: errors are measured against the field's typical gradient size,
    // so points where a component happens to be near zero do not inflate the relative error.
    const double gscale = std::max(1.0, g.norm());
    const double hscale = std::max(1.0, H.norm());
    for (int a = 0; a < 3; ++a) {
      Vec3 e = Vec3::Zero();
      e[a] = h;
      const double fd = (field->value(p + e) - field->value(p - e)) / (2 * h);
      EXPECT_LT(relative_error(fd, g[a], gscale), 1e-6) << "d/dx" << a << " at " << p.transpose();
      const Vec3 dg = (field->gradient(p + e) - field->gradient(p - e)) / (2 * h);
      for (int b = 0; b < 3; ++b)
        EXPECT_LT(relative_error(dg[b], H(b, a), hscale), 1e-6) << "H(" << b << "," << a << ") at " << p.transpose();
    }
    EXPECT_LT((H - H.transpose()).norm(), 1e-12 * hscale);
    ++checked;
  }
  EXPECT_EQ(checked, 60);
}

INSTANTIATE_TEST_SUITE_P(
    EveryModel, FieldDerivatives,
    ::testing::Values(
        ModelCase{"sphere", R"J({"type": "sphere", "center": [0.1, -0.2, 0.3], "radius": 1.5})J"},
        ModelCase{"ellipsoid", R"J({"type": "ellipsoid", "center": [0, 0, 0], "radii": [1, 2, 0.5]})J"},
        ModelCase{"torus", R"J({"type": "torus", "center": [0, 0, 0], "major_radius": 1, "minor_radius": 0.3})J"},
        ModelCase{"blobs_wyvill",
                  R"J({"type": "blobs", "kernel": "wyvill", "threshold": 0.3, "blobs": [
                      {"center": [0, 0, 0], "radius": 1, "strength": 1},
                      {"center": [0.8, 0.2, 0], "radius": 0.7, "strength": 1.5}]})J"},
        ModelCase{"blobs_blinn",
                  R"J({"type": "blobs", "kernel": "blinn", "threshold": 0.5, "blobs": [
                      {"center": [0, 0, 0], "radius": 1, "strength": 1},
                      {"center": [1, 0.5, 0], "radius": 0.5, "strength": 2}]})J"},
        ModelCase{"expression_tanglecube",
                  R"J({"type": "expression", "value": "x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + 11.8",
                      "bounds": [[-3, -3, -3], [3, 3, 3]]})J"},
        ModelCase{"expression_every_function",
                  R"J({"type": "expression",
                      "value": "sqrt(x^2 + 1) * exp(-y/a) + log(z^2 + 2) - sin(x*y) / cos(0.3*z) + tan(0.2*x) + abs(y - 5) + min(x, 4 - y) * max(z, -4) + pow(x^2 + 1, 0.5*z) - 2^(y/3) + pi/(1 + z^2)",
                      "params": {"a": 2.5},
                      "bounds": [[-1.5, -1.5, -1.5], [1.5, 1.5, 1.5]]})J"},
        ModelCase{"compiled_double_torus", R"J({"type": "double_torus"})J"},
        ModelCase{"compiled_capped_cylinder", R"J({"type": "capped_cylinder"})J"},
        ModelCase{"compiled_tanglecube", R"J({"type": "tanglecube"})J"}),
    [](const auto& info) { return info.param.name; });

}  // namespace
}  // namespace cdp
