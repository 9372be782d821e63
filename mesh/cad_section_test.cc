#include "mesh/cad_section.h"

#include <gtest/gtest.h>

#include "core/check.h"
#include "tests/util/input_error.h"

namespace candi::mesh {
namespace {

using V = Eigen::Vector2d;
const SectionSource kCadSource{"drawing.dxf", "C"};

Polyline2 Open(std::vector<V> points) { return {std::move(points), false}; }

std::string ErrorOf(const std::vector<Polyline2>& pieces) {
  return testing::InputErrorMessage([&] { AssembleSection({}, pieces, kCadSource); });
}

TEST(SectionOptions, DefaultsPassAndBadValuesThrow) {
  EXPECT_NO_THROW(SectionOptions().Check());
  SectionOptions o;
  o.join_tolerance = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
}

TEST(AssembleSection, JoinsLinesGivenInAnyOrderAndDirection) {
  // The chain (0,0)-(1,1)-(2,3)-(3,2)-(4,0), pieces shuffled and some reversed.
  const Polyline2 s = AssembleSection({},
                                      {Open({V(2, 3), V(1, 1)}), Open({V(3, 2), V(4, 0)}),
                                       Open({V(0, 0), V(1, 1)}), Open({V(3, 2), V(2, 3)})},
                                      kCadSource);
  EXPECT_FALSE(s.closed);
  const std::vector<V> forward = {V(0, 0), V(1, 1), V(2, 3), V(3, 2), V(4, 0)};
  std::vector<V> backward(forward.rbegin(), forward.rend());
  EXPECT_TRUE(s.points == forward || s.points == backward);
}

TEST(AssembleSection, EndsWithinTheToleranceJoinAndALoopIsClosed) {
  const Polyline2 s = AssembleSection(
      {}, {Open({V(0, 0), V(1, 0)}), Open({V(1, 1e-8), V(0.5, 1)}), Open({V(0.5, 1), V(0, 0)})},
      kCadSource);
  EXPECT_TRUE(s.closed);
  EXPECT_EQ(s.points.size(), 3u);
}

TEST(AssembleSection, BranchesGapsAndTooFewVerticesAreNamedErrors) {
  std::string m =
      ErrorOf({Open({V(0, 0), V(1, 1)}), Open({V(1, 1), V(2, 0)}), Open({V(1, 1), V(1, 3)})});
  EXPECT_NE(m.find("drawing.dxf: layer 'C'"), std::string::npos) << m;
  EXPECT_NE(m.find("branches at (1, 1): 3 piece ends"), std::string::npos) << m;
  m = ErrorOf({Open({V(0, 0), V(1, 1)}), Open({V(1.5, 1), V(2, 0)})});
  EXPECT_NE(m.find("2 separate chains"), std::string::npos) << m;
  EXPECT_NE(m.find("smallest gap is 0.5 m"), std::string::npos) << m;
  m = ErrorOf({Open({V(0, 0), V(1, 1), V(1, 1)})});
  EXPECT_NE(m.find("2 distinct vertices"), std::string::npos) << m;
  m = ErrorOf({});
  EXPECT_NE(m.find("no section geometry"), std::string::npos) << m;
}

TEST(AssembleSection, ASelfIntersectingSectionIsAClearError) {
  const std::string m = ErrorOf({Open({V(0, 0), V(2, 2), V(2, 0), V(0, 2)})});
  EXPECT_NE(m.find("crosses itself at (1, 1)"), std::string::npos) << m;
  const std::string back = ErrorOf({Open({V(0, 0), V(2, 2), V(1, 1)})});
  EXPECT_NE(back.find("crosses itself"), std::string::npos) << "a line doubling back: " << back;
}

TEST(MergeCoincidentVertices, MergesRunsAndTheClosingVertex) {
  const Polyline2 m = MergeCoincidentVertices(
      {{V(0, 0), V(0, 0), V(1, 0), V(1, 1e-12), V(1, 1), V(0, 1e-13)}, true}, 1e-9);
  EXPECT_EQ(m.points, (std::vector<V>{V(0, 0), V(1, 0), V(1, 1)}));
}

TEST(FindSelfIntersection, SimpleLinesAndTouchingEndsOfAClosedLoop) {
  EXPECT_FALSE(FindSelfIntersection(Open({V(0, 0), V(1, 1), V(2, 0), V(3, 1)})).found);
  EXPECT_FALSE(FindSelfIntersection({{V(0, 0), V(1, 0), V(1, 1), V(0, 1)}, true}).found);
  EXPECT_TRUE(FindSelfIntersection(Open({V(0, 0), V(2, 0), V(2, 1), V(1, 0)})).found)
      << "a vertex touching an earlier segment";
}

}  // namespace
}  // namespace candi::mesh
