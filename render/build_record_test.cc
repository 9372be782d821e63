#include "render/build_record.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "core/atomic_file.h"
#include "core/check.h"
#include "tests/util/test_util.h"

namespace candi::render {
namespace {

using testing::TempDir;

// An archive.json as candi wrote it before the record kept the render settings (main at
// 11d32bb, 2026-12-07: tests/data/build/archive_json_2026-12-07.json, a build of two point layers
// with a comparison, COPC files, a licence and annotations): it still reads, without render
// settings, and writes back the same but for its inline annotation camera, now written whole.
TEST(BuildRecord, AnOlderRecordStillReads) {
  const std::string path = testing::SourceDir() + "/tests/data/build/archive_json_2026-12-07.json";
  const std::string text = ReadFileToString(path);
  const BuildRecord r = BuildRecord::FromJson(text, path);
  EXPECT_FALSE(r.render.has_value());
  EXPECT_EQ(r.name, "older");
  ASSERT_EQ(r.layers.size(), 2u);
  EXPECT_EQ(r.layers[1].file, "layers/scan.ply");
  EXPECT_TRUE(r.layers[1].highlight);
  ASSERT_EQ(r.comparisons.size(), 1u);
  EXPECT_EQ(r.comparisons[0].count, 2000u);
  ASSERT_TRUE(r.copc.has_value());
  EXPECT_EQ(r.copc->layers.size(), 2u);
  ASSERT_EQ(r.annotations.size(), 2u);
  EXPECT_EQ(r.annotations[0].view, "top");
  ASSERT_TRUE(r.annotations[1].camera.has_value());
  EXPECT_EQ(r.annotations[1].camera->eye, Eigen::Vector3d(416005, 9167995, 120));
  nlohmann::json old = nlohmann::json::parse(text), again = nlohmann::json::parse(r.ToJson());
  old.erase("annotations");
  again.erase("annotations");
  EXPECT_EQ(again, old);
  EXPECT_EQ(BuildRecord::FromJson(r.ToJson(), path).ToJson(), r.ToJson());
}

BuildRecord Example() {
  BuildRecord r;
  r.candi_version = "test";
  r.scene_path = "/somewhere/scene.json";
  r.scene_sha256 = "ab";
  r.name = "site";
  r.seed = 7;
  r.origin = {416000, 9168000, 0};
  r.crs_definition = "EPSG:32749";
  r.crs_label = "WGS 84 / UTM zone 49S";
  BuildLayerRecord l;
  l.name = "hill";
  l.kind = "foundation";
  l.file = "layers/hill.ply";
  l.parameters_json = R"({"count":10,"sections":["A"]})";
  l.sources.push_back({"/somewhere/hill.dxf", "cd", 12});
  l.world_from_layer(0, 3) = 416000.125;
  l.replaced_by = {{"close", 3}};
  l.crs_json = R"({"stated":null,"transformed":false})";
  r.layers.push_back(l);
  r.views.push_back({"top", "renders/top.png", false, {{"hill", 0.6}}, true});
  ImageSettings s;
  s.spbr.repeat_level = 12;
  s.spbr.seed = 7;
  s.width = 200;
  s.height = 150;
  s.background = {10, 20, 30};
  s.brightness = Brightness::Gain(1.5);
  r.render = s;
  r.licence = "CC0";
  Camera c;
  c.eye = {416010, 9168000, 50};
  c.target = {416000, 9168000, 0};
  r.annotations.push_back({"stair", "", {416000, 9168000, 3}, "", c});
  r.annotations.push_back({"foot", "the foot", {416001, 9168000, 3}, "top", std::nullopt});
  BuildComparisonRecord cmp;
  cmp.name = "d";
  cmp.compared = "hill";
  cmp.reference = "close";
  cmp.reference_is_layer = true;
  cmp.method = "m3c2";
  cmp.count = 5;
  cmp.mean = NAN;
  cmp.within_tolerance = NAN;
  cmp.significant = 2;
  r.comparisons.push_back(cmp);
  BuildCopcRecord copc;
  copc.layers.push_back({"layers/hill.copc.laz", 10, 999, "hill"});
  copc.scene = BuildCopcFileRecord{"copc/site.copc.laz", 10, 1000, ""};
  copc.scale_m = 1e-4;
  r.copc = copc;
  return r;
}

// Every field written is read back, and the text again is the same bytes.
TEST(BuildRecord, WritesAndReadsEveryField) {
  const BuildRecord r = Example();
  const std::string text = r.ToJson();
  const BuildRecord back = BuildRecord::FromJson(text, "x.json");
  EXPECT_EQ(back.ToJson(), text);
  ASSERT_TRUE(back.render.has_value());
  EXPECT_EQ(*back.render, *r.render);
  EXPECT_EQ(back.layers[0].world_from_layer(0, 3), 416000.125);
  EXPECT_EQ(back.layers[0].replaced_by, r.layers[0].replaced_by);
  EXPECT_EQ(back.views[0].opacity, r.views[0].opacity);
  ASSERT_TRUE(back.annotations[0].camera.has_value());
  EXPECT_EQ(back.annotations[0].camera->eye, r.annotations[0].camera->eye);
  EXPECT_EQ(back.annotations[1].view, "top");
  EXPECT_TRUE(std::isnan(back.comparisons[0].mean));
  EXPECT_EQ(back.comparisons[0].significant, 2u);
  EXPECT_EQ(back.copc->scene->path, "copc/site.copc.laz");
  // A comparison's checkpoint entry, without "resumed".
  const std::string entry = ComparisonToJson(r.comparisons[0]);
  EXPECT_EQ(entry.find("resumed"), std::string::npos);
  EXPECT_EQ(ComparisonToJson(ComparisonFromJson(entry, "e")), entry);
  EXPECT_EQ(CopcFilesToJson(CopcFilesFromJson(CopcFilesToJson(*r.copc), "c")),
            CopcFilesToJson(*r.copc));
  // No render setting of the build depends on the machine it was made on.
  EXPECT_EQ(text.find("\"render\": {\n    \"background\": [\n      10"), text.find("\"render\""));
}

// A record that is not one, or holds a wrong type, is named with the JSON path.
TEST(BuildRecord, BadRecordsNameTheFileAndThePath) {
  auto message = [](const std::string& text) {
    try {
      BuildRecord::FromJson(text, "archive.json");
      return std::string("no throw");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
  };
  EXPECT_NE(message("[1]").find("archive.json"), std::string::npos);
  EXPECT_NE(message("{\"name\": \"x\"}").find("no \"crs\""), std::string::npos);
  EXPECT_NE(message("{").find("not valid JSON"), std::string::npos);
  std::string text = Example().ToJson();
  const std::string good = "\"repeat_level\": 12";
  text.replace(text.find(good), good.size(), "\"repeat_level\": 0");
  EXPECT_NE(message(text).find("/render/repeat_level"), std::string::npos) << message(text);
  text = Example().ToJson();
  const std::string gain = "\"brightness\": 1.5";
  text.replace(text.find(gain), gain.size(), "\"brightness\": 500");
  EXPECT_NE(message(text).find("/render/brightness"), std::string::npos) << message(text);
}

TEST(BuildRecord, FindBuildAndReadNameTheFolder) {
  TempDir dir;
  EXPECT_EQ(FindBuild(dir.path()), "");
  try {
    ReadBuildRecord(dir.path());
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no archive.json"), std::string::npos) << e.what();
  }
  WriteBuildRecord(dir.path(), Example());
  EXPECT_EQ(ReadBuildRecord(dir.path()).name, "site");
  EXPECT_EQ(FindBuild(dir.path()), "") << "no render archive beside it";
}

}  // namespace
}  // namespace candi::render
