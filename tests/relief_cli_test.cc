// End-to-end tests of `candi relief ...` on tiny data: synth -> dataset -> train -> predict ->
// points -> eval, exit codes and messages for bad input, and `candi bench relief`.
#include <gtest/gtest.h>

#include <string>

#include "core/png_io.h"
#include "core/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi {
namespace {

using testing::FileExists;
using testing::RunCandi;
using testing::TempDir;
using Result = testing::CommandResult;

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
  const PngImage depth = ReadPng(dir_->File("panels/panel_0000_depth.png"));
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

TEST_F(ReliefCli, PredictPointsAndEvalOnAnyPhoto) {
  const std::string photo = dir_->File("panels/panel_0001_photo.png");
  const Result p = RunCandi("relief predict " + photo + " --model " + dir_->File("m.pt") + " -o " +
                            dir_->File("d.png") + " --tile 32 --overlap 8");
  ASSERT_EQ(p.code, 0) << p.output;
  const PngImage d = ReadPng(dir_->File("d.png"));
  EXPECT_EQ(d.bit_depth, 8);
  EXPECT_EQ(d.image8.width(), 192);
  const Result pts = RunCandi("relief points " + photo + " " + dir_->File("d.png") + " -o " +
                              dir_->File("panel.ply") + " --width-m 2.7 --height-m 0.92 --depth-m 0.15");
  ASSERT_EQ(pts.code, 0) << pts.output;
  const PointCloud cloud = ReadPointCloud(dir_->File("panel.ply"));
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
  for (const char* row : {"BTS DenseNet-161 (paper)", "intensity as depth*", "linear SFS, Pentland*", "candi BTS"}) {
    EXPECT_NE(e.out.find(row), std::string::npos) << row << "\n" << e.out;
  }
  const Result one = RunCandi("relief eval --photo " + photo + " --depth " +
                              dir_->File("panels/panel_0001_depth.png") + " --tile 32 --overlap 8");
  EXPECT_EQ(one.code, 0) << one.output;
}

TEST_F(ReliefCli, SixteenBitColourAndTinyPhotosPredict) {
  Image16 colour16(40, 20, 3, 30000);
  colour16.at(5, 5, 0) = 65535;
  WritePng(dir_->File("c16.png"), colour16);
  const Result r = RunCandi("-q relief predict " + dir_->File("c16.png") + " --model " + dir_->File("m.pt") +
                            " -o " + dir_->File("c16_depth.png") + " --width-m 0 --tile 64 --overlap 16");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(ReadPng(dir_->File("c16_depth.png")).image8.width(), 40);
}

TEST_F(ReliefCli, BadInputsAreExitTwoNamingTheFile) {
  const std::string photo = dir_->File("panels/panel_0001_photo.png");
  Result r = RunCandi("relief predict " + photo + " --model " + dir_->File("none.pt") + " -o " + dir_->File("x.png"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("none.pt"), std::string::npos) << r.output;
  r = RunCandi("relief predict " + photo + " --model " + photo + " -o " + dir_->File("x.png"));
  EXPECT_EQ(r.code, 2) << "a PNG is not a model: " << r.output;
  Image8 small(10, 10, 1, 3);
  WritePng(dir_->File("small.png"), small);
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

}  // namespace
}  // namespace candi
