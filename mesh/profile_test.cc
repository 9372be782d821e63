#include "mesh/profile.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "core/check.h"
#include "tests/util/input_error.h"

namespace candi::mesh {
namespace {

using V = Eigen::Vector2d;
const SectionSource kProfileSource{"drawing.dxf", "B"};

Profile Build(std::vector<V> points, int n = 101, bool closed = false, ProfileOptions o = {}) {
  o.samples_per_side = n;
  return BuildProfile(o, {std::move(points), closed}, kProfileSource);
}

std::string ErrorOf(std::vector<V> points, ProfileOptions o = {}) {
  return testing::InputErrorMessage([&] { BuildProfile(o, {points, false}, kProfileSource); });
}

TEST(ProfileOptions, DefaultsPassAndBadValuesThrow) {
  EXPECT_NO_THROW(ProfileOptions().Check());
  EXPECT_EQ(ProfileOptions().samples_per_side, 1000);
  ProfileOptions o;
  o.samples_per_side = 1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
}

TEST(BuildProfile, SplitsAtTheHighestVertexIntoLeftAndRightSides) {
  const Profile p = Build({V(-4, 0), V(-1, 2), V(0.4, 3), V(2, 1), V(5, -1)});
  EXPECT_EQ(p.origin, V(0, 3));
  EXPECT_EQ(p.reference + p.origin, V(0.4, 3));
  ASSERT_EQ(p.left.size(), 101u);
  ASSERT_EQ(p.right.size(), 101u);
  EXPECT_EQ(p.left.front(), p.reference);
  EXPECT_EQ(p.right.front(), p.reference);
  EXPECT_EQ(p.left.back() + p.origin, V(-4, 0));
  EXPECT_EQ(p.right.back() + p.origin, V(5, -1));
  // The drawing direction does not matter.
  const Profile r = Build({V(5, -1), V(2, 1), V(0.4, 3), V(-1, 2), V(-4, 0)});
  EXPECT_EQ(r.left, p.left);
  EXPECT_EQ(r.right, p.right);
}

TEST(BuildProfile, TiesAreBrokenDeterministically) {
  // A flat top splits at its middle.
  Profile p = Build({V(-3, 0), V(-1, 2), V(2, 2), V(4, 0)});
  EXPECT_EQ(p.reference + p.origin, V(0.5, 2));
  // Two equal peaks: the one nearer the mean x of the tied ones, the smaller x on a tie.
  p = Build({V(-3, 0), V(-1, 2), V(0, 1), V(1, 2), V(3, 0)});
  EXPECT_EQ(p.reference + p.origin, V(-1, 2));
  const Profile r = Build({V(3, 0), V(1, 2), V(0, 1), V(-1, 2), V(-3, 0)});
  EXPECT_EQ(r.reference + r.origin, V(-1, 2));
  EXPECT_EQ(r.left, p.left);
  EXPECT_EQ(r.right, p.right);
}

TEST(BuildProfile, PeakAtAnEndMirrorsTheHalfSectionOrFailsClearly) {
  const Profile p = Build({V(0, 5), V(2, 4), V(4, 0)});
  EXPECT_TRUE(p.mirrored_single_side);
  for (size_t i = 0; i < p.left.size(); ++i) {
    EXPECT_NEAR(p.left[i].x() - p.reference.x(), -(p.right[i].x() - p.reference.x()), 1e-12);
    EXPECT_EQ(p.left[i].y(), p.right[i].y());
  }
  ProfileOptions o;
  o.mirror_single_side = false;
  const std::string m = ErrorOf({V(0, 5), V(2, 4), V(4, 0)}, o);
  EXPECT_NE(m.find("drawing.dxf: layer 'B'"), std::string::npos) << m;
  EXPECT_NE(m.find("one side is empty"), std::string::npos) << m;
}

TEST(BuildProfile, DuplicateVerticesMergeAndTooFewAreAnError) {
  const Profile p = Build({V(-2, 0), V(-2, 0), V(0, 1), V(0, 1), V(2, 0)});
  EXPECT_EQ(p.section_vertices, 3u);
  for (const auto& q : p.left) EXPECT_TRUE(q.allFinite());
  const std::string m = ErrorOf({V(0, 0), V(0, 0), V(1, 1)});
  EXPECT_NE(m.find("2 distinct vertices"), std::string::npos) << m;
}

TEST(BuildProfile, VerticalAndOverhangingSegmentsStayFinite) {
  // A vertical cliff on the left, an overhang on the right (x goes back under itself).
  const Profile p =
      Build({V(-3, -2), V(-3, 2), V(0, 3), V(2, 2), V(3, 1), V(2.5, 0), V(4, -2)}, 401);
  for (const auto& q : p.left) {
    ASSERT_TRUE(q.allFinite());
    if (q.y() + p.origin.y() < 2 - 1e-9) {
      EXPECT_EQ(q.x() + p.origin.x(), -3) << "vertical wall";
    }
  }
  double min_x_after_peak = 1e9;
  bool overhang = false;
  for (const auto& q : p.right) {
    ASSERT_TRUE(q.allFinite());
    if (q.y() + p.origin.y() < 1) {
      overhang |= q.x() + p.origin.x() < 2.9;
      min_x_after_peak = std::min(min_x_after_peak, q.x() + p.origin.x());
    }
  }
  EXPECT_TRUE(overhang);
  EXPECT_GE(min_x_after_peak, 2.5 - 1e-9) << "no overshoot past the drawn vertex";
}

TEST(BuildProfile, SurveyCoordinatesGiveTheSameShapeAsNearTheOrigin) {
  const std::vector<V> near = {V(-40.25, 0.5), V(-10.5, 8.75), V(3.125, 12.5), V(45.5, -1.25)};
  std::vector<V> far = near;
  const V shift(512345.0, 1234567.0);
  for (V& q : far) q += shift;
  const Profile a = Build(near, 1000), b = Build(far, 1000);
  EXPECT_EQ(b.origin - a.origin, shift);
  for (size_t i = 0; i < a.left.size(); ++i) {
    EXPECT_NEAR((a.left[i] - b.left[i]).norm(), 0.0, 1e-9 * a.extent);
    EXPECT_NEAR((a.right[i] - b.right[i]).norm(), 0.0, 1e-9 * a.extent);
  }
}

TEST(BuildProfile, AClosedSectionSplitsAtItsTopAndBottom) {
  // A diamond: top (0, 2), bottom (0, -2), both sides run from the top to the bottom.
  const Profile p = Build({V(0, -2), V(1, 0), V(0, 2), V(-1, 0)}, 51, true);
  EXPECT_TRUE(p.closed);
  EXPECT_EQ(p.left.front() + p.origin, V(0, 2));
  EXPECT_EQ(p.left.back() + p.origin, V(0, -2));
  EXPECT_EQ(p.right.back() + p.origin, V(0, -2));
  EXPECT_LT(p.left[25].x(), p.reference.x());
  EXPECT_GT(p.right[25].x(), p.reference.x());
}

}  // namespace
}  // namespace candi::mesh
