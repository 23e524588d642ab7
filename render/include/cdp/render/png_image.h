// An 8-bit RGB image and its PNG file, encoded by stb_image_write (Debian's libstb-dev; header
// only, compiled into src/png_image.cpp): deflate-compressed, with per-row filters. The same
// image always gives the same bytes. Writing the bytes to a file is the caller's job
// (apps/render.cpp, atomically), as everywhere in raytrace/.
#pragma once

#include <array>
#include <cstdint>
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

// The complete PNG file as bytes. Throws InvalidInputError for an empty image or one whose rgb
// size is not 3 * width * height, and std::bad_alloc when the encoder runs out of memory.
std::vector<std::uint8_t> encode_png(const Image& image);

}  // namespace cdp
