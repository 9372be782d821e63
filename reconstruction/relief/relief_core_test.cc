// Tests of the torch-free relief pieces: images, synthesis, metrics, baselines, points, tiles,
// dataset. Data is built in code.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/rng.h"
#include "reconstruction/relief/relief_baselines.h"
#include "reconstruction/relief/relief_dataset.h"
#include "reconstruction/relief/relief_image.h"
#include "reconstruction/relief/relief_metrics.h"
#include "reconstruction/relief/relief_net.h"
#include "reconstruction/relief/relief_photo_pairs.h"
#include "reconstruction/relief/relief_place.h"
#include "reconstruction/relief/relief_points.h"
#include "reconstruction/relief/relief_synth.h"
#include "reconstruction/relief/relief_tiles.h"
#include "reconstruction/relief/relief_train.h"
#include "tests/util/option_check.h"
#include "tests/util/test_util.h"

namespace candi::relief {
namespace {

using testing::TempDir;

ImageF Ramp(int w, int h) {
  ImageF im(w, h, 1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) im.at(x, y) = static_cast<float>(10 + 200.0 * x / w + 30.0 * y / h);
  }
  return im;
}

TEST(ReliefOptions, DefaultsPass) {
  testing::ExpectDefaultsPass<SynthOptions, OldPhotoOptions, ReliefPointsOptions, TileOptions,
                              PatchOptions, AugmentOptions, ScanRasterOptions, SurfaceMetricOptions,
                              NetOptions, PredictOptions, TrainOptions, PhotoPairOptions,
                              PanelPlacementOptions>();
  SynthOptions s;
  s.width = 8;
  EXPECT_THROW(s.Check(), std::invalid_argument);
  ReliefPointsOptions p;
  p.depth_m = NAN;
  EXPECT_THROW(p.Check(), std::invalid_argument);
  TileOptions t;
  t.overlap = t.tile;
  EXPECT_THROW(t.Check(), std::invalid_argument);
}

// The messages of the rules that name two fields, an entry or a derived value.
TEST(ReliefOptions, RulesNameTheirFields) {
  using testing::OptionCheckMessage;
  OldPhotoOptions photo;
  photo.light_elevation_max_deg = 95;
  EXPECT_EQ(OptionCheckMessage(photo),
            "OldPhotoOptions::light_elevation_min_deg = 15 and "
            "light_elevation_max_deg = 95; must satisfy 0 < min <= max < 90");
  photo = {};
  photo.light_azimuth_min_deg = 180;
  EXPECT_EQ(OptionCheckMessage(photo),
            "OldPhotoOptions::light_azimuth_min_deg = 180; must be <= light_azimuth_max_deg");
  SynthOptions synth;
  synth.height_m = 0.1;  // 30 pixels
  EXPECT_EQ(OptionCheckMessage(synth),
            "SynthOptions::height_m / width_m * width = 29.629629629629626; must "
            "be >= 32 pixels (rounded)");
  ScanRasterOptions scan;
  scan.frame = "wall";
  EXPECT_EQ(OptionCheckMessage(scan), "ScanRasterOptions::frame = wall; must be auto or panel");
  NetOptions net;
  net.blocks = {4, 6, 8};
  EXPECT_EQ(OptionCheckMessage(net), "NetOptions::blocks = (4, 6, 8); must have 4 entries");
  net.blocks = {4, 0, 8, 6};
  EXPECT_EQ(OptionCheckMessage(net), "NetOptions::blocks[1] = 0; must be in [1, 64]");
  PredictOptions predict;
  predict.tiles.tile = 100;
  EXPECT_EQ(OptionCheckMessage(predict),
            "PredictOptions::tiles.tile = 100; must be a multiple of 32");
  TrainOptions train;
  train.resume = true;
  EXPECT_EQ(OptionCheckMessage(train), "TrainOptions::resume = true; needs a checkpoint path");
  train = {};
  train.end_learning_rate = 1;
  EXPECT_EQ(OptionCheckMessage(train),
            "TrainOptions::end_learning_rate = 1; must be in [0, learning_rate]");
  PhotoPairOptions pairs;
  pairs.far_percentile = pairs.near_percentile;
  EXPECT_EQ(OptionCheckMessage(pairs),
            "PhotoPairOptions::far_percentile = 0.02; must be in (near_percentile, 1]");
}

TEST(ReliefImage, PhotosOfEveryKindReadAsGreyAndDepthRoundTrips) {
  TempDir dir;
  Image16 grey16(4, 2, 1, 65535);
  io::WritePng(dir.File("g16.png"), grey16);
  EXPECT_FLOAT_EQ(ReadPhoto(dir.File("g16.png")).at(3, 1), 1.0f);
  Image8 rgb(4, 2, 3, 0);
  rgb.at(1, 1, 1) = 255;  // pure green: luminance 0.587
  io::WritePng(dir.File("rgb.png"), rgb);
  const ImageF g = ReadPhoto(dir.File("rgb.png"));
  EXPECT_EQ(g.channels(), 1);
  EXPECT_NEAR(g.at(1, 1), 0.587, 1e-6);
  EXPECT_THROW(ReadDepth(dir.File("rgb.png")), InputError);  // colour is not a depth map
  ImageF levels = Ramp(7, 5);
  levels.at(0, 0) = NAN;
  WriteDepth16(dir.File("d16.png"), levels);
  const ImageF back = ReadDepth(dir.File("d16.png"));
  EXPECT_EQ(back.at(0, 0), 0.0f);  // NaN written as "no data"
  EXPECT_NEAR(back.at(6, 4), levels.at(6, 4), 1.0 / 512);
  WriteDepth8(dir.File("d8.png"), levels);
  EXPECT_EQ(ReadDepth(dir.File("d8.png")).at(3, 2), std::round(levels.at(3, 2)));
  EXPECT_THROW(ReadPhoto(dir.File("missing.png")), InputError);
}

TEST(ReliefImage, ResampleKeepsMeansAndLinearRamps) {
  const ImageF a = Ramp(64, 32);
  const ImageF down = Resample(a, 16, 8);
  double sa = 0, sd = 0;
  for (float v : a.values()) sa += v;
  for (float v : down.values()) sd += v;
  EXPECT_NEAR(sa / a.values().size(), sd / down.values().size(), 1e-3);
  const ImageF up = Resample(down, 64, 32);
  EXPECT_NEAR(up.at(32, 16), a.at(32, 16), 0.5);
  EXPECT_EQ(GaussianBlur(a, 0).values(), a.values());
}

TEST(ReliefSynth, PanelsAreDeterministicInRangeAndEffectsSwitch) {
  SynthOptions o;
  o.width = 160;
  const SynthPanel a = SynthesizePanel(o, 3), b = SynthesizePanel(o, 3), c = SynthesizePanel(o, 4);
  EXPECT_EQ(a.photo.photo.values(), b.photo.photo.values());
  EXPECT_EQ(a.depth.values(), b.depth.values());
  EXPECT_NE(a.depth.values(), c.depth.values());
  EXPECT_EQ(a.depth.height(), 55);
  float lo = 1e9, hi = -1e9;
  for (float v : a.height_m.values()) lo = std::min(lo, v), hi = std::max(hi, v);
  EXPECT_GE(lo, 0.0f);
  EXPECT_LT(hi, 0.15f);
  EXPECT_GT(hi, 0.05f) << "carving reaches well out of the wall";
  for (float v : a.photo.photo.values()) ASSERT_TRUE(v >= 0 && v <= 1);
  for (float v : a.depth.values()) ASSERT_GE(v, kMinValidLevel);  // every synthetic pixel is valid
  OldPhotoOptions plain;
  plain.shadows = plain.stains = plain.blur = plain.grain = plain.tone = plain.fading = false;
  const PhotoSimulation p0 = SimulateOldPhoto(plain, a.height_m, {}, a.pixel_m, 1);
  plain.shadows = true;
  const PhotoSimulation p1 = SimulateOldPhoto(plain, a.height_m, {}, a.pixel_m, 1);
  double darker = 0;
  for (size_t i = 0; i < p0.photo.values().size(); ++i) darker += p0.photo.values()[i] - p1.photo.values()[i];
  EXPECT_GT(darker, 0) << "cast shadows darken";
}

TEST(ReliefSynth, CastShadowOfAStepFallsAwayFromTheLight) {
  // A 0.1 m block on the left; light from the left (azimuth 180) at 45 degrees: the wall right
  // of the block is in shadow for 0.1 m, then lit.
  ImageF h(100, 20, 1, 0.0f);
  for (int y = 0; y < 20; ++y) for (int x = 0; x < 20; ++x) h.at(x, y) = 0.1f;
  OldPhotoOptions o;
  o.stains = o.blur = o.grain = o.tone = o.fading = false;
  o.light_azimuth_min_deg = o.light_azimuth_max_deg = 180;
  o.light_elevation_min_deg = o.light_elevation_max_deg = 45;
  const ImageF photo = SimulateOldPhoto(o, h, {}, 0.01, 1).photo;  // 1 cm pixels
  EXPECT_LT(photo.at(25, 10), photo.at(35, 10) * 0.7) << "10 pixels of shadow";
  EXPECT_NEAR(photo.at(35, 10), photo.at(80, 10), 1e-4);
}

TEST(ReliefMetrics, PerfectPredictionAndMasks) {
  const ImageF gt = Ramp(20, 10);
  const DepthMetrics m = ComputeDepthMetrics(gt, gt);
  EXPECT_EQ(m.count, 200);
  EXPECT_EQ(m.delta1, 1.0);
  EXPECT_EQ(m.delta3, 1.0);
  EXPECT_EQ(m.rmse, 0.0);
  EXPECT_EQ(m.rmse_log, 0.0);
  EXPECT_EQ(m.abs_rel, 0.0);
  EXPECT_EQ(m.sq_rel, 0.0);
  ImageF holes = gt, wrong = gt;
  holes.at(0, 0) = 0, holes.at(1, 0) = NAN, holes.at(2, 0) = 0.5f;
  wrong.at(0, 0) = wrong.at(1, 0) = wrong.at(2, 0) = 250;  // at masked pixels only
  const DepthMetrics masked = ComputeDepthMetrics(wrong, holes);
  EXPECT_EQ(masked.count, 197);
  EXPECT_EQ(masked.rmse, 0.0);
  Image8 mask(20, 10, 1, 1);
  mask.at(5, 5) = 0;
  EXPECT_EQ(ComputeDepthMetrics(gt, gt, mask).count, 199);
  // Hand values: prediction 2 g everywhere.
  ImageF half = gt;  // truth 5..120; the prediction (gt) is twice that
  const ImageF& twice = gt;
  for (float& v : half.values()) v *= 0.5f;
    const DepthMetrics t = ComputeDepthMetrics(twice, half);
  EXPECT_EQ(t.delta1, 0.0);
  EXPECT_EQ(t.delta3, 0.0);  // 1.25^3 = 1.953 < 2
  EXPECT_NEAR(t.rmse_log, std::log(2.0), 1e-6);
  EXPECT_NEAR(t.abs_rel, 1.0, 1e-6);
}

TEST(ReliefMetrics, AllZeroDepthAndNanPredictionsAreGuarded) {
  const ImageF zeros(8, 8, 1, 0.0f);
  const DepthMetrics z = ComputeDepthMetrics(Ramp(8, 8), zeros);
  EXPECT_EQ(z.count, 0);
  EXPECT_EQ(z.rmse, 0.0);
  ImageF nan(8, 8, 1, NAN);
  const DepthMetrics n = ComputeDepthMetrics(nan, Ramp(8, 8));
  EXPECT_EQ(n.count, 64);
  EXPECT_TRUE(std::isfinite(n.rmse) && n.rmse > 0) << "NaN counts as the worst, never skipped";
  EXPECT_EQ(n.delta1, 0.0);
}

TEST(ReliefBaselines, PentlandRecoversALinearlyShadedSurface) {
  // z = sin(2 pi x / 32) shaded by a light from the right at 30 deg elevation, linear model.
  const int w = 128, h = 64;
  const double el = 30 * M_PI / 180, lx = std::cos(el);
  ImageF z(w, h, 1), photo(w, h, 1), truth(w, h, 1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double a = 2 * M_PI * x / 32;
      z.at(x, y) = static_cast<float>(std::sin(a));
      photo.at(x, y) = static_cast<float>(0.5 - 0.05 * lx * std::cos(a) * 2 * M_PI / 32);
      truth.at(x, y) = static_cast<float>(128 - 100 * std::sin(a));
    }
  }
  const ImageF levels = FitLevels(PentlandHeight(photo, 0, 30), truth);
  const DepthMetrics m = ComputeDepthMetrics(levels, truth);
  EXPECT_LT(m.rmse, 5.0) << "of a 200-level swing";
  const DepthMetrics flat = ComputeDepthMetrics(FitLevels(IntensityAsHeight(photo), truth), truth);
  EXPECT_GT(flat.rmse, 50.0) << "intensity is the slope, not the height";
  const ImageF constant = FitLevels(ImageF(w, h, 1, 0.3f), truth);  // no variance: the mean
  EXPECT_NEAR(constant.at(3, 3), 128, 1.0);
}

