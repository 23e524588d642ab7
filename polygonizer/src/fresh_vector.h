// Vectors whose elements start uninitialized, for the large arrays a parallel pass then writes in
// full. A std::vector of n elements writes them all on the thread that makes it, and a new array
// of tens of megabytes is fresh pages: their faults, not the writing, were most of the serial
// stretches of a check of 2*10^6 triangles. Left to the pass, each page is first written, and
// faulted in, by the thread that fills it.
#pragma once

#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace cdp::detail {

// std::allocator, but an element made with no value is default-initialized: left as it is for a
// trivial type (an int, a struct of them, an Eigen vector of doubles).
template <class T>
struct UninitializedAllocator : std::allocator<T> {
  using value_type = T;
  template <class U>
  struct rebind {
    using other = UninitializedAllocator<U>;
  };
  UninitializedAllocator() noexcept = default;
  template <class U>
  UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

// \pre every element is written before it is read (vector(n) and resize(n) leave them as they are).
template <class T>
using FreshVector = std::vector<T, UninitializedAllocator<T>>;

}  // namespace cdp::detail
