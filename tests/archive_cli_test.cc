// End-to-end tests of `candi pack` and `candi render ARCHIVE`, in one process and under mpirun:
// the MPI image is bit-identical to the one-process image, damaged archives and failed ranks are
// reported and leave no image.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/rng.h"
#include "io/image/png_io.h"
#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

namespace fs = std::filesystem;

// Stacked translucent squares at survey coordinates.
void WriteScene(const std::string& path, size_t n) {
  PointCloud c;
  c.schema.colors = true;
  c.SetSchema(c.schema);
  c.Resize(n);
  c.frame.origin = Eigen::Vector3d(500000, 4500000, 0);
  Rng rng(3);
  for (size_t i = 0; i < n; ++i) {
    const int layer = static_cast<int>(i % 3);
    c.positions[i] = Eigen::Vector3d(rng.Uniform(0, 10) + 2 * layer, rng.Uniform(0, 10), 3.0 * layer);
    c.colors[i] = {static_cast<uint8_t>(80 * layer + 60), static_cast<uint8_t>(200 - 60 * layer), 90};
  }
  io::WritePointCloud(path, c);
}

std::vector<uint16_t> Pixels16(const std::string& path) {
  const io::PngImage png = io::ReadPng(path);
  const Image16& im = png.image16;
  return std::vector<uint16_t>(im.data(), im.data() + size_t{3} * im.width() * im.height());
}

class ArchiveCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    WriteScene(dir_->path() + "/scene.ply", 40000);
    const testing::CommandResult r =
        RunCandi("pack " + dir_->path() + "/scene.ply -o " + dir_->path() + "/arc --chunk-points 1024");
    ASSERT_EQ(r.code, 0) << r.output;
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string Render(const std::string& archive, const std::string& out) {
    return archive + " -o " + out + ".png --png16 " + out + "16.png -L 12 --size 96x72 --seed 5 --threads 1";
  }
  static TempDir* dir_;
};
TempDir* ArchiveCli::dir_ = nullptr;

TEST_F(ArchiveCli, PackReportsAndRenderDrawsTheScene) {
  const std::string d = dir_->path();
  EXPECT_TRUE(FileExists(d + "/arc/manifest.json"));
  EXPECT_TRUE(FileExists(d + "/arc/data-00000.bin"));
  EXPECT_EQ(fs::file_size(d + "/arc/data-00000.bin"), 40000u * 8);
  const testing::CommandResult r = RunCandi("render " + Render(d + "/arc", d + "/one"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("chunks in view"), std::string::npos) << r.output;
  const io::PngImage png = io::ReadPng(d + "/one.png");
  EXPECT_EQ(png.text.at("candi:mode"), "archive");
  int covered = 0;
  const size_t values = size_t{3} * png.image8.width() * png.image8.height();
  for (size_t i = 0; i < values; ++i) covered += png.image8.data()[i] > 0;
  EXPECT_GT(covered, 1000);
}

TEST_F(ArchiveCli, MpiRendersWithOneTwoThreeRanksAreBitIdenticalToOneProcess) {
  if (!OnPath("mpirun")) GTEST_SKIP() << "mpirun not installed (Debian: openmpi-bin)";
  const std::string d = dir_->path();
  const testing::CommandResult base = RunCandi("render " + Render(d + "/arc", d + "/base"));
  ASSERT_EQ(base.code, 0) << base.output;
  const std::vector<uint16_t> expected = Pixels16(d + "/base16.png");
  for (int ranks : {1, 2, 3}) {
    const std::string out = d + "/np" + std::to_string(ranks);
    const testing::CommandResult r = RunCommand(MpirunCandi(ranks) + " render " + Render(d + "/arc", out));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_TRUE(Pixels16(out + "16.png") == expected) << ranks << " ranks";
  }
}

TEST_F(ArchiveCli, FailedRankStopsAllRanksAndNoImageIsWritten) {
  if (!OnPath("mpirun")) GTEST_SKIP() << "mpirun not installed (Debian: openmpi-bin)";
  const std::string d = dir_->path();
  // Rank 1 reads a copy of the archive with one corrupt chunk (MPMD launch: one program per rank).
  fs::copy(d + "/arc", d + "/bad", fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  {
    std::fstream f(d + "/bad/data-00000.bin", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(100000);
    f.put('\x7f');
  }
  const std::string out = d + "/failed";
  const testing::CommandResult r =
      RunCommand("mpirun --oversubscribe --allow-run-as-root -np 1 " CANDI_EXECUTABLE " render " +
                 Render(d + "/arc", out) + " : -np 1 " CANDI_EXECUTABLE " render " + Render(d + "/bad", out));
  // The reason reaches the user whatever the timing between the ranks (rank 0 prints every
  // rank's report before any process exits), with the input error's exit code.
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("MPI rank 1 of 2 failed: error: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("does not match its hash"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("another rank failed"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(out + ".png"));
  EXPECT_FALSE(FileExists(out + "16.png"));
}

TEST_F(ArchiveCli, DamagedArchivesAndTooSmallBudgetsAreClearErrors) {
  const std::string d = dir_->path();
  fs::copy(d + "/arc", d + "/short", fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  fs::resize_file(d + "/short/data-00000.bin", 1000);
  testing::CommandResult r = RunCandi("render " + Render(d + "/short", d + "/x"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("data-00000.bin"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("truncated"), std::string::npos) << r.output;
  fs::remove(d + "/short/data-00000.bin");
  r = RunCandi("render " + Render(d + "/short", d + "/x"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("cannot open archive data file"), std::string::npos) << r.output;
  r = RunCandi("render " + Render(d + "/arc", d + "/x") + " --chunk-budget 0.001");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("chunk budget"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(d + "/x.png"));
  // Point files under mpirun are refused (each rank would draw everything).
  if (OnPath("mpirun")) {
    r = RunCommand(MpirunCandi(2) + " render " + d + "/scene.ply -o " + d + "/y.png");
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.output.find("archive"), std::string::npos) << r.output;
  }
}

}  // namespace
}  // namespace candi::testing
