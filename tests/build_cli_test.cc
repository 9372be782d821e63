// End-to-end tests of `candi build SCENE -o ARCHIVE`: outputs, provenance, survey-scale frames,
// and the scene file's errors (each names the JSON path of the culprit).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "compare/deviation.h"
#include "core/sha256.h"
#include "io/image/png_io.h"
#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

using nlohmann::json;
using Result = CommandResult;

// A 4 m x 2 m wall of points at survey coordinates, 1 cm grid, with millimetre offsets that float
// would lose (E 416000.xxx).
void WriteSurveyWall(const std::string& path) {
  PointCloud c;
  c.schema.colors = true;
  c.SetSchema(c.schema);
  c.frame.origin = Eigen::Vector3d(416000, 9168000, 250);
  for (int i = 0; i < 400; ++i)
    for (int j = 0; j < 200; ++j) {
      c.positions.emplace_back(0.01 * i + 0.0007, 5.0, 0.01 * j);
      c.colors.push_back({200, 60, 40});
    }
  io::WritePointCloud(path, c);
}

json BaseScene() {
  json scene = json::parse(R"({
    "candi_scene": 1,
    "name": "test",
    "seed": 7,
    "render": {"repeat_level": 8, "width": 96, "height": 64, "background": [255, 255, 255]},
    "views": [{"name": "all"}, {"name": "opaque", "opaque": true},
              {"name": "focus", "focus": true, "layers": ["wall", "hill"]}],
    "layers": [
      {"name": "wall", "kind": "points", "file": "wall.ply", "opacity": 0.6, "highlight": true},
      {"name": "hill", "kind": "foundation", "dxf": "FOUNDATION", "sections": ["D"],
       "samples_per_side": 40, "angular_steps": 12, "count": 3000, "color": [0, 160, 0],
       "opacity": 0.3,
       "world_from_layer": {"scale": 0.001, "translation": [416002, 9168010, 240]}}
    ]})");
  scene["layers"][1]["dxf"] = std::filesystem::absolute("examples/borobudur/foundation.dxf").string();
  return scene;
}

void WriteScene(const std::string& path, const json& scene) { testing::WriteBytes(path, scene.dump(2)); }

