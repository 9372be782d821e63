// End-to-end tests of `candi register`: a real run at survey coordinates, the printed figures,
// the output's shift and precision, the transform JSON, exit codes.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <string>

#include "core/transform.h"
#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/surface_cloud.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

using Result = CommandResult;

const Eigen::Vector3d kScanSite(416000.0, 9168000.0, 250.0);

// The truth: 1.5 degrees about the vertical through the site's centre and a few centimetres.
Rigid3 Truth() {
  const Eigen::Vector3d centre = kScanSite + Eigen::Vector3d(5, 5, 0);
  const Eigen::Quaterniond q(Eigen::AngleAxisd(1.5 * M_PI / 180, Eigen::Vector3d::UnitZ()));
  return Rigid3(q, centre - q * centre + Eigen::Vector3d(0.07, -0.05, 0.03));
}

// fixed.ply (double, shift kScanSite) and moving.ply (float, its own shift), 8000 points each.
void WriteClouds(const TempDir& dir) {
  testing::SurfaceCloudSpec f, m;
  f.count = m.count = 8000;
  f.seed = 1;
  m.seed = 2;
  f.origin = m.origin = kScanSite;
  io::WritePointCloud(dir.File("fixed.ply"), testing::SurfaceCloud(f));
  PointCloud moving = testing::SurfaceCloud(m);
  const Rigid3 inverse = Truth().Inverse();
  for (size_t i = 0; i < moving.size(); ++i) {
    moving.positions[i] = inverse * moving.WorldPosition(i) - moving.frame.origin;
  }
  moving.schema.position_type = ScalarType::kFloat32;
  io::PointWriteOptions o;
  o.precision = io::PositionPrecision::kFloat32;
  io::WritePointCloud(dir.File("moving.ply"), moving, o);
}

TEST(RegisterCli, RecoversTheMotionPrintsFiguresAndKeepsShiftAndPrecision) {
  TempDir dir;
  WriteClouds(dir);
  const Result r = RunCandi("register " + dir.File("moving.ply") + " " + dir.File("fixed.ply") +
                            " -o " + dir.File("out.ply") + " --max-distance 0.3 --transform-out " +
                            dir.File("t.json"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.out.find("status converged"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("RMS before"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("overlap before"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("fixed_from_moving"), std::string::npos) << r.out;
  const nlohmann::json j = nlohmann::json::parse(ReadBytes(dir.File("t.json")));
  Eigen::Matrix4d m;
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) m(a, b) = j["fixed_from_moving"][a][b].get<double>();
  }
  const Eigen::Matrix4d truth = Truth().ToMatrix();
  const Eigen::Vector4d x = (kScanSite + Eigen::Vector3d(10, 10, 0)).homogeneous();
  EXPECT_LT((m * x - truth * x).norm(), 2e-3);
  EXPECT_LT(j["rms_after_m"].get<double>(), j["rms_before_m"].get<double>());
  EXPECT_GT(j["overlap_after"].get<double>(), 0.95);
  const PointCloud in = io::ReadPointCloud(dir.File("moving.ply"));
  const PointCloud out = io::ReadPointCloud(dir.File("out.ply"));
  ASSERT_EQ(out.size(), in.size());
  EXPECT_EQ(out.frame, in.frame);
  // Colours, normals, layer, id kept; the writer may widen float positions to double when the
  // moved values are not exact in float (its lossless policy), so precision is not compared.
  PointSchema expected = in.schema;
  expected.position_type = out.schema.position_type;
  EXPECT_EQ(out.schema, expected);
  EXPECT_LT((out.WorldPosition(0) - Truth() * in.WorldPosition(0)).norm(), 2e-3);
  // The JSON is accepted as an initial transform: ICP then starts at the answer.
  const Result again = RunCandi("-q register " + dir.File("moving.ply") + " " +
                                dir.File("fixed.ply") + " -o " + dir.File("again.ply") +
                                " --method point --initial " + dir.File("t.json"));
  ASSERT_EQ(again.code, 0) << again.output;
  EXPECT_TRUE(again.out.find("overlap before 9") != std::string::npos ||
              again.out.find("overlap before 100") != std::string::npos)
      << again.out;
}

TEST(RegisterCli, MissingInputIsExitTwoNamingIt) {
  TempDir dir;
  WriteClouds(dir);
  const Result r = RunCandi("register " + dir.File("nope.ply") + " " + dir.File("fixed.ply") +
                            " -o " + dir.File("out.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find(dir.File("nope.ply")), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir.File("out.ply")));
}

TEST(RegisterCli, BadOptionValuesAreExitOne) {
  TempDir dir;
  const std::string base = "register a.ply b.ply -o " + dir.File("out.ply");
  for (const char* bad : {" --max-distance 0", " --max-distance -1", " --iterations 0",
                          " --method planar", " --voxel -0.1", " --iterations x"}) {
    const Result r = RunCandi(base + bad);
    EXPECT_EQ(r.code, 1) << bad << ": " << r.output;
  }
}

TEST(RegisterCli, UnwritableOutputFolderAndNoOverlapAreExitTwo) {
  TempDir dir;
  WriteClouds(dir);
  const std::string inputs = dir.File("moving.ply") + " " + dir.File("fixed.ply");
  const Result r = RunCandi("register " + inputs + " -o " + dir.File("no/such/dir/out.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("does not exist"), std::string::npos) << r.output;
  TempDir other;
  testing::SurfaceCloudSpec s;
  s.count = 500;
  s.origin = kScanSite + Eigen::Vector3d(1000, 0, 0);
  io::WritePointCloud(other.File("away.ply"), testing::SurfaceCloud(s));
  const Result none = RunCandi("register " + other.File("away.ply") + " " + dir.File("fixed.ply") +
                               " -o " + dir.File("out2.ply"));
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.output.find("no overlap"), std::string::npos) << none.output;
  EXPECT_FALSE(FileExists(dir.File("out2.ply")));
}

}  // namespace
}  // namespace candi::testing
