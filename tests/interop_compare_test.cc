// `candi compare` against CloudCompare 2.11 (Debian's `cloudcompare`, its command line with
// QT_QPA_PLATFORM=offscreen) on the same files at survey coordinates (E 416000, N 9168000): C2C
// distances equal within float rounding, C2M within 0.1 mm, and the report, the JSON summary and
// the fields in PLY and LAS extra bytes. CloudCompare computes in float after its global shift
// (we give it the shift, so its float coordinates span metres, not kilometres); candi in double
// about its own origin. Debian's CloudCompare has no M3C2 plugin: M3C2 is checked against the
// paper's formulas in compare/deviation_test.cc. Skips, naming the package, without CloudCompare.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/rng.h"
#include "io/ply/ply_io.h"
#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

const Eigen::Vector3d kCompareSite(416000.0, 9168000.0, 100.0);
constexpr char kShift[] = "-GLOBAL_SHIFT -416000 -9168000 -100 ";

double Height(double x, double y) { return 0.3 * std::sin(0.7 * x) + 0.2 * std::cos(0.9 * y); }

// Points on the surface z = Height(x, y) over [0, size]^2 plus `offset` and uniform noise.
PointCloud Surface(int count, double size, double offset, double noise, uint64_t seed) {
  Rng rng(seed);
  PointCloud c;
  for (int i = 0; i < count; ++i) {
    const double x = rng.Uniform(0, size), y = rng.Uniform(0, size);
    c.positions.push_back(kCompareSite + Eigen::Vector3d(x, y, Height(x, y) + offset +
                                                           noise * (2 * rng.Uniform() - 1)));
  }
  return c;
}

bool HaveCloudCompare() { return RunCommand("command -v CloudCompare >/dev/null").code == 0; }

#define REQUIRE_CLOUDCOMPARE()                                                                  \
  if (!HaveCloudCompare()) {                                                                    \
    GTEST_SKIP() << "'CloudCompare' is not installed (Debian package cloudcompare; "            \
                    "scripts/deps.sh installs it); skipping";                                   \
  }

// Runs CloudCompare on `compared` and `reference` with `operation`, saving the compared cloud
// with its distances to `saved` (PLY; for C2C a second name, for the reference cloud, follows);
// returns the field `field` of the first, in point order.
std::vector<double> CloudCompareDistances(const std::string& compared, const std::string& reference,
                                          const std::string& operation, const std::string& saved,
                                          const std::string& field) {
  const std::string command =
      "timeout 300 env QT_QPA_PLATFORM=offscreen CloudCompare -SILENT -NO_TIMESTAMP -AUTO_SAVE OFF "
      "-C_EXPORT_FMT PLY -O " + std::string(kShift) + compared + " -O " + kShift + reference + " " +
      operation + " -SAVE_CLOUDS FILE \"" + saved + "\"";
  const CommandResult r = RunCommand(command);
  EXPECT_EQ(r.code, 0) << command << "\n" << r.output;
  const PointCloud c = io::ReadPointCloud(saved.substr(0, saved.find(' ')));
  const ScalarField* f = c.FindScalar(field);
  std::vector<double> out;
  if (!f) {
    ADD_FAILURE() << saved << " has no field " << field << "\n" << r.output;
    return out;
  }
  for (size_t i = 0; i < c.size(); ++i) out.push_back(f->Get(i));
  return out;
}

std::vector<double> CandiDistances(const std::string& path) {
  const PointCloud c = io::ReadPointCloud(path);
  const ScalarField* f = c.FindScalar("distance");
  std::vector<double> out;
  if (!f) {
    ADD_FAILURE() << path << " has no field distance";
    return out;
  }
  for (size_t i = 0; i < c.size(); ++i) out.push_back(f->Get(i));
  return out;
}

