#include "reconstruction/photogrammetry/scenes/virtual_scanner.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "core/check.h"
#include "tests/util/option_check.h"
#include "tests/util/scan_scene.h"

namespace candi::photogrammetry {
namespace {

using testing::CourtyardScene;
using testing::CourtyardStations;

VirtualScannerOptions Coarse(double noise = 0) {
  VirtualScannerOptions o;
  o.azimuth_step_deg = o.elevation_step_deg = 0.5;
  o.range_noise = noise;
  return o;
}

// Distance (m) from the world point `x` to the nearest triangle plane of `mesh` whose triangle
// it projects into (the scene's triangles are all rectangles' halves; enough for hits).
double DistanceToMesh(const TriMesh& mesh, const Eigen::Vector3d& x_world) {
  const Eigen::Vector3d x = mesh.vertices.frame.ToLocal(x_world);
  double best = std::numeric_limits<double>::infinity();
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d a = mesh.vertices.positions[f[0]], b = mesh.vertices.positions[f[1]],
                          c = mesh.vertices.positions[f[2]];
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    const double d = n.dot(x - a);
    const Eigen::Vector3d p = x - d * n;  // projection; barycentric test with a tolerance
    const Eigen::Vector3d v0 = b - a, v1 = c - a, v2 = p - a;
    const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0),
                 d21 = v2.dot(v1), den = d00 * d11 - d01 * d01;
    const double v = (d11 * d20 - d01 * d21) / den, w = (d00 * d21 - d01 * d20) / den;
    if (v < -1e-6 || w < -1e-6 || v + w > 1 + 1e-6) continue;
    best = std::min(best, std::abs(d));
  }
  return best;
}

TEST(VirtualScannerOptions, DefaultsPassAndEachRuleRejects) {
  testing::ExpectDefaultsPass<VirtualScannerOptions>();
  testing::ExpectEachBreakRejected<VirtualScannerOptions>(
      VirtualScannerOptions(),
      {[](auto& o) { o.azimuth_step_deg = 0; }, [](auto& o) { o.elevation_step_deg = 91; },
       [](auto& o) { o.min_elevation_deg = -91; },
       [](auto& o) { o.max_elevation_deg = o.min_elevation_deg - 1; },
       [](auto& o) { o.min_range = -1; }, [](auto& o) { o.max_range = o.min_range; },
       [](auto& o) { o.range_noise = std::nan(""); }});
}

TEST(ScanMesh, HitsLieOnTheMeshInTheScannersFrame) {
  const TriMesh scene = CourtyardScene();
  const Rigid3 pose = CourtyardStations(8)[3];
  const PointCloud scan = ScanMesh(Coarse(), scene, pose);
  scan.CheckConsistent();
  ASSERT_GT(scan.size(), 50000u);
  EXPECT_EQ(scan.frame.origin, Eigen::Vector3d::Zero());
  for (size_t i = 0; i < scan.size(); i += 97) {
    const Eigen::Vector3d w = pose * scan.positions[i];
    EXPECT_LT(DistanceToMesh(scene, w), 1e-9) << "point " << i;
    EXPECT_NEAR(scan.positions[i].norm(), scan.scalars[0].f32[i], 1e-4);
  }
}

TEST(ScanMesh, WallsOccludeWhatLiesBehindThem) {
  const TriMesh scene = CourtyardScene();
  const Rigid3 pose = CourtyardStations(8)[0];  // east of the building, x = 30.5
  const PointCloud scan = ScanMesh(Coarse(), scene, pose);
  int building_east_face = 0;
  for (const Eigen::Vector3d& p : scan.positions) {
    const Eigen::Vector3d w = pose * p;
    // Nothing inside the building or the walls, nothing outside the courtyard, nothing on the
    // building's far (west) side, which the building hides from this station.
    EXPECT_FALSE(w.x() > 16 + 1e-6 && w.x() < 24 - 1e-6 && w.y() > 12 + 1e-6 && w.y() < 18 - 1e-6 &&
                 w.z() < 7 - 1e-6);
    EXPECT_TRUE(w.x() >= -1e-6 && w.x() <= 40 + 1e-6 && w.y() >= -1e-6 && w.y() <= 30 + 1e-6);
    EXPECT_FALSE(std::abs(w.x() - 16) < 1e-6 && w.y() > 12 && w.y() < 18);
    if (std::abs(w.x() - 24) < 1e-6) ++building_east_face;
  }
  EXPECT_GT(building_east_face, 1000);
}

