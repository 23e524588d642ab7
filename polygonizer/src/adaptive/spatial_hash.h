// A uniform hash grid over points identified by small integers (front nodes, mesh vertices),
// or over boxes (triangles, for the seeding's coverage tests).
// Queries visit cells in a fixed order and cells keep insertion order, so results are
// deterministic; callers that pick "the nearest" still break ties by id.
// Optionally (Crowding::split) a cell crowded with points hands them to a finer grid over its
// extent, so that searches stay local where edges are far shorter than the cell.
#pragma once

#include <cdp/core/cancel.h>
#include <cdp/core/field.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <vector>

#include "../polled_growth.h"

namespace cdp::adaptive {

// What a cell does when more than kCrowdedCell points are inserted into it.
enum class Crowding {
  keep,   // nothing: every query in the cell looks at all its points
  split,  // its points move to a finer hash over the cell (see SpatialHash::insert)
};

class SpatialHash {
 public:
  explicit SpatialHash(double cell_size, Crowding crowding = Crowding::keep)
      : SpatialHash(cell_size, crowding, 0) {}

  double cell_size() const { return h_; }
  // Without counting, the const queries write nothing, so several threads may query the hash at
  // once (while none inserts); visits() then stops growing. Counting is on by default.
  void set_counting(bool on) {
    counting_ = on;
    if (coarser_) coarser_->set_counting(on);
    for (auto& f : finer_)
      if (f) f->set_counting(on);
  }
  // A run's cancel token, polled while the table grows: at 10^6 cells one growth rehashes 2*10^6
  // slots and moves the cells' arrays, 0.1-0.2 s in one call (cancel.h). Not passed to the
  // coarser and finer levels, which stay small.
  void set_cancel(const CancelToken& cancel) { cancel_ = cancel; }

  // Empties the hash, its cells' arrays freed a block at a time with a poll of the cancel token
  // before each (polled_growth.h): the repair's hash holds about a cell per two triangles, and
  // 10^6 small arrays freed at once took 0.1 s. \throw CancelledError, once cancelled; the hash
  // is then only to be destroyed.
  void clear() {
    detail::polled_clear(ids_, [this] {
      if (cancel_) cancel_->check("adaptive");
    });
    std::vector<Slot>().swap(slots_);
    std::vector<std::uint64_t>().swap(keys_);
    std::vector<double>().swap(reach_);
    std::vector<std::unique_ptr<SpatialHash>>().swap(finer_);
    coarser_.reset();
  }

  // Ids looked at by the searches so far (an upper bound; a search stopping early counts its
  // whole last cell): the cost of the searches, which the tracker bounds.
  std::uint64_t visits() const { return visits_ + (coarser_ ? coarser_->visits() : 0); }

  // With Crowding::split, a cell that would hold more than kCrowdedCell points hands them to a
  // finer hash over its extent (cells kSplitRatio times smaller, at most kMaxSplitDepth levels
  // down, which bounds the splitting of coincident points). The tracker's vertex hash needs it:
  // on the Barth ball at factor 10 the necks' edges are a hundredth of the cell, thousands of
  // vertices shared a cell, and the test of each new point against the finished mesh looked at
  // all of them (over 6000 points a step, the search bound). A split cell's points are visited
  // in the finer hash's order, so only callers whose answers do not depend on order may use it.
  // Such a hash holds points, not boxes, and keeps their ids only: a split asks position_of(id)
  // where each point it hands on lies (the point's position when it was inserted). A hash that
  // never splits never calls it.
  void insert(int id, const Vec3& p) {
    insert(id, p, [](int) -> Vec3 { throw std::logic_error("SpatialHash: a splitting hash needs positions"); });
  }
  template <class PositionOf>
  void insert(int id, const Vec3& p, const PositionOf& position_of) {
    const auto c = static_cast<std::size_t>(cell(key(cell_of(p))));
    if (crowding_ == Crowding::keep) {
      ids_[c].push_back(id);
      return;
    }
    if (finer_[c]) {
      finer_[c]->insert(id, p, position_of);
      return;
    }
    ids_[c].push_back(id);
    if (ids_[c].size() <= kCrowdedCell || depth_ >= kMaxSplitDepth) return;
    finer_[c].reset(new SpatialHash(h_ / kSplitRatio, Crowding::split, depth_ + 1));
    finer_[c]->counting_ = counting_;
    for (const int moved : ids_[c]) finer_[c]->insert(moved, moved == id ? p : position_of(moved), position_of);
    std::vector<int>().swap(ids_[c]);
  }

