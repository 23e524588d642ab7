#include <cdp/core/errors.h>
#include <cdp/io/volume_io.h>

#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <charconv>
#include <cmath>
#include <string_view>
#include <type_traits>
#include <sstream>

namespace cdp {

namespace {

// Headers longer than this are refused before they are parsed: numpy writes a few hundred bytes,
// NRRD headers are lines of text; a malformed file must not make the parser's work unbounded.
constexpr std::size_t kMaxHeader = std::size_t{1} << 20;
// Most numbers in one header field (a shape, "sizes", "space directions").
constexpr std::size_t kMaxNumbers = 64;

// A scalar type as stored: its size, kind ('f' float, 'i' signed, 'u' unsigned, 'b' bool) and
// whether its bytes are big-endian.
struct Scalar {
  char kind = 0;
  std::size_t size = 0;
  bool big_endian = false;
};

double read_scalar(const unsigned char* p, const Scalar& s) {
  unsigned char b[8];
  std::memcpy(b, p, s.size);
  if (s.big_endian != (std::endian::native == std::endian::big)) std::reverse(b, b + s.size);
  switch (s.kind) {
    case 'f':
      if (s.size == 4) {
        float v;
        std::memcpy(&v, b, 4);
        return v;
      } else {
        double v;
        std::memcpy(&v, b, 8);
        return v;
      }
    case 'b':
      return b[0] != 0 ? 1.0 : 0.0;
    case 'i':
      switch (s.size) {
        case 1: return static_cast<std::int8_t>(b[0]);
        case 2: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
        case 4: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
        default: { std::int64_t v; std::memcpy(&v, b, 8); return static_cast<double>(v); }
      }
    default:
      switch (s.size) {
        case 1: return b[0];
        case 2: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
        case 4: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
        default: { std::uint64_t v; std::memcpy(&v, b, 8); return static_cast<double>(v); }
      }
  }
}

// Converts `count` stored scalars to doubles; `fastest_first`: the file's first axis varies
// fastest (Fortran order, NRRD), so sample (i, j, k) is at (k * n1 + j) * n0 + i there.
std::vector<double> convert(const unsigned char* data, const Scalar& s, const std::array<std::size_t, 3>& n,
                            bool fastest_first) {
  std::vector<double> out(n[0] * n[1] * n[2]);
  std::size_t f = 0;
  for (std::size_t i = 0; i < n[0]; ++i)
    for (std::size_t j = 0; j < n[1]; ++j)
      for (std::size_t k = 0; k < n[2]; ++k, ++f) {
        const std::size_t stored = fastest_first ? (k * n[1] + j) * n[0] + i : f;
        out[f] = read_scalar(data + stored * s.size, s);
      }
  return out;
}

std::string read_bytes(const std::filesystem::path& path) {
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in.is_open()) throw FileError(path.string() + ": cannot read volume: " + std::strerror(errno ? errno : EIO), errno ? errno : EIO);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw FileError(path.string() + ": cannot read volume: input error", EIO);
  return bytes;
}

// The three sizes of a 3-D array; `what` names them in messages.
std::array<std::size_t, 3> three_sizes(const std::vector<unsigned long long>& sizes, const std::string& name) {
  if (sizes.size() != 3)
    throw InvalidInputError(name + ": a volume needs a 3-D array, found " + std::to_string(sizes.size()) + " dimensions");
  std::array<std::size_t, 3> n{};
  std::size_t total = 1;
  for (int a = 0; a < 3; ++a) {
    if (sizes[a] == 0 || sizes[a] > Volume::kMaxSamples) throw InvalidInputError(name + ": array size out of range");
    n[a] = static_cast<std::size_t>(sizes[a]);
    total *= n[a];
    if (total > Volume::kMaxSamples)
      throw InvalidInputError(name + ": more than " + std::to_string(Volume::kMaxSamples) + " samples");
  }
  return n;
}

// The numbers of a header's list, read with from_chars between `separators`: "33, 41, 25" (a
// shape, "sizes": whole numbers) or "(0.5,0,0) (0,2,0) (0,0,1)" (geometry: finite numbers).
// Anything else is an error naming `key`: no number of a file is read by a function that throws
// its own exceptions or reads past the text.
template <class T>
std::vector<T> list_in(std::string_view text, std::string_view separators, const std::string& name,
                       const std::string& key, const char* expected) {
  std::vector<T> out;
  std::size_t p = 0;
  while (p < text.size()) {
    if (separators.find(text[p]) != std::string_view::npos) {
      ++p;
      continue;
    }
    T v{};
    const auto r = std::from_chars(text.data() + p, text.data() + text.size(), v);
    bool finite = true;
    if constexpr (std::is_floating_point_v<T>) finite = std::isfinite(v);
    if (r.ec != std::errc() || !finite || out.size() == kMaxNumbers)
      throw InvalidInputError(name + ": \"" + key + "\" must " + expected);
    out.push_back(v);
    p = static_cast<std::size_t>(r.ptr - text.data());
  }
  return out;
}

std::vector<unsigned long long> integers_in(std::string_view text, const std::string& name, const std::string& key) {
  return list_in<unsigned long long>(text, ", \t", name, key, "list whole numbers of samples");
}

std::vector<double> numbers_in(std::string_view text, const std::string& name, const std::string& key) {
  return list_in<double>(text, "(), \t", name, key, "hold finite numbers");
}

VolumeSamples read_npy(const std::string& bytes, const std::string& name) {
  static const char kMagic[] = "\x93NUMPY";
  if (bytes.size() < 10 || bytes.compare(0, 6, kMagic, 6) != 0) throw InvalidInputError(name + ": not an .npy file");
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(bytes[i]); };
  const int major = byte(6);
  std::size_t header_len = 0, start = 0;
  if (major == 1) {
    header_len = byte(8) | (byte(9) << 8);
    start = 10;
  } else if (major == 2 || major == 3) {
    if (bytes.size() < 12) throw InvalidInputError(name + ": truncated .npy header");
    header_len = byte(8) | (byte(9) << 8) | (byte(10) << 16) | (static_cast<std::size_t>(byte(11)) << 24);
    start = 12;
  } else {
    throw InvalidInputError(name + ": unknown .npy version " + std::to_string(major));
  }
  if (bytes.size() < start + header_len) throw InvalidInputError(name + ": truncated .npy header");
  if (header_len > kMaxHeader) throw InvalidInputError(name + ": .npy header longer than " + std::to_string(kMaxHeader) + " bytes");
  const std::string header = bytes.substr(start, header_len);
  // The value after 'key': in numpy's header dict (a Python literal written by numpy itself).
  const auto value_of = [&](const std::string& key) -> std::string_view {
    const std::size_t at = header.find("'" + key + "'");
    if (at == std::string::npos) throw InvalidInputError(name + ": malformed .npy header (no " + key + ")");
    std::size_t p = header.find_first_not_of(" \t", at + key.size() + 2);
    if (p == std::string::npos || header[p] != ':') throw InvalidInputError(name + ": malformed .npy header (" + key + ")");
    p = header.find_first_not_of(" \t", p + 1);
    if (p == std::string::npos) throw InvalidInputError(name + ": malformed .npy header (" + key + ")");
    return std::string_view(header).substr(p);
  };
  const std::string_view descr_value = value_of("descr");
  const std::size_t close = descr_value.find('\'', 1);
  if (descr_value.empty() || descr_value[0] != '\'' || close == std::string_view::npos || close > 33)
    throw InvalidInputError(name + ": the array's type is not a real, integer or bool scalar");
  const std::string_view descr = descr_value.substr(1, close - 1);
  Scalar s;
  const bool order_known = !descr.empty() && (descr[0] == '<' || descr[0] == '>' || descr[0] == '|' || descr[0] == '=');
  const bool kind_known = descr.size() >= 3 && (descr[1] == 'f' || descr[1] == 'i' || descr[1] == 'u' || descr[1] == 'b');
  const auto parsed = kind_known ? std::from_chars(descr.data() + 2, descr.data() + descr.size(), s.size)
                                 : std::from_chars_result{descr.data(), std::errc::invalid_argument};
  if (!order_known || !kind_known || parsed.ec != std::errc() || parsed.ptr != descr.data() + descr.size())
    throw InvalidInputError(name + ": the array's type " + std::string(descr) + " is not a real, integer or bool scalar");
  s.big_endian = descr[0] == '>' || (descr[0] == '=' && std::endian::native == std::endian::big);
  s.kind = descr[1];
  if (!(s.size == 1 || s.size == 2 || s.size == 4 || s.size == 8) || (s.kind == 'f' && s.size < 4))
    throw InvalidInputError(name + ": unsupported array type " + std::string(descr));
  const std::string_view order = value_of("fortran_order");
  if (!order.starts_with("True") && !order.starts_with("False"))
    throw InvalidInputError(name + ": malformed .npy header (fortran_order)");
  const bool fortran = order.starts_with("True");
  const std::string_view shape_value = value_of("shape");
  const std::size_t shape_end = shape_value.find(')');
  if (shape_value.empty() || shape_value[0] != '(' || shape_end == std::string_view::npos)
    throw InvalidInputError(name + ": malformed .npy header (shape)");
  const std::vector<unsigned long long> sizes = integers_in(shape_value.substr(1, shape_end - 1), name, "shape");
  const auto n = three_sizes(sizes, name);
  const std::size_t data = start + header_len;
  if (bytes.size() - data < n[0] * n[1] * n[2] * s.size) throw InvalidInputError(name + ": truncated .npy data");
  VolumeSamples v;
  v.dims = n;
  v.values = convert(reinterpret_cast<const unsigned char*>(bytes.data()) + data, s, n, fortran);
  return v;
}

