// Self-intersections of a triangle mesh without Embree: an exact triangle-triangle test (double
// predicates with Shewchuk's error bounds and an exact fallback) and a hash-grid broad phase, so
// the core can check its own output. <cdp/raytrace/self_intersection.h> runs the same exact test
// behind Embree's rtcCollide; the rules and limits are in raytrace/README.md.
#pragma once

#include <cdp/core/cancel.h>
#include <cdp/core/mesh.h>

#include <array>
#include <cstddef>
#include <utility>
#include <vector>

namespace cdp {

// Whether the three points are collinear (zero area), decided exactly.
bool triangle_is_degenerate(const Vec3& a, const Vec3& b, const Vec3& c);

// The exact test, for triangles given by their corners. Vertices are shared when their positions
// are equal (same index or bit-identical coordinates). Closed triangles intersect when they have
// a point in common that is not in the convex hull of their shared vertices:
//  - no shared vertex: any contact (a touching vertex or edge, a crossing, a coplanar overlap);
//  - one shared vertex: any common point other than that vertex;
//  - a shared edge: only when both lie in one plane on the same side of the edge (folded flat
//    onto each other); triangles in different planes meet only along the line of the edge;
//  - three shared vertices (a duplicated triangle, either orientation): always.
// Degenerate triangles (see triangle_is_degenerate) never intersect anything here. Throws
// InvalidInputError on non-finite corners.
// \throw InvalidInputError when a corner is not finite.
bool triangles_intersect(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b);
// The same for triangles f and g of a mesh (f != g). Throws InvalidInputError on bad indices.
// \throw InvalidInputError when f or g is not a triangle of the mesh, f == g, one of their vertex
//        indices is out of range, or one of their corners is not finite.
bool triangles_intersect(const Mesh& mesh, int f, int g);

// Every intersecting pair (f, g), f < g, of distinct triangles (see triangles_intersect), found
// by a hash grid over the triangles' bounding boxes (cells about twice the median longest edge; the
// few triangles much larger than a cell are tested against all): the first max_pairs of them in
// lexicographic order. Every pair whose boxes overlap is decided exactly once: by the exact test,
// or, for a pair sharing a vertex whose star is proved to be a flat fan (one that projects
// one-to-one onto a plane), without it, since such a pair cannot intersect. Meshes of 2048
// triangles or more are searched on `threads` threads (0: all cores, at most 8); the result is
// the same on any number. Deterministic, no output; memory linear in the number of triangles (plus max_pairs), time
// linear for triangles of similar sizes. Throws InvalidInputError on out-of-range indices or
// non-finite positions (of vertices that triangles use); LimitExceededError when the grid would
// hold 2^32 entries (beyond 67 million triangles).
// `cancel`, when given, is polled every few thousand triangles or buckets (\throw CancelledError).
// \throw InvalidInputError as triangle_boxes_for_intersection.
// \throw LimitExceededError when the hash grid would hold 2^32 entries.
std::vector<std::pair<int, int>> self_intersecting_pairs(const Mesh& mesh, std::size_t max_pairs = 16,
                                                         int threads = 0, const CancelToken* cancel = nullptr);
// self_intersecting_pairs among the pairs with at least one triangle whose flag in `involved` is
// set (one flag per triangle): for a caller who knows the others apart (the adaptive
// polygonizer's blocks, each checked on its own, whose triangles lie strictly inside them).
// \throw InvalidInputError for a flag count other than the triangle count, and as
//        self_intersecting_pairs; LimitExceededError as self_intersecting_pairs.
std::vector<std::pair<int, int>> self_intersecting_pairs_involving(const Mesh& mesh, const std::vector<char>& involved,
                                                                   std::size_t max_pairs = 16, int threads = 0,
                                                                   const CancelToken* cancel = nullptr);
// The number of such pairs (the same search).
// \throw InvalidInputError and LimitExceededError as self_intersecting_pairs.
std::size_t count_self_intersecting_pairs(const Mesh& mesh, int threads = 0);

// ---- For broad phases (self_intersecting_pairs here, Embree's in <cdp/raytrace/self_intersection.h>).

// Each triangle's bounding box, empty (min > max) for degenerate triangles, which take part in no
// pair; `degenerate`, when given, receives their number. Throws InvalidInputError (naming `what`)
// on out-of-range indices or non-finite positions. Triangles with a common point have
// overlapping boxes (closed, touching included), so a broad phase on these boxes loses no pair.
// \return one box per triangle, in order.
// \throw InvalidInputError "WHAT: problem" for more than INT_MAX triangles, an out-of-range vertex
//        index, or a non-finite position of a vertex that a triangle uses.
std::vector<Box> triangle_boxes_for_intersection(const Mesh& mesh, std::size_t* degenerate = nullptr,
                                                 const char* what = "self-intersections");

// triangles_intersect without its checks, for candidates whose corners are known to be finite
// and whose triangles are not degenerate (non-empty boxes above).
// \pre every corner is finite and neither triangle is degenerate (triangle_is_degenerate).
bool nondegenerate_triangles_intersect(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b);

// A floating-point filter before the exact test, for two triangles (s, a1, a2) and (s, b1, b2)
// that share exactly the vertex s: true only when a plane through s has a1 and a2 strictly on
// one side and b1 and b2 strictly on the other, so that the triangles meet only at s, which
// triangles_intersect does not count. Decides no sign that rounding could flip; false when
// unsure, for corners that are not finite, and for coordinates so small that products underflow.
// The plane's normal is the difference of the triangles' mean directions from s: it separates
// two angles at s whose bisectors are more than twice the wider half-angle apart, as two
// triangles of one fan with a triangle between them are (the pairs a local intersection test
// meets most, each straddling the other's plane).
bool apart_at_shared_vertex(const Vec3& s, const Vec3& a1, const Vec3& a2, const Vec3& b1, const Vec3& b2);

}  // namespace cdp
