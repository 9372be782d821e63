// End-to-end tests of `candi relief ...` on tiny data: synth -> dataset -> train -> predict ->
// points -> eval, exit codes and messages for bad input, and `candi bench relief`.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "io/image/png_io.h"
#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

using Result = CommandResult;

class ReliefCli : public ::testing::Test {
 protected:
  // One tiny trained model shared by the tests (about 10 s on one thread).
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    const Result s = RunCandi("-q relief synth -o " + dir_->File("panels") + " --count 3 --width 192 --seed 4");
    ASSERT_EQ(s.code, 0) << s.output;
    const Result d = RunCandi("-q relief dataset " + dir_->File("panels") + " -o " + dir_->File("data") +
                              " --pixels-per-m " + std::to_string(192 / 2.7) + " --patch 32 --stride 16");
    ASSERT_EQ(d.code, 0) << d.output;
    const Result t = RunCandi("-q relief train --data " + dir_->File("data") + " --out " + dir_->File("m.pt") +
                              " --epochs 2 --batch 8 --growth 4 --blocks 1,1,2,1 --width 32");
    ASSERT_EQ(t.code, 0) << t.output;
    train_output_ = new std::string(t.output);
  }
  static void TearDownTestSuite() {
    delete dir_;
    delete train_output_;
  }
  static TempDir* dir_;
  static std::string* train_output_;
};
TempDir* ReliefCli::dir_ = nullptr;
std::string* ReliefCli::train_output_ = nullptr;

TEST_F(ReliefCli, SynthDatasetAndTrainWriteTheirFiles) {
  EXPECT_TRUE(FileExists(dir_->File("panels/panel_0002_photo.png")));
  const io::PngImage depth = io::ReadPng(dir_->File("panels/panel_0000_depth.png"));
  EXPECT_EQ(depth.bit_depth, 16);
  EXPECT_EQ(depth.image16.width(), 192);
  EXPECT_EQ(depth.text.count("candi_light_azimuth_deg"), 1u);
  EXPECT_TRUE(FileExists(dir_->File("data/train/000000_photo.png")));
  EXPECT_TRUE(FileExists(dir_->File("data/val/000000_depth.png"))) << "the last panel validates";
  EXPECT_TRUE(FileExists(dir_->File("data/dataset.txt")));
  EXPECT_TRUE(FileExists(dir_->File("m.pt")));
  EXPECT_TRUE(FileExists(dir_->File("m.pt.ckpt")));
  EXPECT_NE(train_output_->find("epoch 2/2  loss"), std::string::npos) << *train_output_;
  EXPECT_NE(train_output_->find("val d1"), std::string::npos);
}

// Folders trained on together must agree on their resolution: the second one is named, with
// both values, and no model is written.
TEST_F(ReliefCli, TrainRefusesDataFoldersOfDifferentResolutions) {
  const Result d = RunCandi("-q relief dataset " + dir_->File("panels") + " -o " + dir_->File("data_fine") +
                            " --pixels-per-m " + std::to_string(2 * 192 / 2.7) + " --patch 32 --stride 16");
  ASSERT_EQ(d.code, 0) << d.output;
  const Result r = RunCandi("relief train --data " + dir_->File("data") + " --data " + dir_->File("data_fine") +
                            " --out " + dir_->File("mixed.pt") + " --epochs 1 --growth 4 --blocks 1,1,2,1 --width 32");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find(dir_->File("data_fine") + "/dataset.txt"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("differs from"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir_->File("mixed.pt")));
}

