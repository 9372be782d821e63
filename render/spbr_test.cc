#include "render/spbr.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/check.h"
#include "core/rng.h"
#include "render/archive_clip.h"
#include "render/archive_pack.h"
#include "render/archive_render.h"
#include "render/reference.h"
#include "render/spbr_stream.h"
#include "render/splat_cloud.h"
#include "render/synthetic_scene.h"
#include "tests/util/option_check.h"

namespace candi::render {
namespace {

// A camera looking straight down at z = 0, one pixel = `pixel` metres, covering [0, w*pixel] x
// [0, h*pixel] (image x along world x, image y down along -y).
Camera TopView(int w, int h, double pixel, Projection projection = Projection::kOrthographic) {
  Camera c;
  c.projection = projection;
  c.width = w;
  c.height = h;
  c.target = Eigen::Vector3d(0.5 * w * pixel, 0.5 * h * pixel, 0);
  c.eye = c.target + Eigen::Vector3d(0, 0, 10);
  c.up = Eigen::Vector3d(0, 1, 0);
  c.ortho_height = h * pixel;
  c.fov_y_deg = 2 * std::atan(0.5 * h * pixel / 10) * 180 / M_PI;
  return c;
}

PointCloud Plane(size_t n, double sx, double sy, double z, Rgb8 color, uint64_t seed) {
  return UniformRectangle(n, sx, sy, z, color, seed);
}

SpbrResult Render(const PointCloud& cloud, const Camera& camera, int L, uint64_t seed, int threads = 0,
                  SplatCloud* splats_out = nullptr) {
  SplatCloudOptions build;
  build.spbr.repeat_level = L;
  build.spbr.seed = seed;
  const SplatCloud splats = BuildSplatCloud(build, {&cloud});
  Camera local = camera;  // the camera is given in world coordinates here
  local.eye -= splats.frame.origin;
  local.target -= splats.frame.origin;
  SpbrOptions options;
  options.threads = threads;
  SpbrResult r = RenderSpbr(options, local, splats);
  if (splats_out) *splats_out = splats;
  return r;
}

double MeanRegion(const ImageF& image, int channel, int x0, int y0, int x1, int y1) {
  double sum = 0;
  for (int y = y0; y < y1; ++y) for (int x = x0; x < x1; ++x) sum += image.at(x, y, channel);
  return sum / ((x1 - x0) * (y1 - y0));
}

TEST(RenderModuleOptions, DefaultsPassCheck) {
  testing::ExpectDefaultsPass<SpbrOptions, SpbrStreamOptions, SplatCloudOptions, ReferenceOptions,
                              PackOptions, ArchiveRenderOptions, ClippedReadOptions>();
}

TEST(ArchiveRenderOptions, LayerSharesAndEnsemblesNameTheirFields) {
  ArchiveRenderOptions o;
  o.layer_fraction = {1, 0.5, 17};
  EXPECT_EQ(testing::OptionCheckMessage(o),
            "ArchiveRenderOptions::layer_fraction[2] = 17; must be in [0, 16]");
  o = {};
  o.spbr.repeat_level = 10;
  o.ensemble_begin = 5;
  o.ensemble_end = 3;
  EXPECT_EQ(testing::OptionCheckMessage(o),
            "ArchiveRenderOptions::ensemble_begin = 5 and ensemble_end = 3; "
            "ensembles [5, 3) not within [0, 10]");
}

TEST(SpbrOptions, DefaultsPassAndBadValuesNameTheField) {
  EXPECT_NO_THROW(SpbrOptions{}.Check());
  SpbrOptions o;
  o.threads = -1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  SplatCloudOptions s;
  s.spbr.repeat_level = 0;
  try {
    s.Check();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("repeat_level = 0"), std::string::npos);
  }
}

TEST(Spbr, OpaqueRenderShowsTheNearestPoint) {
  PointCloud back = Plane(20000, 6.4, 6.4, 0.0, {0, 0, 255}, 1);
  const PointCloud front = Plane(20000, 6.4, 6.4, 1.0, {255, 0, 0}, 2);
  back.Append(front);
  const Camera camera = TopView(64, 64, 0.1);
  const SpbrResult r = Render(back, camera, 1, 7);
  SplatCloud splats;
  Render(back, camera, 1, 7, 0, &splats);
  ReferenceOptions ref;
  ref.spbr.repeat_level = 1;
  Camera local = camera;
  local.eye -= splats.frame.origin;
  local.target -= splats.frame.origin;
  const ImageF exact = RenderSortedBlend(ref, local, splats.frame, {&back});
  const ImageF image = AverageImage(r, {0, 0, 0});
  int same = 0;
  for (size_t i = 0; i < image.values().size(); ++i) same += image.values()[i] == exact.values()[i];
  EXPECT_GE(same, 0.995 * image.values().size()) << "pixels whose nearest point differs";
}

TEST(Spbr, SameSeedSameImageForAnyThreadCountAndRun) {
  const PointCloud cloud = Plane(200000, 12.8, 12.8, 0.0, {200, 100, 50}, 3);
  const Camera camera = TopView(128, 128, 0.1, Projection::kPerspective);
  const SpbrResult one = Render(cloud, camera, 32, 11, 1);
  const SpbrResult two = Render(cloud, camera, 32, 11, 2);
  const SpbrResult again = Render(cloud, camera, 32, 11, 2);
  EXPECT_TRUE(one.sums == two.sums);
  EXPECT_TRUE(two.sums == again.sums);
  const SpbrResult other = Render(cloud, camera, 32, 12, 2);
  EXPECT_FALSE(other.sums == one.sums) << "the seed matters";
}

// alpha = 1 - (1 - s/S)^(n/L) for a uniform plane: measured as white-on-black intensity.
TEST(Spbr, PlaneOpacityFollowsTheLaw) {
  const int w = 96, L = 32;
  const double pixel = 0.05, side = w * pixel;
  const double s_over_S = (pixel * pixel) / (side * side);
  for (double alpha : {0.1, 0.3, 0.5, 0.7, 0.9}) {
    const double n = L * std::log1p(-alpha) / std::log1p(-s_over_S);
    const PointCloud plane = Plane(static_cast<size_t>(std::llround(n)), side, side, 0.0, {255, 255, 255}, 5);
    const ImageF image = AverageImage(Render(plane, TopView(w, w, pixel), L, 9), {0, 0, 0});
    const double predicted = -std::expm1((std::llround(n) / double(L)) * std::log1p(-s_over_S));
    const double measured = MeanRegion(image, 0, 0, 0, w, w) / 255.0;
    EXPECT_NEAR(measured, predicted, 0.02) << "alpha " << alpha;
    EXPECT_NEAR(predicted, alpha, 1e-3);
  }
}

// sigma * sqrt(L) stays constant: one white layer of alpha 0.5 over black, full contrast.
TEST(Spbr, NoiseFallsAsOneOverSqrtL) {
  const int w = 64;
  const double pixel = 0.05, side = w * pixel;
  const double s_over_S = (pixel * pixel) / (side * side);
  std::vector<double> scaled;
  for (int L : {16, 64, 256, 1024}) {
    const double n = L * std::log1p(-0.5) / std::log1p(-s_over_S);
    const PointCloud plane = Plane(static_cast<size_t>(n), side, side, 0.0, {255, 255, 255}, 21);
    const ImageF image = AverageImage(Render(plane, TopView(w, w, pixel), L, 4), {0, 0, 0});
    double s = 0, s2 = 0;
    for (int y = 0; y < w; ++y) {
      for (int x = 0; x < w; ++x) {
        s += image.at(x, y, 0);
        s2 += image.at(x, y, 0) * image.at(x, y, 0);
      }
    }
    const double m = s / (w * w);
    scaled.push_back(std::sqrt(s2 / (w * w) - m * m) * std::sqrt(double(L)));
  }
  for (double v : scaled) EXPECT_NEAR(v, 127.5, 12.75) << "sigma * sqrt(L)";
}

// Points on a w x w-pixel plane for opacity `alpha` at repeat level L (the SPBR law).
size_t PointsFor(double alpha, int L, int w) {
  return static_cast<size_t>(std::llround(L * std::log1p(-alpha) / std::log1p(-1.0 / (double(w) * w))));
}

// Three translucent layers (alpha 0.5, 0.4, 0.3 at repeat level L) over a grey background, each
// covering a different width, so the image holds 3, 2, 1 and 0 overlapping layers.
PointCloud ThreeLayers(int w, double pixel, int L) {
  const double side = w * pixel;
  const Rgb8 colors[3] = {{180, 160, 140}, {120, 150, 170}, {90, 110, 130}};
  const double alphas[3] = {0.5, 0.4, 0.3};
  PointCloud all;
  for (int k = 0; k < 3; ++k) {
    const double width = side * (0.75 - 0.25 * k);
    const size_t n = static_cast<size_t>(PointsFor(alphas[k], L, w) * (0.75 - 0.25 * k));
    const PointCloud layer = Plane(n, width, side, 1.0 + k, colors[k], 100 + k + L);
    if (k == 0) all = layer; else all.Append(layer);
  }
  return all;
}

ImageF ExactImage(const PointCloud& cloud, const Camera& camera, int L, Rgb8 background) {
  const LocalFrame frame = RenderFrameFor(cloud.WorldBounds());  // the frame SPBR renders in
  Camera local = camera;
  local.eye -= frame.origin;
  local.target -= frame.origin;
  ReferenceOptions ref;
  ref.spbr.repeat_level = L;
  ref.background = background;
  return RenderSortedBlend(ref, local, frame, {&cloud});
}

TEST(Spbr, UnbiasedAgainstExactSortedBlending) {
  const int w = 48, L = 100;
  const double pixel = 0.1;
  const Rgb8 background{100, 100, 100};
  const Camera camera = TopView(w, w, pixel);
  const PointCloud all = ThreeLayers(w, pixel, L);
  const ImageF exact = ExactImage(all, camera, L, background);
  // The mean over seeds: its bias, per region of equal layering, stays under half a grey level.
  const int seeds = 16;
  ImageF mean(w, w, 3, 0.0f);
  for (int s = 0; s < seeds; ++s) {
    const ImageF image = AverageImage(Render(all, camera, L, 1000 + s), background);
    for (size_t i = 0; i < mean.values().size(); ++i) mean.values()[i] += image.values()[i] / seeds;
  }
  for (int region = 0; region < 4; ++region) {  // columns covered by 3, 2, 1 and 0 layers
    const int x0 = region * w / 4 + 2, x1 = (region + 1) * w / 4 - 2;
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(MeanRegion(mean, c, x0, 0, x1, w), MeanRegion(exact, c, x0, 0, x1, w), 0.5)
          << "region " << region << " channel " << c;
    }
  }
  EXPECT_GT(MeanRegion(exact, 0, 2, 0, w / 4 - 2, w) - 100.0, 10.0) << "the layers are visible";
  // One render at L = 1000 (same opacities) is within RMSE 2 of the exact image.
  const PointCloud dense = ThreeLayers(w, pixel, 1000);
  const ImageF one = AverageImage(Render(dense, camera, 1000, 77), background);
  EXPECT_LT(Rmse(one, ExactImage(dense, camera, 1000, background)), 2.0);
}

