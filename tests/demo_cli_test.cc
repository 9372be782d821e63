// `candi demo --quick`: the reduced Borobudur example end to end (what `make demo` runs, smaller):
// 12 relief panels on the south foot (8 behind the encasement, 4 in the excavated corner), and the
// corner's close range through COLMAP structure from motion and dense stereo.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "io/image/png_io.h"
#include "io/point_io.h"
#include "render/camera.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

using nlohmann::json;

// The demo's panel k on the south foot wall (y = -56.5): x from t to t + 2.7, z 0.8 to 1.72.
struct PanelBox {
  double x0, x1;
};
PanelBox SouthPanel(int k) {
  const double t = -56.5 + 0.5 + 2.8 * k + 0.05;
  return {t, t + 2.7};
}

// The pixel rectangle (shrunk by `margin` px) covering panel k as the view sees it.
struct PixelRect {
  int u0, u1, v0, v1;
};
PixelRect Project(const render::Camera& camera, int k, int margin) {
  const render::Camera::Projector p = camera.MakeProjector();
  const PanelBox b = SouthPanel(k);
  double u0 = 1e9, u1 = -1e9, v0 = 1e9, v1 = -1e9;
  for (double x : {b.x0, b.x1})
    for (double z : {0.8, 1.72}) {
      double u = 0, v = 0, d = 0;
      EXPECT_TRUE(p.Project(Eigen::Vector3d(x, -56.5, z), &u, &v, &d));
      u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    }
  return {static_cast<int>(std::ceil(u0)) + margin, static_cast<int>(std::floor(u1)) - margin,
          static_cast<int>(std::ceil(v0)) + margin, static_cast<int>(std::floor(v1)) - margin};
}

render::Camera LoadCamera(const std::string& path) {
  const json j = json::parse(testing::ReadBytes(path));
  render::Camera c;
  c.width = j["width"], c.height = j["height"], c.fov_y_deg = j["fov_y_deg"];
  for (int i = 0; i < 3; ++i) c.eye[i] = j["eye"][i], c.target[i] = j["target"][i], c.up[i] = j["up"][i];
  return c;
}

// Pixels of `rect` where a and b differ by more than `tolerance` in some channel, and how many.
std::pair<size_t, size_t> Differing(const Image8& a, const Image8& b, const PixelRect& r, int tolerance) {
  size_t differ = 0, total = 0;
  for (int v = std::max(r.v0, 0); v <= std::min(r.v1, a.height() - 1); ++v)
    for (int u = std::max(r.u0, 0); u <= std::min(r.u1, a.width() - 1); ++u) {
      ++total;
      for (int c = 0; c < 3; ++c)
        if (std::abs(int(a.at(u, v, c)) - int(b.at(u, v, c))) > tolerance) {
          ++differ;
          break;
        }
    }
  return {differ, total};
}

