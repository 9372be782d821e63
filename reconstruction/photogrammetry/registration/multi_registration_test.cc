#include "reconstruction/photogrammetry/registration/multi_registration.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "core/check.h"
#include "core/rng.h"
#include "reconstruction/photogrammetry/scenes/virtual_scanner.h"
#include "tests/util/option_check.h"
#include "tests/util/scan_scene.h"

namespace candi::photogrammetry {
namespace {

using testing::CourtyardScene;
using testing::CourtyardStations;

constexpr double kDegree = M_PI / 180.0;

// Registration as the tests run it: thinned to 0.2 m (0.5 m for ICP), which keeps every test
// well under 20 s on one core and still recovers the poses to a fraction of a millimetre.
MultiRegistrationOptions TestRegistration() {
  MultiRegistrationOptions o;
  o.voxel = 0.2;
  o.icp_voxel = 0.5;
  return o;
}

struct ScanSet {
  std::vector<PointCloud> scans;
  std::vector<Rigid3> truth, start;
};

// The courtyard (shifted by `origin`) scanned from `count` stations; every start pose but the
// first moved by 0.5 m in a random direction and turned by 5 degrees about a random axis
// through the station (seeded).
ScanSet MakeScans(int count, const Eigen::Vector3d& origin = Eigen::Vector3d::Zero()) {
  ScanSet s;
  const TriMesh scene = CourtyardScene(origin);
  s.truth = CourtyardStations(count, 10.5, origin);
  Rng rng(7);
  for (int i = 0; i < count; ++i) {
    s.scans.push_back(ScanMesh(testing::CourtyardScanner(100 + i), scene, s.truth[i]));
    if (i == 0) {
      s.start.push_back(s.truth[i]);
      continue;
    }
    Eigen::Vector3d dir(rng.Normal(), rng.Normal(), rng.Normal()),
        axis(rng.Normal(), rng.Normal(), rng.Normal());
    const Eigen::Quaterniond turn(Eigen::AngleAxisd(5 * kDegree, axis.normalized()));
    s.start.emplace_back(turn * s.truth[i].rotation,
                         s.truth[i].translation + 0.5 * dir.normalized());
  }
  return s;
}

double TranslationError(const Rigid3& a, const Rigid3& b) {
  return (a.translation - b.translation).norm();
}
double RotationErrorDeg(const Rigid3& a, const Rigid3& b) {
  return Eigen::AngleAxisd(a.rotation * b.rotation.conjugate()).angle() / kDegree;
}

struct Timed {
  MultiRegistrationResult result;
  double seconds = 0;
};

Timed Register(const ScanSet& s, const MultiRegistrationOptions& o = TestRegistration(),
               const std::vector<ScanTarget>& targets = {}) {
  const auto t0 = std::chrono::steady_clock::now();
  Timed t;
  t.result = RegisterScans(o, s.scans, s.start, targets);
  t.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return t;
}

// Checks every connected pose against the truth and prints the figures (for the record).
void ExpectPosesRecovered(const ScanSet& s, const Timed& t, const char* what) {
  const MultiRegistrationResult& r = t.result;
  ASSERT_EQ(r.world_from_scan.size(), s.truth.size());
  double worst_t = 0, worst_r = 0;
  for (size_t i = 0; i < s.truth.size(); ++i) {
    EXPECT_TRUE(r.scans[i].connected) << "scan " << i;
    const double et = TranslationError(r.world_from_scan[i], s.truth[i]);
    const double er = RotationErrorDeg(r.world_from_scan[i], s.truth[i]);
    EXPECT_LT(et, 0.002) << "scan " << i;
    EXPECT_LT(er, 0.01) << "scan " << i;
    worst_t = std::max(worst_t, et);
    worst_r = std::max(worst_r, er);
  }
  size_t points = 0;
  for (const PointCloud& c : s.scans) points += c.size();
  std::printf(
      "[%s] %zu scans, %.0f points/scan, %zu candidate pairs, %zu loops, %d rounds, "
      "worst pose error %.3f mm %.5f deg, %.1f s: %s\n",
      what, s.scans.size(), static_cast<double>(points) / s.scans.size(), r.pairs.size(),
      r.loops.size(), r.outer_iterations, worst_t * 1e3, worst_r, t.seconds, r.message.c_str());
}

TEST(MultiRegistrationOptions, DefaultsPassAndEachRuleRejects) {
  testing::ExpectDefaultsPass<MultiRegistrationOptions>();
  testing::ExpectEachBreakRejected<MultiRegistrationOptions>(
      MultiRegistrationOptions(),
      {[](auto& o) { o.max_correspondence_distance = 0; },
       [](auto& o) { o.solve_distance = 2 * o.max_correspondence_distance; },
       [](auto& o) { o.solve_distance = 0; }, [](auto& o) { o.icp_iterations = 0; },
       [](auto& o) { o.voxel = -1; }, [](auto& o) { o.min_overlap = 1.5; },
       [](auto& o) { o.loss_scale = 0; }, [](auto& o) { o.outer_iterations = 0; },
       [](auto& o) { o.correspondences_per_pair = 1; }, [](auto& o) { o.normal_neighbours = 2; }});
}

TEST(RegisterScans, RecoversARingOfPerturbedStationsAndClosesItsLoops) {
  const ScanSet s = MakeScans(8);
  const Timed t = Register(s);
  ExpectPosesRecovered(s, t, "ring of 8");
  const MultiRegistrationResult& r = t.result;
  EXPECT_TRUE(r.converged) << r.message;
  EXPECT_TRUE(r.scans[0].fixed);
  ASSERT_FALSE(r.loops.empty());
  double worst_loop = 0, worst_loop_deg = 0;
  for (const LoopReport& loop : r.loops) {
    EXPECT_GE(loop.scans.size(), 3u);
    worst_loop = std::max(worst_loop, loop.translation);
    worst_loop_deg = std::max(worst_loop_deg, loop.rotation_deg);
  }
  // Every cycle of the pair graph (some through pairs of opposite stations, 20 m apart, that share
  // little) within 2 cm and 0.1 degrees; the ring of neighbours, composed here, much closer.
  EXPECT_LT(worst_loop, 0.02);
  EXPECT_LT(worst_loop_deg, 0.1);
  const int n = static_cast<int>(s.truth.size());
  Rigid3 ring;  // scan 0 -> 1 -> ... -> n-1 -> 0
  for (int i = 0; i < n; ++i) {
    const int a = i, b = (i + 1) % n;
    for (const PairReport& p : r.pairs) {
      if (p.moving == std::min(a, b) && p.fixed == std::max(a, b)) {
        ASSERT_TRUE(p.accepted) << a << "-" << b << ": " << p.reason;
        ring = (a < b ? p.fixed_from_moving : p.fixed_from_moving.Inverse()) * ring;
      }
    }
  }
  const double ring_t = ring.translation.norm(),
               ring_r = Eigen::AngleAxisd(ring.rotation).angle() / kDegree;
  EXPECT_LT(ring_t, 0.003);
  EXPECT_LT(ring_r, 0.01);
  std::printf("[ring of 8] the ring's own loop (pairwise fits composed): %.3f mm %.5f deg\n",
              ring_t * 1e3, ring_r);
  int accepted = 0;
  for (const PairReport& p : r.pairs) {
    if (!p.accepted) continue;
    ++accepted;
    EXPECT_LT(p.rms_global, 0.01) << p.moving << "-" << p.fixed;
    EXPECT_LT(p.discrepancy_translation, 0.01) << p.moving << "-" << p.fixed;
  }
  EXPECT_GE(accepted, 8);  // at least the ring's neighbours
  for (size_t i = 1; i < s.truth.size(); ++i) {
    EXPECT_NEAR(r.scans[i].translation_change, TranslationError(s.start[i], s.truth[i]), 0.003);
    EXPECT_NEAR(r.scans[i].rotation_change_deg, 5.0, 0.02);
    EXPECT_LT(r.scans[i].residual_rms, 0.01);
  }
  std::printf("[ring of 8] worst loop %.3f mm %.5f deg over %zu loops, %d accepted pairs\n",
              worst_loop * 1e3, worst_loop_deg, r.loops.size(), accepted);
}

TEST(RegisterScans, SurveyCoordinatesKeepMillimetres) {
  const ScanSet s = MakeScans(6, Eigen::Vector3d(500000, 4000000, 120));
  const Timed t = Register(s);
  ExpectPosesRecovered(s, t, "survey, 6");
  EXPECT_EQ(t.result.origin.x(), std::round(t.result.origin.x()));
  EXPECT_GT(t.result.origin.norm(), 4e6);
}

TEST(RegisterScans, AScanWithoutOverlapIsReportedAndKeepsItsStartPose) {
  ScanSet s = MakeScans(4);
  // A fifth scan 1 km away: a copy of scan 1 (geometry that would match, were it near).
  s.scans.push_back(s.scans[1]);
  s.truth.push_back(
      Rigid3(s.truth[1].rotation, s.truth[1].translation + Eigen::Vector3d(1000, 0, 0)));
  s.start.push_back(s.truth.back());
  const Timed t = Register(s);
  const MultiRegistrationResult& r = t.result;
  for (int i = 0; i < 4; ++i) {
    EXPECT_TRUE(r.scans[i].connected);
    EXPECT_LT(TranslationError(r.world_from_scan[i], s.truth[i]), 0.002);
  }
  EXPECT_FALSE(r.scans[4].connected);
  EXPECT_EQ(r.world_from_scan[4].translation, s.start[4].translation);
  EXPECT_EQ(r.world_from_scan[4].rotation.coeffs(), s.start[4].rotation.coeffs());
  EXPECT_EQ(r.scans[4].translation_change, 0);
  for (const PairReport& p : r.pairs) EXPECT_NE(p.fixed, 4);  // never a candidate
  EXPECT_NE(r.message.find("4 of 5 scans"), std::string::npos) << r.message;
}

TEST(RegisterScans, ControlTargetsTieTheBlockToTheSurveyAndChecksVerifyIt) {
  ScanSet s = MakeScans(4);
  s.start[0] = Rigid3(Eigen::Quaterniond(Eigen::AngleAxisd(3 * kDegree, Eigen::Vector3d::UnitZ())) *
                          s.truth[0].rotation,
                      s.truth[0].translation + Eigen::Vector3d(0.3, -0.2, 0.1));
  // Targets on the building's corners and the walls, seen from the scans that hold them (their
  // scan coordinates from the truth, as a scanner's target fit would give them).
  const std::vector<std::pair<int, Eigen::Vector3d>> points = {
      {0, {24, 12, 2}}, {1, {24, 18, 3}}, {2, {16, 18, 2.5}}, {3, {16, 12, 1}}, {0, {40, 15, 1.5}}};
  std::vector<ScanTarget> targets;
  for (size_t k = 0; k < points.size(); ++k) {
    ScanTarget t;
    t.name = "T" + std::to_string(k);
    t.scan = points[k].first;
    t.world = points[k].second;
    t.in_scan = s.truth[t.scan].Inverse() * t.world;
    t.role = k == 4 ? TargetRole::kCheck : TargetRole::kControl;
    t.accuracy = 0.002;
    targets.push_back(t);
  }
  const Timed t = Register(s, TestRegistration(), targets);
  ExpectPosesRecovered(s, t, "targets, 4");
  EXPECT_FALSE(t.result.scans[0].fixed);
  EXPECT_EQ(t.result.control.count, 4);
  EXPECT_EQ(t.result.check.count, 1);
  EXPECT_LT(t.result.control.d3, 0.002);
  EXPECT_LT(t.result.check.d3, 0.002);
}

TEST(RegisterScans, SameInputSameBytesWhateverTheThreads) {
  const ScanSet s = MakeScans(3);
  MultiRegistrationResult a, b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    a = Register(s).result;
  }
  {
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    b = Register(s).result;
  }
  ASSERT_EQ(a.world_from_scan.size(), b.world_from_scan.size());
  for (size_t i = 0; i < a.world_from_scan.size(); ++i) {
    EXPECT_EQ(0, std::memcmp(a.world_from_scan[i].translation.data(),
                             b.world_from_scan[i].translation.data(), 3 * sizeof(double)));
    EXPECT_EQ(0, std::memcmp(a.world_from_scan[i].rotation.coeffs().data(),
                             b.world_from_scan[i].rotation.coeffs().data(), 4 * sizeof(double)));
  }
}

TEST(RegisterScans, BadInputThrows) {
  PointCloud cloud;
  cloud.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0.1}};
  const MultiRegistrationOptions o;
  EXPECT_THROW(RegisterScans(o, {}, {}), InputError);
  EXPECT_THROW(RegisterScans(o, {cloud, PointCloud()}, {Rigid3(), Rigid3()}), InputError);
  EXPECT_THROW(RegisterScans(o, {cloud, cloud}, {Rigid3()}), InputError);
  PointCloud nan_cloud = cloud;
  nan_cloud.positions[2].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(RegisterScans(o, {cloud, nan_cloud}, {Rigid3(), Rigid3()}), InputError);
  Rigid3 nan_pose;
  nan_pose.translation.z() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(RegisterScans(o, {cloud, cloud}, {Rigid3(), nan_pose}), InputError);
  ScanTarget target;
  target.scan = 2;
  EXPECT_THROW(RegisterScans(o, {cloud, cloud}, {Rigid3(), Rigid3()}, {target}), InputError);
  MultiRegistrationOptions fixed = o;
  fixed.fixed_scans = {5};
  EXPECT_THROW(RegisterScans(fixed, {cloud, cloud}, {Rigid3(), Rigid3()}), InputError);
  MultiRegistrationOptions bad = o;
  bad.voxel = -1;
  EXPECT_THROW(RegisterScans(bad, {cloud, cloud}, {Rigid3(), Rigid3()}), std::invalid_argument);
}

}  // namespace
}  // namespace candi::photogrammetry
