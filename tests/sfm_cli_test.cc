// `candi sfm`: exit codes and messages of the cases that need no COLMAP run.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

void Put(const std::string& path, const std::string& bytes) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  WriteBytes(path, bytes);
}

TEST(SfmCli, MissingColmapExitsTwoWithInstallHint) {
  TempDir dir;
  Put(dir.File("in/a.jpg"), "x");
  Put(dir.File("in/b.jpg"), "x");
  const auto r = RunCandi("sfm " + dir.File("in") + " -o " + dir.File("ws") + " --colmap " +
                          dir.File("nowhere/colmap"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("COLMAP was not found"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("apt install colmap"), std::string::npos) << r.output;
  // The environment variable is the fallback.
  const auto e = testing::RunCommand("CANDI_COLMAP=" + dir.File("env/colmap") + " " +
                                     std::string(CANDI_EXECUTABLE) + " sfm " + dir.File("in") +
                                     " -o " + dir.File("ws2"));
  EXPECT_EQ(e.code, 2) << e.output;
  EXPECT_NE(e.output.find("env/colmap"), std::string::npos) << e.output;
}

TEST(SfmCli, FoldersWithoutTwoImagesExitTwo) {
  TempDir dir;
  Put(dir.File("docs/a.txt"), "x");
  auto r = RunCandi("sfm " + dir.File("docs") + " -o " + dir.File("ws"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("no images"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("ignored"), std::string::npos) << "warns about the non-image file";
  Put(dir.File("one/x.png"), "x");
  r = RunCandi("sfm " + dir.File("one") + " -o " + dir.File("ws"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("at least 2"), std::string::npos) << r.output;
  r = RunCandi("sfm " + dir.File("absent") + " -o " + dir.File("ws"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("no such folder"), std::string::npos) << r.output;
}

TEST(SfmCli, BadOptionsAreUsageErrors) {
  TempDir dir;
  EXPECT_EQ(RunCandi("sfm " + dir.path() + " -o " + dir.File("ws") + " --max-features 5").code, 1);
  EXPECT_EQ(RunCandi("sfm " + dir.path()).code, 1);  // -o is required
  Put(dir.File("in/a.jpg"), "x");
  Put(dir.File("in/b.jpg"), "x");
  const auto r = RunCandi("sfm " + dir.File("in") + " -o " + dir.File("ws") + " --camera-model FISH");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("camera_model = FISH"), std::string::npos) << r.output;
  const auto m = RunCandi("sfm " + dir.File("in") + " -o " + dir.File("ws") + " --matching vocab");
  EXPECT_EQ(m.code, 1) << m.output;
  EXPECT_NE(m.output.find("auto, exhaustive, sequential, retrieval or positional"), std::string::npos) << m.output;
  Put(dir.File("priors.csv"), "name,E,N\na.jpg,1,2\n");
  const auto p = RunCandi("sfm " + dir.File("in") + " -o " + dir.File("ws2") + " --priors " + dir.File("priors.csv") +
                          " --colmap " + dir.File("nowhere/colmap"));
  EXPECT_EQ(p.code, 2) << p.output;
  const auto t = RunCandi("sfm " + dir.File("in") + " -o " + dir.File("ws3") + " --targets " + dir.File("t.csv"));
  EXPECT_EQ(t.code, 1) << t.output;
  EXPECT_NE(t.output.find("picks"), std::string::npos) << t.output;
}

// `candi campaign`: writes a small campaign; refuses an occupied folder and bad counts.
TEST(CampaignCli, WritesACampaignAndRefusesBadInput) {
  TempDir dir;
  const auto r = RunCandi("campaign " + dir.File("site") + " --photos 12 --size 64 --chunks 2 --supersample 1");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("12 photos of 64 x 48 in 2 session(s)"), std::string::npos) << r.output;
  for (const char* f : {"s1/s1_0001.jpg", "s2/s2_0001.jpg", "targets.csv", "picks.csv", "truth/cameras.csv",
                        "truth/surface.ply", "campaign.json"}) {
    EXPECT_TRUE(std::filesystem::exists(dir.File("site/") + f)) << f;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.File("site/priors.csv")));
  const auto again = RunCandi("campaign " + dir.File("site") + " --photos 12 --size 64");
  EXPECT_EQ(again.code, 2) << again.output;
  EXPECT_NE(again.output.find("--overwrite"), std::string::npos) << again.output;
  EXPECT_EQ(RunCandi("campaign " + dir.File("x") + " --photos 4").code, 1);
  const auto uav = RunCandi("campaign " + dir.File("y") + " --photos 20 --chunks 3 --uav 10");
  EXPECT_EQ(uav.code, 1) << uav.output;
  EXPECT_NE(uav.output.find("uav_photos"), std::string::npos) << uav.output;
}

}  // namespace
}  // namespace candi::testing