TEST_F(ReliefCli, PredictPointsAndEvalOnAnyPhoto) {
  const std::string photo = dir_->File("panels/panel_0001_photo.png");
  const Result p = RunCandi("relief predict " + photo + " --model " + dir_->File("m.pt") + " -o " +
                            dir_->File("d.png") + " --tile 32 --overlap 8");
  ASSERT_EQ(p.code, 0) << p.output;
  const io::PngImage d = io::ReadPng(dir_->File("d.png"));
  EXPECT_EQ(d.bit_depth, 8);
  EXPECT_EQ(d.image8.width(), 192);
  const Result pts = RunCandi("relief points " + photo + " " + dir_->File("d.png") + " -o " +
                              dir_->File("panel.ply") + " --width-m 2.7 --height-m 0.92 --depth-m 0.15");
  ASSERT_EQ(pts.code, 0) << pts.output;
  const PointCloud cloud = io::ReadPointCloud(dir_->File("panel.ply"));
  EXPECT_EQ(cloud.size(), 192u * 65u);
  const Box3d box = cloud.LocalBounds();
  EXPECT_GE(box.min.x(), 0.0);
  EXPECT_LE(box.max.x(), 2.7);
  EXPECT_LE(box.max.y(), 0.92);
  EXPECT_GE(box.min.z(), 0.0);
  EXPECT_LE(box.max.z(), 0.15 + 1e-6);
  EXPECT_TRUE(cloud.schema.colors);
  const Result e = RunCandi("relief eval --model " + dir_->File("m.pt") + " --panels 1 --width 192 --tile 32 --overlap 8");
  ASSERT_EQ(e.code, 0) << e.output;
  for (const char* row : {"BTS DenseNet-161 (paper)", "intensity as depth*", "linear SFS, Pentland*", "m (", "normal", "edge F1"}) {
    EXPECT_NE(e.out.find(row), std::string::npos) << row << "\n" << e.out;
  }
  const Result one = RunCandi("relief eval --photo " + photo + " --depth " +
                              dir_->File("panels/panel_0001_depth.png") + " --tile 32 --overlap 8");
  EXPECT_EQ(one.code, 0) << one.output;
}

TEST_F(ReliefCli, SixteenBitColourAndTinyPhotosPredict) {
  Image16 colour16(40, 20, 3, 30000);
  colour16.at(5, 5, 0) = 65535;
  io::WritePng(dir_->File("c16.png"), colour16);
  const Result r = RunCandi("-q relief predict " + dir_->File("c16.png") + " --model " + dir_->File("m.pt") +
                            " -o " + dir_->File("c16_depth.png") + " --width-m 0 --tile 64 --overlap 16");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(io::ReadPng(dir_->File("c16_depth.png")).image8.width(), 40);
}