TEST(DemoCli, QuickDemoHidesThePanelsBehindTheEncasementAndShowsThemSeeThrough) {
  const std::string relief = std::string(CANDI_EXECUTABLE) + "-relief";
  if (!testing::FileExists(relief)) GTEST_SKIP() << "the demo runs in candi-relief, not built here (CANDI_BUILD_RELIEF=OFF)";
  TempDir dir;
  const testing::CommandResult r = RunCandi("-q demo --quick --width 320 --height 240 -o " + dir.File("demo"));
  ASSERT_EQ(r.code, 0) << r.output;
  const json a = json::parse(testing::ReadBytes(dir.File("demo/archive/archive.json")));
  ASSERT_EQ(a["layers"].size(), 4u);
  EXPECT_EQ(a["layers"][0]["name"], "building");
  EXPECT_EQ(a["layers"][1]["points"], 200000);
  EXPECT_EQ(a["layers"][1]["scanned"], false);
  const json& reliefs = a["layers"][2];
  EXPECT_EQ(reliefs["name"], "reliefs");
  EXPECT_EQ(reliefs["scanned"], false);
  ASSERT_EQ(reliefs["parameters"]["panels"].size(), 12u);
  EXPECT_EQ(reliefs["parameters"]["misfits"], 0);
  size_t at_photo_resolution = 0;
  for (const json& p : reliefs["parameters"]["panels"]) {
    EXPECT_LT(p["rms_mm"].get<double>(), 5.0) << p.dump();
    at_photo_resolution += p["prediction"] == "photo resolution";
  }
  EXPECT_EQ(at_photo_resolution, 8u) << "the hidden panels go through the network at their photos' resolution";

  // The close range: photos -> sfm -> dense -> georeferenced on the picked targets, over the scan.
  const json& corner = a["layers"][3];
  EXPECT_EQ(corner["name"], "corner");
  EXPECT_EQ(corner["scanned"], true);
  EXPECT_NE(corner["method"].get<std::string>().find("structure from motion"), std::string::npos) << corner.dump();
  EXPECT_GT(corner["points"].get<int>(), 5000) << corner.dump();
  const json& georef = corner["parameters"]["georef"];
  EXPECT_EQ(georef["converged"], true) << georef.dump();
  EXPECT_GE(georef["rmse_m"]["control"]["count"].get<int>(), 3) << georef.dump();
  EXPECT_LT(georef["rmse_m"]["control"]["3d"].get<double>(), 0.03) << georef.dump();
  EXPECT_GT(a["layers"][0]["replaced_by"]["corner"].get<int>(), 1000) << "the close range replaces the scan in the dig";
  // Its points on the exposed foot wall (y = -56.5) lie on it: the whole chain's accuracy.
  const PointCloud close_range = io::ReadPointCloud(dir.File("demo/archive/layers/corner.ply"));
  std::vector<double> off_wall;
  for (size_t i = 0; i < close_range.size(); ++i) {
    const Eigen::Vector3d p = close_range.WorldPosition(i);
    if (p.x() > 46 && p.x() < 55 && p.z() > 0.3 && p.z() < 3.7 && std::abs(p.y() + 56.5) < 0.5)
      off_wall.push_back(std::abs(p.y() + 56.5));
  }
  ASSERT_GT(off_wall.size(), 300u) << "too few close-range points on the foot wall";
  std::nth_element(off_wall.begin(), off_wall.begin() + off_wall.size() / 2, off_wall.end());
  // Measured 1.68 cm on every quick run here since the SfM is repeatable (before, with COLMAP's
  // own matcher, 1.8 to 6.9 cm from run to run), 2.0 cm in the full demo. The quick stereo pixel
  // is 7.4 cm at 11 m; a failed georeference is off by decimetres or more. 4 cm leaves room for
  // another machine's rounding (README, Reproducibility), and is about half a stereo pixel.
  const double median = off_wall[off_wall.size() / 2];
  std::printf("close range to the foot wall: median %.4f m over %zu points\n", median, off_wall.size());
  EXPECT_LT(median, 0.04) << "median distance of the close range to the foot wall, m (a stereo pixel is 0.074)";

  const auto png = [&](const char* name) { return io::ReadPng(dir.File(std::string("demo/archive/renders/") + name + ".png")).image8; };
  const Image8 opaque = png("corner_opaque"), opaque_building = png("corner_opaque_building");
  const Image8 see_through = png("corner_transparent"), see_through_building = png("corner_transparent_building");
  const render::Camera camera = LoadCamera(dir.File("demo/archive/renders/corner_opaque.view.json"));
  // Hidden panels (south side 28..35, behind the encasement): the opaque render is the building's
  // alone there; the see-through render shows them.
  size_t hidden_changed = 0, hidden_total = 0, hidden_seen = 0;
  for (int k = 30; k <= 35; ++k) {
    const PixelRect rect = Project(camera, k, 1);
    const auto o = Differing(opaque, opaque_building, rect, 8);
    const auto t = Differing(see_through, see_through_building, rect, 8);
    hidden_changed += o.first, hidden_total += o.second, hidden_seen += t.first;
  }
  ASSERT_GT(hidden_total, 50u) << "the hidden panels' region is off the image";
  std::printf("hidden panels' region: %zu of %zu pixels differ in the opaque render, %zu in the see-through one\n",
              hidden_changed, hidden_total, hidden_seen);
  EXPECT_LT(hidden_changed, hidden_total / 50) << "hidden panels show through the encasement";
  EXPECT_GT(hidden_seen, hidden_total / 4) << "hidden panels do not show in the see-through render";
  // The four in the dig (36..39) are visible in the opaque render too.
  size_t visible_changed = 0, visible_total = 0;
  for (int k = 36; k <= 39; ++k) {
    const auto o = Differing(opaque, opaque_building, Project(camera, k, 1), 8);
    visible_changed += o.first, visible_total += o.second;
  }
  ASSERT_GT(visible_total, 20u);
  EXPECT_GT(visible_changed, visible_total / 3) << "the excavated panels are not visible";

  for (const char* v : {"overview_opaque", "overview_transparent", "corner_opaque", "corner_transparent", "corner_panels"})
    EXPECT_TRUE(testing::FileExists(dir.File(std::string("demo/") + v + ".png"))) << v;
  EXPECT_TRUE(testing::FileExists(dir.File("demo/scene.json")));
  EXPECT_NE(r.out.find("reliefs"), std::string::npos) << r.out;  // the layer table
}

