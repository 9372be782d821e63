// `candi dense`: exit codes and messages for bad input. (The end-to-end run on the synthetic
// workspace needs the COLMAP model reader; see reconstruction/photogrammetry/mvs/dense_workspace.h.)
#include <gtest/gtest.h>

#include <string>

#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

TEST(DenseCli, MissingWorkspaceIsABadInputNamingIt) {
  TempDir dir;
  const auto r = RunCandi("dense " + dir.File("nowhere") + " -o " + dir.File("d.ply"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("nowhere"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir.File("d.ply")));
}

TEST(DenseCli, BadOptionsAreUsageErrors) {
  TempDir dir;
  EXPECT_EQ(RunCandi("dense " + dir.path() + " -o " + dir.File("d.ply") + " --resolution-scale 0").code, 1);
  EXPECT_EQ(RunCandi("dense " + dir.path() + " -o " + dir.File("d.ply") + " --iterations 0").code, 1);
  EXPECT_EQ(RunCandi("dense " + dir.path() + " -o " + dir.File("d.ply") + " --window 0").code, 1);
  EXPECT_EQ(RunCandi("dense " + dir.path() + " -o " + dir.File("d.unknown")).code, 2);
  EXPECT_FALSE(FileExists(dir.File("d.ply")));
}

}  // namespace
}  // namespace candi::testing