TEST(Spbr, HardCases) {
  const Camera camera = TopView(32, 32, 0.1, Projection::kPerspective);
  // An empty cloud renders the background.
  const SpbrResult empty = Render(PointCloud{}, camera, 4, 1);
  EXPECT_EQ(empty.copies, 0u);
  for (size_t p = 0; p < 32 * 32; ++p) EXPECT_EQ(empty.sums.sums[4 * p + 3], 0u);
  // One point lights one pixel in the ensembles that hold it (L = 1: all).
  PointCloud one = Plane(1, 3.2, 3.2, 0.0, {255, 255, 255}, 3);
  const SpbrResult r1 = Render(one, camera, 1, 1);
  int lit = 0;
  for (size_t p = 0; p < 32 * 32; ++p) lit += r1.sums.sums[4 * p + 3];
  EXPECT_EQ(lit, 1);
  // Points behind the camera, on the near plane, and outside the view draw nothing.
  PointCloud behind = Plane(1000, 3.2, 3.2, 20.0, {255, 0, 0}, 4);   // above the eye (z = 10)
  PointCloud at_eye = Plane(1000, 3.2, 3.2, 10.0, {255, 0, 0}, 5);   // depth 0
  PointCloud beside = Plane(1000, 3.2, 3.2, 0.0, {255, 0, 0}, 6);
  for (auto& p : beside.positions) p.x() += 100.0;
  for (const PointCloud* c : {&behind, &at_eye, &beside}) {
    const SpbrResult r = Render(*c, camera, 4, 1);
    uint64_t hits = 0;
    for (size_t p = 0; p < 32 * 32; ++p) hits += r.sums.sums[4 * p + 3];
    EXPECT_EQ(hits, 0u);
  }
  // NaN positions are refused with a message.
  PointCloud bad = Plane(10, 1, 1, 0, {1, 2, 3}, 7);
  bad.positions[4].y() = std::nan("");
  try {
    Render(bad, camera, 4, 1);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("point 4"), std::string::npos) << e.what();
  }
}

