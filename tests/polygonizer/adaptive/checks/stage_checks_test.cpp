// The checks stage (polygonizer/src/adaptive/stage_checks.h) on meshes made by hand.
#include <gtest/gtest.h>

#include "src/adaptive/stage_checks.h"

#include <cdp/core/cancel.h>
#include <cdp/core/errors.h>

#include <string>

namespace cdp::adaptive {
namespace {

TEST(AdaptiveStages, TheChecksRefuseAnOpenMeshAndCountTheQualityBoundsMissed) {
  Mesh tetra;
  tetra.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tetra.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const CancelToken cancel;
  EXPECT_EQ(check_mesh(tetra, 1, true, 1, cancel), 1u);
  EXPECT_THROW(check_mesh(tetra, 2, true, 1, cancel), NoSurfaceError);  // one component from two seeds
  Mesh open = tetra;
  open.triangles.pop_back();
  try {
    check_mesh(open, 1, true, 1, cancel);
    ADD_FAILURE() << "no error";
  } catch (const NoSurfaceError& e) {
    EXPECT_NE(std::string(e.what()).find("3 boundary"), std::string::npos) << e.what();
  }
  // The tetrahedron's faces: three right isosceles triangles (45 degrees, edge ratio 1.41) and
  // one equilateral: none under 30 degrees, a mean edge ratio of 1.31 (over 1.25); triangles
  // beyond the tolerance are a bound missed too.
  EXPECT_EQ(missed_bounds(tetra, 0), 1);
  EXPECT_EQ(missed_bounds(tetra, 5), 2);
  Mesh sliver = tetra;
  sliver.positions[3] = {0.5, 0.5, 0.01};  // the faces at vertex 3 nearly flat: angles near 0
  EXPECT_EQ(missed_bounds(sliver, 0), 3);
  EXPECT_NEAR(min_angle_degrees(tetra), 45, 1e-9);
}

}  // namespace
}  // namespace cdp::adaptive
