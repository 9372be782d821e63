// The photogrammetry stages a build shares with `candi dense` and `candi georef`: dense stereo on
// a synthetic workspace, and georeferencing on surveyed targets. (Structure from motion runs
// COLMAP: reconstruction/photogrammetry/mvs/sfm_dense_test.cc and tests/sfm_cli_test.cc.)
#include "pipeline/photogrammetry.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <filesystem>

#include "core/check.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/mvs/dense_workspace.h"
#include "reconstruction/photogrammetry/scenes/synthetic_views.h"
#include "reconstruction/photogrammetry/scenes/synthetic_workspace.h"
#include "tests/util/option_check.h"
#include "tests/util/test_util.h"

namespace candi::pipeline {
namespace {

namespace fs = std::filesystem;
namespace pg = photogrammetry;
using testing::ExpectEachBreakRejected;
using testing::TempDir;

std::string Workspace(const TempDir& dir, std::vector<pg::SyntheticView>* views) {
  pg::SyntheticViewsOptions o;
  o.views = 4;
  o.width = 96;
  o.height = 72;
  *views = pg::RenderSyntheticViews(o);
  pg::WriteDenseWorkspace(*views, pg::SyntheticSparsePoints(*views, 16), dir.File("ws"));
  return dir.File("ws");
}

TEST(DenseOptions, DefaultsPassAndTheirPartsAreChecked) {
  ExpectEachBreakRejected<DenseOptions>({}, {
      [](DenseOptions& o) { o.stereo.window_radius = 0; },
      [](DenseOptions& o) { o.fusion.min_views = 0; },
  });
}

TEST(DenseStereo, PointsOnTheSceneAndTheMapsOnlyWhenAsked) {
  TempDir dir;
  std::vector<pg::SyntheticView> views;
  const std::string ws = Workspace(dir, &views);
  DenseOptions o;
  o.stereo.iterations = 2;
  o.write_maps = false;
  const DenseCloud dense = DenseStereo(o, ws);
  EXPECT_EQ(dense.images, 4u);
  EXPECT_GT(dense.cloud.size(), 300u);  // four 96 x 72 views, fused
  EXPECT_GT(dense.valid_pixels, 0u);
  EXPECT_LE(dense.valid_pixels, dense.total_pixels);
  EXPECT_EQ(dense.cloud.meta.comments.back(), "candi dense " + ws);
  const auto no_maps = [&] {
    const std::string maps = dir.File("ws/stereo/depth_maps");  // the workspace may hold the folder
    return !fs::exists(maps) || fs::is_empty(maps);
  };
  EXPECT_TRUE(no_maps());
  // Most points lie on the synthetic scene's surfaces (relative depth error along a view's ray
  // within 1 %).
  std::vector<Eigen::Vector3d> points;
  for (size_t i = 0; i < dense.cloud.size(); ++i) points.push_back(dense.cloud.WorldPosition(i));
  std::vector<ImageF> no_depth;
  for (const pg::SyntheticView& v : views) no_depth.emplace_back(v.image.width(), v.image.height(), 1);
  EXPECT_GT(pg::ScoreSyntheticDense(views, no_depth, points).accuracy, 0.8);
  // Threads change nothing.
  o.stereo.threads = 1;
  EXPECT_EQ(DenseStereo(o, ws).cloud.positions, dense.cloud.positions);
  o.write_maps = true;
  DenseStereo(o, ws);
  EXPECT_FALSE(no_maps());
  EXPECT_THROW(DenseStereo(o, dir.File("nowhere")), InputError);
}

// survey = 3 R_z(40 deg) model + t, at survey coordinates.
const Sim3 kSurveyFromModel(3.0, Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ())),
                            Eigen::Vector3d(712345.5, 9123456.25, 87));

std::string Targets(const TempDir& dir) {
  std::string csv = "name,E,N,H,role,accuracy,x,y,z\n";
  const Eigen::Vector3d model[6] = {{0, 0, 0}, {4, 0, 0}, {4, 3, 0}, {0, 3, 1}, {2, 1, 2}, {1, 2, 0.5}};
  for (int i = 0; i < 6; ++i) {
    const Eigen::Vector3d s = kSurveyFromModel * model[i];
    char line[256];
    std::snprintf(line, sizeof(line), "T%d,%.4f,%.4f,%.4f,%s,0.002,%g,%g,%g\n", i, s.x(), s.y(), s.z(),
                  i == 5 ? "check" : "control", model[i].x(), model[i].y(), model[i].z());
    csv += line;
  }
  testing::WriteBytes(dir.File("targets.csv"), csv);
  return dir.File("targets.csv");
}

