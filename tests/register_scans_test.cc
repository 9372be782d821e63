// `candi register-scans` end to end: scans that candi's virtual scanner makes of the courtyard
// (tests/util/scan_scene.h) at survey coordinates, written as point files in their scanner
// frames, start poses perturbed by 0.5 m and 5 degrees, registered by the command; the poses in
// registration.json and the moved scans against the truth; a scan with no overlap reported and
// left where it was; targets; bad input.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/rng.h"
#include "io/e57/e57_writer.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/registration/registration.h"
#include "reconstruction/photogrammetry/scenes/virtual_scanner.h"
#include "tests/run_candi.h"
#include "tests/util/rigid_json.h"
#include "tests/util/scan_scene.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

constexpr double kDeg = M_PI / 180.0;
const Eigen::Vector3d kOrigin(500000.0, 4000000.0, 120.0);

struct Scans {
  std::vector<Rigid3> truth, start;
  std::string args;  // the scan files, space separated
};

// `count` stations of the courtyard at kOrigin, scanned, written as s<i>.ply in scanner frames;
// every start pose but the first moved 0.5 m and turned 5 degrees (seeded).
Scans MakeScans(const TempDir& dir, int count) {
  Scans s;
  const TriMesh scene = CourtyardScene(kOrigin);
  s.truth = CourtyardStations(count, 10.5, kOrigin);
  Rng rng(11);
  for (int i = 0; i < count; ++i) {
    const std::string file = dir.File("s" + std::to_string(i) + ".ply");
    io::WritePointCloud(file, photogrammetry::ScanMesh(CourtyardScanner(200 + i), scene, s.truth[i]));
    s.args += " " + file;
    if (i == 0) {
      s.start.push_back(s.truth[0]);
      continue;
    }
    const Eigen::Vector3d dir3(rng.Normal(), rng.Normal(), rng.Normal()), axis(rng.Normal(), rng.Normal(), rng.Normal());
    s.start.emplace_back(Eigen::Quaterniond(Eigen::AngleAxisd(5 * kDeg, axis.normalized())) * s.truth[i].rotation,
                         s.truth[i].translation + 0.5 * dir3.normalized());
  }
  return s;
}

void WritePoses(const std::string& path, const std::vector<Rigid3>& poses) {
  nlohmann::json j = nlohmann::json::array();
  for (const Rigid3& p : poses) j.push_back(RigidJson(p));
  WriteBytes(path, j.dump());
}

constexpr char kFast[] = " --voxel 0.2 --icp-voxel 0.5";

