// Reads back the PNG files the project writes (8-bit RGB, stored deflate blocks, filter 0) for
// the tests, checking every length, checksum and header field on the way. It rejects any
// other PNG: it is a test oracle for our writer, not a general decoder.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

namespace cdp::test {

struct DecodedPng {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  std::array<int, 3> at(int x, int y) const {
    const std::size_t i = 3 * (static_cast<std::size_t>(y) * width + x);
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
};

namespace detail {
inline std::uint32_t be32(const std::vector<std::uint8_t>& b, std::size_t i) {
  return (std::uint32_t(b[i]) << 24) | (std::uint32_t(b[i + 1]) << 16) | (std::uint32_t(b[i + 2]) << 8) | b[i + 3];
}
// Bitwise CRC-32 (no table), independent of the writer's.
inline std::uint32_t crc(const std::uint8_t* p, std::size_t n) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return ~c;
}
}  // namespace detail

// The error of the first problem found, or the decoded picture.
inline std::optional<DecodedPng> decode_png(const std::vector<std::uint8_t>& b, std::string* error = nullptr) {
  auto fail = [&](const std::string& what) -> std::optional<DecodedPng> {
    if (error) *error = what;
    return std::nullopt;
  };
  const std::uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (b.size() < 8 || !std::equal(sig, sig + 8, b.begin())) return fail("bad signature");
  DecodedPng png;
  std::vector<std::uint8_t> z;
  bool ended = false;
  for (std::size_t i = 8; !ended;) {
    if (i + 12 > b.size()) return fail("truncated chunk");
    const std::uint32_t len = detail::be32(b, i);
    if (i + 12 + len > b.size()) return fail("chunk longer than the file");
    const std::string type(b.begin() + i + 4, b.begin() + i + 8);
    if (detail::crc(&b[i + 4], len + 4) != detail::be32(b, i + 8 + len)) return fail("bad CRC in " + type);
    const std::size_t d = i + 8;
    if (type == "IHDR") {
      if (len != 13) return fail("IHDR length");
      png.width = static_cast<int>(detail::be32(b, d));
      png.height = static_cast<int>(detail::be32(b, d + 4));
      if (b[d + 8] != 8 || b[d + 9] != 2 || b[d + 10] || b[d + 11] || b[d + 12]) return fail("not 8-bit RGB");
    } else if (type == "IDAT") {
      z.insert(z.end(), b.begin() + d, b.begin() + d + len);
    } else if (type == "IEND") {
      ended = true;
      if (d + len + 4 != b.size()) return fail("bytes after IEND");
    }
    i = d + len + 4;
  }
  if (png.width < 1 || png.height < 1) return fail("no IHDR");
  if (z.size() < 6 || ((z[0] << 8) | z[1]) % 31 != 0 || (z[0] & 0x0F) != 8) return fail("bad zlib header");
  std::vector<std::uint8_t> raw;
  std::size_t p = 2;
  for (bool last = false; !last;) {
    if (p + 5 > z.size()) return fail("truncated deflate block");
    if ((z[p] & 0x06) != 0) return fail("not a stored block");
    last = z[p] & 1;
    const unsigned len = z[p + 1] | (z[p + 2] << 8), nlen = z[p + 3] | (z[p + 4] << 8);
    if ((len ^ 0xFFFFu) != nlen) return fail("stored block length check");
    if (p + 5 + len > z.size()) return fail("stored block longer than the data");
    raw.insert(raw.end(), z.begin() + p + 5, z.begin() + p + 5 + len);
    p += 5 + len;
  }
  if (p + 4 != z.size()) return fail("zlib stream length");
  std::uint32_t a = 1, s = 0;
  for (std::uint8_t v : raw) {
    a = (a + v) % 65521;
    s = (s + a) % 65521;
  }
  if (((s << 16) | a) != detail::be32(z, p)) return fail("bad Adler-32");
  const std::size_t row = 3 * static_cast<std::size_t>(png.width);
  if (raw.size() != (row + 1) * png.height) return fail("pixel data size");
  for (int y = 0; y < png.height; ++y) {
    if (raw[y * (row + 1)] != 0) return fail("filter type not 0");
    png.rgb.insert(png.rgb.end(), raw.begin() + y * (row + 1) + 1, raw.begin() + (y + 1) * (row + 1));
  }
  return png;
}

inline std::optional<DecodedPng> read_png_file(const std::string& path, std::string* error = nullptr) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (error) *error = "cannot open " + path;
    return std::nullopt;
  }
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return decode_png(bytes, error);
}

}  // namespace cdp::test
