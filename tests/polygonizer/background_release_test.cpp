// release_in_background (polygonizer/src/background_release.h): what a cancelled run's stages
// hand over is moved out of them and destroyed on another thread.
#include "src/background_release.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

namespace cdp::detail {
namespace {

// Records the thread that destroys it (a moved-from one records nothing).
struct Witness {
  std::shared_ptr<std::atomic<std::thread::id>> destroyed_on = std::make_shared<std::atomic<std::thread::id>>();
  Witness() = default;
  Witness(Witness&&) noexcept = default;
  ~Witness() {
    if (destroyed_on) destroyed_on->store(std::this_thread::get_id());
  }
};

TEST(BackgroundRelease, ThePartsLeaveTheirOwnerAndAreDestroyedOnAnotherThread) {
  std::vector<std::vector<int>> cells(1000, std::vector<int>(3, 7));
  Witness witness;
  const auto destroyed_on = witness.destroyed_on;
  release_in_background(cells, witness);
  EXPECT_TRUE(cells.empty());
  // Bounded wait: the thread runs at once on any machine that runs the tests.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (destroyed_on->load() == std::thread::id() && std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  EXPECT_NE(destroyed_on->load(), std::thread::id());
  EXPECT_NE(destroyed_on->load(), std::this_thread::get_id());
}

}  // namespace
}  // namespace cdp::detail