TEST(Georeference, TheSimilarityOfTheTargetsMovesTheCloudIntoTheSurveyFrame) {
  TempDir dir;
  GeorefOptions o;
  o.crs = "EPSG:32749";
  const pg::GeorefResult fit = FitGeoref(o, Targets(dir), nullptr, "");
  EXPECT_TRUE(fit.fit.converged);
  EXPECT_NEAR(fit.survey_from_model.scale, 3.0, 1e-4);
  EXPECT_LT(fit.check.d3, 1e-3);
  PointCloud cloud;
  cloud.positions = {{0, 0, 0}, {2, 1, 2}};
  Georeference(o, fit, &cloud);
  EXPECT_EQ(cloud.meta.crs, "EPSG:32749");
  EXPECT_EQ(cloud.frame, fit.frame);
  EXPECT_LT((cloud.WorldPosition(1) - kSurveyFromModel * Eigen::Vector3d(2, 1, 2)).norm(), 1e-3);
  const nlohmann::json report = GeorefReport(o, fit);
  EXPECT_EQ(report.at("loss"), "huber");
  EXPECT_EQ(report.at("crs"), "EPSG:32749");
  EXPECT_EQ(report.at("targets").size(), 6u);
  EXPECT_TRUE(report.at("converged").get<bool>());
  EXPECT_NEAR(report.at("survey_from_model").at("scale").get<double>(), 3.0, 1e-4);
}

TEST(Georeference, BadInputsAreNamed) {
  TempDir dir;
  GeorefOptions o;
  o.targets_crs = "EPSG:4979";  // without the survey CRS to transform into
  EXPECT_THROW(FitGeoref(o, Targets(dir), nullptr, ""), std::invalid_argument);
  o = GeorefOptions();
  testing::WriteBytes(dir.File("picks.csv"), "name,image,u,v\nT0,a.png,1,2\n");
  EXPECT_THROW(FitGeoref(o, Targets(dir), nullptr, dir.File("picks.csv")), std::invalid_argument);
  testing::WriteBytes(dir.File("two.csv"), "name,E,N,H,role,accuracy,x,y,z\nA,1,2,3,control,0.01,0,0,0\n");
  EXPECT_THROW(FitGeoref(o, dir.File("two.csv"), nullptr, ""), InputError);
  o.fit.loss_scale = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
}

TEST(GeoreferenceFiles, APointFileStreamedIntoTheSurveyFrameAfterTheFitIsReported) {
  TempDir dir;
  PointCloud cloud;
  cloud.schema.colors = true;
  cloud.positions = {{0, 0, 0}, {2, 1, 2}, {4, 3, 0}};
  cloud.colors = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}};
  io::WritePointCloud(dir.File("model.ply"), cloud);
  GeorefOptions o;
  o.crs = "EPSG:32749";
  GeorefFiles files;
  files.input = dir.File("model.ply");
  files.targets = Targets(dir);
  files.output = dir.File("survey.las");
  bool fitted = false;
  const pg::GeorefResult r = GeoreferenceFiles(o, files, [&](const pg::GeorefResult& fit) {
    fitted = true;
    EXPECT_TRUE(fit.fit.converged);
    EXPECT_FALSE(fs::exists(files.output));
  });
  EXPECT_TRUE(fitted);
  EXPECT_NEAR(r.survey_from_model.scale, 3.0, 1e-4);
  const PointCloud moved = io::ReadPointCloud(files.output);
  ASSERT_EQ(moved.size(), 3u);
  EXPECT_FALSE(moved.meta.crs.empty());
  EXPECT_EQ(moved.colors[2], cloud.colors[2]);
  EXPECT_LT((moved.WorldPosition(1) - kSurveyFromModel * Eigen::Vector3d(2, 1, 2)).norm(), 2e-3);
  const nlohmann::json report = nlohmann::json::parse(testing::ReadBytes(files.output + ".georef.json"));
  EXPECT_EQ(report.at("crs"), "EPSG:32749");
}

TEST(GeoreferenceFiles, AModelMovedWithItsPointsAndBadInputsNamedFirst) {
  TempDir dir;
  std::vector<pg::SyntheticView> views;
  const std::string ws = Workspace(dir, &views);
  GeorefFiles files;
  files.input = ws + "/sparse";
  files.targets = Targets(dir);
  files.output = dir.File("model_utm");
  GeoreferenceFiles(GeorefOptions(), files);
  EXPECT_TRUE(fs::exists(dir.File("model_utm/points.ply")));
  EXPECT_TRUE(fs::exists(dir.File("model_utm.georef.json")));
  EXPECT_FALSE(io::ReadPointCloud(dir.File("model_utm/points.ply")).empty());
  // An unknown output format and a missing input are refused before the fit.
  files.input = dir.File("missing.ply");
  files.output = dir.File("out.ply");
  EXPECT_THROW(GeoreferenceFiles(GeorefOptions(), files), InputError);
  files.input = ws + "/sparse";
  files.targets = dir.File("missing.csv");
  EXPECT_THROW(GeoreferenceFiles(GeorefOptions(), files), InputError);
  EXPECT_FALSE(fs::exists(dir.File("out.ply")));
}

}  // namespace
}  // namespace candi::pipeline