TEST(RegisterScansCli, RecoversPerturbedStationsAtSurveyCoordinates) {
  TempDir dir;
  Scans s = MakeScans(dir, 5);
  // A sixth scan a kilometre away: it overlaps nothing.
  const TriMesh far_scene = CourtyardScene(kOrigin + Eigen::Vector3d(1000, 0, 0));
  const Rigid3 far_pose = CourtyardStations(1, 10.5, kOrigin + Eigen::Vector3d(1000, 0, 0))[0];
  io::WritePointCloud(dir.File("far.ply"), photogrammetry::ScanMesh(CourtyardScanner(300), far_scene, far_pose));
  s.args += " " + dir.File("far.ply");
  s.truth.push_back(far_pose);
  s.start.push_back(far_pose);
  WritePoses(dir.File("poses.json"), s.start);
  const CommandResult r =
      RunCandi("register-scans" + s.args + " -o " + dir.File("out") + " --poses " + dir.File("poses.json") + kFast);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("overlap no registered scan"), std::string::npos) << r.output;
  const nlohmann::json j = nlohmann::json::parse(ReadBytes(dir.File("out/registration.json")));
  ASSERT_EQ(j["scans"].size(), 6u);
  for (int i = 0; i < 5; ++i) {
    SCOPED_TRACE("scan " + std::to_string(i));
    EXPECT_TRUE(j["scans"][i]["connected"].get<bool>());
    const Rigid3 got = RigidFromJson(j["scans"][i]["world_from_scan"]);
    EXPECT_LT((got.translation - s.truth[i].translation).norm(), 0.002);
    EXPECT_LT(Eigen::AngleAxisd(got.rotation * s.truth[i].rotation.conjugate()).angle() / kDeg, 0.01);
  }
  EXPECT_FALSE(j["scans"][5]["connected"].get<bool>());
  EXPECT_EQ(j["scans"][0]["start_from"], "given (--poses)");  // where each start came from
  const Rigid3 kept = RigidFromJson(j["scans"][5]["world_from_scan"]);
  EXPECT_LT((kept.translation - far_pose.translation).norm(), 1e-6);
  EXPECT_FALSE(j["loops"].empty());
  for (const auto& loop : j["loops"]) EXPECT_LT(loop["translation_m"].get<double>(), 0.02);
  // The moved scan 3 lies where the truth puts it, millimetres kept at E 500000.
  const PointCloud moved = io::ReadPointCloud(dir.File("out/s3.ply"));
  const PointCloud raw = io::ReadPointCloud(dir.File("s3.ply"));
  ASSERT_EQ(moved.size(), raw.size());
  double worst = 0;
  for (size_t i = 0; i < raw.size(); i += 97) {
    worst = std::max(worst, (moved.WorldPosition(i) - s.truth[3] * raw.WorldPosition(i)).norm());
  }
  EXPECT_LT(worst, 0.003);
  EXPECT_GT(moved.WorldPosition(0).x(), 499000);
}

TEST(RegisterScansCli, ControlTargetsTieTheBlockToTheSurvey) {
  TempDir dir;
  Scans s = MakeScans(dir, 3);
  // Four targets on the walls and the building, seen in the scans that face them; two are checks.
  const std::vector<Eigen::Vector3d> corners = {{0.0, 5, 2}, {40.0, 25, 2}, {16, 15, 5}, {24, 13, 3}};
  std::string csv = "name,scan,x,y,z,E,N,H,role,accuracy\n";
  for (size_t k = 0; k < corners.size(); ++k) {
    const int scan = static_cast<int>(k % 3);
    const Eigen::Vector3d world = corners[k] + kOrigin;
    const Eigen::Vector3d in_scan = s.truth[scan].Inverse() * world;
    char line[256];
    std::snprintf(line, sizeof(line), "t%zu,%d,%.6f,%.6f,%.6f,%.4f,%.4f,%.4f,%s,0.002\n", k, scan, in_scan.x(),
                  in_scan.y(), in_scan.z(), world.x(), world.y(), world.z(), k < 3 ? "control" : "check");
    csv += line;
  }
  WriteBytes(dir.File("targets.csv"), csv);
  // Every start pose perturbed, scan 0 too: the targets fix the frame.
  std::vector<Rigid3> start = s.start;
  start[0].translation += Eigen::Vector3d(0.3, -0.2, 0.1);
  WritePoses(dir.File("poses.json"), start);
  const CommandResult r = RunCandi("register-scans" + s.args + " -o " + dir.File("out") + " --poses " +
                                   dir.File("poses.json") + " --targets " + dir.File("targets.csv") + kFast);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("control targets: 3"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("check targets: 1"), std::string::npos) << r.output;
  const nlohmann::json j = nlohmann::json::parse(ReadBytes(dir.File("out/registration.json")));
  EXPECT_LT(j["check_rmse"]["xyz_m"].get<double>(), 0.005);
  for (int i = 0; i < 3; ++i) {
    const Rigid3 got = RigidFromJson(j["scans"][i]["world_from_scan"]);
    EXPECT_LT((got.translation - s.truth[i].translation).norm(), 0.005) << i;
  }
}

