// `candi sfm`: exit codes and messages of the cases that need no COLMAP run; a campaign mapped in
// chunks is the same bytes on one thread and process as on two threads and two MPI ranks.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

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
  Put(dir.File("in/a.jpg"), "a");
  Put(dir.File("in/b.jpg"), "b");
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
  Put(dir.File("in/a.jpg"), "a");
  Put(dir.File("in/b.jpg"), "b");
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
  EXPECT_NE(p.output.find("lacks the column 'H'"), std::string::npos) << p.output;
  const auto positional = RunCandi("sfm " + dir.File("in") + " -o " + dir.File("ws4") + " --matching positional");
  EXPECT_EQ(positional.code, 1) << positional.output;
  EXPECT_NE(positional.output.find("priors"), std::string::npos) << positional.output;
  const auto both = RunCandi("sfm " + dir.File("in") + " -o " + dir.File("ws5") + " --resume --overwrite");
  EXPECT_EQ(both.code, 1) << both.output;
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

// Mapped in chunks (each session's mapper apart, tied by the targets), the model is the same bytes
// with one thread and one process as with two threads and, under mpirun, the chunks shared out over
// two ranks (rank 1 maps s2); without mpirun, two threads and two mappers at once. The 60 photos of
// 320 px in three sessions of RunSfm's chunked test; about a minute a run.
TEST(SfmCli, AChunkedCampaignIsTheSameBytesOnOneAndTwoThreadsAndRanks) {
  if (!OnPath("colmap")) GTEST_SKIP() << "COLMAP is not installed (scripts/deps.sh installs it)";
  TempDir dir;
  const std::string site = dir.File("site");
  const auto made = RunCandi("campaign " + site + " --photos 60 --size 320 --chunks 3 -q");
  ASSERT_EQ(made.code, 0) << made.output;
  const std::string chunked = " --targets " + site + "/targets.csv --picks " + site + "/picks.csv";
  const auto one = RunCandi("sfm " + site + " -o " + dir.File("one") + chunked + " --threads 1 --chunk-parallel 1");
  ASSERT_EQ(one.code, 0) << one.output;
  EXPECT_NE(one.output.find("images registered / total    60 / 60"), std::string::npos) << one.output;
  if (OnPath("mpirun")) {
    const auto ranks = RunCommand(MpirunCandi(2) + " sfm " + site + " -o " + dir.File("two") + chunked +
                                  " --threads 2 --chunk-parallel 1");
    ASSERT_EQ(ranks.code, 0) << ranks.output;
    EXPECT_EQ(ReadBytes(dir.File("two/logs/mapper_s2.log")).rfind("# rank 1 of 2\n", 0), 0u)
        << "chunk s2 is mapped by rank 1";
    EXPECT_EQ(ReadBytes(dir.File("two/logs/mapper_s3.log")).rfind("# rank 0 of 2\n", 0), 0u);
  } else {
    std::printf("mpirun not installed (Debian: openmpi-bin): two threads, two mappers at once\n");
    const auto two = RunCandi("sfm " + site + " -o " + dir.File("two") + chunked + " --threads 2 --chunk-parallel 2");
    ASSERT_EQ(two.code, 0) << two.output;
  }
  for (const char* f : {"sparse/merged/cameras.bin", "sparse/merged/images.bin", "sparse/merged/points3D.bin",
                        "sparse_chunks/s1/0/images.bin", "sparse_chunks/s2/0/points3D.bin",
                        "sparse_chunks/s3/0/images.bin", "matches.txt",
                        "transitive_matches/round_1.txt"}) {
    const std::string a = ReadBytes(dir.File(std::string("one/") + f));
    EXPECT_FALSE(a.empty()) << f;
    EXPECT_TRUE(a == ReadBytes(dir.File(std::string("two/") + f))) << f << " differs between the runs";
  }
}

}  // namespace
}  // namespace candi::testing
