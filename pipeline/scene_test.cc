// The scene file (pipeline/scene.h): every layer kind as parsed, paths resolved against the
// scene's folder, and every error it names, each with the JSON path of its culprit.
#include "pipeline/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "core/check.h"
#include "tests/util/test_util.h"

namespace candi::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::TempDir;
using testing::WriteBytes;

class SceneFile : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* f : {"scan.ply", "drawing.dxf", "p01.png", "p02.ply", "model.pt", "walls.csv", "dense.ply",
                          "targets.csv", "picks.csv", "view.json"}) {
      WriteBytes(dir_.File(f), "x");
    }
    fs::create_directories(dir_.File("ws"));
    fs::create_directories(dir_.File("photos"));
    WriteBytes(dir_.File("photos/b.jpg"), "x");
    WriteBytes(dir_.File("photos/a.jpg"), "x");
  }

  // A valid scene of one points layer, to change.
  static json Minimal() {
    return {{"candi_scene", 1}, {"layers", json::array({{{"name", "scan"}, {"kind", "points"}, {"file", "scan.ply"}}})}};
  }

  Scene Load(const json& j, const std::string& name = "site.json") const {
    WriteBytes(dir_.File(name), j.dump(2));
    return LoadScene(dir_.File(name));
  }

  // The error a scene gives: its message, which must name the scene file.
  std::string Error(const json& j) const { return ErrorOfText(j.dump()); }
  std::string ErrorOfText(const std::string& text) const {
    WriteBytes(dir_.File("bad.json"), text);
    try {
      LoadScene(dir_.File("bad.json"));
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("bad.json"), std::string::npos) << what;
      return what;
    }
    ADD_FAILURE() << "no error for " << text;
    return "";
  }

  // Expects the error of `j` to name `path` (the JSON path of the culprit) and to say `message`.
  void ExpectError(const json& j, const std::string& path, const std::string& message) const {
    const std::string what = Error(j);
    EXPECT_NE(what.find(": " + path + ": "), std::string::npos) << "path " << path << " in: " << what;
    EXPECT_NE(what.find(message), std::string::npos) << "message '" << message << "' in: " << what;
  }

  std::string Path(const std::string& name) const { return fs::path(dir_.File(name)).lexically_normal().string(); }

  TempDir dir_;
};

