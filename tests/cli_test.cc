// End-to-end tests of the `candi` command line: exit codes, messages, outputs.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/rng.h"
#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

using Result = CommandResult;

PointCloud SurveyCloud(size_t n) {
  PointCloud c;
  c.schema.colors = true;
  c.schema.scalars = {{"intensity", ScalarType::kFloat32}};
  c.SetSchema(c.schema);
  c.Resize(n);
  Rng rng(11);
  for (size_t i = 0; i < n; ++i) {
    c.positions[i] = Eigen::Vector3d(500000.123 + 0.001 * static_cast<double>(rng.Below(100000)),
                                     4500000.456 + 0.001 * static_cast<double>(rng.Below(100000)),
                                     100.789 + 0.001 * static_cast<double>(rng.Below(10000)));
    c.colors[i] = {static_cast<uint8_t>(i), 7, static_cast<uint8_t>(255 - i % 256)};
    c.scalars[0].f32[i] = static_cast<float>(i % 1000);
  }
  return c;
}

TEST(Cli, VersionHelpAndUsageErrors) {
  Result r = RunCandi("--version");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("candi 0."), std::string::npos);
  EXPECT_EQ(RunCandi("--help").code, 0);
  EXPECT_EQ(RunCandi("").code, 1) << "a subcommand is required";
  EXPECT_EQ(RunCandi("nosuchcommand").code, 1);
  r = RunCandi("convert a.ply b.ply --ply-encoding sideways");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("ply-encoding"), std::string::npos) << r.output;
  // Option values are checked before any file is touched.
  r = RunCandi("convert a.ply b.ply --las-scale -1");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("--las-scale '-1'"), std::string::npos) << r.output;
  EXPECT_EQ(RunCandi("convert a.ply b.ply --shift 1,2").code, 1);
}

// `candi --help` lists the commands in groups along a user's path, every command once.
TEST(Cli, HelpGroupsTheCommandsAlongTheUsersPath) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> expected = {
      {"Inspect and convert", {"info", "convert", "compare"}},
      {"Digitize",
       {"sfm", "dense", "georef", "register", "register-scans", "clean", "colorcorrect", "foundation", "relief"}},
      {"Assemble", {"build", "pack", "export"}},
      {"Look", {"render", "view", "publish", "section"}},
      {"Other", {"opacity", "demo", "campaign", "bench"}},
  };
  const Result r = RunCandi("--help");
  ASSERT_EQ(r.code, 0);
  // Sections are a heading line `Name:` and the indented lines up to a blank one.
  std::vector<std::pair<std::string, std::vector<std::string>>> groups;
  std::map<std::string, int> seen;
  std::istringstream in(r.out);
  std::string line, section;
  while (std::getline(in, line)) {
    if (line.empty()) {
      section.clear();
    } else if (line[0] != ' ' && line.back() == ':') {
      section = line.substr(0, line.size() - 1);
      if (section != "Options" && section != "Positionals") groups.push_back({section, {}});
    } else if (!section.empty() && section != "Options" && section != "Positionals" &&
               line.rfind("  ", 0) == 0 && line[2] != ' ' && line[2] != '-') {
      const std::string name = line.substr(2, line.find(' ', 2) - 2);
      groups.back().second.push_back(name);
      ++seen[name];
    }
  }
  EXPECT_EQ(groups, expected) << r.out;
  for (const auto& [name, count] : seen) {
    EXPECT_EQ(count, 1) << name << " is listed " << count << " times";
  }
  EXPECT_EQ(r.out.find("Subcommands:"), std::string::npos)
      << "a command outside the groups:\n" << r.out;
  // The usage line names `candi`, not the path it was run by (the reference docs are generated).
  EXPECT_NE(r.out.find("Usage: candi [OPTIONS] SUBCOMMAND"), std::string::npos) << r.out;
}

// Every command's help is answered by `candi` itself (relief and PCL commands too), the same text.
TEST(Cli, SubcommandHelpNamesTheWholeCommand) {
  for (const char* command : {"relief train", "bench relief", "register", "demo", "relief place"}) {
    const Result r = RunCandi(std::string(command) + " --help");
    EXPECT_EQ(r.code, 0) << command << ": " << r.output;
    EXPECT_NE(r.out.find(std::string("Usage: candi ") + command + " [OPTIONS]"), std::string::npos)
        << r.out;
  }
}

