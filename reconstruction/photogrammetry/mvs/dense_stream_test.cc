#include "reconstruction/photogrammetry/mvs/dense_stream.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "core/check.h"
#include "io/image/png_io.h"
#include "reconstruction/photogrammetry/mvs/dense_workspace.h"
#include "reconstruction/photogrammetry/scenes/synthetic_views.h"
#include "reconstruction/photogrammetry/scenes/synthetic_workspace.h"
#include "tests/util/test_util.h"

namespace candi::photogrammetry {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

const std::vector<SyntheticView>& StreamViews() {
  static const std::vector<SyntheticView> views = [] {
    SyntheticViewsOptions o;
    o.views = 6;
    o.width = 120;
    o.height = 90;
    return RenderSyntheticViews(o);
  }();
  return views;
}

// A fresh copy of the synthetic workspace (cameras true, sparse points with tracks) in DIR/NAME.
std::string StreamWorkspace(const TempDir& dir, const std::string& name) {
  const std::string ws = dir.File(name);
  WriteDenseWorkspace(StreamViews(), SyntheticSparsePoints(StreamViews(), 8), ws);
  return ws;
}

DenseStreamOptions StreamOptions(int threads = 2) {
  DenseStreamOptions o;
  o.stereo.iterations = 2;
  o.stereo.threads = threads;
  return o;
}

void ExpectSameCloud(const PointCloud& a, const PointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.colors, b.colors);
  EXPECT_EQ(a.normals, b.normals);
}

TEST(DenseStream, SameBytesAsTheInMemoryStagesAndOnOneAndTwoThreads) {
  TempDir dir;
  const std::string ws = StreamWorkspace(dir, "a");
  const DenseStreamResult streamed = RunDenseStream(StreamOptions(2), ws);
  EXPECT_TRUE(streamed.sources_from_tracks);
  EXPECT_EQ(streamed.images, 6u);
  EXPECT_EQ(streamed.maps_made, 6u);
  EXPECT_EQ(streamed.maps_found, 0u);
  EXPECT_EQ(streamed.tiles, 1);
  EXPECT_GT(streamed.cloud.size(), 1000u);
  EXPECT_TRUE(streamed.empty_maps.empty());
  // The image cache held the images at most (6 views of 120 x 90: 7 bytes a pixel and a little).
  EXPECT_GT(streamed.peak_cache_bytes, 0u);
  EXPECT_LT(streamed.peak_cache_bytes, 6u * 120 * 90 * 8);

  // In memory, from the same workspace (tracks and all): the same points, bit for bit.
  PatchMatchOptions so = StreamOptions().stereo;
  const PatchMatchResult stereo = RunPatchMatch(so, ReadDenseWorkspace(ws));
  ExpectSameCloud(streamed.cloud, FuseDepthMaps(FusionOptions(), stereo.maps));
  EXPECT_EQ(streamed.valid_pixels, stereo.valid_pixels);

  // The sources are written in COLMAP's format, and the maps COLMAP's stereo_fusion reads.
  const std::string cfg = testing::ReadBytes(ws + "/stereo/patch-match.cfg");
  EXPECT_EQ(cfg.rfind(StreamViews()[0].name + "\n", 0), 0u) << cfg;
  for (const SyntheticView& v : StreamViews()) {
    EXPECT_TRUE(fs::exists(ws + "/stereo/depth_maps/" + v.name + ".geometric.bin")) << v.name;
    EXPECT_TRUE(fs::exists(ws + "/stereo/normal_maps/" + v.name + ".geometric.bin")) << v.name;
  }
  // One thread, in a workspace of its own.
  ExpectSameCloud(RunDenseStream(StreamOptions(1), StreamWorkspace(dir, "b")).cloud, streamed.cloud);
  // Run again: everything is found finished and nothing is made.
  const DenseStreamResult again = RunDenseStream(StreamOptions(2), ws);
  EXPECT_EQ(again.maps_found, 6u);
  EXPECT_EQ(again.maps_made, 0u);
  EXPECT_EQ(again.filtered_found, 6u);
  EXPECT_EQ(again.tiles_found, 1u);
  EXPECT_FALSE(again.settings_changed);
  ExpectSameCloud(again.cloud, streamed.cloud);
}

