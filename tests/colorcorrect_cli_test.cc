// End-to-end tests of `candi colorcorrect`: a colour cast removed from a PNG and from point colours
// (patches from a CSV or located in a card photo by their corners), ΔE reported, exit codes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "io/image/png_io.h"
#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

using Result = CommandResult;

// Six ColorChecker patches (published sRGB) and greys: enough to span RGB.
const int kPatches[][3] = {{115, 82, 68}, {98, 122, 157}, {214, 126, 44}, {80, 91, 166},
                           {157, 188, 64}, {175, 54, 60},  {8, 133, 161},  {243, 243, 242},
                           {122, 122, 121}, {52, 52, 52}};
constexpr int kCount = 10;

double Decode(double v) { v /= 255; return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }
double Encode(double v) {
  v = std::clamp(v, 0.0, 1.0);
  return 255 * (v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055);
}

// The camera's cast, in linear RGB.
uint8_t Cast(const int* rgb, int c) {
  const double m[3][4] = {{0.80, 0.10, 0.05, 0.02}, {0.06, 0.85, 0.05, 0.01}, {0.03, 0.07, 0.78, 0.03}};
  double v = m[c][3];
  for (int k = 0; k < 3; ++k) v += m[c][k] * Decode(rgb[k]);
  return static_cast<uint8_t>(std::lround(Encode(v)));
}

std::string PatchesCsv() {
  std::string csv = "patch,measured_r,measured_g,measured_b,reference_r,reference_g,reference_b\n";
  for (int i = 0; i < kCount; ++i) {
    const int* p = kPatches[i];
    csv += "p" + std::to_string(i) + "," + std::to_string(Cast(p, 0)) + "," + std::to_string(Cast(p, 1)) +
           "," + std::to_string(Cast(p, 2)) + "," + std::to_string(p[0]) + "," + std::to_string(p[1]) +
           "," + std::to_string(p[2]) + "\n";
  }
  return csv;
}

// A photo: one 20x20 block per patch in a row, with the cast.
Image8 CastImage() {
  Image8 image(20 * kCount, 20, 3);
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < image.width(); ++x) {
      for (int c = 0; c < 3; ++c) image.at(x, y, c) = Cast(kPatches[x / 20], c);
    }
  }
  return image;
}

TEST(ColorCorrectCli, RemovesACastFromAPngAndReportsDeltaE) {
  TempDir dir;
  WriteBytes(dir.File("card.csv"), PatchesCsv());
  io::WritePng(dir.File("photo.png"), CastImage());
  const Result r = RunCandi("colorcorrect " + dir.File("photo.png") + " -o " + dir.File("fixed.png") +
                            " --patches " + dir.File("card.csv"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.out.find("CIEDE2000"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("mean (fitted)"), std::string::npos) << r.out;
  const io::PngImage fixed = io::ReadPng(dir.File("fixed.png"));
  for (int i = 0; i < kCount; ++i) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(fixed.image8.at(20 * i + 10, 10, c), kPatches[i][c], 2.0) << i;
  }
  const nlohmann::json j = nlohmann::json::parse(ReadBytes(dir.File("fixed.png.colorcorrect.json")));
  EXPECT_LT(j["mean_after"].get<double>(), 1.0);
  EXPECT_GT(j["mean_before"].get<double>(), 3.0);
  EXPECT_EQ(j["delta_e"], "CIEDE2000");
}

TEST(ColorCorrectCli, LocatesPatchesInACardPhotoAndCorrectsPointColours) {
  TempDir dir;
  io::WritePng(dir.File("card.png"), CastImage());
  std::string csv = "patch,x0,y0,x1,y1,x2,y2,x3,y3,reference_r,reference_g,reference_b\n";
  for (int i = 0; i < kCount; ++i) {
    char line[200];
    std::snprintf(line, sizeof(line), "p%d,%d,1,%d,1,%d,18,%d,18,%d,%d,%d\n", i, 20 * i + 1,
                  20 * i + 18, 20 * i + 18, 20 * i + 1, kPatches[i][0], kPatches[i][1], kPatches[i][2]);
    csv += line;
  }
  WriteBytes(dir.File("corners.csv"), csv);
  PointCloud cloud;
  cloud.SetSchema([] { PointSchema s; s.colors = true; return s; }());
  for (int i = 0; i < kCount; ++i) {
    cloud.positions.emplace_back(i, 0, 0);
    cloud.colors.push_back(Rgb8{Cast(kPatches[i], 0), Cast(kPatches[i], 1), Cast(kPatches[i], 2)});
  }
  io::WritePointCloud(dir.File("in.ply"), cloud);
  const Result r = RunCandi("colorcorrect " + dir.File("in.ply") + " -o " + dir.File("out.ply") +
                            " --card " + dir.File("card.png") + " --corners " + dir.File("corners.csv"));
  ASSERT_EQ(r.code, 0) << r.output;
  const PointCloud out = io::ReadPointCloud(dir.File("out.ply"));
  ASSERT_EQ(out.size(), static_cast<size_t>(kCount));
  for (int i = 0; i < kCount; ++i) {
    EXPECT_NEAR(out.colors[i].r, kPatches[i][0], 2.0) << i;
    EXPECT_NEAR(out.colors[i].b, kPatches[i][2], 2.0) << i;
  }
}

TEST(ColorCorrectCli, BadInputsAndOptionsGiveClearErrorsAndExitCodes) {
  TempDir dir;
  WriteBytes(dir.File("card.csv"), PatchesCsv());
  io::WritePng(dir.File("photo.png"), CastImage());
  const std::string patches = " --patches " + dir.File("card.csv");
  Result r = RunCandi("colorcorrect " + dir.File("missing.png") + " -o " + dir.File("o.png") + patches);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("missing.png"), std::string::npos) << r.output;
  const std::string base = "colorcorrect " + dir.File("photo.png") + " -o ";
  EXPECT_EQ(RunCandi(base + dir.File("o.png") + patches + " --max-outliers -1").code, 1);
  EXPECT_EQ(RunCandi(base + dir.File("o.png") + patches + " --outlier-delta-e 0").code, 1);
  EXPECT_EQ(RunCandi(base + dir.File("o.png")).code, 1);  // neither --patches nor --card
  EXPECT_EQ(RunCandi(base + dir.File("o.ply") + patches).code, 1);  // PNG in, points out
  r = RunCandi(base + dir.File("no/such/folder/o.png") + patches);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("no/such/folder/o.png"), std::string::npos) << r.output;
  WriteBytes(dir.File("grey.csv"),
             "patch,measured_r,measured_g,measured_b,reference_r,reference_g,reference_b\n"
             "a,10,10,10,12,12,12\nb,50,50,50,55,55,55\nc,100,100,100,110,110,110\n"
             "d,200,200,200,210,210,210\nbad,1,2,x,4,5,6\n");
  r = RunCandi(base + dir.File("o.png") + " --patches " + dir.File("grey.csv"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("grey.csv: line 6: field 'measured_b'"), std::string::npos) << r.output;
  WriteBytes(dir.File("grey.csv"),
             "patch,measured_r,measured_g,measured_b,reference_r,reference_g,reference_b\n"
             "a,10,10,10,12,12,12\nb,50,50,50,55,55,55\nc,100,100,100,110,110,110\n"
             "d,200,200,200,210,210,210\n");
  r = RunCandi(base + dir.File("o.png") + " --patches " + dir.File("grey.csv"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("do not span RGB"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir.File("o.png")));
}

}  // namespace
}  // namespace candi::testing
