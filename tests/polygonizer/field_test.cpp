// The batched field calls (values_gradients, gradients_hessians) give every model the numbers its
// single-point calls give and count evaluations as those would.
#include <gtest/gtest.h>

#include <cdp/core/field.h>
#include <cdp/core/models/compiled.h>
#include <cdp/core/models/level_shift.h>
#include <cdp/core/models/mpu.h>
#include <cdp/core/models/vis.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <thread>
#include <vector>

#include "common/same_bits.h"
#include "common/test_fields.h"
#include "polygonizer/oriented_point_sets.h"

namespace cdp {
namespace {

using test::same_bits;

std::vector<std::unique_ptr<Field>> models() {
  std::vector<std::unique_ptr<Field>> v;
  v.push_back(test::tanglecube());
  v.push_back(test::three_separate_blobs());
  v.push_back(std::make_unique<Torus>(Vec3(0.1, 0, 0), 1.0, 0.3));
  v.push_back(test::field_from_json(
      R"({"type": "expression", "value": "max(abs(x),max(abs(y),abs(z)))-1", "bounds": [[-1.5,-1.5,-1.5],[1.5,1.5,1.5]]})"));
  v.push_back(std::make_unique<Vis>(test::torus_points(16, 8), 0.03));
  MpuOptions o;
  o.max_error = 0.002;
  v.push_back(std::make_unique<Mpu>(test::sphere_points(400), o));
  return v;
}

TEST(FieldBatches, GiveTheSinglePointNumbersAndCountsForEveryModel) {
  std::mt19937 rng(2024);
  constexpr std::size_t kPoints = 200;
  for (const auto& field : models()) {
    SCOPED_TRACE(field->type_name());
    const Box box = field->bounds();
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<Vec3> p(kPoints);
    for (Vec3& x : p) x = box.min + box.size().cwiseProduct(Vec3(u(rng), u(rng), u(rng)));

    std::vector<double> v1(kPoints), h1v(kPoints);
    std::vector<Vec3> g1(kPoints), h1g(kPoints);
    std::vector<Mat3> h1(kPoints);
    field->reset_counts();
    for (std::size_t i = 0; i < kPoints; ++i) {
      v1[i] = field->value_gradient(p[i], g1[i]);
      h1v[i] = field->gradient_hessian(p[i], h1g[i], h1[i]);
    }
    const EvaluationCounts single = field->counts();

    std::vector<double> v2(kPoints), h2v(kPoints);
    std::vector<Vec3> g2(kPoints), h2g(kPoints);
    std::vector<Mat3> h2(kPoints);
    field->reset_counts();
    field->values_gradients(p.data(), v2.data(), g2.data(), kPoints);
    field->gradients_hessians(p.data(), h2v.data(), h2g.data(), h2.data(), kPoints);
    const EvaluationCounts batched = field->counts();

    EXPECT_EQ(batched.value, single.value);
    EXPECT_EQ(batched.value_gradient, single.value_gradient);
    EXPECT_EQ(batched.gradient_hessian, single.gradient_hessian);
    EXPECT_EQ(batched.value_gradient, kPoints);
    EXPECT_EQ(batched.gradient_hessian, kPoints);
    for (std::size_t i = 0; i < kPoints; ++i) {
      ASSERT_TRUE(same_bits(v1[i], v2[i]) && same_bits(g1[i], g2[i])) << "value_gradient at point " << i;
      ASSERT_TRUE(same_bits(h1v[i], h2v[i]) && same_bits(h1g[i], h2g[i]) && same_bits(h1[i], h2[i]))
          << "gradient_hessian at point " << i;
    }
  }
}

// evaluate_together: the three batched kinds in one evaluation, each point's numbers and the counts
// those of its own kind's batch, for every model and through a level shift (F - c).
TEST(FieldBatches, TogetherGiveEachKindsNumbersAndCounts) {
  std::mt19937 rng(2026);
  constexpr std::size_t kPlain = 5, kGradients = 7, kHessians = 11;
  for (const auto& model : models()) {
    const LevelShift shifted(*model, 0.125);
    for (const Field* field : {static_cast<const Field*>(model.get()), static_cast<const Field*>(&shifted)}) {
      SCOPED_TRACE(field->type_name() + (field == &shifted ? " - 0.125" : ""));
      const Box box = field->bounds();
      std::uniform_real_distribution<double> u(0, 1);
      std::vector<Vec3> p(kPlain + kGradients + kHessians);
      for (Vec3& x : p) x = box.min + box.size().cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
      const Vec3* pg = p.data() + kPlain;
      const Vec3* ph = pg + kGradients;

      std::vector<double> v(p.size()), w(p.size());
      std::vector<Vec3> g(p.size()), gw(p.size());
      std::vector<Mat3> h(kHessians), hw(kHessians);
      field->reset_counts();
      field->values(p.data(), w.data(), kPlain);
      field->values_gradients(pg, w.data() + kPlain, gw.data() + kPlain, kGradients);
      field->gradients_hessians(ph, w.data() + kPlain + kGradients, gw.data() + kPlain + kGradients, hw.data(), kHessians);
      const EvaluationCounts apart = field->counts();
      field->reset_counts();
      field->evaluate_together({p.data(), v.data(), nullptr, nullptr, kPlain},
                               {pg, v.data() + kPlain, g.data() + kPlain, nullptr, kGradients},
                               {ph, v.data() + kPlain + kGradients, g.data() + kPlain + kGradients, h.data(), kHessians});
      const EvaluationCounts together = field->counts();
      EXPECT_EQ(together.value, kPlain);
      EXPECT_EQ(together.value_gradient, kGradients);
      EXPECT_EQ(together.gradient_hessian, kHessians);
      EXPECT_EQ(together.total(), apart.total());
      for (std::size_t i = 0; i < p.size(); ++i) {
        ASSERT_TRUE(same_bits(v[i], w[i])) << "value at point " << i;
        if (i >= kPlain) {
          ASSERT_TRUE(same_bits(g[i], gw[i])) << "gradient at point " << i;
        }
      }
      for (std::size_t i = 0; i < kHessians; ++i) ASSERT_TRUE(same_bits(h[i], hw[i])) << "Hessian at point " << i;
      if (field == &shifted) {
        EXPECT_EQ(v[0], model->value(p[0]) - 0.125);
      }
    }
  }
}

TEST(FieldBatches, AnEmptyBatchEvaluatesAndCountsNothing) {
  const auto field = test::tanglecube();
  field->values_gradients(nullptr, nullptr, nullptr, 0);
  field->gradients_hessians(nullptr, nullptr, nullptr, nullptr, 0);
  field->evaluate_together({}, {}, {});
  EXPECT_EQ(field->counts().total(), 0u);
}

// Each thread counts in a slot of its own (EvaluationCounter): more threads than slots share
// them, and every evaluation of every thread is in the total, kind by kind.
TEST(FieldCounts, EveryThreadsEvaluationsAreCountedOnce) {
  const auto field = test::tanglecube();
  constexpr int kThreads = 11, kCalls = 2000;  // more threads than slots
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      Vec3 g;
      Mat3 h;
      for (int i = 0; i < kCalls; ++i) {
        const Vec3 p(0.001 * i, 0.1 * t, 0.3);
        field->value(p);
        field->value_gradient(p, g);
        if (i % 2 == 0) field->gradient_hessian(p, g, h);
      }
      std::vector<Vec3> points(3, Vec3(0.2, 0.1, 0.3));
      std::vector<double> values(3);
      field->values(points.data(), values.data(), 3);
    });
  for (auto& t : threads) t.join();
  const EvaluationCounts c = field->counts();
  EXPECT_EQ(c.value, std::uint64_t{kThreads} * (kCalls + 3));
  EXPECT_EQ(c.value_gradient, std::uint64_t{kThreads} * kCalls);
  EXPECT_EQ(c.gradient_hessian, std::uint64_t{kThreads} * kCalls / 2);
  field->reset_counts();
  EXPECT_EQ(field->counts().total(), 0u);
}

}  // namespace
}  // namespace cdp

