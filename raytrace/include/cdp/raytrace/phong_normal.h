// The normal a Phong shader sees: vertex normals blended with the hit's barycentric coordinates.
#pragma once

#include <cdp/core/field.h>
#include <cdp/core/mesh.h>

#include <array>
#include <vector>

namespace cdp {

// normalize((1-u-v) n0 + u n1 + v n2) of triangle `triangle`; zero when the blend vanishes
// (opposite vertex normals). Requires mesh.normals; the triangle's corner normals replace them
// when the mesh has them (Mesh::corner_normals).
// \pre the triangle's vertex indices are in range.
// \throw InvalidInputError when the mesh has no normal per vertex (corner normals or not).
// \throw std::out_of_range for a triangle that is not in the mesh.
Vec3 phong_normal(const Mesh& mesh, int triangle, double u, double v);

// Vertex normals as the normalized sum of the incident triangles' area vectors, for meshes
// read without normals; zero for vertices without (non-degenerate) triangles.
// \pre every triangle index is in [0, mesh.num_vertices()).
std::vector<Vec3> area_weighted_normals(const Mesh& mesh);

// Vertex normals from the field: the normalized gradient at each vertex, the exact normal of
// the surface there when the vertex lies on it. What the adaptive method writes; giving every
// mesh these (evaluate --normals field) compares meshes, not normal estimators. Zero where the
// gradient vanishes or is not finite.
// \throw what the field's evaluations throw, unchanged.
std::vector<Vec3> field_normals(const Field& field, const Mesh& mesh);

// For a field with creases (Field::has_pieces): the field's normal at every triangle corner, the
// normal of the piece the triangle lies on where the corner's vertex is on a crease (two or more
// pieces within kCornerPieceRadius of the diagonal), the vertex's entry of `vertex_normals`
// elsewhere. So that a mesh whose edges follow a crease is shaded and measured with each side's
// normal rather than their blend; a mesh whose vertices miss the creases gets its vertex normals.
// Empty for a field without creases.
// \pre every triangle index is in [0, mesh.num_vertices()).
// \return three normals per triangle, in order.
// \throw std::out_of_range when vertex_normals has no entry for a vertex a triangle uses.
// \throw what the field's evaluations throw, unchanged.
std::vector<std::array<Vec3, 3>> field_corner_normals(const Field& field, const Mesh& mesh,
                                                      const std::vector<Vec3>& vertex_normals);

}  // namespace cdp