TEST_F(SceneFile, EveryLayerKindAndItsDefaults) {
  json j = {{"candi_scene", 1}, {"name", "borobudur"}, {"origin", {500000, 9100000, 200}}, {"seed", 7},
            {"render", {{"repeat_level", 32}, {"width", 640}, {"height", 480}, {"background", {1, 2, 3}},
                        {"brightness", 1.5}}}};
  j["layers"] = json::array(
      {{{"name", "scan"}, {"kind", "points"}, {"file", "scan.ply"}, {"columns", "x,y,z,r,g,b"}, {"opacity", 0.25},
        {"color", {10, 20, 30}}, {"world_from_layer", {{"scale", 2}, {"rotation_deg", {0, 0, 90}},
                                                         {"translation", {1, 2, 3}}}}},
       {{"name", "foundation"}, {"kind", "foundation"}, {"dxf", "drawing.dxf"}, {"sections", {"A", "B"}},
        {"samples_per_side", 200}, {"angular_steps", 36}, {"count", 1000}, {"mode", "sweep"}},
       {{"name", "reliefs"}, {"kind", "relief"}, {"model", "model.pt"}, {"placement", "walls.csv"}, {"width_m", 2.5},
        {"highlight", true},
        {"panels", {{{"id", "P01"}, {"photo", "p01.png"}, {"native_resolution", true}},
                    {{"id", "P02"}, {"points", "p02.ply"}}}}},
       {{"name", "corner"}, {"kind", "photogrammetry"}, {"images", "photos"}, {"targets", "targets.csv"},
        {"picks", "picks.csv"}, {"max_image_size", 800}, {"max_features", 1024}, {"resolution_scale", 0.5},
        {"iterations", 2}, {"replaces", {"scan"}}, {"replace_voxel", 0.25}},
       {{"name", "dense"}, {"kind", "photogrammetry"}, {"dense", "dense.ply"}},
       {{"name", "ws"}, {"kind", "photogrammetry"}, {"workspace", "ws"}}});
  j["views"] = json::array({{{"name", "overview"}, {"camera", "view.json"}, {"opaque", true}},
                            {{"name", "close"},
                             {"camera", {{"eye", {0, -1, 1}}}},
                             {"layers", {"scan", "reliefs"}},
                             {"focus", true},
                             {"focus_opacity", 0.8},
                             {"dim", 0.3},
                             {"opacity", {{"scan", 0.1}}},
                             {"point_size", 3}}});
  const Scene s = Load(j);
  EXPECT_EQ(s.name, "borobudur");
  ASSERT_TRUE(s.origin.has_value());
  EXPECT_EQ(*s.origin, Eigen::Vector3d(500000, 9100000, 200));
  EXPECT_EQ(s.seed, 7u);
  EXPECT_EQ(s.render.spbr.repeat_level, 32);
  EXPECT_EQ(s.render.width, 640);
  EXPECT_EQ(s.render.height, 480);
  EXPECT_EQ(s.render.background.b, 3);
  EXPECT_EQ(s.render.brightness, Brightness::Gain(1.5));
  ASSERT_EQ(s.layers.size(), 6u);

  const SceneLayer& scan = s.layers[0];
  EXPECT_EQ(scan.kind, LayerKind::kPoints);
  EXPECT_EQ(scan.file, Path("scan.ply"));
  EXPECT_EQ(scan.columns, "x,y,z,r,g,b");
  EXPECT_DOUBLE_EQ(scan.opacity, 0.25);
  ASSERT_TRUE(scan.color.has_value());
  EXPECT_EQ(scan.color->g, 20);
  EXPECT_NEAR((scan.world_from_layer * Eigen::Vector3d(1, 0, 0) - Eigen::Vector3d(1, 4, 3)).norm(), 0, 1e-12);

  const SceneLayer& f = s.layers[1];
  EXPECT_EQ(f.kind, LayerKind::kFoundation);
  EXPECT_EQ(f.dxf, Path("drawing.dxf"));
  EXPECT_EQ(f.foundation.layers, (std::vector<std::string>{"A", "B"}));
  EXPECT_EQ(f.foundation.surface.profile.samples_per_side, 200);
  EXPECT_EQ(f.foundation.surface.revolve.angular_steps, 36);
  EXPECT_EQ(f.foundation.sample.count, 1000u);
  EXPECT_EQ(f.foundation.sample.density, 0.0);
  EXPECT_EQ(f.foundation.surface.revolve.mode, mesh::RevolveMode::kSweep);

  const SceneLayer& r = s.layers[2];
  EXPECT_EQ(r.kind, LayerKind::kRelief);
  EXPECT_EQ(r.model, Path("model.pt"));
  EXPECT_EQ(r.placement, Path("walls.csv"));
  EXPECT_DOUBLE_EQ(r.width_m, 2.5);
  EXPECT_TRUE(r.highlight);
  ASSERT_EQ(r.panels.size(), 2u);
  EXPECT_EQ(r.panels[0].photo, Path("p01.png"));
  EXPECT_TRUE(r.panels[0].native_resolution);
  EXPECT_EQ(r.panels[1].points, Path("p02.ply"));
  EXPECT_TRUE(r.panels[1].photo.empty());

  const SceneLayer& c = s.layers[3];
  EXPECT_EQ(c.kind, LayerKind::kPhotogrammetry);
  EXPECT_EQ(c.images, Path("photos"));
  EXPECT_EQ(c.targets, Path("targets.csv"));
  EXPECT_EQ(c.picks, Path("picks.csv"));
  EXPECT_EQ(c.sfm.max_image_size, 800);
  EXPECT_EQ(c.sfm.max_features, 1024);
  EXPECT_DOUBLE_EQ(c.stereo.resolution_scale, 0.5);
  EXPECT_EQ(c.stereo.iterations, 2);
  EXPECT_EQ(c.replaces, (std::vector<std::string>{"scan"}));
  EXPECT_DOUBLE_EQ(c.replace_voxel, 0.25);
  // Sources: the files it reads, the photos sorted by name.
  const std::vector<std::string> sources = c.Sources();
  ASSERT_EQ(sources.size(), 4u);
  EXPECT_EQ(fs::path(sources[2]).filename(), "a.jpg");
  EXPECT_EQ(fs::path(sources[3]).filename(), "b.jpg");
  EXPECT_EQ(s.layers[4].dense, Path("dense.ply"));
  EXPECT_EQ(s.layers[5].workspace, Path("ws"));
  // Defaults where the file says nothing.
  EXPECT_DOUBLE_EQ(s.layers[4].opacity, 1.0);
  EXPECT_EQ(s.layers[4].stereo.iterations, photogrammetry::PatchMatchOptions().iterations);
  EXPECT_DOUBLE_EQ(s.layers[4].stereo.resolution_scale, 1.0);

  ASSERT_EQ(s.views.size(), 2u);
  EXPECT_EQ(s.views[0].camera_file, Path("view.json"));
  EXPECT_TRUE(s.views[0].opaque);
  ASSERT_TRUE(s.views[1].camera.has_value());
  EXPECT_EQ(s.views[1].layers, (std::vector<std::string>{"scan", "reliefs"}));
  // Focus: highlighted layers at focus_opacity, others dimmed; overrides win.
  EXPECT_DOUBLE_EQ(ViewOpacity(s.views[1], r), 0.8);
  EXPECT_DOUBLE_EQ(ViewOpacity(s.views[1], f), 0.3);
  EXPECT_DOUBLE_EQ(ViewOpacity(s.views[1], scan), 0.1);
  EXPECT_DOUBLE_EQ(ViewOpacity(s.views[0], scan), 0.25);
  EXPECT_EQ(s.views[1].point_size, 3.0);
}

