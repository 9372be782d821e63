// Early checks of an output path, so that a long command fails before its work, not after it.
#pragma once

#include <string>

namespace candi::app {

// Throws InputError naming `output` when its folder does not exist or is not writable.
void CheckOutputFolder(const std::string& output);

}  // namespace candi::app
