#include "reconstruction/photogrammetry/sfm/chunked_mapping.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "core/check.h"
#include "reconstruction/photogrammetry/scenes/campaign.h"
#include "tests/util/test_util.h"

namespace candi::photogrammetry {
namespace {

namespace fs = std::filesystem;
using candi::testing::TempDir;

TEST(ChunkedMapping, ChunksAreTheFolders) {
  const auto chunks = ChunksByFolder({"s2/b.jpg", "s1/a.jpg", "top.jpg", "s1/c.jpg"});
  ASSERT_EQ(chunks.size(), 3u);
  EXPECT_EQ(chunks.at("s1"), (std::vector<std::string>{"s1/a.jpg", "s1/c.jpg"}));
  EXPECT_EQ(chunks.at("all"), (std::vector<std::string>{"top.jpg"}));
}

TEST(ChunkedMapping, UndistortingInvertsColmapsDistortion) {
  ColmapImage image;
  for (const auto& [model, params] : std::vector<std::pair<std::string, std::vector<double>>>{
           {"SIMPLE_RADIAL", {500, 320, 240, -0.08}},
           {"RADIAL", {500, 320, 240, -0.08, 0.02}},
           {"OPENCV", {500, 510, 320, 240, -0.08, 0.02, 0.001, -0.002}},
           {"PINHOLE", {500, 510, 320, 240}}}) {
    ColmapCamera camera;
    camera.model = model;
    camera.params = params;
    ColmapCamera pinhole = camera;
    pinhole.model = "PINHOLE";
    pinhole.params = {params[0], model == "SIMPLE_RADIAL" || model == "RADIAL" ? params[0] : params[1],
                      model == "SIMPLE_RADIAL" || model == "RADIAL" ? params[1] : params[2],
                      model == "SIMPLE_RADIAL" || model == "RADIAL" ? params[2] : params[3]};
    for (const Eigen::Vector3d& x : {Eigen::Vector3d(0.3, -0.2, 1), Eigen::Vector3d(-0.5, 0.4, 1.5)}) {
      const Eigen::Vector2d distorted = ProjectToImage(camera, image, x);
      const Eigen::Vector2d straight = ProjectToImage(pinhole, image, x);
      EXPECT_LT((UndistortPixel(camera, distorted) - straight).norm(), 1e-6) << model;
    }
  }
  ColmapCamera fisheye;
  fisheye.model = "OPENCV_FISHEYE";
  fisheye.params = {500, 500, 320, 240, 0, 0, 0, 0};
  EXPECT_THROW(UndistortPixel(fisheye, {1, 1}), InputError);
}

// Chunk models made from the campaign's truth, each in a frame of its own (a similarity away
// from the world): tying finds each frame from the targets' picks alone, and a chunk whose
// targets were not picked is named and left out.
TEST(ChunkedMapping, TiesChunksOnTheirTargetsAndNamesTheOneThatCannotBe) {
  TempDir dir;
  CampaignOptions o;
  o.photos = 45;
  o.width = 320;
  o.chunks = 3;
  o.supersample = 1;
  const std::string site = dir.File("site");
  const Campaign c = WriteCampaign(o, site);
  // Picks of s3's targets removed: s3 cannot be tied.
  std::ifstream in(site + "/picks.csv");
  std::string line, kept;
  while (std::getline(in, line))
    if (line.find(",s3_") == std::string::npos) kept += line + "\n";
  candi::testing::WriteBytes(dir.File("picks.csv"), kept);
  std::map<std::string, std::string> models;
  std::map<std::string, std::vector<std::string>> images;
  std::map<std::string, Sim3> model_from_world;
  for (size_t k = 0; k < c.chunks.size(); ++k) {
    const std::string& name = c.chunks[k];
    const Sim3 t(0.5 + 0.3 * k, Eigen::Quaterniond(Eigen::AngleAxisd(0.4 + k, Eigen::Vector3d(1, 2, 3).normalized())),
                 Eigen::Vector3d(3.0 * k, -2, 1));
    model_from_world[name] = t;
    ColmapModel m;
    ColmapCamera camera;
    camera.camera_id = 1;
    camera.model = "SIMPLE_RADIAL";
    camera.width = c.photos.front().camera.width;
    camera.height = c.photos.front().camera.height;
    camera.params = {c.photos.front().camera.fx, c.photos.front().camera.cx, c.photos.front().camera.cy, 0.0};
    m.cameras[1] = camera;
    uint32_t id = 1;
    for (const CampaignPhoto& p : c.photos) {
      if (p.chunk != name) continue;
      ColmapImage image;
      image.image_id = id++;
      image.camera_id = 1;
      image.name = name + "/" + p.name;
      // Model frame X_m = T X_w: R_m = R T_R^T, t_m = s t - R_m T_t.
      const Eigen::Quaterniond r = Eigen::Quaterniond(p.camera.rotation) * t.rotation.conjugate();
      image.cam_from_world_rotation = r.normalized();
      image.cam_from_world_translation = t.scale * p.camera.translation - r * t.translation;
      m.images[image.image_id] = image;
      images[name].push_back(image.name);
      // A point on the wall the photo faces, as a sparse point.
      const Eigen::Vector3d dir = p.camera.rotation.transpose() * p.camera.Ray(p.camera.cx, p.camera.cy);
      ColmapPoint3d point;
      point.point3d_id = m.points3d.size() + 1;
      point.xyz = t * (p.camera.Center() + c.scene.RayHit(p.camera.Center(), dir) * dir);
      m.points3d[point.point3d_id] = point;
    }
    models[name] = dir.File("models/" + name);
    WriteColmapModelBinary(m, models[name]);
  }
  ChunkedMappingOptions options;
  options.targets = site + "/targets.csv";
  options.picks = dir.File("picks.csv");
  options.joint.enabled = false;  // the ties themselves (joint_adjustment_test.cc adjusts)
  const ChunkedMappingResult r = TieChunks(models, images, {}, options, dir.File("merged"));
  EXPECT_FALSE(r.joint.ran);
  ASSERT_EQ(r.chunks.size(), 3u);
  EXPECT_LT((r.frame.origin - kCampaignSurveyOrigin).norm(), 100.0);
  for (const ChunkResult& k : r.chunks) {
    if (k.name == "s3") {
      EXPECT_FALSE(k.tied);
      EXPECT_NE(k.reason.find("usable control targets"), std::string::npos) << k.reason;
      continue;
    }
    ASSERT_TRUE(k.tied) << k.name << ": " << k.reason;
    // Its own session's four targets, and those of the neighbouring sessions its photos see.
    EXPECT_GE(k.control_used, 3) << k.name;
    EXPECT_GE(k.check_used, 1) << k.name;
    EXPECT_LT(k.check.d3, 0.01) << k.name;
    // local = world + survey origin - shift; the tie recovers T^-1 to ~1 cm two metres from its
    // targets (1 mm survey noise, 0.3 px picks of 7 mm pixels).
    const Eigen::Vector3d offset = kCampaignSurveyOrigin - r.frame.origin;
    for (const Eigen::Vector3d& x : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(2, -1, 2)}) {
      EXPECT_LT((k.local_from_model * (model_from_world[k.name] * x) - (x + offset)).norm(), 0.015) << k.name;
    }
  }
  const ColmapModel merged = ReadColmapModel(r.merged_dir);
  EXPECT_EQ(r.merged_images, images["s1"].size() + images["s2"].size());
  EXPECT_EQ(merged.images.size(), r.merged_images);
  EXPECT_EQ(merged.cameras.size(), 2u);
  for (const auto& [id, image] : merged.images) EXPECT_EQ(image.name.substr(0, 2) == "s3", false);
  // No chunk at all: the message names each chunk's reason.
  // A folder of one photo is named as such.
  std::map<std::string, std::string> none = {{"s1", ""}, {"s2", ""}, {"s9", ""}};
  images["s9"] = {"s9/only.jpg"};
  try {
    TieChunks(none, images, {}, options, dir.File("merged2"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("s2: its mapper found no model (logs/mapper_s2.log)"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("s9: a folder of one photo"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace candi::photogrammetry