TEST_F(ReliefCli, BadInputsAreExitTwoNamingTheFile) {
  const std::string photo = dir_->File("panels/panel_0001_photo.png");
  Result r = RunCandi("relief predict " + photo + " --model " + dir_->File("none.pt") + " -o " + dir_->File("x.png"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("none.pt"), std::string::npos) << r.output;
  r = RunCandi("relief predict " + photo + " --model " + photo + " -o " + dir_->File("x.png"));
  EXPECT_EQ(r.code, 2) << "a PNG is not a model: " << r.output;
  Image8 small(10, 10, 1, 3);
  io::WritePng(dir_->File("small.png"), small);
  r = RunCandi("relief points " + photo + " " + dir_->File("small.png") + " -o " + dir_->File("p.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("small.png"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir_->File("p.ply")));
  r = RunCandi("relief train --data " + dir_->File("nope") + " --out " + dir_->File("y.pt"));
  EXPECT_EQ(r.code, 2);
  r = RunCandi("relief points " + photo + " " + photo + " -o " + dir_->File("p.ply") + " --depth-m -1");
  EXPECT_EQ(r.code, 1) << r.output;
  r = RunCandi("relief synth -o " + dir_->File("s") + " --width 8");
  EXPECT_EQ(r.code, 1) << r.output;
}

// The real-photo workflow on the Sceaux photos: pairs from the COLMAP model and OpenMVS's dense
// cloud, fine-tuning, scoring the held-out photo, predicting its JPEG and making points of it.
TEST_F(ReliefCli, RealPhotoPairsFineTuneScoreAndPredict) {
  CANDI_REQUIRE_SHARED_DATA(model, "colmap/sceaux_1600_sparse");
  CANDI_REQUIRE_SHARED_DATA(photos, "photos/sceaux_castle");
  CANDI_REQUIRE_SHARED_DATA(dense, "dense/sceaux_openmvs_dense.ply");
  const std::string pairs = dir_->File("sceaux");
  const std::string common = "relief dataset " + dense + " --colmap " + model + " --images " + photos +
                             " --max-side 128 --patch 64 --stride 32 -o " + pairs;
  Result r = RunCandi(common + " --holdout nosuch.JPG");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("nosuch.JPG"), std::string::npos) << r.output;
  r = RunCandi("-q " + common + " --holdout 100_7105.JPG,100_7109");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.out.find("11 views (2 held out)"), std::string::npos) << r.out;
  EXPECT_TRUE(FileExists(pairs + "/holdout/100_7105_mask.png"));
  EXPECT_TRUE(FileExists(pairs + "/views/100_7100_depth.png"));
  EXPECT_FALSE(FileExists(pairs + "/views/100_7105_depth.png")) << "held out from training";
  EXPECT_TRUE(FileExists(pairs + "/train/000000_photo.png"));
  const io::PngImage depth = io::ReadPng(pairs + "/holdout/100_7105_depth.png");
  EXPECT_EQ(depth.image16.width(), 128);
  EXPECT_EQ(depth.text.count("candi_depth_near"), 1u);

  r = RunCandi("-q relief train --data " + pairs + " --finetune " + dir_->File("m.pt") + " --out " +
               dir_->File("tuned.pt") + " --epochs 1 --batch 4 --edge-loss 1");
  ASSERT_EQ(r.code, 0) << r.output;
  r = RunCandi("relief train --data " + pairs + " --finetune " + dir_->File("m.pt") + " --out " +
               dir_->File("t2.pt") + " --growth 8");
  EXPECT_NE(r.code, 0) << "network options do not apply to a fine-tuned model";

  r = RunCandi("relief eval --pairs " + pairs + "/holdout --model " + dir_->File("m.pt") + " --model " +
               dir_->File("tuned.pt") + " --tile 64 --overlap 16");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* row : {"2 photo pairs", "intensity as depth*", "m (", "tuned (", "normal", "edge F1",
                          "differences over 4 px"}) {
    EXPECT_NE(r.out.find(row), std::string::npos) << row << "\n" << r.out;
  }

  // A surface held out (x > 0 of the chateau), then two held-out parts scored alone and averaged.
  const std::string surface = dir_->File("surface");
  r = RunCandi("relief dataset " + dense + " --colmap " + model + " --images " + photos +
               " --max-side 128 --patch 64 --stride 32 --holdout-region side:1,0,0,0 -o " + surface);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.out.find("held-out surface side:1,0,0,0:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("none in training"), std::string::npos) << r.out;
  r = RunCandi("relief dataset " + dense + " --colmap " + model + " --images " + photos +
               " --holdout-region side:0,0,0,1 -o " + dir_->File("bad_region"));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("side:0,0,0,1"), std::string::npos) << r.output;
  r = RunCandi("relief eval --pairs " + pairs + "/holdout --pairs " + surface + "/holdout --model " +
               dir_->File("tuned.pt") + " --tile 64 --overlap 16");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* row : {"part 1: 2 photo pairs", "part 2: ", "mean over the 2 held-out parts", "tuned ("}) {
    EXPECT_NE(r.out.find(row), std::string::npos) << row << "\n" << r.out;
  }

  // A relative model fine-tuned on two folders together (both 64 px patches): said on stderr,
  // scored after the fit (its row marked *), and its prediction stretched to the full range.
  r = RunCandi("relief train --data " + pairs + " --data " + surface + " --finetune " + dir_->File("m.pt") +
               " --relative --out " + dir_->File("rel.pt") + " --epochs 1 --batch 4");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("relative: scale-and-shift-invariant loss"), std::string::npos) << r.output;
  r = RunCandi("relief eval --pairs " + surface + "/holdout --model " + dir_->File("rel.pt"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.out.find("rel ("), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" par.)*"), std::string::npos) << "a relative model's row is fitted\n" << r.out;
  r = RunCandi("-q relief predict " + pairs + "/holdout/100_7105_photo.png --model " + dir_->File("rel.pt") +
               " --width-m 0 -o " + dir_->File("rel_depth.png"));
  ASSERT_EQ(r.code, 0) << r.output;
  {
    const io::PngImage rel = io::ReadPng(dir_->File("rel_depth.png"));
    const auto [lo, hi] = std::minmax_element(rel.image8.values().begin(), rel.image8.values().end());
    EXPECT_LE(*lo, 1) << "stretched: the 2nd percentile is level 1";
    EXPECT_GE(*hi, 254) << "and the 98th level 255";
  }
  // Folders of different patch sizes cannot be trained on together: the folder is named.
  r = RunCandi("relief train --data " + pairs + " --data " + dir_->File("data") + " --out " + dir_->File("x.pt") +
               " --epochs 1");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find(dir_->File("data")), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("share one size"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir_->File("x.pt")));

  // Both protocols' tables: held-out photos, and held-out surfaces part by part with the mean.
  r = RunCandi("bench relief --pairs " + pairs + " --parts " + surface + " --parts " + surface + " --model " +
               dir_->File("m.pt") + " --finetune-seconds 1 --edge-loss 0 --relative");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* row : {"Protocol: held-out photos", "Protocol: held-out surfaces", "as shipped, read as relative*",
                          "  linear SFS, Pentland* [2]", "  fine-tuned* [1]", "\nfine-tuned*"}) {
    EXPECT_NE(r.out.find(row), std::string::npos) << row << "\n" << r.out;
  }

  r = RunCandi("relief predict " + photos + "/100_7105.JPG --model " + dir_->File("tuned.pt") +
               " --width-m 0 --tile 64 --overlap 16 -o " + dir_->File("7105_depth.png"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(io::ReadPng(dir_->File("7105_depth.png")).image8.width(), 2832) << "the photo's own size";
  r = RunCandi("-q relief points " + pairs + "/holdout/100_7105_photo.png " + dir_->File("7105_128.png") +
               " -o " + dir_->File("7105.ply"));
  EXPECT_EQ(r.code, 2) << "no such depth map: " << r.output;

  // To points, placed by Ceres: the held-out view as a 12.8 x 9.6 m "panel" whose depth range is
  // the view's; its control points are where the reconstruction puts those pixels (true depth)
  // in a survey frame at 10^6 m, the panel's own points where the network puts them.
  const std::string photo128 = pairs + "/holdout/100_7105_photo.png";
  r = RunCandi("-q relief predict " + photo128 + " --model " + dir_->File("tuned.pt") +
               " --width-m 0 --tile 64 --overlap 16 -o " + dir_->File("7105_128.png"));
  ASSERT_EQ(r.code, 0) << r.output;
  const double range = std::stod(depth.text.at("candi_depth_far")) - std::stod(depth.text.at("candi_depth_near"));
  ASSERT_GT(range, 0);
  const std::string panels = dir_->File("panels_7105");
  std::filesystem::create_directories(panels);
  r = RunCandi("-q relief points " + photo128 + " " + dir_->File("7105_128.png") + " -o " + panels +
               "/100_7105.ply --width-m 12.8 --height-m 9.6 --depth-m " + std::to_string(range));
  ASSERT_EQ(r.code, 0) << r.output;
  const io::PngImage predicted = io::ReadPng(dir_->File("7105_128.png"));
  std::string csv = "panel,point,x,y,z,E,N,H\n";
  int controls = 0;
  for (int py = 8; py < 96; py += 16) {
    for (int px = 8; px < 128; px += 16) {
      const double truth = depth.image16.at(px, py) / 256.0;
      if (truth < 1) continue;  // unknown
      const double x = (px + 0.5) * 0.1, y = 9.6 - (py + 0.5) * 0.1;
      const double z_net = range * (1 - predicted.image8.at(px, py) / 255.0), z_true = range * (1 - truth / 255.0);
      char line[256];
      std::snprintf(line, sizeof(line), "100_7105,c%d,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n", controls++, x, y,
                    z_net, 652000.0 + x, 9170000.0 - z_true, 240.0 + y);
      csv += line;
    }
  }
  ASSERT_GE(controls, 6);
  testing::WriteBytes(dir_->File("facade.csv"), csv);
  r = RunCandi("relief place " + dir_->File("facade.csv") + " -o " + dir_->File("placements.json") +
               " --panels " + panels + " --points-out " + dir_->File("world"));
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json placed = nlohmann::json::parse(testing::ReadBytes(dir_->File("placements.json")));
  ASSERT_EQ(placed["panels"].size(), 1u);
  EXPECT_TRUE(std::isfinite(placed["panels"][0]["rms_mm"].get<double>()));
  const PointCloud world = io::ReadPointCloud(dir_->File("world/100_7105.ply"));
  ASSERT_EQ(world.size(), 128u * 96u);
  const Eigen::Vector3d corner = world.WorldPosition(0);
  EXPECT_NEAR(corner.x(), 652000.05, 5) << "the top-left pixel lands at the left edge of the facade";
  EXPECT_NEAR(corner.z(), 240.0 + 9.55, 5);

  // Fine-tuning seconds -> accuracy on the held-out photos, plain and with the edge term.
  r = RunCandi("bench relief --pairs " + pairs + " --model " + dir_->File("m.pt") +
               " --finetune-seconds 1 --edge-loss 2");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* row : {"as shipped", "linear SFS, Pentland*", "fine-tuned ", "fine-tuned, edge term 2"}) {
    EXPECT_NE(r.out.find(row), std::string::npos) << row << "\n" << r.out;
  }

  // A depth map of the wrong size in a folder of pairs: exit 2 naming it.
  io::WritePng(pairs + "/holdout/100_7109_depth.png", Image16(20, 10, 1, 300));
  r = RunCandi("relief eval --pairs " + pairs + "/holdout");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("100_7109_depth.png"), std::string::npos) << r.output;
}

