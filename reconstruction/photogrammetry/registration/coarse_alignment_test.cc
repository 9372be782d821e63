#include "reconstruction/photogrammetry/registration/coarse_alignment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/check.h"
#include "reconstruction/photogrammetry/registration/multi_registration.h"
#include "reconstruction/photogrammetry/registration/registration.h"
#include "reconstruction/photogrammetry/scenes/virtual_scanner.h"
#include "tests/util/option_check.h"
#include "tests/util/scan_scene.h"

namespace candi::photogrammetry {
namespace {

using testing::CourtyardScene;
using testing::CourtyardStations;

constexpr double kDeg = M_PI / 180.0;

TEST(CoarseAlignmentOptions, DefaultsPassAndEachRuleRejects) {
  testing::ExpectDefaultsPass<CoarseAlignmentOptions>();
  testing::ExpectEachBreakRejected<CoarseAlignmentOptions>(
      CoarseAlignmentOptions(),
      {[](auto& o) { o.voxel = 0; }, [](auto& o) { o.normal_neighbours = 2; },
       [](auto& o) { o.feature_radius = o.voxel; }, [](auto& o) { o.max_iterations = 0; },
       [](auto& o) { o.correspondence_randomness = 0; },
       [](auto& o) { o.similarity_threshold = 1; }, [](auto& o) { o.inlier_distance = 0; },
       [](auto& o) { o.min_inlier_fraction = 2; }});
}

// A scan with no start pose at all (its own frame taken as the world) is found against its
// neighbour in the world, to a start RegisterScans then refines to a fraction of a millimetre.
TEST(CoarseAlign, FindsAScanWithoutAStartPoseAndRegisterScansFinishesIt) {
  const Eigen::Vector3d shift(500000, 4000000, 80);  // at survey coordinates
  const TriMesh scene = CourtyardScene(shift);
  const std::vector<Rigid3> truth = CourtyardStations(8, 10.5, shift);
  const PointCloud fixed_scan = ScanMesh(testing::CourtyardScanner(1), scene, truth[0]);
  const PointCloud moving_scan = ScanMesh(testing::CourtyardScanner(2), scene, truth[1]);
  PointCloud fixed_world = TransformPointCloud(truth[0], fixed_scan);
  const CoarseAlignmentResult coarse = CoarseAlign({}, moving_scan, fixed_world);
  ASSERT_TRUE(coarse.found) << coarse.message;
  const double et = (coarse.fixed_from_moving.translation - truth[1].translation).norm();
  const double er =
      Eigen::AngleAxisd(coarse.fixed_from_moving.rotation * truth[1].rotation.conjugate()).angle() /
      kDeg;
  EXPECT_LT(et, 0.5);
  EXPECT_LT(er, 3.0);
  MultiRegistrationOptions o;
  o.voxel = 0.2;
  o.icp_voxel = 0.5;
  const MultiRegistrationResult fine =
      RegisterScans(o, {fixed_scan, moving_scan}, {truth[0], coarse.fixed_from_moving});
  const double ft = (fine.world_from_scan[1].translation - truth[1].translation).norm();
  const double fr =
      Eigen::AngleAxisd(fine.world_from_scan[1].rotation * truth[1].rotation.conjugate()).angle() /
      kDeg;
  EXPECT_LT(ft, 0.002);
  EXPECT_LT(fr, 0.01);
  std::printf(
      "[coarse] %s; start error %.3f m %.3f deg (%llu/%llu points); after RegisterScans "
      "%.3f mm %.5f deg\n",
      coarse.message.c_str(), et, er, static_cast<unsigned long long>(coarse.moving_points),
      static_cast<unsigned long long>(coarse.fixed_points), ft * 1e3, fr);
}

TEST(CoarseAlign, BadInputThrows) {
  PointCloud cloud;
  cloud.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_THROW(CoarseAlign({}, PointCloud(), cloud), InputError);
  EXPECT_THROW(CoarseAlign({}, cloud, PointCloud()), InputError);
  cloud.positions[1].x() = std::nan("");
  EXPECT_THROW(CoarseAlign({}, cloud, cloud), InputError);
}

}  // namespace
}  // namespace candi::photogrammetry