TEST(InteropCompare, C2cEqualsCloudCompareWithinFloatRounding) {
  REQUIRE_CLOUDCOMPARE();
  TempDir dir;
  io::WritePointCloud(dir.File("ref.ply"), Surface(40000, 8, 0, 0.002, 1));
  io::WritePointCloud(dir.File("cmp.ply"), Surface(20000, 8, 0.004, 0.002, 2));
  const CommandResult r = RunCandi("-q compare " + dir.File("ref.ply") + " " + dir.File("cmp.ply") +
                                   " -o " + dir.File("out.ply"));
  ASSERT_EQ(r.code, 0) << r.output;
  const std::vector<double> candi = CandiDistances(dir.File("out.ply"));
  const std::vector<double> cc = CloudCompareDistances(dir.File("cmp.ply"), dir.File("ref.ply"), "-C2C_DIST",
                                                       dir.File("cc.ply") + " " + dir.File("cc_ref.ply"),
                                                       "C2C_absolute_distances");
  ASSERT_EQ(candi.size(), 20000u);
  ASSERT_EQ(cc.size(), candi.size());
  // CloudCompare's coordinates are float within ~8 m of its shift: an ulp is 2^-23 * 8 m ~ 1 um;
  // a distance from differences of such coordinates is good to a few of them. candi's "distance"
  // field is float too (an ulp of a 1 cm distance is 1e-9 m).
  const double tolerance = 8 * std::ldexp(1.0, -23) * 8.0;
  double worst = 0, mean_candi = 0, mean_cc = 0;
  for (size_t i = 0; i < candi.size(); ++i) {
    worst = std::max(worst, std::abs(candi[i] - cc[i]));
    mean_candi += candi[i] / candi.size();
    mean_cc += cc[i] / cc.size();
  }
  EXPECT_LT(worst, tolerance) << "largest difference " << worst << " m";
  EXPECT_NEAR(mean_candi, mean_cc, 1e-7);
  EXPECT_GT(mean_candi, 0.001);  // the distances are not all zero
  // The summary says the same mean.
  const nlohmann::json summary = nlohmann::json::parse(ReadBytes(dir.File("out.ply.compare.json")));
  EXPECT_NEAR(summary["mean_m"].get<double>(), mean_candi, 1e-6);
  EXPECT_EQ(summary["count"], 20000);
  EXPECT_TRUE(FileExists(dir.File("out.ply.histogram.svg")));
  EXPECT_NE(ReadBytes(dir.File("out.ply.report.md")).find("out.ply.histogram.svg"), std::string::npos);
}

TEST(InteropCompare, C2mEqualsCloudCompareWithinATenthOfAMillimetre) {
  REQUIRE_CLOUDCOMPARE();
  TempDir dir;
  // A height-field mesh at 0.2 m, double coordinates at the site.
  TriMesh mesh;
  const int n = 41;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double x = 0.2 * i, y = 0.2 * j;
      mesh.vertices.positions.push_back(kCompareSite + Eigen::Vector3d(x, y, Height(x, y)));
    }
  }
  for (int i = 0; i + 1 < n; ++i) {
    for (int j = 0; j + 1 < n; ++j) {
      const uint32_t a = static_cast<uint32_t>(i * n + j), b = a + n;
      mesh.faces.push_back({a, b, a + 1});
      mesh.faces.push_back({a + 1, b, b + 1});
    }
  }
  io::WritePlyMesh(dir.File("mesh.ply"), mesh);
  io::WritePointCloud(dir.File("cmp.ply"), Surface(20000, 8, 0.0, 0.05, 3));
  const CommandResult r = RunCandi("-q compare " + dir.File("mesh.ply") + " " + dir.File("cmp.ply") +
                                   " -o " + dir.File("out.las") + " --method c2m");
  ASSERT_EQ(r.code, 0) << r.output;
  // LAS: the distance in an extra-bytes field, the points in their order.
  const std::vector<double> candi = CandiDistances(dir.File("out.las"));
  const std::vector<double> cc = CloudCompareDistances(dir.File("cmp.ply"), dir.File("mesh.ply"), "-C2M_DIST",
                                                       dir.File("cc.ply"), "C2M_signed_distances");
  ASSERT_EQ(candi.size(), 20000u);
  ASSERT_EQ(cc.size(), candi.size());
  double worst = 0;
  size_t negative = 0;
  for (size_t i = 0; i < candi.size(); ++i) {
    worst = std::max(worst, std::abs(candi[i] - cc[i]));
    negative += candi[i] < 0 ? 1 : 0;
  }
  EXPECT_LT(worst, 1e-4) << "largest difference " << worst << " m";
  EXPECT_GT(negative, 5000u);  // both signs occur
  EXPECT_LT(negative, 15000u);
}

TEST(InteropCompare, BadInputIsNamedAndNothingIsWritten) {
  TempDir dir;
  io::WritePointCloud(dir.File("ref.ply"), Surface(1000, 4, 0, 0.002, 4));
  WriteBytes(dir.File("empty.xyz"), "");
  CommandResult r = RunCandi("-q compare " + dir.File("ref.ply") + " " + dir.File("empty.xyz") + " -o " +
                             dir.File("out.ply") + " --columns x,y,z");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("empty.xyz"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir.File("out.ply")));
  // A point cloud given as the mesh for C2M: it has no faces.
  r = RunCandi("-q compare " + dir.File("ref.ply") + " " + dir.File("ref.ply") + " -o " + dir.File("out.ply") +
               " --method c2m");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("no faces"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir.File("out.ply")));
  r = RunCandi("-q compare " + dir.File("ref.ply") + " " + dir.File("ref.ply") + " -o " + dir.File("out.ply") +
               " --method m3c2 --min-points 1");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("min-points"), std::string::npos) << r.output;
  // An existing output is replaced only when the comparison succeeded.
  WriteBytes(dir.File("keep.ply"), "not replaced");
  r = RunCandi("-q compare " + dir.File("missing.ply") + " " + dir.File("ref.ply") + " -o " + dir.File("keep.ply"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_EQ(ReadBytes(dir.File("keep.ply")), "not replaced");
}

}  // namespace
}  // namespace candi::testing
