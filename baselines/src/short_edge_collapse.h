// Removes the degenerate triangles cell-partitioning methods make where the surface passes
// (nearly) through a lattice corner: every crossed edge at that corner gets a vertex next to the
// corner, and the triangles joining them have edges a millionth of a cell long.
#pragma once

#include <cdp/core/mesh.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace cdp::marching {

struct CollapseReport {
  std::size_t collapsed_edges = 0;
  std::size_t dropped_components = 0;  // closed pieces no longer than min_length: below the lattice
  std::size_t short_edges_left = 0;    // edges under min_length no collapse could remove
};

// Collapses every edge shorter than min_length, shortest first, by merging one end into the
// other, which keeps its position (so vertices stay on the surface); the end kept is the one
// whose new triangles are best shaped. A collapse is made only when it keeps the mesh a closed,
// oriented 2-manifold of the same topology (the link condition of Dey et al.: the two ends share
// no neighbour but the two opposite corners of the edge's triangles) and folds no triangle over
// (each moved triangle keeps the side its normal points to). A short edge these rules block is
// unblocked, where possible, by first merging a nearby vertex of its triangles (within ten
// times min_length) into one of its ends. Vertices on an open boundary are never merged. Then a
// component all of whose edges are shorter than min_length (a cap around a
// corner inside which the field is negative by a rounding error) is removed. The order depends
// only on lengths and `keys` (one per vertex, unique, independent of the traversal's order),
// so both traversals give the same triangles. Unreferenced vertices are removed, keeping order;
// mesh.normals and other per-vertex data must be computed afterwards.
CollapseReport collapse_short_edges(Mesh& mesh, const std::vector<std::uint64_t>& keys, double min_length);

}  // namespace cdp::marching
