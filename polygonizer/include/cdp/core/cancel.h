// Cancelling a run from outside it: the caller keeps a CancelToken, puts a copy in the options
// of a polygonizer (AdaptiveOptions, MarchingOptions) and calls cancel() from another thread or
// a signal handler; the run polls the token in its loops and ends with CancelledError, freeing
// what it holds (the field is left as it was and can mesh again). Like libfive's atomic cancel
// flag and Manifold's ExecutionContext, and unlike throwing from a progress callback, it needs
// no callback and is polled where no progress is reported (the repair, the final checks).
#pragma once

#include <atomic>
#include <memory>
#include <stdexcept>

namespace cdp {

// The run was cancelled through its CancelToken.
class CancelledError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A flag shared by its copies. A default token is a fresh flag, not cancelled.
class CancelToken {
 public:
  CancelToken() : flag_(std::make_shared<std::atomic<bool>>(false)) {}

  // Thread-safe, and async-signal-safe (one lock-free atomic store): a SIGINT handler may call
  // it. Every run holding a copy of this token ends with CancelledError at its next poll.
  void cancel() const noexcept { flag_->store(true, std::memory_order_relaxed); }
  // Makes the token usable for another run (its own flag: a linked token's parent stays as it is).
  void reset() const noexcept { flag_->store(false, std::memory_order_relaxed); }
  // A new token cancelled with this one and by its own cancel(), which leaves this one as it is:
  // a part of a run that the run stops alone (a block whose result can no longer matter) while
  // the caller's cancel() still reaches it.
  CancelToken linked() const {
    CancelToken t;
    t.parent_ = std::make_shared<const CancelToken>(*this);
    return t;
  }
  bool cancelled() const noexcept {
    return flag_->load(std::memory_order_relaxed) || (parent_ && parent_->cancelled());
  }
  // The poll of the algorithms' loops. \throw CancelledError naming `what` once cancel() was called.
  void check(const char* what) const {
    if (cancelled()) throw CancelledError(std::string(what) + ": cancelled");
  }

 private:
  static_assert(std::atomic<bool>::is_always_lock_free);
  std::shared_ptr<std::atomic<bool>> flag_;
  std::shared_ptr<const CancelToken> parent_;  // linked(): the token this one follows
};

}  // namespace cdp
