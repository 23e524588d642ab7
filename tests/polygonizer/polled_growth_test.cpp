// polled_growth.h: arrays are grown (grow_apart, each as push_back would grow it), filled
// (polled_vector) and, as arrays of buffers, freed (polled_clear) a block at a time with a
// cancel poll before each block.
#include "src/polled_growth.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <utility>
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

TEST(PolledGrowth, ACancelledGrowthLeavesTheArraysAsTheyWere) {
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
  EXPECT_EQ(a, (std::vector<int>{1, 2}));
  EXPECT_EQ(a.capacity(), 2u);
  EXPECT_EQ(b.capacity(), 2u);  // not reached
}

// An element whose moves cancel a token once a given number of them were made: a cancel()
// arriving from another thread while a growth moves its blocks.
struct CancellingElement {
  static inline const CancelToken* token = nullptr;
  static inline std::size_t moves = 0, cancel_at = 0;
  std::vector<int> value;
  explicit CancellingElement(std::vector<int> v) : value(std::move(v)) {}
  CancellingElement(const CancellingElement&) = default;
  CancellingElement(CancellingElement&& o) noexcept : value(std::move(o.value)) {
    if (++moves == cancel_at) token->cancel();
  }
  CancellingElement& operator=(CancellingElement&& o) noexcept = default;
  bool operator==(const CancellingElement&) const = default;
};

TEST(PolledGrowth, ALongArrayMovesABlockBetweenPollsAndGetsItsElementsBackWhenCancelled) {
  std::vector<CancellingElement> a(2 * kPolledFill + 1, CancellingElement({1, 2}));
  a.shrink_to_fit();
  a.back() = CancellingElement({3});
  const std::vector<CancellingElement> before = a;
  const CancelToken cancel;
  CancellingElement::token = &cancel;
  // Cancelled during the second block: the poll before the third throws, two blocks moved.
  CancellingElement::moves = 0;
  CancellingElement::cancel_at = kPolledFill + 1;
  EXPECT_THROW(grow_apart(cancel, "repair", 1, a), CancelledError);
  EXPECT_EQ(CancellingElement::moves, 2 * kPolledFill);
  EXPECT_EQ(a, before);
  EXPECT_EQ(a.capacity(), before.size());
  // Not cancelled: every element moved once, the capacity doubled.
  cancel.reset();
  CancellingElement::moves = 0;
  CancellingElement::cancel_at = 0;
  grow_apart(cancel, "repair", 1, a);
  EXPECT_EQ(CancellingElement::moves, before.size());
  EXPECT_EQ(a, before);
  EXPECT_EQ(a.capacity(), 2 * before.size());
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

TEST(PolledGrowth, PolledClearFreesABlockAfterEachPollAndKeepsWhatAThrowingPollLeft) {
  const std::size_t n = 2 * kPolledFill + 5;
  std::vector<std::vector<int>> stars(n, std::vector<int>{1, 2, 3});
  int polls = 0;
  polled_clear(stars, [&] { ++polls; });
  EXPECT_TRUE(stars.empty());
  EXPECT_EQ(stars.capacity(), 0u);
  EXPECT_EQ(polls, 3);
  // Cancelled at the second poll: one block is freed, the rest (and their contents) held.
  stars.assign(n, std::vector<int>{4});
  polls = 0;
  EXPECT_THROW(polled_clear(stars,
                            [&] {
                              if (++polls == 2) throw CancelledError("test: cancelled");
                            }),
               CancelledError);
  ASSERT_EQ(stars.size(), n - kPolledFill);
  EXPECT_EQ(stars.back(), std::vector<int>{4});
}

}  // namespace
}  // namespace cdp::detail
