// Seeds land on every component; fields without a usable surface are reported as such.
#include <gtest/gtest.h>

#include <cdp/core/errors.h>
#include <cdp/core/surface_seeds.h>

#include <set>

#include "common/test_fields.h"

namespace cdp {
namespace {

std::string no_surface_message(const std::string& json) {
  try {
    find_surface_seeds(*test::field_from_json(json));
  } catch (const NoSurfaceError& e) {
    return e.what();
  }
  return "";
}

TEST(SurfaceSeeds, OneSeedOnEachOfThreeSeparateBlobs) {
  const auto f = test::three_separate_blobs();
  const auto seeds = find_surface_seeds(*f);
  ASSERT_EQ(seeds.size(), 3u);
  std::set<int> clusters;
  for (const auto& s : seeds) {
    EXPECT_LT(std::abs(f->value(s.point)) / f->gradient(s.point).norm(), 1e-9);
    clusters.insert(s.cluster);
  }
  EXPECT_EQ(clusters, (std::set<int>{0, 1, 2}));
}

TEST(SurfaceSeeds, CrossingsCoverEveryComponentAndAreDeterministic) {
  const auto f = test::tanglecube();
  const auto a = find_surface_crossings(*f);
  const auto b = find_surface_crossings(*f);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].point, b[i].point);
    EXPECT_EQ(a[i].cluster, b[i].cluster);
  }
  int max_cluster = 0;
  for (const auto& c : a) max_cluster = std::max(max_cluster, c.cluster);
  EXPECT_EQ(max_cluster, 0) << "the tanglecube is one connected surface";
  EXPECT_GT(a.size(), 100u);
}

TEST(SurfaceSeeds, FieldWithoutZeroCrossingIsReported) {
  const std::string msg =
      no_surface_message(R"({"type": "expression", "value": "x^2 + y^2 + z^2 + 1", "bounds": [[-1,-1,-1],[1,1,1]]})");
  EXPECT_NE(msg.find("no zero crossing"), std::string::npos) << msg;
  EXPECT_NE(msg.find("positive everywhere"), std::string::npos) << msg;
}

TEST(SurfaceSeeds, SurfaceLeavingTheBoxIsReported) {
  const std::string msg = no_surface_message(R"({"type": "sphere", "radius": 1, "bounds": [[-0.5,-2,-2],[2,2,2]]})");
  EXPECT_NE(msg.find("the surface leaves the box"), std::string::npos) << msg;
}

TEST(SurfaceSeeds, NaNFieldIsReported) {
  const std::string msg =
      no_surface_message(R"({"type": "expression", "value": "sqrt(x) + y", "bounds": [[-1,-1,-1],[1,1,1]]})");
  EXPECT_NE(msg.find("not finite"), std::string::npos) << msg;
}

TEST(SurfaceSeeds, TripleRootWithVanishingGradientStillGivesSeedsOnTheSurface) {
  // The gradient of (|x|^2 - 1)^3 vanishes on the surface; bisection along the grid edge brings
  // the point close enough that the projection accepts it without dividing by a zero gradient.
  const auto f = test::field_from_json(
      R"({"type": "expression", "value": "(x^2 + y^2 + z^2 - 1)^3", "bounds": [[-2,-2,-2],[2,2,2]]})");
  const auto seeds = find_surface_seeds(*f);
  ASSERT_EQ(seeds.size(), 1u);
  EXPECT_NEAR(seeds[0].point.norm(), 1.0, 1e-6);
}

}  // namespace
}  // namespace cdp
