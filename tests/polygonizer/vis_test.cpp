// Variational implicit surfaces: interpolation, reproduction of known surfaces, exact
// derivatives, the vectorized kernels against the scalar reference, and bad input.
#include <gtest/gtest.h>

#include <cdp/core/errors.h>
#include <cdp/core/models/vis.h>
#include <cdp/io/field_factory.h>

#include <random>
#include <vector>

#include "../../polygonizer/src/helper_thread.h"
#include "../../polygonizer/src/parallel.h"
#include "common/test_fields.h"
#include "polygonizer/oriented_point_sets.h"

namespace cdp {
namespace {

using test::first_order_distance;

TEST(Vis, InterpolatesItsConstraints) {
  const Vis vis(test::sphere_points(150), 0.02);
  const VisSolveInfo& info = vis.solve_info();
  EXPECT_EQ(info.constraints, 300u);
  EXPECT_EQ(info.unknowns, 304u);
  EXPECT_LT(info.interpolation_residual, 1e-9);
  EXPECT_LT(info.polynomial_residual, 1e-9);
  EXPECT_GT(info.rcond, 0.0);
  ASSERT_EQ(vis.centres().size(), 300u);
  for (std::size_t i = 0; i < vis.centres().size(); ++i)
    EXPECT_NEAR(vis.value(vis.centres()[i]), vis.constraint_values()[i], 1e-9 * 0.02) << i;
  // Half of the constraints are zeros on the surface, half the offset outside.
  EXPECT_EQ(std::count(vis.constraint_values().begin(), vis.constraint_values().end(), 0.0), 150);
  EXPECT_EQ(std::count(vis.constraint_values().begin(), vis.constraint_values().end(), 0.02), 150);
}

TEST(Vis, ReproducesASphere) {
  const Vis vis(test::sphere_points(200), 0.02);
  // Inside negative, outside positive.
  EXPECT_LT(vis.value(Vec3::Zero()), 0.0);
  EXPECT_GT(vis.value(Vec3(1.5, 0.2, 0.1)), 0.0);
  // Stated deviation: within 1e-4 of the radius anywhere on the sphere (200 points; measured 2e-6).
  const OrientedPoints dense = test::sphere_points(2000);
  double worst = 0;
  for (const Vec3& p : dense.positions) worst = std::max(worst, first_order_distance(vis, p));
  RecordProperty("max_deviation", std::to_string(worst));
  EXPECT_LT(worst, 1e-4);
  // The box holds the sphere with a margin, and the field is positive on its corners.
  EXPECT_TRUE(vis.bounds().contains(Vec3(1.05, 0, 0)));
  EXPECT_GT(vis.value(vis.bounds().min), 0.0);
  EXPECT_GT(vis.value(vis.bounds().max), 0.0);
}

TEST(Vis, ReproducesATorus) {
  const Vis vis(test::torus_points(32, 14), 0.02);
  EXPECT_LT(vis.value(Vec3(1, 0, 0)), 0.0);    // inside the tube
  EXPECT_GT(vis.value(Vec3(0, 0, 0)), 0.0);    // the hole
  // Stated deviation: within 2e-4 (0.05% of the tube radius) off the sample grid (measured 1.2e-5).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(0, 2 * M_PI);
  double worst = 0;
  for (int i = 0; i < 500; ++i) {
    const double u = angle(rng), v = angle(rng);
    const Vec3 n(std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v));
    const Vec3 p = Vec3(std::cos(u), std::sin(u), 0.0) + 0.4 * n;
    worst = std::max(worst, first_order_distance(vis, p));
  }
  RecordProperty("max_deviation", std::to_string(worst));
  EXPECT_LT(worst, 2e-4);
}

TEST(Vis, DerivativesMatchFiniteDifferencesAndTheScalarReference) {
  const Vis vis(test::torus_points(20, 10), 0.03);
  const Box box = vis.bounds();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double h = 1e-5;
  std::vector<Vec3> batch;
  for (int trial = 0; trial < 40; ++trial) {
    const Vec3 p = box.min + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(box.size());
    batch.push_back(p);
    Vec3 g, g2;
    Mat3 H;
    const double v0 = vis.value(p);
    EXPECT_EQ(v0, vis.value_gradient(p, g));  // one kernel: the same bits
    EXPECT_EQ(v0, vis.gradient_hessian(p, g2, H));
    EXPECT_EQ(g, g2);
    const double scale = std::max(1.0, g.norm());
    for (int a = 0; a < 3; ++a) {
      const Vec3 e = h * Vec3::Unit(a);
      const double fd = (vis.value(p + e) - vis.value(p - e)) / (2 * h);
      EXPECT_NEAR(g[a], fd, 1e-6 * scale) << "gradient " << a << " at " << p.transpose();
      Vec3 gp, gm;
      vis.value_gradient(p + e, gp);
      vis.value_gradient(p - e, gm);
      const Vec3 hfd = (gp - gm) / (2 * h);
      for (int b = 0; b < 3; ++b)
        EXPECT_NEAR(H(b, a), hfd[b], 1e-5 * std::max(1.0, H.norm())) << "hessian " << a << b;
    }
    EXPECT_TRUE(H.isApprox(H.transpose(), 1e-14));
    // The scalar loop sums in another order: equal to rounding.
    Vec3 gs, gs2;
    Mat3 Hs;
    EXPECT_NEAR(vis.value_scalar(p), v0, 1e-10 * scale);
    EXPECT_NEAR(vis.value_gradient_scalar(p, gs), v0, 1e-10 * scale);
    EXPECT_NEAR(vis.gradient_hessian_scalar(p, gs2, Hs), v0, 1e-10 * scale);
    EXPECT_LT((gs - g).norm(), 1e-10 * scale);
    EXPECT_LT((gs2 - g).norm(), 1e-10 * scale);
    EXPECT_LT((Hs - H).norm(), 1e-10 * std::max(1.0, H.norm()));
  }
  // The batch gives the single values bit for bit, and counts as many value evaluations.
  vis.reset_counts();
  std::vector<double> out(batch.size());
  vis.values(batch.data(), out.data(), batch.size());
  EXPECT_EQ(vis.counts().value, batch.size());
  for (std::size_t i = 0; i < batch.size(); ++i) EXPECT_EQ(out[i], vis.value(batch[i]));
  // Exactly at a centre the Hessian is finite (the r^3 kernel's Hessian vanishes there).
  Vec3 g;
  Mat3 H;
  vis.gradient_hessian(vis.centres()[3], g, H);
  EXPECT_TRUE(H.allFinite());
}

// With a helper thread lent (helper_thread.h), evaluations over enough centres run half their
// lanes on it: the same bits as without, and the helper does run them.
TEST(Vis, AHelperThreadGivesTheSameBits) {
  Vis vis(test::sphere_points(150), 0.02);
  vis.set_split_centres(vis.num_centres(), vis.num_centres());  // both split, on 300 centres
  const Box box = vis.bounds();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> at{vis.centres()[7]};  // on a centre: the Hessian's select branch
  for (int i = 0; i < 200; ++i) at.push_back(box.min + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(box.size()));
  struct Values {
    double v, vg, gh;
    Vec3 g, g2;
    Mat3 h;
  };
  const auto evaluate = [&] {
    std::vector<Values> out(at.size());
    for (std::size_t i = 0; i < at.size(); ++i) {
      out[i].v = vis.value(at[i]);
      out[i].vg = vis.value_gradient(at[i], out[i].g);
      out[i].gh = vis.gradient_hessian(at[i], out[i].g2, out[i].h);
    }
    return out;
  };
  const std::vector<Values> alone = evaluate();
  const detail::LendHelper lend(2);
  if (detail::available_processors() < 2) GTEST_SKIP() << "one processor: no helper is lent";
  ASSERT_NE(detail::lent_helper(), nullptr);
  const std::vector<Values> helped = evaluate();
  EXPECT_EQ(detail::lent_helper()->tasks_run(), 2 * at.size());
  for (std::size_t i = 0; i < at.size(); ++i) {
    EXPECT_EQ(helped[i].v, alone[i].v) << i;
    EXPECT_EQ(helped[i].vg, alone[i].vg) << i;
    EXPECT_EQ(helped[i].gh, alone[i].gh) << i;
    EXPECT_EQ(helped[i].g, alone[i].g) << i;
    EXPECT_EQ(helped[i].g2, alone[i].g2) << i;
    EXPECT_EQ(helped[i].h, alone[i].h) << i;
    EXPECT_EQ(helped[i].vg, helped[i].v) << i;  // one kernel, whichever thread sums which lanes
    EXPECT_EQ(helped[i].g, helped[i].g2) << i;
  }
}

TEST(Vis, ConstraintSpacingIsTheClosestPairOfDataPoints) {
  const OrientedPoints pts = test::torus_points(12, 6);
  const Vis vis(pts, 0.01);
  double closest = HUGE_VAL;
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (std::size_t j = i + 1; j < pts.size(); ++j)
      closest = std::min(closest, (pts.positions[i] - pts.positions[j]).norm());
  ASSERT_TRUE(vis.constraint_spacing());
  EXPECT_DOUBLE_EQ(*vis.constraint_spacing(), closest);
  EXPECT_FALSE(vis.lipschitz_bound());
}

TEST(Vis, BadInputIsAnError) {
  // Too few points.
  EXPECT_THROW(Vis(test::sphere_points(3), 0.01), InvalidInputError);
  // A repeated point: singular system.
  OrientedPoints dup = test::sphere_points(30);
  dup.positions.push_back(dup.positions[4]);
  dup.normals.push_back(dup.normals[4]);
  try {
    Vis v(dup, 0.01, "dup");
    FAIL() << "no error";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("coincide"), std::string::npos) << e.what();
  }
  // Points and normals in one plane: no unique linear part.
  OrientedPoints flat;
  for (int i = 0; i < 12; ++i) {
    const double a = 2 * M_PI * i / 12;
    flat.positions.emplace_back(std::cos(a), std::sin(a), 0.0);
    flat.normals.emplace_back(std::cos(a), std::sin(a), 0.0);
  }
  try {
    Vis v(flat, 0.01, "flat");
    FAIL() << "no error";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("singular"), std::string::npos) << e.what();
  }
  // An offset that crosses the surface: a spherical cavity (normals inward) of radius 0.1 with
  // offset 0.15 puts offset points nearer to the far wall than to their own points.
  OrientedPoints cavity = test::sphere_points(40, 0.1);
  for (Vec3& n : cavity.normals) n = -n;
  EXPECT_NO_THROW(Vis(cavity, 0.02));
  EXPECT_THROW(Vis(cavity, 0.15), InvalidInputError);
  // A non-unit normal.
  OrientedPoints bad = test::sphere_points(20);
  bad.normals[2] *= 2;
  EXPECT_THROW(Vis(bad, 0.01), InvalidInputError);
  // Constraint counts.
  const OrientedPoints sphere = test::sphere_points(50);
  EXPECT_THROW(make_vis(sphere, {101, 0.01}, "odd"), InvalidInputError);
  EXPECT_THROW(make_vis(sphere, {102, 0.01}, "too many"), InvalidInputError);
  EXPECT_THROW(make_vis(sphere, {100, 0.2}, "offset"), InvalidInputError);
  EXPECT_EQ(make_vis(sphere, {100, 0.01}, "all")->solve_info().constraints, 100u);
}

