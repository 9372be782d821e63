// candi register's and register-scans' pipelines without argv: scans the virtual scanner makes
// of the courtyard (tests/util/scan_scene.h) at survey coordinates, written in their scanner
// frames and registered from their files; what is written, the callbacks, the names of the moved
// scans, and bad inputs. The registrations' accuracy is tested by the photogrammetry module and,
// end to end, by tests/register_scans_test.cc and tests/register_cli_test.cc.
#include "pipeline/scan_registration.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "core/check.h"
#include "io/e57/e57_writer.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/scenes/virtual_scanner.h"
#include "tests/util/option_check.h"
#include "tests/util/rigid_json.h"
#include "tests/util/scan_scene.h"
#include "tests/util/test_util.h"

namespace candi::pipeline {
namespace {

namespace fs = std::filesystem;
using testing::ExpectEachBreakRejected;
using testing::FileExists;
using testing::ReadBytes;
using testing::RigidFromJson;
using testing::RigidJson;
using testing::TempDir;
using testing::WriteBytes;

const Eigen::Vector3d kOrigin(500000.0, 4000000.0, 120.0);

// `count` stations of the courtyard scanned at 1 degree steps, in their scanner frames.
std::vector<PointCloud> Scan(int count, std::vector<Rigid3>* truth) {
  const TriMesh scene = testing::CourtyardScene(kOrigin);
  *truth = testing::CourtyardStations(count, 10.5, kOrigin);
  std::vector<PointCloud> scans;
  for (int i = 0; i < count; ++i) {
    photogrammetry::VirtualScannerOptions o = testing::CourtyardScanner(200 + i);
    o.azimuth_step_deg = o.elevation_step_deg = 1.0;
    scans.push_back(photogrammetry::ScanMesh(o, scene, (*truth)[i]));
  }
  return scans;
}

// The scans as DIR/s<i>.ply, and their start poses (the truth, the others moved 0.2 m) as
// DIR/poses.json.
std::vector<std::string> WriteScans(const TempDir& dir, const std::vector<PointCloud>& scans,
                                    const std::vector<Rigid3>& truth) {
  std::vector<std::string> files;
  nlohmann::json poses = nlohmann::json::array();
  for (size_t i = 0; i < scans.size(); ++i) {
    files.push_back(dir.File("s" + std::to_string(i) + ".ply"));
    io::WritePointCloud(files.back(), scans[i]);
    Rigid3 start = truth[i];
    if (i > 0) start.translation += Eigen::Vector3d(0.2, -0.1, 0.05);
    poses.push_back(RigidJson(start));
  }
  WriteBytes(dir.File("poses.json"), poses.dump());
  return files;
}

RegisterScansOptions Fast() {
  RegisterScansOptions o;
  o.registration.voxel = 0.2;
  o.registration.icp_voxel = 0.5;
  return o;
}

TEST(RegisterScansOptions, DefaultsPassAndEachRuleIsChecked) {
  ExpectEachBreakRejected<RegisterScansOptions>(
      {}, {
              [](RegisterScansOptions& o) { o.registration.voxel = -1; },
              [](RegisterScansOptions& o) {
                o.coarse = true;
                o.coarse_options.feature_radius = 0.1;  // under the coarse voxel
              },
          });
  RegisterScansOptions unused;
  unused.coarse_options.feature_radius = 0.1;  // not checked without coarse alignment
  EXPECT_NO_THROW(unused.Check());
  ExpectEachBreakRejected<RegisterPairOptions>(
      {}, {
              [](RegisterPairOptions& o) { o.icp.max_correspondence_distance = 0; },
          });
}

TEST(RegisterScanFiles, WritesTheMovedScansAndTheReportAfterSayingWhatItFound) {
  TempDir dir;
  std::vector<Rigid3> truth;
  const std::vector<std::string> files = WriteScans(dir, Scan(3, &truth), truth);
  RegisterScansOptions o = Fast();
  o.poses = dir.File("poses.json");
  o.format = "las";
  std::vector<std::string> events;
  RegisterScansCallbacks c;
  c.progress.start = [&](const std::string& label, const std::string& unit) -> ProgressCallback {
    events.push_back(label + " (" + unit + ")");
    return nullptr;
  };
  c.progress.finish = [&] { events.push_back("finish"); };
  c.registered = [&](const RegisteredScans& r) {
    events.push_back("registered " + std::to_string(r.result.scans.size()));
    EXPECT_FALSE(fs::exists(dir.File("out"))) << "nothing written yet";
  };
  const RegisteredScans r = RegisterScanFiles(o, files, dir.File("out"), c);
  EXPECT_EQ(events,
            std::vector<std::string>({"register 3 scans (steps)", "finish", "registered 3"}));
  ASSERT_EQ(r.scans.size(), 3u);
  EXPECT_EQ(r.outputs, std::vector<std::string>({"s0.las", "s1.las", "s2.las"}));
  EXPECT_EQ(r.scans[1].label, files[1]);
  EXPECT_GT(r.points[2], 10000u);
  const nlohmann::json j = nlohmann::json::parse(ReadBytes(dir.File("out/registration.json")));
  ASSERT_EQ(j["scans"].size(), 3u);
  for (int i = 0; i < 3; ++i) {
    SCOPED_TRACE("scan " + std::to_string(i));
    EXPECT_EQ(j["scans"][i]["start_from"], "given (--poses)");
    EXPECT_EQ(j["scans"][i]["output"], r.outputs[i]);
    EXPECT_LT(
        (RigidFromJson(j["scans"][i]["world_from_scan"]).translation - truth[i].translation).norm(),
        0.01);
    EXPECT_TRUE(FileExists(dir.File("out/" + r.outputs[i])));
  }
  EXPECT_EQ(io::ReadPointCloud(dir.File("out/s2.las")).size(), r.points[2]);
}

TEST(RegisterScanFiles, AnE57FilesScansCountOneByOneFromTheirStoredPoses) {
  TempDir dir;
  std::vector<Rigid3> truth;
  const std::vector<PointCloud> scans = Scan(2, &truth);
  std::vector<io::E57Scan> e57;
  for (size_t i = 0; i < scans.size(); ++i) {
    io::E57Scan out;
    out.name = "station " + std::to_string(i);
    out.rotation = truth[i].rotation;
    out.translation = truth[i].translation;
    for (int k = 0; k < 3; ++k) {
      io::E57Field f;
      f.name = std::string("cartesian") + "XYZ"[k];
      for (size_t p = 0; p < scans[i].size(); ++p) f.values.push_back(scans[i].WorldPosition(p)[k]);
      out.fields.push_back(f);
    }
    e57.push_back(out);
  }
  io::WriteE57(dir.File("site.e57"), e57);
  RegisterScansOptions o = Fast();
  o.format = "ply";
  o.fixed = "0,1";  // both held: the stored poses are the result
  const RegisteredScans r = RegisterScanFiles(o, {dir.File("site.e57")}, dir.File("out"));
  ASSERT_EQ(r.scans.size(), 2u);
  EXPECT_EQ(r.scans[1].label, dir.File("site.e57") + "#1 (station 1)");
  EXPECT_EQ(r.outputs, std::vector<std::string>({"site_0.ply", "site_1.ply"}));
  const nlohmann::json j = nlohmann::json::parse(ReadBytes(dir.File("out/registration.json")));
  EXPECT_EQ(j["scans"][1]["start_from"], "stored in the E57 file");
  EXPECT_LT(
      (RigidFromJson(j["scans"][1]["world_from_scan"]).translation - truth[1].translation).norm(),
      1e-6);
}

TEST(RegisterScanFiles, BadInputIsNamedBeforeAnythingIsWritten) {
  TempDir dir;
  std::vector<Rigid3> truth;
  const std::vector<std::string> files = WriteScans(dir, Scan(2, &truth), truth);
  const std::string out = dir.File("out");
  EXPECT_THROW(RegisterScanFiles(Fast(), {files[0]}, out), std::invalid_argument);
  RegisterScansOptions o = Fast();
  o.fixed = "5";
  try {
    RegisterScanFiles(o, files, out);
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "--fixed: 5 is not a scan index (0-1)");
  }
  o = Fast();
  WriteBytes(dir.File("one_pose.json"), "[" + RigidJson(Rigid3()).dump() + "]");
  o.poses = dir.File("one_pose.json");
  EXPECT_THROW(RegisterScanFiles(o, files, out), InputError);
  o = Fast();
  WriteBytes(dir.File("t.csv"), "name,scan,x,y,z,E,N,H\nt1,7,0,0,0,1,2,3\n");
  o.targets = dir.File("t.csv");
  EXPECT_THROW(RegisterScanFiles(o, files, out), InputError);
  o = Fast();
  o.format = "doc";
  EXPECT_THROW(RegisterScanFiles(o, files, out), InputError);
  EXPECT_FALSE(fs::exists(out));
}

TEST(RegisterPair, WritesTheMovedFileAndTheTransformFromAnInitialOne) {
  TempDir dir;
  std::vector<Rigid3> truth;
  const PointCloud scan = Scan(1, &truth)[0];
  // The scan in world coordinates, and again moved 0.1 m off, the initial transform taking most
  // of it back.
  io::WritePointCloud(dir.File("fixed.ply"), photogrammetry::TransformPointCloud(truth[0], scan));
  const Rigid3 off(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1, 0, 0));
  io::WritePointCloud(dir.File("moving.ply"),
                      photogrammetry::TransformPointCloud(off * truth[0], scan));
  WriteBytes(
      dir.File("initial.json"),
      nlohmann::json({{"fixed_from_moving", RigidJson(Rigid3(Eigen::Quaterniond::Identity(),
                                                             Eigen::Vector3d(-0.08, 0, 0)))}})
          .dump());
  RegisterPairOptions o;
  o.icp.max_correspondence_distance = 0.5;
  o.icp.voxel = 0.2;
  o.initial = dir.File("initial.json");
  o.transform_out = dir.File("t.json");
  std::vector<std::string> events;
  RegisterPairCallbacks c;
  c.progress.start = [&](const std::string& label, const std::string& unit) -> ProgressCallback {
    events.push_back(label + " (" + unit + ")");
    return nullptr;
  };
  c.registered = [&](const photogrammetry::RegistrationResult&) {
    events.push_back("registered");
    EXPECT_FALSE(FileExists(dir.File("t.json")));
  };
  const RegisteredPair r =
      RegisterPair(o, dir.File("moving.ply"), dir.File("fixed.ply"), dir.File("moved.ply"), c);
  EXPECT_EQ(events, std::vector<std::string>({"ICP (iterations)", "registered"}));
  const Eigen::Vector3d station = off * truth[0].translation;  // in the moving file
  EXPECT_LT((r.result.fixed_from_moving * station - truth[0].translation).norm(), 0.005);
  EXPECT_EQ(r.points, scan.size());
  EXPECT_EQ(io::ReadPointCloud(dir.File("moved.ply")).size(), scan.size());
  const nlohmann::json t = nlohmann::json::parse(ReadBytes(dir.File("t.json")));
  EXPECT_EQ(t["moving"], dir.File("moving.ply"));
  EXPECT_NEAR(RigidFromJson(t["fixed_from_moving"]).translation.x(),
              r.result.fixed_from_moving.translation.x(), 1e-9);
  // A transform that is not rigid, and clouds that do not overlap, are named.
  WriteBytes(dir.File("scaled.json"), "[[2,0,0,0],[0,2,0,0],[0,0,2,0],[0,0,0,1]]");
  o.initial = dir.File("scaled.json");
  EXPECT_THROW(
      RegisterPair(o, dir.File("moving.ply"), dir.File("fixed.ply"), dir.File("moved2.ply")),
      InputError);
  const Rigid3 far(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1000, 0, 0));
  io::WritePointCloud(dir.File("far.ply"),
                      photogrammetry::TransformPointCloud(far * truth[0], scan));
  o.initial.clear();
  EXPECT_THROW(RegisterPair(o, dir.File("far.ply"), dir.File("fixed.ply"), dir.File("moved2.ply")),
               InputError);
  EXPECT_FALSE(FileExists(dir.File("moved2.ply")));
}

}  // namespace
}  // namespace candi::pipeline
