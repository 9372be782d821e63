#include "core/polyline.h"

#include <gtest/gtest.h>

namespace candi {
namespace {

TEST(DistanceToPolyline, NearestSegmentItsEndsAndDegenerateLines) {
  const std::vector<Eigen::Vector2d> l = {{0, 0}, {2, 0}, {2, 2}};
  EXPECT_DOUBLE_EQ(DistanceToPolyline({1, 1}, l), 1.0);        // as far from both segments
  EXPECT_DOUBLE_EQ(DistanceToPolyline({1, -0.5}, l), 0.5);     // above the first segment
  EXPECT_DOUBLE_EQ(DistanceToPolyline({3, 1}, l), 1.0);        // beside the second
  EXPECT_DOUBLE_EQ(DistanceToPolyline({-3, 4}, l), 5.0);       // beyond the first end
  EXPECT_DOUBLE_EQ(DistanceToPolyline({4, 5}, {{1, 1}, {1, 1}}), 5.0);  // a zero-length segment
  EXPECT_EQ(DistanceToPolyline({0, 0}, {{1, 1}}), 1e300);      // no segment
  // Survey coordinates keep millimetres.
  EXPECT_NEAR(DistanceToPolyline({5e6 + 1, 9e6 + 0.003}, {{5e6, 9e6}, {5e6 + 2, 9e6}}), 0.003, 1e-9);
}

}  // namespace
}  // namespace candi
