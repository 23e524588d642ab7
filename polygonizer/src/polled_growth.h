// Arrays that grow in step (a mesh's per-vertex or per-triangle arrays), grown one at a time
// with a cancel poll between. Left to push_back, arrays of the same length reach their capacity
// at the same element and are all copied at once: at 10^6 vertices the tracker's six per-vertex
// arrays moved about 80 MB, page faults included, in one unpolled call of 0.1-0.15 s, over the
// 0.1 s a cancelled run has to stop (cancel.h).
#pragma once

#include <cdp/core/cancel.h>

#include <algorithm>
#include <cstddef>
#include <vector>

namespace cdp::detail {

// Makes room for `n` more elements in each of `arrays` that lacks it, doubling its capacity as
// push_back would (so the capacities, and nothing else, are as before), and polls `cancel` after
// each array it moved. \throw CancelledError naming `what`, once cancelled.
template <class... Array>
void grow_apart(const CancelToken& cancel, const char* what, std::size_t n, Array&... arrays) {
  const auto grow = [&](auto& a) {
    if (a.size() + n <= a.capacity()) return;
    a.reserve(std::max(2 * a.capacity(), a.size() + n));
    cancel.check(what);
  };
  (grow(arrays), ...);
}

// n copies of `value`, made kPolledFill at a time with `poll()` before each block: filling a
// vector of millions of elements (a hundred megabytes of fresh pages, page faults and all) is a
// loop too.
inline constexpr std::size_t kPolledFill = std::size_t{1} << 16;
template <class T, class Poll>
std::vector<T> polled_vector(std::size_t n, Poll poll, const T& value = T()) {
  std::vector<T> v;
  v.reserve(n);
  for (std::size_t i = 0; i < n; i += kPolledFill) {
    poll();
    v.resize(std::min(n, i + kPolledFill), value);
  }
  return v;
}

}  // namespace cdp::detail
