// Test helper: the message of an options struct's Check().
#pragma once

#include <stdexcept>
#include <string>

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

}  // namespace candi::testing
