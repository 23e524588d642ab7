// The crossing of F = 0 on a lattice edge, by a bracketed root search.
#pragma once

#include <cdp/core/field.h>

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

}  // namespace cdp::marching