TEST(Vis, LoadsFromJsonRelativeToTheFile) {
  const std::string dir = std::string(CDP_SOURCE_DIR) + "/experiments/fields/";
  const auto field = load_field(dir + "bunny_vis800.json");
  ASSERT_EQ(field->type_name(), "vis");
  const auto& vis = dynamic_cast<const Vis&>(*field);
  EXPECT_EQ(vis.solve_info().constraints, 800u);
  EXPECT_LT(vis.solve_info().interpolation_residual, kVisMaxResidual);
  EXPECT_GT(*vis.constraint_spacing(), 0.0);
  EXPECT_TRUE(vis.bounds().valid());
}

TEST(Vis, JsonErrorsNameTheProblem) {
  const std::string base = std::string(CDP_SOURCE_DIR) + "/experiments/fields";
  auto error_of = [&](const std::string& text) -> std::string {
    try {
      make_field(nlohmann::json::parse(text), "t.json", base);
    } catch (const InvalidInputError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of(R"({"type": "vis", "points": "nope.ply"})").find("nope.ply"), std::string::npos);
  EXPECT_NE(error_of(R"({"type": "vis", "points": "../../data/bunny.ply", "constraints": 801})")
                .find("constraints"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"type": "vis", "points": "../../data/bunny.ply", "constraints": 200000})")
                .find("the scan has"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"type": "vis", "points": "../../data/bunny.ply", "normal_ofset": 0.01})")
                .find("normal_ofset"),
            std::string::npos);
}

}  // namespace
}  // namespace cdp
