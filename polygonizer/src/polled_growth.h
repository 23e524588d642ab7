// Arrays that grow in step (a mesh's per-vertex or per-triangle arrays), grown one at a time
// with a cancel poll between. Left to push_back, arrays of the same length reach their capacity
// at the same element and are all copied at once: at 10^6 vertices the tracker's six per-vertex
// arrays moved about 80 MB, page faults included, in one unpolled call of 0.1-0.15 s, over the
// 0.1 s a cancelled run has to stop (cancel.h).
#pragma once

#include <cdp/core/cancel.h>

#include <algorithm>
#include <cstddef>
#include <iterator>
#include <type_traits>
#include <vector>

namespace cdp::detail {

// The elements a polled loop below handles between two polls: a few milliseconds of page faults.
inline constexpr std::size_t kPolledFill = std::size_t{1} << 16;

// Makes room for `n` more elements in each of `arrays` that lacks it, doubling its capacity as
// push_back would (so the capacities, and nothing else, are as before). Each array is moved into
// its new storage kPolledFill elements at a time with a poll of `cancel` before each block and
// after the array: the page faults of the fresh storage, not the copy, are most of a growth's
// time (a 24 MB array grown to 48 MB took 0.09 s in one call). \throw CancelledError naming
// `what`, once cancelled; the array being moved then gets its elements back, unchanged.
template <class... Array>
void grow_apart(const CancelToken& cancel, const char* what, std::size_t n, Array&... arrays) {
  const auto grow = [&](auto& a) {
    if (a.size() + n <= a.capacity()) return;
    std::remove_reference_t<decltype(a)> b;
    b.reserve(std::max(2 * a.capacity(), a.size() + n));
    try {
      for (std::size_t i = 0; i < a.size(); i += kPolledFill) {
        cancel.check(what);
        const auto from = a.begin() + static_cast<std::ptrdiff_t>(i);
        b.insert(b.end(), std::make_move_iterator(from),
                 std::make_move_iterator(from + static_cast<std::ptrdiff_t>(std::min(kPolledFill, a.size() - i))));
      }
    } catch (...) {
      std::move(b.begin(), b.end(), a.begin());  // resident pages, no allocation: quick
      throw;
    }
    a.swap(b);
    cancel.check(what);
  };
  (grow(arrays), ...);
}

// n copies of `value`, made kPolledFill at a time with `poll()` before each block: filling a
// vector of millions of elements (a hundred megabytes of fresh pages, page faults and all) is a
// loop too.
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

// Empties `v`, a vector of buffers (a mesh's per-vertex stars, say), freeing them kPolledFill
// at a time from the back with `poll()` before each block: 10^6 small buffers given back at
// once took 0.1 s at 2*10^6 triangles. Where `poll` throws, what is left is still held.
template <class T, class Poll>
void polled_clear(std::vector<std::vector<T>>& v, Poll poll) {
  while (!v.empty()) {
    poll();
    v.resize(v.size() - std::min(v.size(), kPolledFill));
  }
  std::vector<std::vector<T>>().swap(v);
}

}  // namespace cdp::detail
