// Coordinate reference systems end to end: layers in WGS 84 and UTM zone 49S meet in one scene
// frame (checked against PROJ's own cs2cs), a scene mixing CRSs without declaring one is an error
// naming both, a layer without a CRS in a scene that declares one is warned about, and `candi
// convert --to-crs` and `candi info` carry and show the CRS.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

using nlohmann::json;

// Points around Borobudur (110.2038 E, 7.6079 S), lon/lat in degrees, ellipsoidal height.
std::vector<Eigen::Vector3d> LonLatPoints() {
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < 7; ++i)
    for (int j = 0; j < 5; ++j) p.emplace_back(110.2030 + 0.0003 * i, -7.6085 + 0.0002 * j, 250.0 + i + 0.1 * j);
  return p;
}

void WritePly(const std::string& path, const std::vector<Eigen::Vector3d>& points, const std::string& crs) {
  PointCloud c;
  c.SetSchema(c.schema);
  c.positions = points;
  c.meta.crs = crs;
  io::PointWriteOptions o;
  o.precision = io::PositionPrecision::kFloat64;
  io::WritePointCloud(path, c, o);
}

// cs2cs from EPSG:4326 (its axis order: latitude, longitude) to EPSG:32749 (easting, northing).
std::vector<Eigen::Vector3d> Cs2csToUtm(const std::vector<Eigen::Vector3d>& lonlat, const std::string& dir) {
  std::string input;
  char line[128];
  for (const Eigen::Vector3d& p : lonlat) {
    std::snprintf(line, sizeof(line), "%.12f %.12f %.6f\n", p.y(), p.x(), p.z());
    input += line;
  }
  testing::WriteBytes(dir + "/cs2cs_in.txt", input);
  const testing::CommandResult r = RunCommand("cs2cs -f %.6f EPSG:4326 EPSG:32749 < " + dir + "/cs2cs_in.txt");
  EXPECT_EQ(r.code, 0) << r.output;
  std::vector<Eigen::Vector3d> out;
  std::istringstream in(r.out);
  double e, n, h;
  while (in >> e >> n >> h) out.emplace_back(e, n, h);
  return out;
}

bool HaveCs2cs() { return RunCommand("command -v cs2cs").code == 0; }

json Scene(bool with_crs) {
  json s = {{"candi_scene", 1}, {"seed", 3},
            {"layers", {{{"name", "gnss"}, {"kind", "points"}, {"file", "gnss.ply"}},
                        {{"name", "grid"}, {"kind", "points"}, {"file", "grid.ply"}}}}};
  if (with_crs) s["crs"] = "EPSG:32749";
  return s;
}

TEST(CrsCli, Wgs84AndUtmLayersMeetInTheScenesCrsAsCs2csPutsThem) {
  if (!HaveCs2cs()) GTEST_SKIP() << "cs2cs (Debian proj-bin) is absent";
  TempDir dir;
  const std::vector<Eigen::Vector3d> lonlat = LonLatPoints();
  const std::vector<Eigen::Vector3d> expected = Cs2csToUtm(lonlat, dir.path());
  ASSERT_EQ(expected.size(), lonlat.size());
  WritePly(dir.File("gnss.ply"), lonlat, "EPSG:4326");
  std::vector<Eigen::Vector3d> grid = {{416000.25, 9158900.5, 260.0}, {416010.75, 9158910.125, 261.5}};
  WritePly(dir.File("grid.ply"), grid, "EPSG:32749");
  testing::WriteBytes(dir.File("scene.json"), Scene(true).dump(2));
  const testing::CommandResult r = RunCandi("build " + dir.File("scene.json") + " -o " + dir.File("out"));
  ASSERT_EQ(r.code, 0) << r.output;

  const PointCloud gnss = io::ReadPointCloud(dir.File("out/layers/gnss.ply"));
  ASSERT_EQ(gnss.size(), expected.size());
  double worst = 0;
  for (size_t i = 0; i < gnss.size(); ++i) {
    const Eigen::Vector3d w = gnss.frame.ToWorld(gnss.positions[i]);
    worst = std::max(worst, (w.head<2>() - expected[i].head<2>()).norm());
    EXPECT_NEAR(w.z(), lonlat[i].z(), 1e-6);  // a 2-D CRS pair: heights pass through
  }
  EXPECT_LT(worst, 1e-6) << "metres from cs2cs";  // cs2cs prints micrometres
  const PointCloud g = io::ReadPointCloud(dir.File("out/layers/grid.ply"));
  ASSERT_EQ(g.size(), 2u);
  EXPECT_NEAR((g.frame.ToWorld(g.positions[1]) - grid[1]).norm(), 0, 1e-9);  // untouched

  const json archive = json::parse(testing::ReadBytes(dir.File("out/archive.json")));
  EXPECT_EQ(archive["crs"]["definition"], "EPSG:32749");
  EXPECT_NE(archive["crs"]["label"].get<std::string>().find("UTM zone 49S"), std::string::npos);
  EXPECT_TRUE(archive["layers"][0]["crs"]["transformed"].get<bool>());
  EXPECT_FALSE(archive["layers"][1]["crs"]["transformed"].get<bool>());
  EXPECT_NE(r.output.find("WGS 84 (EPSG:4326) -> WGS 84 / UTM zone 49S (EPSG:32749)"), std::string::npos) << r.output;
  // The layers carry the scene's CRS on, for candi info and the tools after.
  EXPECT_EQ(gnss.meta.crs, "EPSG:32749");
}

