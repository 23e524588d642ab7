// The helper thread lent to serial evaluations (polygonizer/src/helper_thread.h): both parts of
// a task run, the helper's result comes back, it wakes after sleeping, and it is lent only
// where the caller allows a second thread.
#include <gtest/gtest.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <thread>
#include <vector>

#include "../../polygonizer/src/helper_thread.h"
#include "../../polygonizer/src/parallel.h"

namespace cdp::detail {
namespace {

TEST(HelperThread, RunsBothPartsAndReturnsTheHelpersResult) {
  // On one processor each hand-over waits for the scheduler: fewer of them.
  const int tasks = available_processors() >= 2 ? 10000 : 50;
  HelperThread helper;
  std::vector<int> mine;
  for (int i = 0; i < tasks; ++i) {
    const std::thread::id caller = std::this_thread::get_id();
    const auto [value, elsewhere] = helper.run_beside(
        [i, caller] { return std::pair<long, bool>(3L * i, std::this_thread::get_id() != caller); },
        [&] { mine.push_back(i); });
    ASSERT_EQ(value, 3L * i);
    ASSERT_TRUE(elsewhere);
  }
  EXPECT_EQ(mine.size(), static_cast<std::size_t>(tasks));
  EXPECT_EQ(helper.tasks_run(), static_cast<std::uint64_t>(tasks));
}

TEST(HelperThread, WakesAfterSleeping) {
  // Past the idle spin (half a millisecond) the helper sleeps, and a task wakes it. How soon it
  // goes to sleep depends on when it is scheduled: waited for, up to 10 s (a loaded machine).
  const auto slept = [](const HelperThread& h, std::uint64_t times) {
    for (int ms = 0; ms < 10000 && h.sleeps() < times; ++ms) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    return h.sleeps() >= times;
  };
  HelperThread helper;
  EXPECT_EQ(helper.run_beside([] { return 1; }, [] {}), 1);
  EXPECT_TRUE(slept(helper, 1));
  EXPECT_EQ(helper.run_beside([] { return 2; }, [] {}), 2);
  EXPECT_TRUE(slept(helper, 2));
  EXPECT_EQ(helper.tasks_run(), 2u);
  // Destroyed while it sleeps: the destructor wakes and joins it (the test would hang otherwise).
}

TEST(LendHelper, LendsOnlyWithASecondThreadAndOnlyToItsThread) {
  EXPECT_EQ(lent_helper(), nullptr);
  if (available_processors() < 2) {
    const LendHelper two(2);
    EXPECT_EQ(lent_helper(), nullptr);  // the two would take turns on one processor
    GTEST_SKIP() << "one processor: no helper is lent";
  }
  {
    const LendHelper one(1);
    EXPECT_EQ(lent_helper(), nullptr);
  }
  {
    const LendHelper two(2);
    HelperThread* helper = lent_helper();
    ASSERT_NE(helper, nullptr);
    EXPECT_EQ(lent_helper(), helper);  // one helper for the scope, started on first use
    {
      const LendHelper inner(2);  // one is lent already: the same stays
      EXPECT_EQ(lent_helper(), helper);
    }
    EXPECT_EQ(lent_helper(), helper);
    HelperThread* seen_elsewhere = helper;
    std::thread([&] { seen_elsewhere = lent_helper(); }).join();
    EXPECT_EQ(seen_elsewhere, nullptr);
    EXPECT_EQ(helper->run_beside([] { return 7; }, [] {}), 7);
    {
      const NoHelperHere withdrawn;  // as in parallel_blocks
      EXPECT_EQ(lent_helper(), nullptr);
    }
    EXPECT_EQ(lent_helper(), helper);
    // parallel_blocks withdraws it from its calling thread, one of the workers.
    std::vector<HelperThread*> seen(4, helper);
    parallel_blocks(seen.size(), 1, 2, [&](std::size_t begin, std::size_t, unsigned) { seen[begin] = lent_helper(); });
    for (HelperThread* h : seen) EXPECT_EQ(h, nullptr);
    EXPECT_EQ(lent_helper(), helper);
  }
  EXPECT_EQ(lent_helper(), nullptr);
}

TEST(ParallelBlocks, RethrowsTheLowestBlocksErrorAsOneThreadWould) {
  // Block 50 throws at once, block 10 after a while: one thread stops at block 10, and so must
  // four, whatever their timing (the first error in time was rethrown before), every block below
  // it having run.
  for (int repeat = 0; repeat < 5; ++repeat) {
    std::vector<char> ran(64, 0);
    try {
      parallel_blocks(ran.size(), 1, 4, [&](std::size_t begin, std::size_t, unsigned) {
        ran[begin] = 1;
        if (begin == 10) {
          std::this_thread::sleep_for(std::chrono::milliseconds(20));
          throw std::runtime_error("block 10");
        }
        if (begin == 50) throw std::runtime_error("block 50");
      });
      ADD_FAILURE() << "no error";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "block 10");
    }
    for (std::size_t b = 0; b <= 10; ++b) EXPECT_TRUE(ran[b]) << b;
  }
}

}  // namespace
}  // namespace cdp::detail