TEST(ScanMesh, RangeNoiseHasTheSigmaAsked) {
  const TriMesh scene = CourtyardScene();
  const Rigid3 pose = CourtyardStations(8)[5];
  const PointCloud exact = ScanMesh(Coarse(0), scene, pose);
  const PointCloud noisy = ScanMesh(Coarse(0.005), scene, pose);
  // Rays that hit in both (a noisy range rarely crosses min_range/max_range), matched by index.
  size_t j = 0, n = 0;
  double sum = 0, sum2 = 0;
  for (size_t i = 0; i < noisy.size(); ++i) {
    while (j < exact.size() && exact.scalars[1].f64[j] < noisy.scalars[1].f64[i]) ++j;
    if (j == exact.size() || exact.scalars[1].f64[j] != noisy.scalars[1].f64[i]) continue;
    const double e = noisy.positions[i].norm() - exact.positions[j].norm();
    sum += e;
    sum2 += e * e;
    ++n;
  }
  ASSERT_GT(n, 50000u);
  const double mean = sum / n, sigma = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 0, 1e-4);
  EXPECT_NEAR(sigma, 0.005, 0.0002);  // ~1% for > 5e4 samples (standard error 0.3%)
}

TEST(ScanMesh, SameSeedSameBytesWhateverTheThreadsOtherSeedOtherNoise) {
  const TriMesh scene = CourtyardScene();
  const Rigid3 pose = CourtyardStations(8)[1];
  PointCloud a, b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    a = ScanMesh(Coarse(0.003), scene, pose);
  }
  {
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    b = ScanMesh(Coarse(0.003), scene, pose);
  }
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(
      0, std::memcmp(a.positions.data(), b.positions.data(), a.size() * sizeof(Eigen::Vector3d)));
  VirtualScannerOptions other = Coarse(0.003);
  other.seed = 2;
  const PointCloud c = ScanMesh(other, scene, pose);
  ASSERT_GT(c.size(), 0u);
  EXPECT_NE(a.positions[0], c.positions[0]);
}

TEST(ScanMesh, SurveyCoordinatesKeepSubMillimetreHits) {
  const Eigen::Vector3d shift(500000, 4000000, 100);
  const TriMesh scene = CourtyardScene(shift);
  const Rigid3 pose = CourtyardStations(8, 10.5, shift)[2];
  const PointCloud scan = ScanMesh(Coarse(), scene, pose);
  const PointCloud near = ScanMesh(Coarse(), CourtyardScene(), CourtyardStations(8)[2]);
  ASSERT_EQ(scan.size(), near.size());
  for (size_t i = 0; i < scan.size(); i += 101) {
    EXPECT_LT((scan.positions[i] - near.positions[i]).norm(), 1e-6);
  }
}

TEST(ScanMesh, TheGridIsTheOneAsked) {
  VirtualScannerOptions o = Coarse();
  o.min_elevation_deg = -10;
  o.max_elevation_deg = 10;
  EXPECT_EQ(ScannerRows(o), 41);
  EXPECT_EQ(ScannerColumns(o), 720);
  // The building's wall seen straight on: the ray at azimuth 0, elevation 0 hits at 24 - x.
  const Rigid3 pose(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ())),
                    Eigen::Vector3d(27, 15, 1.6));
  const PointCloud scan = ScanMesh(o, CourtyardScene(), pose);
  bool found = false;
  for (size_t i = 0; i < scan.size(); ++i) {
    if (scan.scalars[1].f64[i] != 20) continue;  // column 0, row 20 (elevation 0)
    EXPECT_NEAR(scan.positions[i].x(), 3.0, 1e-9);
    found = true;
  }
  EXPECT_TRUE(found);
}

TEST(ScanMesh, BadInputThrows) {
  TriMesh scene = CourtyardScene();
  Rigid3 nan_pose;
  nan_pose.translation.x() = std::nan("");
  EXPECT_THROW(ScanMesh(Coarse(), scene, nan_pose), InputError);
  scene.faces.push_back({0, 1, 1000000});
  EXPECT_THROW(ScanMesh(Coarse(), scene, Rigid3()), InputError);
  EXPECT_EQ(ScanMesh(Coarse(), TriMesh(), Rigid3()).size(), 0u);
}

}  // namespace
}  // namespace candi::photogrammetry
