// End-to-end tests of `candi georef`: a point file georeferenced with targets (a blunder flagged,
// survey coordinates kept to the millimetre), two chunks tied into one frame, exit codes and messages.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "core/rng.h"
#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

using Result = CommandResult;
using V = Eigen::Vector3d;

const V kSite(416000.0, 9168000.0, 265.0);  // UTM 49S near Borobudur

// model = s R survey + t for a chunk: each chunk has its own unknown similarity.
struct Chunk {
  double s;
  Eigen::Quaterniond r;
  V t;
  V Model(const V& survey) const { return s * (r * (survey - kSite)) + t; }
};

const Chunk kChunkA{0.1, Eigen::Quaterniond(Eigen::AngleAxisd(0.8, V(0.1, -0.2, 1).normalized())), V(3, -2, 1)};
const Chunk kChunkB{2.5, Eigen::Quaterniond(Eigen::AngleAxisd(-2.0, V(0.3, 0.1, 1).normalized())), V(-40, 7, 12)};

std::vector<V> Surveyed(int n) {
  Rng rng(42);
  std::vector<V> p;
  for (int i = 0; i < n; ++i) p.push_back(kSite + V(rng.Uniform(-60, 60), rng.Uniform(-60, 60), rng.Uniform(0, 35)));
  return p;
}

// Targets CSV for a chunk: 9 control and 3 check targets, 1 mm noise; `blunder` adds 0.5 m to one.
std::string TargetsCsv(const Chunk& chunk, int blunder = -1) {
  const std::vector<V> survey = Surveyed(12);
  Rng rng(7);
  std::string csv = "name,E,N,H,role,accuracy,x,y,z\n";
  char line[256];
  for (int i = 0; i < 12; ++i) {
    V noisy = survey[i] + 0.001 * V(rng.Normal(), rng.Normal(), rng.Normal());
    if (i == blunder) noisy.z() += 0.5;
    const V m = chunk.Model(noisy);
    std::snprintf(line, sizeof(line), "P%d,%.4f,%.4f,%.4f,%s,0.003,%.9f,%.9f,%.9f\n", i,
                  survey[i].x(), survey[i].y(), survey[i].z(), i < 9 ? "control" : "check",
                  m.x(), m.y(), m.z());
    csv += line;
  }
  return csv;
}

// The same 50 surface points (the chunks' overlap) in a chunk's model frame.
std::vector<V> Overlap() {
  Rng rng(9);
  std::vector<V> p;
  for (int i = 0; i < 50; ++i) p.push_back(kSite + V(rng.Uniform(-10, 10), rng.Uniform(-10, 10), rng.Uniform(0, 30)));
  return p;
}

void WriteChunk(const std::string& path, const Chunk& chunk) {
  PointCloud cloud;
  for (const V& w : Overlap()) cloud.positions.push_back(chunk.Model(w));
  io::WritePointCloud(path, cloud);
}

std::string TargetRow(const std::string& out, const std::string& name) {
  const size_t at = out.find("\n" + name + " ");
  return at == std::string::npos ? "" : out.substr(at + 1, out.find('\n', at + 1) - at - 1);
}

