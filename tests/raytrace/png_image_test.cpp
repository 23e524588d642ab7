// PNG files with stored deflate blocks: checksums, round trips through an independent reader,
// images larger than one block, atomic writing.
#include <gtest/gtest.h>

#include <raytrace/png_image.h>

#include <polygonizer/errors.h>

#include "common/png_decode.h"
#include "common/run_command.h"

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

TEST(PngImage, WritesAtomicallyAndNamesTheFileOnFailure) {
  test::TempDir dir("png_image");
  write_png(gradient(5, 4), dir.path / "a.png");
  const auto png = test::read_png_file((dir.path / "a.png").string());
  ASSERT_TRUE(png);
  EXPECT_EQ(png->width, 5);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path), {}), 1) << "no temporary left";
  try {
    write_png(gradient(5, 4), dir.path / "missing" / "b.png");
    FAIL();
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("missing/b.png: cannot write the image"), std::string::npos) << e.what();
  }
  EXPECT_THROW(encode_png(Image{}), InvalidInputError);
}

}  // namespace
}  // namespace cdp
