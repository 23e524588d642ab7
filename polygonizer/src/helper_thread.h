// A second thread lent to the serial parts of a run, so that one evaluation of a costly field can
// run half of its sum on another core.
//
// The tracker places one or two points an expansion (1.2 on average on the bunny VIS-800 at
// factor 3: 4,772 expansions of one point, 1,237 of two), each with two or three Newton rounds
// and a Hessian: there is no block of points to share among threads (parallel.h), and most of
// its field work is single evaluations of a few microseconds (a VIS-800 Hessian 2.5 us, a
// VIS-4004 one 13 us). Starting a thread, or waking one that sleeps, costs tens of microseconds,
// so the helper spins while work may come: an empty task handed over and back costs 0.6 us on
// this 2-core machine (the cache lines the two threads write cross between cores), and in the
// tracker about a microsecond, so splitting pays from a few microseconds of work (the
// thresholds of Vis). After kIdleSpin of waiting it sleeps, so that a helper lent to a long
// serial pass of cheap work does not hold a core for long.
//
// A caller lends a helper to the evaluations made on its thread for a scope (LendHelper); a model
// that can split a sum asks lent_helper() and, given one, runs one part there and the other
// itself. Each part must be a pure function of its inputs, so that the result is the same bits
// with or without a helper, on any number of threads. The helper keeps the floating-point
// environment it started with (the default's: round to nearest, no flush to zero): a caller
// that changes it inside the scope gets other bits from the helper's parts. Each thread that
// lends (concurrent polygonize_adaptive calls) has its own helper.
#pragma once

#include <atomic>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <thread>
#include <type_traits>

namespace cdp::detail {

class LendHelper;

class HelperThread {
 public:
  // The most a task may hold (its captures) and return: a VIS Hessian's half holds the model, a
  // point and a count, and returns eleven pairs of sums.
  static constexpr std::size_t kTaskBytes = 40;
  static constexpr std::size_t kResultBytes = 240;

  HelperThread();
  ~HelperThread();
  HelperThread(const HelperThread&) = delete;
  HelperThread& operator=(const HelperThread&) = delete;

  // Runs there() on the helper and here() on the calling thread, and returns there()'s result
  // once both are done. `there` is copied to the helper with its captures (capture the point by
  // value: each cache line the helper must fetch from the caller costs about 0.1 us), and its
  // result comes back through the helper's own lines. Neither may throw: the helper has no one
  // to hand an exception to (noexcept: std::terminate if one does).
  template <class There, class Here>
  auto run_beside(const There& there, Here&& here) noexcept {
    using Result = decltype(there());
    // Copied into the helper's lines (a copy that throws ends the program, as the tasks do) and
    // never destroyed there.
    static_assert(std::is_copy_constructible_v<There> && std::is_trivially_destructible_v<There> &&
                  sizeof(There) <= kTaskBytes && alignof(There) <= 8);
    static_assert(std::is_copy_constructible_v<Result> && std::is_trivially_destructible_v<Result> &&
                  sizeof(Result) <= kResultBytes && alignof(Result) <= 16);
    assert(!busy_ && "run_beside: one task at a time (a `here` may not hand over another)");
    busy_ = true;
    ::new (static_cast<void*>(task_bytes_)) There(there);
    post(&call<There, Result>);
    here();
    wait();
    busy_ = false;
    return *std::launder(reinterpret_cast<const Result*>(result_));
  }

  // Tasks the helper has run (the stats' split_evaluations), and the times it went to sleep.
  std::uint64_t tasks_run() const { return done_.load(std::memory_order_acquire); }
  std::uint64_t sleeps() const { return sleeps_.load(std::memory_order_relaxed); }

 private:
  template <class F, class Result>
  static void call(const unsigned char* task, unsigned char* result) {
    ::new (static_cast<void*>(result)) Result((*std::launder(reinterpret_cast<const F*>(task)))());
  }
  void post(void (*task)(const unsigned char*, unsigned char*)) noexcept;
  void wait() noexcept;
  void loop() noexcept;

  // What the caller writes and the helper polls, in one cache line: the task, its number and
  // its captures (handed over by `posted_`, release, and read after it, acquire).
  alignas(64) std::atomic<std::uint64_t> posted_{0};
  void (*run_)(const unsigned char*, unsigned char*) = nullptr;
  alignas(8) unsigned char task_bytes_[kTaskBytes];
  // What the helper writes and the caller polls, from the next line on: the number of the last
  // task done and its result.
  alignas(64) std::atomic<std::uint64_t> done_{0};
  alignas(16) unsigned char result_[kResultBytes];
  // Whether the helper sleeps (or is about to) in posted_.wait: post then wakes it.
  alignas(64) std::atomic<bool> sleeping_{false};
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> sleeps_{0};
  bool busy_ = false;  // the caller's: inside run_beside
  std::thread thread_;
};

// Withdraws the lent helper, if any, from this thread for its lifetime: parallel_blocks does so
// while its workers run, so that no evaluation hands work to a helper beside them (an idle one
// spins for at most kIdleSpin, then sleeps).
class NoHelperHere {
 public:
  NoHelperHere() noexcept;
  ~NoHelperHere();
  NoHelperHere(const NoHelperHere&) = delete;
  NoHelperHere& operator=(const NoHelperHere&) = delete;

 private:
  LendHelper* saved_;
};

// The helper lent to evaluations on this thread (its thread started at the first call), or
// nullptr: none lent, or no thread could be started (then evaluations run whole).
HelperThread* lent_helper() noexcept;

// Lends a helper thread to the evaluations made on this thread while it lives, when `threads`
// (0: the processors available, as worker_count reads it) allows a second thread, the process
// may run on two processors or more, and no helper is lent already; otherwise nothing. The
// thread starts when an evaluation first asks for it, so that fields which never split cost
// nothing. parallel_blocks withdraws it while its workers run (NoHelperHere). A scope object:
// destroyed on the thread that made it.
class LendHelper {
 public:
  explicit LendHelper(int threads);
  ~LendHelper();
  LendHelper(const LendHelper&) = delete;
  LendHelper& operator=(const LendHelper&) = delete;
  // Tasks the helper ran (0 when none was lent or started).
  std::uint64_t tasks_run() const { return helper_ ? helper_->tasks_run() : 0; }

 private:
  friend HelperThread* lent_helper() noexcept;
  HelperThread* helper() noexcept;

  bool lending_ = false;
  bool failed_ = false;  // starting the thread threw: none is tried again
  std::unique_ptr<HelperThread> helper_;
};

}  // namespace cdp::detail
