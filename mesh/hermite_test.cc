#include "mesh/hermite.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/check.h"

namespace candi::mesh {
namespace {

TEST(FitMonotoneCubic, ExactAtKnotsAndReproducesLines) {
  const std::vector<double> t = {0, 0.3, 1, 2.5, 2.6}, v = {1, 1.6, 3, 6, 6.2};
  const MonotoneCubic c = FitMonotoneCubic(t, v);
  for (size_t k = 0; k < t.size(); ++k) EXPECT_EQ(c.Evaluate(t[k]), v[k]);
  for (double x = 0; x <= 2.6; x += 0.01) EXPECT_NEAR(c.Evaluate(x), 1 + 2 * x, 1e-12);
}

TEST(FitMonotoneCubic, NoOvershootAtAStepAndFlatRunsStayFlat) {
  const std::vector<double> t = {0, 1, 2, 3, 4, 5}, v = {0, 0, 0, 1, 1, 1};
  const MonotoneCubic c = FitMonotoneCubic(t, v);
  double previous = -1;
  for (double x = 0; x <= 5; x += 0.001) {
    const double y = c.Evaluate(x);
    EXPECT_GE(y, 0.0);
    EXPECT_LE(y, 1.0);
    EXPECT_GE(y, previous - 1e-15) << "monotone at " << x;
    previous = y;
    if (x < 2 || x > 3) {
      EXPECT_EQ(y, x < 2 ? 0.0 : 1.0) << x;
    }
  }
}

TEST(FitMonotoneCubic, BadKnotsAreMisuse) {
  EXPECT_THROW(FitMonotoneCubic({0, 0}, {1, 2}), InternalError);
  EXPECT_THROW(FitMonotoneCubic({0}, {1}), InternalError);
}

TEST(ResampleByArcLength, KeepsEndsExactVerticalSegmentsVerticalAndSpacesEvenly) {
  // Up a wall, across, down a wall: x stays exactly constant on the walls.
  const std::vector<Eigen::Vector2d> v = {{0, 0}, {0, 2}, {0, 4}, {3, 4}, {3, 0}};
  const auto r = ResampleByArcLength(v, 111);
  ASSERT_EQ(r.size(), 111u);
  EXPECT_EQ(r.front(), v.front());
  EXPECT_EQ(r.back(), v.back());
  for (const auto& p : r) {
    if (p.y() < 4 - 1e-9) {
      EXPECT_TRUE(p.x() == 0 || p.x() == 3) << p.transpose();
    }
    EXPECT_LE(p.y(), 4.0);
  }
  // 11 m of line in 110 steps: 0.1 m apart along straight parts.
  EXPECT_NEAR((r[5] - r[4]).norm(), 0.1, 1e-12);
}

TEST(ResampleByArcLength, NearlyCollinearAndUnevenVerticesStayOnTheLine) {
  std::vector<Eigen::Vector2d> v;
  for (double x : {0.0, 1e-6, 0.5, 0.5000001, 3.0, 10.0}) v.emplace_back(x, 2 * x + 1e-13 * x * x);
  for (const auto& p : ResampleByArcLength(v, 1000)) EXPECT_NEAR(p.y(), 2 * p.x(), 1e-9);
}

}  // namespace
}  // namespace candi::mesh
