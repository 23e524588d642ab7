// Surface a finished mesh does not cover: a front that crossed a neck narrower than its edges and
// closed on each side of it leaves two closed components where the surface has one, facing each
// other across the solid, and every other check passes (closed, manifold, no intersection, each
// seed one component). The blob fields of results/topology_sweep.md came out so with exit 0.
#pragma once

#include <cdp/core/field.h>
#include <cdp/core/mesh.h>

#include <optional>
#include <vector>

namespace cdp::adaptive {

// Two vertices of different components facing each other across the solid: close together
// (within twice the longest edge at each), each inward of the other's side (the segment between
// them leaves each through its inside), the field negative along the segment (sampled at a
// quarter, half and three quarters). A cut neck shows so; so does a shell thinner than two
// edges, whose two walls are separate surfaces. At most `per_component_pair` pairs for each two
// components, in vertex order.
struct FacingPair {
  int a = -1, b = -1;
};
std::vector<FacingPair> facing_across_solid(const Field& field, const Mesh& mesh, int per_component_pair);

// Whether surface points a and b are joined by the zero set of the field near them: the cells where
// F changes sign, of a grid of step |b - a| / kJoinCellsPerGap over their bounding box grown by
// |b - a| (clipped to the field's box), flood-filled (26-neighbours) from a's cell, reach b's.
// Across a neck the wall between two caps joins them; the two walls of a shell are not joined.
bool joined_by_surface(const Field& field, const Vec3& a, const Vec3& b);

// The largest distance F / |grad F| of a triangle's centroid to the surface, as a share of the
// triangle's longest edge, over the triangles whose centroids lie within radius of center.
double deepest_triangle_near(const Field& field, const Mesh& mesh, const Vec3& center, double radius);

// The midpoint of a facing pair whose ends the surface joins, with a cap beside it (a triangle
// deeper than kCapDepth of its edge within the pair's length of its midpoint): the mesh left the
// surface between two of its components uncovered there. Tests at most kJoinTestsPerComponentPair
// facing pairs for each two components.
std::optional<Vec3> uncovered_between_components(const Field& field, const Mesh& mesh);

}  // namespace cdp::adaptive