TEST(ReliefPoints, OnePointPerPixelInThePanelFrame) {
  ImageF photo(4, 2, 1, 0.5f), depth(4, 2, 1, 255.0f);
  depth.at(0, 0) = 0;       // front plane
  depth.at(3, 1) = NAN;     // guarded: on the wall
  photo.at(0, 0) = 1.0f;
  ReliefPointsOptions o;
  o.width_m = 4, o.height_m = 2, o.depth_m = 0.15;
  const PointCloud c = DepthToPoints(o, photo, depth);
  ASSERT_EQ(c.size(), 8u);
  EXPECT_TRUE(c.positions[0].isApprox(Eigen::Vector3d(0.5, 1.5, 0.15)));
  EXPECT_TRUE(c.positions[7].isApprox(Eigen::Vector3d(3.5, 0.5, 0.0)));
  EXPECT_EQ(c.colors[0], (Rgb8{255, 255, 255}));
  EXPECT_EQ(c.colors[1], (Rgb8{128, 128, 128}));
}

TEST(ReliefTiles, LocalPredictorIsReproducedAwayFromBordersWithoutSeams) {
  const ImageF image = Ramp(200, 90);
  // A local operator (3x3 box filter with clamped borders), like a network's finite field.
  auto box = [](const ImageF& t) {
    ImageF o(t.width(), t.height(), 1);
    for (int y = 0; y < t.height(); ++y) {
      for (int x = 0; x < t.width(); ++x) {
        double s = 0;
        for (int dy = -1; dy <= 1; ++dy) for (int dx = -1; dx <= 1; ++dx)
          s += t.at(std::clamp(x + dx, 0, t.width() - 1), std::clamp(y + dy, 0, t.height() - 1));
        o.at(x, y) = static_cast<float>(s / 9);
      }
    }
    return o;
  };
  TileOptions o;
  o.tile = 64;
  o.overlap = 16;
  const ImageF tiled = PredictTiled(o, image, box), whole = box(image);
  for (int y = 1; y < 89; ++y) {
    for (int x = 1; x < 199; ++x) ASSERT_NEAR(tiled.at(x, y), whole.at(x, y), 1e-3) << x << "," << y;
  }
  EXPECT_EQ(TileStarts(200, 64, 16), (std::vector<int>{0, 45, 91, 136}));
  // Smaller than a tile (mirror-padded) and exactly one tile.
  const ImageF small = PredictTiled(o, Ramp(10, 7), [](const ImageF& t) { return t; });
  EXPECT_EQ(small.values(), Ramp(10, 7).values());
  EXPECT_EQ(PredictTiled(o, Ramp(64, 64), box).values(), box(Ramp(64, 64)).values());
}

