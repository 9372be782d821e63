// A build of every layer kind that needs no network and no COLMAP (points; a foundation from a
// drawing; relief panels given as points, placed by Ceres; photogrammetry from a dense cloud,
// georeferenced on targets), end to end in one process: the outputs, the layers in one survey
// frame, the same bytes for any thread count, resuming, and bad options; and the scene's
// comparisons (deviation maps between layers, or a layer and a file).
#include "pipeline/build.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/rng.h"
#include "io/ply/ply_io.h"
#include "io/point_io.h"
#include "render/build_record.h"
#include "render/synthetic_scene.h"
#include "tests/util/dxf_text.h"
#include "tests/util/test_util.h"
#include "view/publish.h"
#include "view/source.h"

namespace candi::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::TempDir;

// The survey frame: a site near (500000, 9100000), 10 m high.
const Eigen::Vector3d kSite(500000, 9100000, 10);

// The model frame of the "dense" cloud: survey = 2 R_z(30 deg) model + t.
Sim3 SurveyFromModel() {
  return Sim3(2.0, Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 6, Eigen::Vector3d::UnitZ())), kSite);
}

// A panel's wall position: x along +E, y up, z out towards -N, at (E0, N0, H0).
Sim3 WorldFromPanel(double e0) {
  Eigen::Matrix3d r;
  r.col(0) = Eigen::Vector3d::UnitX();
  r.col(1) = Eigen::Vector3d::UnitZ();
  r.col(2) = -Eigen::Vector3d::UnitY();
  return Sim3(1.0, Eigen::Quaterniond(r), kSite + Eigen::Vector3d(e0, -20, 1));
}

class BuildScene : public ::testing::Test {
 protected:
  void SetUp() override {
    // Points: a sheet over the site, in survey coordinates.
    PointCloud sheet = render::UniformRectangle(20000, 40, 30, 0, {180, 170, 150}, 3);
    for (Eigen::Vector3d& p : sheet.positions) p += kSite - Eigen::Vector3d(20, 15, 0);
    io::PointWriteOptions wide;
    wide.precision = io::PositionPrecision::kFloat64;
    io::WritePointCloud(dir_.File("sheet.ply"), sheet, wide);
    // Foundation: one layer's section (metres).
    testing::DxfText dxf;
    dxf.Lines("A", {Eigen::Vector2d(-10, -2), Eigen::Vector2d(0, 3), Eigen::Vector2d(12, -2)});
    testing::WriteBytes(dir_.File("foundation.dxf"), dxf.str());
    // Relief: two panels given as points, and their documented corners.
    std::string csv = "panel,point,x,y,z,E,N,H\n";
    for (int k = 0; k < 2; ++k) {
      const std::string id = "P0" + std::to_string(k + 1);
      io::WritePointCloud(dir_.File(id + ".ply"), render::UniformRectangle(3000, 2.7, 0.92, 0.05, {90, 90, 90}, 5 + k));
      const Sim3 t = WorldFromPanel(3.0 * k);
      for (const Eigen::Vector3d& c : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2.7, 0, 0),
                                       Eigen::Vector3d(2.7, 0.92, 0), Eigen::Vector3d(0, 0.92, 0)}) {
        const Eigen::Vector3d w = t * c;
        char line[256];
        std::snprintf(line, sizeof(line), "%s,c%g_%g,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n", id.c_str(), c.x(), c.y(),
                      c.x(), c.y(), c.z(), w.x(), w.y(), w.z());
        csv += line;
      }
    }
    testing::WriteBytes(dir_.File("walls.csv"), csv);
    // Photogrammetry: a dense cloud in its model frame, and surveyed targets with model coordinates.
    PointCloud dense = render::UniformRectangle(8000, 5, 4, 0, {120, 110, 100}, 9);
    io::WritePointCloud(dir_.File("dense.ply"), dense);
    std::string targets = "name,E,N,H,role,accuracy,x,y,z\n";
    const Eigen::Vector3d model[5] = {{-2, -2, 0}, {2, -2, 0}, {2, 2, 0}, {-2, 2, 0.5}, {0, 0, 1}};
    for (int i = 0; i < 5; ++i) {
      const Eigen::Vector3d s = SurveyFromModel() * model[i];
      char line[256];
      std::snprintf(line, sizeof(line), "T%d,%.6f,%.6f,%.6f,%s,0.002,%g,%g,%g\n", i, s.x(), s.y(), s.z(),
                    i == 4 ? "check" : "control", model[i].x(), model[i].y(), model[i].z());
      targets += line;
    }
    testing::WriteBytes(dir_.File("targets.csv"), targets);
  }

  json SceneJson() const {
    json j = {{"candi_scene", 1}, {"name", "site"}, {"seed", 3},
              {"render", {{"repeat_level", 8}, {"width", 120}, {"height", 90}}}};
    j["layers"] = json::array(
        {{{"name", "sheet"}, {"kind", "points"}, {"file", "sheet.ply"}, {"opacity", 0.3}},
         {{"name", "foundation"}, {"kind", "foundation"}, {"dxf", "foundation.dxf"}, {"count", 4000},
          {"samples_per_side", 30}, {"angular_steps", 12}, {"opacity", 0.6},
          {"world_from_layer", {{"translation", {kSite.x(), kSite.y(), kSite.z() - 5}}}}},
         {{"name", "reliefs"}, {"kind", "relief"}, {"placement", "walls.csv"}, {"highlight", true},
          {"panels", {{{"id", "P01"}, {"points", "P01.ply"}}, {{"id", "P02"}, {"points", "P02.ply"}}}}},
         {{"name", "close"}, {"kind", "photogrammetry"}, {"dense", "dense.ply"}, {"targets", "targets.csv"},
          {"replaces", {"sheet"}}}});
    j["views"] = json::array(
        {{{"name", "opaque"}, {"opaque", true}},
         {{"name", "see_through"},
          {"camera", {{"eye", {kSite.x() + 30, kSite.y() - 40, kSite.z() + 30}},
                      {"target", {kSite.x(), kSite.y(), kSite.z()}}, {"width", 120}, {"height", 90}}}}});
    return j;
  }

  Scene WriteScene(const json& j) const {
    testing::WriteBytes(dir_.File("scene.json"), j.dump(2));
    return LoadScene(dir_.File("scene.json"));
  }

  BuildSummary BuildInto(const std::string& out, int threads, bool resume = false) const {
    BuildOptions o;
    o.output = dir_.File(out);
    o.threads = threads;
    o.resume = resume;
    return Build(o, WriteScene(SceneJson()));
  }

  TempDir dir_;
};