// The licence and labelled points a published page shows (survey coordinates: mm at 10^6 m).
TEST_F(SceneFile, LicenceAndAnnotations) {
  json j = Minimal();
  j["views"] = json::array({{{"name", "front"}}});
  j["licence"] = "CC BY 4.0, Balai Konservasi Borobudur";
  j["annotations"] = json::array({{{"title", "Panel 1"},
                                   {"text", "hidden foot"},
                                   {"position", {416000.001, 9168000.002, 265.5}},
                                   {"view", "front"}},
                                  {{"title", "Stair"},
                                   {"position", {1, 2, 3}},
                                   {"view", {{"eye", {0, -5, 1}}, {"target", {0, 0, 0}}}}},
                                  {{"title", "Bare"}, {"position", {0, 0, 0}}}});
  const Scene s = Load(j);
  EXPECT_EQ(s.licence, "CC BY 4.0, Balai Konservasi Borobudur");
  ASSERT_EQ(s.annotations.size(), 3u);
  EXPECT_EQ(s.annotations[0].position, Eigen::Vector3d(416000.001, 9168000.002, 265.5));
  EXPECT_EQ(s.annotations[0].view, "front");
  EXPECT_EQ(s.annotations[0].text, "hidden foot");
  ASSERT_TRUE(s.annotations[1].camera.has_value());
  EXPECT_TRUE(s.annotations[2].view.empty() && !s.annotations[2].camera);

  json bad = j;
  bad["annotations"][0].erase("title");
  ExpectError(bad, "/annotations/0", "missing key \"title\"");
  bad = j;
  bad["annotations"][0]["title"] = "";
  ExpectError(bad, "/annotations/0/title", "1-200 characters");
  bad = j;
  bad["annotations"][0]["view"] = "back";
  ExpectError(bad, "/annotations/0/view", "no view named \"back\"");
  bad = j;
  bad["annotations"][1]["view"] = {{"eye", {0, 0, 0}}, {"fov", 3}};
  ExpectError(bad, "/annotations/1/view", "not a camera");
  bad = j;
  bad["annotations"][2]["position"] = {1, 2};
  ExpectError(bad, "/annotations/2/position", "three numbers");
  bad = j;
  bad["annotations"][2]["colour"] = 1;
  ExpectError(bad, "/annotations/2/colour", "unknown key");
  bad = j;
  bad["licence"] = 4;
  ExpectError(bad, "/licence", "expected a string");
}

TEST_F(SceneFile, DefaultsOfAMinimalScene) {
  const Scene s = Load(Minimal(), "my_site.json");
  EXPECT_EQ(s.name, "my_site");  // the file's stem
  EXPECT_FALSE(s.origin.has_value());
  EXPECT_EQ(s.seed, 1u);
  EXPECT_EQ(s.render.spbr.repeat_level, 100);
  EXPECT_TRUE(s.render.brightness.automatic());
  EXPECT_EQ(s.render.background, (Rgb8{255, 255, 255}));  // a scene's default
  EXPECT_EQ(s.render.spbr.seed, s.seed);
  EXPECT_TRUE(s.views.empty());
  EXPECT_EQ(LayerKindName(s.layers[0].kind), "points");
  EXPECT_EQ(s.path, fs::absolute(dir_.File("my_site.json")).lexically_normal().string());
}

TEST_F(SceneFile, NotJson) {
  EXPECT_NE(ErrorOfText("{\"candi_scene\": 1,").find("not valid JSON"), std::string::npos);
  EXPECT_NE(ErrorOfText("{\"candi_scene\": 1e999}").find("not valid JSON"), std::string::npos);
  EXPECT_THROW(LoadScene(dir_.File("missing.json")), InputError);
}

