#include "core/clip.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/point_cloud.h"

namespace candi {
namespace {

TEST(ClipRegion, NoPlaneKeepsEverything) {
  const ClipRegion none;
  EXPECT_TRUE(none.Contains(Eigen::Vector3d(1e7, -1e7, 3)));
  EXPECT_EQ(none.Classify(Box3d{Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()}), ClipRelation::kInside);
}

TEST(ClipRegion, BoxKeepsItsInsideAndItsFaces) {
  const ClipRegion box = ClipRegion::Box(Box3d{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 2, 3)});
  EXPECT_EQ(box.planes.size(), 6u);
  EXPECT_TRUE(box.Contains(Eigen::Vector3d(0.5, 1, 1.5)));
  EXPECT_TRUE(box.Contains(Eigen::Vector3d(0, 2, 3)));  // on the faces
  EXPECT_FALSE(box.Contains(Eigen::Vector3d(1.0000001, 1, 1)));
  EXPECT_FALSE(box.Contains(Eigen::Vector3d(0.5, -1e-12, 1)));
  EXPECT_EQ(box.Classify(Box3d{Eigen::Vector3d(0.1, 0.1, 0.1), Eigen::Vector3d(0.9, 1.9, 2.9)}), ClipRelation::kInside);
  EXPECT_EQ(box.Classify(Box3d{Eigen::Vector3d(2, 0, 0), Eigen::Vector3d(3, 1, 1)}), ClipRelation::kOutside);
  EXPECT_EQ(box.Classify(Box3d{Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d(3, 1, 1)}), ClipRelation::kPartial);
  EXPECT_EQ(box.Classify(Box3d{}), ClipRelation::kOutside);  // an empty box holds nothing
}

TEST(ClipRegion, SlabIsTwoPlanesAThicknessApart) {
  const ClipRegion slab = ClipRegion::Slab(Eigen::Vector3d(10, 0, 0), Eigen::Vector3d(0, 2, 0), 0.2);
  EXPECT_TRUE(slab.Contains(Eigen::Vector3d(-50, 0.0999, 7)));
  EXPECT_TRUE(slab.Contains(Eigen::Vector3d(-50, -0.0999, 7)));
  EXPECT_FALSE(slab.Contains(Eigen::Vector3d(-50, 0.1001, 7)));
  EXPECT_FALSE(slab.Contains(Eigen::Vector3d(-50, -0.1001, 7)));
  // Zero thickness keeps the plane itself.
  const ClipRegion plane = ClipRegion::Slab(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY(), 0);
  EXPECT_TRUE(plane.Contains(Eigen::Vector3d(3, 0, 4)));
  EXPECT_FALSE(plane.Contains(Eigen::Vector3d(3, 1e-9, 4)));
}

// Survey coordinates: a half-space given at 1e6 m keeps mm decisions once moved to a local frame.
TEST(ClipRegion, SurveyCoordinatesKeepMillimetres) {
  const Eigen::Vector3d origin(712000, 9162000, 0);
  const ClipRegion world{{{Eigen::Vector3d(712345.678, 9162345.0, 100), Eigen::Vector3d(1, 0, 0)}}};
  const ClipRegion local = world.ToLocal(origin);
  EXPECT_TRUE(local.Contains(Eigen::Vector3d(712345.6785, 9162345.0, 100) - origin));
  EXPECT_FALSE(local.Contains(Eigen::Vector3d(712345.6775, 9162345.0, 100) - origin));
  PointCloud cloud;
  cloud.frame.origin = origin;
  for (double x : {712345.675, 712345.677, 712345.679, 712345.681}) cloud.positions.push_back(Eigen::Vector3d(x, 9162345, 1) - origin);
  EXPECT_EQ(ClipCloud(world, &cloud), 2u);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_NEAR(cloud.WorldPosition(0).x(), 712345.679, 1e-9);
}

TEST(ClipRegion, CheckNamesTheBadPlane) {
  ClipRegion r{{{Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()},
                {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}}};
  try {
    r.Check("--clip-plane");
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--clip-plane: plane 2 has a zero normal"), std::string::npos) << e.what();
  }
  r.planes[1].normal = Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0, 1);
  EXPECT_THROW(r.Check("x"), std::invalid_argument);
  r.planes.pop_back();
  EXPECT_NO_THROW(r.Check("x"));
}

}  // namespace
}  // namespace candi
