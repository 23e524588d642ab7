// Mesh files through OpenMesh (PLY, OBJ, OFF, STL, by extension), and conversion to and from
// OpenMesh's TriMesh for users who want its half-edge structure.
#pragma once

#include <polygonizer/mesh.h>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <filesystem>

namespace cdp {

struct OpenMeshTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
  VertexAttributes(OpenMesh::Attributes::Normal);
};
using TriMesh = OpenMesh::TriMesh_ArrayKernelT<OpenMeshTraits>;

// Throws InvalidInputError when OpenMesh refuses a triangle (a non-manifold configuration).
// Vertex scalars become double vertex properties of the same names.
TriMesh to_openmesh(const Mesh& mesh);
Mesh from_openmesh(const TriMesh& mesh);

// Writes positions, normals (when present) and triangles; the format follows the extension.
// Writes to a temporary file and renames it, so a failure leaves no half-written file.
void write_mesh(const Mesh& mesh, const std::filesystem::path& path, bool binary = true);
// Reads positions, triangles and vertex normals (when the file has them); from PLY files also
// the scalar (double or float) vertex properties, into vertex_scalars under their names.
// Throws InvalidInputError "FILE: problem" for anything it cannot read whole (polygonizer/README.md).
// Redirects std::cerr while OpenMesh reads: not to be called concurrently.
Mesh read_mesh(const std::filesystem::path& path);

}  // namespace cdp
