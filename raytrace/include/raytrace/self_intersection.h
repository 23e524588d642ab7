// Self-intersections of a triangle mesh: pairs of triangles that meet anywhere other than at the
// vertices or the edge they share. Embree's rtcCollide on the triangles' bounding boxes gives the
// candidate pairs (src/box_overlaps.cpp); an exact triangle-triangle test decides each
// (src/self_intersection.cpp; the rules and limits are in raytrace/README.md).
#pragma once

#include <polygonizer/mesh.h>

#include <array>
#include <cstddef>
#include <utility>
#include <vector>

namespace cdp {

struct SelfIntersectionReport {
  std::size_t pairs = 0;                     // intersecting pairs of triangles
  std::vector<std::pair<int, int>> examples; // the first pairs (f < g) in lexicographic order
  std::size_t degenerate_triangles = 0;      // zero-area triangles, left out of the test
  std::size_t candidate_pairs = 0;           // pairs whose bounding boxes overlap (all tested)
};

// Every intersecting pair of distinct triangles (see triangles_intersect). Deterministic and
// independent of the thread count; no output. Throws InvalidInputError on out-of-range indices
// or non-finite positions.
SelfIntersectionReport find_self_intersections(const Mesh& mesh, std::size_t max_examples = 16);

// The exact test find_self_intersections applies to each candidate pair, for triangles given by
// their corners. Vertices are shared when their positions are equal (same index or bit-identical
// coordinates). Closed triangles intersect when they have a point in common that is not in the
// convex hull of their shared vertices:
//  - no shared vertex: any contact (a touching vertex or edge, a crossing, a coplanar overlap);
//  - one shared vertex: any common point other than that vertex;
//  - a shared edge: only when both lie in one plane on the same side of the edge (folded flat
//    onto each other); triangles in different planes meet only along the line of the edge;
//  - three shared vertices (a duplicated triangle, either orientation): always.
// Degenerate triangles (see triangle_is_degenerate) never intersect anything here.
bool triangles_intersect(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b);
// The same for triangles f and g of a mesh (f != g). Throws InvalidInputError on bad indices.
bool triangles_intersect(const Mesh& mesh, int f, int g);

// Whether the three points are collinear (zero area), decided exactly.
bool triangle_is_degenerate(const Vec3& a, const Vec3& b, const Vec3& c);

// The broad phase: every pair (i, j), i < j, of boxes that overlap (closed boxes, touching
// counts), sorted. Embree's rtcCollide on user geometries gives candidates from float boxes
// (mapped to [-1, 1]^3, rounded outwards and inflated by 2^-20, so none is lost); each is then
// checked on the double boxes, so the result is exact. Empty boxes (min > max on an axis) take
// part in no pair; non-finite boxes throw InvalidInputError. Independent of the thread count.
std::vector<std::pair<int, int>> overlapping_box_pairs(const std::vector<Box>& boxes);

}  // namespace cdp