TEST(ReliefTiles, DisagreeingTilesBlendContinuously) {
  // Each tile predicts a different constant: the blend must change smoothly (no jump > the
  // ramp's largest step) where a one-pass prediction would be constant inside each tile.
  TileOptions o;
  o.tile = 64;
  o.overlap = 32;
  int calls = 0;
  const ImageF out = PredictTiled(o, ImageF(160, 64, 1, 0.0f),
                                  [&](const ImageF& t) { return ImageF(t.width(), t.height(), 1, 100.0f * calls++); });
  double max_jump = 0;
  for (int x = 0; x + 1 < 160; ++x) max_jump = std::max<double>(max_jump, std::abs(out.at(x + 1, 10) - out.at(x, 10)));
  EXPECT_LT(max_jump, 100.0 * 0.2) << "a seam would jump by 100 in one pixel";
}

TEST(ReliefDataset, ScanOfATiltedPlaneRendersItsDepthAndPatchesAugment) {
  // A 1 m x 0.5 m wall with a 0.1 m high box, points every 5 mm, in the panel frame.
  PointCloud c;
  for (double x = 0; x < 1.0; x += 0.005) {
    for (double y = 0; y < 0.5; y += 0.005) {
      const bool box = x > 0.4 && x < 0.6 && y > 0.2 && y < 0.3;
      c.positions.emplace_back(x, y, box ? 0.1 : 0.0);
    }
  }
  ScanRasterOptions o;
  o.frame = "panel";
  o.pixels_per_m = 100;
  const TrainingPair p = RasterizeScan(o, c, "test");
  ASSERT_EQ(p.depth.width(), 100);
  ASSERT_EQ(p.depth.height(), 50);
  EXPECT_NEAR(p.depth.at(50, 25), LevelFromHeight(0.1, 0.15), 1e-3);
  EXPECT_NEAR(p.depth.at(10, 10), 255.0, 1e-3);
  o.frame = "auto";  // PCA finds the same plane
  const TrainingPair q = RasterizeScan(o, c, "test");
  EXPECT_NEAR(q.depth.at(q.depth.width() / 2, q.depth.height() / 2), LevelFromHeight(0.1, 0.15), 1.0);
  PatchOptions patches;
  patches.patch = 32;
  patches.stride = 16;
  const auto cut = CutPatches(patches, p);
  EXPECT_EQ(cut.size(), 6u * 3u);
  const TrainingPair a1 = Augment({}, cut[0], 7, 3), a2 = Augment({}, cut[0], 7, 3);
  EXPECT_EQ(a1.photo.values(), a2.photo.values());
  AugmentOptions flip;
  flip.rotate_probability = flip.brightness_probability = 0;
  flip.flip_probability = 1;
  const TrainingPair f = Augment(flip, cut[0], 7, 3);
  EXPECT_EQ(f.depth.at(0, 5), cut[0].depth.at(31, 5));
  TempDir dir;
  WritePairs(dir.File("pairs"), cut);
  const auto back = ReadPairs(dir.File("pairs"));
  ASSERT_EQ(back.size(), cut.size());
  EXPECT_NEAR(back[3].depth.at(4, 4), cut[3].depth.at(4, 4), 1.0 / 256);
  EXPECT_THROW(RasterizeScan(o, PointCloud(), "empty.ply"), InputError);
}