TEST(BuildOptions, DefaultsNeedAnOutputAndThreadsAreChecked) {
  BuildOptions o;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o.output = "out";
  EXPECT_NO_THROW(o.Check());
  o.threads = 300;
  EXPECT_THROW(o.Check(), std::invalid_argument);
}

TEST_F(BuildScene, EveryLayerInOneSurveyFrameWithItsOutputs) {
  const BuildSummary s = BuildInto("out", 2);
  ASSERT_EQ(s.layers.size(), 4u);
  EXPECT_EQ(s.views, 2u);
  EXPECT_EQ(s.frame.origin, Eigen::Vector3d(500000, 9100000, 0));  // LocalFrame::Auto: 100 m grid
  EXPECT_EQ(s.layers[1].points, 4000u);
  EXPECT_EQ(s.layers[2].points, 6000u);
  EXPECT_TRUE(s.layers[0].scanned);
  EXPECT_FALSE(s.layers[1].scanned);
  uint64_t total = 0;
  for (const BuildLayerSummary& l : s.layers) total += l.points;
  EXPECT_EQ(total, s.points);
  for (const char* f : {"layers/sheet.ply", "layers/close.ply", "archive/manifest.json", "renders/opaque.png",
                        "renders/opaque.view.json", "renders/see_through.png", "meshlab/scene.mlp",
                        "meshlab/shift.txt", "archive.json", "timings.json", "work/foundation_foundation.ply",
                        "work/close_georef.ply", "work/close_georef.ply.georef.json"}) {
    EXPECT_TRUE(fs::exists(dir_.File(std::string("out/") + f))) << f;
  }
  const json a = json::parse(ReadFileToString(dir_.File("out/archive.json")));
  EXPECT_EQ(a.at("points").get<uint64_t>(), s.points);
  EXPECT_EQ(a.at("layers").at(2).at("parameters").at("misfits").get<int>(), 0);
  EXPECT_LT(a.at("layers").at(3).at("parameters").at("georef").at("rmse_m").at("check").at("3d").get<double>(), 1e-3);
  EXPECT_GT(a.at("layers").at(0).at("replaced_by").at("close").get<uint64_t>(), 0u);  // close range replaces the sheet

  // The photogrammetry layer lands where the targets say: the model's corner (2, 2, 0) at survey.
  const PointCloud close = io::ReadPointCloud(dir_.File("out/layers/close.ply"));
  EXPECT_TRUE(close.frame.IsIdentity());  // double world coordinates, no shift
  double nearest = 1e300;
  const Eigen::Vector3d corner = SurveyFromModel() * Eigen::Vector3d(2.5, 2, 0);
  for (const Eigen::Vector3d& p : close.positions) nearest = std::min(nearest, (p - corner).norm());
  EXPECT_LT(nearest, 0.2);
  // The relief panels: their first corner on the wall.
  const PointCloud reliefs = io::ReadPointCloud(dir_.File("out/layers/reliefs.ply"));
  Box3d box;
  for (const Eigen::Vector3d& p : reliefs.positions) box.Extend(p);
  EXPECT_NEAR(box.min.x(), kSite.x(), 0.05);
  EXPECT_NEAR(box.max.x(), kSite.x() + 5.7, 0.05);
  EXPECT_NEAR(box.min.z(), kSite.z() + 1, 0.05);
}

