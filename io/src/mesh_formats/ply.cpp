// PLY (Turk 1994): ASCII and binary of either byte order on reading, binary little-endian or
// ASCII on writing, with double coordinates and any scalar vertex properties.
#include "mesh_formats/mesh_formats.h"

#include <cdp/core/errors.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <sstream>
#include <vector>

namespace cdp::formats {

namespace {

enum class Type { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
enum class Encoding { Ascii, LittleEndian, BigEndian };

std::optional<Type> parse_type(const std::string& s) {
  if (s == "char" || s == "int8") return Type::Int8;
  if (s == "uchar" || s == "uint8") return Type::UInt8;
  if (s == "short" || s == "int16") return Type::Int16;
  if (s == "ushort" || s == "uint16") return Type::UInt16;
  if (s == "int" || s == "int32") return Type::Int32;
  if (s == "uint" || s == "uint32") return Type::UInt32;
  if (s == "float" || s == "float32") return Type::Float32;
  if (s == "double" || s == "float64") return Type::Float64;
  return std::nullopt;
}

std::size_t size_of(Type t) {
  switch (t) {
    case Type::Int8: case Type::UInt8: return 1;
    case Type::Int16: case Type::UInt16: return 2;
    case Type::Int32: case Type::UInt32: case Type::Float32: return 4;
    case Type::Float64: return 8;
  }
  return 8;
}

bool is_integer(Type t) { return t != Type::Float32 && t != Type::Float64; }

struct Property {
  std::string name;
  Type type = Type::Float64;
  bool list = false;
  Type count_type = Type::UInt8;
};

struct Element {
  std::string name;
  std::size_t count = 0;
  std::vector<Property> properties;
  // The fewest bytes (binary) or characters (ASCII, a digit and a separator per value) one
  // record can take: what bounds the count a file of this size can really hold.
  std::size_t min_record(Encoding e) const {
    std::size_t n = 0;
    for (const auto& p : properties) n += e == Encoding::Ascii ? 2 : size_of(p.list ? p.count_type : p.type);
    return std::max<std::size_t>(n, 1);
  }
};

// Reads values from the data after the header; every read checks the end of the data.
class Cursor {
 public:
  Cursor(std::string_view data, Encoding e, const std::string& name) : data_(data), enc_(e), name_(name) {}