TEST(BuildCli, TwoLayerSceneGivesLayersArchiveRendersProvenanceAndMeshlab) {
  TempDir dir;
  WriteSurveyWall(dir.File("wall.ply"));
  WriteScene(dir.File("scene.json"), BaseScene());
  const Result r = RunCandi("build " + dir.File("scene.json") + " -o " + dir.File("out"));
  ASSERT_EQ(r.code, 0) << r.output;

  // Layers: the wall keeps its millimetres at survey coordinates; the hill has its exact count.
  const PointCloud wall = io::ReadPointCloud(dir.File("out/layers/wall.ply"));
  ASSERT_EQ(wall.size(), 80000u);
  const Eigen::Vector3d first = wall.frame.ToWorld(wall.positions[0]);
  EXPECT_NEAR(first.x(), 416000.0007, 1e-6);
  EXPECT_NEAR(first.y(), 9168005.0, 1e-6);
  EXPECT_EQ(wall.colors[0], (Rgb8{200, 60, 40}));
  ASSERT_NE(wall.FindScalar("scene_layer"), nullptr);
  ASSERT_NE(wall.FindScalar("quality"), nullptr);
  const PointCloud hill = io::ReadPointCloud(dir.File("out/layers/hill.ply"));
  ASSERT_EQ(hill.size(), 3000u);
  EXPECT_EQ(hill.colors[17], (Rgb8{0, 160, 0}));
  EXPECT_EQ(hill.FindScalar("scene_layer")->Get(5), 1.0);
  for (size_t i = 0; i < hill.size(); i += 97) {  // the drawing (mm) placed near the wall, in metres
    const Eigen::Vector3d w = hill.frame.ToWorld(hill.positions[i]);
    EXPECT_NEAR(w.x(), 416002, 200);
    EXPECT_NEAR(w.y(), 9168010, 200);
  }

  // Renders: three PNGs of the scene's size; the opaque one differs from the transparent one.
  for (const char* v : {"all", "opaque", "focus"}) {
    const io::PngImage png = io::ReadPng(dir.File(std::string("out/renders/") + v + ".png"));
    EXPECT_EQ(png.image8.width(), 96);
    EXPECT_EQ(png.image8.height(), 64);
    EXPECT_TRUE(FileExists(dir.File(std::string("out/renders/") + v + ".view.json")));
  }
  EXPECT_FALSE(io::ReadPng(dir.File("out/renders/all.png")).image8 == io::ReadPng(dir.File("out/renders/opaque.png")).image8);

  // Provenance: sources with their hashes, methods, counts, the frame; scanned vs reconstructed.
  const json a = json::parse(testing::ReadBytes(dir.File("out/archive.json")));
  EXPECT_EQ(a["points"], 83000);
  EXPECT_EQ(a["seed"], 7);
  ASSERT_EQ(a["layers"].size(), 2u);
  EXPECT_EQ(a["layers"][0]["sources"][0]["sha256"], Sha256OfFile(dir.File("wall.ply")));
  EXPECT_EQ(a["layers"][0]["scanned"], true);
  EXPECT_EQ(a["layers"][1]["scanned"], false);
  EXPECT_EQ(a["layers"][1]["sources"][0]["sha256"], Sha256OfFile("examples/borobudur/foundation.dxf"));
  EXPECT_EQ(a["scene"]["sha256"], Sha256OfFile(dir.File("scene.json")));
  EXPECT_GT(a["frame"]["origin"][0].get<double>(), 4e5);  // survey coordinates: a shift was chosen
  // The focus view: the highlighted wall at 0.95, the hill dimmed to 0.3 x 0.5.
  EXPECT_DOUBLE_EQ(a["views"][2]["opacity"]["wall"].get<double>(), 0.95);
  EXPECT_DOUBLE_EQ(a["views"][2]["opacity"]["hill"].get<double>(), 0.15);

  // The archive and the MeshLab project (local float coordinates, shift beside them).
  EXPECT_TRUE(FileExists(dir.File("out/archive/archive.json")) || std::filesystem::is_directory(dir.File("out/archive")));
  const std::string mlp = testing::ReadBytes(dir.File("out/meshlab/scene.mlp"));
  EXPECT_NE(mlp.find("filename=\"wall.ply\""), std::string::npos);
  EXPECT_NE(mlp.find("filename=\"hill.ply\""), std::string::npos);
  const PointCloud local = io::ReadPointCloud(dir.File("out/meshlab/wall.ply"));
  EXPECT_TRUE(local.frame.IsIdentity());
  EXPECT_LT(local.positions[0].cwiseAbs().maxCoeff(), 1e4);
  EXPECT_NE(testing::ReadBytes(dir.File("out/meshlab/shift.txt")).find("416000"), std::string::npos);

  // Same scene, same seed: the same bytes.
  const Result again = RunCandi("build " + dir.File("scene.json") + " -o " + dir.File("out2"));
  ASSERT_EQ(again.code, 0) << again.output;
  EXPECT_EQ(testing::ReadBytes(dir.File("out/layers/hill.ply")), testing::ReadBytes(dir.File("out2/layers/hill.ply")));
  EXPECT_TRUE(io::ReadPng(dir.File("out/renders/all.png")).image8 == io::ReadPng(dir.File("out2/renders/all.png")).image8);
}

