#include "io/image/jpeg_io.h"

#include <gtest/gtest.h>

#include <cmath>

#include "io/image/png_io.h"
#include "tests/util/input_error.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using testing::TempDir;

// A smooth colour ramp: JPEG at quality 100 keeps it within a few grey levels.
Image8 Ramp(int w, int h, int channels) {
  Image8 image(w, h, channels);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < channels; ++c)
        image.at(x, y, c) = static_cast<uint8_t>((x * 3 + y * 2 + 40 * c) % 256 / 2 + 60);
  return image;
}

int MaxDifference(const Image8& a, const Image8& b) {
  int worst = 0;
  for (size_t i = 0; i < a.values().size(); ++i)
    worst = std::max(worst, std::abs(int(a.values()[i]) - int(b.values()[i])));
  return worst;
}

TEST(Jpeg, ColourAndGreyRoundTrip) {
  TempDir dir;
  const Image8 rgb = Ramp(40, 24, 3);
  WriteJpeg(dir.File("a.jpg"), rgb, 100);
  const Image8 a = ReadJpeg(dir.File("a.jpg"));
  ASSERT_EQ(a.width(), 40);
  ASSERT_EQ(a.height(), 24);
  ASSERT_EQ(a.channels(), 3);
  EXPECT_LE(MaxDifference(a, rgb), 4);

  const Image8 grey = Ramp(17, 9, 1);  // odd sizes: partial MCUs
  WriteJpeg(dir.File("g.jpg"), grey, 100);
  const Image8 g = ReadJpeg(dir.File("g.jpg"));
  ASSERT_EQ(g.channels(), 1);
  EXPECT_LE(MaxDifference(g, grey), 3);
  // Lower quality: smaller file, larger error, still the same picture.
  WriteJpeg(dir.File("q.jpg"), rgb, 30);
  EXPECT_LT(testing::ReadBytes(dir.File("q.jpg")).size(), testing::ReadBytes(dir.File("a.jpg")).size());
  EXPECT_LE(MaxDifference(ReadJpeg(dir.File("q.jpg")), rgb), 40);
}

TEST(Jpeg, ReadImageRgb8AcceptsPngAndJpegByContent) {
  TempDir dir;
  const Image8 rgb = Ramp(8, 6, 3);
  WriteJpeg(dir.File("photo.png"), rgb, 100);  // a JPEG with the wrong extension
  EXPECT_LE(MaxDifference(ReadImageRgb8(dir.File("photo.png")), rgb), 4);

  WritePng(dir.File("rgba.jpg"), Ramp(8, 6, 4));  // a PNG with the wrong extension; alpha dropped
  const Image8 rgba = ReadImageRgb8(dir.File("rgba.jpg"));
  ASSERT_EQ(rgba.channels(), 3);
  EXPECT_EQ(rgba.at(5, 4, 2), Ramp(8, 6, 4).at(5, 4, 2));

  Image16 wide(3, 2, 1);
  wide.values() = {0, 65535, 257 * 100, 32768, 128, 65535};
  WritePng(dir.File("wide.png"), wide);
  const Image8 w = ReadImageRgb8(dir.File("wide.png"));
  ASSERT_EQ(w.channels(), 3);
  EXPECT_EQ(w.at(0, 0, 1), 0);
  EXPECT_EQ(w.at(1, 0, 0), 255);
  EXPECT_EQ(w.at(2, 0, 2), 100);
  EXPECT_EQ(w.at(0, 1, 0), 128);  // 32768 * 255 / 65535 = 127.5 -> 128
  EXPECT_EQ(w.at(1, 1, 0), 0);    // 128 -> 0.498 -> 0
}

TEST(Jpeg, BadFilesAreInputErrorsNamingThePath) {
  TempDir dir;
  EXPECT_NE(testing::InputErrorMessage([&] { ReadJpeg(dir.File("missing.jpg")); }).find("missing.jpg"),
            std::string::npos);
  testing::WriteBytes(dir.File("x.jpg"), "not a jpeg");
  EXPECT_NE(testing::InputErrorMessage([&] { ReadJpeg(dir.File("x.jpg")); }).find("not a JPEG"),
            std::string::npos);
  testing::WriteBytes(dir.File("t.tif"), std::string("II*\0abcdefgh", 12));
  EXPECT_NE(testing::InputErrorMessage([&] { ReadImageRgb8(dir.File("t.tif")); }).find("TIFF"),
            std::string::npos);
  // Truncated: libjpeg would fill the rest with grey; candi refuses it.
  WriteJpeg(dir.File("full.jpg"), Ramp(64, 64, 3), 90);
  const std::string bytes = testing::ReadBytes(dir.File("full.jpg"));
  testing::WriteBytes(dir.File("cut.jpg"), bytes.substr(0, bytes.size() * 2 / 3));
  EXPECT_NE(testing::InputErrorMessage([&] { ReadJpeg(dir.File("cut.jpg")); }).find("truncated"),
            std::string::npos);
  // Only the header: fails in the header or the scan, never a crash.
  testing::WriteBytes(dir.File("head.jpg"), bytes.substr(0, 20));
  EXPECT_THROW(ReadJpeg(dir.File("head.jpg")), InputError);
  // A failed write leaves nothing behind.
  EXPECT_THROW(WriteJpeg(dir.File("no/dir/y.jpg"), Ramp(4, 4, 3)), InputError);
  EXPECT_FALSE(testing::FileExists(dir.File("no/dir/y.jpg")));
}

// The viewer's frames: EncodeJpeg's bytes are a JPEG, and exactly what WriteJpeg puts in the file.
TEST(Jpeg, EncodedBytesAreTheFile) {
  TempDir dir;
  const std::string bytes = EncodeJpeg(Ramp(37, 21, 3), 85);
  EXPECT_EQ(bytes.compare(0, 3, "\xff\xd8\xff"), 0);
  WriteJpeg(dir.File("a.jpg"), Ramp(37, 21, 3), 85);
  EXPECT_EQ(testing::ReadBytes(dir.File("a.jpg")), bytes);
  EXPECT_EQ(ReadJpeg(dir.File("a.jpg")).channels(), 3);
  EXPECT_THROW(EncodeJpeg(Ramp(4, 4, 1), 0), InternalError);
}

}  // namespace
}  // namespace candi::io