// CloudCompare's ICP (-ICP, its partial-overlap setting at 60 %, to convergence) registers scan 1
// onto scan 0 from the same perturbed start; candi's pose is no farther from the truth.
TEST(RegisterScansCli, NoWorseThanCloudCompareIcpFromTheSameStart) {
  if (RunCommand("command -v CloudCompare >/dev/null").code != 0) {
    GTEST_SKIP() << "'CloudCompare' is not installed (Debian package cloudcompare; scripts/deps.sh installs it)";
  }
  TempDir dir;
  const TriMesh scene = CourtyardScene(kOrigin);
  const std::vector<Rigid3> truth = CourtyardStations(6, 10.5, kOrigin);
  // Two neighbouring stations, coarser than the other tests (~4e4 points: below CloudCompare's
  // default sampling limit, so its run is deterministic too).
  std::vector<PointCloud> scans;
  for (int i = 0; i < 2; ++i) {
    photogrammetry::VirtualScannerOptions o = CourtyardScanner(400 + i);
    o.azimuth_step_deg = o.elevation_step_deg = 0.8;
    scans.push_back(photogrammetry::ScanMesh(o, scene, truth[i]));
    io::WritePointCloud(dir.File("s" + std::to_string(i) + ".ply"), scans.back());
  }
  const Rigid3 start(Eigen::Quaterniond(Eigen::AngleAxisd(5 * kDeg, Eigen::Vector3d(1, 2, 3).normalized())) *
                         truth[1].rotation,
                     truth[1].translation + 0.5 * Eigen::Vector3d(2, -1, 1).normalized());
  WritePoses(dir.File("poses.json"), {truth[0], start});
  const CommandResult r = RunCandi("register-scans " + dir.File("s0.ply") + " " + dir.File("s1.ply") + " -o " +
                                   dir.File("out") + " --poses " + dir.File("poses.json"));
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(ReadBytes(dir.File("out/registration.json")));
  const Rigid3 candi = RigidFromJson(j["scans"][1]["world_from_scan"]);
  const double candi_error = (candi.translation - truth[1].translation).norm();
  // CloudCompare on both scans in world coordinates under their start poses (shifted to the site).
  for (int i = 0; i < 2; ++i) {
    PointCloud world = photogrammetry::TransformPointCloud(i == 0 ? truth[0] : start, scans[i]);
    world.Rebase(LocalFrame());
    io::WritePointCloud(dir.File("w" + std::to_string(i) + ".ply"), world);
  }
  const std::string shift = " -GLOBAL_SHIFT -500000 -4000000 -120 ";
  const CommandResult cc = RunCommand("cd " + dir.path() + " && timeout 600 env QT_QPA_PLATFORM=offscreen "
                                      "CloudCompare -SILENT -AUTO_SAVE OFF -O" + shift + "w1.ply -O" + shift +
                                      "w0.ply -ICP -OVERLAP 60 -MIN_ERROR_DIFF 1e-8");
  ASSERT_EQ(cc.code, 0) << cc.output;
  std::string matrix_file;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) {
    if (e.path().filename().string().find("REGISTRATION_MATRIX") != std::string::npos) matrix_file = e.path();
  }
  ASSERT_FALSE(matrix_file.empty()) << cc.output;
  std::istringstream in(ReadBytes(matrix_file));
  Eigen::Matrix4d m;
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) in >> m(a, b);
  // CloudCompare's matrix acts on its shifted coordinates x - kOrigin.
  const Eigen::Matrix3d rot = m.block<3, 3>(0, 0);
  const Rigid3 correction(Eigen::Quaterniond(rot), m.block<3, 1>(0, 3) + kOrigin - rot * kOrigin);
  const Rigid3 cloudcompare = correction * start;
  const double cc_error = (cloudcompare.translation - truth[1].translation).norm();
  RecordProperty("candi_error_m", std::to_string(candi_error));
  RecordProperty("cloudcompare_error_m", std::to_string(cc_error));
  EXPECT_LT(candi_error, 0.002);
  EXPECT_LE(candi_error, cc_error) << "CloudCompare's ICP came " << cc_error << " m from the truth, candi "
                                   << candi_error << " m";
}

