#include "reconstruction/photogrammetry/scenes/synthetic_views.h"

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include <gtest/gtest.h>

#include "io/image/png_io.h"
#include "tests/util/test_util.h"

namespace candi::photogrammetry {
namespace {

SyntheticViewsOptions Small() {
  SyntheticViewsOptions o;
  o.views = 3;
  o.width = 64;
  o.height = 48;
  o.supersample = 1;
  return o;
}

TEST(SyntheticViews, DefaultsPassCheckAndBadOptionsThrow) {
  EXPECT_NO_THROW(SyntheticViewsOptions().Check());
  SyntheticViewsOptions o;
  o.views = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = SyntheticViewsOptions();
  o.noise_sigma = -1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = SyntheticViewsOptions();
  o.fov_degrees = 0;
  EXPECT_THROW(RenderSyntheticViews(o), std::invalid_argument);
}

TEST(SyntheticViews, TrueDepthBackProjectsOntoTheSurfaceSeenByEveryView) {
  const auto views = RenderSyntheticViews(Small());
  ASSERT_EQ(views.size(), 3u);
  int checked = 0;
  for (const SyntheticView& v : views) {
    EXPECT_EQ(v.image.width(), 64);
    EXPECT_EQ(v.image.channels(), 3);
    for (int y = 0; y < 48; y += 7) {
      for (int x = 0; x < 64; x += 7) {
        const double d = v.depth.at(x, y);
        ASSERT_GT(d, 0) << "every pixel sees the block or the ground";
        const Eigen::Vector3d X = v.camera.ToWorld(d * v.camera.Ray(x + 0.5, y + 0.5));
        // A point on the surface: on the ground (z = 0) or on the block (|x| <= 1.6, |y| <= 1).
        EXPECT_TRUE(std::abs(X.z()) < 1e-5 || (std::abs(X.x()) <= 1.6 + 1e-5 && std::abs(X.y()) <= 1 + 1e-5))
            << X.transpose();
        // Another view's ray towards X hits X itself when nothing occludes it: at least consistent.
        const Eigen::Vector3d dir = X - views[0].camera.Center();
        EXPECT_LE(SyntheticSceneRayHit(views[0].camera.Center(), dir), 1.0 + 1e-5);
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 100);
}

TEST(SyntheticViews, SeededTextureAndNoiseAreReproducible) {
  SyntheticViewsOptions o = Small();
  const auto a = RenderSyntheticViews(o), b = RenderSyntheticViews(o);
  EXPECT_TRUE(a[1].image == b[1].image);
  o.seed = 2;
  EXPECT_FALSE(RenderSyntheticViews(o)[1].image == a[1].image);
  o.seed = 1;
  o.noise_sigma = 5;
  const auto noisy = RenderSyntheticViews(o);
  EXPECT_FALSE(noisy[1].image == a[1].image);
  EXPECT_TRUE(noisy[1].depth == a[1].depth);
  o.noise_sigma = 0;
  o.textureless = true;
  const auto flat = RenderSyntheticViews(o);
  // Textureless: a face of the block lit uniformly has one colour.
  const int x = 32, y = 24;
  EXPECT_EQ(flat[1].image.at(x, y, 0), flat[1].image.at(x + 1, y, 0));
}

TEST(SyntheticViews, ScoreOfTheTruthIsPerfect) {
  const auto views = RenderSyntheticViews(Small());
  std::vector<ImageF> depths;
  for (const auto& v : views) depths.push_back(v.depth);
  const auto points = SyntheticSparsePoints(views, 4);
  const SyntheticDenseScore s = ScoreSyntheticDense(views, depths, points);
  EXPECT_GT(s.points, 300u);
  EXPECT_DOUBLE_EQ(s.accuracy, 1.0);
  EXPECT_DOUBLE_EQ(s.completeness, 1.0);
  // A point 5 % too far along the ray fails the 1 % tolerance.
  std::vector<Eigen::Vector3d> far;
  for (const auto& p : points) far.push_back(views[0].camera.Center() + 1.05 * (p - views[0].camera.Center()));
  EXPECT_LT(ScoreSyntheticDense(views, depths, far).accuracy, 0.5);
}

TEST(SyntheticViews, WritesPngImages) {
  testing::TempDir dir;
  const auto views = RenderSyntheticViews(Small());
  const std::string folder = dir.path() + "/images";
  WriteSyntheticImages(views, folder);
  const io::PngImage png = io::ReadPng(folder + "/view_001.png");
  EXPECT_TRUE(png.image8 == views[1].image);
}

}  // namespace
}  // namespace candi::photogrammetry
