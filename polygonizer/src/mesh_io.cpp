// OpenMesh's readers and writers register themselves through MeshIO.hh, which must come first.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <polygonizer/errors.h>
#include <polygonizer/mesh_io.h>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <new>
#include <sstream>
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

// ---- Reading: what OpenMesh's readers let through ----

namespace {

std::vector<std::string> words(const std::string& line) {
  std::istringstream in(line.substr(0, line.find('#')));  // '#' starts a comment in OBJ and OFF
  std::vector<std::string> w;
  for (std::string t; in >> t;) w.push_back(t);
  return w;
}

// OpenMesh's text readers cannot parse "nan", "inf" or "1e999" and then report something
// unrelated (a bad face index) or nothing at all, so such numbers are refused first, by line.
void check_finite(const std::filesystem::path& path, const std::string& token, std::size_t line) {
  char* end = nullptr;
  const double x = std::strtod(token.c_str(), &end);
  if (end != token.c_str() && *end == '\0' && !std::isfinite(x))
    throw InvalidInputError(path.string() + ": line " + std::to_string(line) + ": \"" + token +
                            "\" is not a finite number");
}

std::size_t ply_type_size(const std::string& type) {
  for (const char* t : {"char", "uchar", "int8", "uint8"})
    if (type == t) return 1;
  for (const char* t : {"short", "ushort", "int16", "uint16"})
    if (type == t) return 2;
  for (const char* t : {"double", "float64"})
    if (type == t) return 8;
  return 4;
}

// Refuses non-finite numbers in text files, and PLY or OFF files whose header declares more
// vertices and faces than the file holds: OpenMesh would reserve memory for the declared counts
// (std::bad_alloc for 1e12 vertices) and its ASCII PLY reader repeats the last face of a
// truncated file. Each entry is counted at its smallest (a face is at least a triangle), in
// numbers for text data and bytes for binary data. Anything else is left to OpenMesh.
void check_mesh_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string ext = path.extension().string();
  std::string text;
  std::size_t line = 0;
  auto next_line = [&] { return std::getline(in, text) && (++line, true); };
  double vertices = 0, faces = 0, needed = 0;  // double: declared counts may be absurdly large
  std::size_t held = 0;
  bool binary = false;
  if (ext == ".obj") {
    while (next_line())
      if (const auto w = words(text); !w.empty() && (w[0] == "v" || w[0] == "vn"))
        for (std::size_t k = 1; k < w.size(); ++k) check_finite(path, w[k], line);
    return;
  }
  if (ext == ".ply") {
    if (!next_line() || words(text) != std::vector<std::string>{"ply"}) return;
    bool face_element = false, ended = false;
    double count = 0;
    while (!ended && next_line()) {
      const auto w = words(text);
      if (w.empty()) continue;
      try {
        if (w[0] == "end_header") ended = true;
        else if (w[0] == "format" && w.size() > 1) binary = w[1] != "ascii";
        else if (w[0] == "element" && w.size() > 2) {
          count = static_cast<double>(std::stoull(w[2]));
          face_element = w[1] == "face";
          if (w[1] == "vertex") vertices = count;
          if (face_element) faces = count;
        } else if (w[0] == "property" && w.size() > 3 && w[1] == "list")
          needed += count * (binary ? ply_type_size(w[2]) + (face_element ? 3 * ply_type_size(w[3]) : 0)
                                    : 1 + (face_element ? 3 : 0));
        else if (w[0] == "property" && w.size() > 1)
          needed += count * (binary ? ply_type_size(w[1]) : 1);
      } catch (const std::exception&) {
        return;  // an unreadable count: OpenMesh's error
      }
    }
    if (!ended) return;
  } else if (ext == ".off") {
    // "OFF" (or COFF, NOFF, ...), then the vertex, face and edge counts, possibly on one line.
    std::vector<std::string> header;
    while (header.size() < 4 && next_line())
      for (const auto& w : words(text)) header.push_back(w);
    if (header.size() < 4 || header[0].size() < 3 || header[0].compare(header[0].size() - 3, 3, "OFF") != 0 ||
        header[0].find('n') != std::string::npos || header[1] == "BINARY")
      return;  // not a text OFF file whose counts this check knows how to read
    try {
      vertices = static_cast<double>(std::stoull(header[1]));
      faces = static_cast<double>(std::stoull(header[2]));
    } catch (const std::exception&) {
      return;
    }
    needed = 3 * vertices + 4 * faces;
    for (std::size_t k = 4; k < header.size(); ++k) check_finite(path, header[k], line), ++held;
  } else {
    return;
  }
  if (faces == 0) throw InvalidInputError(path.string() + ": the mesh has no triangles");
  if (binary) {
    const auto start = in.tellg();
    in.seekg(0, std::ios::end);
    held = static_cast<std::size_t>(in.tellg() - start);
  } else {
    while (next_line())
      for (const auto& w : words(text)) check_finite(path, w, line), ++held;
  }
  if (needed > static_cast<double>(held)) {
    std::ostringstream msg;
    msg.precision(17);
    msg << path.string() << ": the header declares " << vertices << " vertices and " << faces
        << " faces, which need at least " << needed << (binary ? " bytes" : " numbers")
        << ", but the file holds only " << held;
    throw InvalidInputError(msg.str());
  }
}

