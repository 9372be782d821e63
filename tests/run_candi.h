// Running the `candi` executable from the integration tests.
#pragma once

#include <string>

#include "tests/util/test_util.h"

namespace candi::testing {

// Runs `candi <args>` (CANDI_EXECUTABLE is defined by tests/CMakeLists.txt), capturing its output.
inline CommandResult RunCandi(const std::string& args) {
  return RunCommand(std::string(CANDI_EXECUTABLE) + " " + args);
}

}  // namespace candi::testing