  void remove(int id, const Vec3& p) {
    const int c = find(key(cell_of(p)));
    if (c < 0) return;
    const auto u = static_cast<std::size_t>(c);
    if (crowding_ == Crowding::split && finer_[u]) {
      finer_[u]->remove(id, p);
      return;
    }
    auto& v = ids_[u];
    for (std::size_t i = 0; i < v.size(); ++i)
      if (v[i] == id) {
        v[i] = v.back();
        v.pop_back();
        if (v.empty() && u < reach_.size()) reach_[u] = 0;
        return;
      }
  }

  // Each cell's reach: at least every length widen_reach gave for a point in it since the cell
  // was last empty (for the tracker's front hash, the front edges that start there). A search
  // for edges near a segment passes over the cells too far for any of theirs to come near it
  // (any_in with a `far` test), without changing which id it answers or in what order it asks:
  // a cell passed over holds no id pred would accept. On a scan whose fronts made edges of 0.3
  // beside a few of 5, the searches of every short edge looked through every node within the
  // longest edge's reach. Only for a hash of points that never splits (Crowding::keep).
  void widen_reach(const Vec3& p, double length) {
    const auto c = static_cast<std::size_t>(cell(key(cell_of(p))));
    if (reach_.size() < ids_.size()) reach_.resize(ids_.size(), 0);
    reach_[c] = std::max(reach_[c], length);
  }

  // Stores id in every cell the box [lo, hi] overlaps (for objects with an extent: triangles).
  // A box wider than kMaxBoxSpan cells along an axis goes to a coarser level instead (cells
  // kLevelRatio times wider, as often as needed), so that a large triangle among small ones
  // fills a few cells, not millions: a sphere's triangles of edge 1 beside a torus tube of
  // radius 0.003, in a hash sized by the tube's edges, took 330 s of a run to insert.
  void insert_box(int id, const Vec3& lo, const Vec3& hi) {
    const Cell a = cell_of(lo), b = cell_of(hi);
    if (too_wide(a, b)) {
      if (!coarser_) {
        coarser_ = std::make_unique<SpatialHash>(h_ * kLevelRatio);
        coarser_->counting_ = counting_;
      }
      coarser_->insert_box(id, lo, hi);
      return;
    }
    for_each_key(a, b, [&](std::uint64_t k) { ids_[static_cast<std::size_t>(cell(k))].push_back(id); });
  }

