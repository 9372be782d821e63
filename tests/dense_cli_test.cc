// `candi dense`: exit codes and messages for bad input; the run on the synthetic workspace, again
// (everything found finished) and under mpirun on two ranks, the same points.
#include <gtest/gtest.h>

#include <string>

#include "io/point_io.h"
#include "reconstruction/photogrammetry/scenes/synthetic_views.h"
#include "reconstruction/photogrammetry/scenes/synthetic_workspace.h"

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

std::string SyntheticWorkspace(const TempDir& dir, const std::string& name) {
  static const std::vector<photogrammetry::SyntheticView> views = [] {
    photogrammetry::SyntheticViewsOptions o;
    o.views = 6;
    o.width = 120;
    o.height = 90;
    return photogrammetry::RenderSyntheticViews(o);
  }();
  photogrammetry::WriteDenseWorkspace(views, photogrammetry::SyntheticSparsePoints(views, 8), dir.File(name));
  return dir.File(name);
}

void ExpectSamePoints(const std::string& a, const std::string& b) {
  const PointCloud x = io::ReadPointCloud(a), y = io::ReadPointCloud(b);
  ASSERT_EQ(x.size(), y.size());
  for (size_t i = 0; i < x.size(); ++i) {
    ASSERT_EQ(x.WorldPosition(i), y.WorldPosition(i)) << i;
    ASSERT_EQ(x.colors[i], y.colors[i]) << i;
    ASSERT_EQ(x.normals[i], y.normals[i]) << i;
  }
}

TEST(DenseCli, ARunAgainFindsEverythingFinishedAndTwoRanksMakeTheSamePoints) {
  TempDir dir;
  const std::string ws = SyntheticWorkspace(dir, "ws");
  const std::string args = " --iterations 2 --threads 1 --max-memory 64";
  const auto first = RunCandi("dense " + ws + " -o " + dir.File("a.ply") + args);
  ASSERT_EQ(first.code, 0) << first.output;
  EXPECT_NE(first.output.find("stereo: 6 depth maps made, 0 found finished"), std::string::npos) << first.output;
  EXPECT_NE(first.output.find("sources from the tracks"), std::string::npos) << first.output;
  EXPECT_TRUE(FileExists(ws + "/stereo/patch-match.cfg"));
  const auto again = RunCandi("dense " + ws + " -o " + dir.File("b.ply") + args);
  ASSERT_EQ(again.code, 0) << again.output;
  EXPECT_NE(again.output.find("6 of 6 depth maps found finished"), std::string::npos) << again.output;
  EXPECT_NE(again.output.find("stereo: 0 depth maps made, 6 found finished"), std::string::npos) << again.output;
  EXPECT_EQ(ReadBytes(dir.File("a.ply")), ReadBytes(dir.File("b.ply")));
  if (!OnPath("mpirun")) {
    std::printf("mpirun not installed (Debian: openmpi-bin): two ranks not run\n");
    return;
  }
  const std::string ws2 = SyntheticWorkspace(dir, "ws2");
  const auto ranks = RunCommand("mpirun --oversubscribe --allow-run-as-root -np 2 " CANDI_EXECUTABLE " dense " + ws2 +
                                " -o " + dir.File("c.ply") + args + " 2>&1");
  ASSERT_EQ(ranks.code, 0) << ranks.output;
  ExpectSamePoints(dir.File("a.ply"), dir.File("c.ply"));
  // Each rank made its share: 3 photos each, 6 in all.
  EXPECT_NE(ranks.output.find("stereo: 6 depth maps made"), std::string::npos) << ranks.output;
}

}  // namespace
}  // namespace candi::testing
