// Oriented points (positions with outward unit normals) taken from a triangle mesh, the input of
// the data-driven models (models/vis.h, models/mpu.h), and a deterministic evenly spread subset.
// Reading them from a mesh file is cdp::io's (read_oriented_points in <cdp/io/mesh_io.h>).
#pragma once

#include <cdp/core/field.h>
#include <cdp/core/mesh.h>

#include <cstddef>
#include <string>
#include <vector>

namespace cdp {

struct OrientedPoints {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;  // unit length, pointing outward (towards F > 0)

  std::size_t size() const { return positions.size(); }
};

// Positions are the mesh's vertices and normals the area-weighted face normals: the sum over the
// triangles around a vertex of their edge cross products (twice the area times the unit normal),
// normalized. Counter-clockwise triangles seen from outside give outward normals. Vertices that
// no triangle uses, or whose summed normal vanishes, are dropped (they have no orientation).
// `source` names the mesh in messages; InvalidInputError when no vertex is left.
// \return the kept vertices (also leaving out those with a non-finite position), in index order.
// \throw InvalidInputError "SOURCE: problem" for a triangle with an out-of-range vertex index, or
//        when no vertex is left.
OrientedPoints oriented_points_from_mesh(const Mesh& mesh, const std::string& source);

// Farthest-point sampling: the first index is the lexicographically smallest position (x, then
// y, then z; the lowest index among equal ones), each next one the point farthest from those
// already chosen (ties to the lowest index). The result spreads evenly over the surface, does
// not depend on the order of the vertices except through ties, and never repeats a position
// while distinct positions remain. O(n * size) time. InvalidInputError when n > size.
// \pre the positions are finite.
// \return n indices into `positions`, in the order chosen.
// \throw InvalidInputError when n > positions.size().
std::vector<std::size_t> farthest_point_subset(const std::vector<Vec3>& positions, std::size_t n);

// The points at `indices`, in that order.
// \throw std::out_of_range for an index past the positions or the normals.
OrientedPoints select_points(const OrientedPoints& points, const std::vector<std::size_t>& indices);

// The smallest axis-aligned box holding the positions (invalid for no points).
Box bounding_box(const std::vector<Vec3>& positions);

}  // namespace cdp
