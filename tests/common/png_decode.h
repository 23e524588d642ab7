// Reads back the PNG files the project writes, for the tests: the pixels come from stb_image
// (an independent decoder, not the writer's code); before that, the file's structure is checked
// as stb_image does not: every chunk's length and CRC-32, an 8-bit RGB header and nothing after
// IEND. A damaged file is refused, not decoded into other pixels.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace cdp::test {

struct DecodedPng {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // row after row from the top, 3 bytes per pixel
  std::array<int, 3> at(int x, int y) const {
    const std::size_t i = 3 * (static_cast<std::size_t>(y) * width + x);
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
};

// The decoded picture, or std::nullopt and the first problem found in *error.
std::optional<DecodedPng> decode_png(const std::vector<std::uint8_t>& bytes, std::string* error = nullptr);
std::optional<DecodedPng> read_png_file(const std::string& path, std::string* error = nullptr);

}  // namespace cdp::test
