#include <cdp/render/png_image.h>

#include <cdp/core/errors.h>

#include <algorithm>
#include <new>
#include <utility>

// The encoder's code lives in this file only: static, so that no other copy of stb (a library
// linking its own) can clash with it; no stdio, since the bytes go to memory.
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#define STBI_WRITE_NO_STDIO
#include <stb_image_write.h>

namespace cdp {

Image::Image(int w, int h, Rgb fill) : width(w), height(h) {
  if (w < 1 || h < 1) throw InvalidInputError("image: width and height must be positive");
  rgb.resize(3 * static_cast<std::size_t>(w) * h);
  for (std::size_t i = 0; i < rgb.size(); i += 3) std::copy(fill.begin(), fill.end(), rgb.begin() + i);
}

Rgb Image::at(int x, int y) const {
  const std::size_t i = 3 * (static_cast<std::size_t>(y) * width + x);
  return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

void Image::set(int x, int y, Rgb c) {
  const std::size_t i = 3 * (static_cast<std::size_t>(y) * width + x);
  std::copy(c.begin(), c.end(), rgb.begin() + i);
}

std::vector<std::uint8_t> encode_png(const Image& image) {
  if (image.width < 1 || image.height < 1) throw InvalidInputError("png: the image is empty");
  const std::size_t row = 3 * static_cast<std::size_t>(image.width);
  if (image.rgb.size() != row * image.height) throw InvalidInputError("png: pixel data does not match the size");
  // stb counts bytes in int: refuse what would overflow it rather than write a broken file.
  if (image.rgb.size() > (1u << 30)) throw InvalidInputError("png: the image is too large (more than 1 GiB of pixels)");
  struct Output {
    std::vector<std::uint8_t> bytes;
    bool failed = false;
  } out;
  // No exception may cross stb's C code (it would leak the encoded buffer).
  const auto append = [](void* context, void* data, int size) {
    auto* o = static_cast<Output*>(context);
    const auto* bytes = static_cast<const std::uint8_t*>(data);
    try {
      o->bytes.insert(o->bytes.end(), bytes, bytes + size);
    } catch (const std::bad_alloc&) {
      o->failed = true;
    }
  };
  // stb returns 0 only when one of its allocations fails.
  if (!stbi_write_png_to_func(append, &out, image.width, image.height, 3, image.rgb.data(), static_cast<int>(row)) ||
      out.failed)
    throw std::bad_alloc();
  return std::move(out.bytes);
}

}  // namespace cdp