std::string gunzip(const std::string& in, std::size_t expected, const std::string& name) {
  std::string out(expected, '\0');
  z_stream z{};
  if (inflateInit2(&z, 16 + MAX_WBITS) != Z_OK) throw InvalidInputError(name + ": cannot start gzip decoding");
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data()));
  z.avail_in = static_cast<uInt>(std::min<std::size_t>(in.size(), UINT32_MAX));
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(std::min<std::size_t>(expected, UINT32_MAX));
  const int rc = inflate(&z, Z_FINISH);
  const std::size_t got = z.total_out;
  inflateEnd(&z);
  // Z_STREAM_END only: the stream ended where the data do and its checksum held.
  if (rc != Z_STREAM_END || got != expected)
    throw InvalidInputError(name + ": corrupt or truncated gzip data (" + std::to_string(got) + " of " +
                            std::to_string(expected) + " bytes)");
  return out;
}

Scalar nrrd_type(const std::string& type, const std::string& name) {
  static const std::map<std::string, Scalar> types = [] {
    std::map<std::string, Scalar> t;
    for (const char* n : {"signed char", "int8", "int8_t"}) t[n] = {'i', 1};
    for (const char* n : {"uchar", "unsigned char", "uint8", "uint8_t"}) t[n] = {'u', 1};
    for (const char* n : {"short", "short int", "signed short", "signed short int", "int16", "int16_t"}) t[n] = {'i', 2};
    for (const char* n : {"ushort", "unsigned short", "unsigned short int", "uint16", "uint16_t"}) t[n] = {'u', 2};
    for (const char* n : {"int", "signed int", "int32", "int32_t"}) t[n] = {'i', 4};
    for (const char* n : {"uint", "unsigned int", "uint32", "uint32_t"}) t[n] = {'u', 4};
    for (const char* n : {"longlong", "long long", "long long int", "signed long long", "signed long long int", "int64",
                          "int64_t"})
      t[n] = {'i', 8};
    for (const char* n : {"ulonglong", "unsigned long long", "unsigned long long int", "uint64", "uint64_t"}) t[n] = {'u', 8};
    t["float"] = {'f', 4};
    t["double"] = {'f', 8};
    return t;
  }();
  const auto it = types.find(type);
  if (it == types.end()) throw InvalidInputError(name + ": unsupported NRRD type \"" + type.substr(0, 32) + "\"");
  return it->second;
}

