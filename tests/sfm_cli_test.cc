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
}

}  // namespace
}  // namespace candi::testing
