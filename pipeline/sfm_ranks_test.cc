// candi sfm without mpirun: the run in this process, its failures thrown as they come; the chunk
// jobs as rank 0 hands them out. Under mpirun the ranks' share is tested end to end by
// tests/sfm_cli_test.cc (the same model bytes on one and two ranks).
#include "pipeline/sfm_ranks.h"

#include <gtest/gtest.h>

#include "core/check.h"
#include "tests/util/test_util.h"

namespace candi::pipeline {
namespace {

TEST(SfmRanks, ChunkJobsCrossAsTheyAre) {
  std::vector<photogrammetry::ChunkMapperJob> jobs = {
      {"s1", {"colmap", "mapper", "--image_list_path", "/w/chunks/s1.txt"}, "/w/logs/mapper_s1.log"},
      {"a b\"\\", {"/opt/colmap 3.8/colmap", "--output_path", "/w s/sparse_chunks/a b"}, "/w s/logs/x.log"}};
  const std::vector<photogrammetry::ChunkMapperJob> back = ChunkJobsFromText(ChunkJobsToText(jobs));
  ASSERT_EQ(back.size(), jobs.size());
  for (size_t k = 0; k < jobs.size(); ++k) {
    EXPECT_EQ(back[k].chunk, jobs[k].chunk);
    EXPECT_EQ(back[k].argv, jobs[k].argv);
    EXPECT_EQ(back[k].log, jobs[k].log);
  }
  EXPECT_TRUE(ChunkJobsFromText(ChunkJobsToText({})).empty());
}

TEST(SfmRanks, WithoutMpirunTheRunIsThisProcesssAndItsFailureIsThrown) {
  testing::TempDir dir;
  photogrammetry::SfmOptions o;
  RanksReporting reporting;
  reporting.describe = [](std::exception_ptr) { return std::pair<int, std::string>(9, "not used"); };
  EXPECT_THROW(StructureFromMotionOnRanks(o, dir.File("no_photos_here"), dir.File("work"), reporting), InputError);
}

}  // namespace
}  // namespace candi::pipeline
