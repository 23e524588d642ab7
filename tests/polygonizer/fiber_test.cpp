// Fibers (polygonizer/src/fiber.h): bodies interleave where they suspend, each on its own stack;
// exceptions thrown and caught inside a body cross its suspensions; one that escapes comes out of
// resume; a stack overflow would hit the guard page (not tested: it ends the process).
#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "../../polygonizer/src/fiber.h"

namespace cdp::detail {
namespace {

TEST(Fiber, BodiesRunWhereTheyWereSuspendedEachOnItsOwnStack) {
  std::string order;
  std::vector<std::unique_ptr<Fiber>> fibers;
  std::vector<const void*> frames(2, nullptr);
  for (int k = 0; k < 2; ++k)
    fibers.push_back(std::make_unique<Fiber>([&, k] {
      int local = 0;  // on the fiber's stack, alive across the suspensions
      frames[static_cast<std::size_t>(k)] = &local;
      for (int step = 0; step < 3; ++step) {
        local += step;
        order += std::string(1, static_cast<char>('a' + k)) + std::to_string(local) + " ";
        fibers[static_cast<std::size_t>(k)]->suspend();
      }
    }));
  int rounds = 0;
  while (!fibers[0]->finished() || !fibers[1]->finished()) {
    for (auto& f : fibers)
      if (!f->finished()) f->resume();
    ASSERT_LE(++rounds, 4);
  }
  EXPECT_EQ(rounds, 4);  // three suspensions each, then the returns
  EXPECT_EQ(order, "a0 b0 a1 b1 a3 b3 ");
  const int here = 0;
  EXPECT_NE(frames[0], frames[1]);
  for (const void* f : frames) EXPECT_NE(f, static_cast<const void*>(&here));
}

TEST(Fiber, ExceptionsCrossSuspensionsInsideAndComeOutOfResumeWhenTheyEscape) {
  int caught = 0;
  std::unique_ptr<Fiber> fiber;
  fiber = std::make_unique<Fiber>([&] {
    try {
      fiber->suspend();
      throw std::runtime_error("inside");
    } catch (const std::runtime_error&) {
      ++caught;
    }
    fiber->suspend();
    throw std::logic_error("escapes");
  });
  fiber->resume();  // to the first suspension
  EXPECT_EQ(caught, 0);
  fiber->resume();  // throws and catches inside, then suspends
  EXPECT_EQ(caught, 1);
  EXPECT_FALSE(fiber->finished());
  EXPECT_THROW(fiber->resume(), std::logic_error);
  EXPECT_TRUE(fiber->finished());
}

TEST(Fiber, ADeepBodyHasTheStackAThreadWouldHave) {
  // A megabyte of frames, well within the default stack (a thread's).
  std::function<int(int)> deep = [&](int depth) {
    volatile char pad[1024];
    pad[0] = static_cast<char>(depth);
    return depth == 0 ? pad[0] : deep(depth - 1) + 1;
  };
  int result = -1;
  Fiber fiber([&] { result = deep(1000); });
  fiber.resume();
  EXPECT_TRUE(fiber.finished());
  EXPECT_EQ(result, 1000);
}

}  // namespace
}  // namespace cdp::detail
