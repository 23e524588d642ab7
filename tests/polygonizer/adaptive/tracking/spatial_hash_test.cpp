// The adaptive tracker's spatial hash (polygonizer/src/adaptive/spatial_hash.h): a crowded cell
// that splits loses no point, finds none twice, and keeps searches local.
#include <gtest/gtest.h>

#include <algorithm>
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

namespace {

// Distance from x to the segment a-b.
double to_segment(const Vec3& x, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const double t = std::clamp((x - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (a + t * d - x).norm();
}

// The front hash's use of widen_reach: each point has a length (its front edge's), most short,
// a few long; a search asks for the first point, in the hash's order, within its own length of a
// segment, in a box widened by the longest length. Passing over the cells too far for their
// longest length must give the same first point, every time, while looking at fewer points; a
// cell that was emptied forgets the long lengths it held.
TEST(AdaptiveSpatialHash, PassingOverFarCellsByTheirReachKeepsEveryAnswer) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 4), shortish(0.01, 0.05), longish(0.5, 1.5);
  const int n = 6000;
  std::vector<Vec3> p;
  std::vector<double> length;
  SpatialHash plain(0.25), reaching(0.25);
  for (int i = 0; i < n; ++i) {
    p.emplace_back(unit(rng), unit(rng), 0.1 * unit(rng));  // a thick sheet, as fronts lie on a surface
    length.push_back(i % 200 == 0 ? longish(rng) : shortish(rng));
    plain.insert(i, p.back());
    reaching.insert(i, p.back());
    reaching.widen_reach(p.back(), length.back());
  }
  // A tenth of the points leave, the long ones among them, and come back, half of the long ones
  // short: their cells keep the long reach unless they emptied (a bound still).
  for (int i = 0; i < n; i += 10) {
    plain.remove(i, p[static_cast<std::size_t>(i)]);
    reaching.remove(i, p[static_cast<std::size_t>(i)]);
  }
  for (int i = 0; i < n; i += 10) {
    if (i % 400 != 0) length[static_cast<std::size_t>(i)] = shortish(rng);
    plain.insert(i, p[static_cast<std::size_t>(i)]);
    reaching.insert(i, p[static_cast<std::size_t>(i)]);
    reaching.widen_reach(p[static_cast<std::size_t>(i)], length[static_cast<std::size_t>(i)]);
  }
  const double longest = *std::max_element(length.begin(), length.end());
  std::uniform_real_distribution<double> step(-0.04, 0.04);
  int found = 0;
  std::uint64_t plain_visits = 0, reaching_visits = 0;
  for (int q = 0; q < 400; ++q) {
    const Vec3 a(unit(rng), unit(rng), 0.1 * unit(rng)), b = a + Vec3(step(rng), step(rng), 0.2 * step(rng));
    const Vec3 mid = 0.5 * (a + b);
    const double r = 0.5 * (b - a).norm() + longest;
    const Vec3 lo = mid.array() - r, hi = mid.array() + r;
    const auto near = [&](int id) {
      const auto i = static_cast<std::size_t>(id);
      return to_segment(p[i], a, b) <= length[i];
    };
    const auto far = [&](const Vec3& cell_lo, const Vec3& cell_hi, double reach) {
      const Vec3 seg_lo = a.cwiseMin(b), seg_hi = a.cwiseMax(b);
      return (cell_lo - seg_hi).cwiseMax(seg_lo - cell_hi).cwiseMax(0.0).norm() > reach;
    };
    int first_plain = -1, first_reaching = -1;
    const std::uint64_t plain_before = plain.visits(), reaching_before = reaching.visits();
    plain.any_in(lo, hi, [&](int id) { return near(id) && (first_plain = id, true); });
    reaching.any_in(lo, hi, far, [&](int id) { return near(id) && (first_reaching = id, true); });
    plain_visits += plain.visits() - plain_before;
    reaching_visits += reaching.visits() - reaching_before;
    EXPECT_EQ(first_reaching, first_plain) << "query " << q;
    found += first_plain >= 0;
    // The same through a gathered box around the query's.
    SpatialHash::Gathered g;
    reaching.gather(lo.array() - 0.3, hi.array() + 0.3, g);
    int first_gathered = -1;
    reaching.any_in(g, lo, hi, far, [&](int id) { return near(id) && (first_gathered = id, true); });
    EXPECT_EQ(first_gathered, first_plain) << "query " << q;
  }
  EXPECT_GT(found, 50);  // the comparison means something: many queries find a point
  EXPECT_LT(reaching_visits, plain_visits / 2);

  // Emptied cells forget: every point leaves and comes back short; a query that the long
  // lengths once reached now looks at no cell beyond the short lengths' reach. Its box spans
  // more cells than are occupied, so the occupied cells are the ones asked.
  for (int i = 0; i < n; ++i) reaching.remove(i, p[static_cast<std::size_t>(i)]);
  SpatialHash fresh(0.25);
  for (int i = 0; i < n; ++i) {
    reaching.insert(i, p[static_cast<std::size_t>(i)]);
    reaching.widen_reach(p[static_cast<std::size_t>(i)], 0.02);
    fresh.insert(i, p[static_cast<std::size_t>(i)]);
    fresh.widen_reach(p[static_cast<std::size_t>(i)], 0.02);
  }
  const Vec3 a(2, 2, 0.2), b(2.02, 2, 0.2);
  const auto never = [](int) { return false; };
  const auto far = [&](const Vec3& cell_lo, const Vec3& cell_hi, double reach) {
    return (cell_lo - a.cwiseMax(b)).cwiseMax(a.cwiseMin(b) - cell_hi).cwiseMax(0.0).norm() > reach;
  };
  const std::uint64_t before = reaching.visits(), fresh_before = fresh.visits();
  reaching.any_in(Vec3(0.5, 0.5, -1), Vec3(3.5, 3.5, 1.5), far, never);
  fresh.any_in(Vec3(0.5, 0.5, -1), Vec3(3.5, 3.5, 1.5), far, never);
  EXPECT_EQ(reaching.visits() - before, fresh.visits() - fresh_before);
  EXPECT_LT(reaching.visits() - before, 200u);
}

}  // namespace
