// A function run on a stack of its own (a fiber), on the thread that resumes it, until it
// suspends itself or returns: a switch is a _setjmp and a _longjmp (the registers the ABI keeps
// across a call, a few nanoseconds; swapcontext also saves and restores the signal mask, a system
// call each way, about 0.3 us), where handing a core from one thread to another costs a futex
// wake and two context switches, several microseconds each on this machine. Tasks in lockstep
// (adaptive/lockstep.h) run as fibers: their trackers switch at every evaluation.
//
// POSIX makecontext (a stack of its own to start on) and setjmp rather than a library's
// (Boost.Context needs its compiled part, which every user of the static cdp::core would then
// link; cdp::core needs Eigen only). Under AddressSanitizer the switches are announced to it (its
// fiber interface), so that it knows which stack is live.
#pragma once

#include <cstddef>
#include <exception>
#include <functional>

#include <csetjmp>

#include <ucontext.h>

namespace cdp::detail {

class Fiber {
 public:
  // The default stack is a thread's default on Linux: the tasks are the ones threads ran. Its pages
  // are taken only as they are touched (mmap'd, not reserved), with a guard page below it.
  static constexpr std::size_t kDefaultStackBytes = std::size_t{8} << 20;

  // \throw std::bad_alloc where the stack cannot be mapped.
  explicit Fiber(std::function<void()> body, std::size_t stack_bytes = kDefaultStackBytes);
  ~Fiber();
  Fiber(const Fiber&) = delete;
  Fiber& operator=(const Fiber&) = delete;

  // Runs the body from where it stopped until it suspends or returns, on this thread.
  // \pre !finished(); not from inside the body; every resume of one fiber on the same thread
  //      (its stack's frames hold no thread's own state, but the body may use thread_local).
  // \throw what the body threw, once it has ended by it (then finished()).
  void resume();
  // From inside the body: back to resume's caller, until the next resume.
  void suspend();
  bool finished() const { return finished_; }

 private:
  static void entry(unsigned hi, unsigned lo);
  void switch_out(bool last);

  std::function<void()> body_;
  void* map_ = nullptr;  // the stack's mapping, guard page included
  std::size_t map_bytes_ = 0;
  ucontext_t context_{};  // where the body starts (makecontext)
  std::jmp_buf caller_{}, fiber_{};  // where resume and the body stopped (_setjmp)
  bool started_ = false, finished_ = false;
  std::exception_ptr error_;
  // AddressSanitizer's: the caller's stack, and each side's fake stack across a switch.
  const void* caller_bottom_ = nullptr;
  std::size_t caller_size_ = 0;
  void* caller_fake_ = nullptr;
  void* fiber_fake_ = nullptr;
};

}  // namespace cdp::detail