// The same input and seed give the same bytes: two quick demos into the same folder, the second on
// one core (taskset), give identical layers, render archive, renders, MeshLab project and
// archive.json; only the run times (timings.json, the checkpoints, the logs) and the SQLite
// file's own page layout may differ. This covers COLMAP's part: the SfM model files too.
TEST(DemoCli, TwoQuickDemosGiveTheSameBytesOnTwoCoresAndOne) {
  const std::string relief = std::string(CANDI_EXECUTABLE) + "-relief";
  if (!testing::FileExists(relief)) GTEST_SKIP() << "the demo runs in candi-relief, not built here (CANDI_BUILD_RELIEF=OFF)";
  TempDir dir;
  const std::string args = " -q demo --quick --width 320 --height 240 -o " + dir.File("demo");
  testing::CommandResult r = RunCandi(args);
  ASSERT_EQ(r.code, 0) << r.output;
  std::filesystem::rename(dir.File("demo"), dir.File("first"));
  const bool taskset = testing::RunCommand("taskset -c 0 true").code == 0;
  r = testing::RunCommand((taskset ? "taskset -c 0 " : "") + std::string(CANDI_EXECUTABLE) + args);
  ASSERT_EQ(r.code, 0) << r.output;
  const auto run_specific = [](const std::string& relative) {
    for (const char* part : {"timings.json", "/checkpoints/", "/logs/", "database.db", "sfm_report.json",
                             "sfm_stages.txt"})
      if (relative.find(part) != std::string::npos) return true;
    return false;
  };
  size_t compared = 0;
  std::vector<std::string> differ;
  std::set<std::string> seen;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir.File("first"))) {
    if (!e.is_regular_file() || e.is_symlink()) continue;
    const std::string relative = std::filesystem::relative(e.path(), dir.File("first")).string();
    if (run_specific(relative)) continue;
    ++compared;
    seen.insert(relative);
    const std::string second = dir.File("demo/" + relative);
    if (!testing::FileExists(second) || testing::ReadBytes(e.path().string()) != testing::ReadBytes(second))
      differ.push_back(relative);
  }
  EXPECT_TRUE(differ.empty()) << differ.size() << " of " << compared << " files differ, e.g. " << differ.front();
  for (const char* must : {"archive/archive.json", "archive/layers/corner.ply", "archive/layers/reliefs.ply",
                           "archive/archive/manifest.json", "archive/renders/corner_transparent.png",
                           "archive/work/corner_sfm/sparse/0/images.bin", "archive/work/corner_sfm/sparse/0/points3D.bin",
                           "archive/work/corner_sfm/matches.txt", "archive/work/corner_dense.ply"})
    EXPECT_TRUE(seen.count(must)) << must << " was not compared";
  EXPECT_GT(compared, 50u);
  const json a = json::parse(testing::ReadBytes(dir.File("demo/archive/archive.json")));
  EXPECT_TRUE(a.contains("reproducibility")) << "archive.json says what makes the build repeatable";
  EXPECT_FALSE(a.contains("seconds")) << "run times are kept in timings.json";
}

}  // namespace
}  // namespace candi::testing
