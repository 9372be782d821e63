// The relief stages that hold the network (candi_pipeline_relief): synthetic panels, a panel's
// depth through the shipped model, its points, and a build's in-process panel runner.
#include "pipeline/relief.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/text_format.h"
#include "io/image/png_io.h"
#include "io/point_io.h"
#include "pipeline/relief_dataset.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"
#include "reconstruction/relief/relief_photo_pairs.h"
#include "tests/util/option_check.h"
#include "tests/util/test_util.h"

namespace candi::pipeline {
namespace {

using testing::ExpectEachBreakRejected;
using testing::TempDir;

relief::SynthOptions Small() {
  relief::SynthOptions o;
  o.width = 96;
  o.seed = 4;
  return o;
}

std::string Model() { return testing::SourceDir() + "/examples/relief/relief_model.pt"; }

TEST(WriteSyntheticPanels, PhotoAndDepthWithTheirProvenanceTheSameForTheSameSeed) {
  TempDir dir;
  WriteSyntheticPanels(Small(), 2, dir.File("a"));
  WriteSyntheticPanels(Small(), 2, dir.File("b"));
  for (const char* f : {"panel_0000_photo.png", "panel_0000_depth.png", "panel_0001_photo.png"}) {
    EXPECT_EQ(ReadFileToString(dir.File(std::string("a/") + f)), ReadFileToString(dir.File(std::string("b/") + f)));
  }
  const io::PngImage photo = io::ReadPng(dir.File("a/panel_0001_photo.png"));
  EXPECT_EQ(photo.image8.width(), 96);
  EXPECT_EQ(photo.text.at("candi_seed"), "4");
  EXPECT_EQ(photo.text.at("candi_panel"), "1");
  EXPECT_EQ(io::ReadPng(dir.File("a/panel_0000_depth.png")).bit_depth, 16);
  relief::SynthOptions bad = Small();
  bad.width = 8;
  EXPECT_THROW(WriteSyntheticPanels(bad, 1, dir.File("c")), std::invalid_argument);
}

TEST(PanelDepthOptions, DefaultsPassAndRulesAreChecked) {
  ExpectEachBreakRejected<PanelDepthOptions>({}, {
      [](PanelDepthOptions& o) { o.width_m = -1; },
      [](PanelDepthOptions& o) { o.predict.tiles.tile = 100; },  // not a multiple of 32
  });
}

TEST(ReliefDatasetOptions, DefaultsPassAndRulesAreNamed) {
  ExpectEachBreakRejected<ReliefDatasetOptions>({}, {
      [](ReliefDatasetOptions& o) { o.raster.pixels_per_m = 0; },
      [](ReliefDatasetOptions& o) { o.panel_width_m = std::nan(""); },
      [](ReliefDatasetOptions& o) { o.val_fraction = 0.95; },
      [](ReliefDatasetOptions& o) { o.patches.patch = 48; },  // not a multiple of 32
  });
  ReliefDatasetOptions o;
  o.raster.pixels_per_m = 0;
  EXPECT_EQ(testing::OptionCheckMessage(o), "ReliefDatasetOptions::raster.pixels_per_m = 0; must be > 0");
}

TEST(PredictPanelDepth, ThePhotosSizeInLevelsAndItsPoints) {
  TempDir dir;
  WriteSyntheticPanels(Small(), 1, dir.path());
  const std::string photo = dir.File("panel_0000_photo.png");
  PanelDepthOptions o;
  o.width_m = 0;  // at the photo's own resolution
  const PanelDepth depth = PredictPanelDepth(o, photo, Model());
  const io::PngImage png = io::ReadPng(photo);
  ASSERT_EQ(depth.depth.width(), png.image8.width());
  ASSERT_EQ(depth.depth.height(), png.image8.height());
  for (float v : depth.depth.values()) ASSERT_TRUE(v >= 0 && v <= 255) << v;
  WritePanelDepth(depth.depth, Model(), dir.File("d8.png"), dir.File("d16.png"));
  EXPECT_EQ(io::ReadPng(dir.File("d8.png")).text.at("candi_model"), Model());
  const PanelPoints points = PanelPointsOf(relief::ReliefPointsOptions(), photo, dir.File("d8.png"));
  EXPECT_EQ(points.width, depth.depth.width());
  EXPECT_GT(points.cloud.size(), 0u);
  EXPECT_EQ(points.cloud.meta.comments.back().rfind("candi_relief_points frame=panel", 0), 0u);
  // A depth map of another size is named.
  WriteSyntheticPanels([] { relief::SynthOptions s = Small(); s.width = 128; return s; }(), 1, dir.File("other"));
  EXPECT_THROW(PanelPointsOf(relief::ReliefPointsOptions(), dir.File("other/panel_0000_photo.png"), dir.File("d8.png")),
               InputError);
  EXPECT_THROW(PredictPanelDepth(o, photo, dir.File("missing.pt")), InputError);
}

// A build's panel in this process writes what `relief predict` and `relief points` write.
TEST(ReliefInProcess, WritesTheDepthMapAndThePanelsPoints) {
  TempDir dir;
  WriteSyntheticPanels(Small(), 1, dir.path());
  ReliefPanelJob job;
  job.photo = dir.File("panel_0000_photo.png");
  job.model = Model();
  job.depth = dir.File("p_depth.png");
  job.points = dir.File("p_panel.ply");
  job.log_base = dir.File("p");
  ReliefInProcess()(job);
  const PointCloud cloud = io::ReadPointCloud(job.points);
  EXPECT_GT(cloud.size(), 0u);
  EXPECT_EQ(io::ReadPng(job.depth).bit_depth, 8);
  Box3d box;
  for (const Eigen::Vector3d& p : cloud.positions) box.Extend(p);
  EXPECT_NEAR(box.max.x(), 2.7, 0.05);  // the panel's width
}

// Per pixel of a view: whether its nearest point (camera depth as a float, the first of equal
// ones, as the pairs' z-buffer keeps them) lies in the held-out region, from every point
// projected as COLMAP projects it.
struct NearestSide {
  std::vector<float> depth;
  std::vector<uint8_t> region;  // 1: the nearest point is the region's
};
NearestSide ProjectSides(const photogrammetry::ColmapCamera& cam, const photogrammetry::ColmapImage& image, int w,
                         int h, const std::vector<Eigen::Vector3d>& points, const std::vector<uint8_t>& in_region) {
  NearestSide n;
  n.depth.assign(static_cast<size_t>(w) * h, std::numeric_limits<float>::infinity());
  n.region.assign(n.depth.size(), 0);
  const Eigen::Matrix3d r = image.cam_from_world_rotation.normalized().toRotationMatrix();
  for (size_t i = 0; i < points.size(); ++i) {
    const double z = (r * points[i] + image.cam_from_world_translation).z();
    if (!(z > 0)) continue;
    const Eigen::Vector2d uv = photogrammetry::ProjectToImage(cam, image, points[i]);
    if (!uv.allFinite()) continue;
    const double x = std::floor(uv.x() * w / cam.width), y = std::floor(uv.y() * h / cam.height);
    if (x < 0 || y < 0 || x >= w || y >= h) continue;
    const size_t at = static_cast<size_t>(y) * w + static_cast<size_t>(x);
    if (static_cast<float>(z) < n.depth[at]) {
      n.depth[at] = static_cast<float>(z);
      n.region[at] = in_region[i];
    }
  }
  return n;
}

// Issue 39's surface hold-out on the Sceaux photos: one side of the chateau is held out. No
// training pixel (nor one within the margin) shows it, its photo pixels are grey, and the
// held-out pairs know only pixels whose nearest point is on it.
TEST(PhotoDatasetRegion, TheHeldOutSurfaceNeverReachesTrainingAndIsAllTheHoldoutScores) {
  CANDI_REQUIRE_SHARED_DATA(model_dir, "colmap/sceaux_1600_sparse");
  CANDI_REQUIRE_SHARED_DATA(photos, "photos/sceaux_castle");
  CANDI_REQUIRE_SHARED_DATA(dense, "dense/sceaux_openmvs_dense.ply");
  const PointCloud cloud = io::ReadPointCloud(dense);
  std::vector<Eigen::Vector3d> points;
  std::vector<double> xs;
  for (size_t i = 0; i < cloud.size(); ++i) {
    points.push_back(cloud.frame.ToWorld(cloud.positions[i]));
    xs.push_back(points.back().x());
  }
  std::nth_element(xs.begin(), xs.begin() + xs.size() / 3, xs.end());
  const double cut = xs[xs.size() / 3];  // a third of the points: x below it
  TempDir dir;
  ReliefDatasetOptions o;
  o.colmap = model_dir;
  o.images = photos;
  o.photo_pairs.max_side = 128;
  o.patches.patch = 64;
  o.patches.stride = 32;
  o.holdout_margin = 2;
  o.holdout_region = "side:-1,0,0," + FormatDouble(-cut);
  const relief::SceneRegion region = relief::ParseSceneRegion(o.holdout_region);
  std::vector<uint8_t> in_region(points.size());
  for (size_t i = 0; i < points.size(); ++i) in_region[i] = region.Contains(points[i]);
  const PhotoDatasetSummary s = BuildPhotoDataset(o, {dense}, dir.File("pairs"));
  ASSERT_GT(s.train, 0u);
  ASSERT_GT(s.region_views, 2u);
  EXPECT_EQ(s.held_out, 0u) << "no photo held out";

  const photogrammetry::ColmapModel model = photogrammetry::ReadColmapModel(model_dir);
  auto view_of = [&](const std::string& stem) -> const photogrammetry::ColmapImage& {
    for (const auto& [id, image] : model.images) {
      if (std::filesystem::path(image.name).stem().string() == stem) return image;
    }
    throw std::runtime_error("no image " + stem);
  };
  uint64_t train_known = 0, scored = 0;
  for (const relief::PhotoPair& pair : relief::ReadPhotoPairs(dir.File("pairs/views"))) {
    const photogrammetry::ColmapImage& image = view_of(pair.name);
    const int w = pair.mask.width(), h = pair.mask.height();
    const NearestSide n = ProjectSides(model.cameras.at(image.camera_id), image, w, h, points, in_region);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        if (!n.region[static_cast<size_t>(y) * w + x]) continue;  // the surface does not show here
        // The surface shows: this pixel and those within the margin know nothing and are grey.
        for (int v = std::max(0, y - 2); v <= std::min(h - 1, y + 2); ++v) {
          for (int u = std::max(0, x - 2); u <= std::min(w - 1, x + 2); ++u) {
            ASSERT_EQ(pair.mask.at(u, v), 0) << pair.name << " (" << u << ", " << v << ")";
            ASSERT_NEAR(pair.photo.at(u, v), 0.5f, 1.01f / 255) << pair.name << " (" << u << ", " << v << ")";
          }
        }
      }
    }
    for (uint8_t m : pair.mask.values()) train_known += m != 0;
  }
  for (const relief::PhotoPair& pair : relief::ReadPhotoPairs(dir.File("pairs/holdout"))) {
    const photogrammetry::ColmapImage& image = view_of(pair.name);
    const int w = pair.mask.width(), h = pair.mask.height();
    const NearestSide n = ProjectSides(model.cameras.at(image.camera_id), image, w, h, points, in_region);
    for (size_t i = 0; i < pair.mask.values().size(); ++i) {
      if (pair.mask.values()[i] == 0) continue;
      ++scored;
      ASSERT_TRUE(n.region[i]) << pair.name << " pixel " << i << ": scored, but not the held-out surface";
    }
  }
  EXPECT_EQ(scored, s.region_pixels);
  EXPECT_GT(scored, 1000u);
  EXPECT_GT(train_known, 5 * scored / 10) << "the rest of the chateau still trains";
  // A region holding no point, or every point, is refused by name.
  o.holdout_region = "box:0,0,0,1e-9,1e-9,1e-9";
  try {
    BuildPhotoDataset(o, {dense}, dir.File("none"));
    ADD_FAILURE() << "an empty region was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("holds none of the"), std::string::npos) << e.what();
  }
  o.holdout_region = "side:0,0,1";
  EXPECT_THROW(BuildPhotoDataset(o, {dense}, dir.File("bad")), std::invalid_argument);
}

TEST(SceneRegion, ParsesBoxesAndSidesAndNamesBadText) {
  const relief::SceneRegion box = relief::ParseSceneRegion("box:1,2,3,0,0,0");
  EXPECT_TRUE(box.Contains(Eigen::Vector3d(0.5, 1, 2.9)));
  EXPECT_FALSE(box.Contains(Eigen::Vector3d(0.5, 2.1, 2.9)));
  const relief::SceneRegion side = relief::ParseSceneRegion("side:0,0,2,1");
  EXPECT_TRUE(side.Contains(Eigen::Vector3d(0, 0, 0.6)));
  EXPECT_FALSE(side.Contains(Eigen::Vector3d(9, 9, 0.5)));
  for (const char* bad : {"box:1,2,3", "cube:0,0,0,1,1,1", "side:0,0,0,1", "box:0,0,0,1,1,0", "side:1,x,0,0",
                          "box:0,0,0,1,1,nan", "side"}) {
    try {
      relief::ParseSceneRegion(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace candi::pipeline