VolumeSamples read_nrrd(const std::string& bytes, const std::string& name) {
  if (bytes.compare(0, 4, "NRRD") != 0) throw InvalidInputError(name + ": not an NRRD file (no NRRD magic)");
  std::map<std::string, std::string> fields;
  std::size_t pos = bytes.find('\n');
  bool blank = false;
  while (pos != std::string::npos && pos + 1 < bytes.size()) {
    if (pos > kMaxHeader) throw InvalidInputError(name + ": NRRD header longer than " + std::to_string(kMaxHeader) + " bytes");
    const std::size_t next = bytes.find('\n', pos + 1);
    if (next == std::string::npos) break;
    std::string line = bytes.substr(pos + 1, next - pos - 1);
    pos = next;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) {
      blank = true;
      break;
    }
    if (line[0] == '#') continue;
    const std::size_t colon = line.find(": ");
    if (colon == std::string::npos) continue;  // a key/value pair (":=") carries no geometry
    fields[line.substr(0, colon)] = line.substr(colon + 2);
  }
  if (!blank) throw InvalidInputError(name + ": NRRD header without the blank line that ends it");
  const auto field = [&](const std::string& key) -> std::string {
    const auto it = fields.find(key);
    return it == fields.end() ? std::string() : it->second;
  };
  if (!field("data file").empty() || !field("datafile").empty())
    throw InvalidInputError(name + ": the data lies in another file (detached NRRD headers are not read)");
  if (field("dimension") != "3") throw InvalidInputError(name + ": a volume needs dimension 3, found \"" + field("dimension").substr(0, 32) + "\"");
  Scalar s = nrrd_type(field("type"), name);
  s.big_endian = field("endian") == "big";
  const auto n = three_sizes(integers_in(field("sizes"), name, "sizes"), name);
  for (const char* skip : {"byte skip", "byteskip", "line skip", "lineskip"})
    if (!field(skip).empty() && field(skip) != "0") throw InvalidInputError(name + ": \"" + skip + "\" is not supported");

  VolumeSamples v;
  v.dims = n;
  // Axis-aligned directions only; a negative one flips its axis.
  std::array<bool, 3> flip{false, false, false};
  if (!field("space directions").empty()) {
    const std::vector<double> d = numbers_in(field("space directions"), name, "space directions");
    if (d.size() != 9) throw InvalidInputError(name + ": \"space directions\" must give three 3-D vectors");
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        if (a != b && d[3 * a + b] != 0) throw InvalidInputError(name + ": the space directions are not axis-aligned");
    for (int a = 0; a < 3; ++a) {
      v.spacing[a] = std::abs(d[4 * a]);
      flip[a] = d[4 * a] < 0;
    }
  } else if (!field("spacings").empty()) {
    const std::vector<double> d = numbers_in(field("spacings"), name, "spacings");
    if (d.size() != 3) throw InvalidInputError(name + ": \"spacings\" must give three numbers");
    for (int a = 0; a < 3; ++a) v.spacing[a] = d[a];
  }
  if (!field("space origin").empty()) {
    const std::vector<double> o = numbers_in(field("space origin"), name, "space origin");
    if (o.size() != 3) throw InvalidInputError(name + ": \"space origin\" must give a 3-D point");
    v.origin = Vec3(o[0], o[1], o[2]);
  }
  for (int a = 0; a < 3; ++a)
    if (!(std::isfinite(v.spacing[a]) && v.spacing[a] > 0)) throw InvalidInputError(name + ": a spacing is not positive");

  const std::string encoding = field("encoding");
  const std::size_t expected = n[0] * n[1] * n[2] * s.size;
  std::string data = bytes.substr(pos + 1);
  if (encoding == "gzip" || encoding == "gz") {
    data = gunzip(data, expected, name);
  } else if (encoding != "raw") {
    throw InvalidInputError(name + ": unsupported NRRD encoding \"" + encoding.substr(0, 32) + "\" (raw and gzip are read)");
  }
  if (data.size() < expected) throw InvalidInputError(name + ": truncated NRRD data");
  // NRRD's first axis varies fastest.
  std::vector<double> values = convert(reinterpret_cast<const unsigned char*>(data.data()), s, n, true);
  if (flip[0] || flip[1] || flip[2]) {
    std::vector<double> flipped(values.size());
    for (std::size_t i = 0; i < n[0]; ++i)
      for (std::size_t j = 0; j < n[1]; ++j)
        for (std::size_t k = 0; k < n[2]; ++k) {
          const std::size_t fi = flip[0] ? n[0] - 1 - i : i, fj = flip[1] ? n[1] - 1 - j : j, fk = flip[2] ? n[2] - 1 - k : k;
          flipped[(i * n[1] + j) * n[2] + k] = values[(fi * n[1] + fj) * n[2] + fk];
        }
    values.swap(flipped);
    for (int a = 0; a < 3; ++a)
      if (flip[a]) v.origin[a] -= static_cast<double>(n[a] - 1) * v.spacing[a];
  }
  v.values = std::move(values);
  return v;
}

}  // namespace

VolumeSamples read_volume(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext != ".npy" && ext != ".nrrd")
    throw InvalidInputError(name + ": unknown volume format \"" + ext + "\" (.npy and .nrrd are read)");
  const std::string bytes = read_bytes(path);
  return ext == ".npy" ? read_npy(bytes, name) : read_nrrd(bytes, name);
}

}  // namespace cdp
