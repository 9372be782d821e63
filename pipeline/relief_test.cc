// The relief stages that hold the network (candi_pipeline_relief): synthetic panels, a panel's
// depth through the shipped model, its points, and a build's in-process panel runner.
#include "pipeline/relief.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/atomic_file.h"
#include "core/check.h"
#include "io/image/png_io.h"
#include "io/point_io.h"
#include "pipeline/relief_dataset.h"
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

}  // namespace
}  // namespace candi::pipeline