TEST(GeorefCli, FlagsTheBlunderAndWritesSurveyCoordinatesWithTheShift) {
  TempDir dir;
  WriteBytes(dir.File("t.csv"), TargetsCsv(kChunkA, 4));
  WriteChunk(dir.File("a.ply"), kChunkA);
  const Result r = RunCandi("georef " + dir.File("a.ply") + " --targets " + dir.File("t.csv") +
                            " -o " + dir.File("a_utm.ply"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(TargetRow(r.out, "P4").find("OUTLIER"), std::string::npos) << r.out;
  EXPECT_NE(TargetRow(r.out, "P3").find(" ok"), std::string::npos) << r.out;
  EXPECT_NE(TargetRow(r.out, "P10").find("check"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("control (outliers out)"), std::string::npos);
  const PointCloud out = io::ReadPointCloud(dir.File("a_utm.ply"));
  EXPECT_EQ(out.frame.origin, V(416000, 9168000, 300));
  const std::vector<V> truth = Overlap();
  ASSERT_EQ(out.size(), truth.size());
  for (size_t i = 0; i < truth.size(); ++i) EXPECT_LT((out.WorldPosition(i) - truth[i]).norm(), 0.003) << i;
  const nlohmann::json j = nlohmann::json::parse(ReadBytes(dir.File("a_utm.ply.georef.json")));
  EXPECT_NEAR(j["survey_from_model"]["scale"].get<double>(), 10.0, 0.001);
  EXPECT_EQ(j["shift"][1].get<double>(), 9168000.0);
  EXPECT_EQ(j["targets"][4]["outlier"].get<bool>(), true);
  EXPECT_LT(j["rmse"]["check"]["3d"].get<double>(), 0.005);
  EXPECT_EQ(j["rmse"]["control"]["count"].get<int>(), 8);
}

TEST(GeorefCli, TiesTwoChunksIntoOneFrame) {
  TempDir dir;
  for (const auto& [name, chunk] : {std::pair<std::string, Chunk>{"a", kChunkA}, {"b", kChunkB}}) {
    WriteBytes(dir.File(name + ".csv"), TargetsCsv(chunk));
    WriteChunk(dir.File(name + ".ply"), chunk);
    const Result r = RunCandi("-q georef " + dir.File(name + ".ply") + " --targets " +
                              dir.File(name + ".csv") + " -o " + dir.File(name + "_utm.ply") +
                              " --loss cauchy --loss-scale 0.02");
    ASSERT_EQ(r.code, 0) << r.output;
  }
  const PointCloud a = io::ReadPointCloud(dir.File("a_utm.ply")), b = io::ReadPointCloud(dir.File("b_utm.ply"));
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.frame, b.frame);
  for (size_t i = 0; i < a.size(); ++i) EXPECT_LT((a.positions[i] - b.positions[i]).norm(), 0.002) << i;
}

TEST(GeorefCli, BadInputsAndOptionsGiveClearErrorsAndExitCodes) {
  TempDir dir;
  WriteBytes(dir.File("t.csv"), TargetsCsv(kChunkA));
  WriteChunk(dir.File("a.ply"), kChunkA);
  const std::string base = "georef " + dir.File("a.ply") + " --targets " + dir.File("t.csv");
  Result r = RunCandi("georef " + dir.File("missing.ply") + " --targets " + dir.File("t.csv") +
                      " -o " + dir.File("o.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("missing.ply"), std::string::npos) << r.output;
  EXPECT_EQ(RunCandi(base + " -o " + dir.File("o.ply") + " --loss l1").code, 1);
  EXPECT_EQ(RunCandi(base + " -o " + dir.File("o.ply") + " --loss-scale -1").code, 1);
  EXPECT_EQ(RunCandi(base + " -o " + dir.File("o.ply") + " --outlier-threshold x").code, 1);
  EXPECT_EQ(RunCandi(base).code, 1);  // no -o
  r = RunCandi(base + " -o " + dir.File("no/such/folder/o.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("does not exist"), std::string::npos) << r.output;
  r = RunCandi(base + " -o " + dir.File("o.ply") + " --picks " + dir.File("t.csv"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("--picks needs"), std::string::npos) << r.output;
  WriteBytes(dir.File("bad.csv"), "name,E,N,H,role,accuracy,x,y,z\nP0,1,2,3,control,0.003,1,2,3\n"
                                  "P1,1,2,3,control,0.003,1,2,zz\n");
  r = RunCandi("georef " + dir.File("a.ply") + " --targets " + dir.File("bad.csv") + " -o " + dir.File("o.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("bad.csv: line 3: field 'z': 'zz' is not a finite number"), std::string::npos) << r.output;
  WriteBytes(dir.File("two.csv"), "name,E,N,H,role,accuracy,x,y,z\nP0,1,2,3,control,0.003,1,2,3\n"
                                  "P1,4,2,3,control,0.003,4,2,3\nP2,1,7,3,check,0.003,1,7,3\n");
  r = RunCandi("georef " + dir.File("a.ply") + " --targets " + dir.File("two.csv") + " -o " + dir.File("o.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("2 usable control targets"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir.File("o.ply")));
}

TEST(GeorefCli, ReportsACollinearLayout) {
  TempDir dir;
  std::string csv = "name,E,N,H,role,accuracy,x,y,z\n";
  char line[256];
  for (int i = 0; i < 5; ++i) {
    const V s = kSite + V(10.0 * i, 5.0 * i + 0.001 * (i % 2), 0.2 * i);
    const V m = kChunkA.Model(s);
    std::snprintf(line, sizeof(line), "L%d,%.4f,%.4f,%.4f,control,0.003,%.9f,%.9f,%.9f\n", i, s.x(), s.y(), s.z(), m.x(), m.y(), m.z());
    csv += line;
  }
  WriteBytes(dir.File("t.csv"), csv);
  WriteChunk(dir.File("a.ply"), kChunkA);
  const Result r = RunCandi("georef " + dir.File("a.ply") + " --targets " + dir.File("t.csv") + " -o " + dir.File("o.ply"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.out.find("warning: targets nearly collinear (s2/s1 = "), std::string::npos) << r.out;
}

}  // namespace
}  // namespace candi::testing