TEST(Cli, MissingInputIsExitTwoNamingTheFile) {
  TempDir dir;
  Result r = RunCandi("info " + dir.File("nope.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find(dir.File("nope.ply")), std::string::npos) << r.output;
  r = RunCandi("convert " + dir.File("nope.ply") + " " + dir.File("out.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_FALSE(FileExists(dir.File("out.ply")));
  // Only the error: no progress line for a conversion that never began.
  EXPECT_EQ(r.output.find(" -> "), std::string::npos) << r.output;
}

TEST(Cli, UnwritableOutputIsExitTwoAndCreatesNothing) {
  TempDir dir;
  io::WritePointCloud(dir.File("in.ply"), SurveyCloud(10));
  const Result r = RunCandi("convert " + dir.File("in.ply") + " " + dir.File("no/such/dir/out.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("no/such/dir/out.ply"), std::string::npos) << r.output;
}

TEST(Cli, BadInputLeavesTheEarlierOutputIntact) {
  TempDir dir;
  io::WritePointCloud(dir.File("good.ply"), SurveyCloud(10));
  RunCandi("convert " + dir.File("good.ply") + " " + dir.File("out.las"));
  const std::string before = ReadBytes(dir.File("out.las"));
  ASSERT_FALSE(before.empty());
  std::string bad = ReadBytes(dir.File("good.ply"));
  bad.resize(bad.size() - 7);
  WriteBytes(dir.File("bad.ply"), bad);
  const Result r = RunCandi("convert " + dir.File("bad.ply") + " " + dir.File("out.las"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("bad.ply"), std::string::npos) << r.output;
  EXPECT_EQ(ReadBytes(dir.File("out.las")), before);
}

TEST(Cli, RoundTripPlyLasXyzAtSurveyScale) {
  TempDir dir;
  const PointCloud cloud = SurveyCloud(2000);
  io::WritePointCloud(dir.File("a.ply"), cloud);
  ASSERT_EQ(RunCandi("-q convert " + dir.File("a.ply") + " " + dir.File("b.las") + " --las-scale 0.001").output, "");
  ASSERT_EQ(RunCandi("convert " + dir.File("b.las") + " " + dir.File("c.xyz") + " --shift auto").code, 0);
  EXPECT_TRUE(FileExists(dir.File("c.xyz.shift.json")));
  Result r = RunCandi("convert " + dir.File("c.xyz") + " " + dir.File("d.ply"));
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_EQ(RunCandi("convert " + dir.File("d.ply") + " " + dir.File("e.ply") + " --shift none").code, 0);
  const PointCloud las = io::ReadPointCloud(dir.File("b.las"));
  const PointCloud d = io::ReadPointCloud(dir.File("d.ply"));
  const PointCloud e = io::ReadPointCloud(dir.File("e.ply"));
  ASSERT_EQ(las.size(), cloud.size());
  ASSERT_EQ(d.size(), cloud.size());
  EXPECT_FALSE(d.frame.IsIdentity()) << "the shift travelled through XYZ's sidecar into PLY";
  EXPECT_TRUE(e.frame.IsIdentity());
  ASSERT_TRUE(e.schema.colors) << "colours survived the text step";
  ASSERT_NE(e.FindScalar("intensity"), nullptr);
  for (size_t i = 0; i < cloud.size(); ++i) {
    // LAS: within half the scale; after LAS, every text/double step is exact.
    ASSERT_LE((las.WorldPosition(i) - cloud.WorldPosition(i)).cwiseAbs().maxCoeff(), 0.0005 + 1e-9);
    ASSERT_EQ(d.WorldPosition(i), las.WorldPosition(i)) << i;
    ASSERT_EQ(e.WorldPosition(i), las.WorldPosition(i)) << i;
    ASSERT_EQ(e.colors[i], cloud.colors[i]);
    ASSERT_EQ(e.FindScalar("intensity")->Get(i), cloud.scalars[0].Get(i));
  }
}

TEST(Cli, InfoReportsCountBoundsFieldsAndJson) {
  TempDir dir;
  io::WritePointCloud(dir.File("a.ply"), SurveyCloud(100));
  Result r = RunCandi("info " + dir.File("a.ply"));
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("points    100"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("intensity"), std::string::npos);
  r = RunCandi("-q info --json " + dir.File("a.ply"));
  ASSERT_EQ(r.code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["points"], 100);
  EXPECT_GE(j["bounds"]["min"][0].get<double>(), 500000.123);
  EXPECT_LE(j["bounds"]["max"][1].get<double>(), 4500000.456 + 100.0);
}

TEST(Cli, RealFilesReportTheirCounts) {
  CANDI_REQUIRE_SHARED_DATA(autzen, "las/autzen_trim.las");
  Result r = RunCandi("-q info --json " + autzen);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(nlohmann::json::parse(r.out)["points"], 110000);
  CANDI_REQUIRE_SHARED_DATA(laz, "las/autzen_trim.laz");
  r = RunCandi("info " + laz);  // LAZ reads through the LAS reader
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("LAZ"), std::string::npos);
  CANDI_REQUIRE_SHARED_DATA(dxf, "dxf/bin_dxf_r2000.dxf");
  EXPECT_EQ(RunCandi("info " + dxf).code, 2);
}

TEST(Cli, ConvertToALazNameWritesLaz) {
  CANDI_REQUIRE_SHARED_DATA(autzen, "las/autzen_trim.las");
  TempDir dir;
  Result r = RunCandi("-q convert " + autzen + " " + dir.File("a.laz"));
  ASSERT_EQ(r.code, 0) << r.output;
  r = RunCandi("info " + dir.File("a.laz"));
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("LAZ: LAS 1.2 point format 3, LASzip 3.4r3, pointwise chunked"),
            std::string::npos)
      << r.output;
  r = RunCandi("-q info --json " + dir.File("a.laz"));
  EXPECT_EQ(nlohmann::json::parse(r.out)["points"], 110000);
  r = RunCandi("-q convert " + autzen + " /proc/candi_cli_test.laz");  // nowhere to write
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_FALSE(FileExists("/proc/candi_cli_test.laz"));
}

TEST(Cli, InfoWalksACopcFilesHierarchy) {
  CANDI_REQUIRE_SHARED_DATA(autzen, "las/autzen_trim.las");
  TempDir dir;
  Result r = RunCandi("-q convert " + autzen + " " + dir.File("a.copc.laz"));
  ASSERT_EQ(r.code, 0) << r.output;
  r = RunCandi("-q info --json " + dir.File("a.copc.laz"));
  ASSERT_EQ(r.code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.out);
  const auto& copc = j.at("copc");
  EXPECT_EQ(copc.at("points"), 110000);
  EXPECT_EQ(copc.at("nodes_by_level").at(0), 1);
  uint64_t nodes = 0, points = 0;
  for (const auto& n : copc.at("nodes_by_level")) nodes += n.get<uint64_t>();
  for (const auto& p : copc.at("points_by_level")) points += p.get<uint64_t>();
  EXPECT_EQ(nodes, copc.at("nodes").get<uint64_t>());
  EXPECT_EQ(points, 110000u);
  // The spacing halves a level from the root's, the cube's width / 128.
  EXPECT_DOUBLE_EQ(copc.at("spacing").get<double>(), 2 * copc.at("halfsize").get<double>() / 128);
  r = RunCandi("info " + dir.File("a.copc.laz"));
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("copc      COPC 1.0: " + std::to_string(nodes) + " nodes"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("[warning]"), std::string::npos) << r.output;
  // A root page past the file's end (the info VLR's root_hier_offset, 40 bytes into its payload
  // after LAS 1.4's 375-byte header and the VLR's 54): the points still read, with a warning.
  std::string bytes = ReadBytes(dir.File("a.copc.laz"));
  const uint64_t past = bytes.size() + 1000;
  for (int i = 0; i < 8; ++i) bytes[375 + 54 + 40 + i] = static_cast<char>(past >> (8 * i));
  WriteBytes(dir.File("b.copc.laz"), bytes);
  r = RunCandi("info " + dir.File("b.copc.laz"));
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("[warning] not a valid COPC hierarchy: " + dir.File("b.copc.laz") + ": byte " +
                          std::to_string(past)),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("points    110000"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("copc      COPC"), std::string::npos) << r.output;
  // Not COPC: no such line.
  r = RunCandi("-q info --json " + autzen);
  EXPECT_FALSE(nlohmann::json::parse(r.out).contains("copc"));
}

}  // namespace
}  // namespace candi::testing