TEST(DenseStream, ARunStoppedInAnyStageResumesToTheSameBytes) {
  TempDir dir;
  DenseStreamOptions o = StreamOptions();
  o.fusion.max_tile_views = 3;  // several fusion cells
  const std::string whole_ws = StreamWorkspace(dir, "whole");
  const DenseStreamResult whole = RunDenseStream(o, whole_ws);
  ASSERT_GT(whole.tiles, 2);
  EXPECT_EQ(whole.points, whole.cloud.size());
  // Handed over cell by cell (a point file's writer): the same points, in the same order, and
  // none held in the result.
  DenseStreamOptions streamed = o;
  PointCloud cells = FusedCloud();
  int handed = 0;
  streamed.cells_out = [&](const PointCloud& cell) {
    cells.Append(cell);
    ++handed;
  };
  const DenseStreamResult by_cell = RunDenseStream(streamed, whole_ws);
  EXPECT_EQ(handed, whole.tiles);
  EXPECT_TRUE(by_cell.cloud.empty());
  EXPECT_EQ(by_cell.points, whole.cloud.size());
  ExpectSameCloud(cells, whole.cloud);
  const struct {
    const char* stage;
    size_t after;
  } stops[] = {{"stereo", 2}, {"filter", 4}, {"fusion", 1}};
  for (const auto& stop : stops) {
    SCOPED_TRACE(stop.stage);
    const std::string ws = StreamWorkspace(dir, stop.stage);
    DenseStreamOptions stopped = o;
    stopped.committed = [&](const std::string& stage, size_t done) {
      if (stage == stop.stage && done == stop.after) throw std::runtime_error("stopped");
    };
    EXPECT_THROW(RunDenseStream(stopped, ws), std::runtime_error);
    const DenseStreamResult resumed = RunDenseStream(o, ws);
    EXPECT_FALSE(resumed.settings_changed);
    ExpectSameCloud(resumed.cloud, whole.cloud);
    if (std::string(stop.stage) == "stereo") {
      EXPECT_EQ(resumed.maps_found, 2u);
      EXPECT_EQ(resumed.maps_made, 4u);
      EXPECT_EQ(resumed.filtered_found, 0u);
    } else if (std::string(stop.stage) == "filter") {
      EXPECT_EQ(resumed.maps_found, 6u);
      EXPECT_EQ(resumed.filtered_found, 4u);
    } else {
      EXPECT_EQ(resumed.filtered_found, 6u);
      // Cells run in parallel: another may have finished before the stop.
      EXPECT_GE(resumed.tiles_found, 1u);
      EXPECT_LT(resumed.tiles_found, static_cast<size_t>(whole.tiles));
    }
  }
  // The cells changed only which pixels meet: the same surface, a similar count of points.
  const DenseStreamResult one_cell = RunDenseStream(StreamOptions(), StreamWorkspace(dir, "one"));
  EXPECT_NEAR(static_cast<double>(whole.cloud.size()), static_cast<double>(one_cell.cloud.size()),
              0.05 * one_cell.cloud.size());
}

TEST(DenseStream, ChangedSettingsRemakeTheStagesTheyTouchAndABrokenFileIsMadeAgain) {
  TempDir dir;
  const std::string ws = StreamWorkspace(dir, "ws");
  DenseStreamOptions o = StreamOptions();
  const DenseStreamResult first = RunDenseStream(o, ws);
  o.fusion.min_views = 2;  // fusion only: the depth maps stay
  const DenseStreamResult fusion = RunDenseStream(o, ws);
  EXPECT_TRUE(fusion.settings_changed);
  EXPECT_EQ(fusion.maps_found, 6u);
  EXPECT_EQ(fusion.filtered_found, 6u);
  EXPECT_EQ(fusion.tiles_found, 0u);
  EXPECT_GT(fusion.cloud.size(), first.cloud.size());
  o.stereo.max_cost = 0.3;  // the filter: raw maps stay
  const DenseStreamResult filter = RunDenseStream(o, ws);
  EXPECT_EQ(filter.maps_found, 6u);
  EXPECT_EQ(filter.filtered_found, 0u);
  o.stereo.seed = 7;  // stereo: everything again
  const DenseStreamResult stereo = RunDenseStream(o, ws);
  EXPECT_EQ(stereo.maps_found, 0u);
  EXPECT_EQ(stereo.maps_made, 6u);
  // A truncated depth map (a disk that lost its tail) is not taken as finished.
  const std::string raw = ws + "/stereo/candi/raw/" + StreamViews()[3].name + ".bin";
  const std::string bytes = testing::ReadBytes(raw);
  testing::WriteBytes(raw, bytes.substr(0, bytes.size() / 2));
  fs::remove_all(ws + "/stereo/candi/filtered");
  const DenseStreamResult mended = RunDenseStream(o, ws);
  EXPECT_EQ(mended.maps_found, 5u);
  EXPECT_EQ(mended.maps_made, 1u);
  ExpectSameCloud(mended.cloud, stereo.cloud);
  // --no-maps: nothing of stereo/ is left once the run has finished.
  o.keep_maps = false;
  const DenseStreamResult no_maps = RunDenseStream(o, StreamWorkspace(dir, "no_maps"));
  ExpectSameCloud(no_maps.cloud, stereo.cloud);
  EXPECT_FALSE(fs::exists(dir.File("no_maps/stereo/candi")));
  EXPECT_TRUE(fs::is_empty(dir.File("no_maps/stereo/depth_maps")));
}