TEST(ReliefBenchCli, WidthTableHasPlainAndEdgeRows) {
  const Result r = RunCandi("bench relief --widths 32 --seconds 1 --train-panels 1 --eval-panels 1 --edge-loss 1");
  ASSERT_EQ(r.code, 0) << r.output;
  size_t rows = 0;
  for (size_t at = r.out.find("\n    32 "); at != std::string::npos; at = r.out.find("\n    32 ", at + 1)) ++rows;
  EXPECT_EQ(rows, 2u) << r.out;
  EXPECT_NE(r.out.find("edge F1"), std::string::npos) << r.out;
}

TEST(ReliefCliScan, DatasetFromARealScan) {
  CANDI_REQUIRE_SHARED_DATA(scan, "ply/Laurana50k.ply");
  TempDir dir;
  // The bust is in millimetres: "metres" are the file's units here.
  const Result r = RunCandi("-q relief dataset " + scan + " -o " + dir.File("data") +
                            " --pixels-per-m 0.25 --patch 32 --stride 32 --depth-m 300");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(FileExists(dir.File("data/train/000000_photo.png")));
  const Result huge = RunCandi("-q relief dataset " + scan + " -o " + dir.File("huge") + " --pixels-per-m 200");
  EXPECT_EQ(huge.code, 2) << huge.output;
  EXPECT_NE(huge.output.find("Laurana50k.ply"), std::string::npos) << huge.output;
}

