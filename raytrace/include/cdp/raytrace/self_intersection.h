// Self-intersections of a triangle mesh: pairs of triangles that meet anywhere other than at the
// vertices or the edge they share. Embree's rtcCollide on the triangles' bounding boxes gives the
// candidate pairs (src/box_overlaps.cpp); the core's exact triangle-triangle test decides each
// (<cdp/core/triangle_intersection.h>, which this header includes; the rules and limits are in
// raytrace/README.md). The core also has a broad phase without Embree (self_intersecting_pairs).
#pragma once

#include <cdp/core/mesh.h>
#include <cdp/core/triangle_intersection.h>

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

// Every intersecting pair of distinct triangles (see triangles_intersect in
// <cdp/core/triangle_intersection.h>). Deterministic and independent of the thread count; no
// output. Throws InvalidInputError on out-of-range indices or non-finite positions.
// \return the number of pairs, the first max_examples of them, the degenerate triangles and the
//         candidate pairs.
// \throw InvalidInputError as triangle_boxes_for_intersection and overlapping_box_pairs.
// \throw std::bad_alloc as overlapping_box_pairs.
SelfIntersectionReport find_self_intersections(const Mesh& mesh, std::size_t max_examples = 16);

// The broad phase: every pair (i, j), i < j, of boxes that overlap (closed boxes, touching
// counts), sorted. Embree's rtcCollide on user geometries gives candidates from float boxes
// (mapped to [-1, 1]^3, rounded outwards and inflated by 2^-20, so none is lost); each is then
// checked on the double boxes, so the result is exact. Empty boxes (min > max on an axis) take
// part in no pair; non-finite boxes throw InvalidInputError. Independent of the thread count.
// \throw InvalidInputError for more than INT_MAX boxes, a box that is not finite, boxes whose extent
//        overflows double, or when Embree fails (no device, an error building or colliding).
// \throw std::bad_alloc when collecting Embree's pairs fails.
std::vector<std::pair<int, int>> overlapping_box_pairs(const std::vector<Box>& boxes);

}  // namespace cdp
