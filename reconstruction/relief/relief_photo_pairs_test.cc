// Tests of the real-photo pairs (relief_photo_pairs.h), the evaluation on them and the normal
// metric's step: a camera and clouds built in code, and the Sceaux photos with their OpenMVS
// dense cloud where ../shared/data is present.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/check.h"
#include "io/image/png_io.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"
#include "reconstruction/relief/relief_eval.h"
#include "reconstruction/relief/relief_image.h"
#include "reconstruction/relief/relief_metrics.h"
#include "reconstruction/relief/relief_photo_pairs.h"
#include "tests/util/test_util.h"

namespace candi::relief {
namespace {

using photogrammetry::ColmapCamera;
using photogrammetry::ColmapImage;
using testing::TempDir;

ColmapCamera Pinhole(int w, int h, double f) {
  ColmapCamera c;
  c.camera_id = 1;
  c.model = "PINHOLE";
  c.width = w;
  c.height = h;
  c.params = {f, f, w / 2.0, h / 2.0};
  return c;
}

// The world point seen at the centre of pixel (x, y) at camera depth z (identity pose).
Eigen::Vector3d PointAt(const ColmapCamera& c, int x, int y, double z) {
  return {(x + 0.5 - c.params[2]) / c.params[0] * z, (y + 0.5 - c.params[3]) / c.params[1] * z, z};
}

TEST(PhotoPairOptions, DefaultsPassAndBadValuesAreRejected) {
  EXPECT_NO_THROW(PhotoPairOptions().Check());
  PhotoPairOptions o;
  o.far_percentile = o.near_percentile;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = PhotoPairOptions();
  o.occlusion_tolerance = NAN;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = PhotoPairOptions();
  o.max_side = 8;
  EXPECT_THROW(o.Check(), std::invalid_argument);
}

// A front wall at z = 4 over the left half (with one hole), a back wall at z = 8 behind the whole
// view except the top 5 rows, which nothing covers.
TEST(PhotoPairs, DepthIsTheNearestPointsAndUnseenOrHiddenPixelsAreMasked) {
  const ColmapCamera cam = Pinhole(64, 48, 60);
  ColmapImage image;
  image.camera_id = 1;
  image.name = "sub/view_01.jpg";
  std::vector<Eigen::Vector3d> points;
  const int hole_x = 10, hole_y = 20;
  for (int y = 5; y < 48; ++y) {
    for (int x = 0; x < 64; ++x) {
      points.push_back(PointAt(cam, x, y, 8.0));
      if (x < 32 && !(x == hole_x && y == hole_y)) points.push_back(PointAt(cam, x, y, 4.0));
    }
  }
  points.push_back(Eigen::Vector3d(NAN, 0, 4));    // skipped, not a crash
  points.push_back(Eigen::Vector3d(0, 0, -3));     // behind the camera
  points.push_back(Eigen::Vector3d(1e3, 0, 1.0));  // outside the view
  PhotoPairOptions o;
  o.near_percentile = 0;
  o.far_percentile = 1;
  const ImageF photo(128, 96, 1, 0.5f);  // the original at twice the camera's size
  const PhotoPair pair = BuildPhotoPair(o, cam, image, photo, "view_01.jpg", points);
  EXPECT_EQ(pair.name, "view_01");
  ASSERT_EQ(pair.depth.width(), 64);
  ASSERT_EQ(pair.photo.height(), 48);
  EXPECT_DOUBLE_EQ(pair.near, 4.0);
  EXPECT_DOUBLE_EQ(pair.far, 8.0);
  // Project a point, read its depth back.
  for (const Eigen::Vector3d& p : {PointAt(cam, 7, 30, 4.0), PointAt(cam, 50, 11, 8.0)}) {
    const Eigen::Vector2d uv = photogrammetry::ProjectToImage(cam, image, p);
    const int x = static_cast<int>(uv.x()), y = static_cast<int>(uv.y());
    ASSERT_EQ(pair.mask.at(x, y), 255) << x << "," << y;
    EXPECT_NEAR(CameraDepthOfLevel(pair.depth.at(x, y), pair.near, pair.far), p.z(), 1e-5);
  }
  for (int x = 0; x < 64; ++x) EXPECT_EQ(pair.mask.at(x, 2), 0) << "no point above row 5";
  EXPECT_EQ(pair.depth.at(3, 2), 0.0f);
  EXPECT_EQ(pair.mask.at(hole_x, hole_y), 0) << "the back wall seen through a hole is hidden";
  EXPECT_EQ(pair.mask.at(32, 30), 0) << "the far side of the edge is masked";
  EXPECT_EQ(pair.mask.at(34, 30), 255);
  EXPECT_FLOAT_EQ(pair.depth.at(34, 30), 255.0f);
  EXPECT_FLOAT_EQ(pair.depth.at(31, 30), 1.0f);

  // No occlusion test: the hole shows the back wall.
  o.occlusion_radius = 0;
  const PhotoPair open = BuildPhotoPair(o, cam, image, photo, "view_01.jpg", points);
  EXPECT_NEAR(CameraDepthOfLevel(open.depth.at(hole_x, hole_y), open.near, open.far), 8.0, 1e-5);

  // The photo must have the camera's aspect ratio.
  EXPECT_THROW(BuildPhotoPair(o, cam, image, ImageF(100, 96, 1, 0.5f), "odd.jpg", points), InputError);
  // A flat view (one depth): level 128 where known, nothing divides by zero.
  std::vector<Eigen::Vector3d> flat = {PointAt(cam, 5, 5, 3.0), PointAt(cam, 6, 5, 3.0)};
  const PhotoPair f = BuildPhotoPair(PhotoPairOptions(), cam, image, photo, "f.jpg", flat);
  EXPECT_FLOAT_EQ(f.depth.at(5, 5), 128.0f);
  // No point at all: everything masked.
  const PhotoPair none = BuildPhotoPair(PhotoPairOptions(), cam, image, photo, "n.jpg", {});
  EXPECT_EQ(*std::max_element(none.mask.values().begin(), none.mask.values().end()), 0);
}

TEST(PhotoPairs, FilesRoundTripAndBadFilesNameThemselves) {
  TempDir dir;
  PhotoPair p;
  p.name = "a";
  p.photo = ImageF(40, 30, 1, 0.25f);
  p.depth = ImageF(40, 30, 1, 0.0f);
  p.mask = Image8(40, 30, 1, 0);
  p.depth.at(3, 4) = 17.3f;
  p.mask.at(3, 4) = 255;
  p.near = 2.5;
  p.far = 9.75;
  WritePhotoPair(dir.File("pairs"), p);
  std::vector<PhotoPair> back = ReadPhotoPairs(dir.File("pairs"));
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].name, "a");
  EXPECT_NEAR(back[0].depth.at(3, 4), 17.3, 1.0 / 256);
  EXPECT_EQ(back[0].mask.at(3, 4), 255);
  EXPECT_EQ(back[0].mask.at(0, 0), 0);
  EXPECT_DOUBLE_EQ(back[0].near, 2.5);
  EXPECT_DOUBLE_EQ(back[0].far, 9.75);
  // A depth map of the wrong size is an error naming it.
  WriteDepth16(dir.File("pairs/a_depth.png"), ImageF(41, 30, 1, 5.0f));
  try {
    ReadPhotoPairs(dir.File("pairs"));
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("a_depth.png"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReadPhotoPairs(dir.File("nothing")), InputError);
  EXPECT_THROW(ReadPhotoPairs(dir.path()), InputError) << "a folder without pairs";
}

TEST(PhotoPairs, ConstantGreyPhotosScoreFiniteBaselines) {
  EvalPanel p;
  p.photo = ImageF(64, 48, 1, 0.5f);
  p.depth = ImageF(64, 48, 1, 0.0f);
  p.mask = Image8(64, 48, 1, 0);
  for (int y = 0; y < 48; ++y) {
    for (int x = 0; x < 64; ++x) {
      p.depth.at(x, y) = static_cast<float>(1 + 3 * x);
      p.mask.at(x, y) = x < 60 ? 255 : 0;
    }
  }
  const std::vector<MethodScore> scores = EvaluatePanels({p}, {}, PredictOptions());
  ASSERT_EQ(scores.size(), 2u);
  for (const MethodScore& s : scores) {
    EXPECT_EQ(s.metrics.count, 60 * 48) << s.name << ": the mask is honoured";
    EXPECT_TRUE(std::isfinite(s.metrics.rmse_log) && std::isfinite(s.normals.mean_deg)) << s.name;
  }
}

// Depth noisy at the pixel scale (a checkerboard of 2x2-pixel cells, +-1 level, on a plane):
// normals from neighbours read the noise, normals over 4 pixels read the plane.
// Leave-one-part-out: each part weighs the same, a part without scored pixels is left out of a
// metric's mean, and parts scoring other methods are refused.
TEST(MeanOverParts, EachPartWeighsTheSame) {
  auto score = [](const std::string& name, double delta1, int64_t count, double normal, int64_t normals) {
    MethodScore s;
    s.name = name;
    s.metrics.delta1 = delta1;
    s.metrics.rmse_log = 1 - delta1;
    s.metrics.count = count;
    s.normals.mean_deg = normal;
    s.normals.count = normals;
    s.seconds = 1;
    return s;
  };
  const std::vector<std::vector<MethodScore>> parts = {
      {score("a", 0.2, 1000000, 40, 10), score("net", 0.9, 1000000, 20, 10)},
      {score("a", 0.6, 10, 0, 0), score("net", 0.5, 10, 30, 10)}};
  const std::vector<MethodScore> mean = MeanOverParts(parts);
  ASSERT_EQ(mean.size(), 2u);
  EXPECT_EQ(mean[0].name, "a");
  EXPECT_NEAR(mean[0].metrics.delta1, 0.4, 1e-12) << "not weighted by pixels";
  EXPECT_NEAR(mean[0].metrics.rmse_log, 0.6, 1e-12);
  EXPECT_EQ(mean[0].metrics.count, 1000010);
  EXPECT_NEAR(mean[0].normals.mean_deg, 40, 1e-12) << "the part without normals is left out";
  EXPECT_NEAR(mean[1].normals.mean_deg, 25, 1e-12);
  EXPECT_EQ(mean[1].seconds, 2);
  EXPECT_THROW(MeanOverParts({}), std::invalid_argument);
  EXPECT_THROW(MeanOverParts({parts[0], {score("b", 0.1, 1, 0, 0), score("net", 0.1, 1, 0, 0)}}), std::invalid_argument);
}

TEST(SurfaceMetrics, NormalStepReadsTheSurfaceUnderPixelNoise) {
  ImageF plane(40, 40, 1), noisy(40, 40, 1);
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 40; ++x) {
      plane.at(x, y) = static_cast<float>(100 + 0.5 * x);
      noisy.at(x, y) = plane.at(x, y) + ((x / 2 + y / 2) % 2 ? 1.0f : -1.0f);
    }
  }
  SurfaceMetricOptions o;
  SurfaceMetricsAccumulator one(o);
  one.Add(plane, noisy);
  o.normal_step = 4;
  SurfaceMetricsAccumulator four(o);
  four.Add(plane, noisy);
  EXPECT_GT(one.Normals().mean_deg, 30);
  EXPECT_LT(four.Normals().mean_deg, 1e-9);
  EXPECT_EQ(four.Normals().count, 32 * 32);
  o.normal_step = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
}