// `candi relief place`: two panels on a south face at survey coordinates; panel_0001's positions
// are those of a 2.4 x 1.1 m slot (it does not fit: a warning, exit 0).
std::string PlaceCsv() {
  std::string csv = "# documented positions on the foot wall, UTM 49S\npanel,point,x,y,z,E,N,H\n";
  const double e0 = 416012.3456, n0 = 9168001.2345, h0 = 240.5;
  auto row = [&](const std::string& panel, const std::string& point, double x, double y, double e, double h) {
    char buf[200];
    std::snprintf(buf, sizeof(buf), "%s,%s,%.4f,%.4f,0,%.4f,%.4f,%.4f\n", panel.c_str(), point.c_str(), x, y, e, n0, h);
    csv += buf;
  };
  const char* names[] = {"bl", "br", "tr", "tl"};
  const double u[] = {0, 1, 1, 0}, v[] = {0, 0, 1, 1};
  for (int k = 0; k < 4; ++k) row("panel_0000", names[k], 2.7 * u[k], 0.92 * v[k], e0 + 2.7 * u[k], h0 + 0.92 * v[k]);
  for (int k = 0; k < 4; ++k) row("panel_0001", names[k], 2.7 * u[k], 0.92 * v[k], e0 + 3 + 2.4 * u[k], h0 + 1.1 * v[k]);
  return csv;
}