// The record keeps the render settings the build resolved: a build copied to another folder,
// its scene file deleted, opens in candi view (view::OpenViewerSource) and candi publish with
// its own L, image size, background, brightness and seed; nothing reads the scene file again.
TEST_F(BuildScene, AMovedBuildKeepsItsRenderSettings) {
  json j = SceneJson();
  j["seed"] = 11;
  j["render"] = {{"repeat_level", 12},
                 {"width", 200},
                 {"height", 150},
                 {"background", {10, 20, 30}},
                 {"brightness", 1.5}};
  BuildOptions o;
  o.output = dir_.File("out");
  o.threads = 2;
  Build(o, WriteScene(j));
  const render::BuildRecord record = render::ReadBuildRecord(dir_.File("out"));
  ASSERT_TRUE(record.render.has_value());
  EXPECT_EQ(record.render->spbr.repeat_level, 12);
  EXPECT_EQ(record.render->spbr.seed, 11u);
  // The record read and written again: the same bytes.
  EXPECT_EQ(record.ToJson(), ReadFileToString(dir_.File("out/archive.json")));

  fs::create_directories(dir_.File("elsewhere"));
  fs::copy(dir_.File("out"), dir_.File("elsewhere/moved"), fs::copy_options::recursive);
  fs::remove_all(dir_.File("out"));
  fs::remove(dir_.File("scene.json"));
  const view::ViewerSource source =
      view::OpenViewerSource(dir_.File("elsewhere/moved"), render::Orientation());
  EXPECT_EQ(source.settings.spbr.repeat_level, 12);
  EXPECT_EQ(source.settings.spbr.seed, 11u);
  EXPECT_EQ(source.settings.background, (Rgb8{10, 20, 30}));
  EXPECT_EQ(source.settings.brightness, Brightness::Gain(1.5));
  EXPECT_EQ(source.first_view.width, 200);
  EXPECT_EQ(source.first_view.height, 150);
  EXPECT_EQ(source.views.size(), 2u);

  view::PublishOptions p;
  p.group_points = 4000;
  view::PublishSite(p, dir_.File("elsewhere/moved"), dir_.File("site"), render::Orientation());
  const json site = json::parse(ReadFileToString(dir_.File("site/site.json")));
  EXPECT_EQ(site.at("data").at("repeat_level"), 12);
  EXPECT_EQ(site.at("data").at("seed"), 11);
  const json& settings = site.at("scene").at("settings");
  EXPECT_EQ(settings.at("repeat_level"), 12);
  EXPECT_EQ(settings.at("background"), json::array({10, 20, 30}));
  EXPECT_EQ(settings.at("brightness"), 1.5);
  EXPECT_EQ(site.at("scene").at("first_view").at("width"), 200);
}

