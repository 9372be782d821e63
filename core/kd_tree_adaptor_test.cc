#include "core/kd_tree_adaptor.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <type_traits>

namespace candi {
namespace {

TEST(KdTreeAdaptor, GivesCountAndCoordinatesOfFloatPoints) {
  KdTreeAdaptor<Eigen::Vector3f> cloud;
  EXPECT_EQ(cloud.kdtree_get_point_count(), 0u);
  cloud.points = {Eigen::Vector3f(1, 2, 3), Eigen::Vector3f(-4, 5.5f, 6)};
  EXPECT_EQ(cloud.kdtree_get_point_count(), 2u);
  static_assert(std::is_same_v<decltype(cloud.kdtree_get_pt(0, 0)), float>);
  EXPECT_EQ(cloud.kdtree_get_pt(0, 2), 3.0f);
  EXPECT_EQ(cloud.kdtree_get_pt(1, 0), -4.0f);
  EXPECT_EQ(cloud.kdtree_get_pt(1, 1), 5.5f);
}

TEST(KdTreeAdaptor, GivesDoublesOf2DPointsAndNoBoundingBox) {
  KdTreeAdaptor<Eigen::Vector2d> cloud;
  cloud.points = {Eigen::Vector2d(0.1, -1e4), Eigen::Vector2d(2.5, 7)};
  static_assert(std::is_same_v<decltype(cloud.kdtree_get_pt(0, 0)), double>);
  EXPECT_EQ(cloud.kdtree_get_pt(0, 0), 0.1);
  EXPECT_EQ(cloud.kdtree_get_pt(0, 1), -1e4);
  EXPECT_EQ(cloud.kdtree_get_pt(1, 1), 7.0);
  int box = 0;  // any type: nanoflann computes the box itself when given none
  EXPECT_FALSE(cloud.kdtree_get_bbox(box));
}

}  // namespace
}  // namespace candi