namespace cdp {
namespace {

std::unique_ptr<Field> expression_field(const std::string& value) {
  return test::field_from_json(R"({"type": "expression", "value": ")" + value +
                               R"(", "bounds": [[-2,-2,-2],[2,2,2]]})");
}

// Field::smooth promises a regular zero set: claimed by the models whose gradient is continuous
// and nonzero on the surface, by compiled models whose authors say so, never by an expression.
TEST(FieldSmooth, ClaimedOnlyWhereNoCreaseCanHide) {
  EXPECT_TRUE(test::three_separate_blobs()->smooth());
  EXPECT_TRUE(Torus(Vec3::Zero(), 1.0, 0.3).smooth());
  EXPECT_TRUE(Vis(test::torus_points(16, 8), 0.03).smooth());
  MpuOptions o;
  o.max_error = 0.002;
  EXPECT_TRUE(Mpu(test::sphere_points(400), o).smooth());
  EXPECT_FALSE(test::tanglecube()->smooth());  // an expression: a polynomial may have a node
  const auto compiled = compiled_models();
  EXPECT_TRUE(compiled.at("tanglecube")()->smooth());
  EXPECT_TRUE(compiled.at("double_torus")()->smooth());
  EXPECT_FALSE(compiled.at("capped_cylinder")()->smooth());
  // Each of these can make a crease, a cusp or a node where the surface passes.
  for (const char* v : {"max(abs(x),max(abs(y),abs(z)))-1", "min(x,y)", "sqrt(x^2)-0.5", "x^0.5+y-1",
                        "x^2+y^2-z^2", "exp(-x^2)*sin(y)+cos(z)-0.5"})
    EXPECT_FALSE(expression_field(v)->smooth()) << v;
}

TEST(FieldLiveBranches, NameTheChoicesTheValueDependsOn) {
  // At (0.5, 0.1, 0) the max takes abs(x) - 1: the value depends on the max and abs(x), not on
  // abs(y), whose argument the max discards. The branch points told apart by how far their
  // switches lie: abs(x)'s 0.5, abs(y)'s 0.1, the max's (0.5 - 0.1) / sqrt(2).
  const auto field = expression_field("max(abs(x) - 1, abs(y) - 1)");
  const Vec3 p(0.5, 0.1, 0);
  Field::BranchRecord record;
  ASSERT_TRUE(field->branch_record(p, record));
  ASSERT_EQ(record.taken.size(), 3u);
  const auto which = [&](double distance) {
    for (std::size_t k = 0; k < 3; ++k)
      if (std::abs(record.distance[k] - distance) < 1e-12) return k;
    ADD_FAILURE() << "no branch point whose switch lies " << distance << " away";
    return std::size_t{0};
  };
  const std::size_t abs_x = which(0.5), abs_y = which(0.1), max = which(0.4 / std::sqrt(2.0));
  const std::optional<std::uint64_t> live = field->live_branches(p, record.taken);
  ASSERT_TRUE(live.has_value());
  EXPECT_TRUE(*live >> abs_x & 1u);
  EXPECT_TRUE(*live >> max & 1u);
  EXPECT_FALSE(*live >> abs_y & 1u);
  // A model without branch points cannot tell.
  EXPECT_FALSE(Torus(Vec3::Zero(), 1.0, 0.3).live_branches(p, {}).has_value());
}

}  // namespace
}  // namespace cdp