TEST(Spbr, SurveyScaleCoordinatesRenderTheSameImageAsAtTheOrigin) {
  PointCloud near_origin = Plane(50000, 6.4, 6.4, 0.0, {10, 200, 30}, 8);
  for (auto& p : near_origin.positions) p = (p * 1024.0).array().round() / 1024.0;  // exact shifts
  PointCloud survey = near_origin;
  const Eigen::Vector3d shift(512000, 4300000, 200);
  for (auto& p : survey.positions) p += shift;
  Camera camera = TopView(64, 64, 0.1, Projection::kPerspective);
  const SpbrResult a = Render(near_origin, camera, 16, 5);
  camera.eye += shift;
  camera.target += shift;
  const SpbrResult b = Render(survey, camera, 16, 5);
  EXPECT_TRUE(a.sums == b.sums);
}

TEST(Spbr, MultiplicityZeroHidesAndFullMultiplicityIsOpaque) {
  const int w = 32, L = 8;
  PointCloud plane = Plane(4000, 3.2, 3.2, 0.0, {255, 255, 255}, 9);
  const int field = plane.AddScalarField(kMultiplicityField);
  for (float& m : plane.scalars[field].f32) m = 0.0f;
  const ImageF hidden = AverageImage(Render(plane, TopView(w, w, 0.1), L, 1), {0, 0, 0});
  EXPECT_EQ(MeanRegion(hidden, 0, 0, 0, w, w), 0.0);
  for (float& m : plane.scalars[field].f32) m = static_cast<float>(L);
  const SpbrResult full = Render(plane, TopView(w, w, 0.1), L, 1);
  EXPECT_EQ(full.copies, 4000u * L);
  // Every ensemble holds every point: each pixel with a point is white in all L ensembles.
  for (size_t p = 0; p < size_t(w) * w; ++p) {
    const uint32_t hits = full.sums.sums[4 * p + 3];
    EXPECT_TRUE(hits == 0 || hits == static_cast<uint32_t>(L)) << hits;
  }
}

TEST(Spbr, BrightnessGainLiftsTheBrightPercentileToTheOpaqueLevel) {
  const int w = 64, L = 64;
  const double pixel = 0.05, side = w * pixel;
  const double s_over_S = (pixel * pixel) / (side * side);
  const double n = L * std::log1p(-0.3) / std::log1p(-s_over_S);
  const PointCloud plane = Plane(static_cast<size_t>(n), side, side, 0.0, {200, 200, 200}, 12);
  const SpbrResult r = Render(plane, TopView(w, w, pixel), L, 2);
  const double gain = AutoBrightnessGain(r);
  // alpha 0.3 of grey 200 averages 60; the brightest percent of the image (about 60 + 2.3 sigma)
  // must be lifted to 200: a gain of roughly 2.2 to 3.4.
  EXPECT_GT(gain, 2.0);
  EXPECT_LT(gain, 3.6);
  EXPECT_EQ(std::round(gain * 100), gain * 100) << "a multiple of 0.01";
}

}  // namespace
}  // namespace candi::render
