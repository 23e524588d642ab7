// The project's triangle mesh: plain indexed arrays, what every polygonizer produces and every
// metric reads. Connectivity (triangles) is kept apart from geometry (positions, normals).
// Conversion to OpenMesh and file I/O are cdp::io's (<cdp/io/mesh_io.h>).
#pragma once

#include <cdp/core/field.h>

#include <array>
#include <map>
#include <string>
#include <vector>

namespace cdp {

struct Mesh {
  std::vector<Vec3> positions;
  // Per vertex, unit length (zero where the field's gradient was zero or NaN); empty if
  // not computed.
  std::vector<Vec3> normals;
  std::vector<std::array<int, 3>> triangles;    // counter-clockwise seen from outside
  // Normals per triangle corner, for vertices on a crease of the surface (one normal per side);
  // empty when the vertex normals serve. Where given, they replace `normals` for shading and the
  // Phong error (raytrace's phong_normal). Not written to files.
  std::vector<std::array<Vec3, 3>> corner_normals;
  std::map<std::string, std::vector<double>> vertex_scalars;  // e.g. "mac", "shape_index"

  std::size_t num_vertices() const { return positions.size(); }
  std::size_t num_triangles() const { return triangles.size(); }
};

// Sets mesh.normals to the normalized field gradient at every vertex (one value_gradient each,
// evaluated in batches).
// \throw what the field's evaluations throw, unchanged.
void compute_field_normals(const Field& field, Mesh& mesh);

}  // namespace cdp
