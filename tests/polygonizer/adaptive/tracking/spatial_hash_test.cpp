// The adaptive tracker's spatial hash (polygonizer/src/adaptive/spatial_hash.h): a crowded cell
// that splits loses no point, finds none twice, and keeps searches local.
#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <random>
#include <vector>

#include "src/adaptive/spatial_hash.h"

namespace {

using cdp::Vec3;
using cdp::adaptive::Crowding;
using cdp::adaptive::SpatialHash;

// Points in a unit box, a tenth of them spread over it and the rest crowded into a ball of
// radius 0.01 at its centre: with cells of 0.25, that ball lies in one cell.
std::vector<Vec3> crowded_points(int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(0, 1), ball(-0.01, 0.01);
  std::vector<Vec3> p;
  for (int i = 0; i < n; ++i) {
    if (i % 10 == 0) p.emplace_back(unit(rng), unit(rng), unit(rng));
    else p.emplace_back(0.6 + ball(rng), 0.6 + ball(rng), 0.6 + ball(rng));
  }
  return p;
}

bool in_box(const Vec3& x, const Vec3& lo, const Vec3& hi) {
  return (x.array() >= lo.array()).all() && (x.array() <= hi.array()).all();
}

TEST(AdaptiveSpatialHash, ACrowdedCellSplitsWithoutLosingPointsAndKeepsSearchesLocal) {
  std::mt19937 rng(7);
  const std::vector<Vec3> p = crowded_points(3000, rng);
  const auto position = [&](int id) -> const Vec3& { return p[static_cast<std::size_t>(id)]; };
  SpatialHash split(0.25, Crowding::split), kept(0.25);
  for (int i = 0; i < static_cast<int>(p.size()); ++i) {
    split.insert(i, p[static_cast<std::size_t>(i)], position);
    kept.insert(i, p[static_cast<std::size_t>(i)]);
  }
  // Every third point leaves again.
  std::vector<char> present(p.size(), 1);
  for (int i = 0; i < static_cast<int>(p.size()); i += 3) {
    split.remove(i, p[static_cast<std::size_t>(i)]);
    kept.remove(i, p[static_cast<std::size_t>(i)]);
    present[static_cast<std::size_t>(i)] = 0;
  }
  std::uniform_real_distribution<double> unit(0, 1), small(0.0005, 0.004);
  for (int q = 0; q < 200; ++q) {
    // Half the queries small, inside the crowd; half anywhere, of any size up to the box.
    const Vec3 c = q % 2 ? Vec3(0.6, 0.6, 0.6) + 0.01 * Vec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5)
                         : Vec3(unit(rng), unit(rng), unit(rng));
    const double r = q % 2 ? small(rng) : 0.5 * unit(rng);
    const Vec3 lo = c.array() - r, hi = c.array() + r;
    std::map<int, int> seen;
    split.for_each_near(c, r, [&](int id) { ++seen[id]; });
    for (std::size_t i = 0; i < p.size(); ++i) {
      const int id = static_cast<int>(i);
      if (present[i] && in_box(p[i], lo, hi)) {
        EXPECT_EQ(seen.count(id), 1u) << "query " << q << " lost point " << id;
      }
      if (!present[i]) {
        EXPECT_EQ(seen.count(id), 0u) << "query " << q << " found removed point " << id;
      }
    }
    for (const auto& [id, times] : seen) EXPECT_EQ(times, 1) << "query " << q << " point " << id;
  }
  // A query a tenth of the crowd wide looks at a few of its 1800 remaining points, not all.
  const std::uint64_t split_before = split.visits(), kept_before = kept.visits();
  split.for_each_near(Vec3(0.6, 0.6, 0.6), 0.001, [](int) {});
  kept.for_each_near(Vec3(0.6, 0.6, 0.6), 0.001, [](int) {});
  EXPECT_GT(kept.visits() - kept_before, 1500u);
  EXPECT_LT(split.visits() - split_before, 300u);
}

}  // namespace

namespace {

// A run's token (set_cancel) is polled while the table grows, the one long step of a large hash;
// a hash without one grows as before, and a token never cancelled changes nothing.
TEST(AdaptiveSpatialHash, GrowingPollsTheRunsCancelToken) {
  const auto fill = [](SpatialHash& hash, int from, int to) {
    for (int i = from; i < to; ++i) hash.insert(i, Vec3(i + 0.5, 0.5, 0.5));  // a cell each
  };
  const auto found = [](const SpatialHash& hash, int n) {  // the points found where they were put
    int count = 0;
    for (int i = 0; i < n; ++i) hash.for_each_near(Vec3(i + 0.5, 0.5, 0.5), 0.1, [&](int id) { count += id == i; });
    return count;
  };
  const cdp::CancelToken cancel;
  SpatialHash polled(1.0), plain(1.0);
  polled.set_cancel(cancel);
  // The first table has 64 slots, kept at most half full: the 33rd cell makes it grow.
  fill(polled, 0, 32);
  cancel.cancel();
  EXPECT_THROW(fill(polled, 32, 33), cdp::CancelledError);
  fill(plain, 0, 1000);
  EXPECT_EQ(found(plain, 1000), 1000);
  cancel.reset();
  SpatialHash uncancelled(1.0);
  uncancelled.set_cancel(cancel);
  fill(uncancelled, 0, 1000);
  EXPECT_EQ(found(uncancelled, 1000), 1000);
}

}  // namespace
