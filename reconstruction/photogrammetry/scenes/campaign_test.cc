#include "reconstruction/photogrammetry/scenes/campaign.h"

#include <tbb/global_control.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include <gtest/gtest.h>

#include "core/atomic_file.h"
#include "core/check.h"
#include "io/image/jpeg_io.h"
#include "io/point_io.h"
#include "tests/util/test_util.h"

namespace candi::photogrammetry {
namespace {

namespace fs = std::filesystem;

std::vector<std::vector<std::string>> ReadCsv(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream s(line);
    std::string f;
    while (std::getline(s, f, ',')) fields.push_back(f);
    rows.push_back(fields);
  }
  return rows;
}

TEST(Campaign, PlansThePhotosCountedSessionsAndTargetsEachSessionCanUse) {
  CampaignOptions o;
  o.photos = 60;
  o.chunks = 3;
  const Campaign c = PlanCampaign(o);
  ASSERT_EQ(c.photos.size(), 60u);
  ASSERT_EQ(c.chunks, (std::vector<std::string>{"s1", "s2", "s3"}));
  std::map<std::string, int> per_chunk;
  std::set<std::string> names;
  for (const CampaignPhoto& p : c.photos) {
    ++per_chunk[p.chunk];
    EXPECT_TRUE(names.insert(p.name).second) << p.name;
    // Every walk photo faces its wall at the wall distance (the centre ray hits stone ~2 m away).
    const Eigen::Vector3d centre_ray = p.camera.rotation.transpose() * p.camera.Ray(p.camera.cx, p.camera.cy);
    const double t = c.scene.RayHit(p.camera.Center(), centre_ray);
    EXPECT_GT(t, 0.5 * o.wall_distance) << p.name;
    EXPECT_LT(t, 2.5 * o.wall_distance) << p.name;
  }
  for (const auto& [chunk, n] : per_chunk) EXPECT_GE(n, 15) << chunk;
  // Neighbours in a row overlap: the wall point at the centre of one photo is in the next's frame.
  int pairs = 0, overlapping = 0;
  for (size_t i = 0; i + 1 < c.photos.size(); ++i) {
    const CampaignPhoto &a = c.photos[i], &b = c.photos[i + 1];
    if (a.chunk != b.chunk || a.row != b.row || a.terrace != b.terrace) continue;
    ++pairs;
    const Eigen::Vector3d dir = a.camera.rotation.transpose() * a.camera.Ray(a.camera.cx, a.camera.cy);
    const Eigen::Vector3d x = a.camera.Center() + c.scene.RayHit(a.camera.Center(), dir) * dir;
    overlapping += c.scene.Sees(b.camera, x);
  }
  EXPECT_GT(pairs, 40);
  EXPECT_EQ(overlapping, pairs);
  // Four targets a session, one of them a check; each seen by >= 2 photos of its own session;
  // no two in one place.
  ASSERT_EQ(c.targets.size(), 12u);
  for (size_t i = 0; i < c.targets.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      EXPECT_GT((c.targets[i].center - c.targets[j].center).norm(), 0.5) << c.targets[i].name << " " << c.targets[j].name;
  for (const std::string& chunk : c.chunks) {
    int control = 0, check = 0;
    for (const CampaignTarget& t : c.targets) {
      if (t.chunk != chunk) continue;
      (t.check ? check : control) += 1;
      int seen = 0;
      for (const CampaignPhoto& p : c.photos) seen += p.chunk == chunk && c.scene.Sees(p.camera, t.center);
      EXPECT_GE(seen, 2) << t.name;
    }
    EXPECT_EQ(control, 3) << chunk;
    EXPECT_EQ(check, 1) << chunk;
  }
  // The loop: the first and the last photo of the lowest row look at neighbouring stretches.
  const CampaignPhoto& first = c.photos.front();
  const CampaignPhoto* last = nullptr;
  for (const CampaignPhoto& p : c.photos)
    if (p.terrace == 0 && p.row == 0) last = &p;
  ASSERT_NE(last, nullptr);
  EXPECT_EQ(last->chunk, "s3");
  EXPECT_LT((first.camera.Center() - last->camera.Center()).norm(), 2.0);
}

TEST(Campaign, TheBuildingGrowsWithTheCountAndKeepsTheWallDistance) {
  CampaignOptions o;
  o.photos = 60;
  const Campaign small = PlanCampaign(o);
  o.photos = 2000;
  o.chunks = 12;
  o.uav_photos = 100;
  const Campaign large = PlanCampaign(o);
  EXPECT_EQ(small.terrace_half_sides.size(), 1u);
  EXPECT_GE(large.terrace_half_sides.size(), 3u);
  EXPECT_GT(large.terrace_half_sides.front(), 8 * small.terrace_half_sides.front());
  EXPECT_EQ(large.photos.size(), 2000u);
  int uav = 0;
  for (const CampaignPhoto& p : large.photos) uav += p.chunk == "uav";
  EXPECT_EQ(uav, 100);
  // The step between neighbours stays near the footprint times (1 - overlap) at every size.
  for (const Campaign* c : {&small, &large}) {
    double sum = 0;
    int n = 0;
    for (size_t i = 0; i + 1 < c->photos.size(); ++i) {
      const CampaignPhoto &a = c->photos[i], &b = c->photos[i + 1];
      if (a.chunk != b.chunk || a.row != b.row || a.terrace != b.terrace || a.chunk == "uav") continue;
      sum += (a.camera.Center() - b.camera.Center()).norm();
      ++n;
    }
    const double footprint = 2 * o.wall_distance * std::tan(0.5 * o.fov_degrees * M_PI / 180);
    EXPECT_NEAR(sum / n, footprint * (1 - o.overlap), 0.25 * footprint * (1 - o.overlap));
  }
}

TEST(Campaign, CarvingsAreContinuousReliefsBehindTheFace) {
  CampaignOptions o;
  const Campaign c = PlanCampaign(o);
  ASSERT_FALSE(c.scene.carvings.empty());
  const SyntheticCarving& k = c.scene.carvings.front();
  double deepest = 0, largest_jump = 0;
  for (int i = 0; i <= 400; ++i) {
    for (int j = 0; j <= 200; ++j) {
      const double u = k.width * i / 400, v = k.height * j / 200;
      const double d = k.Depth(u, v);
      ASSERT_GE(d, 0);
      ASSERT_LE(d, k.depth);
      deepest = std::max(deepest, d);
      if (i > 0) largest_jump = std::max(largest_jump, std::abs(d - k.Depth(k.width * (i - 1) / 400, v)));
    }
  }
  EXPECT_EQ(k.Depth(0.001, 0.5 * k.height), 0.0);  // the frame is the face
  EXPECT_GT(deepest, 0.9 * k.depth);
  EXPECT_LT(largest_jump, 0.2 * k.depth);  // no cliff between samples 4 mm apart
  // A ray square onto the panel stops behind the face by the carving's depth there.
  const Eigen::Vector3d n = k.u_axis.cross(k.v_axis);
  int checked = 0;
  for (double u = 0.1; u < k.width; u += 0.137) {
    const double v = 0.5 * k.height;
    const Eigen::Vector3d on_face = k.origin + u * k.u_axis + v * k.v_axis;
    const double t = c.scene.RayHit(on_face + 1.0 * n, -n);
    EXPECT_NEAR(t, 1.0 + k.Depth(u, v), 1e-6) << u;
    ++checked;
  }
  EXPECT_GT(checked, 5);
}

TEST(Campaign, BadOptionsNameTheField) {
  CampaignOptions o;
  o.photos = 4;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = CampaignOptions();
  o.uav_photos = 55;  // leaves 5 for 3 sessions
  try {
    o.Check();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("uav_photos"), std::string::npos) << e.what();
  }
  o = CampaignOptions();
  o.gps_sigma = std::nan("");
  EXPECT_THROW(o.Check(), std::invalid_argument);
}

// Writes a small campaign on one thread and on two: the same bytes in every file.
TEST(Campaign, WritesPhotosWithExifTargetsPicksPriorsAndTruthTheSameOnAnyThreadCount) {
  candi::testing::TempDir dir;
  CampaignOptions o;
  o.photos = 14;
  o.width = 96;
  o.chunks = 2;
  o.uav_photos = 4;
  o.gps_sigma = 3;
  o.noise_sigma = 2;
  o.supersample = 1;
  std::map<std::string, std::string> bytes[2];
  for (int threads : {1, 2}) {
    const fs::path out = fs::path(dir.path()) / ("t" + std::to_string(threads));
    {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      WriteCampaign(o, out.string());
    }
    for (const auto& e : fs::recursive_directory_iterator(out)) {
      if (e.is_regular_file()) bytes[threads - 1][fs::relative(e.path(), out).string()] = ReadFileToString(e.path().string());
    }
  }
  ASSERT_EQ(bytes[0].size(), bytes[1].size());
  for (const auto& [name, content] : bytes[0]) EXPECT_TRUE(bytes[1][name] == content) << name;
  const fs::path out = fs::path(dir.path()) / "t1";
  // Photos: 14 JPEGs in three session folders, each with the EXIF segment.
  int photos = 0;
  for (const char* chunk : {"s1", "s2", "uav"}) {
    for (const auto& e : fs::directory_iterator(out / chunk)) {
      const std::string jpeg = ReadFileToString(e.path().string());
      EXPECT_NE(jpeg.find(std::string("Exif\0\0II*\0", 10)), std::string::npos) << e.path();
      EXPECT_EQ(io::ReadJpeg(e.path().string()).width(), 96);
      ++photos;
    }
  }
  EXPECT_EQ(photos, 14);
  const auto targets = ReadCsv(out / "targets.csv"), picks = ReadCsv(out / "picks.csv");
  const auto priors = ReadCsv(out / "priors.csv"), cameras = ReadCsv(out / "truth" / "cameras.csv");
  EXPECT_EQ(targets.size(), 1u + 4 + 4 + 4);
  EXPECT_EQ(targets[0], (std::vector<std::string>{"name", "E", "N", "H", "role", "accuracy"}));
  EXPECT_GT(picks.size(), 8u);
  ASSERT_EQ(priors.size(), 15u);
  ASSERT_EQ(cameras.size(), 15u);
  // Priors are the true centres plus noise of the stated sigma (survey frame, ~10^6 m).
  double sum_sq = 0;
  for (size_t i = 1; i < priors.size(); ++i) {
    ASSERT_EQ(priors[i][0], cameras[i][0]);
    for (int a = 0; a < 3; ++a) {
      const double d = std::stod(priors[i][1 + a]) - std::stod(cameras[i][4 + a]);
      sum_sq += d * d;
    }
  }
  EXPECT_GT(std::stod(cameras[1][5]), 9.0e6);
  EXPECT_NEAR(std::sqrt(sum_sq / (3 * 14)), 3.0, 1.5);
  // The truth surface: in the survey frame, near the building.
  const PointCloud surface = io::ReadPointCloud((out / "truth" / "surface.ply").string());
  EXPECT_GT(surface.size(), 1000u);
  const Box3d box = surface.WorldBounds();
  EXPECT_NEAR(box.Center().x(), kCampaignSurveyOrigin.x(), 80);
  EXPECT_GT(box.min.z(), kCampaignSurveyOrigin.z() - 1.01);
  // A second run into the same folder is refused unless told to overwrite.
  EXPECT_THROW(WriteCampaign(o, out.string()), InputError);
  // Overwritten with fewer sessions: the old sessions' folders go, the user's files stay.
  candi::testing::WriteBytes((out / "notes.txt").string(), "mine");
  o.chunks = 1;
  o.uav_photos = 0;
  EXPECT_NO_THROW(WriteCampaign(o, out.string(), true));
  EXPECT_TRUE(fs::exists(out / "s1"));
  EXPECT_FALSE(fs::exists(out / "s2"));
  EXPECT_FALSE(fs::exists(out / "uav"));
  EXPECT_TRUE(fs::exists(out / "notes.txt"));
}

}  // namespace
}  // namespace candi::photogrammetry
