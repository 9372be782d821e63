#include "reconstruction/photogrammetry/registration/registration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/check.h"
#include "tests/util/input_error.h"
#include "tests/util/surface_cloud.h"

namespace candi::photogrammetry {
namespace {

using testing::SurfaceCloud;
using testing::SurfaceCloudSpec;

// A small motion about `centre` (world): 2 degrees about a tilted axis and a few centimetres.
Rigid3 SmallMotion(const Eigen::Vector3d& centre) {
  const Eigen::Quaterniond q(
      Eigen::AngleAxisd(2.0 * M_PI / 180.0, Eigen::Vector3d(0.3, 0.2, 1.0).normalized()));
  const Eigen::Vector3d dt(0.12, -0.08, 0.05);
  return Rigid3(q, centre - q * centre + dt);
}

// The largest displacement between two transforms over the cloud's world bounding box corners.
double MaxDisplacement(const Rigid3& a, const Rigid3& b, const PointCloud& cloud) {
  const Box3d box = cloud.WorldBounds();
  double worst = 0;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d x((c & 1) ? box.max.x() : box.min.x(), (c & 2) ? box.max.y() : box.min.y(),
                            (c & 4) ? box.max.z() : box.min.z());
    worst = std::max(worst, (a * x - b * x).norm());
  }
  return worst;
}

// Fixed and moving clouds: independent samples of the same surface; moving is displaced by the
// inverse of `truth`, so fixed_from_moving = truth.
struct Pair {
  PointCloud fixed, moving;
  Rigid3 truth;
};

Pair MakePair(SurfaceCloudSpec fixed_spec, SurfaceCloudSpec moving_spec) {
  Pair p;
  p.fixed = SurfaceCloud(fixed_spec);
  const Eigen::Vector3d centre = p.fixed.WorldBounds().Center();
  p.truth = SmallMotion(centre);
  p.moving = TransformPointCloud(p.truth.Inverse(), SurfaceCloud(moving_spec));
  return p;
}

Pair DefaultPair(double noise = 0, size_t count = 20000) {
  SurfaceCloudSpec f, m;
  f.count = m.count = count;
  f.seed = 1;
  m.seed = 2;
  f.noise = m.noise = noise;
  return MakePair(f, m);
}

TEST(RegistrationOptions, DefaultsPassAndBadValuesNameTheField) {
  RegistrationOptions o;
  EXPECT_NO_THROW(o.Check());
  o.max_correspondence_distance = 0;
  try {
    o.Check();
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_correspondence_distance = 0"), std::string::npos)
        << e.what();
  }
  o = RegistrationOptions();
  o.max_iterations = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = RegistrationOptions();
  o.voxel = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(o.Check(), std::invalid_argument);
  EXPECT_THROW(ParseIcpMethod("planar"), std::invalid_argument);
  EXPECT_EQ(ParseIcpMethod(IcpMethodName(IcpMethod::kPointToPoint)), IcpMethod::kPointToPoint);
}

TEST(RegisterPointClouds, PointToPlaneRecoversAKnownMotionToAMillimetre) {
  const Pair p = DefaultPair();
  const RegistrationResult r = RegisterPointClouds({}, p.moving, p.fixed);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_EQ(r.method, IcpMethod::kPointToPlane);
  EXPECT_FALSE(r.normals_estimated);  // the fixed cloud has normals
  EXPECT_LT(MaxDisplacement(r.fixed_from_moving, p.truth, p.moving), 1e-3);
  EXPECT_LT(r.rms_after, r.rms_before);
  EXPECT_GT(r.overlap_after, 0.97);
  EXPECT_GT(r.iterations, 1);
}

TEST(RegisterPointClouds, PointToPointAndEstimatedNormalsRecoverTheMotion) {
  Pair p = DefaultPair(0, 8000);
  RegistrationOptions o;
  o.method = IcpMethod::kPointToPoint;
  o.max_iterations = 100;
  const RegistrationResult point = RegisterPointClouds(o, p.moving, p.fixed);
  ASSERT_NE(point.status, RegistrationStatus::kNoOverlap) << point.message;
  EXPECT_EQ(point.method, IcpMethod::kPointToPoint);
  // Independent samples bias point-to-point by a fraction of the spacing (11 cm here).
  EXPECT_LT(MaxDisplacement(point.fixed_from_moving, p.truth, p.moving), 0.03);
  PointSchema no_normals = p.fixed.schema;
  no_normals.normals = false;
  p.fixed.SetSchema(no_normals);
  const RegistrationResult plane = RegisterPointClouds({}, p.moving, p.fixed);
  ASSERT_TRUE(plane.converged()) << plane.message;
  EXPECT_TRUE(plane.normals_estimated);
  EXPECT_LT(MaxDisplacement(plane.fixed_from_moving, p.truth, p.moving), 3e-3);
}

TEST(RegisterPointClouds, NoisyCloudsRecoverWithinAFewMillimetres) {
  const Pair p = DefaultPair(/*noise=*/0.005);
  RegistrationOptions o;
  o.voxel = 0.1;
  const RegistrationResult r = RegisterPointClouds(o, p.moving, p.fixed);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_LT(r.moving_solve_points, p.moving.size());
  EXPECT_LT(MaxDisplacement(r.fixed_from_moving, p.truth, p.moving), 4e-3);
  // The residual is the noise of both clouds plus the spacing, not the motion.
  EXPECT_LT(r.rms_after, 0.05);
  EXPECT_GT(r.rms_before, 0.06);
}

TEST(RegisterPointClouds, SurveyCoordinatesRecoverToAMillimetre) {
  SurfaceCloudSpec f, m;
  f.seed = 3;
  m.seed = 4;
  f.origin = m.origin = Eigen::Vector3d(416000.0, 9168000.0, 250.0);
  Pair p = MakePair(f, m);
  // The moving cloud in another, non-integer frame (as a file with its own shift would be).
  p.moving.Rebase(LocalFrame{Eigen::Vector3d(416123.25, 9168045.5, 251.0)});
  const RegistrationResult r = RegisterPointClouds({}, p.moving, p.fixed);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_LT(MaxDisplacement(r.fixed_from_moving, p.truth, p.moving), 1e-3);
  EXPECT_NEAR(r.origin.x(), 416005.0, 1.0);
  // The same clouds near the origin give the same motion relative to the site (float never
  // touched the survey coordinates).
  PointCloud fixed0 = p.fixed, moving0 = p.moving;
  const Eigen::Vector3d shift = f.origin;
  fixed0.frame.origin -= shift;
  moving0.frame.origin -= shift;
  const RegistrationResult r0 = RegisterPointClouds({}, moving0, fixed0);
  const Eigen::Vector3d x = p.moving.WorldPosition(0);
  EXPECT_LT(((r.fixed_from_moving * x - shift) - r0.fixed_from_moving * (x - shift)).norm(), 1e-5);
}

TEST(RegisterPointClouds, PartialOverlapIsReported) {
  SurfaceCloudSpec f, m;
  f.seed = 5;
  m.seed = 6;
  f.x0 = 0, f.x1 = 10;
  m.x0 = 5, m.x1 = 15;  // half of the moving cloud lies beyond the fixed one
  const Pair p = MakePair(f, m);
  RegistrationOptions o;
  o.max_correspondence_distance = 0.3;
  const RegistrationResult r = RegisterPointClouds(o, p.moving, p.fixed);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_NEAR(r.overlap_after, 0.5, 0.03);
  EXPECT_LT(MaxDisplacement(r.fixed_from_moving, p.truth, p.moving), 3e-3);
}

TEST(RegisterPointClouds, NoOverlapIsAClearFailureResult) {
  Pair p = DefaultPair();
  p.moving.frame.origin += Eigen::Vector3d(100, 0, 0);
  const RegistrationResult r = RegisterPointClouds({}, p.moving, p.fixed);
  EXPECT_EQ(r.status, RegistrationStatus::kNoOverlap);
  EXPECT_FALSE(r.converged());
  EXPECT_EQ(r.iterations, 0);
  EXPECT_EQ(r.overlap_before, 0.0);
  EXPECT_TRUE(std::isnan(r.rms_before));
  EXPECT_NE(r.message.find("no overlap"), std::string::npos) << r.message;
  EXPECT_TRUE(r.fixed_from_moving.translation.isZero(0.0));  // the initial transform
  // ... which an initial transform cures.
  RegistrationOptions o;
  o.initial = Rigid3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-100.05, 0.02, 0));
  const RegistrationResult cured = RegisterPointClouds(o, p.moving, p.fixed);
  ASSERT_TRUE(cured.converged()) << cured.message;
  const Rigid3 truth = p.truth * Rigid3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-100, 0, 0));
  EXPECT_LT(MaxDisplacement(cured.fixed_from_moving, truth, p.moving), 1e-3);
}

