#include "section/section_path.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace candi::section {
namespace {

TEST(SectionPath, VerticalPlaneGivesChainageAndElevation) {
  const SectionPath s = SectionPath::Plane(Eigen::Vector3d(10, 20, 5), Eigen::Vector3d(0, 2, 0), 0.2);
  double depth = 0;
  const Eigen::Vector2d d = s.ToDrawing(Eigen::Vector3d(13, 20.05, 7.5), 0, &depth);
  EXPECT_NEAR(d.x(), 3, 1e-12);  // u = n x z = +x
  EXPECT_NEAR(d.y(), 7.5, 1e-12);  // elevation
  EXPECT_NEAR(depth, 0.05, 1e-12);
  EXPECT_TRUE((s.ToWorld(d) - Eigen::Vector3d(13, 20, 7.5)).norm() < 1e-12);
  ASSERT_EQ(s.regions().size(), 1u);
  EXPECT_TRUE(s.regions()[0].Contains(Eigen::Vector3d(-1e3, 20.09, 0)));
  EXPECT_FALSE(s.regions()[0].Contains(Eigen::Vector3d(-1e3, 20.11, 0)));
}

// Two survey points at 1e6-1e7 m: chainage runs from the first towards the second, and a mm
// offset survives.
TEST(SectionPath, ThroughTwoSurveyPointsKeepsMillimetres) {
  const Eigen::Vector3d a(712345.678, 9162345.123, 250), b(712445.678, 9162345.123, 251);
  const SectionPath s = SectionPath::Through(a, b, 0.05);
  double depth = 0;
  const Eigen::Vector2d d = s.ToDrawing(Eigen::Vector3d(712395.679, 9162345.124, 261.001), 0, &depth);
  EXPECT_NEAR(d.x(), 50.001, 1e-8);
  EXPECT_NEAR(d.y(), 261.001, 1e-8);
  EXPECT_NEAR(std::abs(depth), 0.001, 1e-8);
  EXPECT_THROW(SectionPath::Through(a, a + Eigen::Vector3d(0, 0, 3), 0.1), std::invalid_argument);
}

TEST(SectionPath, HorizontalPlaneIsAPlanCutInSurveyCoordinates) {
  const SectionPath s = SectionPath::Plane(Eigen::Vector3d(500000, 4000000, 12), Eigen::Vector3d(0, 0, -1), 0.1);
  const Eigen::Vector2d d = s.ToDrawing(Eigen::Vector3d(500001.234, 4000002.345, 12.01), 0, nullptr);
  EXPECT_EQ(d, Eigen::Vector2d(500001.234, 4000002.345));
  EXPECT_NEAR(s.ToWorld(d).z(), 12, 1e-9);
}

TEST(SectionPath, PathUnrollsItsSegmentsAndMergesRepeatedVertices) {
  size_t merged = 0;
  const SectionPath s = SectionPath::Path({{0, 0}, {10, 0}, {10, 0}, {10, 5}}, 0.2, &merged);
  EXPECT_EQ(merged, 1u);
  ASSERT_EQ(s.regions().size(), 2u);
  const Eigen::Vector3d on_second(10.05, 3, 2);
  EXPECT_EQ(s.NearestSegment(on_second), 1u);
  const Eigen::Vector2d d = s.ToDrawing(on_second, 1, nullptr);
  EXPECT_NEAR(d.x(), 13, 1e-12);  // 10 m of the first segment, then 3 along the second
  EXPECT_NEAR(d.y(), 2, 1e-12);
  EXPECT_TRUE((s.ToWorld(Eigen::Vector2d(13, 2)) - Eigen::Vector3d(10, 3, 2)).norm() < 1e-12);
  EXPECT_FALSE(s.regions()[0].Contains(Eigen::Vector3d(10.2, 0, 0)));  // beyond the end + T/2
  EXPECT_TRUE(s.regions()[0].Contains(Eigen::Vector3d(10.05, 0, 0)));
}

TEST(SectionPath, DegenerateInputIsAClearError) {
  for (double t : {0.0, -0.1, std::numeric_limits<double>::quiet_NaN()}) {
    try {
      SectionPath::Plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), t);
      ADD_FAILURE() << t;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("--thickness"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(SectionPath::Plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.1), std::invalid_argument);
  try {
    SectionPath::Path({{1, 1}, {1, 1}, {1, 1}}, 0.1);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("3 vertices, 1 distinct"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace candi::section
