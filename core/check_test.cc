#include "core/check.h"

#include <gtest/gtest.h>

namespace candi {
namespace {

TEST(CandiCheck, PassesSilentlyAndThrowsWithFileLineAndMessage) {
  EXPECT_NO_THROW(CANDI_CHECK(1 + 1 == 2) << "never built");
  try {
    const int value = 3;
    CANDI_CHECK(value < 2) << "value = " << value;
    FAIL() << "no throw";
  } catch (const InternalError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("check_test.cc:"), std::string::npos) << what;
    EXPECT_NE(what.find("check failed: value < 2: value = 3"), std::string::npos) << what;
  }
}

TEST(CandiCheck, ComparisonMacrosPrintBothSides) {
  try {
    CANDI_CHECK_EQ(2, 3);
    FAIL();
  } catch (const InternalError& e) {
    EXPECT_NE(std::string(e.what()).find("2 = 2, 3 = 3"), std::string::npos) << e.what();
  }
}

TEST(InputError, NamesPathAndPosition) {
  const InputError e("a/b.ply", "line 7", "bad token");
  EXPECT_STREQ(e.what(), "a/b.ply: line 7: bad token");
  EXPECT_EQ(e.path(), "a/b.ply");
  EXPECT_STREQ(InputError("x.las", "", "empty").what(), "x.las: empty");
}

}  // namespace
}  // namespace candi
