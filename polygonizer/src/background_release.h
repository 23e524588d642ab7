// Memory of a run that is being abandoned, given back on a thread of its own. A run cancelled at
// 2*10^6 triangles held about 10^6 small buffers (the repair's per-vertex stars, the cells of the
// repair's and the tracker's hashes): freeing them one by one between cancel() and the
// CancelledError took most of a 0.3 s latency, far over the 0.1 s asked of a cancelled run. The
// stage objects that own them hand them here from their destructors when the run's cancel token
// is set; the error then reaches the caller at once, and the memory is back within a fraction of
// a second. A run that is not cancelled frees its memory as before, on its own thread, and its
// caller's next run reuses what glibc keeps.
#pragma once

#include <memory>
#include <thread>
#include <tuple>
#include <utility>

namespace cdp::detail {

// Moves `parts` into one object destroyed on a detached thread. Where no thread (or no memory)
// can be had, the parts are freed here, as they would have been.
template <class... T>
void release_in_background(T&... parts) noexcept {
  try {
    auto held = std::make_unique<std::tuple<T...>>(std::move(parts)...);
    std::thread([p = held.get()] { delete p; }).detach();
    held.release();  // the thread owns it now
  } catch (...) {
  }
}

}  // namespace cdp::detail