// The campaign issue end to end: `candi campaign`'s 60 photos in three sessions as a scene's
// photogrammetry layer mapped in chunks, tied by the targets and adjusted as one, then dense
// stereo: the layer's points are in the survey frame, on the true surface.
TEST(BuildCli, ACampaignLayerMappedInChunksLandsOnTheTrueSurfaceInTheSurveyFrame) {
  if (!OnPath("colmap")) GTEST_SKIP() << "COLMAP is not installed (scripts/deps.sh installs it)";
  TempDir dir;
  const std::string site = dir.File("site");
  const Result made = RunCandi("-q campaign " + site + " --photos 60 --size 320 --chunks 3");
  ASSERT_EQ(made.code, 0) << made.output;
  json scene = json::parse(R"({"candi_scene": 1, "name": "campaign", "seed": 5,
    "render": {"repeat_level": 2, "width": 64, "height": 48},
    "layers": [{"name": "walls", "kind": "photogrammetry", "chunks": true, "resolution_scale": 0.5}]})");
  scene["layers"][0]["images"] = site;
  scene["layers"][0]["targets"] = site + "/targets.csv";
  scene["layers"][0]["picks"] = site + "/picks.csv";
  WriteScene(dir.File("scene.json"), scene);
  const Result r = RunCandi("-q build " + dir.File("scene.json") + " -o " + dir.File("out"));
  ASSERT_EQ(r.code, 0) << r.output;
  const PointCloud walls = io::ReadPointCloud(dir.File("out/layers/walls.ply"));
  ASSERT_GT(walls.size(), 5000u);
  EXPECT_NEAR(walls.frame.ToWorld(walls.positions[0]).x(), 410000, 100);  // survey coordinates
  const PointCloud truth = io::ReadPointCloud(site + "/truth/surface.ply");
  const compare::DeviationResult d =
      compare::CompareToCloud(compare::DeviationOptions{}, truth, walls, "truth", "walls");
  std::vector<double> distance;
  for (double v : d.distance)
    if (std::isfinite(v)) distance.push_back(std::abs(v));
  ASSERT_GT(distance.size(), walls.size() / 2);
  std::sort(distance.begin(), distance.end());
  const double median = distance[distance.size() / 2], p90 = distance[distance.size() * 9 / 10];
  std::printf("%zu dense points against the true surface: median %.1f mm, 90%% %.1f mm\n", walls.size(),
              1e3 * median, 1e3 * p90);
  // Measured 5.0 and 9.2 mm (160 x 120 px depth maps: 14 mm pixels on the wall).
  EXPECT_LT(median, 0.01);
  EXPECT_LT(p90, 0.02);
  const json a = json::parse(testing::ReadBytes(dir.File("out/archive.json")));
  const json& chunks = a["layers"][0]["parameters"]["sfm"]["chunks"];
  ASSERT_EQ(chunks.size(), 3u) << a["layers"][0].dump(2);
  for (const json& c : chunks) EXPECT_TRUE(c["tied"].get<bool>()) << c.dump();
  const json& joint = a["layers"][0]["parameters"]["sfm"]["joint_adjustment"];
  EXPECT_TRUE(joint["ran"].get<bool>()) << joint.dump();
  EXPECT_LT(joint["check_rmse_m"].get<double>(), 0.01) << joint.dump();
}

// Builds the scene {wall.ply (written by the caller), `name` replacing it} and returns its
// archive.json (an empty object, after a test failure, when the build fails).
json BuildWallReplacedBy(const TempDir& dir, const std::string& name, const PointCloud& cloud) {
  io::WritePointCloud(dir.File(name + ".ply"), cloud);
  json scene = json::parse(R"({"candi_scene": 1, "seed": 3,
    "render": {"repeat_level": 4, "width": 64, "height": 48},
    "layers": [{"name": "wall", "kind": "points", "file": "wall.ply"}]})");
  scene["layers"].push_back({{"name", name}, {"kind", "points"}, {"file", name + ".ply"}, {"replaces", {"wall"}}});
  WriteScene(dir.File("scene.json"), scene);
  const Result r = RunCandi("-q build " + dir.File("scene.json") + " -o " + dir.File("out"));
  EXPECT_EQ(r.code, 0) << r.output;
  return r.code == 0 ? json::parse(testing::ReadBytes(dir.File("out/archive.json"))) : json::object();
}

// A layer that replaces another drops the other's points in the 0.5 m cubes it covers (close
// range over a coarse scan), at survey coordinates; provenance counts them.
TEST(BuildCli, ReplacingLayerDropsTheCoveredPointsOfTheOther) {
  TempDir dir;
  WriteSurveyWall(dir.File("wall.ply"));  // x = 0.0007 + 0.01 i, i < 400; z = 0.01 j, j < 200
  PointCloud fine;
  fine.frame.origin = Eigen::Vector3d(416000, 9168000, 250);
  for (int i = 0; i < 100; ++i)  // x in [0.0057, 1.9857], 2 cm grid: the first four 0.5 m columns
    for (int j = 0; j < 100; ++j) fine.positions.emplace_back(0.0057 + 0.02 * i, 5.003, 0.02 * j);
  const json a = BuildWallReplacedBy(dir, "fine", fine);
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(a["layers"][0]["points"], 40000) << "the wall's points at x < 2 m are replaced";
  EXPECT_EQ(a["layers"][0]["replaced_by"]["fine"], 40000);
  EXPECT_EQ(a["layers"][1]["points"], 10000);
  EXPECT_EQ(a["layers"][1]["replaces"], json::array({"wall"}));
  const PointCloud wall = io::ReadPointCloud(dir.File("out/layers/wall.ply"));
  ASSERT_EQ(wall.size(), 40000u);
  double min_x = 1e300;
  for (size_t i = 0; i < wall.size(); ++i) min_x = std::min(min_x, wall.WorldPosition(i).x());
  EXPECT_NEAR(min_x, 416002.0007, 1e-6) << "the survival starts at the first uncovered cube, mm kept";
}