TEST(DenseStream, APhotoWithoutDepthIsReportedAndTheRestFused) {
  TempDir dir;
  const std::string ws = StreamWorkspace(dir, "ws");
  // A flat grey photo: no texture, so no depth.
  const SyntheticView& v = StreamViews()[2];
  io::WritePng(ws + "/images/" + v.name, Image8(v.image.width(), v.image.height(), 3, 128));
  const DenseStreamResult r = RunDenseStream(StreamOptions(), ws);
  ASSERT_EQ(r.empty_maps.size(), 1u);
  EXPECT_EQ(r.empty_maps[0], v.name);
  EXPECT_GT(r.cloud.size(), 500u);
}

TEST(DenseStream, AFolderThatCannotBeWrittenIsNamed) {
  TempDir dir;
  const std::string ws = StreamWorkspace(dir, "ws");
  RunDenseStream(StreamOptions(), ws);
  for (const char* stage : {"raw", "filtered", "fused"}) fs::remove_all(ws + "/stereo/candi/" + stage);
  testing::WriteBytes(ws + "/stereo/candi/raw", "a file where the maps' folder goes");
  try {
    RunDenseStream(StreamOptions(), ws);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("stereo/candi/raw"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(ws + "/stereo/candi/fused"));
  EXPECT_THROW(RunDenseStream(StreamOptions(), dir.File("nowhere")), InputError);
}

TEST(FusionTiles, PointsOnAWallAreCutIntoCellsOfFewViews) {
  // 2,000 points on the plane x = 0 and 1,000 on y = 5 (a wall shares one coordinate, where a
  // median split cannot cut), every ten points seen by a view of their own.
  std::vector<Eigen::Vector3d> points;
  std::vector<std::vector<int>> views;
  for (int k = 0; k < 3000; ++k) {
    const double u = (k % 50) * 0.2, v = (k / 50 % 40) * 0.1;
    points.push_back(k < 2000 ? Eigen::Vector3d(0, u, v) : Eigen::Vector3d(u, 5, v));
    views.push_back({k / 10});
  }
  const FusionTiles tiles(points, views, 16, 64);
  EXPECT_GE(tiles.count(), 16);
  std::vector<std::vector<int>> seen(tiles.count());
  for (size_t k = 0; k < points.size(); ++k) seen[tiles.Leaf(points[k])].push_back(views[k][0]);
  for (std::vector<int>& cell : seen) {
    std::sort(cell.begin(), cell.end());
    cell.erase(std::unique(cell.begin(), cell.end()), cell.end());
    EXPECT_LE(cell.size(), 16u + 64u / 10);  // at most the cap, or a cell too small to cut
  }
  // The same cells on a second build; a NaN point still has one.
  const FusionTiles again(points, views, 16, 64);
  EXPECT_EQ(again.count(), tiles.count());
  for (size_t k = 0; k < points.size(); k += 97) EXPECT_EQ(again.Leaf(points[k]), tiles.Leaf(points[k]));
  const int nan_cell = tiles.Leaf(Eigen::Vector3d(NAN, NAN, NAN));
  EXPECT_TRUE(nan_cell >= 0 && nan_cell < tiles.count());
  // One cell when every point is the same.
  const FusionTiles same(std::vector<Eigen::Vector3d>(500, Eigen::Vector3d(1, 2, 3)),
                         std::vector<std::vector<int>>(views.begin(), views.begin() + 500), 4, 64);
  EXPECT_EQ(same.count(), 1);
}

}  // namespace
}  // namespace candi::photogrammetry
