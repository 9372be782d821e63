#include "core/transform.h"

#include <gtest/gtest.h>

#include "core/check.h"
#include "core/rng.h"

namespace candi {
namespace {

Eigen::Quaterniond RandomRotation(Rng& rng) {
  Eigen::Quaterniond q(rng.Normal(), rng.Normal(), rng.Normal(), rng.Normal());
  return q.normalized();
}

TEST(Rigid3, ComposeAndInverse) {
  Rng rng(1);
  for (int t = 0; t < 100; ++t) {
    const Rigid3 a(RandomRotation(rng), Eigen::Vector3d(rng.Normal(), rng.Normal(), rng.Normal()));
    const Rigid3 b(RandomRotation(rng), Eigen::Vector3d(rng.Normal(), rng.Normal(), rng.Normal()));
    const Eigen::Vector3d x(rng.Normal(), rng.Normal(), rng.Normal());
    EXPECT_LT(((a * b) * x - a * (b * x)).norm(), 1e-12);
    EXPECT_LT((a.Inverse() * (a * x) - x).norm(), 1e-12);
    EXPECT_LT(((a.ToMatrix() * x.homogeneous()).head<3>() - a * x).norm(), 1e-12);
  }
}

TEST(Sim3, ComposeInverseAndMatrixRoundTrip) {
  Rng rng(2);
  for (int t = 0; t < 100; ++t) {
    const Sim3 a(rng.Uniform(0.1, 10), RandomRotation(rng), Eigen::Vector3d(rng.Normal(), rng.Normal(), 1e6));
    const Eigen::Vector3d x(rng.Normal(), rng.Normal(), rng.Normal());
    EXPECT_LT((a.Inverse() * (a * x) - x).norm(), 1e-8);  // translation 1e6: ~1e-15 relative
    const Sim3 back = Sim3FromMatrix(a.ToMatrix());
    EXPECT_NEAR(back.scale, a.scale, 1e-12 * a.scale);
    EXPECT_LT((back * x - a * x).norm(), 1e-8);
  }
}

TEST(Sim3, RejectsBadScaleAndReflections) {
  EXPECT_THROW(Sim3(0.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero()), InternalError);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(0, 0) = -1;
  EXPECT_THROW(Sim3FromMatrix(m), std::invalid_argument);
  m = Eigen::Matrix4d::Identity();
  m(0, 1) = 0.5;  // shear
  EXPECT_THROW(Sim3FromMatrix(m), std::invalid_argument);
}

}  // namespace
}  // namespace candi
