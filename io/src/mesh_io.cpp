// OpenMesh's readers and writers register themselves through MeshIO.hh, which must come first.
#include <OpenMesh/Core/IO/MeshIO.hh>

#include "mesh_formats/mesh_formats.h"

#include <cdp/core/errors.h>
#include <cdp/io/atomic_write.h>
#include <cdp/io/mesh_io.h>

#include <cctype>
#include <cerrno>
#include <fstream>
#include <iterator>
#include <sstream>
#include <system_error>

namespace cdp {

namespace {

// OpenMesh's own log lines ("[OBJWriter] : write file", "[PLYWriter] : cannot write to stream")
// would interleave with the programs' one-line messages; failures reach the caller as
// exceptions instead. Done once, before the first use of OpenMesh's readers or writers.
void silence_openmesh() {
  static const bool done = [] {
    omlog().disable();
    omout().disable();
    omerr().disable();
    return true;
  }();
  (void)done;
}

OpenMesh::Vec3d to_om(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
Vec3 from_om(const OpenMesh::Vec3d& v) { return {v[0], v[1], v[2]}; }

}  // namespace

TriMesh to_openmesh(const Mesh& mesh) {
  silence_openmesh();
  TriMesh om;
  std::vector<TriMesh::VertexHandle> vh;
  vh.reserve(mesh.positions.size());
  for (const auto& p : mesh.positions) vh.push_back(om.add_vertex(to_om(p)));
  if (mesh.normals.size() == mesh.positions.size())
    for (std::size_t i = 0; i < vh.size(); ++i) om.set_normal(vh[i], to_om(mesh.normals[i]));
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || static_cast<std::size_t>(t[k]) >= vh.size())
        throw InvalidInputError("mesh: triangle " + std::to_string(f) + " has an out-of-range vertex index");
    if (!om.add_face(vh[t[0]], vh[t[1]], vh[t[2]]).is_valid())
      throw InvalidInputError("mesh: triangle " + std::to_string(f) +
                              " makes a non-manifold configuration that OpenMesh cannot represent");
  }
  for (const auto& [name, values] : mesh.vertex_scalars) {
    if (values.size() != mesh.positions.size()) continue;
    OpenMesh::VPropHandleT<double> prop;
    om.add_property(prop, name);
    om.property(prop).set_persistent(true);
    for (std::size_t i = 0; i < vh.size(); ++i) om.property(prop, vh[i]) = values[i];
  }
  return om;
}

Mesh from_openmesh(const TriMesh& om) {
  Mesh mesh;
  mesh.positions.reserve(om.n_vertices());
  for (auto v : om.vertices()) mesh.positions.push_back(from_om(om.point(v)));
  if (om.has_vertex_normals()) {
    mesh.normals.reserve(om.n_vertices());
    for (auto v : om.vertices()) mesh.normals.push_back(from_om(om.normal(v)));
  }
  mesh.triangles.reserve(om.n_faces());
  for (auto f : om.faces()) {
    std::array<int, 3> t{};
    int k = 0;
    for (auto v : om.fv_range(f)) {
      if (k == 3) throw InvalidInputError("mesh: face " + std::to_string(f.idx()) + " is not a triangle");
      t[k++] = v.idx();
    }
    mesh.triangles.push_back(t);
  }
  return mesh;
}

namespace {

std::string extension_of(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

void write_mesh(const Mesh& mesh, const std::filesystem::path& path, bool binary) {
  const std::string ext = extension_of(path);
  // PLY, OBJ and OFF go to the file in pieces (never the whole file in memory beside the mesh).
  if (ext == ".ply" || ext == ".obj" || ext == ".off") {
    write_file_atomically(
        path,
        [&](const ByteSink& append) {
          if (ext == ".ply") formats::write_ply(mesh, binary, append);
          else if (ext == ".obj") formats::write_obj(mesh, append);
          else formats::write_off(mesh, append);
        },
        "mesh");
    return;
  }
  std::string bytes;
  if (ext == ".stl") {
    // STL is float32 by definition; OpenMesh writes it.
    silence_openmesh();
    TriMesh om = to_openmesh(mesh);
    OpenMesh::IO::Options opts;
    if (binary) opts += OpenMesh::IO::Options::Binary;
    std::ostringstream out;
    if (!OpenMesh::IO::write_mesh(om, out, ".stl", opts))
      throw InvalidInputError(path.string() + ": cannot write mesh (OpenMesh's STL writer failed)");
    bytes = out.str();
  } else {
    throw InvalidInputError(path.string() + ": cannot write mesh: unsupported extension \"" + ext +
                            "\" (.ply, .obj, .off or .stl)");
  }
  write_file_atomically(path, bytes, "mesh");
}

Mesh read_mesh(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) throw FileError(name + ": file not found", ec ? ec.value() : ENOENT);
  if (std::filesystem::is_directory(status)) throw FileError(name + ": is a directory, not a mesh file", EISDIR);
  const std::string ext = extension_of(path);
  if (ext != ".ply" && ext != ".obj" && ext != ".off" && ext != ".stl")
    throw InvalidInputError(name + ": unsupported mesh format \"" + ext + "\" (.ply, .obj, .off or .stl)");
  if (ext == ".stl") {
    silence_openmesh();
    TriMesh om;
    OpenMesh::IO::Options read;
    if (!OpenMesh::IO::read_mesh(om, name, read)) throw InvalidInputError(name + ": cannot read mesh (malformed STL file)");
    Mesh mesh = from_openmesh(om);
    // STL stores face normals only. The traits give every TriMesh a vertex normal property,
    // which the reader leaves as allocated: uninitialised values, sometimes NaN, that were
    // returned as the file's normals (and then refused by check_mesh at random).
    if (!read.vertex_has_normal()) mesh.normals.clear();
    formats::check_mesh(mesh, name);
    return mesh;
  }
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in.is_open()) {
    const int err = errno != 0 ? errno : EIO;
    throw FileError(name + ": cannot read the file", err);
  }
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw FileError(name + ": cannot read the file", EIO);
  if (ext == ".ply") return formats::read_ply(bytes, name);
  if (ext == ".obj") return formats::read_obj(bytes, name);
  return formats::read_off(bytes, name);
}

OrientedPoints read_oriented_points(const std::filesystem::path& path) {
  return oriented_points_from_mesh(read_mesh(path), path.string());
}

}  // namespace cdp
