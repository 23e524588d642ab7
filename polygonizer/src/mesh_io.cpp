// OpenMesh's readers and writers register themselves through MeshIO.hh, which must come first.
#include <OpenMesh/Core/IO/MeshIO.hh>

#include <polygonizer/errors.h>
#include <polygonizer/mesh_io.h>

#include <unistd.h>

#include <system_error>

namespace cdp {

namespace {

OpenMesh::Vec3d to_om(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
Vec3 from_om(const OpenMesh::Vec3d& v) { return {v[0], v[1], v[2]}; }

}  // namespace

TriMesh to_openmesh(const Mesh& mesh) {
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

void write_mesh(const Mesh& mesh, const std::filesystem::path& path, bool binary) {
  TriMesh om = to_openmesh(mesh);
  OpenMesh::IO::Options opts;
  if (mesh.normals.size() == mesh.positions.size()) opts += OpenMesh::IO::Options::VertexNormal;
  const std::string ext = path.extension().string();
  if (binary && (ext == ".ply" || ext == ".stl" || ext == ".off")) opts += OpenMesh::IO::Options::Binary;
  if (ext == ".ply" && !mesh.vertex_scalars.empty()) opts += OpenMesh::IO::Options::Custom;
  // Write next to the target and rename, so that a failure never leaves a half-written file.
  std::filesystem::path tmp = path;
  std::string tmp_name = ".";
  tmp_name += path.stem().string();
  tmp_name += ".tmp" + std::to_string(getpid()) + ext;
  tmp.replace_filename(tmp_name);
  if (!OpenMesh::IO::write_mesh(om, tmp.string(), opts)) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw InvalidInputError(path.string() + ": cannot write mesh (unsupported extension or unwritable folder)");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw InvalidInputError(path.string() + ": cannot write mesh: " + ec.message());
  }
}

Mesh read_mesh(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InvalidInputError(path.string() + ": file not found");
  TriMesh om;
  om.request_vertex_normals();
  OpenMesh::IO::Options opts = OpenMesh::IO::Options::VertexNormal;
  // PLY only: OpenMesh's PLY reader turns every extra vertex property into a named property.
  if (path.extension() == ".ply") opts += OpenMesh::IO::Options::Custom;
  if (!OpenMesh::IO::read_mesh(om, path.string(), opts))
    throw InvalidInputError(path.string() + ": cannot read mesh (unsupported or malformed file)");
  Mesh mesh = from_openmesh(om);
  if (!opts.check(OpenMesh::IO::Options::VertexNormal)) mesh.normals.clear();
  // Scalar vertex properties (double or float in the file) become vertex_scalars, as written.
  for (auto it = om.vprops_begin(); it != om.vprops_end(); ++it) {
    if (!*it) continue;
    const std::string name = (*it)->name();
    std::vector<double> values;
    values.reserve(om.n_vertices());
    if (OpenMesh::VPropHandleT<double> hd; om.get_property_handle(hd, name)) {
      for (auto v : om.vertices()) values.push_back(om.property(hd, v));
    } else if (OpenMesh::VPropHandleT<float> hf; om.get_property_handle(hf, name)) {
      for (auto v : om.vertices()) values.push_back(om.property(hf, v));
    } else {
      continue;
    }
    mesh.vertex_scalars[name] = std::move(values);
  }
  return mesh;
}

}  // namespace cdp