// ---- surface metrics ----

constexpr double kDegPerRad = 180 / 3.14159265358979323846;

// Level `near` left of column x_edge, `far` from it on: the true edge is column x_edge - 1.
ImageF Step(int w, int h, int x_edge, float near = 50, float far = 150) {
  ImageF im(w, h, 1, near);
  for (int y = 0; y < h; ++y) {
    for (int x = x_edge; x < w; ++x) im.at(x, y) = far;
  }
  return im;
}

NormalMetrics Normals(const ImageF& prediction, const ImageF& truth,
                      const SurfaceMetricOptions& o = {}, const Image8& mask = Image8()) {
  SurfaceMetricsAccumulator acc(o);
  acc.Add(prediction, truth, mask);
  return acc.Normals();
}

EdgeMetrics Edges(const ImageF& prediction, const ImageF& truth,
                  const SurfaceMetricOptions& o = {}) {
  SurfaceMetricsAccumulator acc(o);
  acc.Add(prediction, truth);
  return acc.Edges();
}

TEST(SurfaceMetricOptions, DefaultsPassAndBadValuesAreRejected) {
  EXPECT_NO_THROW(SurfaceMetricOptions().Check());
  SurfaceMetricOptions o;
  o.level_per_pixel = NAN;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  EXPECT_THROW(SurfaceMetricsAccumulator{o}, std::invalid_argument);
  o = {};
  o.level_per_pixel = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.edge_jump_levels = -1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o.edge_jump_levels = NAN;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.edge_tolerance_px = -1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o.edge_tolerance_px = 17;
  try {
    o.Check();
    ADD_FAILURE() << "edge_tolerance_px = 17 passed";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("edge_tolerance_px = 17"), std::string::npos) << e.what();
  }
}