  // insert_box(id, lo[id], hi[id]) for every id of the two arrays, in order: the same cells made
  // in the same order, but each cell's array sized once, at the capacity its push_backs would
  // reach. One insert_box at a time, the arrays grew a few times each, and the repair's hash of
  // every triangle was a tenth of its run (the torus at factor 40, perf). For a hash of boxes
  // (Crowding::keep). Polls the cancel token (set_cancel).
  void insert_boxes(const std::vector<Vec3>& lo, const std::vector<Vec3>& hi) {
    const auto poll = [this](std::size_t i) {
      if (cancel_ && i % kGrowPollEvery == 0) cancel_->check("adaptive");
    };
    // Each box's cells made in insert_box's order and counted; the arrays sized; the ids stored,
    // the cells found again (a lookup costs less than keeping every entry's cell).
    std::vector<std::uint32_t> added;  // by cell: the entries it gets here
    for (std::size_t id = 0; id < lo.size(); ++id) {
      poll(id);
      const Cell a = cell_of(lo[id]), b = cell_of(hi[id]);
      if (too_wide(a, b)) continue;
      for_each_key(a, b, [&](std::uint64_t k) {
        const auto c = static_cast<std::size_t>(cell(k));
        if (c >= added.size()) added.resize(ids_.size(), 0);
        ++added[c];
      });
    }
    for (std::size_t c = 0; c < added.size(); ++c) {
      poll(c);
      if (added[c]) ids_[c].reserve(std::bit_ceil(ids_[c].size() + added[c]));
    }
    std::vector<std::uint32_t>().swap(added);
    for (std::size_t id = 0; id < lo.size(); ++id) {
      poll(id);
      const Cell a = cell_of(lo[id]), b = cell_of(hi[id]);
      if (too_wide(a, b))
        insert_box(static_cast<int>(id), lo[id], hi[id]);
      else
        for_each_key(a, b, [&](std::uint64_t k) {
          ids_[static_cast<std::size_t>(find(k))].push_back(static_cast<int>(id));
        });
    }
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

  // The occupied cells overlapping a box, in the order any_in visits them, taken once so that
  // several queries inside that box (the checks of one expansion) do not each look up every
  // cell. Holds indices of cells: valid until the next insert.
  struct Gathered {
    std::int64_t lo[3] = {0, 0, 0}, hi[3] = {-1, -1, -1};  // the box's cells; empty: nothing gathered
    struct Run {
      std::int64_t i, j, k;
      int cell;
    };
    std::vector<Run> runs;
  };

  // Gathers the cells overlapping [lo, hi] (none where any_in would not visit them in the order
  // of its cell-by-cell loop: a box over more cells than are occupied, or a coarser level).
  void gather(const Vec3& lo, const Vec3& hi, Gathered& g) const {
    g.runs.clear();
    g.hi[0] = g.lo[0] - 1;
    const Cell a = cell_of(lo), b = cell_of(hi);
    if (coarser_ || crowding_ == Crowding::split || spanned(a, b) > static_cast<double>(ids_.size())) return;
    g.lo[0] = a.i, g.lo[1] = a.j, g.lo[2] = a.k;
    g.hi[0] = b.i, g.hi[1] = b.j, g.hi[2] = b.k;
    for (std::int64_t k = a.k; k <= b.k; ++k)
      for (std::int64_t j = a.j; j <= b.j; ++j)
        for (std::int64_t i = a.i; i <= b.i; ++i)
          if (const int c = find(key({i, j, k})); c >= 0 && !ids_[static_cast<std::size_t>(c)].empty())
            g.runs.push_back({i, j, k, c});
  }

  // any_in(lo, hi, pred) with the same answer, the same order of calls to pred and the same
  // visits, from the cells g gathered when the box lies within g's (else by any_in itself).
  template <class Pred>
  bool any_in(const Gathered& g, const Vec3& lo, const Vec3& hi, Pred&& pred) const {
    return any_in(g, lo, hi, kNeverFar, pred);
  }
  // The same, passing over the cells for which far(cell_lo, cell_hi, reach) holds (widen_reach).
  template <class Far, class Pred>
  bool any_in(const Gathered& g, const Vec3& lo, const Vec3& hi, const Far& far, Pred&& pred) const {
    const Cell a = cell_of(lo), b = cell_of(hi);
    if (a.i < g.lo[0] || a.j < g.lo[1] || a.k < g.lo[2] || b.i > g.hi[0] || b.j > g.hi[1] || b.k > g.hi[2] ||
        spanned(a, b) > static_cast<double>(ids_.size()))
      return any_in(lo, hi, far, pred);
    // g's cells in any_in's order; those of the smaller box keep that order among themselves.
    for (const auto& r : g.runs) {
      if (r.i < a.i || r.i > b.i || r.j < a.j || r.j > b.j || r.k < a.k || r.k > b.k) continue;
      if (passes_over({r.i, r.j, r.k}, r.cell, far)) continue;
      const std::vector<int>& ids = ids_[static_cast<std::size_t>(r.cell)];
      if (counting_) visits_ += ids.size();
      for (int id : ids)
        if (pred(id)) return true;
    }
    return false;
  }

  template <class Fn>
  void for_each_near(const Gathered& g, const Vec3& p, double r, Fn&& fn) const {
    any_in(g, p.array() - r, p.array() + r, [&](int id) {
      fn(id);
      return false;
    });
  }

  // Whether pred(id) holds for an id stored in a cell overlapping the box [lo, hi]; stops at the
  // first (an id stored in several cells may be asked more than once). The coarser levels of
  // large boxes (insert_box) are asked after this one's cells.
  // A box over more cells than are occupied visits the occupied cells inside it instead, in the
  // order they were made (a star of the sphere's long edges in a hash sized by a thin tube's
  // short ones spans millions of cells, nearly all empty).
  template <class Pred>
  bool any_in(const Vec3& lo, const Vec3& hi, Pred&& pred) const {
    return any_in(lo, hi, kNeverFar, pred);
  }
  // The same, passing over the cells for which far(cell_lo, cell_hi, reach) holds (widen_reach).
  template <class Far, class Pred>
  bool any_in(const Vec3& lo, const Vec3& hi, const Far& far, Pred&& pred) const {
    const Cell a = cell_of(lo), b = cell_of(hi);
    const auto visit = [&](int c) {
      if (crowding_ == Crowding::split && finer_[static_cast<std::size_t>(c)])
        return any_in_finer(c, lo, hi, pred);
      const std::vector<int>& ids = ids_[static_cast<std::size_t>(c)];
      if (counting_) visits_ += ids.size();
      for (int id : ids)
        if (pred(id)) return true;
      return false;
    };
    if (spanned(a, b) > static_cast<double>(ids_.size())) {
      // A cell's key holds its coordinates modulo 2^21 (key): it is in the box when some cell
      // of the box has the same residues, as the scan below would find it.
      const auto meets = [](std::uint64_t residue, std::int64_t from, std::int64_t to) {
        if (to - from >= static_cast<std::int64_t>(kAxisMask)) return true;
        return ((residue - (static_cast<std::uint64_t>(from) & kAxisMask)) & kAxisMask) <=
               static_cast<std::uint64_t>(to - from);
      };
      // A cell in the box lies at `from` plus its residue's offset from from's (where the box spans
      // fewer cells than the key tells apart along every axis: else `far` is not asked).
      const bool placed = b.i - a.i < static_cast<std::int64_t>(kAxisMask) &&
                          b.j - a.j < static_cast<std::int64_t>(kAxisMask) &&
                          b.k - a.k < static_cast<std::int64_t>(kAxisMask);
      const auto at = [](std::uint64_t residue, std::int64_t from) {
        return from + static_cast<std::int64_t>((residue - static_cast<std::uint64_t>(from)) & kAxisMask);
      };
      for (std::size_t c = 0; c < keys_.size(); ++c) {
        const std::uint64_t x = keys_[c], xi = x & kAxisMask, xj = (x >> 21) & kAxisMask, xk = (x >> 42) & kAxisMask;
        if (!meets(xi, a.i, b.i) || !meets(xj, a.j, b.j) || !meets(xk, a.k, b.k)) continue;
        if (placed && passes_over({at(xi, a.i), at(xj, a.j), at(xk, a.k)}, static_cast<int>(c), far)) continue;
        if (visit(static_cast<int>(c))) return true;
      }
    } else {
      for (std::int64_t k = a.k; k <= b.k; ++k)
        for (std::int64_t j = a.j; j <= b.j; ++j)
          for (std::int64_t i = a.i; i <= b.i; ++i) {
            const int c = find(key({i, j, k}));
            if (c >= 0 && !passes_over({i, j, k}, c, far) && visit(c)) return true;
          }
    }
    return coarser_ && coarser_->any_in(lo, hi, pred);
  }

 private:
  // any_in's `far` when no cell is to be passed over.
  static constexpr auto kNeverFar = [](const Vec3&, const Vec3&, double) { return false; };
  struct Cell;
  // Whether `far` holds for cell c at `at` and its reach. Its box is widened by a billionth of its
  // coordinates' size: cell_of rounds p / h, so a point may lie that much outside its cell. A
  // cell without a reach is never passed over.
  template <class Far>
  bool passes_over(const Cell& at, int c, const Far& far) const {
    const auto u = static_cast<std::size_t>(c);
    if (u >= reach_.size() || reach_[u] <= 0) return false;
    const Vec3 lo(static_cast<double>(at.i) * h_, static_cast<double>(at.j) * h_, static_cast<double>(at.k) * h_);
    const double slack = 1e-9 * (h_ + lo.cwiseAbs().maxCoeff());
    return far(Vec3(lo.array() - slack), Vec3(lo.array() + (h_ + slack)), reach_[u]);
  }

  SpatialHash(double cell_size, Crowding crowding, int depth)
      : h_(cell_size), inv_h_(1.0 / cell_size), crowding_(crowding), depth_(depth) {}

  // any_in over a split cell's points. The box needs no clipping to the cell: the finer hash's
  // cells all lie inside it, at most kSplitRatio^3 of them on its first level, and a box over
  // more cells than it holds visits its occupied cells instead (any_in).
  template <class Pred>
  bool any_in_finer(int c, const Vec3& lo, const Vec3& hi, Pred& pred) const {
    const SpatialHash& f = *finer_[static_cast<std::size_t>(c)];
    if (!counting_) return f.any_in(lo, hi, pred);
    const std::uint64_t before = f.visits_;
    const bool hit = f.any_in(lo, hi, pred);
    visits_ += f.visits_ - before;
    return hit;
  }

  mutable std::uint64_t visits_ = 0;
  bool counting_ = true;
  struct Cell {
    std::int64_t i, j, k;
  };
  // std::floor as an integer, without its library call (the build targets no SSE4.1 rounding
  // instruction): the conversion truncates toward zero, one less below zero unless exact.
  static std::int64_t floor_int(double x) {
    const auto i = static_cast<std::int64_t>(x);
    return i - (x < static_cast<double>(i));
  }
  // The number of cells from a to b (as a double: a huge box overflows no integer).
  static double spanned(const Cell& a, const Cell& b) {
    return (static_cast<double>(b.i - a.i) + 1) * (static_cast<double>(b.j - a.j) + 1) *
           (static_cast<double>(b.k - a.k) + 1);
  }
  Cell cell_of(const Vec3& p) const {
    return {floor_int(p.x() * inv_h_), floor_int(p.y() * inv_h_), floor_int(p.z() * inv_h_)};
  }
  static constexpr std::uint64_t kAxisMask = 0x1fffffULL;
  static std::uint64_t key(const Cell& c) {
    // 21 bits per axis; fields far larger than 2^20 cells wrap, which only costs speed.
    const auto m = [](std::int64_t v) { return static_cast<std::uint64_t>(v) & kAxisMask; };
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
  // A box from cell a to cell b goes to the coarser level (insert_box).
  static bool too_wide(const Cell& a, const Cell& b) {
    return b.i - a.i > kMaxBoxSpan || b.j - a.j > kMaxBoxSpan || b.k - a.k > kMaxBoxSpan;
  }
  // fn(key) for the cells from a to b, x fastest.
  template <class Fn>
  static void for_each_key(const Cell& a, const Cell& b, Fn&& fn) {
    for (std::int64_t k = a.k; k <= b.k; ++k)
      for (std::int64_t j = a.j; j <= b.j; ++j)
        for (std::int64_t i = a.i; i <= b.i; ++i) fn(key({i, j, k}));
  }
  // The index of the cell with key k, made empty if there is none.
  int cell(std::uint64_t k) {
    if (2 * (ids_.size() + 1) > slots_.size()) grow();
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t s = slot_hash(k) & mask;; s = (s + 1) & mask) {
      Slot& slot = slots_[s];
      if (slot.cell < 0) {
        slot = {k, static_cast<int>(ids_.size())};
        keys_.push_back(k);
        ids_.emplace_back();
        if (crowding_ == Crowding::split) finer_.emplace_back();
        return slot.cell;
      }
      if (slot.key == k) return slot.cell;
    }
  }
  // Doubles the slots (at half load), and with a cancel token, the cells' arrays too, which fill
  // up at the same cell: one array at a time, polled between and while rehashing.
  void grow() {
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(old.empty() ? 64 : 2 * old.size(), Slot{});
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = 0; i < old.size(); ++i) {
      if (cancel_ && i % kGrowPollEvery == 0) cancel_->check("adaptive");
      const Slot& o = old[i];
      if (o.cell < 0) continue;
      std::size_t s = slot_hash(o.key) & mask;
      while (slots_[s].cell >= 0) s = (s + 1) & mask;
      slots_[s] = o;
    }
    if (cancel_) detail::grow_apart(*cancel_, "adaptive", 1, keys_, ids_);
  }
  struct Slot {
    std::uint64_t key = 0;
    int cell = -1;  // index into ids_; -1 marks a free slot
  };