TEST(ReliefPlaceCli, PlacesPanelsWarnsAMisfitAndWritesWorldPoints) {
  TempDir dir;
  testing::WriteBytes(dir.File("walls.csv"), PlaceCsv());
  PointCloud panel;
  panel.positions = {Eigen::Vector3d(1.35, 0.46, 0.1), Eigen::Vector3d(0, 0, 0)};
  io::WritePointCloud(dir.File("panel_0000.ply"), panel);
  io::WritePointCloud(dir.File("panel_0001.ply"), panel);
  const Result r = RunCandi("relief place " + dir.File("walls.csv") + " -o " + dir.File("placements.json") +
                            " --panels " + dir.path() + " --points-out " + dir.File("world"));
  ASSERT_EQ(r.code, 0) << "a misfit is a warning: " << r.output;
  EXPECT_NE(r.out.find("2 panels, 1 fit, 1 do not"), std::string::npos) << r.out;
  EXPECT_NE(r.output.find("panel 'panel_0001': does not fit"), std::string::npos) << r.output;
  const nlohmann::json j = nlohmann::json::parse(testing::ReadBytes(dir.File("placements.json")));
  EXPECT_EQ(j["fit"], "rigid");
  EXPECT_EQ(j["misfits"], 1);
  const nlohmann::json& p0 = j["panels"][0];
  EXPECT_EQ(p0["status"], "ok");
  EXPECT_LT(p0["rms_mm"].get<double>(), 0.01);
  EXPECT_EQ(p0["correspondences"].size(), 4u);
  EXPECT_EQ(p0["correspondences"][0]["line"], 3);
  EXPECT_NEAR(p0["world_from_panel"]["matrix"][0][3].get<double>(), 416012.3456, 1e-6);
  EXPECT_EQ(j["panels"][1]["status"], "misfit");
  EXPECT_GT(j["panels"][1]["rms_mm"].get<double>(), 20.0);
  // The panel's points in world coordinates keep mm detail at 10^7 m (double, shifted).
  const PointCloud world = io::ReadPointCloud(dir.File("world/panel_0000.ply"));
  ASSERT_EQ(world.size(), 2u);
  EXPECT_FALSE(world.frame.IsIdentity());
  const Eigen::Vector3d expected(416012.3456 + 1.35, 9168001.2345 - 0.1, 240.5 + 0.46);
  EXPECT_LT((world.WorldPosition(0) - expected).norm(), 1e-6) << world.WorldPosition(0).transpose();
  EXPECT_TRUE(FileExists(dir.File("world/panel_0001.ply")));
}

TEST(ReliefPlaceCli, BadInputIsExitTwoNamingFileAndLineAndWritesNothing) {
  // A few cases here (each call loads candi-relief's libtorch, ~3 s of CPU); relief_place_test.cc
  // has all the CSV errors (missing column, < 3 points, duplicates, coincident points, accuracy).
  TempDir dir;
  testing::WriteBytes(dir.File("bad.csv"), "panel,point,x,y,z,E,N,H\np,a,0,0,0,1,2,3\n"
                                           "p,b,1,NaN,0,2,2,3\np,c,0,1,0,1,2,4\n");
  Result r = RunCandi("relief place " + dir.File("bad.csv") + " -o " + dir.File("p.json"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find(dir.File("bad.csv") + ": line 3: field 'y': 'NaN' is not a finite number"),
            std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir.File("p.json")));
  testing::WriteBytes(dir.File("walls.csv"), PlaceCsv());
  // The output folder does not exist.
  r = RunCandi("relief place " + dir.File("walls.csv") + " -o " + dir.File("no/such/p.json"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find(dir.File("no/such")), std::string::npos) << r.output;
  testing::WriteBytes(dir.File("panel_0001.ply"), "not a ply");
  r = RunCandi("relief place " + dir.File("walls.csv") + " -o " + dir.File("p.json") + " --panels " +
               dir.File("panel_0001.ply") + " --points-out " + dir.File("world"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find(dir.File("panel_0001.ply")), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir.File("p.json")));
}

}  // namespace
}  // namespace candi::testing
