// Checks raytrace/field_cost.h: which points are timed, how often each kind is evaluated, and
// that the price list is positive (timings themselves are not asserted: the machine is shared).
#include <gtest/gtest.h>

#include <cdp/core/models/analytic.h>
#include <cdp/raytrace/field_cost.h>

#include "common/reference_meshes.h"

namespace cdp {
namespace {

TEST(FieldCost, EvaluatesEachKindAtStridedVerticesTheGivenNumberOfTimes) {
  const Sphere sphere(Vec3::Zero(), 1.0);
  const Mesh mesh = icosphere(4);  // 2562 vertices: stride 3 gives 854 points for at most 1000
  ASSERT_EQ(mesh.positions.size(), 2562u);
  FieldCostOptions o;
  o.repetitions = 2;
  const EvaluationCounts before = sphere.counts();
  const FieldCost cost = measure_field_cost(sphere, mesh, o);
  const EvaluationCounts made = sphere.counts() - before;
  EXPECT_EQ(cost.points, 854u);
  EXPECT_EQ(made.value, 2u * 854u);
  EXPECT_EQ(made.value_gradient, 2u * 854u);
  EXPECT_EQ(made.gradient_hessian, 2u * 854u);
  EXPECT_GT(cost.value_seconds, 0);
  EXPECT_GT(cost.value_gradient_seconds, 0);
  EXPECT_GT(cost.gradient_hessian_seconds, 0);
}

TEST(FieldCost, NoVerticesCostNothing) {
  const Sphere sphere(Vec3::Zero(), 1.0);
  const FieldCost cost = measure_field_cost(sphere, Mesh{});
  EXPECT_EQ(cost.points, 0u);
  EXPECT_EQ(sphere.counts().total(), 0u);
  EXPECT_EQ(cost.gradient_hessian_seconds, 0);
}

}  // namespace
}  // namespace cdp
