// A uniform hash grid over points identified by small integers (front nodes, mesh vertices),
// or over boxes (triangles, for the seeding's coverage tests).
// Queries visit cells in a fixed order and cells keep insertion order, so results are
// deterministic; callers that pick "the nearest" still break ties by id.
#pragma once

#include <cdp/core/field.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace cdp::adaptive {

class SpatialHash {
 public:
  explicit SpatialHash(double cell_size) : h_(cell_size), inv_h_(1.0 / cell_size) {}

  double cell_size() const { return h_; }
  // Ids looked at by the searches so far (an upper bound; a search stopping early counts its
  // whole last cell): the cost of the searches, which the tracker bounds.
  std::uint64_t visits() const { return visits_; }

  void insert(int id, const Vec3& p) { cell(key(cell_of(p))).push_back(id); }

  void remove(int id, const Vec3& p) {
    const int c = find(key(cell_of(p)));
    if (c < 0) return;
    auto& v = ids_[static_cast<std::size_t>(c)];
    for (std::size_t i = 0; i < v.size(); ++i)
      if (v[i] == id) {
        v[i] = v.back();
        v.pop_back();
        return;
      }
  }

  // Stores id in every cell the box [lo, hi] overlaps (for objects with an extent: triangles).
  void insert_box(int id, const Vec3& lo, const Vec3& hi) {
    const Cell a = cell_of(lo), b = cell_of(hi);
    for (std::int64_t k = a.k; k <= b.k; ++k)
      for (std::int64_t j = a.j; j <= b.j; ++j)
        for (std::int64_t i = a.i; i <= b.i; ++i) cell(key({i, j, k})).push_back(id);
  }

  // Calls fn(id) for every id stored in a cell overlapping the cube of half-side r around p;
  // the caller filters by exact distance.
  template <class Fn>
  void for_each_near(const Vec3& p, double r, Fn&& fn) const {
    any_in(p.array() - r, p.array() + r, [&](int id) {
      fn(id);
      return false;
    });
  }

  // Whether pred(id) holds for an id stored in a cell overlapping the box [lo, hi]; stops at the
  // first (an id stored in several cells may be asked more than once).
  template <class Pred>
  bool any_in(const Vec3& lo, const Vec3& hi, Pred&& pred) const {
    const Cell a = cell_of(lo), b = cell_of(hi);
    for (std::int64_t k = a.k; k <= b.k; ++k)
      for (std::int64_t j = a.j; j <= b.j; ++j)
        for (std::int64_t i = a.i; i <= b.i; ++i) {
          const int c = find(key({i, j, k}));
          if (c < 0) continue;
          const std::vector<int>& ids = ids_[static_cast<std::size_t>(c)];
          visits_ += ids.size();
          for (int id : ids)
            if (pred(id)) return true;
        }
    return false;
  }

 private:
  mutable std::uint64_t visits_ = 0;
  struct Cell {
    std::int64_t i, j, k;
  };
  Cell cell_of(const Vec3& p) const {
    return {static_cast<std::int64_t>(std::floor(p.x() * inv_h_)), static_cast<std::int64_t>(std::floor(p.y() * inv_h_)),
            static_cast<std::int64_t>(std::floor(p.z() * inv_h_))};
  }
  static std::uint64_t key(const Cell& c) {
    // 21 bits per axis; fields far larger than 2^20 cells wrap, which only costs speed.
    const auto m = [](std::int64_t v) { return static_cast<std::uint64_t>(v) & 0x1fffffULL; };
    return m(c.i) | (m(c.j) << 21) | (m(c.k) << 42);
  }

  // The cells live in an open-addressing table (linear probing, at most half full) of keys and
  // indices into ids_: a query looks at 27 cells or more, and std::unordered_map's chained
  // buckets made the lookups 9% of a run on the torus. Cells are never removed (an emptied cell
  // keeps its slot), so probing needs no tombstones.
  static std::size_t slot_hash(std::uint64_t k) {
    k ^= k >> 31;
    k *= 0x7fb5d329728ea185ULL;
    k ^= k >> 27;
    return static_cast<std::size_t>(k);
  }
  int find(std::uint64_t k) const {
    if (slots_.empty()) return -1;
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t s = slot_hash(k) & mask;; s = (s + 1) & mask) {
      const Slot& slot = slots_[s];
      if (slot.cell < 0) return -1;
      if (slot.key == k) return slot.cell;
    }
  }
  std::vector<int>& cell(std::uint64_t k) {
    if (2 * (ids_.size() + 1) > slots_.size()) grow();
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t s = slot_hash(k) & mask;; s = (s + 1) & mask) {
      Slot& slot = slots_[s];
      if (slot.cell < 0) {
        slot = {k, static_cast<int>(ids_.size())};
        return ids_.emplace_back();
      }
      if (slot.key == k) return ids_[static_cast<std::size_t>(slot.cell)];
    }
  }
  void grow() {
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(old.empty() ? 64 : 2 * old.size(), Slot{});
    const std::size_t mask = slots_.size() - 1;
    for (const Slot& o : old) {
      if (o.cell < 0) continue;
      std::size_t s = slot_hash(o.key) & mask;
      while (slots_[s].cell >= 0) s = (s + 1) & mask;
      slots_[s] = o;
    }
  }
  struct Slot {
    std::uint64_t key = 0;
    int cell = -1;  // index into ids_; -1 marks a free slot
  };

  double h_, inv_h_;
  std::vector<Slot> slots_;
  std::vector<std::vector<int>> ids_;
};

}  // namespace cdp::adaptive