TEST(CrsCli, MixingCrssWithoutASceneCrsIsAnErrorNamingBoth) {
  TempDir dir;
  WritePly(dir.File("gnss.ply"), LonLatPoints(), "EPSG:4326");
  WritePly(dir.File("grid.ply"), {{416000.25, 9158900.5, 260.0}}, "EPSG:32749");
  testing::WriteBytes(dir.File("scene.json"), Scene(false).dump(2));
  const testing::CommandResult r = RunCandi("build " + dir.File("scene.json") + " -o " + dir.File("out"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("EPSG:4326"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("EPSG:32749"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("declare the scene's \"crs\""), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.File("out/archive.json")));
}

TEST(CrsCli, ALayerWithoutCrsInASceneThatDeclaresOneIsWarnedAbout) {
  TempDir dir;
  WritePly(dir.File("gnss.ply"), {{416000.5, 9158900.5, 250.0}}, "");
  WritePly(dir.File("grid.ply"), {{416000.25, 9158900.5, 260.0}}, "EPSG:32749");
  testing::WriteBytes(dir.File("scene.json"), Scene(true).dump(2));
  const testing::CommandResult r = RunCandi("build " + dir.File("scene.json") + " -o " + dir.File("out"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("layer gnss states no CRS; taken to be in the scene's"), std::string::npos) << r.output;
  // Saying so silences it.
  json scene = Scene(true);
  scene["layers"][0]["crs"] = "scene";
  testing::WriteBytes(dir.File("scene2.json"), scene.dump(2));
  const testing::CommandResult quiet = RunCandi("build " + dir.File("scene2.json") + " -o " + dir.File("out2"));
  ASSERT_EQ(quiet.code, 0) << quiet.output;
  EXPECT_EQ(quiet.output.find("states no CRS"), std::string::npos) << quiet.output;
}

TEST(CrsCli, SceneCrsTyposAndContradictionsNameTheJsonPath) {
  TempDir dir;
  WritePly(dir.File("gnss.ply"), LonLatPoints(), "EPSG:4326");
  WritePly(dir.File("grid.ply"), {{416000.25, 9158900.5, 260.0}}, "EPSG:32749");
  json scene = Scene(true);
  scene["crs"] = "EPSG:999999";
  testing::WriteBytes(dir.File("bad.json"), scene.dump(2));
  testing::CommandResult r = RunCandi("build " + dir.File("bad.json") + " -o " + dir.File("out"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("/crs"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("PROJ cannot read"), std::string::npos) << r.output;
  scene = Scene(true);
  scene["layers"][0]["crs"] = "EPSG:32750";  // the file says 4326
  testing::WriteBytes(dir.File("contradiction.json"), scene.dump(2));
  r = RunCandi("build " + dir.File("contradiction.json") + " -o " + dir.File("out"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("/layers/0/crs"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("EPSG:4326"), std::string::npos) << r.output;
}

TEST(CrsCli, ConvertReprojectsLikeCs2csAndCarriesTheCrsIntoLas) {
  if (!HaveCs2cs()) GTEST_SKIP() << "cs2cs (Debian proj-bin) is absent";
  TempDir dir;
  const std::vector<Eigen::Vector3d> lonlat = LonLatPoints();
  const std::vector<Eigen::Vector3d> expected = Cs2csToUtm(lonlat, dir.path());
  WritePly(dir.File("gnss.ply"), lonlat, "");
  // No CRS stated: --to-crs needs --crs.
  testing::CommandResult r = RunCandi("convert " + dir.File("gnss.ply") + " " + dir.File("utm.las") + " --to-crs EPSG:32749");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("give it with --crs"), std::string::npos) << r.output;
  r = RunCandi("convert " + dir.File("gnss.ply") + " " + dir.File("utm.las") + " --crs EPSG:4326 --to-crs EPSG:32749");
  ASSERT_EQ(r.code, 0) << r.output;
  const PointCloud utm = io::ReadPointCloud(dir.File("utm.las"));
  ASSERT_EQ(utm.size(), expected.size());
  for (size_t i = 0; i < utm.size(); ++i) {
    EXPECT_NEAR(utm.positions[i].x(), expected[i].x(), 0.0006);  // LAS's 1 mm grid
    EXPECT_NEAR(utm.positions[i].y(), expected[i].y(), 0.0006);
  }
  EXPECT_NE(utm.meta.crs.find("UTM zone 49S"), std::string::npos) << utm.meta.crs;  // WKT VLR
  r = RunCandi("info " + dir.File("utm.las"));
  EXPECT_NE(r.out.find("crs       WGS 84 / UTM zone 49S (EPSG:32749)"), std::string::npos) << r.out;
  // A CRS the file contradicts is refused; an unreadable one names PROJ's reason.
  r = RunCandi("convert " + dir.File("utm.las") + " " + dir.File("x.ply") + " --crs EPSG:4326");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("--to-crs"), std::string::npos) << r.output;
  r = RunCandi("convert " + dir.File("utm.las") + " " + dir.File("x.ply") + " --to-crs NOT_A_CRS");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("PROJ cannot read the CRS 'NOT_A_CRS'"), std::string::npos) << r.output;
}

TEST(CrsCli, InfoShowsTheCrsOfLasAndE57) {
  CANDI_REQUIRE_SHARED_DATA(autzen, "las/autzen_trim.las");
  testing::CommandResult r = RunCandi("info " + autzen);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.out.find("crs       NAD_1983_HARN_Lambert_Conformal_Conic"), std::string::npos) << r.out;
  TempDir dir;
  r = RunCandi("convert " + autzen + " " + dir.File("a.e57"));
  ASSERT_EQ(r.code, 0) << r.output;
  r = RunCandi("info --json " + dir.File("a.e57"));
  ASSERT_EQ(r.code, 0) << r.output;
  const json j = json::parse(r.out);
  EXPECT_NE(j["crs"]["definition"].get<std::string>().find("Lambert_Conformal_Conic"), std::string::npos);
  EXPECT_EQ(j["points"], 110000);
}

TEST(CrsCli, GeorefFitsGnssTargetsTransformedIntoTheSurveyCrs) {
  if (!HaveCs2cs()) GTEST_SKIP() << "cs2cs (Debian proj-bin) is absent";
  TempDir dir;
  // Four GNSS targets in WGS 84; their UTM 49S positions (cs2cs) are the model's plus a shift.
  const std::vector<Eigen::Vector3d> lonlat = {{110.2031, -7.6084, 250.0}, {110.2047, -7.6083, 252.0},
                                               {110.2046, -7.6071, 265.0}, {110.2032, -7.6072, 255.0}};
  const std::vector<Eigen::Vector3d> utm = Cs2csToUtm(lonlat, dir.path());
  ASSERT_EQ(utm.size(), 4u);
  const Eigen::Vector3d shift(415000, 9158000, 0);
  std::string csv = "name,E,N,H,role,accuracy,x,y,z\n";
  char row[256];
  for (size_t i = 0; i < 4; ++i) {
    const Eigen::Vector3d m = utm[i] - shift;
    std::snprintf(row, sizeof(row), "T%zu,%.10f,%.10f,%.4f,%s,0.01,%.6f,%.6f,%.6f\n", i, lonlat[i].x(), lonlat[i].y(),
                  lonlat[i].z(), i < 3 ? "control" : "check", m.x(), m.y(), m.z());
    csv += row;
  }
  testing::WriteBytes(dir.File("targets.csv"), csv);
  WritePly(dir.File("model.ply"), {utm[0] - shift, utm[2] - shift}, "");
  testing::CommandResult r = RunCandi("georef " + dir.File("model.ply") + " --targets " + dir.File("targets.csv") +
                                      " --targets-crs EPSG:4326 --crs EPSG:32749 --rigid -o " + dir.File("site.ply"));
  ASSERT_EQ(r.code, 0) << r.output;
  const json report = json::parse(testing::ReadBytes(dir.File("site.ply.georef.json")));
  EXPECT_LT(report["rmse"]["control"]["3d"].get<double>(), 0.001) << report.dump(2);
  EXPECT_LT(report["rmse"]["check"]["3d"].get<double>(), 0.001) << report.dump(2);
  EXPECT_EQ(report["targets_crs"], "EPSG:4326");
  const PointCloud site = io::ReadPointCloud(dir.File("site.ply"));
  EXPECT_EQ(site.meta.crs, "EPSG:32749");
  EXPECT_LT((site.frame.ToWorld(site.positions[1]) - utm[2]).head<2>().norm(), 0.001);
  // Without --crs there is nothing to transform into.
  r = RunCandi("georef " + dir.File("model.ply") + " --targets " + dir.File("targets.csv") +
               " --targets-crs EPSG:4326 -o " + dir.File("x.ply"));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("--targets-crs needs --crs"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace candi::testing