// An E57 file with several scans counts as several: each read in its own frame, its stored pose
// its start.
TEST(RegisterScansCli, AnE57FileWithSeveralScansStartsFromItsPoses) {
  TempDir dir;
  Scans s = MakeScans(dir, 3);
  std::vector<io::E57Scan> e57;
  for (int i = 0; i < 3; ++i) {
    const PointCloud scan = io::ReadPointCloud(dir.File("s" + std::to_string(i) + ".ply"));
    io::E57Scan out;
    out.name = "station " + std::to_string(i);
    out.rotation = s.start[i].rotation;
    out.translation = s.start[i].translation;
    for (int k = 0; k < 3; ++k) {
      io::E57Field f;
      f.name = std::string("cartesian") + "XYZ"[k];
      for (size_t p = 0; p < scan.size(); ++p) f.values.push_back(scan.WorldPosition(p)[k]);
      out.fields.push_back(f);
    }
    e57.push_back(out);
  }
  io::WriteE57(dir.File("site.e57"), e57);
  const CommandResult r =
      RunCandi("register-scans " + dir.File("site.e57") + " -o " + dir.File("out") + " --format ply" + kFast);
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(ReadBytes(dir.File("out/registration.json")));
  ASSERT_EQ(j["scans"].size(), 3u);
  for (int i = 0; i < 3; ++i) {
    SCOPED_TRACE("scan " + std::to_string(i));
    EXPECT_EQ(j["scans"][i]["e57_scan"], i);
    EXPECT_EQ(j["scans"][i]["output"], "site_" + std::to_string(i) + ".ply");
    const Rigid3 got = RigidFromJson(j["scans"][i]["world_from_scan"]);
    EXPECT_LT((got.translation - s.truth[i].translation).norm(), 0.002);
    EXPECT_LT(Eigen::AngleAxisd(got.rotation * s.truth[i].rotation.conjugate()).angle() / kDeg, 0.01);
  }
  EXPECT_TRUE(FileExists(dir.File("out/site_2.ply")));
}

TEST(RegisterScansCli, BadInputIsNamed) {
  TempDir dir;
  Scans s = MakeScans(dir, 2);
  WriteBytes(dir.File("poses.json"), "[[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]]");
  CommandResult r = RunCandi("register-scans" + s.args + " -o " + dir.File("out") + " --poses " + dir.File("poses.json"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("1 poses for 2 scans"), std::string::npos) << r.output;
  WriteBytes(dir.File("t.csv"), "name,scan,x,y,z,E,N,H\nt1,7,0,0,0,1,2,3\n");
  r = RunCandi("register-scans" + s.args + " -o " + dir.File("out") + " --targets " + dir.File("t.csv"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("line 2"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("'7'"), std::string::npos) << r.output;
  r = RunCandi("register-scans " + dir.File("s0.ply") + " -o " + dir.File("out"));
  EXPECT_EQ(r.code, 1) << r.output;
  r = RunCandi("register-scans" + s.args + " -o " + dir.File("out") + " --coarse --coarse-radius 0.1");
  EXPECT_EQ(r.code, 1) << r.output;  // a feature radius under the coarse voxel
  EXPECT_NE(r.output.find("feature_radius"), std::string::npos) << r.output;
  r = RunCandi("register-scans" + s.args + " -o " + dir.File("out") + " --fixed 5");
  EXPECT_EQ(r.code, 1) << r.output;
  WriteBytes(dir.File("empty.xyz"), "");
  r = RunCandi("register-scans" + s.args + " " + dir.File("empty.xyz") + " -o " + dir.File("out") +
               " --format ply");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("empty.xyz"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir.File("out/registration.json")));
}

}  // namespace
}  // namespace candi::testing
