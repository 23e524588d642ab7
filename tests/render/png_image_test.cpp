// PNG files from stb_image_write: round trips through an independent reader (stb_image, after
// checking every chunk's CRC), real compression, the same bytes for the same image, invalid
// images.
#include <gtest/gtest.h>

#include <cdp/render/png_image.h>

#include <cdp/core/errors.h>

#include "common/png_decode.h"

namespace cdp {
namespace {

Image gradient(int w, int h) {
  Image im(w, h, {0, 0, 0});
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      im.set(x, y, {static_cast<std::uint8_t>(x * 7), static_cast<std::uint8_t>(y * 3), static_cast<std::uint8_t>(x ^ y)});
  return im;
}

TEST(PngImage, RoundTripKeepsSizeAndEveryPixel) {
  // 300 x 100 is 90 kB of scanlines: more than one 64 KiB window of the deflate stream.
  for (auto [w, h] : {std::pair{3, 2}, std::pair{300, 100}, std::pair{1, 1}, std::pair{257, 3}}) {
    const Image im = gradient(w, h);
    std::string error;
    const auto png = test::decode_png(encode_png(im), &error);
    ASSERT_TRUE(png) << error << " at " << w << "x" << h;
    EXPECT_EQ(png->width, w);
    EXPECT_EQ(png->height, h);
    EXPECT_EQ(png->rgb, im.rgb);
  }
}

TEST(PngImage, PicturesAreCompressedAndTheSameImageGivesTheSameBytes) {
  // A white background with a shaded disc, like a rendered panel: the stored (uncompressed)
  // encoder of earlier versions wrote 3 bytes per pixel.
  Image im(600, 600, {255, 255, 255});
  for (int y = 0; y < 600; ++y)
    for (int x = 0; x < 600; ++x)
      if ((x - 300) * (x - 300) + (y - 300) * (y - 300) < 250 * 250)
        im.set(x, y, {static_cast<std::uint8_t>(x / 3), static_cast<std::uint8_t>(y / 3), 128});
  const std::vector<std::uint8_t> png = encode_png(im);
  EXPECT_LT(png.size(), 600u * 600u * 3u / 10u);
  EXPECT_EQ(encode_png(im), png);
  const auto decoded = test::decode_png(png);
  ASSERT_TRUE(decoded);
  EXPECT_EQ(decoded->rgb, im.rgb);
}

TEST(PngImage, DamagedBytesAreCaughtByTheChecksums) {
  // Shows the reader used as the oracle does check: flipping a byte of the compressed pixels
  // breaks the CRC of their chunk.
  std::vector<std::uint8_t> bytes = encode_png(gradient(4, 4));
  bytes[bytes.size() - 20] ^= 0x01;
  std::string error;
  EXPECT_FALSE(test::decode_png(bytes, &error));
  EXPECT_EQ(error, "bad CRC in IDAT");
}

TEST(PngImage, EmptyOrInconsistentImagesAreErrors) {
  EXPECT_THROW(encode_png(Image{}), InvalidInputError);
  Image im(2, 2, {1, 2, 3});
  im.rgb.pop_back();
  EXPECT_THROW(encode_png(im), InvalidInputError);
  EXPECT_THROW(Image(0, 3, {0, 0, 0}), InvalidInputError);
}

}  // namespace
}  // namespace cdp