TEST(RegisterPointClouds, TheIterationLimitGivesNotConverged) {
  const Pair p = DefaultPair();
  RegistrationOptions o;
  o.method = IcpMethod::kPointToPoint;
  o.max_iterations = 2;
  int calls = 0;
  const RegistrationResult r =
      RegisterPointClouds(o, p.moving, p.fixed, [&](uint64_t, uint64_t total) {
        ++calls;
        EXPECT_EQ(total, 2u);
      });
  EXPECT_EQ(r.status, RegistrationStatus::kNotConverged) << r.message;
  EXPECT_EQ(r.iterations, 2);
  EXPECT_EQ(calls, 3);  // once before, once per iteration
  EXPECT_NE(r.message.find("iteration limit"), std::string::npos);
  EXPECT_LT(r.rms_after, r.rms_before);  // it still moved the right way
}

TEST(RegisterPointClouds, EmptyAndNonFiniteInputsAreErrors) {
  Pair p = DefaultPair();
  PointCloud empty;
  EXPECT_NE(testing::InputErrorMessage([&] { RegisterPointClouds({}, empty, p.fixed); })
                .find("moving cloud"),
            std::string::npos);
  EXPECT_NE(testing::InputErrorMessage([&] { RegisterPointClouds({}, p.moving, empty); })
                .find("fixed cloud"),
            std::string::npos);
  p.moving.positions[5].y() = std::numeric_limits<double>::quiet_NaN();
  const std::string message =
      testing::InputErrorMessage([&] { RegisterPointClouds({}, p.moving, p.fixed); });
  EXPECT_NE(message.find("point 5"), std::string::npos) << message;
  EXPECT_NE(message.find("not finite"), std::string::npos) << message;
}

