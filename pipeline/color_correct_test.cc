// candi colorcorrect's pipeline without argv: a cast in linear RGB put on reference colours and
// taken off again, from a patches CSV into a PNG and from a card photo into point colours; what is
// written, and when; bad inputs. The fit itself is tested in photogrammetry/color_correct_test.cc.
#include "pipeline/color_correct.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/check.h"
#include "io/image/png_io.h"
#include "io/point_io.h"
#include "tests/util/test_util.h"

namespace candi::pipeline {
namespace {

namespace pg = photogrammetry;
using testing::FileExists;
using testing::ReadBytes;
using testing::TempDir;
using testing::WriteBytes;

// Eight reference colours spanning RGB, and each as a camera with a cast records it.
const Rgb8 kReference[] = {{115, 82, 68},  {98, 122, 157},  {214, 126, 44},  {80, 91, 166},
                           {157, 188, 64}, {243, 243, 242}, {122, 122, 121}, {52, 52, 52}};
constexpr int kCount = 8;

Rgb8 WithCast(const Rgb8& c) {
  const Eigen::Vector3d in(pg::SrgbToLinear(c.r / 255.0), pg::SrgbToLinear(c.g / 255.0),
                           pg::SrgbToLinear(c.b / 255.0));
  Eigen::Matrix3d m;
  m << 0.80, 0.10, 0.05, 0.06, 0.85, 0.05, 0.03, 0.07, 0.78;
  const Eigen::Vector3d out = m * in + Eigen::Vector3d(0.02, 0.01, 0.03);
  auto byte = [](double v) { return static_cast<uint8_t>(std::lround(255 * pg::LinearToSrgb(v))); };
  return {byte(out.x()), byte(out.y()), byte(out.z())};
}

std::string Csv(const Rgb8& c) {
  return std::to_string(c.r) + "," + std::to_string(c.g) + "," + std::to_string(c.b);
}

// A photo of the patches with the cast, 10 x 10 pixels each in a row; `grey`: one channel.
Image8 Photo(int channels = 3) {
  Image8 image(10 * kCount, 10, channels);
  for (int y = 0; y < 10; ++y) {
    for (int x = 0; x < image.width(); ++x) {
      const Rgb8 c = WithCast(kReference[x / 10]);
      for (int k = 0; k < channels; ++k) image.at(x, y, k) = k == 0 ? c.r : k == 1 ? c.g : c.b;
    }
  }
  return image;
}

ColorCard PatchesCsv(const TempDir& dir) {
  std::string csv = "patch,measured_r,measured_g,measured_b,reference_r,reference_g,reference_b\n";
  for (int i = 0; i < kCount; ++i)
    csv += "p" + std::to_string(i) + "," + Csv(WithCast(kReference[i])) + "," + Csv(kReference[i]) +
           "\n";
  WriteBytes(dir.File("patches.csv"), csv);
  ColorCard card;
  card.patches = dir.File("patches.csv");
  return card;
}

TEST(ColorCorrectFile, APngCorrectedFromItsPatchesAfterTheFitIsReported) {
  TempDir dir;
  io::WritePng(dir.File("photo.png"), Photo(), {{"Source", "test"}});
  bool fitted = false;
  const pg::ColorCorrection c =
      ColorCorrectFile(pg::ColorCorrectionOptions(), PatchesCsv(dir), dir.File("photo.png"),
                       dir.File("fixed.png"), [&](const pg::ColorCorrection& fit) {
                         fitted = true;
                         EXPECT_EQ(fit.patches.size(), size_t{kCount});
                         EXPECT_FALSE(FileExists(dir.File("fixed.png")));
                       });
  EXPECT_TRUE(fitted);
  EXPECT_LT(c.mean_after, 1.0);
  const io::PngImage fixed = io::ReadPng(dir.File("fixed.png"));
  EXPECT_EQ(fixed.text.at("Source"), "test");
  for (int i = 0; i < kCount; ++i)
    EXPECT_NEAR(fixed.image8.at(10 * i + 5, 5, 1), kReference[i].g, 2.0) << i;
  const nlohmann::json j =
      nlohmann::json::parse(ReadBytes(dir.File("fixed.png.colorcorrect.json")));
  EXPECT_EQ(j["patches"].size(), size_t{kCount});
  EXPECT_EQ(j["delta_e"], "CIEDE2000");
}

// The card: Photo() as DIR/card.png, and each patch's inner 8 x 8 pixels in DIR/corners.csv.
ColorCard CardPhoto(const TempDir& dir) {
  io::WritePng(dir.File("card.png"), Photo());
  std::string corners = "patch,x0,y0,x1,y1,x2,y2,x3,y3,reference_r,reference_g,reference_b\n";
  for (int i = 0; i < kCount; ++i) {
    const std::string x0 = std::to_string(10 * i + 1), x1 = std::to_string(10 * i + 8);
    corners += "p" + std::to_string(i) + "," + x0 + ",1," + x1 + ",1," + x1 + ",8," + x0 + ",8," +
               Csv(kReference[i]) + "\n";
  }
  WriteBytes(dir.File("corners.csv"), corners);
  ColorCard card;
  card.card = dir.File("card.png");
  card.corners = dir.File("corners.csv");
  return card;
}

TEST(ColorCorrectFile, PointColoursCorrectedFromACardPhoto) {
  TempDir dir;
  PointCloud cloud;
  cloud.schema.colors = true;
  for (int i = 0; i < kCount; ++i) {
    cloud.positions.emplace_back(i, 0, 0);
    cloud.colors.push_back(WithCast(kReference[i]));
  }
  io::WritePointCloud(dir.File("points.ply"), cloud);
  ColorCorrectFile(pg::ColorCorrectionOptions(), CardPhoto(dir), dir.File("points.ply"),
                   dir.File("fixed.ply"));
  const PointCloud fixed = io::ReadPointCloud(dir.File("fixed.ply"));
  ASSERT_EQ(fixed.size(), size_t{kCount});
  for (int i = 0; i < kCount; ++i) EXPECT_NEAR(fixed.colors[i].r, kReference[i].r, 2.0) << i;
  EXPECT_TRUE(FileExists(dir.File("fixed.ply.colorcorrect.json")));
}

TEST(ColorCorrectFile, BadInputsAreNamedBeforeAnythingIsWritten) {
  TempDir dir;
  const ColorCard card = PatchesCsv(dir);
  const pg::ColorCorrectionOptions o;
  io::WritePng(dir.File("photo.png"), Photo());
  EXPECT_THROW(ColorCorrectFile(o, ColorCard(), dir.File("photo.png"), dir.File("a.png")),
               std::invalid_argument);
  EXPECT_THROW(ColorCorrectFile(o, card, dir.File("photo.png"), dir.File("a.ply")),
               std::invalid_argument);
  EXPECT_THROW(ColorCorrectFile(o, card, dir.File("missing.png"), dir.File("a.png")), InputError);
  io::WritePng(dir.File("grey.png"), Photo(1));
  EXPECT_THROW(ColorCorrectFile(o, card, dir.File("grey.png"), dir.File("a.png")), InputError);
  PointCloud plain;
  plain.positions = {{0, 0, 0}, {1, 0, 0}};
  io::WritePointCloud(dir.File("plain.ply"), plain);
  EXPECT_THROW(ColorCorrectFile(o, card, dir.File("plain.ply"), dir.File("a.ply")), InputError);
  io::WritePng(dir.File("card16.png"), Image16(80, 10, 3));
  ColorCard deep;
  deep.card = dir.File("card16.png");
  deep.corners = dir.File("corners.csv");
  EXPECT_THROW(ColorCorrectFile(o, deep, dir.File("photo.png"), dir.File("a.png")), InputError);
  EXPECT_FALSE(FileExists(dir.File("a.png")));
  EXPECT_FALSE(FileExists(dir.File("a.ply")));
}

}  // namespace
}  // namespace candi::pipeline
