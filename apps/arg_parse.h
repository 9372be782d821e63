// Parsing of option values shared by the commands ("1,2,3", "1024x768").
#pragma once

#include <string>
#include <vector>

namespace candi::app {

// Finite numbers separated by `separator`; throws std::invalid_argument("<what> '<text>': ...").
std::vector<double> ParseNumbers(const std::string& text, char separator, const std::string& what);

}  // namespace candi::app