TEST_F(SceneFile, TopLevelErrors) {
  json j = Minimal();
  j.erase("candi_scene");
  ExpectError(j, "/", "missing key \"candi_scene\"");
  j = Minimal();
  j["candi_scene"] = 2;
  ExpectError(j, "/candi_scene", "this candi reads scene version 1");
  j["candi_scene"] = 1.5;
  ExpectError(j, "/candi_scene", "expected an integer");
  j = Minimal();
  j["colour"] = 1;
  ExpectError(j, "/colour", "unknown key");
  ExpectError(json::array(), "/", "expected an object");
  j = Minimal();
  j["origin"] = "centre";
  ExpectError(j, "/origin", "expected [E, N, H] or \"auto\"");
  j["origin"] = {1, 2};
  ExpectError(j, "/origin", "expected an array of three numbers");
  j = Minimal();
  j["seed"] = -1;
  ExpectError(j, "/seed", "out of range");
  j = Minimal();
  j["crs"] = "NOT_A_CRS";
  ExpectError(j, "/crs", "PROJ");
  j = Minimal();
  j.erase("layers");
  ExpectError(j, "/", "missing key \"layers\"");
  j["layers"] = json::array();
  ExpectError(j, "/layers", "no layers");
  j["layers"] = "scan";
  ExpectError(j, "/layers", "expected an array");
}

TEST_F(SceneFile, RenderErrors) {
  json j = Minimal();
  j["render"] = {{"repeat_level", 0}};
  ExpectError(j, "/render/repeat_level", "out of range: 0 is not in [1, 100000]");
  j["render"] = {{"width", 20000}};
  ExpectError(j, "/render/width", "out of range");
  j["render"] = {{"background", {0, 0, 256}}};
  ExpectError(j, "/render/background/2", "out of range");
  j["render"] = {{"background", {0, 0}}};
  ExpectError(j, "/render/background", "expected [r, g, b]");
  j["render"] = {{"brightness", "bright"}};
  ExpectError(j, "/render/brightness", "expected auto, none or a gain in (0, 100]");
  j["render"] = {{"brightness", -1}};
  ExpectError(j, "/render/brightness", "out of range");
  // One range for a gain everywhere (the command line's, the viewer's): (0, 100].
  j["render"] = {{"brightness", 0}};
  ExpectError(j, "/render/brightness", "out of range: 0 is not in (0, 100]");
  j["render"] = {{"brightness", 500}};
  ExpectError(j, "/render/brightness", "out of range: 500 is not in (0, 100]");
  j["render"] = {{"gamma", 2}};
  ExpectError(j, "/render/gamma", "unknown key");
}

TEST_F(SceneFile, LayerErrors) {
  auto with = [](const json& layer) {
    json j = Minimal();
    j["layers"] = json::array({layer});
    return j;
  };
  const json scan = Minimal()["layers"][0];
  ExpectError(with("scan"), "/layers/0", "expected an object");
  json l = scan;
  l.erase("name");
  ExpectError(with(l), "/layers/0", "missing key \"name\"");
  l = scan;
  l.erase("kind");
  ExpectError(with(l), "/layers/0", "missing key \"kind\"");
  l = scan;
  l["name"] = "a b";
  ExpectError(with(l), "/layers/0/name", "a layer name is 1-64 characters");
  l["name"] = std::string(65, 'a');
  ExpectError(with(l), "/layers/0/name", "a layer name is 1-64 characters");
  l = scan;
  l["kind"] = "mesh";
  ExpectError(with(l), "/layers/0/kind", "unknown kind \"mesh\"");
  l = scan;
  l["dxf"] = "drawing.dxf";
  ExpectError(with(l), "/layers/0/dxf", "unknown key");
  l = scan;
  l.erase("file");
  ExpectError(with(l), "/layers/0", "a points layer needs \"file\"");
  l = scan;
  l["file"] = "nowhere.ply";
  ExpectError(with(l), "/layers/0/file", "no such file");
  l["file"] = "";
  ExpectError(with(l), "/layers/0/file", "empty path");
  l["file"] = "ws";
  ExpectError(with(l), "/layers/0/file", "a folder, expected a file");
  l["file"] = 3;
  ExpectError(with(l), "/layers/0/file", "expected a string");
  l = scan;
  l["opacity"] = 0;
  ExpectError(with(l), "/layers/0/opacity", "out of range: 0 is not in (0, 1]");
  l["opacity"] = "half";
  ExpectError(with(l), "/layers/0/opacity", "expected a number");
  l = scan;
  l["highlight"] = 1;
  ExpectError(with(l), "/layers/0/highlight", "expected true or false");
  l = scan;
  l["color"] = {1, 2, 3.5};
  ExpectError(with(l), "/layers/0/color/2", "expected an integer");
  l = scan;
  l["crs"] = "scene";
  ExpectError(with(l), "/layers/0/crs", "\"scene\" needs the scene's \"crs\"");
  l = scan;
  l["replace_voxel"] = 0.5;
  ExpectError(with(l), "/layers/0/replace_voxel", "only with \"replaces\"");
  l = scan;
  l["replaces"] = {"scan"};
  ExpectError(with(l), "/layers/0/replaces/0", "a layer cannot replace itself");
  l["replaces"] = {"other"};
  ExpectError(with(l), "/layers/0/replaces/0", "no layer named \"other\"");
  json two = Minimal();
  two["layers"].push_back(scan);
  ExpectError(two, "/layers/1/name", "layer name \"scan\" repeats");
}