// The same sources, scene and seed give the same bytes whatever the thread count. Both builds go
// to the same folder (paths are recorded in the files), the first then moved aside.
TEST_F(BuildScene, SameBytesForAnyThreadCount) {
  BuildInto("two", 1);
  fs::rename(dir_.File("two"), dir_.File("one"));
  BuildInto("two", 2);
  for (const char* f : {"layers/sheet.ply", "layers/foundation.ply", "layers/reliefs.ply", "layers/close.ply",
                        "archive/manifest.json", "renders/opaque.png", "renders/see_through.png",
                        "meshlab/foundation.ply", "archive.json"}) {
    EXPECT_EQ(ReadFileToString(dir_.File(std::string("one/") + f)), ReadFileToString(dir_.File(std::string("two/") + f)))
        << f;
  }
}

TEST_F(BuildScene, ResumeReusesWhatIsUnchanged) {
  BuildInto("out", 2);
  const std::string render = ReadFileToString(dir_.File("out/renders/see_through.png"));
  BuildInto("out", 2, /*resume=*/true);
  const json a = json::parse(ReadFileToString(dir_.File("out/archive.json")));
  EXPECT_TRUE(a.at("pack_resumed").get<bool>());
  EXPECT_FALSE(a.at("layers").at(0).at("resumed").get<bool>());  // a point file is read, not kept
  EXPECT_TRUE(a.at("layers").at(1).at("resumed").get<bool>());
  EXPECT_TRUE(a.at("layers").at(3).at("resumed").get<bool>());
  EXPECT_TRUE(a.at("views").at(1).at("resumed").get<bool>());
  EXPECT_EQ(ReadFileToString(dir_.File("out/renders/see_through.png")), render);
  // A changed input redoes its layer and what depends on it.
  PointCloud dense = render::UniformRectangle(8000, 5, 4, 0.1, {120, 110, 100}, 9);
  io::WritePointCloud(dir_.File("dense.ply"), dense);
  BuildInto("out", 2, /*resume=*/true);
  const json b = json::parse(ReadFileToString(dir_.File("out/archive.json")));
  EXPECT_FALSE(b.at("layers").at(3).at("resumed").get<bool>());
  EXPECT_TRUE(b.at("layers").at(1).at("resumed").get<bool>());
  EXPECT_FALSE(b.at("pack_resumed").get<bool>());
}

TEST_F(BuildScene, BadInputsAreNamed) {
  BuildOptions o;
  o.output = dir_.File("no/such/parent/out");
  EXPECT_THROW(Build(o, WriteScene(SceneJson())), InputError);
  json j = SceneJson();
  j["layers"][2]["panels"].push_back({{"id", "P09"}, {"points", "P01.ply"}});
  o.output = dir_.File("out");
  try {
    Build(o, WriteScene(j));
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("panel 'P09' of layer 'reliefs' has no correspondences"), std::string::npos)
        << e.what();
  }
}

// Two point layers of one flat surface, one lifted by kLift, compared with each other (C2C to
// a local plane) and with a mesh of the surface (C2M): small enough for a second's build.
class BuildComparisons : public ::testing::Test {
 protected:
  static constexpr double kLift = 0.05;  // m

  void SetUp() override {
    io::PointWriteOptions wide;
    wide.precision = io::PositionPrecision::kFloat64;
    PointCloud ground = render::UniformRectangle(3000, 10, 8, 0, {150, 150, 150}, 11);
    PointCloud lifted = render::UniformRectangle(2000, 10, 8, kLift, {200, 60, 60}, 12);
    for (PointCloud* c : {&ground, &lifted})
      for (Eigen::Vector3d& p : c->positions) p += kSite;
    io::WritePointCloud(dir_.File("ground.ply"), ground, wide);
    io::WritePointCloud(dir_.File("lifted.ply"), lifted, wide);
    // The surface as a mesh in world coordinates, a little larger than the points; facing up.
    TriMesh mesh;
    for (const Eigen::Vector3d& c : {Eigen::Vector3d(-1, -1, 0), Eigen::Vector3d(11, -1, 0),
                                     Eigen::Vector3d(11, 9, 0), Eigen::Vector3d(-1, 9, 0)}) {
      mesh.vertices.positions.push_back(kSite + c);
    }
    mesh.faces = {{0, 1, 2}, {0, 2, 3}};
    io::WritePlyMesh(dir_.File("ground_mesh.ply"), mesh, wide);
  }

