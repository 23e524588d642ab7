#include "helper_thread.h"

#include "parallel.h"

#include <chrono>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace cdp::detail {

namespace {

// How long an idle helper spins before it sleeps: a sleeping one takes tens of microseconds to
// wake, more than the task it wakes for. The tracker's evaluations come a few microseconds
// apart in bursts, with gaps of tens of microseconds (the bunny VIS-800 at factor 3: 7,260
// Hessians in 64 ms). With 24 us (2000 pauses of 12 ns) the helper slept through many of those
// gaps: splitting the VIS-800's Hessians made its tracking 6.5 % slower, and the VIS-4004's
// Hessians alone gained 3 %; with 500 us, 3.6 % slower (which is why a VIS-800 does not split,
// Vis::kSplitGradientHessianCentres) and the VIS-4004 23 % faster with its values and gradients
// split too. The clock is read every kSpinsPerClockRead pauses.
constexpr std::chrono::microseconds kIdleSpin{500};
constexpr int kSpinsPerClockRead = 64;
// Rounds the caller spins on a task before it yields its processor each round instead: a task
// is a microsecond or a few; one still running after this has lost its processor.
constexpr int kBusySpins = 20000;

void pause() noexcept {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}

thread_local LendHelper* t_lender = nullptr;

}  // namespace

HelperThread::HelperThread() : thread_([this] { loop(); }) {}

HelperThread::~HelperThread() {
  // stop_ before the new number, so that the helper, woken or spinning, sees it with the number.
  stop_.store(true, std::memory_order_seq_cst);
  posted_.fetch_add(1, std::memory_order_seq_cst);
  posted_.notify_one();
  thread_.join();
}

void HelperThread::post(void (*run)(const unsigned char*, unsigned char*)) noexcept {
  run_ = run;
  posted_.store(posted_.load(std::memory_order_relaxed) + 1, std::memory_order_seq_cst);
  // Either the helper's check of posted_ after it set sleeping_ sees the new number, or this
  // sees sleeping_ set (both sequentially consistent), so no wake-up is lost.
  if (sleeping_.load(std::memory_order_seq_cst)) posted_.notify_one();
}

void HelperThread::wait() noexcept {
  const std::uint64_t target = posted_.load(std::memory_order_relaxed);
  for (int spins = 0; done_.load(std::memory_order_acquire) != target; ++spins) {
    if (spins < kBusySpins) pause();
    else std::this_thread::yield();
  }
}

void HelperThread::loop() noexcept {
  using Clock = std::chrono::steady_clock;
  std::uint64_t seen = 0;
  for (;;) {
    std::uint64_t now;
    Clock::time_point idle_since = Clock::now();
    for (int spins = 0; (now = posted_.load(std::memory_order_acquire)) == seen; ++spins) {
      if (spins % kSpinsPerClockRead != kSpinsPerClockRead - 1 || Clock::now() - idle_since < kIdleSpin) {
        pause();
        continue;
      }
      sleeping_.store(true, std::memory_order_seq_cst);
      if (posted_.load(std::memory_order_seq_cst) == seen) {
        sleeps_.fetch_add(1, std::memory_order_relaxed);
        posted_.wait(seen, std::memory_order_seq_cst);
      }
      sleeping_.store(false, std::memory_order_relaxed);
      idle_since = Clock::now();
    }
    if (stop_.load(std::memory_order_acquire)) return;
    run_(task_bytes_, result_);
    seen = now;
    done_.store(now, std::memory_order_release);
  }
}

HelperThread* lent_helper() noexcept { return t_lender ? t_lender->helper() : nullptr; }

NoHelperHere::NoHelperHere() noexcept : saved_(t_lender) { t_lender = nullptr; }

NoHelperHere::~NoHelperHere() { t_lender = saved_; }

HelperThread* LendHelper::helper() noexcept {
  if (!helper_ && !failed_) {
    try {
      helper_ = std::make_unique<HelperThread>();
    } catch (...) {  // no thread to spare (std::system_error): evaluations run whole
      failed_ = true;
    }
  }
  return helper_.get();
}

LendHelper::LendHelper(int threads) {
  // On one processor the two would take turns, each spinning through the other's time slice.
  if (t_lender || worker_count(threads) < 2 || available_processors() < 2) return;
  lending_ = true;
  t_lender = this;
}

LendHelper::~LendHelper() {
  if (lending_) t_lender = nullptr;
}

}  // namespace cdp::detail
