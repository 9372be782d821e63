// Many-scan registration at scale: the courtyard (tests/util/scan_scene.h) scanned by candi's
// virtual scanner from N stations, every start pose but the first moved 0.5 m and turned 5
// degrees, registered by RegisterScans on 1 and 2 threads: seconds and the worst pose error
// against the truth. With --cloudcompare, the first two scans are also registered pairwise by
// CloudCompare's ICP from the same start, and its pose error printed beside candi's pairwise
// (register) and many-scan results.
//
//   register_bench [--scans 8] [--step 0.12] [--runs 1] [--cloudcompare] [--dir candi-bench-register]
//
// --step is the scanner's angular step in degrees (0.12: ~2e6 points a station).
#include <tbb/task_arena.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/rng.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/registration/multi_registration.h"
#include "reconstruction/photogrammetry/registration/registration.h"
#include "reconstruction/photogrammetry/scenes/virtual_scanner.h"
#include "tests/util/scan_scene.h"

namespace {

using namespace candi;
constexpr double kDeg = M_PI / 180.0;

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct PoseError {
  double mm = 0, deg = 0;
};

PoseError Error(const Rigid3& a, const Rigid3& b) {
  return {(a.translation - b.translation).norm() * 1000,
          Eigen::AngleAxisd(a.rotation * b.rotation.conjugate()).angle() / kDeg};
}

// The 4x4 CloudCompare writes beside a registered cloud (*REGISTRATION_MATRIX*.txt).
bool ReadMatrix(const std::string& dir, Eigen::Matrix4d* m) {
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.find("REGISTRATION_MATRIX") == std::string::npos) continue;
    std::ifstream in(e.path());
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) in >> (*m)(i, j);
    return static_cast<bool>(in);
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  int scans = 8, runs = 1;
  double step = 0.12;
  bool cloudcompare = false;
  std::string dir = "candi-bench-register";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--scans" && i + 1 < argc) scans = std::atoi(argv[++i]);
    else if (a == "--step" && i + 1 < argc) step = std::atof(argv[++i]);
    else if (a == "--runs" && i + 1 < argc) runs = std::atoi(argv[++i]);
    else if (a == "--dir" && i + 1 < argc) dir = argv[++i];
    else if (a == "--cloudcompare") cloudcompare = true;
    else {
      std::fprintf(stderr, "usage: register_bench [--scans N] [--step DEG] [--runs N] [--cloudcompare] [--dir D]\n");
      return 1;
    }
  }
  if (scans < 2 || step <= 0 || runs < 1) {
    std::fprintf(stderr, "register_bench: --scans >= 2, --step > 0, --runs >= 1\n");
    return 1;
  }
  const Eigen::Vector3d origin(500000.0, 4000000.0, 120.0);
  const TriMesh scene = testing::CourtyardScene(origin);
  const std::vector<Rigid3> truth = testing::CourtyardStations(scans, 10.5, origin);
  std::vector<PointCloud> clouds;
  std::vector<Rigid3> start;
  Rng rng(7);
  size_t points = 0;
  auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < scans; ++i) {
    photogrammetry::VirtualScannerOptions o = testing::CourtyardScanner(100 + i);
    o.azimuth_step_deg = o.elevation_step_deg = step;
    clouds.push_back(photogrammetry::ScanMesh(o, scene, truth[i]));
    points += clouds.back().size();
    if (i == 0) {
      start.push_back(truth[0]);
      continue;
    }
    const Eigen::Vector3d dir3(rng.Normal(), rng.Normal(), rng.Normal()), axis(rng.Normal(), rng.Normal(), rng.Normal());
    start.emplace_back(Eigen::Quaterniond(Eigen::AngleAxisd(5 * kDeg, axis.normalized())) * truth[i].rotation,
                       truth[i].translation + 0.5 * dir3.normalized());
  }
  std::printf("register_bench: %d stations of the courtyard at E 500000 N 4000000, %.2f deg steps, 1 mm range "
              "noise: %.2f M points a scan (scanning %.1f s); starts moved 0.5 m and turned 5 deg\n\n",
              scans, step, points / 1e6 / scans, Seconds(t0));
  std::printf("%-34s %8s %10s %14s %14s\n", "registration", "threads", "seconds", "worst pose mm", "worst pose deg");
  photogrammetry::MultiRegistrationOptions options;  // the defaults
  for (int threads : {1, 2}) {
    std::vector<double> seconds;
    photogrammetry::MultiRegistrationResult r;
    for (int k = 0; k < runs; ++k) {
      tbb::task_arena arena(threads);
      t0 = std::chrono::steady_clock::now();
      arena.execute([&] { r = photogrammetry::RegisterScans(options, clouds, start); });
      seconds.push_back(Seconds(t0));
    }
    std::sort(seconds.begin(), seconds.end());
    PoseError worst;
    for (int i = 0; i < scans; ++i) {
      const PoseError e = Error(r.world_from_scan[i], truth[i]);
      worst.mm = std::max(worst.mm, e.mm);
      worst.deg = std::max(worst.deg, e.deg);
    }
    std::printf("%-34s %8d %10.1f %14.3f %14.5f\n", "candi register-scans (defaults)", threads,
                seconds[seconds.size() / 2], worst.mm, worst.deg);
    std::fflush(stdout);
  }
  // The first pair alone: candi's pairwise ICP (register) and CloudCompare's ICP, same start.
  photogrammetry::RegistrationOptions icp;
  icp.max_correspondence_distance = 1.0;
  icp.voxel = 0.05;  // the solve on a 5 cm voxel grid (the figures on all points)
  // Both scans in world coordinates under their start poses; ICP finds the correction of scan 1.
  const PointCloud moving = photogrammetry::TransformPointCloud(start[1], clouds[1]);
  const PointCloud fixed = photogrammetry::TransformPointCloud(start[0], clouds[0]);
  t0 = std::chrono::steady_clock::now();
  photogrammetry::RegistrationResult pair = photogrammetry::RegisterPointClouds(icp, moving, fixed);
  icp.max_correspondence_distance = 0.1;
  icp.initial = pair.fixed_from_moving;
  pair = photogrammetry::RegisterPointClouds(icp, moving, fixed);
  const double pair_seconds = Seconds(t0);
  // The truth: world_from_scan1 = truth[1], so the correction applied to start[1] must give it.
  const PoseError pe = Error(pair.fixed_from_moving * start[1], truth[1]);
  std::printf("%-34s %8s %10.1f %14.3f %14.5f\n", "candi register (pair 0-1, voxel 5 cm)", "1", pair_seconds, pe.mm,
              pe.deg);
  if (cloudcompare) {
    std::filesystem::create_directories(dir);
    PointCloud m = moving, f = fixed;
    m.Rebase(LocalFrame());
    f.Rebase(LocalFrame());
    io::WritePointCloud(dir + "/moving.ply", m);
    io::WritePointCloud(dir + "/fixed.ply", f);
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
      if (e.path().filename().string().find("REGISTRATION_MATRIX") != std::string::npos) std::filesystem::remove(e);
    }
    const std::string command =
        "cd " + dir + " && env QT_QPA_PLATFORM=offscreen CloudCompare -SILENT -AUTO_SAVE OFF -O -GLOBAL_SHIFT "
        "-500000 -4000000 -120 moving.ply -O -GLOBAL_SHIFT -500000 -4000000 -120 fixed.ply -ICP -MIN_ERROR_DIFF "
        "1e-8 -ITER 200 -OVERLAP 60 -RANDOM_SAMPLING_LIMIT 200000 > cc.log 2>&1";
    t0 = std::chrono::steady_clock::now();
    const int status = std::system(command.c_str());
    const double cc_seconds = Seconds(t0);
    Eigen::Matrix4d mat;
    if (status != 0 || !ReadMatrix(dir, &mat)) {
      std::printf("CloudCompare -ICP failed (status %d): see %s/cc.log\n", status, dir.c_str());
    } else {
      // CloudCompare's matrix is in its shifted frame: x' = R (x - s) + t + s, world = that.
      const Eigen::Vector3d s = origin;
      const Eigen::Matrix3d rot = mat.block<3, 3>(0, 0);
      const Eigen::Vector3d t = mat.block<3, 1>(0, 3) + s - rot * s;
      const Rigid3 cc(Eigen::Quaterniond(rot), t);
      const PoseError ce = Error(cc * start[1], truth[1]);
      std::printf("%-34s %8s %10.1f %14.3f %14.5f\n", "CloudCompare -ICP (pair 0-1)", "all", cc_seconds, ce.mm,
                  ce.deg);
    }
  }
  return 0;
}