// OpenMesh reports what it skips (faces with out-of-range or repeated vertex indices) or fails on
// only as text on its log streams, which end in std::cerr. While it reads, std::cerr writes into
// a string instead, so that such text becomes this reader's error rather than a stray line next
// to a silently smaller mesh. std::cerr is global: meshes must not be read concurrently.
class CerrCapture {
 public:
  CerrCapture() : saved_(std::cerr.rdbuf(text_.rdbuf())) {}
  ~CerrCapture() { release(); }
  CerrCapture(const CerrCapture&) = delete;
  CerrCapture& operator=(const CerrCapture&) = delete;
  // The first line written, without OpenMesh's "ImporterT: " or "[PLYReader] : " prefix.
  std::string first_line() {
    release();
    std::string s = text_.str();
    s = s.substr(0, s.find('\n'));
    if (const auto colon = s.find(": "); colon != std::string::npos && colon < 16) s = s.substr(colon + 2);
    return s;
  }

 private:
  void release() {
    if (!saved_) return;
    omerr().flush();
    omlog().flush();
    std::cerr.rdbuf(saved_);
    saved_ = nullptr;
  }
  std::ostringstream text_;
  std::streambuf* saved_;
};

// OpenMesh's words for the faces it skipped (its importer's, then its PLY reader's, which
// counts them first), in ours; any other text as it is.
std::string skipped_faces(const std::string& message, std::size_t vertices) {
  const std::string range = " (the file has " + std::to_string(vertices) + " vertices)";
  if (message.find("invalid vertex index") != std::string::npos) return "a face has an out-of-range vertex index" + range;
  if (message.find("equal vertices") != std::string::npos) return "a face repeats a vertex index";
  if (const auto at = message.find("The reader encountered invalid faces"); at != std::string::npos)
    return message.substr(0, at) + " face(s) with an out-of-range or repeated vertex index" + range;
  return message;
}

}  // namespace

Mesh read_mesh(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InvalidInputError(path.string() + ": file not found");
  TriMesh om;
  om.request_vertex_normals();
  OpenMesh::IO::Options opts = OpenMesh::IO::Options::VertexNormal;
  // PLY only: OpenMesh's PLY reader turns every extra vertex property into a named property.
  if (path.extension() == ".ply") opts += OpenMesh::IO::Options::Custom;
  check_mesh_file(path);
  CerrCapture openmesh_messages;
  bool read = false;
  try {
    read = OpenMesh::IO::read_mesh(om, path.string(), opts);
  } catch (const std::bad_alloc&) {
    throw InvalidInputError(path.string() + ": cannot read mesh: the counts it declares do not fit in memory");
  }
  const std::string message = openmesh_messages.first_line();
  if (!read)
    throw InvalidInputError(path.string() + ": cannot read mesh (unsupported or malformed file" +
                            (message.empty() ? "" : ": " + message) + ")");
  if (!message.empty()) throw InvalidInputError(path.string() + ": " + skipped_faces(message, om.n_vertices()));
  Mesh mesh = from_openmesh(om);
  if (!opts.check(OpenMesh::IO::Options::VertexNormal)) mesh.normals.clear();
  if (mesh.triangles.empty()) throw InvalidInputError(path.string() + ": the mesh has no triangles");
  for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    if (!mesh.positions[i].allFinite() || (i < mesh.normals.size() && !mesh.normals[i].allFinite()))
      throw InvalidInputError(path.string() + ": vertex " + std::to_string(i) + " has a non-finite " +
                              (mesh.positions[i].allFinite() ? "normal" : "coordinate"));
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