  json SceneJson(double tolerance = 0.06) const {
    json j = {{"candi_scene", 1}, {"name", "flat"}, {"seed", 1}};
    j["layers"] = json::array({{{"name", "ground"}, {"kind", "points"}, {"file", "ground.ply"}},
                               {{"name", "lifted"}, {"kind", "points"}, {"file", "lifted.ply"}}});
    j["comparisons"] = json::array(
        {{{"name", "lifted_vs_ground"}, {"compared", "lifted"}, {"reference", "ground"}, {"method", "c2c"},
          {"model", "plane"}, {"tolerance", tolerance}},
         {{"name", "lifted_vs_mesh"}, {"compared", "lifted"}, {"reference", "ground_mesh.ply"}, {"method", "c2m"},
          {"tolerance", 0.01}}});
    return j;
  }

  json BuildInto(const json& scene, bool resume) {
    testing::WriteBytes(dir_.File("scene.json"), scene.dump(2));
    BuildOptions o;
    o.output = dir_.File("out");
    o.threads = 2;
    o.resume = resume;
    summary_ = Build(o, LoadScene(dir_.File("scene.json")));
    return json::parse(ReadFileToString(dir_.File("out/archive.json")));
  }

  TempDir dir_;
  BuildSummary summary_;  // of the last build
};

TEST_F(BuildComparisons, MeasureTheKnownOffsetAndAreListedInTheArchive) {
  const json a = BuildInto(SceneJson(), false);
  ASSERT_EQ(a.at("comparisons").size(), 2u);
  const json& c2c = a["comparisons"][0];
  EXPECT_EQ(c2c.at("name"), "lifted_vs_ground");
  EXPECT_EQ(c2c.at("compared"), "lifted");
  EXPECT_EQ(c2c.at("reference"), "ground");
  EXPECT_EQ(c2c.at("reference_kind"), "layer");
  EXPECT_EQ(c2c.at("method"), "c2c");
  EXPECT_EQ(c2c.at("count").get<uint64_t>(), 2000u);
  EXPECT_EQ(c2c.at("undefined").get<uint64_t>(), 0u);
  EXPECT_NEAR(c2c.at("mean_m").get<double>(), kLift, 1e-6);  // the plane through the ground's points
  EXPECT_NEAR(c2c.at("rms_m").get<double>(), kLift, 1e-6);
  EXPECT_DOUBLE_EQ(c2c.at("within_tolerance").get<double>(), 1.0);  // tolerance 6 cm
  EXPECT_FALSE(c2c.at("resumed").get<bool>());
  const json& c2m = a["comparisons"][1];
  EXPECT_EQ(c2m.at("reference_kind"), "file");
  EXPECT_EQ(c2m.at("reference"), fs::path(dir_.File("ground_mesh.ply")).lexically_normal().string());
  EXPECT_TRUE(c2m.at("signed").get<bool>());
  EXPECT_NEAR(c2m.at("mean_m").get<double>(), kLift, 1e-6);  // above the upward-facing mesh: positive
  EXPECT_DOUBLE_EQ(c2m.at("within_tolerance").get<double>(), 0.0);  // tolerance 1 cm
  for (const json& c : a["comparisons"]) {
    for (const char* f : {"cloud", "summary", "histogram", "report"}) {
      EXPECT_TRUE(fs::exists(dir_.File("out/" + c.at("files").at(f).get<std::string>()))) << f;
    }
  }
  // The deviation map: the compared layer's points, in world coordinates, with their distances.
  const PointCloud map = io::ReadPointCloud(dir_.File("out/compare/lifted_vs_mesh.ply"));
  ASSERT_EQ(map.size(), 2000u);
  EXPECT_NEAR(map.frame.ToWorld(map.positions[0]).z(), kSite.z() + kLift, 1e-6);
  const json summary = json::parse(ReadFileToString(dir_.File("out/compare/lifted_vs_ground.ply.compare.json")));
  EXPECT_NEAR(summary.at("mean_m").get<double>(), kLift, 1e-6);
  const json timings = json::parse(ReadFileToString(dir_.File("out/timings.json")));
  EXPECT_TRUE(timings.at("comparisons").contains("lifted_vs_mesh"));
  // What candi build prints.
  ASSERT_EQ(summary_.comparisons.size(), 2u);
  EXPECT_EQ(summary_.comparisons[1].name, "lifted_vs_mesh");
  EXPECT_EQ(summary_.comparisons[1].method, "c2m");
  EXPECT_EQ(summary_.comparisons[1].count, 2000u);
  EXPECT_NEAR(summary_.comparisons[1].mean, kLift, 1e-6);
  EXPECT_DOUBLE_EQ(summary_.comparisons[0].within_tolerance, 1.0);
  EXPECT_DOUBLE_EQ(summary_.comparisons[0].tolerance, 0.06);
}

