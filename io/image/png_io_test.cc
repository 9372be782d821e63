#include "io/image/png_io.h"

#include <gtest/gtest.h>

#include "core/rng.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using testing::TempDir;

TEST(Png, EightAndSixteenBitRoundTripWithText) {
  TempDir dir;
  Image8 rgb(5, 3, 3);
  for (size_t i = 0; i < rgb.values().size(); ++i) rgb.values()[i] = static_cast<uint8_t>(17 * i);
  WritePng(dir.File("a.png"), rgb, {{"Seed", "42"}, {"RepeatLevel", "100"}});
  const PngImage a = ReadPng(dir.File("a.png"));
  EXPECT_EQ(a.bit_depth, 8);
  EXPECT_EQ(a.image8, rgb);
  EXPECT_EQ(a.text.at("Seed"), "42");

  Image16 grey(4, 4, 1);
  for (size_t i = 0; i < grey.values().size(); ++i) grey.values()[i] = static_cast<uint16_t>(4099 * i);
  WritePng(dir.File("b.png"), grey);
  const PngImage b = ReadPng(dir.File("b.png"));
  EXPECT_EQ(b.bit_depth, 16);
  EXPECT_EQ(b.image16, grey);
}

TEST(Png, BadFilesAndPathsAreInputErrors) {
  TempDir dir;
  testing::WriteBytes(dir.File("x.png"), "not a png at all");
  EXPECT_THROW(ReadPng(dir.File("x.png")), InputError);
  EXPECT_THROW(ReadPng(dir.File("missing.png")), InputError);
  EXPECT_THROW(WritePng(dir.File("no/dir/y.png"), Image8(2, 2, 3)), InputError);
  EXPECT_FALSE(testing::FileExists(dir.File("no/dir/y.png")));
  // A truncated PNG is refused, not half-read.
  WritePng(dir.File("t.png"), Image8(64, 64, 3, 9));
  std::string bytes = testing::ReadBytes(dir.File("t.png"));
  testing::WriteBytes(dir.File("t.png"), bytes.substr(0, bytes.size() / 2));
  EXPECT_THROW(ReadPng(dir.File("t.png")), InputError);
}

// The viewer's converged frames: fast compression is still lossless, the text chunks travel, and
// the balanced encoding is exactly what WritePng puts in the file.
TEST(Png, EncodedBytesDecodeAndMatchTheFile) {
  Image8 rgb(37, 21, 3);
  Rng rng(4);
  for (uint8_t& v : rgb.values()) v = static_cast<uint8_t>(rng.Uniform(0, 256));
  TempDir dir;
  testing::WriteBytes(dir.File("fast.png"), EncodePng(rgb, {{"Seed", "4"}}, PngCompression::kFast));
  const PngImage fast = ReadPng(dir.File("fast.png"));
  EXPECT_EQ(fast.image8, rgb);
  EXPECT_EQ(fast.text.at("Seed"), "4");
  Image16 grey(6, 5, 1);
  for (size_t i = 0; i < grey.values().size(); ++i) grey.values()[i] = static_cast<uint16_t>(2017 * i);
  WritePng(dir.File("grey.png"), grey, {{"RepeatLevel", "3"}});
  EXPECT_EQ(testing::ReadBytes(dir.File("grey.png")), EncodePng(grey, {{"RepeatLevel", "3"}}));
  EXPECT_NE(EncodePng(rgb), EncodePng(rgb, {}, PngCompression::kFast));
}

TEST(Png, BadTextKeyIsAnInputError) {
  EXPECT_THROW(EncodePng(Image8(2, 2, 3), {{"", "an empty key"}}), InputError);
}

}  // namespace
}  // namespace candi::io