TEST(RegisterPointClouds, IsDeterministic) {
  const Pair p = DefaultPair(0.003, 8000);
  const RegistrationResult a = RegisterPointClouds({}, p.moving, p.fixed);
  const RegistrationResult b = RegisterPointClouds({}, p.moving, p.fixed);
  EXPECT_EQ(a.fixed_from_moving.ToMatrix(), b.fixed_from_moving.ToMatrix());
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.rms_after, b.rms_after);
}

TEST(TransformPointCloud, KeepsFrameAndAttributesAndRotatesNormals) {
  SurfaceCloudSpec spec;
  spec.count = 100;
  spec.origin = Eigen::Vector3d(416000.0, 9168000.0, 0.0);
  const PointCloud cloud = SurfaceCloud(spec);
  const Rigid3 t = SmallMotion(cloud.WorldBounds().Center());
  const PointCloud moved = TransformPointCloud(t, cloud);
  EXPECT_EQ(moved.frame, cloud.frame);
  EXPECT_EQ(moved.schema, cloud.schema);
  for (size_t i = 0; i < cloud.size(); ++i) {
    EXPECT_LT((moved.WorldPosition(i) - t * cloud.WorldPosition(i)).norm(), 1e-8);
    EXPECT_LT((moved.normals[i].cast<double>() - t.rotation * cloud.normals[i].cast<double>()).norm(),
              1e-6);
    EXPECT_EQ(moved.colors[i], cloud.colors[i]);
    EXPECT_EQ(moved.scalars[0].f64[i], cloud.scalars[0].f64[i]);
  }
}

}  // namespace
}  // namespace candi::photogrammetry