TEST(BuildCli, StrayPointsOfTheReplacingLayerCutNoHole) {
  // Three stray close-range points in one 0.5 m cube of the wall (2 500 wall points there) drop
  // only the wall's points near them (within ~voxel / 8), not the whole cube.
  TempDir dir;
  WriteSurveyWall(dir.File("wall.ply"));
  PointCloud stray;
  stray.frame.origin = Eigen::Vector3d(416000, 9168000, 250);
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(3.2, 5.0, 0.5), Eigen::Vector3d(3.21, 5.0, 0.5),
                                   Eigen::Vector3d(3.2, 5.0, 0.51)})
    stray.positions.push_back(p);
  const json a = BuildWallReplacedBy(dir, "stray", stray);
  ASSERT_FALSE(a.empty());
  const int replaced = a["layers"][0]["replaced_by"]["stray"].get<int>();
  EXPECT_GT(replaced, 0) << "the wall's points at the stray points are replaced";
  EXPECT_LT(replaced, 500) << "a few stray points emptied their whole cube";
  EXPECT_EQ(a["layers"][0]["points"].get<int>(), 80000 - replaced);
}

// Each bad key, type, path and value: exit code 2 and the JSON path in the message.
// A scene's "copc" makes candi build write COPC; candi export copc writes the same bytes from the
// finished build and names a folder that is not one.
TEST(BuildCli, CopcFromTheBuildAndFromTheExportAreTheSameBytes) {
  TempDir dir;
  WriteSurveyWall(dir.File("wall.ply"));
  json scene = BaseScene();
  scene["views"] = json::array();
  scene["copc"] = {{"scene", true}};
  WriteScene(dir.File("scene.json"), scene);
  const Result b = RunCandi("-q build " + dir.File("scene.json") + " -o " + dir.File("out"));
  ASSERT_EQ(b.code, 0) << b.output;
  const Result e = RunCandi("export copc " + dir.File("out") + " --out " + dir.File("again.copc.laz"));
  ASSERT_EQ(e.code, 0) << e.output;
  EXPECT_NE(e.out.find("again.copc.laz: 83000 points (every layer"), std::string::npos) << e.out;
  // Progress on stderr: the points read, then the file's octree and its chunks, each to its end.
  for (const std::string stage : {"octree", "chunks"}) {
    EXPECT_NE(e.output.find("copc: again.copc.laz " + stage + ": 100.0% 83000 points"),
              std::string::npos)
        << stage << ":\n" << e.output;
  }
  EXPECT_LT(e.output.find("copc: 100.0%"), e.output.find("again.copc.laz octree")) << e.output;
  const std::string built = testing::ReadBytes(dir.File("out/copc/test.copc.laz"));
  EXPECT_FALSE(built.empty());
  EXPECT_EQ(testing::ReadBytes(dir.File("again.copc.laz")), built);
  EXPECT_FALSE(std::filesystem::exists(dir.File("out/layers/wall.copc.laz")));  // not asked for
  const Result bad = RunCandi("-q export copc " + dir.File("out/layers"));
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.output.find(dir.File("out/layers") + ": no archive.json"), std::string::npos) << bad.output;
  EXPECT_EQ(RunCandi("export copc").code, 1);  // no folder
}

