// A map from 64-bit lattice keys to small values, with open addressing and linear probing: the
// continuation looks up every cube corner and edge in one, and std::unordered_map's node
// allocations cost more there than a cheap field's evaluations.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace cdp::marching {

template <class Value>
class FlatMap {
 public:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};  // never a lattice key

  FlatMap() { rehash(1024); }

  Value* find(std::uint64_t key) {
    for (std::size_t i = slot(key);; i = (i + 1) & mask_) {
      if (keys_[i] == key) return &values_[i];
      if (keys_[i] == kEmpty) return nullptr;
    }
  }

  // The value stored under key (inserting `value` if there was none), and whether it inserted.
  std::pair<Value*, bool> emplace(std::uint64_t key, const Value& value) {
    if (2 * (size_ + 1) > keys_.size()) rehash(2 * keys_.size());
    std::size_t i = slot(key);
    for (; keys_[i] != kEmpty; i = (i + 1) & mask_)
      if (keys_[i] == key) return {&values_[i], false};
    keys_[i] = key;
    values_[i] = value;
    ++size_;
    return {&values_[i], true};
  }

  std::size_t size() const { return size_; }

 private:
  std::size_t slot(std::uint64_t key) const {
    // splitmix64's finalizer: lattice keys are dense integers, the table wants spread bits.
    key ^= key >> 30;
    key *= 0xbf58476d1ce4e5b9ULL;
    key ^= key >> 27;
    key *= 0x94d049bb133111ebULL;
    key ^= key >> 31;
    return static_cast<std::size_t>(key) & mask_;
  }

  void rehash(std::size_t capacity) {
    std::vector<std::uint64_t> old_keys(capacity, kEmpty);
    std::vector<Value> old_values(capacity);
    old_keys.swap(keys_);
    old_values.swap(values_);
    mask_ = capacity - 1;
    size_ = 0;
    for (std::size_t i = 0; i < old_keys.size(); ++i)
      if (old_keys[i] != kEmpty) emplace(old_keys[i], old_values[i]);
  }

  std::vector<std::uint64_t> keys_;
  std::vector<Value> values_;
  std::size_t mask_ = 0;
  std::size_t size_ = 0;
};

}  // namespace cdp::marching
