// The crossing of F = 0 on a lattice edge, by a bracketed root search.
#pragma once

#include <cdp/core/field.h>

#include <cstddef>
#include <span>
#include <vector>

namespace cdp::marching {

struct EdgeRoot {
  Vec3 point;
  int evaluations = 0;
};

// F(a) = fa and F(b) = fb lie on different sides (exactly one of them < 0). Illinois regula
// falsi on the segment, falling back to bisection whenever the bracket fails to halve in two
// steps, until the bracket is at most tolerance / 2 long; the point returned is the linear
// interpolation inside the final bracket, kept at least min(tolerance / 2, |b - a| / 1000) from
// both ends so that no vertex lands exactly on a lattice corner. So it lies within `tolerance`
// of a crossing, measured along the edge. NoSurfaceError if F is not finite on the edge.
EdgeRoot find_edge_root(const Field& field, const Vec3& a, double fa, const Vec3& b, double fb, double tolerance);

// One edge's search of find_edge_root, taken apart into probes and answers, so that many edges
// can be searched in lockstep (each round one batched evaluation of the edges still searching)
// with the very arithmetic of a single search.
class EdgeRootSearch {
 public:
  EdgeRootSearch(const Vec3& a, double fa, const Vec3& b, double fb, double tolerance);
  // Whether the search wants another value; if so, F at probe() is to be given to take().
  bool searching() const { return searching_; }
  Vec3 probe() const { return a_ + t_ * d_; }
  // F at probe(). False (and the search over) when it is not finite.
  bool take(double ft);
  // The crossing, once the search is over.
  Vec3 point() const;
  int evaluations() const { return evaluations_; }

 private:
  // Computes the next probe, or ends the search.
  void advance();

  Vec3 a_, d_;
  double len_ = 0, tolerance_ = 0, stop_width_ = 0, nudge_ = 0;
  // Bracket [lo, hi] in the edge parameter; `lo_inside_` is the side of lo (hi is the other).
  // The Illinois method halves the kept end's value, so signs are tracked apart from values.
  double lo_ = 0, hi_ = 1, flo_ = 0, fhi_ = 0, raw_lo_ = 0, raw_hi_ = 0, t_ = 0;
  bool lo_inside_ = false, searching_ = true;
  int last_kept_ = 0;  // -1: lo moved last time, +1: hi moved
  int slow_steps_ = 0, iterations_ = 0, evaluations_ = 0;
};

struct EdgeRootQuery {
  Vec3 a, b;
  double fa = 0, fb = 0;
};

// find_edge_root on every query with one tolerance, the searches in lockstep: each round
// evaluates the probes of the searches still running in one batched `values` call, so that a
// field whose calls cost more than its arithmetic (a Python function) is called once a round
// rather than once a probe. Every root is the one find_edge_root gives, bit for bit, with the
// same evaluation count. If F is not finite on some edges, the NoSurfaceError is the one
// find_edge_root throws on the first of them in query order (the others still finish).
void find_edge_roots(const Field& field, std::span<const EdgeRootQuery> queries, double tolerance,
                     std::vector<EdgeRoot>& out);

}  // namespace cdp::marching
