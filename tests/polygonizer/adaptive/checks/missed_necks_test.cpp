// The search for necks a mesh stepped over (polygonizer/src/adaptive/missed_necks.h): its walks
// are bounded by the mesh's size, not by a constant a crowd of necks outnumbers, and the starts
// that bound leaves unwalked are counted.
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

}  // namespace
}  // namespace cdp::adaptive
