// PNG files with stored deflate blocks: checksums, round trips through an independent reader,
// images larger than one block, invalid images.
#include <gtest/gtest.h>

#include <raytrace/png_image.h>

#include <polygonizer/errors.h>

#include "common/png_decode.h"

#include <cstring>

namespace cdp {
namespace {

TEST(PngChecksums, MatchTheStandardCheckValues) {
  const char* check = "123456789";
  EXPECT_EQ(crc32(reinterpret_cast<const std::uint8_t*>(check), 9), 0xCBF43926u);
  const char* wiki = "Wikipedia";
  EXPECT_EQ(adler32(reinterpret_cast<const std::uint8_t*>(wiki), std::strlen(wiki)), 0x11E60398u);
}

Image gradient(int w, int h) {
  Image im(w, h, {0, 0, 0});
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      im.set(x, y, {static_cast<std::uint8_t>(x * 7), static_cast<std::uint8_t>(y * 3), static_cast<std::uint8_t>(x ^ y)});
  return im;
}

TEST(PngImage, RoundTripKeepsSizeAndEveryPixel) {
  // 3 x 2 fits one stored block; 300 x 100 (90 kB of scanlines) needs two.
  for (auto [w, h] : {std::pair{3, 2}, std::pair{300, 100}, std::pair{1, 1}}) {
    const Image im = gradient(w, h);
    std::string error;
    const auto png = test::decode_png(encode_png(im), &error);
    ASSERT_TRUE(png) << error << " at " << w << "x" << h;
    EXPECT_EQ(png->width, w);
    EXPECT_EQ(png->height, h);
    EXPECT_EQ(png->rgb, im.rgb);
  }
}

TEST(PngImage, DamagedBytesAreCaughtByTheChecksums) {
  // Shows the reader used as the oracle does check: flipping a pixel byte breaks the CRC.
  std::vector<std::uint8_t> bytes = encode_png(gradient(4, 4));
  bytes[bytes.size() - 20] ^= 0x01;
  EXPECT_FALSE(test::decode_png(bytes));
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
