// The mesh file formats the project reads and writes itself (PLY, OBJ, OFF), in double
// precision. OpenMesh 9 (Debian 12) passes every coordinate through float on both reading and
// writing, which loses a torus centred at 1e6 and a sphere of radius 1e-6; these formats are
// simple enough to write exactly. STL stays with OpenMesh (the format itself is float32).
// Internal to mesh_io.cpp: the public interface is <cdp/io/mesh_io.h>.
#pragma once

#include <cdp/core/mesh.h>
#include <cdp/io/atomic_write.h>

#include <cstddef>
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

// Writers hand the file's bytes to `sink` in pieces of about kWritePiece bytes, in order, so that
// a large mesh's file is never held whole (write_file_atomically's ByteSink). Coordinates,
// normals and vertex scalars are written so that reading them back gives the same doubles bit
// for bit (binary float64 in PLY; the shortest round-trip decimal in OBJ, OFF and ASCII PLY).
void write_ply(const Mesh& mesh, bool binary, const ByteSink& sink);
void write_obj(const Mesh& mesh, const ByteSink& sink);
void write_off(const Mesh& mesh, const ByteSink& sink);

// A megabyte: a few hundred system calls for a mesh of 10^7 triangles.
inline constexpr std::size_t kWritePiece = std::size_t{1} << 20;

// The writers' buffer: `out` grows by a record at a time and goes to the sink whenever it holds
// kWritePiece bytes (`record_done`), the rest at `finish`.
class PieceWriter {
 public:
  explicit PieceWriter(const ByteSink& sink) : sink_(sink) { out.reserve(kWritePiece + 4096); }
  void record_done() {
    if (out.size() >= kWritePiece) finish();
  }
  void finish() {
    if (!out.empty()) sink_(out);
    out.clear();
  }
  std::string out;

 private:
  const ByteSink& sink_;
};

// The shortest decimal text that reads back as the same double.
std::string shortest_decimal(double v);

// Checks shared by the readers: finite coordinates, indices in range, at least one triangle.
void check_mesh(const Mesh& mesh, const std::string& name);

}  // namespace cdp::formats