TEST(SurfaceMetrics, IdenticalMapsScorePerfectly) {
  const ImageF gt = Step(12, 8, 6);
  SurfaceMetricsAccumulator acc;
  acc.Add(gt, gt);
  acc.Add(Ramp(40, 8), Ramp(40, 8));  // sums over images; 5 levels a pixel is smooth
  const NormalMetrics n = acc.Normals();
  EXPECT_EQ(n.count, 10 * 6 + 38 * 6);
  EXPECT_NEAR(n.mean_deg, 0, 1e-9);
  EXPECT_NEAR(n.median_deg, 0, 1e-9);
  EXPECT_EQ(n.within_11, 1.0);
  EXPECT_EQ(n.within_30, 1.0);
  const EdgeMetrics e = acc.Edges();
  EXPECT_EQ(e.truth, 8) << "column 5 of the step only; the ramp is smooth";
  EXPECT_EQ(e.predicted, 8);
  EXPECT_EQ(e.precision, 1.0);
  EXPECT_EQ(e.recall, 1.0);
  EXPECT_EQ(e.f1, 1.0);
}

TEST(SurfaceMetrics, TiltedPlaneAgainstFlatReadsItsSlopeAngle) {
  SurfaceMetricOptions o;
  o.level_per_pixel = 0.25;
  const double slope = 3;  // levels per pixel
  ImageF tilted(10, 7, 1);
  for (int y = 0; y < 7; ++y) {
    for (int x = 0; x < 10; ++x) tilted.at(x, y) = static_cast<float>(100 + slope * x);
  }
  const NormalMetrics n = Normals(tilted, ImageF(10, 7, 1, 100.0f), o);
  const double expected = std::atan(slope * o.level_per_pixel) * kDegPerRad;  // 36.87 degrees
  EXPECT_EQ(n.count, 8 * 5);
  EXPECT_NEAR(n.mean_deg, expected, 1e-6);
  EXPECT_NEAR(n.median_deg, expected, 1e-6);
  EXPECT_EQ(n.within_30, 0.0);
  EXPECT_EQ(Normals(ImageF(10, 7, 1, 100.0f), tilted, o).mean_deg, n.mean_deg) << "symmetric";
  o.level_per_pixel = 1;
  EXPECT_NEAR(Normals(tilted, ImageF(10, 7, 1, 100.0f), o).mean_deg, std::atan(slope) * kDegPerRad,
              1e-6);
}

