// The search for necks a mesh stepped over (polygonizer/src/adaptive/missed_necks.h): its walks
// are bounded by the mesh's size, not by a constant a crowd of necks outnumbers, and the starts
// that bound leaves unwalked are counted; a neck capped at its waist is found though its core lies
// on the right side of the mesh; a distance field's neck or tunnel, whose core is a kink and no
// saddle, is found along the caps across it, and a tip cut off is not taken for one.
#include <gtest/gtest.h>

#include "common/reference_meshes.h"
#include "common/test_fields.h"
#include "src/adaptive/missed_necks.h"

#include <Eigen/Geometry>

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

// The mesh's vertex normals as the tracker sets them: F's unit gradient.
void set_field_normals(const Field& field, Mesh& mesh) {
  mesh.normals.clear();
  for (const Vec3& p : mesh.positions) {
    Vec3 g;
    field.value_gradient(p, g);
    mesh.normals.push_back(g.normalized());
  }
}

// A ball of radius 0.45 about `center` whose triangles are those of icosphere(4), turned so that
// one of them has its middle on the x axis: a cap across a rod along x, as a front leaves it.
Mesh ball_capping_x(const Vec3& center) {
  Mesh m = icosphere(4);
  Vec3 nearest = Vec3::Zero();
  for (const auto& t : m.triangles) {
    const Vec3 c = (m.positions[static_cast<std::size_t>(t[0])] + m.positions[static_cast<std::size_t>(t[1])] +
                    m.positions[static_cast<std::size_t>(t[2])]).normalized();
    if (c.x() > nearest.x()) nearest = c;
  }
  const Mat3 turn = Eigen::Quaterniond::FromTwoVectors(nearest, Vec3::UnitX()).toRotationMatrix();
  for (Vec3& p : m.positions) p = center + 0.45 * (turn * p);
  return m;
}

Mesh joined(Mesh a, const Mesh& b) {
  const int n = static_cast<int>(a.positions.size());
  a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
  for (const auto& t : b.triangles) a.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});
  return a;
}

TEST(MissedNecks, ADistanceFieldsNeckOrTunnelIsFoundAlongTheCapsAcrossItAndATipCutOffIsNot) {
  // A rod of solid 0.02 wide along x from -0.7 to 0.7, as a distance (a capsule): its core is a
  // kink of F (grad F has length 1 all round it), no saddle, so no walk settles there and there
  // are no starts.
  const auto rod = test::field_from_json(R"J({"type": "expression",
      "value": "hypot(x - clamp(x, -0.7, 0.7), y, z) - 0.01", "bounds": [[-1, -1, -1], [1, 1, 1]]})J");
  // Two balls that cut it 0.1 apart, a triangle of each across it: their triangles turn about a
  // right angle from the rod's normals at their corners (caps).
  Mesh cut = joined(ball_capping_x(Vec3(-0.5, 0, 0)), ball_capping_x(Vec3(0.5, 0, 0)));
  set_field_normals(*rod, cut);
  const NeckSearch found = find_missed_necks(*rod, cut, {});
  EXPECT_EQ(found.walks, 0u);
  EXPECT_GT(found.caps, 0u);
  ASSERT_FALSE(found.missed.empty());
  EXPECT_TRUE(found.missed[0].kinked);
  EXPECT_LT(found.missed[0].value, 0);  // a neck of solid cut
  EXPECT_NEAR(found.missed[0].width, 0.02, 1e-3);
  EXPECT_LT(std::hypot(found.missed[0].point.y(), found.missed[0].point.z()), 1e-3);
  EXPECT_LT(std::abs(found.missed[0].point.x()), 0.05 + 1e-9);

  // The same as a tunnel of void in the solid (F > 0 inside it), closed by the one ball that
  // the mesh encloses it in.
  const auto tunnel = test::field_from_json(R"J({"type": "expression", "value": "0.01 - hypot(y, z)",
                                                "bounds": [[-1, -1, -1], [1, 1, 1]]})J");
  Mesh closed = ball_capping_x(Vec3::Zero());
  set_field_normals(*tunnel, closed);
  const NeckSearch shut = find_missed_necks(*tunnel, closed, {});
  ASSERT_FALSE(shut.missed.empty());
  EXPECT_TRUE(shut.missed[0].kinked);
  EXPECT_GT(shut.missed[0].value, 0);
  EXPECT_NEAR(shut.missed[0].width, 0.02, 1e-3);

  // A rod that ends at x = 0, the ball cutting it off 0.05 before its tip:
  // the solid outside the mesh ends within the walk along its core, a tip and no neck.
  const auto capsule = test::field_from_json(R"J({"type": "expression",
      "value": "hypot(x - clamp(x, -0.7, 0), y, z) - 0.01", "bounds": [[-1, -1, -1], [1, 1, 1]]})J");
  Mesh tip = ball_capping_x(Vec3(-0.5, 0, 0));
  set_field_normals(*capsule, tip);
  const NeckSearch tip_search = find_missed_necks(*capsule, tip, {});
  EXPECT_GT(tip_search.caps, 0u);
  EXPECT_TRUE(tip_search.missed.empty());
}

}  // namespace
}  // namespace cdp::adaptive
