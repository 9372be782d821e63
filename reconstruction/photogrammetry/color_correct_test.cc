#include "reconstruction/photogrammetry/color_correct.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "core/check.h"
#include "core/rng.h"
#include "tests/util/color_checker.h"
#include "tests/util/test_util.h"

namespace candi::photogrammetry {
namespace {

using V = Eigen::Vector3d;

// The camera's error: measured_lin = D [reference_lin; 1] (a colour cast, crosstalk, an offset).
ColorMatrix Distortion() {
  ColorMatrix d;
  d << 0.80, 0.10, 0.05, 0.02,  //
      0.06, 0.85, 0.05, 0.01,   //
      0.03, 0.07, 0.78, 0.03;
  return d;
}

std::vector<ColorPatch> SyntheticCard(double noise, uint64_t seed) {
  Rng rng(seed);
  std::vector<ColorPatch> patches;
  for (const testing::ReferencePatch& p : testing::ColorChecker24()) {
    V measured = ApplyColorMatrix(Distortion(), p.Rgb());
    measured += noise * V(rng.Normal(), rng.Normal(), rng.Normal());
    patches.push_back({p.name, measured.cwiseMax(0.0).cwiseMin(255.0), p.Rgb(), 0});
  }
  return patches;
}

TEST(DeltaE2000, MatchesSharmasTestData) {
  // G. Sharma, W. Wu, E. Dalal (2005), test pairs 1, 7 and 17.
  EXPECT_NEAR(DeltaE2000(V(50, 2.6772, -79.7751), V(50, 0, -82.7485)), 2.0425, 1e-4);
  EXPECT_NEAR(DeltaE2000(V(50, 0, 0), V(50, -1, 2)), 2.3669, 1e-4);
  EXPECT_NEAR(DeltaE2000(V(50, 2.5, 0), V(73, 25, -18)), 27.1492, 1e-4);
  EXPECT_EQ(DeltaE2000(V(40, 10, 10), V(40, 10, 10)), 0.0);
}

TEST(SrgbToLab, WhiteIsNeutralAndTheRoundTripHolds) {
  const V white = SrgbToLab(V(255, 255, 255));
  EXPECT_NEAR(white[0], 100, 1e-3);
  EXPECT_NEAR(white[1], 0, 1e-3);
  EXPECT_NEAR(white[2], 0, 1e-3);
  // The standard's two pieces meet with a 3e-8 step at 0.04045 / 0.0031308 (IEC 61966-2-1).
  for (double v : {0.0, 0.01, 0.04045, 0.5, 1.0}) EXPECT_NEAR(LinearToSrgb(SrgbToLinear(v)), v, 1e-7);
}

TEST(FitColorCorrection, RecoversTheInverseOfAKnownDistortion) {
  const ColorCorrection c = FitColorCorrection({}, SyntheticCard(0, 0));
  Eigen::Matrix4d d = Eigen::Matrix4d::Identity();
  d.topRows<3>() = Distortion();
  const ColorMatrix product = c.matrix * d;  // should be [I | 0]
  EXPECT_LT((product - ColorMatrix::Identity()).cwiseAbs().maxCoeff(), 1e-6) << product;
  EXPECT_LT(c.max_after, 1.0);
  EXPECT_LT(c.mean_after, 0.01);
  EXPECT_GT(c.mean_before, 3.0);  // the cast is visible
  EXPECT_TRUE(c.warnings.empty());
  for (const PatchDeltaE& p : c.patches) EXPECT_FALSE(p.outlier) << p.name;
}

TEST(FitColorCorrection, ReducesTheErrorUnderNoise) {
  const ColorCorrection c = FitColorCorrection({}, SyntheticCard(2.0, 1));
  EXPECT_LT(c.mean_after, 0.5 * c.mean_before);
  EXPECT_LT(c.mean_after, 2.0);
  EXPECT_EQ(c.patches.size(), 24u);
}

TEST(FitColorCorrection, LeavesOutAndReportsOneBadPatch) {
  std::vector<ColorPatch> card = SyntheticCard(1.0, 2);
  card[6].measured = V(30, 200, 40);  // "orange" misread (a reflection, the wrong patch)
  const ColorCorrection c = FitColorCorrection({}, card);
  for (size_t i = 0; i < card.size(); ++i) EXPECT_EQ(c.patches[i].outlier, i == 6) << card[i].name;
  ASSERT_EQ(c.warnings.size(), 1u);
  EXPECT_NE(c.warnings[0].find("'orange'"), std::string::npos);
  EXPECT_LT(c.mean_after, 1.5);
  EXPECT_GT(c.patches[6].after, 20);
}

TEST(FitColorCorrection, RejectsGreyOnlyAndTooFewPatches) {
  std::vector<ColorPatch> grey;
  for (double v : {40.0, 80.0, 120.0, 160.0, 200.0, 240.0}) grey.push_back({"g", V(v, v, v), V(v, v, v), 0});
  try {
    FitColorCorrection({}, grey);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("do not span RGB"), std::string::npos) << e.what();
  }
  std::vector<ColorPatch> three = SyntheticCard(0, 0);
  three.resize(3);
  EXPECT_THROW(FitColorCorrection({}, three), InputError);
  ColorCorrectionOptions o;
  o.max_outliers = -1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  EXPECT_NO_THROW(ColorCorrectionOptions().Check());
}

// A card photo: 24 patches as slightly rotated quads on a dark surround, with noise.
Image8 CardImage(std::vector<PatchQuad>* quads) {
  Image8 image(260, 180, 3, 20);
  const double angle = 0.05;
  const Eigen::Matrix2d r = Eigen::Rotation2Dd(angle).toRotationMatrix();
  const auto& refs = testing::ColorChecker24();
  for (int k = 0; k < 24; ++k) {
    const Eigen::Vector2d origin(20 + 38 * (k % 6), 15 + 38 * (k / 6));
    PatchQuad q;
    q.name = refs[k].name;
    q.reference = refs[k].Rgb();
    const Eigen::Vector2d corner[4] = {{0, 0}, {30, 0}, {30, 30}, {0, 30}};
    for (int c = 0; c < 4; ++c) q.corners[c] = origin + r * corner[c];
    quads->push_back(q);
    const V measured = ApplyColorMatrix(Distortion(), refs[k].Rgb());
    for (int y = 0; y < image.height(); ++y) {
      for (int x = 0; x < image.width(); ++x) {
        const Eigen::Vector2d local = r.transpose() * (Eigen::Vector2d(x, y) - origin);
        if (local.minCoeff() < 0 || local.maxCoeff() > 30) continue;
        for (int c = 0; c < 3; ++c) {
          const double noise = ((x * 7 + y * 13 + c) % 5) - 2;  // +-2 levels
          image.at(x, y, c) = static_cast<uint8_t>(std::clamp(std::lround(measured[c] + noise), 0L, 255L));
        }
      }
    }
  }
  return image;
}

TEST(SamplePatches, TakesTheMedianOfEachQuadsInnerHalf) {
  std::vector<PatchQuad> quads;
  const Image8 image = CardImage(&quads);
  const std::vector<ColorPatch> patches = SamplePatches(image, quads, "corners.csv");
  ASSERT_EQ(patches.size(), 24u);
  for (int k = 0; k < 24; ++k) {
    const V expected = ApplyColorMatrix(Distortion(), testing::ColorChecker24()[k].Rgb());
    EXPECT_LT((patches[k].measured - expected).cwiseAbs().maxCoeff(), 1.01) << patches[k].name;
  }
  const ColorCorrection c = FitColorCorrection({}, patches);
  EXPECT_LT(c.mean_after, 1.0);
  quads[3].corners[2] = Eigen::Vector2d(400, 10);
  quads[3].line = 5;
  try {
    SamplePatches(image, quads, "corners.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("corners.csv: line 5: patch 'foliage' reaches outside"),
              std::string::npos) << e.what();
  }
}

TEST(ApplyColorMatrix, CorrectsImagesAndPointColours) {
  const ColorCorrection c = FitColorCorrection({}, SyntheticCard(0, 0));
  Image8 image(24, 1, 4, 255);
  PointCloud cloud;
  cloud.SetSchema([] { PointSchema s; s.colors = true; return s; }());
  cloud.Resize(24);
  for (int k = 0; k < 24; ++k) {
    const V m = ApplyColorMatrix(Distortion(), testing::ColorChecker24()[k].Rgb());
    for (int ch = 0; ch < 3; ++ch) image.at(k, 0, ch) = static_cast<uint8_t>(std::lround(m[ch]));
    image.at(k, 0, 3) = static_cast<uint8_t>(k);
    cloud.colors[k] = Rgb8{image.at(k, 0, 0), image.at(k, 0, 1), image.at(k, 0, 2)};
  }
  ApplyColorMatrix(c.matrix, &image);
  ApplyColorMatrix(c.matrix, &cloud);
  for (int k = 0; k < 24; ++k) {
    const V ref = testing::ColorChecker24()[k].Rgb();
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(image.at(k, 0, ch), ref[ch], 2.0) << k;
    EXPECT_EQ(image.at(k, 0, 3), k);  // alpha kept
    EXPECT_EQ(cloud.colors[k], (Rgb8{image.at(k, 0, 0), image.at(k, 0, 1), image.at(k, 0, 2)}));
  }
  Image8 grey(2, 2, 1);
  EXPECT_THROW(ApplyColorMatrix(c.matrix, &grey), std::invalid_argument);
}

TEST(ReadColorPatches, ErrorsNameTheLineAndField) {
  testing::TempDir dir;
  const std::string header =
      "patch,measured_r,measured_g,measured_b,reference_r,reference_g,reference_b\n";
  testing::WriteBytes(dir.File("p.csv"), header + "a,1,2,3,4,5,6\nb,1,300,3,4,5,6\n");
  try {
    ReadColorPatches(dir.File("p.csv"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("p.csv: line 3: field 'measured_g': 300; must be in 0..255"),
              std::string::npos) << e.what();
  }
  testing::WriteBytes(dir.File("p.csv"), header + "a,1,2,3,4,5,6\n");
  EXPECT_EQ(ReadColorPatches(dir.File("p.csv")).at(0).reference, V(4, 5, 6));
}

}  // namespace
}  // namespace candi::photogrammetry
