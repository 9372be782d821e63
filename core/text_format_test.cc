#include "core/text_format.h"

#include <gtest/gtest.h>

#include <limits>
#include <sstream>

namespace candi {
namespace {

// What messages printed with std::ostringstream at that precision.
std::string Streamed(double value, int digits) {
  std::ostringstream s;
  s.precision(digits);
  s << value;
  return s.str();
}

TEST(FormatSignificant, PrintsAsAnOstreamAtThatPrecision) {
  EXPECT_EQ(FormatSignificant(0.1234567891234, 10), "0.1234567891");
  EXPECT_EQ(FormatSignificant(123456789012.0, 10), "1.23456789e+11");
  EXPECT_EQ(FormatSignificant(0.05, 3), "0.05");
  EXPECT_EQ(FormatSignificant(2.0, 6), "2");
  for (double v :
       {0.0, -0.0, 1.0 / 3, 2.5e-7, 1e300, 12345.678, -98.7654321,
        std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
    for (int digits : {3, 4, 6, 10})
      EXPECT_EQ(FormatSignificant(v, digits), Streamed(v, digits)) << v;
  }
}

TEST(FormatDouble, IsTheShortestTextThatReadsBack) {
  EXPECT_EQ(FormatDouble(0.5), "0.5");
  EXPECT_EQ(FormatDouble(0.1), "0.1");
  EXPECT_EQ(FormatDouble(500000.123), "500000.123");
  EXPECT_EQ(FormatDouble(1e-20), "1e-20");
}

}  // namespace
}  // namespace candi
