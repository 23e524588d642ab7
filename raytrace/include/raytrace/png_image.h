// An 8-bit RGB image and its PNG file. None of the project's dependencies writes PNG, so the
// writer here emits the simplest valid PNG: one IDAT chunk holding a zlib stream of *stored*
// (uncompressed) deflate blocks, with the CRC-32 and Adler-32 checksums the format requires.
// Files are about 3 bytes per pixel; scripts that keep images recompress them (matplotlib).
// Writing the bytes to a file is the caller's job (apps/render.cpp), as everywhere in raytrace/.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace cdp {

using Rgb = std::array<std::uint8_t, 3>;

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // row after row from the top, 3 bytes per pixel

  Image() = default;
  Image(int w, int h, Rgb fill);
  Rgb at(int x, int y) const;
  void set(int x, int y, Rgb c);
};

// The complete PNG file (signature, IHDR, IDAT, IEND) as bytes. Throws InvalidInputError for an
// empty image or one whose rgb size is not 3 * width * height.
std::vector<std::uint8_t> encode_png(const Image& image);

// CRC-32 (ISO 3309, as PNG uses it) and Adler-32 (RFC 1950), exposed for the tests.
std::uint32_t crc32(const std::uint8_t* data, std::size_t n, std::uint32_t crc = 0);
std::uint32_t adler32(const std::uint8_t* data, std::size_t n, std::uint32_t adler = 1);

}  // namespace cdp
