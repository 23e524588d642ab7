// The mesh file formats the project reads and writes itself (PLY, OBJ, OFF), in double
// precision. OpenMesh 9 (Debian 12) passes every coordinate through float on both reading and
// writing, which loses a torus centred at 1e6 and a sphere of radius 1e-6; these formats are
// simple enough to write exactly. STL stays with OpenMesh (the format itself is float32).
// Internal to mesh_io.cpp: the public interface is <cdp/io/mesh_io.h>.
#pragma once

#include <cdp/core/mesh.h>

#include <string>
#include <string_view>

namespace cdp::formats {

// Readers take the whole file's bytes and the file's name for messages; they throw
// InvalidInputError "NAME: problem" on anything malformed, never read past the data, and never
// allocate more than the data can fill (a header that declares a billion vertices is an error,
// not a std::bad_alloc).
Mesh read_ply(std::string_view data, const std::string& name);
Mesh read_obj(std::string_view data, const std::string& name);
Mesh read_off(std::string_view data, const std::string& name);

// Writers return the file's bytes. Coordinates, normals and vertex scalars are written so that
// reading them back gives the same doubles bit for bit (binary float64 in PLY; the shortest
// round-trip decimal in OBJ, OFF and ASCII PLY).
std::string write_ply(const Mesh& mesh, bool binary);
std::string write_obj(const Mesh& mesh);
std::string write_off(const Mesh& mesh);

// The shortest decimal text that reads back as the same double.
std::string shortest_decimal(double v);

// Checks shared by the readers: finite coordinates, indices in range, at least one triangle.
void check_mesh(const Mesh& mesh, const std::string& name);

}  // namespace cdp::formats
