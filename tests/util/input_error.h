// Test helper: the message of the InputError a call throws.
#pragma once

#include <functional>
#include <string>

#include "core/check.h"

namespace candi::testing {

// what() of the InputError `f` throws; "" when it throws none (other exceptions propagate).
inline std::string InputErrorMessage(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace candi::testing
