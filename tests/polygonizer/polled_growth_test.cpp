// grow_apart (polygonizer/src/polled_growth.h): arrays that fill up together are grown one by
// one, each as push_back would grow it, with a cancel poll after each one moved.
#include "src/polled_growth.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <vector>

namespace cdp::detail {
namespace {

TEST(PolledGrowth, FullArraysDoubleAsPushBackWouldAndKeepTheirElements) {
  std::vector<double> a{1, 2, 3, 4};
  std::vector<int> b{5, 6, 7, 8};
  a.shrink_to_fit();
  b.shrink_to_fit();
  std::vector<double> pushed = a;  // how push_back grows the same array
  pushed.shrink_to_fit();
  pushed.push_back(0);
  const CancelToken cancel;
  grow_apart(cancel, "test", 1, a, b);
  EXPECT_EQ(a.capacity(), pushed.capacity());
  EXPECT_EQ(b.capacity(), 8u);
  EXPECT_EQ(a, (std::vector<double>{1, 2, 3, 4}));
  EXPECT_EQ(b, (std::vector<int>{5, 6, 7, 8}));
  // Room for more than the doubling gives: at least what is asked.
  grow_apart(cancel, "test", 100, a);
  EXPECT_GE(a.capacity(), a.size() + 100);
}

TEST(PolledGrowth, ArraysWithRoomAreLeftAlone) {
  std::vector<int> a;
  a.reserve(16);
  a.assign({1, 2, 3});
  const int* data = a.data();
  const CancelToken cancel;
  cancel.cancel();  // nothing moves, so nothing polls
  EXPECT_NO_THROW(grow_apart(cancel, "test", 2, a));
  EXPECT_EQ(a.data(), data);
  EXPECT_EQ(a.capacity(), 16u);
}

TEST(PolledGrowth, ACancelledRunStopsAfterTheFirstArrayItMoves) {
  std::vector<int> a{1, 2}, b{3, 4};
  a.shrink_to_fit();
  b.shrink_to_fit();
  const CancelToken cancel;
  cancel.cancel();
  try {
    grow_apart(cancel, "adaptive", 1, a, b);
    FAIL() << "expected CancelledError";
  } catch (const CancelledError& e) {
    EXPECT_STREQ(e.what(), "adaptive: cancelled");
  }
  EXPECT_GE(a.capacity(), 3u);  // moved, then polled
  EXPECT_EQ(b.capacity(), 2u);  // not reached
  EXPECT_EQ(a, (std::vector<int>{1, 2}));
}

TEST(PolledGrowth, APolledVectorHoldsItsCopiesAndPollsBeforeEachBlock) {
  const std::size_t n = 2 * kPolledFill + 5;
  int polls = 0;
  const std::vector<int> v = polled_vector(n, [&] { ++polls; }, 7);
  EXPECT_EQ(v, std::vector<int>(n, 7));
  EXPECT_EQ(polls, 3);
  EXPECT_TRUE(polled_vector<int>(0, [&] { ++polls; }).empty());
  EXPECT_EQ(polls, 3);
}

}  // namespace
}  // namespace cdp::detail