  double read(Type t) {
    if (enc_ == Encoding::Ascii) return read_text(t);
    const std::size_t n = size_of(t);
    if (pos_ + n > data_.size()) throw InvalidInputError(name_ + ": the data ends early" + where());
    unsigned char b[8];
    std::memcpy(b, data_.data() + pos_, n);
    pos_ += n;
    const bool little_host = [] { const std::uint16_t x = 1; unsigned char c; std::memcpy(&c, &x, 1); return c == 1; }();
    if ((enc_ == Encoding::LittleEndian) != little_host) std::reverse(b, b + n);
    switch (t) {
      case Type::Int8: { std::int8_t v; std::memcpy(&v, b, 1); return v; }
      case Type::UInt8: return b[0];
      case Type::Int16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
      case Type::UInt16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
      case Type::Int32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
      case Type::UInt32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
      case Type::Float32: { float v; std::memcpy(&v, b, 4); return v; }
      case Type::Float64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0;
  }
  std::size_t remaining() const { return data_.size() - pos_; }
  // Where the next value belongs, for messages; kept as parts so that no string is built per record.
  void set_where(const std::string* element, std::size_t record) {
    element_ = element;
    record_ = record;
  }

 private:
  double read_text(Type t) {
    while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
    if (pos_ >= data_.size()) throw InvalidInputError(name_ + ": the data ends early" + where());
    double v = 0;
    const char* begin = data_.data() + pos_;
    const char* end = data_.data() + data_.size();
    // from_chars does not take the '+' that some writers put before positive numbers.
    const auto r = std::from_chars(begin + (*begin == '+' ? 1 : 0), end, v);
    if (r.ec == std::errc::result_out_of_range) throw InvalidInputError(name_ + ": a number out of range" + where());
    if (r.ec != std::errc() || (r.ptr < end && !std::isspace(static_cast<unsigned char>(*r.ptr))))
      throw InvalidInputError(name_ + ": \"" + std::string(begin, std::find_if(begin, std::min(end, begin + 20), [](char c) {
                                return std::isspace(static_cast<unsigned char>(c));
                              })) + "\" is not a number" + where());
    if (is_integer(t) && v != std::floor(v)) throw InvalidInputError(name_ + ": an integer expected" + where());
    pos_ = static_cast<std::size_t>(r.ptr - data_.data());
    return v;
  }

  std::string where() const {
    return element_ ? " (" + *element_ + " " + std::to_string(record_) + ")" : std::string();
  }

  std::string_view data_;
  std::size_t pos_ = 0;
  Encoding enc_;
  const std::string& name_;
  const std::string* element_ = nullptr;
  std::size_t record_ = 0;
};

}  // namespace

Mesh read_ply(std::string_view data, const std::string& name) {
  // The header: text lines up to "end_header".
  const std::string_view end_marker = "end_header";
  std::size_t header_end = std::string_view::npos;
  for (std::size_t at = data.find(end_marker); at != std::string_view::npos; at = data.find(end_marker, at + 1))
    if (at > 0 && data[at - 1] == '\n') {
      header_end = at;
      break;
    }
  if (data.substr(0, 4) != "ply\n" && data.substr(0, 5) != "ply\r\n")
    throw InvalidInputError(name + ": not a PLY file (it does not start with \"ply\")");
  if (header_end == std::string_view::npos) throw InvalidInputError(name + ": the PLY header has no end_header line");
  std::size_t data_start = header_end + end_marker.size();
  while (data_start < data.size() && data[data_start] == '\r') ++data_start;
  if (data_start < data.size() && data[data_start] == '\n') ++data_start;

  std::optional<Encoding> encoding;
  std::vector<Element> elements;
  std::istringstream header{std::string(data.substr(0, header_end))};
  std::string line;
  int line_no = 0;
  while (std::getline(header, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream in(line);
    std::string word;
    in >> word;
    const auto bad = [&](const std::string& what) {
      return InvalidInputError(name + ": header line " + std::to_string(line_no) + ": " + what);
    };
    if (word.empty() || word == "ply" || word == "comment" || word == "obj_info") continue;
    if (word == "format") {
      std::string kind, version;
      in >> kind >> version;
      if (kind == "ascii") encoding = Encoding::Ascii;
      else if (kind == "binary_little_endian") encoding = Encoding::LittleEndian;
      else if (kind == "binary_big_endian") encoding = Encoding::BigEndian;
      else throw bad("unknown format \"" + kind + "\"");
    } else if (word == "element") {
      Element e;
      long double count = -1;
      in >> e.name >> count;
      if (!in || e.name.empty() || count < 0 || count != std::floor(count) || count > 1e15)
        throw bad("an element needs a name and a count");
      e.count = static_cast<std::size_t>(count);
      elements.push_back(std::move(e));
    } else if (word == "property") {
      if (elements.empty()) throw bad("a property before any element");
      Property p;
      std::string type;
      in >> type;
      if (type == "list") {
        std::string count_type, item_type;
        in >> count_type >> item_type >> p.name;
        const auto ct = parse_type(count_type);
        const auto it = parse_type(item_type);
        if (!ct || !it || !is_integer(*ct)) throw bad("a list property needs an integer count type and an item type");
        p.list = true;
        p.count_type = *ct;
        p.type = *it;
      } else {
        const auto t = parse_type(type);
        if (!t) throw bad("unknown property type \"" + type + "\"");
        p.type = *t;
        in >> p.name;
      }
      if (p.name.empty()) throw bad("a property needs a name");
      elements.back().properties.push_back(std::move(p));
    } else {
      throw bad("unknown keyword \"" + word + "\"");
    }
  }
  if (!encoding) throw InvalidInputError(name + ": the PLY header has no format line");

  Mesh mesh;
  Cursor cursor(data.substr(data_start), *encoding, name);
  for (const Element& e : elements) {
    // A count the remaining data cannot hold is an error before anything is allocated for it.
    if (e.count > cursor.remaining() / e.min_record(*encoding))
      throw InvalidInputError(name + ": the header declares " + std::to_string(e.count) + " " + e.name +
                              " records but the file is too short for them");
    const bool is_vertex = e.name == "vertex";
    const bool is_face = e.name == "face";
    int xyz[3] = {-1, -1, -1}, nxyz[3] = {-1, -1, -1};
    int indices = -1;
    for (int k = 0; k < static_cast<int>(e.properties.size()); ++k) {
      const Property& p = e.properties[k];
      static const char* axes[3] = {"x", "y", "z"};
      static const char* normal_axes[3] = {"nx", "ny", "nz"};
      for (int a = 0; a < 3; ++a) {
        if (is_vertex && !p.list && p.name == axes[a]) xyz[a] = k;
        if (is_vertex && !p.list && p.name == normal_axes[a]) nxyz[a] = k;
      }
      if (is_face && p.list && (p.name == "vertex_indices" || p.name == "vertex_index") && is_integer(p.type))
        indices = k;
    }
    if (is_vertex && (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0))
      throw InvalidInputError(name + ": the vertex element has no x, y and z properties");
    if (is_face && indices < 0) throw InvalidInputError(name + ": the face element has no vertex_indices list");
    const bool has_normals = is_vertex && nxyz[0] >= 0 && nxyz[1] >= 0 && nxyz[2] >= 0;
    if (is_vertex) {
      mesh.positions.resize(e.count);
      if (has_normals) mesh.normals.resize(e.count);
      for (int k = 0; k < static_cast<int>(e.properties.size()); ++k) {
        const Property& p = e.properties[k];
        const bool used = k == xyz[0] || k == xyz[1] || k == xyz[2] ||
                          (has_normals && (k == nxyz[0] || k == nxyz[1] || k == nxyz[2]));
        if (!p.list && !used) mesh.vertex_scalars[p.name].resize(e.count);
      }
    }
    std::vector<double> values(e.properties.size());
    std::vector<long long> polygon;
    for (std::size_t r = 0; r < e.count; ++r) {
      cursor.set_where(&e.name, r);
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        const Property& p = e.properties[k];
        if (!p.list) {
          values[k] = cursor.read(p.type);
          continue;
        }
        const double n = cursor.read(p.count_type);
        if (n < 0 || n > static_cast<double>(cursor.remaining()))
          throw InvalidInputError(name + ": a list of " + std::to_string(static_cast<long long>(n)) + " items in " + e.name +
                                  " " + std::to_string(r));
        const auto count = static_cast<std::size_t>(n);
        if (static_cast<int>(k) == indices) polygon.assign(count, 0);
        for (std::size_t i = 0; i < count; ++i) {
          const double v = cursor.read(p.type);
          if (static_cast<int>(k) == indices) polygon[i] = static_cast<long long>(v);
        }
      }
      if (is_vertex) {
        mesh.positions[r] = Vec3(values[xyz[0]], values[xyz[1]], values[xyz[2]]);
        if (has_normals) mesh.normals[r] = Vec3(values[nxyz[0]], values[nxyz[1]], values[nxyz[2]]);
        for (std::size_t k = 0; k < e.properties.size(); ++k) {
          auto it = mesh.vertex_scalars.find(e.properties[k].name);
          if (it != mesh.vertex_scalars.end() && !e.properties[k].list) it->second[r] = values[k];
        }
      } else if (is_face) {
        if (polygon.size() < 3)
          throw InvalidInputError(name + ": face " + std::to_string(r) + " has " + std::to_string(polygon.size()) +
                                  " vertices");
        for (const long long i : polygon)
          if (i < 0 || i > std::numeric_limits<int>::max())
            throw InvalidInputError(name + ": face " + std::to_string(r) + " refers to vertex " + std::to_string(i));
        // Polygons become a fan of triangles, as OpenMesh's reader did before.
        for (std::size_t i = 1; i + 1 < polygon.size(); ++i)
          mesh.triangles.push_back({static_cast<int>(polygon[0]), static_cast<int>(polygon[i]), static_cast<int>(polygon[i + 1])});
      }
    }
  }
  check_mesh(mesh, name);
  return mesh;
}

void write_ply(const Mesh& mesh, bool binary, const ByteSink& sink) {
  const bool normals = mesh.normals.size() == mesh.positions.size();
  std::vector<std::pair<const std::string*, const std::vector<double>*>> scalars;
  for (const auto& [n, values] : mesh.vertex_scalars)
    if (values.size() == mesh.positions.size()) scalars.push_back({&n, &values});
  PieceWriter w(sink);
  std::string& out = w.out;
  out += "ply\nformat ";
  out += binary ? "binary_little_endian 1.0\n" : "ascii 1.0\n";
  out += "element vertex " + std::to_string(mesh.positions.size()) + "\n";
  for (const char* p : {"x", "y", "z"}) out += std::string("property double ") + p + "\n";
  if (normals)
    for (const char* p : {"nx", "ny", "nz"}) out += std::string("property double ") + p + "\n";
  for (const auto& s : scalars) out += "property double " + *s.first + "\n";
  out += "element face " + std::to_string(mesh.triangles.size()) + "\n";
  out += "property list uchar int vertex_indices\nend_header\n";
  if (binary) {
    static_assert(sizeof(double) == 8 && sizeof(int) == 4, "PLY double and int are 8 and 4 bytes");
    const bool little_host = [] { const std::uint16_t x = 1; unsigned char c; std::memcpy(&c, &x, 1); return c == 1; }();
    const auto put = [&](const void* p, std::size_t n) {
      const std::size_t at = out.size();
      out.append(static_cast<const char*>(p), n);
      if (!little_host) std::reverse(out.begin() + static_cast<std::ptrdiff_t>(at), out.end());
    };
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
      for (int a = 0; a < 3; ++a) put(&mesh.positions[i][a], 8);
      if (normals)
        for (int a = 0; a < 3; ++a) put(&mesh.normals[i][a], 8);
      for (const auto& s : scalars) put(&(*s.second)[i], 8);
      w.record_done();
    }
    for (const auto& t : mesh.triangles) {
      out.push_back(3);
      for (int k = 0; k < 3; ++k) put(&t[k], 4);
      w.record_done();
    }
  } else {
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
      std::string line;
      const auto add = [&](double v) {
        if (!line.empty()) line += ' ';
        line += shortest_decimal(v);
      };
      for (int a = 0; a < 3; ++a) add(mesh.positions[i][a]);
      if (normals)
        for (int a = 0; a < 3; ++a) add(mesh.normals[i][a]);
      for (const auto& s : scalars) add((*s.second)[i]);
      out += line + "\n";
      w.record_done();
    }
    for (const auto& t : mesh.triangles) {
      out += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
      w.record_done();
    }
  }
  w.finish();
}

}  // namespace cdp::formats