TEST(BuildCli, SceneErrorsNameTheJsonPathOfTheCulprit) {
  TempDir dir;
  WriteSurveyWall(dir.File("wall.ply"));
  struct Case {
    const char* what;
    std::function<void(json&)> edit;
    const char* expected;  // in the message
  };
  const std::vector<Case> cases = {
      {"unknown root key", [](json& s) { s["colour"] = 1; }, "/colour: unknown key"},
      {"missing version", [](json& s) { s.erase("candi_scene"); }, "candi_scene"},
      {"wrong version", [](json& s) { s["candi_scene"] = 2; }, "/candi_scene"},
      {"no layers", [](json& s) { s["layers"] = json::array(); }, "/layers: no layers"},
      {"layers not an array", [](json& s) { s["layers"] = 3; }, "/layers: expected an array"},
      {"unknown layer key", [](json& s) { s["layers"][0]["colour"] = {1, 2, 3}; }, "/layers/0/colour: unknown key"},
      {"key of another kind", [](json& s) { s["layers"][0]["dxf"] = "x.dxf"; }, "/layers/0/dxf: unknown key"},
      {"unknown kind", [](json& s) { s["layers"][0]["kind"] = "mesh"; }, "/layers/0/kind: unknown kind"},
      {"missing file", [](json& s) { s["layers"][0]["file"] = "nope.ply"; }, "/layers/0/file: no such file"},
      {"folder as file", [](json& s) { s["layers"][0]["file"] = "."; }, "/layers/0/file: a folder"},
      {"no file key", [](json& s) { s["layers"][0].erase("file"); }, "needs \"file\""},
      {"opacity 0", [](json& s) { s["layers"][0]["opacity"] = 0; }, "/layers/0/opacity: out of range"},
      {"opacity 1.5", [](json& s) { s["layers"][0]["opacity"] = 1.5; }, "/layers/0/opacity: out of range"},
      {"opacity a string", [](json& s) { s["layers"][0]["opacity"] = "half"; }, "/layers/0/opacity: expected a number"},
      {"colour 300", [](json& s) { s["layers"][0]["color"] = {300, 0, 0}; }, "/layers/0/color/0: out of range"},
      {"colour of two", [](json& s) { s["layers"][0]["color"] = {3, 0}; }, "/layers/0/color: expected [r, g, b]"},
      {"bad name", [](json& s) { s["layers"][0]["name"] = "a/b"; }, "/layers/0/name"},
      {"repeated layer", [](json& s) { s["layers"][1] = s["layers"][0]; }, "/layers/1/name: layer name \"wall\" repeats"},
      {"not a similarity", [](json& s) {
         s["layers"][0]["world_from_layer"] = {{"matrix", {{2, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}}};
       }, "/layers/0/world_from_layer/matrix: not a similarity"},
      {"scale 0", [](json& s) { s["layers"][0]["world_from_layer"] = {{"scale", 0}}; }, "/layers/0/world_from_layer/scale"},
      {"unknown transform key", [](json& s) { s["layers"][0]["world_from_layer"] = {{"shift", 1}}; },
       "/layers/0/world_from_layer/shift: unknown key"},
      {"view of an unknown layer", [](json& s) { s["views"][2]["layers"] = {"wall", "moat"}; }, "/views/2/layers/1: no layer named \"moat\""},
      {"view opacity of an unknown layer", [](json& s) { s["views"][0]["opacity"] = {{"moat", 0.5}}; }, "/views/0/opacity/moat"},
      {"repeated view", [](json& s) { s["views"][1]["name"] = "all"; }, "/views/1/name"},
      {"missing camera file", [](json& s) { s["views"][0]["camera"] = "v.json"; }, "/views/0/camera: no such file"},
      {"density and count", [](json& s) { s["layers"][1]["density"] = 5; }, "/layers/1/count: give one of"},
      {"bad mode", [](json& s) { s["layers"][1]["mode"] = "twist"; }, "/layers/1/mode"},
      {"repeat level 0", [](json& s) { s["render"]["repeat_level"] = 0; }, "/render/repeat_level: out of range"},
      {"huge image", [](json& s) { s["render"]["width"] = 100000; }, "/render/width: out of range"},
      {"NaN-like origin", [](json& s) { s["origin"] = {1, "x", 3}; }, "/origin/1: expected a number"},
      {"replaces an unknown layer", [](json& s) { s["layers"][0]["replaces"] = {"moat"}; },
       "/layers/0/replaces/0: no layer named \"moat\""},
      {"replaces itself", [](json& s) { s["layers"][0]["replaces"] = {"wall"}; },
       "/layers/0/replaces/0: a layer cannot replace itself"},
      {"replace_voxel alone", [](json& s) { s["layers"][0]["replace_voxel"] = 0.5; },
       "/layers/0/replace_voxel: only with \"replaces\""},
      {"replace_voxel 0", [](json& s) { s["layers"][0]["replaces"] = {"hill"}, s["layers"][0]["replace_voxel"] = 0; },
       "/layers/0/replace_voxel: out of range"},
      {"two photogrammetry sources", [](json& s) {
         s["layers"][0] = {{"name", "wall"}, {"kind", "photogrammetry"}, {"dense", "wall.ply"}, {"images", "."}};
       }, "/layers/0: a photogrammetry layer needs exactly one of \"dense\", \"workspace\" and \"images\""},
      {"images not a folder", [](json& s) {
         s["layers"][0] = {{"name", "wall"}, {"kind", "photogrammetry"}, {"images", "wall.ply"}};
       }, "/layers/0/images: not a folder"},
      {"picks without targets", [](json& s) {
         s["layers"][0] = {{"name", "wall"}, {"kind", "photogrammetry"}, {"images", "."}, {"picks", "wall.ply"}};
       }, "/layers/0/picks: picks need \"targets\""},
      {"picks without cameras", [](json& s) {
         s["layers"][0] = {{"name", "wall"}, {"kind", "photogrammetry"}, {"dense", "wall.ply"}, {"targets", "wall.ply"},
                           {"picks", "wall.ply"}};
       }, "/layers/0/picks: picks need the cameras"},
      {"max_image_size without images", [](json& s) {
         s["layers"][0] = {{"name", "wall"}, {"kind", "photogrammetry"}, {"workspace", "."}, {"max_image_size", 480}};
       }, "/layers/0/max_image_size: only with \"images\""},
      {"max_features on a dense cloud", [](json& s) {
         s["layers"][0] = {{"name", "wall"}, {"kind", "photogrammetry"}, {"dense", "wall.ply"}, {"max_features", 512}};
       }, "/layers/0/max_features: only with \"images\""},
      {"max_image_size 10", [](json& s) {
         s["layers"][0] = {{"name", "wall"}, {"kind", "photogrammetry"}, {"images", "."}, {"max_image_size", 10}};
       }, "/layers/0/max_image_size: out of range"},
      {"stereo options on a dense cloud", [](json& s) {
         s["layers"][0] = {{"name", "wall"}, {"kind", "photogrammetry"}, {"dense", "wall.ply"}, {"iterations", 2}};
       }, "/layers/0/iterations: dense stereo options need"},
      {"resolution_scale 2", [](json& s) {
         s["layers"][0] = {{"name", "wall"}, {"kind", "photogrammetry"}, {"images", "."}, {"resolution_scale", 2}};
       }, "/layers/0/resolution_scale: out of range"},
      {"native resolution without a photo", [](json& s) {
         s["layers"][0] = {{"name", "reliefs"}, {"kind", "relief"}, {"placement", "wall.ply"},
                           {"panels", {{{"id", "P1"}, {"points", "wall.ply"}, {"native_resolution", true}}}}};
       }, "/layers/0/panels/0/native_resolution: only for panels given by a photo"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    json scene = BaseScene();
    c.edit(scene);
    WriteScene(dir.File("scene.json"), scene);
    const Result r = RunCandi("build " + dir.File("scene.json") + " -o " + dir.File("out"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("scene.json"), std::string::npos) << r.output;
    EXPECT_FALSE(FileExists(dir.File("out/archive.json")));
  }
  testing::WriteBytes(dir.File("broken.json"), "{\"candi_scene\": 1,\n \"layers\": [}");
  const Result r = RunCandi("build " + dir.File("broken.json") + " -o " + dir.File("out"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("not valid JSON"), std::string::npos) << r.output;
  // A number beyond double's range (JSON allows it; the parser throws out_of_range, which was an
  // internal error, exit 3, until fuzz_scene found it).
  testing::WriteBytes(dir.File("huge.json"), "{\"candi_scene\": 1e99999}");
  const Result huge = RunCandi("build " + dir.File("huge.json") + " -o " + dir.File("out"));
  EXPECT_EQ(huge.code, 2) << huge.output;
  EXPECT_NE(huge.output.find("huge.json: not valid JSON"), std::string::npos) << huge.output;
  EXPECT_EQ(RunCandi("build " + dir.File("missing.json") + " -o " + dir.File("out")).code, 2);
  WriteScene(dir.File("scene.json"), BaseScene());
  const Result unwritable = RunCandi("build " + dir.File("scene.json") + " -o " + dir.File("no/such/folder/out"));
  EXPECT_EQ(unwritable.code, 2) << unwritable.output;
}

}  // namespace
}  // namespace candi::testing