TEST_F(SceneFile, TransformErrors) {
  json j = Minimal();
  j["layers"][0]["world_from_layer"] = {{"matrix", {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}}};
  ExpectError(j, "/layers/0/world_from_layer/matrix", "expected 4 rows");
  j["layers"][0]["world_from_layer"] = {{"matrix", {{1, 0, 0, 0}, {0, 1, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}}};
  ExpectError(j, "/layers/0/world_from_layer/matrix/1", "expected 4 numbers");
  j["layers"][0]["world_from_layer"] = {{"matrix", {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 1, 1}}}};
  ExpectError(j, "/layers/0/world_from_layer/matrix/3", "the last row must be 0 0 0 1");
  j["layers"][0]["world_from_layer"] = {{"matrix", {{1, 0, 0, 0}, {0, 2, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}}};
  ExpectError(j, "/layers/0/world_from_layer/matrix", "not a similarity transform");
  j["layers"][0]["world_from_layer"] = {{"scale", 0}};
  ExpectError(j, "/layers/0/world_from_layer/scale", "out of range");
  j["layers"][0]["world_from_layer"] = {{"shear", 1}};
  ExpectError(j, "/layers/0/world_from_layer/shear", "unknown key");
  j["layers"][0]["world_from_layer"] = {{"translation", {1, 2, NAN}}};  // JSON null
  ExpectError(j, "/layers/0/world_from_layer/translation/2", "expected a number");
  // A matrix that is a similarity: read as one.
  j["layers"][0]["world_from_layer"] = {{"matrix", {{0, -2, 0, 5}, {2, 0, 0, 6}, {0, 0, 2, 7}, {0, 0, 0, 1}}}};
  const Scene s = Load(j);
  EXPECT_NEAR(s.layers[0].world_from_layer.scale, 2.0, 1e-12);
}

TEST_F(SceneFile, FoundationErrors) {
  json j = Minimal();
  j["layers"][0] = {{"name", "f"}, {"kind", "foundation"}, {"dxf", "drawing.dxf"}};
  // candi foundation's defaults, at the scene's default density.
  EXPECT_EQ(Load(j).layers[0].foundation.surface.profile.samples_per_side,
            mesh::ProfileOptions().samples_per_side);
  EXPECT_EQ(Load(j).layers[0].foundation.sample.density, kDefaultFoundationDensity);
  json l = j;
  l["layers"][0].erase("dxf");
  ExpectError(l, "/layers/0", "a foundation layer needs \"dxf\"");
  l = j;
  l["layers"][0]["samples_per_side"] = 1;
  ExpectError(l, "/layers/0/samples_per_side", "out of range");
  l = j;
  l["layers"][0]["angular_steps"] = 1;
  ExpectError(l, "/layers/0/angular_steps", "out of range");
  l = j;
  l["layers"][0]["density"] = 10;
  l["layers"][0]["count"] = 10;
  ExpectError(l, "/layers/0/count", "give one of \"density\" and \"count\"");
  l = j;
  l["layers"][0]["density"] = 0;
  ExpectError(l, "/layers/0/density", "out of range");
  l = j;
  l["layers"][0]["mode"] = "twist";
  ExpectError(l, "/layers/0/mode", "expected auto, blend or sweep");
  l = j;
  l["layers"][0]["sections"] = {"A", 2};
  ExpectError(l, "/layers/0/sections/1", "expected a string");
}

TEST_F(SceneFile, ReliefErrors) {
  json j = Minimal();
  j["layers"][0] = {{"name", "r"}, {"kind", "relief"}, {"placement", "walls.csv"},
                    {"panels", {{{"id", "P02"}, {"points", "p02.ply"}}}}};
  EXPECT_TRUE(Load(j).layers[0].model.empty());  // panels given by points need no model
  json l = j;
  l["layers"][0]["panels"] = json::array();
  ExpectError(l, "/layers/0/panels", "no panels");
  l = j;
  l["layers"][0]["panels"][0].erase("id");
  ExpectError(l, "/layers/0/panels/0", "missing key \"id\"");
  l = j;
  l["layers"][0]["panels"][0]["id"] = "P/2";
  ExpectError(l, "/layers/0/panels/0/id", "a panel id is 1-64 characters");
  l = j;
  l["layers"][0]["panels"].push_back({{"id", "P02"}, {"points", "p02.ply"}});
  ExpectError(l, "/layers/0/panels/1/id", "panel id \"P02\" repeats");
  l = j;
  l["layers"][0]["panels"][0]["photo"] = "p01.png";
  ExpectError(l, "/layers/0/panels/0", "give exactly one of \"photo\" and \"points\"");
  l = j;
  l["layers"][0]["panels"][0]["native_resolution"] = true;
  ExpectError(l, "/layers/0/panels/0/native_resolution", "only for panels given by a photo");
  l = j;
  l["layers"][0]["panels"][0]["depth"] = "d.png";
  ExpectError(l, "/layers/0/panels/0/depth", "unknown key");
  l = j;
  l["layers"][0]["panels"][0] = {{"id", "P01"}, {"photo", "p01.png"}};
  ExpectError(l, "/layers/0", "a relief layer needs \"model\"");
  l = j;
  l["layers"][0].erase("placement");
  ExpectError(l, "/layers/0", "a relief layer needs \"placement\"");
  l = j;
  l["layers"][0]["width_m"] = -1;
  ExpectError(l, "/layers/0/width_m", "out of range");
}

TEST_F(SceneFile, PhotogrammetryErrors) {
  json j = Minimal();
  j["layers"][0] = {{"name", "c"}, {"kind", "photogrammetry"}, {"dense", "dense.ply"}};
  json l = j;
  l["layers"][0]["workspace"] = "ws";
  ExpectError(l, "/layers/0", "needs exactly one of \"dense\", \"workspace\" and \"images\"");
  l = j;
  l["layers"][0].erase("dense");
  ExpectError(l, "/layers/0", "needs exactly one of \"dense\", \"workspace\" and \"images\"");
  l = j;
  l["layers"][0].erase("dense");
  l["layers"][0]["workspace"] = "scan.ply";
  ExpectError(l, "/layers/0/workspace", "not a folder");
  l["layers"][0]["workspace"] = "nowhere";
  ExpectError(l, "/layers/0/workspace", "no such folder");
  l = j;
  l["layers"][0]["targets_crs"] = "EPSG:4979";
  ExpectError(l, "/layers/0/targets_crs", "only with \"targets\"");
  l = j;
  l["layers"][0]["targets"] = "targets.csv";
  l["layers"][0]["targets_crs"] = "EPSG:4979";
  ExpectError(l, "/layers/0/targets_crs", "needs the scene's \"crs\"");
  l = j;
  l["layers"][0]["picks"] = "picks.csv";
  ExpectError(l, "/layers/0/picks", "picks need \"targets\"");
  l["layers"][0]["targets"] = "targets.csv";
  ExpectError(l, "/layers/0/picks", "picks need the cameras");
  l = j;
  l["layers"][0]["max_features"] = 2000;
  ExpectError(l, "/layers/0/max_features", "only with \"images\"");
  l = j;
  l["layers"][0]["iterations"] = 2;
  ExpectError(l, "/layers/0/iterations", "dense stereo options need \"images\" or \"workspace\"");
  l = j;
  l["layers"][0].erase("dense");
  l["layers"][0]["images"] = "photos";
  l["layers"][0]["max_image_size"] = 10;
  ExpectError(l, "/layers/0/max_image_size", "out of range");
  l["layers"][0].erase("max_image_size");
  l["layers"][0]["resolution_scale"] = 1.5;
  ExpectError(l, "/layers/0/resolution_scale", "out of range");
}

// A campaign as a photogrammetry layer: the sessions mapped apart and tied by the targets and
// picks (SfmOptions::chunks), the matching and the priors of candi sfm.
TEST_F(SceneFile, ACampaignLayerMapsInChunks) {
  WriteBytes(dir_.File("priors.csv"), "name,E,N,H\n");
  json j = Minimal();
  j["layers"][0] = {{"name", "temple"}, {"kind", "photogrammetry"}, {"images", "photos"}, {"targets", "targets.csv"},
                    {"picks", "picks.csv"}, {"chunks", true}, {"matching", "retrieval"}, {"priors", "priors.csv"}};
  const Scene s = Load(j);
  const photogrammetry::SfmOptions& sfm = s.layers[0].sfm;
  EXPECT_EQ(sfm.chunks.targets, Path("targets.csv"));
  EXPECT_EQ(sfm.chunks.picks, Path("picks.csv"));
  EXPECT_EQ(sfm.pairs.strategy, photogrammetry::PairStrategy::kRetrieval);
  EXPECT_EQ(sfm.priors, Path("priors.csv"));
  j["layers"][0]["chunks"] = false;
  EXPECT_TRUE(Load(j).layers[0].sfm.chunks.targets.empty()) << "one piece, georeferenced afterwards";
  json l = j;
  l["layers"][0]["chunks"] = true;
  l["layers"][0].erase("picks");
  ExpectError(l, "/layers/0/chunks", "ties them by \"targets\" and their \"picks\"");
  l = j;
  l["crs"] = "EPSG:32749";
  l["layers"][0]["chunks"] = true;
  l["layers"][0]["targets_crs"] = "EPSG:4979";
  ExpectError(l, "/layers/0/targets_crs", "not with \"chunks\"");
  l = j;
  l["layers"][0]["matching"] = "vocab";
  ExpectError(l, "/layers/0/matching", "auto, exhaustive, sequential, retrieval or positional");
  l = j;
  l["layers"][0].erase("images");
  l["layers"][0].erase("picks");
  l["layers"][0]["dense"] = "dense.ply";
  ExpectError(l, "/layers/0/chunks", "only with \"images\"");
}

TEST_F(SceneFile, ViewErrors) {
  json j = Minimal();
  auto view = [&](const json& v) {
    json s = j;
    s["views"] = json::array({v});
    return s;
  };
  ExpectError(view({{"camera", "view.json"}}), "/views/0", "missing key \"name\"");
  ExpectError(view({{"name", "a/b"}}), "/views/0/name", "a view name is 1-64 characters");
  ExpectError(view({{"name", "v"}, {"camera", 3}}), "/views/0/camera", "expected a view file or an inline view");
  ExpectError(view({{"name", "v"}, {"camera", "nowhere.json"}}), "/views/0/camera", "no such file");
  ExpectError(view({{"name", "v"}, {"layers", {"scan", "other"}}}), "/views/0/layers/1", "no layer named \"other\"");
  ExpectError(view({{"name", "v"}, {"layers", {"scan", "scan"}}}), "/views/0/layers/1", "is listed twice");
  ExpectError(view({{"name", "v"}, {"layers", json::array()}}), "/views/0/layers", "no layers");
  ExpectError(view({{"name", "v"}, {"opacity", 0.5}}), "/views/0/opacity", "expected an object of layer name");
  ExpectError(view({{"name", "v"}, {"opacity", {{"other", 0.5}}}}), "/views/0/opacity/other", "no layer named");
  ExpectError(view({{"name", "v"}, {"opacity", {{"scan", 2}}}}), "/views/0/opacity/scan", "out of range");
  ExpectError(view({{"name", "v"}, {"point_size", 40}}), "/views/0/point_size", "out of range");
  ExpectError(view({{"name", "v"}, {"dim", 0}}), "/views/0/dim", "out of range");
  ExpectError(view({{"name", "v"}, {"fov", 40}}), "/views/0/fov", "unknown key");
  json two = j;
  two["views"] = json::array({{{"name", "v"}}, {{"name", "v"}}});
  ExpectError(two, "/views/1/name", "view name \"v\" repeats");
}

// Two point layers to compare, and a mesh file.
json WithComparisons(const json& comparisons) {
  json j = {{"candi_scene", 1}, {"comparisons", comparisons}};
  j["layers"] = json::array({{{"name", "scan"}, {"kind", "points"}, {"file", "scan.ply"}},
                             {{"name", "dense"}, {"kind", "points"}, {"file", "dense.ply"}}});
  return j;
}

TEST_F(SceneFile, ComparisonsAndTheirDefaults) {
  WriteBytes(dir_.File("wall.obj"), "x");
  const Scene s = Load(WithComparisons(json::array(
      {{{"name", "dense_vs_scan"}, {"compared", "dense"}, {"reference", "scan"}},
       {{"name", "to_mesh"}, {"compared", "scan"}, {"reference", "wall.obj"}, {"method", "c2m"}, {"unsigned", true},
        {"tolerance", 0.005}, {"bins", 20}, {"range", 0.1}},
       {{"name", "m3c2"}, {"compared", "scan"}, {"reference", "dense"}, {"method", "m3c2"}, {"normal_scale", 0.4},
        {"projection_scale", 0.2}, {"max_depth", 1}, {"registration_error", 0.003}, {"min_points", 5},
        {"orientation", "out"}},
       {{"name", "quadric"}, {"compared", "scan"}, {"reference", "dense.ply"}, {"model", "quadric"},
        {"model_neighbours", 20}}})));
  ASSERT_EQ(s.comparisons.size(), 4u);
  const SceneComparison& plain = s.comparisons[0];
  EXPECT_EQ(plain.name, "dense_vs_scan");
  EXPECT_EQ(plain.compared, "dense");
  EXPECT_EQ(plain.reference_layer, "scan");
  EXPECT_TRUE(plain.reference_file.empty());
  EXPECT_EQ(plain.deviation.method, compare::Method::kC2C);  // candi compare's defaults
  EXPECT_EQ(plain.deviation.c2c.local_model, compare::LocalModel::kNone);
  EXPECT_DOUBLE_EQ(plain.summary.tolerance, 0.01);
  const SceneComparison& mesh = s.comparisons[1];
  EXPECT_EQ(mesh.reference_file, Path("wall.obj"));
  EXPECT_TRUE(mesh.reference_layer.empty());
  EXPECT_EQ(mesh.deviation.method, compare::Method::kC2M);
  EXPECT_FALSE(mesh.deviation.c2m.signed_distance);
  EXPECT_DOUBLE_EQ(mesh.summary.tolerance, 0.005);
  EXPECT_EQ(mesh.summary.bins, 20);
  EXPECT_DOUBLE_EQ(mesh.summary.range, 0.1);
  const compare::M3c2Options& m = s.comparisons[2].deviation.m3c2;
  EXPECT_DOUBLE_EQ(m.normal_scale, 0.4);
  EXPECT_DOUBLE_EQ(m.projection_scale, 0.2);
  EXPECT_DOUBLE_EQ(m.max_depth, 1);
  EXPECT_DOUBLE_EQ(m.registration_error, 0.003);
  EXPECT_EQ(m.min_points, 5);
  EXPECT_EQ(m.orientation, compare::NormalOrientation::kOutward);
  const SceneComparison& q = s.comparisons[3];
  EXPECT_EQ(q.reference_file, Path("dense.ply"));  // not a layer's name: a file
  EXPECT_EQ(q.deviation.c2c.local_model, compare::LocalModel::kQuadric);
  EXPECT_EQ(q.deviation.c2c.model_neighbours, 20);
  EXPECT_TRUE(Load(Minimal()).comparisons.empty());
}

TEST_F(SceneFile, ComparisonErrors) {
  const json ok = {{"name", "c"}, {"compared", "dense"}, {"reference", "scan"}};
  auto with = [&](const json& changes) {
    json c = ok;
    for (auto it = changes.begin(); it != changes.end(); ++it) {
      if (it.value().is_null()) c.erase(it.key());
      else c[it.key()] = it.value();
    }
    return WithComparisons(json::array({c}));
  };
  ExpectError(WithComparisons(3), "/comparisons", "expected an array");
  ExpectError(WithComparisons(json::array({3})), "/comparisons/0", "expected an object");
  ExpectError(with({{"colour", 1}}), "/comparisons/0/colour", "unknown key");
  ExpectError(with({{"name", nullptr}}), "/comparisons/0", "missing key \"name\"");
  ExpectError(with({{"compared", nullptr}}), "/comparisons/0", "missing key \"compared\"");
  ExpectError(with({{"reference", nullptr}}), "/comparisons/0", "missing key \"reference\"");
  ExpectError(with({{"name", "a b"}}), "/comparisons/0/name", "a comparison name is 1-64 characters");
  ExpectError(with({{"compared", "x"}}), "/comparisons/0/compared", "no layer named \"x\"");
  ExpectError(with({{"reference", "x"}}), "/comparisons/0/reference",
              "no layer named \"x\" and no such file: " + Path("x"));
  ExpectError(with({{"reference", "dense"}}), "/comparisons/0/reference", "layer \"dense\" compared to itself");
  ExpectError(with({{"method", "hausdorff"}}), "/comparisons/0/method", "must be c2c, c2m or m3c2");
  ExpectError(with({{"method", "c2m"}}), "/comparisons/0/reference", "c2m compares to a mesh: give a mesh file");
  ExpectError(with({{"method", "c2m"}, {"reference", "targets.csv"}}), "/comparisons/0/reference",
              "c2m compares to a mesh: PLY or OBJ");
  ExpectError(with({{"normal_scale", 0.2}}), "/comparisons/0/normal_scale", "only with \"method\": \"m3c2\"");
  ExpectError(with({{"method", "m3c2"}, {"model", "plane"}}), "/comparisons/0/model",
              "only with \"method\": \"c2c\"");
  ExpectError(with({{"unsigned", true}}), "/comparisons/0/unsigned", "only with \"method\": \"c2m\"");
  ExpectError(with({{"model", "cubic"}}), "/comparisons/0/model", "must be none, plane or quadric");
  ExpectError(with({{"model", "quadric"}, {"model_neighbours", 4}}), "/comparisons/0", "model_neighbours");
  ExpectError(with({{"model_neighbours", 2}}), "/comparisons/0/model_neighbours", "out of range");
  ExpectError(with({{"method", "m3c2"}, {"orientation", "up"}}), "/comparisons/0/orientation", "must be +x");
  ExpectError(with({{"method", "m3c2"}, {"max_depth", -1}}), "/comparisons/0/max_depth", "out of range");
  ExpectError(with({{"tolerance", -0.01}}), "/comparisons/0/tolerance", "out of range");
  ExpectError(with({{"bins", 0}}), "/comparisons/0/bins", "out of range");
  json two = WithComparisons(json::array({ok, ok}));
  ExpectError(two, "/comparisons/1/name", "comparison name \"c\" repeats");
}

}  // namespace
}  // namespace candi::pipeline
