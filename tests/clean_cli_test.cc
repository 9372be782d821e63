// End-to-end tests of `candi clean`: counts printed, fields and shift kept, exit codes.
#include <gtest/gtest.h>

#include <string>

#include "core/rng.h"
#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/surface_cloud.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

using Result = CommandResult;

// 6000 surface points at survey coordinates plus 30 points 1 m off the surface (id >= 1e6).
void WriteNoisy(const std::string& path) {
  testing::SurfaceCloudSpec s;
  s.count = 6000;
  s.origin = Eigen::Vector3d(416000.0, 9168000.0, 250.0);
  PointCloud c = testing::SurfaceCloud(s);
  Rng rng(11);
  for (size_t k = 0; k < 30; ++k) {
    const size_t i = c.size();
    c.Resize(i + 1);
    const double x = rng.Uniform(0, 10), y = rng.Uniform(0, 10);
    c.positions[i] = Eigen::Vector3d(x, y, testing::SurfaceHeight(x, y) + 1.0);
    c.scalars[0].f64[i] = 1e6 + static_cast<double>(k);
  }
  io::WritePointCloud(path, c);
}

TEST(CleanCli, RemovesOutliersThinsAndKeepsFieldsAndShift) {
  TempDir dir;
  WriteNoisy(dir.File("in.ply"));
  const Result r = RunCandi("clean " + dir.File("in.ply") + " -o " + dir.File("out.ply") +
                            " --voxel 0.2");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.out.find("points in"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("removed: outliers"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("removed: voxel 0.2 m"), std::string::npos) << r.out;
  const PointCloud in = io::ReadPointCloud(dir.File("in.ply"));
  const PointCloud out = io::ReadPointCloud(dir.File("out.ply"));
  EXPECT_EQ(out.frame, in.frame);
  EXPECT_EQ(out.schema, in.schema);
  ASSERT_GT(out.size(), 1000u);
  EXPECT_LT(out.size(), 2600u);  // 10 x 10 m at 0.2 m: at most 50 x 50 columns (+ 2 layers)
  const ScalarField* id = out.FindScalar("id");
  ASSERT_NE(id, nullptr);
  for (size_t i = 0; i < out.size(); ++i) {
    ASSERT_LT(id->Get(i), 1e6) << "an outlier survived";
    const size_t j = static_cast<size_t>(id->Get(i));
    ASSERT_EQ(out.positions[i], in.positions[j]);
    ASSERT_EQ(out.colors[i], in.colors[j]);
  }
  const Result plain = RunCandi("-q clean " + dir.File("in.ply") + " -o " + dir.File("p.xyz") +
                                " --no-sor");
  ASSERT_EQ(plain.code, 0) << plain.output;
  EXPECT_EQ(io::ReadPointCloud(dir.File("p.xyz")).size(), in.size());
}

TEST(CleanCli, MissingInputIsExitTwoNamingIt) {
  TempDir dir;
  const Result r = RunCandi("clean " + dir.File("nope.las") + " -o " + dir.File("out.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find(dir.File("nope.las")), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir.File("out.ply")));
}

TEST(CleanCli, BadOptionValuesAreExitOne) {
  TempDir dir;
  for (const char* bad : {" --sor-k 0", " --sor-std 0", " --voxel -1", " --sor-k many"}) {
    const Result r = RunCandi("clean in.ply -o " + dir.File("out.ply") + bad);
    EXPECT_EQ(r.code, 1) << bad << ": " << r.output;
  }
}

TEST(CleanCli, UnwritableOutputFolderIsExitTwo) {
  TempDir dir;
  WriteNoisy(dir.File("in.ply"));
  const Result r = RunCandi("clean " + dir.File("in.ply") + " -o " + dir.File("no/dir/out.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("does not exist"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace candi::testing
