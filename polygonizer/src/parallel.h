// Work shared among threads for the core's data-parallel passes (the seed grid's values, the
// final self-intersection check): blocks of a range handed out in turn from an atomic counter.
// Which thread takes which block varies from run to run, so callers give every block its own
// output slot, or merge per-thread results with an operation whose result does not depend on
// the order (sums, the smallest pairs): the answer is then the same on any number of threads.
#pragma once

#include "helper_thread.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <exception>
#include <mutex>
#if defined(__linux__)
#include <sched.h>
#endif
#include <thread>
#include <utility>
#include <vector>

namespace cdp::detail {

// The processors this process may run on: its CPU affinity where the system tells it (a process
// pinned to one core, or a container given a few, would otherwise start a thread per core of the
// machine and switch between them on its own), else the machine's hardware threads.
inline unsigned available_processors() {
#if defined(__linux__)
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0)
    if (const int n = CPU_COUNT(&set); n > 0) return static_cast<unsigned>(n);
#endif
  return std::thread::hardware_concurrency();
}

// Threads for the core's parallel passes: `requested` when positive, else the processors
// available; at most kMaxThreads (the passes are memory-bound beyond that), at least one.
inline constexpr unsigned kMaxThreads = 8;
inline unsigned worker_count(int requested = 0) {
  const unsigned hw = available_processors();
  const unsigned n = requested > 0 ? static_cast<unsigned>(requested) : hw;
  return std::clamp(n, 1u, kMaxThreads);
}

// The wall time of each data-parallel pass (parallel_blocks of two blocks or more) a run makes
// on its own thread, and its blocks: the work that more threads would share, which the projected
// speedups of BM_AdaptiveBlocks divide among them (BlocksReport::pass_seconds). A run points
// `pass_clock` at its own on its thread; a pass's work, and the passes it makes, count as its own.
struct PassClock {
  std::vector<double> seconds;
  std::vector<std::size_t> blocks;
};
inline thread_local PassClock* pass_clock = nullptr;

// This thread's passes counted on `clock` in its scope (a run's own), or none (nullptr: the
// blocks' own work, timed block by block, and a pass's work); the clock before it after.
class ScopedPassClock {
 public:
  explicit ScopedPassClock(PassClock* clock = nullptr) : saved_(std::exchange(pass_clock, clock)) {}
  ~ScopedPassClock() { pass_clock = saved_; }
  ScopedPassClock(const ScopedPassClock&) = delete;
  ScopedPassClock& operator=(const ScopedPassClock&) = delete;

 private:
  PassClock* saved_;
};

// Calls fn(begin, end, worker) for consecutive blocks [begin, end) of [0, n), each block once,
// on up to `workers` threads (worker in [0, workers)). A range of at most one block runs on the
// calling thread. The exception of the lowest block that threw is rethrown here once all threads
// are done: the one a single thread would throw.
template <class Fn>
void parallel_blocks(std::size_t n, std::size_t block, unsigned workers, Fn&& fn) {
  block = std::max<std::size_t>(block, 1);
  const std::size_t blocks = (n + block - 1) / block;
  workers = static_cast<unsigned>(std::min<std::size_t>(std::max(workers, 1u), blocks));
  PassClock* const clock = blocks >= 2 ? pass_clock : nullptr;
  const ScopedPassClock paused;
  const auto start = std::chrono::steady_clock::now();
  const auto timed = [&] {
    if (clock)
      clock->seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()),
          clock->blocks.push_back(blocks);
  };
  if (workers <= 1) {
    for (std::size_t b = 0; b < blocks; ++b) fn(b * block, std::min(n, (b + 1) * block), 0u);
    timed();
    return;
  }
  // Blocks are taken in increasing order, so every block below one that threw was taken before
  // it and runs to its end: the lowest block that threw is the one a single thread would have
  // stopped at, and its error is the one rethrown, whatever the threads' timing.
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::size_t error_block = blocks;
  std::mutex error_mutex;
  const auto work = [&](unsigned worker) {
    for (std::size_t b; (b = next.fetch_add(1, std::memory_order_relaxed)) < blocks;) try {
        fn(b * block, std::min(n, (b + 1) * block), worker);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (b < error_block) error_block = b, error = std::current_exception();
        next.store(blocks, std::memory_order_relaxed);  // no block after it is started
      }
  };
  // A helper lent to this thread for its serial evaluations (helper_thread.h) must not spin
  // beside the workers: none is lent to them, and this thread is one of them.
  const NoHelperHere no_helper;
  std::vector<std::thread> threads;
  threads.reserve(workers - 1);
  for (unsigned w = 1; w < workers; ++w) threads.emplace_back(work, w);
  work(0);
  for (auto& t : threads) t.join();
  if (error) std::rethrow_exception(error);
  timed();
}

}  // namespace cdp::detail
