// Test helpers: the message of an options struct's Check(), and its rules checked one by one.
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace candi::testing {

// what() of the std::invalid_argument `options.Check()` throws; "no throw" when it throws none.
template <typename Options>
std::string OptionCheckMessage(const Options& options) {
  try {
    options.Check();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no throw";
}

// Expects a default-constructed Options to pass Check(), for each of the types given.
template <typename... Options>
void ExpectDefaultsPass() {
  for (const std::string& message : {OptionCheckMessage(Options())...}) EXPECT_EQ(message, "no throw");
}

// Expects `valid` to pass Check(), and each of `breaks`, applied to its own copy of `valid`, to
// make Check() throw std::invalid_argument (a failure names the break by its index).
template <typename Options>
void ExpectEachBreakRejected(const Options& valid,
                             const std::vector<std::function<void(Options&)>>& breaks) {
  EXPECT_EQ(OptionCheckMessage(valid), "no throw");
  for (size_t i = 0; i < breaks.size(); ++i) {
    Options o = valid;
    breaks[i](o);
    EXPECT_NE(OptionCheckMessage(o), "no throw") << "break " << i << " passed Check()";
  }
}

}  // namespace candi::testing