// The Sceaux photos, their COLMAP model and OpenMVS's dense cloud: the pair agrees with the cloud
// it came from and masks the sky.
TEST(PhotoPairsReal, SceauxDepthAgreesWithTheDenseCloud) {
  CANDI_REQUIRE_SHARED_DATA(model_dir, "colmap/sceaux_1600_sparse");
  CANDI_REQUIRE_SHARED_DATA(photos, "photos/sceaux_castle/100_7105.JPG");
  CANDI_REQUIRE_SHARED_DATA(dense, "dense/sceaux_openmvs_dense.ply");
  const photogrammetry::ColmapModel model = photogrammetry::ReadColmapModel(model_dir);
  const PointCloud cloud = io::ReadPointCloud(dense);
  std::vector<Eigen::Vector3d> points;
  for (size_t i = 0; i < cloud.size(); ++i) points.push_back(cloud.frame.ToWorld(cloud.positions[i]));
  const ColmapImage* image = nullptr;
  for (const auto& [id, im] : model.images) {
    if (im.name == "100_7105.JPG") image = &im;
  }
  ASSERT_NE(image, nullptr);
  const ColmapCamera& cam = model.cameras.at(image->camera_id);
  PhotoPairOptions o;
  o.max_side = 400;
  const PhotoPair pair = BuildPhotoPair(o, cam, *image, ReadPhoto(photos), photos, points);
  ASSERT_EQ(pair.depth.width(), 400);
  size_t known = 0, top_known = 0;
  for (int y = 0; y < pair.mask.height(); ++y) {
    for (int x = 0; x < pair.mask.width(); ++x) {
      known += pair.mask.at(x, y) != 0;
      if (y < pair.mask.height() / 10) top_known += pair.mask.at(x, y) != 0;
    }
  }
  const double coverage = static_cast<double>(known) / pair.mask.values().size();
  EXPECT_GT(coverage, 0.3);
  EXPECT_LT(coverage, 0.8) << "sky and ground are not in the cloud";
  EXPECT_LT(top_known, pair.mask.width() / 20) << "the sky above the roofs is masked";
  // Project every 50th point; where the pair knows the pixel, most points are its nearest one.
  const Eigen::Matrix3d r = image->cam_from_world_rotation.normalized().toRotationMatrix();
  const double s = static_cast<double>(pair.depth.width()) / cam.width;
  size_t compared = 0, agree = 0;
  for (size_t i = 0; i < points.size(); i += 50) {
    const Eigen::Vector2d uv = photogrammetry::ProjectToImage(cam, *image, points[i]);
    if (!uv.allFinite()) continue;
    const int x = static_cast<int>(std::floor(uv.x() * s)), y = static_cast<int>(std::floor(uv.y() * s));
    if (x < 0 || y < 0 || x >= pair.depth.width() || y >= pair.depth.height() || !pair.mask.at(x, y)) continue;
    const double z = (r * points[i] + image->cam_from_world_translation).z();
    const double read = CameraDepthOfLevel(pair.depth.at(x, y), pair.near, pair.far);
    ++compared;
    // Within the depth range (levels clamp outside it), 1 % of the depth.
    if (z < pair.near || z > pair.far || std::abs(read - z) < 0.01 * z) ++agree;
  }
  ASSERT_GT(compared, 2000u);
  EXPECT_GT(static_cast<double>(agree) / compared, 0.9) << agree << " of " << compared;
}

}  // namespace
}  // namespace candi::relief
