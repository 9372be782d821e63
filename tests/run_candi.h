// Running the `candi` executable from the integration tests.
#pragma once

#include <string>

#include "tests/util/test_util.h"

namespace candi::testing {

// Runs `candi <args>` (CANDI_EXECUTABLE is defined by tests/CMakeLists.txt), capturing its output.
inline CommandResult RunCandi(const std::string& args) {
  return RunCommand(std::string(CANDI_EXECUTABLE) + " " + args);
}

// True when `name` is on PATH (mpirun, colmap).
inline bool OnPath(const std::string& name) { return RunCommand("command -v " + name).code == 0; }

// `mpirun ... -np <ranks> candi`, as root too, more ranks than cores allowed.
inline std::string MpirunCandi(int ranks) {
  return "mpirun --oversubscribe --allow-run-as-root -np " + std::to_string(ranks) + " " + CANDI_EXECUTABLE;
}

}  // namespace candi::testing
