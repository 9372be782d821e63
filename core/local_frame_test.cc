#include "core/local_frame.h"

#include <gtest/gtest.h>

#include "core/box.h"
#include "core/rng.h"

namespace candi {
namespace {

TEST(LocalFrame, AutoShiftIsZeroForSmallCoordinatesAndRoundedOtherwise) {
  Box3d small{{-10, -20, 0}, {100, 200, 30}};
  EXPECT_TRUE(LocalFrame::Auto(small).IsIdentity());
  Box3d survey{{500000.123, 4500000.456, 100.789}, {500120.5, 4500300.25, 140.0}};
  const LocalFrame frame = LocalFrame::Auto(survey);
  EXPECT_EQ(frame.origin, Eigen::Vector3d(500100, 4500200, 100));  // centre 500060.3, 4500150.4, 120.4
  EXPECT_TRUE(LocalFrame::Auto(Box3d{}).IsIdentity());
}

TEST(LocalFrame, IntegerShiftRoundTripsExactlyAtSurveyScale) {
  LocalFrame frame;
  frame.origin = Eigen::Vector3d(500000, 4500000, 100);
  Rng rng(3);
  for (int i = 0; i < 100000; ++i) {
    // Millimetre detail on survey coordinates, and random doubles near them.
    const Eigen::Vector3d world(500000.0 + rng.Uniform(-5000, 5000), 4500000.0 + rng.Uniform(-5000, 5000),
                                100.0 + rng.Uniform(-50, 50));
    ASSERT_EQ(frame.ToWorld(frame.ToLocal(world)), world);
  }
}

TEST(LocalFrame, ParseShiftAcceptsThreeNumbersAndNamesErrors) {
  EXPECT_EQ(ParseShift("1,2.5,-3").origin, Eigen::Vector3d(1, 2.5, -3));
  EXPECT_THROW(ParseShift("1,2"), std::invalid_argument);
  EXPECT_THROW(ParseShift("1,2,nan"), std::invalid_argument);
  EXPECT_THROW(ParseShift("1,2,3,4"), std::invalid_argument);
  EXPECT_THROW(ParseShift("a,b,c"), std::invalid_argument);
  LocalFrame f;
  f.origin = Eigen::Vector3d(500000.5, -1e-7, 3);
  EXPECT_EQ(ParseShift(f.ToString()), f);
}

}  // namespace
}  // namespace candi