TEST(SurfaceMetrics, MedianComesFromTheHistogramToItsResolution) {
  // Left half flat, right half tilted: per row 9 angles of 0, one of 45 (the kink), 8 of
  // atan(2); the median lies between the two middle ranks, 0 and 45.
  ImageF mixed(20, 5, 1, 100.0f);
  for (int y = 0; y < 5; ++y) {
    for (int x = 10; x < 20; ++x) mixed.at(x, y) = static_cast<float>(100 + 2 * (x - 10));
  }
  const NormalMetrics n = Normals(mixed, ImageF(20, 5, 1, 100.0f));
  ASSERT_EQ(n.count, 18 * 3);
  EXPECT_GT(n.median_deg, 0.0);
  std::vector<double> angles;
  for (int x = 1; x < 19; ++x) {
    const double d = (mixed.at(x + 1, 2) - mixed.at(x - 1, 2)) / 2.0;
    angles.push_back(std::atan(d) * kDegPerRad);
  }
  std::sort(angles.begin(), angles.end());
  EXPECT_NEAR(n.median_deg, 0.5 * (angles[8] + angles[9]), 0.01);
}

TEST(SurfaceMetrics, ShiftedEdgeMatchesWithinTheTolerance) {
  const ImageF gt = Step(16, 6, 8), shifted = Step(16, 6, 9);
  SurfaceMetricOptions o;
  const EdgeMetrics near = Edges(shifted, gt, o);
  EXPECT_EQ(near.truth, 6);
  EXPECT_EQ(near.predicted, 6);
  EXPECT_EQ(near.precision, 1.0);
  EXPECT_EQ(near.recall, 1.0);
  EXPECT_EQ(near.f1, 1.0);
  o.edge_tolerance_px = 0;
  const EdgeMetrics exact = Edges(shifted, gt, o);
  EXPECT_EQ(exact.precision, 0.0);
  EXPECT_EQ(exact.recall, 0.0);
  EXPECT_EQ(exact.f1, 0.0);
  EXPECT_EQ(Edges(gt, gt, o).f1, 1.0);
  o.edge_jump_levels = 100;  // the step is exactly 100: not more than, so no edge at all
  const EdgeMetrics none = Edges(gt, gt, o);
  EXPECT_EQ(none.truth, 0);
  EXPECT_EQ(none.f1, 0.0);
}

