#include "common/png_decode.h"

#include <algorithm>
#include <fstream>
#include <iterator>
#include <memory>

// stb_image's code lives in this file only; PNG is all the tests read, from memory.
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#define STBI_ONLY_PNG
#define STBI_NO_STDIO
#include <stb_image.h>

namespace cdp::test {

namespace {

std::uint32_t be32(const std::vector<std::uint8_t>& b, std::size_t i) {
  return (std::uint32_t(b[i]) << 24) | (std::uint32_t(b[i + 1]) << 16) | (std::uint32_t(b[i + 2]) << 8) | b[i + 3];
}

// Bitwise CRC-32 (ISO 3309, as PNG uses it).
std::uint32_t crc(const std::uint8_t* p, std::size_t n) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return ~c;
}

// The first problem of the chunk structure, or "".
std::string structure_problem(const std::vector<std::uint8_t>& b) {
  const std::uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (b.size() < 8 || !std::equal(sig, sig + 8, b.begin())) return "bad signature";
  bool header = false;
  for (std::size_t i = 8;;) {
    if (i + 12 > b.size()) return "truncated chunk";
    const std::uint32_t len = be32(b, i);
    if (len > b.size() - i - 12) return "chunk longer than the file";
    const std::string type(b.begin() + i + 4, b.begin() + i + 8);
    if (crc(&b[i + 4], len + 4) != be32(b, i + 8 + len)) return "bad CRC in " + type;
    const std::size_t d = i + 8;
    if (type == "IHDR") {
      // 8 bits per channel, RGB, deflate, adaptive filters, no interlace.
      if (len != 13 || b[d + 8] != 8 || b[d + 9] != 2 || b[d + 10] || b[d + 11] || b[d + 12]) return "not 8-bit RGB";
      header = true;
    } else if (type == "IEND") {
      if (d + len + 4 != b.size()) return "bytes after IEND";
      return header ? "" : "no IHDR";
    }
    i = d + len + 4;
  }
}

}  // namespace

std::optional<DecodedPng> decode_png(const std::vector<std::uint8_t>& bytes, std::string* error) {
  auto fail = [&](const std::string& what) -> std::optional<DecodedPng> {
    if (error) *error = what;
    return std::nullopt;
  };
  if (const std::string problem = structure_problem(bytes); !problem.empty()) return fail(problem);
  int w = 0, h = 0, channels = 0;
  const std::unique_ptr<stbi_uc, void (*)(void*)> pixels(
      stbi_load_from_memory(bytes.data(), static_cast<int>(bytes.size()), &w, &h, &channels, 3), stbi_image_free);
  if (!pixels) return fail(std::string("stb_image: ") + stbi_failure_reason());
  if (channels != 3) return fail("not RGB");
  DecodedPng png;
  png.width = w;
  png.height = h;
  png.rgb.assign(pixels.get(), pixels.get() + 3 * static_cast<std::size_t>(w) * h);
  return png;
}

std::optional<DecodedPng> read_png_file(const std::string& path, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (error) *error = "cannot open " + path;
    return std::nullopt;
  }
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return decode_png(bytes, error);
}

}  // namespace cdp::test