  // insert_box: boxes wider than kMaxBoxSpan cells along an axis go to the next level, whose
  // cells are kLevelRatio times wider; each box is stored in at most (kMaxBoxSpan + 1)^3 cells
  // of its level.
  static constexpr std::int64_t kMaxBoxSpan = 4;
  // grow() polls every so many slots: a few hundred microseconds of rehashing.
  static constexpr std::size_t kGrowPollEvery = 1 << 14;
  static constexpr double kLevelRatio = 4;
  // Crowding::split: a cell splits past 128 points, about 20 times what a cell two edges wide
  // holds on a surface meshed evenly (about 7), so that only cells whose edges are several times
  // shorter than the hash is sized for split; four times finer cells hold about 16 times fewer
  // of a surface's points, and four levels reach edges 256 times shorter.
  static constexpr std::size_t kCrowdedCell = 128;
  static constexpr double kSplitRatio = 4;
  static constexpr int kMaxSplitDepth = 4;

  double h_, inv_h_;
  Crowding crowding_ = Crowding::keep;
  int depth_ = 0;  // levels of splitting above this hash
  std::vector<std::unique_ptr<SpatialHash>> finer_;  // Crowding::split: of each split cell
  std::vector<Slot> slots_;
  std::vector<std::vector<int>> ids_;
  std::vector<std::uint64_t> keys_;  // of each occupied cell, as ids_
  std::vector<double> reach_;         // of each cell, as ids_, or fewer (widen_reach)
  std::unique_ptr<SpatialHash> coarser_;  // created by the first box too wide for this level
  std::optional<CancelToken> cancel_;
};

}  // namespace cdp::adaptive
