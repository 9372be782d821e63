#include <gtest/gtest.h>

#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/check.h"
#include "io/point_io.h"
#include "render/archive.h"
#include "render/synthetic_scene.h"
#include "tests/util/test_util.h"
#include "view/source.h"

namespace candi::view {
namespace {

using candi::testing::TempDir;

// A preview of point files: one record in k of each file (the first of every k), in the files'
// layers; none for files whose points are not records or that are small enough to pack at once.
TEST(ViewerSource, PreviewOfPointFilesTakesOneRecordInK) {
  TempDir dir;
  PointCloud a = render::UniformRectangle(7000, 8, 6, 0, {200, 40, 40}, 1);
  PointCloud b = render::UniformRectangle(3001, 8, 6, 0.5, {40, 200, 40}, 2);
  a.frame.origin = b.frame.origin = Eigen::Vector3d(416000, 9168000, 100);
  io::PointWriteOptions doubles;
  doubles.precision = io::PositionPrecision::kFloat64;
  io::WritePointCloud(dir.File("west.ply"), a, doubles);
  io::WritePointCloud(dir.File("east.las"), b);
  const std::vector<std::string> files = {dir.File("west.ply"), dir.File("east.las")};
  std::optional<ViewerSource> preview = PackPreviewSource(files, "", render::Orientation(), 1000, nullptr);
  ASSERT_TRUE(preview.has_value());
  EXPECT_EQ(preview->kind, "points");
  EXPECT_EQ(preview->preview_every, 11u);  // 10001 points / 1000, rounded up
  EXPECT_EQ(PreviewEvery(files, "", 1000), 11u);
  EXPECT_EQ(preview->preview_points, 10001u);
  const render::Archive archive(preview->archive_dir);
  const render::ArchiveManifest& m = archive.manifest();
  ASSERT_EQ(m.layers.size(), 2u);
  EXPECT_EQ(m.layers[0].name, "west");
  EXPECT_EQ(m.layers[0].points, 637u);  // ceil(7000 / 11)
  EXPECT_EQ(m.layers[1].name, "east");
  EXPECT_EQ(m.layers[1].points, 273u);  // ceil(3001 / 11)
  // The archived points are the files' records 0, k, 2k, ... (as the readers read them, to the
  // archive's quantization).
  const PointCloud west = io::ReadPointCloud(files[0]);
  const PointCloud packed = archive.ReadAll();
  size_t matched = 0;
  for (size_t i = 0; i < packed.size(); ++i) {
    const Eigen::Vector3d p = packed.WorldPosition(i);
    double best = 1e9;
    for (size_t j = 0; j < west.size(); j += 11) best = std::min(best, (west.WorldPosition(j) - p).norm());
    matched += best < 1e-3;
  }
  EXPECT_EQ(matched, 637u);  // every sampled west record, and no other west point
  const nlohmann::json scene = nlohmann::json::parse(preview->ToJson(m));
  EXPECT_EQ(scene.at("preview").at("every"), 11);
  EXPECT_EQ(scene.at("preview").at("points"), 10001);
  std::filesystem::remove_all(preview->temporary_dir);
  // A NaN in a record the preview takes: the reader's error, naming the file and the record.
  PointCloud bad = a;
  bad.positions[33].y() = std::numeric_limits<double>::quiet_NaN();
  io::WritePointCloud(dir.File("bad.ply"), bad, doubles);
  try {
    PackPreviewSource({dir.File("bad.ply"), files[1]}, "", render::Orientation(), 1000, nullptr);
    FAIL() << "NaN accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.ply: vertex 33: coordinate is NaN"), std::string::npos) << e.what();
  }
  // Few enough points, or a file that is not records: no preview.
  EXPECT_FALSE(PackPreviewSource(files, "", render::Orientation(), 5001, nullptr).has_value());
  EXPECT_EQ(PreviewEvery(files, "", 5001), 0u);
  EXPECT_EQ(PreviewEvery(files, "", 5000), 3u);  // 10001 > 2 * 5000
  io::WritePointCloud(dir.File("text.xyz"), b);
  EXPECT_FALSE(PackPreviewSource({files[0], dir.File("text.xyz")}, "", render::Orientation(), 100, nullptr).has_value());
}

}  // namespace
}  // namespace candi::view
