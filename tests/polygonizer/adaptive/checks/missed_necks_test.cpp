// The search for necks a mesh stepped over (polygonizer/src/adaptive/missed_necks.h): its walks
// are bounded by the mesh's size, not by a constant a crowd of necks outnumbers, and the starts
// that bound leaves unwalked are counted; a neck capped at its waist is found though its core lies
// on the right side of the mesh.
#include <gtest/gtest.h>

#include "common/reference_meshes.h"
#include "common/test_fields.h"
#include "src/adaptive/missed_necks.h"

#include <cmath>
#include <numbers>
#include <vector>

namespace cdp::adaptive {
namespace {

TEST(MissedNecks, TheWalksGrowWithTheMeshAndTheStartsLeftUnwalkedAreCounted) {
  // cos x + cos y + cos z has a critical point at every (i, j, k) pi: 17^3 = 4,913 of them for
  // i, j, k in [-8, 8], more than the 4,096 walks a small mesh allows. One start a point, a
  // little off it and pointing at it, so that no start's target is another's.
  const auto field = test::field_from_json(R"J({"type": "expression", "value": "cos(x) + cos(y) + cos(z)",
                                               "bounds": [[-26.5, -26.5, -26.5], [26.5, 26.5, 26.5]]})J");
  std::vector<CriticalStart> starts;
  for (int i = -8; i <= 8; ++i)
    for (int j = -8; j <= 8; ++j)
      for (int k = -8; k <= 8; ++k) {
        const Vec3 c = std::numbers::pi * Vec3(i, j, k), off(0.01, 0.02, 0.03);
        starts.push_back({c + off, -off, 0.1});
      }
  // No critical point is thin at edges of 0.1 (the quadratic model reaches zero about 1.4 away),
  // so none is tested and any closed mesh will do; its vertices set the bound.
  const NeckSearch few = find_missed_necks(*field, icosphere(1), starts);
  EXPECT_EQ(few.walks, 4096u);
  EXPECT_EQ(few.unwalked, starts.size() - 4096);
  EXPECT_EQ(few.critical_points, 4096u);
  EXPECT_EQ(few.tested, 0u);
  const Mesh large = icosphere(6);  // 40,962 vertices: a bound of 10,240 walks
  ASSERT_GT(large.positions.size() / 4, starts.size());
  const NeckSearch all = find_missed_necks(*field, large, starts);
  EXPECT_EQ(all.walks, starts.size());
  EXPECT_EQ(all.unwalked, 0u);
  EXPECT_EQ(all.critical_points, starts.size());
}

TEST(MissedNecks, ANeckCappedAtItsWaistIsFoundByTheTwoSheetsAcrossItsAxisAndTheNearSideOfASurfaceIsNot) {
  // A neck of solid 0.02 wide along x (F < 0 inside; along x, F keeps its sign and grows).
  const auto field = test::field_from_json(R"J({"type": "expression", "value": "y*y + z*z - x*x - 0.0001",
                                               "bounds": [[-1, -1, -1], [1, 1, 1]]})J");
  const Vec3 off(0.001, 0.002, 0.003);
  const std::vector<CriticalStart> starts = {{off, -off, 0.1}};
  const auto join = [](Mesh a, const Mesh& b) {
    const int n = static_cast<int>(a.positions.size());
    a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
    for (const auto& t : b.triangles) a.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});
    return a;
  };
  // Two balls capping the neck 0.005 and 0.01 from its saddle: the saddle is inside the first,
  // on the side its value says, as it was on the crowd of 200 blobs (2e-5 from the cap there).
  const Mesh capped = join(icosphere(5, Vec3(-0.495, 0, 0), 0.5), icosphere(5, Vec3(0.51, 0, 0), 0.5));
  const NeckSearch found = find_missed_necks(*field, capped, starts);
  EXPECT_EQ(found.tested, 1u);
  ASSERT_EQ(found.missed.size(), 1u);
  EXPECT_EQ(found.capped, 1u);
  EXPECT_LT(found.missed[0].point.norm(), 1e-12);
  EXPECT_NEAR(found.missed[0].width, 0.02, 1e-9);
  // A tube round the axis (a long thin ellipsoid) is the neck meshed: nothing is missed.
  Mesh tube = icosphere(4);
  for (Vec3& p : tube.positions) p = p.cwiseProduct(Vec3(1, 0.012, 0.012));
  const NeckSearch kept = find_missed_necks(*field, tube, starts);
  EXPECT_EQ(kept.tested, 1u);
  EXPECT_TRUE(kept.missed.empty());
  EXPECT_EQ(kept.capped, 0u);
  // The same saddle with the solid running on towards +z (a cubic term that leaves F, its
  // gradient and Hessian at the saddle as they were): the near side of a surface, not a neck, as
  // on the horse MPU model at tolerance 1e-3, where a saddle 0.0002 under the surface has its axis
  // along it and the mesh's chords cross that axis. Not taken for a capped neck.
  const auto beneath = test::field_from_json(R"J({"type": "expression", "value": "y*y + z*z - x*x - 0.0001 - 100*z*z*z",
                                                 "bounds": [[-1, -1, -1], [1, 1, 1]]})J");
  const NeckSearch near_side = find_missed_necks(*beneath, capped, starts);
  EXPECT_EQ(near_side.tested, 1u);
  EXPECT_TRUE(near_side.missed.empty());
}

}  // namespace
}  // namespace cdp::adaptive