TEST(SurfaceMetrics, EdgesAreOnTheNearSideAndMatchWithinAEuclideanDisc) {
  // A pit (one far pixel in a near plane) is occluded by its four neighbours; a bump (one near
  // pixel) occludes by itself.
  ImageF pit(9, 9, 1, 50.0f), bump(9, 9, 1, 150.0f);
  pit.at(4, 4) = 150;
  bump.at(4, 4) = 50;
  EXPECT_EQ(Edges(pit, pit).truth, 4);
  EXPECT_EQ(Edges(bump, bump).truth, 1);
  // The bump moved diagonally by (1, 1): 1.41 pixels away.
  ImageF moved(9, 9, 1, 150.0f);
  moved.at(5, 5) = 50;
  SurfaceMetricOptions o;
  o.edge_tolerance_px = 1;
  EXPECT_EQ(Edges(moved, bump, o).recall, 0.0) << "a square, not a disc, of radius 1";
  o.edge_tolerance_px = 2;
  EXPECT_EQ(Edges(moved, bump, o).recall, 1.0);
}

TEST(SurfaceMetrics, PredictionWithoutEdgesHasNoRecall) {
  const EdgeMetrics e = Edges(ImageF(16, 6, 1, 100.0f), Step(16, 6, 8));
  EXPECT_EQ(e.truth, 6);
  EXPECT_EQ(e.predicted, 0);
  EXPECT_EQ(e.recall, 0.0);
  EXPECT_EQ(e.precision, 0.0) << "undefined with no predicted edges: reported as 0";
  EXPECT_EQ(e.f1, 0.0);
}

TEST(SurfaceMetrics, NanPredictionsAndTinyImagesAreGuarded) {
  const ImageF gt = Ramp(40, 10);  // smooth: no true edges
  ImageF bad = gt;
  bad.at(4, 4) = NAN;
  bad.at(6, 6) = INFINITY;
  SurfaceMetricsAccumulator acc;
  acc.Add(bad, gt);
  acc.Add(ImageF(40, 10, 1, NAN), gt);
  const NormalMetrics n = acc.Normals();
  EXPECT_EQ(n.count, 2 * 38 * 8) << "NaN counts as the front plane, never skipped";
  for (double v : {n.mean_deg, n.median_deg, n.within_11, n.within_22, n.within_30}) {
    EXPECT_TRUE(std::isfinite(v)) << v;
  }
  EXPECT_GT(n.mean_deg, 0.0);
  const EdgeMetrics e = acc.Edges();
  EXPECT_EQ(e.predicted, 2) << "each non-finite pixel reads as a pit in front of its neighbours";
  EXPECT_EQ(e.truth, 0);
  for (double v : {e.precision, e.recall, e.f1}) EXPECT_TRUE(std::isfinite(v)) << v;
  SurfaceMetricsAccumulator tiny;
  tiny.Add(Step(2, 2, 1), Step(2, 2, 1));
  tiny.Add(ImageF(1, 1, 1, NAN), ImageF(1, 1, 1, 5.0f));
  tiny.Add(ImageF(0, 0, 1), ImageF(0, 0, 1));
  EXPECT_EQ(tiny.Normals().count, 0);
  EXPECT_EQ(tiny.Normals().mean_deg, 0.0);
  EXPECT_EQ(tiny.Edges().truth, 2) << "a 2x2 step still has a discontinuity";
  EXPECT_THROW(tiny.Add(ImageF(3, 3, 1), ImageF(3, 4, 1)), InternalError);
}

TEST(SurfaceMetrics, MaskAndMissingTruthExcludePixels) {
  const ImageF gt = Step(12, 8, 6);
  EXPECT_EQ(Normals(gt, gt).count, 10 * 6);
  Image8 mask(12, 8, 1, 1);
  mask.at(3, 3) = 0;  // itself and its four neighbours' stencils
  EXPECT_EQ(Normals(gt, gt, {}, mask).count, 10 * 6 - 5);
  ImageF holes = gt;
  holes.at(3, 3) = NAN;
  holes.at(9, 4) = 0;  // "no data", below kMinValidLevel
  EXPECT_EQ(Normals(gt, holes).count, 10 * 6 - 10);
  // The far side of an edge masked out: that edge pixel is no longer an edge in either map, and
  // a wrong prediction under the mask is not judged.
  mask.at(6, 2) = 0;
  ImageF wrong = gt;
  wrong.at(1, 1) = 200;
  SurfaceMetricsAccumulator acc;
  Image8 hide_wrong = mask;
  hide_wrong.at(1, 1) = 0;
  acc.Add(wrong, gt, hide_wrong);
  const EdgeMetrics e = acc.Edges();
  EXPECT_EQ(e.truth, 7);
  EXPECT_EQ(e.predicted, 7);
  EXPECT_EQ(e.precision, 1.0);
}

}  // namespace
}  // namespace candi::relief
