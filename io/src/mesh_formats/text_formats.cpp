// OBJ (vertices, normals, faces; the rest of the format is skipped) and ASCII OFF.
#include "mesh_formats/mesh_formats.h"

#include <cdp/core/errors.h>

#include <charconv>
#include <cmath>
#include <limits>
#include <vector>

namespace cdp::formats {

namespace {

// The lines of a text file with their numbers, and number parsing with the position in messages.
class Lines {
 public:
  Lines(std::string_view data, const std::string& name) : data_(data), name_(name) {
    if (data.find('\0') != std::string_view::npos) throw InvalidInputError(name + ": not a text file (it holds NUL bytes)");
  }
  // The next line without its comment ('#' to the end), or false at the end of the data.
  bool next(std::string_view& line) {
    if (pos_ >= data_.size()) return false;
    std::size_t end = data_.find('\n', pos_);
    if (end == std::string_view::npos) end = data_.size();
    line = data_.substr(pos_, end - pos_);
    pos_ = end + 1;
    ++number_;
    if (const auto hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    return true;
  }
  InvalidInputError error(const std::string& what) const {
    return InvalidInputError(name_ + ":" + std::to_string(number_) + ": " + what);
  }
  std::size_t remaining() const { return pos_ < data_.size() ? data_.size() - pos_ : 0; }

 private:
  std::string_view data_;
  const std::string& name_;
  std::size_t pos_ = 0;
  int number_ = 0;
};

// Splits on blanks.
std::vector<std::string_view> words(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const std::size_t start = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

bool parse_double(std::string_view s, double& v) {
  if (!s.empty() && s[0] == '+') s.remove_prefix(1);
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

bool parse_long(std::string_view s, long long& v) {
  if (!s.empty() && s[0] == '+') s.remove_prefix(1);
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

Vec3 parse_vec3(const Lines& lines, const std::vector<std::string_view>& w, std::size_t first, const char* what) {
  Vec3 v;
  if (w.size() < first + 3) throw lines.error(std::string(what) + " needs three numbers");
  for (int a = 0; a < 3; ++a)
    if (!parse_double(w[first + a], v[a]))
      throw lines.error(std::string(what) + ": \"" + std::string(w[first + a]) + "\" is not a number");
  return v;
}

void add_fan(Mesh& mesh, const std::vector<int>& polygon) {
  for (std::size_t i = 1; i + 1 < polygon.size(); ++i) mesh.triangles.push_back({polygon[0], polygon[i], polygon[i + 1]});
}

}  // namespace

Mesh read_obj(std::string_view data, const std::string& name) {
  Lines lines(data, name);
  Mesh mesh;
  std::vector<Vec3> normals;
  // The normal each vertex uses, when the faces give one consistently (-1: none yet, -2: mixed).
  std::vector<long long> normal_of;
  std::string_view line;
  std::vector<int> polygon;
  while (lines.next(line)) {
    const auto w = words(line);
    if (w.empty()) continue;
    if (w[0] == "v") {
      mesh.positions.push_back(parse_vec3(lines, w, 1, "a vertex"));
      normal_of.push_back(-1);
    } else if (w[0] == "vn") {
      normals.push_back(parse_vec3(lines, w, 1, "a normal"));
    } else if (w[0] == "f") {
      if (w.size() < 4) throw lines.error("a face needs at least three vertices");
      polygon.clear();
      for (std::size_t k = 1; k < w.size(); ++k) {
        // v, v/vt, v/vt/vn or v//vn; negative indices count back from the last vertex read.
        const std::string_view item = w[k];
        const std::size_t slash = item.find('/');
        long long v = 0;
        if (!parse_long(item.substr(0, slash), v) || v == 0) throw lines.error("a face vertex \"" + std::string(item) + "\"");
        const auto nv = static_cast<long long>(mesh.positions.size());
        const long long index = v > 0 ? v - 1 : nv + v;
        if (index < 0 || index >= nv) throw lines.error("a face refers to vertex " + std::to_string(v) + " of " + std::to_string(nv));
        polygon.push_back(static_cast<int>(index));
        long long n = 0;
        const std::size_t second = slash == std::string_view::npos ? slash : item.find('/', slash + 1);
        if (second != std::string_view::npos && parse_long(item.substr(second + 1), n) && n != 0) {
          const auto nn = static_cast<long long>(normals.size());
          const long long ni = n > 0 ? n - 1 : nn + n;
          if (ni < 0 || ni >= nn) throw lines.error("a face refers to normal " + std::to_string(n) + " of " + std::to_string(nn));
          long long& used = normal_of[index];
          used = used == -1 || used == ni ? ni : -2;
        } else {
          normal_of[index] = -2;
        }
      }
      add_fan(mesh, polygon);
    } else if (w[0] == "vt" || w[0] == "vp" || w[0] == "o" || w[0] == "g" || w[0] == "s" || w[0] == "usemtl" ||
               w[0] == "mtllib" || w[0] == "l" || w[0] == "p") {
      continue;  // texture, grouping, material and line data carry nothing a surface mesh needs
    } else {
      throw lines.error("unknown OBJ statement \"" + std::string(w[0]) + "\"");
    }
  }
  // Per-vertex normals only when every vertex has exactly one (as this project writes them).
  bool all = !normals.empty();
  for (const long long n : normal_of) all = all && n >= 0;
  if (all) {
    mesh.normals.resize(mesh.positions.size());
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) mesh.normals[i] = normals[normal_of[i]];
  }
  check_mesh(mesh, name);
  return mesh;
}

Mesh read_off(std::string_view data, const std::string& name) {
  Lines lines(data, name);
  std::string_view line;
  std::vector<std::string_view> tokens;
  // The tokens of the next non-empty line.
  const auto next_words = [&](const char* what) {
    while (lines.next(line)) {
      tokens = words(line);
      if (!tokens.empty()) return;
    }
    throw lines.error(std::string("the data ends early: ") + what + " expected");
  };
  next_words("the OFF header");
  // "OFF" with the optional prefixes of the format: ST (texture), C (colour), N (normal), 4, n.
  const std::string_view head = tokens[0];
  if (head.size() < 3 || head.substr(head.size() - 3) != "OFF") throw lines.error("not an OFF file (no OFF header)");
  const std::string_view prefix = head.substr(0, head.size() - 3);
  if (prefix.find_first_not_of("STCN") != std::string_view::npos)
    throw lines.error("the OFF variant \"" + std::string(head) + "\" is not supported");
  if (tokens.size() > 1 && tokens[1] == "BINARY") throw lines.error("binary OFF is not supported");
  const bool has_normals = prefix.find('N') != std::string_view::npos;
  std::vector<std::string_view> counts(tokens.begin() + 1, tokens.end());
  if (counts.empty()) {
    next_words("the vertex and face counts");
    counts = tokens;
  }
  long long nv = 0, nf = 0;
  if (counts.size() < 2 || !parse_long(counts[0], nv) || !parse_long(counts[1], nf) || nv < 0 || nf < 0)
    throw lines.error("the vertex and face counts");
  // Each vertex and face takes at least a few characters: a count above that is an error, not
  // an allocation.
  if (static_cast<unsigned long long>(nv) + static_cast<unsigned long long>(nf) > lines.remaining())
    throw lines.error("the header declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                      " faces but the file is too short for them");
  Mesh mesh;
  mesh.positions.reserve(static_cast<std::size_t>(nv));
  if (has_normals) mesh.normals.reserve(static_cast<std::size_t>(nv));
  for (long long i = 0; i < nv; ++i) {
    next_words("a vertex");
    mesh.positions.push_back(parse_vec3(lines, tokens, 0, "a vertex"));
    if (has_normals) mesh.normals.push_back(parse_vec3(lines, tokens, 3, "a vertex normal"));
  }
  std::vector<int> polygon;
  for (long long f = 0; f < nf; ++f) {
    next_words("a face");
    long long n = 0;
    if (!parse_long(tokens[0], n) || n < 3 || static_cast<std::size_t>(n) + 1 > tokens.size())
      throw lines.error("a face needs its vertex count (at least 3) and as many indices");
    polygon.clear();
    for (long long k = 1; k <= n; ++k) {
      long long v = 0;
      if (!parse_long(tokens[k], v) || v < 0 || v >= nv)
        throw lines.error("a face refers to vertex \"" + std::string(tokens[k]) + "\" of " + std::to_string(nv));
      polygon.push_back(static_cast<int>(v));
    }
    add_fan(mesh, polygon);
  }
  check_mesh(mesh, name);
  return mesh;
}

void write_obj(const Mesh& mesh, const ByteSink& sink) {
  const bool normals = mesh.normals.size() == mesh.positions.size();
  PieceWriter w(sink);
  std::string& out = w.out;
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    const Vec3& p = mesh.positions[i];
    out += "v " + shortest_decimal(p.x()) + " " + shortest_decimal(p.y()) + " " + shortest_decimal(p.z()) + "\n";
    if (normals) {
      const Vec3& n = mesh.normals[i];
      out += "vn " + shortest_decimal(n.x()) + " " + shortest_decimal(n.y()) + " " + shortest_decimal(n.z()) + "\n";
    }
    w.record_done();
  }
  for (const auto& t : mesh.triangles) {
    out += "f";
    for (int k = 0; k < 3; ++k) {
      const std::string i = std::to_string(t[k] + 1);
      out += " " + i + (normals ? "//" + i : "");
    }
    out += "\n";
    w.record_done();
  }
  w.finish();
}

void write_off(const Mesh& mesh, const ByteSink& sink) {
  const bool normals = mesh.normals.size() == mesh.positions.size();
  PieceWriter w(sink);
  std::string& out = w.out;
  out += normals ? "NOFF\n" : "OFF\n";
  out += std::to_string(mesh.positions.size()) + " " + std::to_string(mesh.triangles.size()) + " 0\n";
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    const Vec3& p = mesh.positions[i];
    out += shortest_decimal(p.x()) + " " + shortest_decimal(p.y()) + " " + shortest_decimal(p.z());
    if (normals) {
      const Vec3& n = mesh.normals[i];
      out += " " + shortest_decimal(n.x()) + " " + shortest_decimal(n.y()) + " " + shortest_decimal(n.z());
    }
    out += "\n";
    w.record_done();
  }
  for (const auto& t : mesh.triangles) {
    out += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
    w.record_done();
  }
  w.finish();
}

}  // namespace cdp::formats
