// Mesh files (PLY, OBJ, OFF, STL, by extension), and conversion to and from OpenMesh's TriMesh
// for users who want its half-edge structure. PLY, OBJ and OFF are read and written here in
// double precision (OpenMesh 9 passes coordinates through float); STL goes through OpenMesh.
#pragma once

#include <cdp/core/mesh.h>
#include <cdp/core/oriented_points.h>

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
// \throw InvalidInputError for a triangle with an out-of-range vertex index, or one OpenMesh refuses.
TriMesh to_openmesh(const Mesh& mesh);
// \return its positions, triangles and vertex normals (always: OpenMeshTraits gives every TriMesh
//         the property, set or not); no vertex scalars.
// \throw InvalidInputError for a face that is not a triangle.
Mesh from_openmesh(const TriMesh& mesh);

// Writes positions, normals (when present), triangles and, to PLY, the vertex scalars; the
// format follows the extension. PLY is binary little-endian float64 (ASCII with binary =
// false), OBJ and OFF are text with the shortest decimals that read back as the same doubles:
// reading a written mesh gives it back bit for bit. Goes through write_file_atomically.
// \throw InvalidInputError (FileError) "PATH: cannot write mesh: reason" for a failure (full
//        disk, unwritable folder), which leaves no file behind.
// \throw InvalidInputError for an extension other than .ply, .obj, .off and .stl; for .stl also as
//        to_openmesh, or when OpenMesh's STL writer fails.
void write_mesh(const Mesh& mesh, const std::filesystem::path& path, bool binary = true);
// Reads positions, triangles (polygons become fans) and vertex normals (when the file has them
// for every vertex); from PLY files also every other scalar vertex property, into
// vertex_scalars under its name.
// \throw InvalidInputError "PATH: problem" for a missing file, a directory, an unknown
//        extension, a malformed or truncated file, a count the file cannot hold, a non-finite
//        coordinate, a face index out of range, and a mesh without faces.
// \throw FileError (the InvalidInputError above) for a missing file, a directory, or a file that
//        cannot be opened or read.
Mesh read_mesh(const std::filesystem::path& path);

// Reads a mesh file (read_mesh) and takes its oriented points (oriented_points_from_mesh), the
// input of the VIS and MPU models. InvalidInputError, naming the file, when it is missing,
// unreadable, or has no oriented vertex.
// \throw FileError and InvalidInputError as read_mesh; InvalidInputError "PATH: problem" as
//        oriented_points_from_mesh when no vertex is left.
OrientedPoints read_oriented_points(const std::filesystem::path& path);

}  // namespace cdp