TEST_F(BuildComparisons, ResumeKeepsThemUnlessTheirSettingsChange) {
  BuildInto(SceneJson(), false);
  const fs::path c2c = dir_.File("out/compare/lifted_vs_ground.ply"), c2m = dir_.File("out/compare/lifted_vs_mesh.ply");
  // Marks on the kept files: a comparison run again would replace them.
  fs::last_write_time(c2c, fs::file_time_type::clock::now() - std::chrono::hours(1));
  const fs::file_time_type old_time = fs::last_write_time(c2c);  // as the file system keeps it
  fs::last_write_time(c2m, old_time);
  const json a = BuildInto(SceneJson(), true);
  EXPECT_TRUE(a.at("comparisons").at(0).at("resumed").get<bool>());
  EXPECT_TRUE(a.at("comparisons").at(1).at("resumed").get<bool>());
  EXPECT_NEAR(a["comparisons"][0].at("mean_m").get<double>(), kLift, 1e-6);  // the figures kept
  EXPECT_EQ(fs::last_write_time(c2c), old_time);
  EXPECT_EQ(fs::last_write_time(c2m), old_time);
  // A changed tolerance redoes that comparison only.
  const json b = BuildInto(SceneJson(0.04), true);
  EXPECT_FALSE(b.at("comparisons").at(0).at("resumed").get<bool>());
  EXPECT_TRUE(b.at("comparisons").at(1).at("resumed").get<bool>());
  EXPECT_DOUBLE_EQ(b["comparisons"][0].at("within_tolerance").get<double>(), 0.0);
  EXPECT_NE(fs::last_write_time(c2c), old_time);
  EXPECT_EQ(fs::last_write_time(c2m), old_time);
  // So does a changed layer file: the lifted layer moved 1 cm further up.
  PointCloud lifted = io::ReadPointCloud(dir_.File("lifted.ply"));
  for (Eigen::Vector3d& p : lifted.positions) p.z() += 0.01;
  io::PointWriteOptions wide;
  wide.precision = io::PositionPrecision::kFloat64;
  io::WritePointCloud(dir_.File("lifted.ply"), lifted, wide);
  const json c = BuildInto(SceneJson(0.04), true);
  EXPECT_FALSE(c.at("comparisons").at(1).at("resumed").get<bool>());
  EXPECT_NEAR(c["comparisons"][1].at("mean_m").get<double>(), kLift + 0.01, 1e-6);
}

TEST_F(BuildComparisons, AnUnknownReferenceIsNamedWhenTheSceneIsLoaded) {
  json j = SceneJson();
  j["comparisons"][0]["reference"] = "no_such_layer";
  testing::WriteBytes(dir_.File("scene.json"), j.dump(2));
  try {
    LoadScene(dir_.File("scene.json"));
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/comparisons/0/reference: no layer named \"no_such_layer\""),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace candi::pipeline
